-- mach-vision: only needed when a Vision macro reports "module 'mach_vision' not found".
-- Put the first two lines at the top of each Macros\mNNN.mcs so Mach4's macros look for native
-- modules in <Mach4 dir>\Modules.
local inst = mc.mcGetInstance()
package.cpath = mc.mcCntlGetMachDir(inst) .. "\\Modules\\?.dll;" .. package.cpath
-- Optional, after the lines above: a profile file other than Profiles\<profile>\MachVision.toml.
-- require("mach_vision").open(mc.mcCntlGetMachDir(inst) .. "\\Profiles\\MyProfile\\MachVision.toml")
