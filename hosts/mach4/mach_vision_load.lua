-- mach-vision: only needed when `require("mach_vision")` reports "module 'mach_vision' not
-- found". Paste into the screen's load script (Operator > Edit Screen > Screen Load Script)
-- so Mach4's macros look for native modules in <Mach4 dir>\Modules.
local inst = mc.mcGetInstance()
local machDir = mc.mcCntlGetMachDir(inst)
package.cpath = machDir .. "\\Modules\\?.dll;" .. package.cpath
-- Optional: a profile file other than Profiles\<profile>\MachVision.toml.
-- require("mach_vision").open(machDir .. "\\Profiles\\MyProfile\\MachVision.toml")
