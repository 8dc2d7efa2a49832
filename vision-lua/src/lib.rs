//! `mach_vision`: the Vision M-codes M280–M284 as a Lua 5.3 native module for Mach4.
//!
//! Each `Macros/mNNN.mcs` of the profile defines `mNNN(hParam)` with one line,
//! `return require("mach_vision").mcode(NNN, hParam)`. Everything else happens here: the line's words are read
//! with `mc.mcCntlGetLocalVarFlag` / `mcCntlGetLocalVar`, the call runs through
//! [`vision_host::Session`] on [`Mach4`] (the [`vision_host::Machine`] over Mach4's `mc` API), and
//! a refusal goes to `mc.mcCntlSetLastError` followed by `mc.mcCntlCycleStop`, which stops the
//! program. The session lives in the Lua state between calls; its profile is
//! `<Mach4 dir>/Profiles/<profile>/MachVision.toml` unless `mach_vision.open(path)` named one.
//!
//! Built with the `module` feature it is the shipped library (it links no Lua: the Lua 5.3 of
//! the process that loads it provides every symbol); the default `vendored` feature compiles
//! Lua 5.3 in for the tests.
//!
//! Lua API (every function returns `ok, message, gcode`: `true, nil, {lines}` on success, the
//! lines being a record of the G-code the M-code already ran on Mach4, never to be run again;
//! `false, "why", {}` after reporting the failure to Mach4 and stopping the cycle). When the
//! cycle cannot be stopped (`mc.mcCntlCycleStop` missing, failing or returning an error code)
//! the function raises a Lua error with both messages instead: Mach4 aborts the macro, and the
//! program does not go on after a refused M-code.
//!
//! * `mach_vision.mcode(m, hParam)`: runs M-code `m` (280–284) with the words of `hParam`.
//! * `mach_vision.open(path)`: (re)opens the session from profile file `path`.
//! * `mach_vision.get(name)`: parameter `name` (case-insensitive: configuration, calibration, a
//!   driver's setting, or telemetry such as `VisionLastStatus`, `VisionRun_DotCount`) as a Lua
//!   boolean, integer, number or string; `nil, "why"` for an unknown name or no session. It
//!   never reports to Mach4 or stops the cycle: a screen's DRO script can call it at any time.
//! * `mach_vision.version`: the crate version.
//!
//! A session opened from a profile `P.toml` publishes its state into `P.panel/` beside it
//! (`state.json`, `frame.png`: [`vision_host::panel`]) for `mach-vision panel --profile P`;
//! no server runs inside Mach4.
//!
//! ```
//! # #[cfg(feature = "vendored")] {
//! use mlua::{Function, Lua};
//!
//! // Outside Mach4 there is no `mc` table: the call is refused, not a crash.
//! let lua = Lua::new();
//! let module = mach_vision::mach_vision(&lua)?;
//! let mcode: Function = module.get("mcode")?;
//! let (ok, message, _gcode): (bool, Option<String>, Vec<String>) = mcode.call((281, 7))?;
//! assert!(!ok && message.is_some_and(|m| m.contains("no `mc` table")));
//! # }
//! # Ok::<(), mlua::Error>(())
//! ```

mod mach4;

use std::path::PathBuf;

use mlua::{IntoLua, Lua, Table, Value};
use vision_host::ParamValue;
use vision_host::{printable_line, registry, HostError, Session, MAX_MESSAGE_CHARS};

pub use mach4::Mach4;

/// The session of one Lua state, taken out for the length of a call.
struct Slot(Option<Session>);

/// Marks the Lua state while an M-code runs (its session is taken out of the [`Slot`]); removed
/// when dropped.
struct Busy(Lua);

impl Busy {
    fn mark(lua: &Lua) -> Busy {
        lua.set_app_data(BusyMark);
        Busy(lua.clone())
    }
}

impl Drop for Busy {
    fn drop(&mut self) {
        self.0.remove_app_data::<BusyMark>();
    }
}

/// The app-data marker [`Busy`] sets.
struct BusyMark;

/// What every Lua entry point returns: `ok, message, gcode`.
type Answer = (bool, Option<String>, Vec<String>);

/// Installs `session` as the Lua state's Vision session (replacing any), so the next M-code uses
/// it: how tests put a simulated camera behind the module, and how `open` works.
pub fn install(lua: &Lua, session: Session) {
    lua.set_app_data(Slot(Some(session)));
}

