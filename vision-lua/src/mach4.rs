//! [`Mach4`]: [`Machine`] over Mach4's `mc` scripting API.

use std::path::PathBuf;

use mlua::{FromLua, Function, IntoLuaMulti, Lua, MultiValue, Table, Value};
use vision_host::{
    printable_line, Controller, Machine, MachineCommand, MachineError, MachineErrorKind, MAX_MESSAGE_CHARS,
};
use vision_math::{LengthUnit, Point2, Vector2};

/// `mcCntlGetUnitsCurrent` for G20 (the G-code number × 10).
const UNITS_INCH: i64 = 200;
/// `mcCntlGetUnitsCurrent` for G21.
const UNITS_MM: i64 = 210;
/// Letters that are never an M-code's parameters.
const NOT_WORDS: [char; 4] = ['G', 'M', 'N', 'O'];
/// The profile file next to Mach4's own `Machine.ini`.
const PROFILE_FILE: &str = "MachVision.toml";

/// The controller of the Lua state's global `mc` table, instance `mc.mcGetInstance()`.
///
/// Mach4's calls return their value(s) followed by a return code; any code other than
/// `mc.MERROR_NOERROR` is a [`MachineError`] naming the call.
pub struct Mach4 {
    lua: Lua,
    mc: Table,
    inst: Value,
    no_error: i64,
    /// The motion and distance modes (`#4001`, `#4003`) at each `save_modal_state`, newest last.
    saved: Vec<(f64, f64)>,
}

/// `mc.SV_MOD_GROUP_1`: the active motion mode as its G number (0, 1, 2, 3, 80, 81, …).
const SV_MOD_GROUP_1: u32 = 4001;
/// `mc.SV_MOD_GROUP_3`: the distance mode, 90 or 91.
const SV_MOD_GROUP_3: u32 = 4003;

/// A failed scripting call or an unusable answer.
fn comm(message: impl Into<String>) -> MachineError {
    MachineError::new(MachineErrorKind::Communication, message.into())
}

fn lua_error(call: &str, e: &mlua::Error) -> MachineError {
    comm(format!("mc.{call} failed: {e}"))
}

impl Mach4 {
    /// The controller behind the global `mc`.
    ///
    /// # Errors
    /// A [`MachineError`] when there is no `mc` table (not inside Mach4) or no instance.
    pub fn new(lua: &Lua) -> Result<Mach4, MachineError> {
        let mc: Table = lua
            .globals()
            .get("mc")
            .map_err(|_| comm("there is no `mc` table: mach_vision runs inside Mach4's macros"))?;
        let no_error = mc.get::<Option<i64>>("MERROR_NOERROR").map_err(|e| lua_error("MERROR_NOERROR", &e))?;
        let mut host =
            Mach4 { lua: lua.clone(), mc, inst: Value::Nil, no_error: no_error.unwrap_or(0), saved: Vec::new() };
        host.inst = host.value("mcGetInstance", ())?;
        Ok(host)
    }

    fn function(&self, call: &str) -> Result<Function, MachineError> {
        self.mc.get::<Function>(call).map_err(|_| comm(format!("this Mach4 has no mc.{call}")))
    }

    /// A constant of the `mc` table (`mc.X_AXIS`, `mc.MTOOL_MILL_X`, …).
    fn constant(&self, name: &str) -> Result<Value, MachineError> {
        match self.mc.get::<Value>(name) {
            Ok(Value::Nil) | Err(_) => Err(comm(format!("this Mach4 has no mc.{name}"))),
            Ok(v) => Ok(v),
        }
    }

    /// Checks a return code.
    #[expect(clippy::float_cmp, reason = "Mach4 error codes are small whole numbers, exact in f64")]
    fn check(&self, call: &str, rc: &Value) -> Result<(), MachineError> {
        match rc {
            Value::Nil => Ok(()),
            Value::Integer(n) if *n == self.no_error => Ok(()),
            Value::Number(n) if *n == self.no_error as f64 => Ok(()),
            other => Err(comm(format!("mc.{call} returned error code {}", describe(other)))),
        }
    }

    fn call(&self, call: &str, args: impl IntoLuaMulti) -> Result<MultiValue, MachineError> {
        self.function(call)?.call::<MultiValue>(args).map_err(|e| lua_error(call, &e))
    }

