-- mach-vision: only needed when a Vision macro reports "module 'mach_vision' not found".
-- Copy the two lines below these comments (`local inst = ...` and `package.cpath = ...`) to the
-- top of each Macros\mNNN.mcs so Mach4's macros look for native modules in <Mach4>\Modules.
local inst = mc.mcGetInstance()
package.cpath = mc.mcCntlGetMachDir(inst) .. "\\Modules\\?.dll;" .. package.cpath
-- Optional, after the two lines above: a profile file other than Profiles\<profile>\MachVision.toml.
-- require("mach_vision").open(mc.mcCntlGetMachDir(inst) .. "\\Profiles\\MyProfile\\MachVision.toml")
