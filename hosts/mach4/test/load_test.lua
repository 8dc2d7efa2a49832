-- Run by load-test.sh in the stock lua5.3: load mach_vision with a plain `require`, run the real
-- m280.mcs (success: the cancel line reaches mcCntlGcodeExecuteWait) and m281.mcs (K not
-- calibrated: mcCntlSetLastError with the manual's message, then mcCntlCycleStop). After each,
-- `mach_vision.get("VisionLastStatus")` and the panel folder beside the profile
-- (MachVision.panel/state.json) show the call, with a sequence number that grows.
-- With a third argument, the port of a Keyence emulator on 127.0.0.1 (`mach-vision emulate`), it
-- also runs m284.mcs through the Keyence driver: `M284 P2` switches the camera's job and saves
-- VisionActiveJob to the profile; the same call to a port nothing answers is refused with the
-- driver's message and stops the cycle.
-- Arguments: the folder holding the module (also used as the Mach4 folder; its
-- Profiles/LoadTest folder must exist: Lua cannot make folders without a shell, and a shell's
-- syntax differs between Linux and Windows), the Macros folder. Runs as is in Linux's lua5.3
-- (mach_vision.so) and in Windows' lua.exe under Wine (mach_vision.dll; hosts/mach4/test/wine-test.sh).
local dir, macros, port = arg[1], arg[2], tonumber(arg[3])
package.cpath = dir .. "/?.so;" .. dir .. "/?.dll;" .. package.cpath

local log = { executed = {}, errors = {}, stopped = false, locals = {} }
local NOERROR = 0
mc = { MERROR_NOERROR = NOERROR, X_AXIS = 0, Y_AXIS = 1, MTOOL_MILL_X = 11, MTOOL_MILL_Y = 12,
       SV_C = 1002, SV_D = 1003, SV_P = 1015, SV_Q = 1016 }
function mc.mcGetInstance() return 0 end
function mc.mcInEditor() return 0 end
function mc.mcCntlGetMachDir(inst) return dir, NOERROR end
function mc.mcProfileGetName(inst) return "LoadTest", NOERROR end
function mc.mcCntlGetLocalVarFlag(inst, h, var) return (log.locals[var] and 1 or 0), NOERROR end
function mc.mcCntlGetLocalVar(inst, h, var) return log.locals[var], NOERROR end
function mc.mcCntlGcodeExecuteWait(inst, code) table.insert(log.executed, code); return NOERROR end
function mc.mcCntlGetPoundVar(inst, n) return 0.0, NOERROR end
function mc.mcCntlSetPoundVar(inst, n, v) return NOERROR end
function mc.mcToolGetCurrent(inst) return 0, NOERROR end
function mc.mcToolGetData(inst, field, tool) return 0.0, NOERROR end
function mc.mcToolSetData(inst, field, tool, v) return NOERROR end
function mc.mcAxisGetPos(inst, axis) return 0.0, NOERROR end
function mc.mcCntlGetUnitsCurrent(inst) return 200, NOERROR end
function mc.mcCntlSetLastError(inst, message) table.insert(log.errors, message); return NOERROR end
function mc.mcCntlCycleStop(inst) log.stopped = true; return NOERROR end

-- Vision enabled, Keyence at an address nothing answers (neither call below triggers).
local profile = assert(io.open(dir .. "/Profiles/LoadTest/MachVision.toml", "w"))
profile:write('[vision]\nVisionEnabled = true\nVisionIP = "127.0.0.1"\n')
profile:close()

local function check(ok, what) if not ok then error("load test: " .. what, 2) end end

local vision = require("mach_vision")
check(type(vision.mcode) == "function", "require('mach_vision') returned no mcode")

-- The panel's state.json once it shows M-code `m`'s call (written by the module's own thread):
-- its text and sequence number. Lua has no sleep: a bounded wait on the clock.
local state_path = dir .. "/Profiles/LoadTest/MachVision.panel/state.json"
local function panel_state(m)
  local deadline = os.time() + 10
  repeat
    local f = io.open(state_path)
    if f then
      local text = f:read("a")
      f:close()
      local seq = tonumber(text:match('"seq": (%d+)'))
      if seq and text:find('"mcode": ' .. m, 1, true) then return text, seq end
    end
  until os.time() > deadline
  error("load test: " .. state_path .. " never showed M" .. m, 2)
end
dofile(macros .. "/m280.mcs")
dofile(macros .. "/m281.mcs")

log.locals = { [mc.SV_P] = 3 }
local ok, message, gcode = m280(7)
check(ok, "M280 P3 refused: " .. tostring(message))
check(gcode[1] == "G69 G50 G52 X0 Y0", "M280 emitted " .. tostring(gcode[1]))
check(log.executed[1] == "G69 G50 G52 X0 Y0", "M280's cancel line did not reach Mach4")
check(not log.stopped, "M280 stopped the cycle")
check(vision.get("VisionRun_Active") == 1 and vision.get("VisionRun_Mode") == 3, "get after M280 P3")
local _, seq280 = panel_state(280)

log.locals = {}
ok, message = m281(7)
check(not ok and message:find("K matrix is zero", 1, true), "M281 without K: " .. tostring(message))
check(log.errors[#log.errors] == message, "M281's refusal did not reach mcCntlSetLastError")
check(log.stopped, "M281's refusal did not stop the cycle")
check(#log.executed == 1, "M281's refusal ran G-code")
check(vision.get("VisionLastStatus") == message, "get(VisionLastStatus) after M281: " .. tostring(vision.get("VisionLastStatus")))
local none, why = vision.get("VisionNoSuch")
check(none == nil and tostring(why):find("VisionNoSuch", 1, true), "get of an unknown name: " .. tostring(why))
check(math.type(vision.get("VisionRun_DotCount")) == "integer" and vision.get("VisionEnabled") == true, "get's types")
local text, seq281 = panel_state(281)
check(seq281 > seq280, "the panel's sequence number did not grow: " .. seq280 .. " then " .. seq281)
check(text:find('"ok": false', 1, true) and text:find("K matrix is zero", 1, true), "state.json after M281:\n" .. text)

local ran = "M280/M281 (get and the panel folder checked)"
if port then
    dofile(macros .. "/m284.mcs")
    local function keyence(path, at)
        local f = assert(io.open(path, "w"))
        f:write('[vision]\nVisionEnabled = true\nVisionDriver = "Keyence"\nVisionIP = "127.0.0.1"\nVisionPort = ' .. at ..
            '\nVisionTimeout = 2.0\n')
        f:close()
        local opened, why = vision.open(path)
        check(opened, "open " .. path .. ": " .. tostring(why))
    end
    local path = dir .. "/Profiles/LoadTest/Keyence.toml"
    keyence(path, port)
    log.locals, log.stopped = { [mc.SV_P] = 2 }, false
    ok, message = m284(7)
    check(ok, "M284 P2 through the Keyence driver: " .. tostring(message))
    check(not log.stopped, "M284 stopped the cycle")
    local f = assert(io.open(path))
    local saved = f:read("a")
    f:close()
    check(saved:find("VisionActiveJob%s*=%s*2") ~= nil, "M284 P2 did not save VisionActiveJob:\n" .. saved)

    -- Port 1 on loopback: nothing listens there.
    keyence(path, 1)
    log.stopped = false
    ok, message = m284(7)
    check(not ok and log.errors[#log.errors] == message, "M284 to a closed port: " .. tostring(message))
    check(log.stopped, "the camera's refusal did not stop the cycle")
    ran = ran .. ", and M284 through the Keyence driver to the emulator on port " .. port .. " (" .. message .. " without it)"
end

print("load test: mach_vision " .. vision.version .. " loads in " .. _VERSION .. " and runs " .. ran)

-- A refusal whose cycle stop fails raises a Lua error with both messages (Mach4 aborts the
-- macro), in the stock Lua too.
mc.mcCntlCycleStop = function(inst) return -18 end
log.locals = {}
local raised, err = pcall(m281, 7)
check(not raised and tostring(err):find("K matrix is zero", 1, true) and tostring(err):find("error code -18", 1, true),
      "a failed cycle stop: " .. tostring(err))
print("load test: a refusal whose cycle stop fails raises a Lua error")
