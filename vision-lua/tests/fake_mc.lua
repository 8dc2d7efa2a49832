-- A fake Mach4 `mc` table for the tests: Mach4's constants and return conventions. The motion
-- and state calls (G-code, pound variables, tools, axes, units) are added per M-code by the
-- Rust harness, over the project's interpreter driving the simulator.
fake = { errors = {}, stopped = false, locals = {} }

mc = {
    MERROR_NOERROR = 0,
    MERROR_INVALID_ARG = -13,
    MERROR_NOT_NOW = -18,
    X_AXIS = 0,
    Y_AXIS = 1,
    MTOOL_MILL_X = 11,
    MTOOL_MILL_Y = 12,
}
-- Mach4 numbers a line's local variables SV_A … SV_Z.
for i = 0, 25 do
    mc["SV_" .. string.char(65 + i)] = 1000 + i
end

function mc.mcGetInstance() return 0 end
function mc.mcInEditor() return 0 end

function mc.mcCntlSetLastError(inst, message)
    table.insert(fake.errors, message)
    return mc.MERROR_NOERROR
end

function mc.mcCntlCycleStop(inst)
    fake.stopped = true
    return mc.MERROR_NOERROR
end

function mc.mcCntlGetLocalVarFlag(inst, hParam, var)
    if type(hParam) ~= "number" then return 0, mc.MERROR_INVALID_ARG end
    if fake.locals[var] ~= nil then return 1, mc.MERROR_NOERROR end
    return 0, mc.MERROR_NOERROR
end

function mc.mcCntlGetLocalVar(inst, hParam, var)
    if type(hParam) ~= "number" or fake.locals[var] == nil then return 0, mc.MERROR_INVALID_ARG end
    return fake.locals[var], mc.MERROR_NOERROR
end

function mc.mcCntlGetMachDir(inst) return fake.machDir or "C:\\Mach4Hobby", mc.MERROR_NOERROR end
function mc.mcProfileGetName(inst) return "Mach4Mill", mc.MERROR_NOERROR end