    /// A call that returns `value, rc`.
    fn value<T: FromLua>(&self, call: &str, args: impl IntoLuaMulti) -> Result<T, MachineError> {
        let mut out = self.call(call, args)?.into_iter();
        let value = out.next().unwrap_or(Value::Nil);
        self.check(call, &out.next().unwrap_or(Value::Nil))?;
        let shown = describe(&value);
        self.lua.unpack::<T>(value).map_err(|_| comm(format!("mc.{call} returned {shown}")))
    }

    /// A call that returns `rc` only.
    fn status(&self, call: &str, args: impl IntoLuaMulti) -> Result<(), MachineError> {
        let out = self.call(call, args)?;
        self.check(call, out.front().unwrap_or(&Value::Nil))
    }

    /// Reports `message` to the operator as an error and stops the program.
    ///
    /// # Errors
    /// `mc.mcCntlCycleStop` is missing, raised a Lua error or returned an error code: the
    /// program was not stopped (the caller must abort the macro). A message line Mach4 refuses
    /// is not an error: the stop is what matters, and the M-code's answer carries the message.
    pub fn fail(&self, message: &str) -> Result<(), MachineError> {
        let _ = self.call("mcCntlSetLastError", (self.inst.clone(), message));
        self.status("mcCntlCycleStop", self.inst.clone())
    }

    /// The words of the M-code's line, from its local variables (`hParam`).
    ///
    /// # Errors
    /// A refused read.
    pub fn words(&self, h_param: &Value) -> Result<Vec<(char, f64)>, MachineError> {
        let mut words = Vec::new();
        for letter in ('A'..='Z').filter(|l| !NOT_WORDS.contains(l)) {
            let Ok(var) = self.constant(&format!("SV_{letter}")) else { continue };
            let flag: f64 = self.value("mcCntlGetLocalVarFlag", (self.inst.clone(), h_param.clone(), var.clone()))?;
            if flag != 0.0 {
                let value: f64 = self.value("mcCntlGetLocalVar", (self.inst.clone(), h_param.clone(), var))?;
                words.push((letter, value));
            }
        }
        Ok(words)
    }

    /// `<Mach4 dir>/Profiles/<profile>/MachVision.toml`.
    ///
    /// # Errors
    /// A refused read.
    pub fn profile_path(&self) -> Result<PathBuf, MachineError> {
        let dir: String = self.value("mcCntlGetMachDir", self.inst.clone())?;
        let profile: String = self.value("mcProfileGetName", self.inst.clone())?;
        Ok(PathBuf::from(dir).join("Profiles").join(profile).join(PROFILE_FILE))
    }

    fn axis(&self, name: &str) -> Result<f64, MachineError> {
        self.value("mcAxisGetPos", (self.inst.clone(), self.constant(name)?))
    }

    fn tool_field(&self, field: &str, tool: u32) -> Result<f64, MachineError> {
        self.value("mcToolGetData", (self.inst.clone(), self.constant(field)?, tool))
    }

    fn set_tool_field(&self, field: &str, tool: u32, value: f64) -> Result<(), MachineError> {
        self.status("mcToolSetData", (self.inst.clone(), self.constant(field)?, tool, value))
    }
}

/// A Lua value for a message (numbers and strings as themselves).
fn describe(v: &Value) -> String {
    match v {
        Value::Integer(n) => n.to_string(),
        Value::Number(n) => n.to_string(),
        Value::String(s) => s.to_string_lossy(),
        other => other.type_name().to_string(),
    }
}