/// The module table `require("mach_vision")` returns.
///
/// # Errors
/// Lua's allocation errors only.
#[cfg_attr(feature = "module", mlua::lua_module(name = "mach_vision"))]
pub fn mach_vision(lua: &Lua) -> mlua::Result<Table> {
    let exports = lua.create_table()?;
    exports.set("mcode", lua.create_function(|lua, (m, h_param): (u32, Value)| mcode(lua, m, &h_param))?)?;
    exports.set("open", lua.create_function(|lua, path: String| open(lua, PathBuf::from(path)))?)?;
    exports.set("get", lua.create_function(|lua, name: String| get(lua, &name))?)?;
    exports.set("version", env!("CARGO_PKG_VERSION"))?;
    Ok(exports)
}

/// The answer of a call that failed, after `host` reported it to the operator and stopped the
/// cycle; a Lua error carrying both messages when the cycle could not be stopped.
fn refused(host: Option<&Mach4>, e: &HostError) -> mlua::Result<Answer> {
    // Messages quote profile paths and camera replies: shown escaped and bounded.
    let message = printable_line(&e.to_string(), MAX_MESSAGE_CHARS);
    if let Some(host) = host {
        if let Err(stop) = host.fail(&message) {
            return Err(mlua::Error::RuntimeError(format!(
                "{message} — and the program could not be stopped ({stop}): stop it by hand"
            )));
        }
    }
    Ok((false, Some(message), Vec::new()))
}

/// The session of profile `path`, publishing its state beside it.
fn open_session(path: &std::path::Path) -> Result<Session, HostError> {
    let mut session = Session::open(path, &registry())?;
    session.publish();
    Ok(session)
}

fn open(lua: &Lua, path: PathBuf) -> mlua::Result<Answer> {
    let host = Mach4::new(lua).ok();
    match open_session(&path) {
        Ok(session) => {
            install(lua, session);
            Ok((true, None, Vec::new()))
        }
        Err(e) => refused(host.as_ref(), &e),
    }
}

fn mcode(lua: &Lua, m: u32, h_param: &Value) -> mlua::Result<Answer> {
    let _busy = Busy::mark(lua);
    let mut host = match Mach4::new(lua) {
        Ok(host) => host,
        Err(e) => return refused(None, &e.into()),
    };
    let taken = lua.app_data_mut::<Slot>().and_then(|mut slot| slot.0.take());
    let session = match taken {
        Some(session) => Ok(session),
        None => host.profile_path().map_err(HostError::from).and_then(|path| open_session(&path)),
    };
    let mut session = match session {
        Ok(session) => session,
        Err(e) => return refused(Some(&host), &e),
    };
    let result = host.words(h_param).map_err(HostError::from).and_then(|words| session.mcode(&mut host, m, &words));
    install(lua, session);
    match result {
        Ok(outcome) => Ok((true, None, outcome.gcode().to_vec())),
        Err(e) => refused(Some(&host), &e),
    }
}

/// `mach_vision.get(name)`: the value, or `nil, "why"`. Without a session yet, the one of
/// Mach4's profile is opened, as the first M-code would.
fn get(lua: &Lua, name: &str) -> mlua::Result<(Value, Option<String>)> {
    if lua.app_data_ref::<BusyMark>().is_some() {
        // Only when a Mach4 callback of a running M-code calls back in.
        return Ok((Value::Nil, Some("the Vision session is busy with an M-code".to_string())));
    }
    let installed = lua.app_data_ref::<Slot>().is_some_and(|slot| slot.0.is_some());
    if !installed {
        let opened = Mach4::new(lua)
            .and_then(|host| host.profile_path())
            .map_err(HostError::from)
            .and_then(|path| open_session(&path));
        match opened {
            Ok(session) => install(lua, session),
            Err(e) => return Ok((Value::Nil, Some(printable_line(&e.to_string(), MAX_MESSAGE_CHARS)))),
        }
    }
    let value = lua.app_data_ref::<Slot>().and_then(|slot| slot.0.as_ref().map(|session| session.param(name)));
    match value {
        Some(Ok(value)) => Ok((lua_value(lua, value)?, None)),
        Some(Err(e)) => Ok((Value::Nil, Some(printable_line(&e.to_string(), MAX_MESSAGE_CHARS)))),
        None => Ok((Value::Nil, Some("no Vision session".to_string()))),
    }
}

/// A parameter as Lua's boolean, integer, number or string.
fn lua_value(lua: &Lua, value: ParamValue) -> mlua::Result<Value> {
    match value {
        ParamValue::Bool(b) => Ok(Value::Boolean(b)),
        ParamValue::Int(i) => Ok(Value::Integer(i)),
        ParamValue::Float(f) => Ok(Value::Number(f)),
        ParamValue::Text(t) => t.into_lua(lua),
    }
}