impl Machine for Mach4 {
    fn controller(&self) -> &'static dyn Controller {
        &vision_host::controller::Mach4
    }

    fn gcode(&self, command: &MachineCommand) -> Result<Vec<String>, MachineError> {
        Ok(vision_mcode::gcode(self.controller(), command)?)
    }

    fn execute(&mut self, line: &str) -> Result<(), MachineError> {
        let done = self.status("mcCntlGcodeExecuteWait", (self.inst.clone(), line));
        done.map_err(|e| e.with_kind(MachineErrorKind::RefusedGcode))
    }

    /// `mcCntlMachineStatePush`, and the motion and distance modes read aside: Mach4's scripts
    /// push and pop the machine state around moves of their own, but which modal groups the
    /// pop restores is not documented, so those two are checked after it.
    fn save_modal_state(&mut self) -> Result<(), MachineError> {
        let modes = (self.pound(SV_MOD_GROUP_1)?, self.pound(SV_MOD_GROUP_3)?);
        self.status("mcCntlMachineStatePush", self.inst.clone())?;
        self.saved.push(modes);
        Ok(())
    }

    /// `mcCntlMachineStatePop`, then the saved motion and distance modes put back where the pop
    /// left another (`G0`/`G1`/`G80`, `G90`/`G91`).
    #[expect(clippy::float_cmp, reason = "G numbers are small whole numbers, exact in f64")]
    fn restore_modal_state(&mut self) -> Result<(), MachineError> {
        let (motion, distance) =
            self.saved.pop().ok_or_else(|| comm("no modal state was saved (mcCntlMachineStatePush)"))?;
        self.status("mcCntlMachineStatePop", self.inst.clone())?;
        for (var, want) in [(SV_MOD_GROUP_3, distance), (SV_MOD_GROUP_1, motion)] {
            if self.pound(var)? == want {
                continue;
            }
            let settable = [0.0, 1.0, 80.0, 90.0, 91.0].contains(&want);
            if !settable {
                return Err(MachineError::new(
                    MachineErrorKind::Other,
                    format!("Mach4 did not restore G{want} after the Vision moves: set it again before the next move"),
                ));
            }
            self.execute(&format!("G{want}"))?;
        }
        Ok(())
    }

    fn pound(&self, index: u32) -> Result<f64, MachineError> {
        let value = self.value("mcCntlGetPoundVar", (self.inst.clone(), index));
        value.map_err(|e| e.with_kind(MachineErrorKind::OutOfRange))
    }

    fn set_pound(&mut self, index: u32, value: f64) -> Result<(), MachineError> {
        let done = self.status("mcCntlSetPoundVar", (self.inst.clone(), index, value));
        done.map_err(|e| e.with_kind(MachineErrorKind::OutOfRange))
    }

    fn active_tool(&self) -> Result<u32, MachineError> {
        let tool: f64 = self.value("mcToolGetCurrent", self.inst.clone())?;
        if tool.fract() == 0.0 && (0.0..=f64::from(u32::MAX)).contains(&tool) {
            #[expect(clippy::cast_possible_truncation, clippy::cast_sign_loss, reason = "checked above")]
            Ok(tool as u32)
        } else {
            Err(comm(format!("mc.mcToolGetCurrent returned {tool}, not a tool number")))
        }
    }

    fn tool_offset(&self, tool: u32) -> Result<Vector2<f64>, MachineError> {
        let unknown = |e: MachineError| e.with_kind(MachineErrorKind::UnknownTool);
        Ok(Vector2::new(
            self.tool_field("MTOOL_MILL_X", tool).map_err(unknown)?,
            self.tool_field("MTOOL_MILL_Y", tool).map_err(unknown)?,
        ))
    }

    fn set_tool_offset(&mut self, tool: u32, offset: Vector2<f64>) -> Result<(), MachineError> {
        self.set_tool_field("MTOOL_MILL_X", tool, offset.x)?;
        self.set_tool_field("MTOOL_MILL_Y", tool, offset.y)
    }

    fn program_position(&self) -> Result<Point2<f64>, MachineError> {
        Ok(Point2::new(self.axis("X_AXIS")?, self.axis("Y_AXIS")?))
    }

    fn units(&self) -> Result<LengthUnit, MachineError> {
        match self.value::<i64>("mcCntlGetUnitsCurrent", self.inst.clone())? {
            UNITS_INCH => Ok(LengthUnit::Inch),
            UNITS_MM => Ok(LengthUnit::Millimetre),
            other => Err(comm(format!(
                "mc.mcCntlGetUnitsCurrent returned {other}, neither {UNITS_INCH} (G20) nor {UNITS_MM} (G21)"
            ))),
        }
    }

    fn dwell(&mut self, seconds: f64) -> Result<(), MachineError> {
        // Mach4 reads G4 P in seconds unless "Dwell in ms" is ticked (see the install guide).
        self.execute(&format!("G4 P{seconds:.3}"))
    }

    fn message(&mut self, text: &str) {
        // A status line only: a refused message is not worth failing the M-code for.
        let _ = self.call("mcCntlSetLastError", (self.inst.clone(), printable_line(text, MAX_MESSAGE_CHARS)));
    }
}
