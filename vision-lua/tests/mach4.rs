//! The real `hosts/mach4/Macros/m28x.mcs`, unmodified, in Lua 5.3 against a fake `mc` whose
//! motion is the project's interpreter driving the simulator: the same G-code and the same cut
//! error as `mach-vision run`, and the manual's messages on the error paths.

use std::cell::RefCell;
use std::path::Path;

use mlua::{Function, Lua, Table, Value};
use vision_core::Params;
use vision_driver_sim::{Sim, World};
use vision_gcode::{Context, HandlerError, MCodeHandler, UserMCode};
use vision_host::panel::{self, PanelValue};
use vision_host::testkit::{example, reference, sim_params, Call, Camera, Rig, Trace, REFUSALS};
use vision_host::Session;
use vision_math::{Point2, Vector2};
use vision_mcode::VISION_MCODES;

const NO_ERROR: i64 = 0;
const NOT_NOW: i64 = -18;
/// The `hParam` handle the fake hands each macro.
const H_PARAM: i64 = 7;

fn hosts_mach4() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../hosts/mach4"))
}

/// A Lua 5.3 state as Mach4's macro state: the fake `mc`, the module on `require`, the five
/// macros loaded from their files.
fn mach4_lua() -> Lua {
    let lua = Lua::new();
    lua.load(include_str!("fake_mc.lua")).set_name("fake_mc.lua").exec().expect("fake mc");
    let preload: Table = lua.globals().get::<Table>("package").and_then(|p| p.get("preload")).expect("preload");
    let open = lua.create_function(|lua, ()| mach_vision::mach_vision(lua)).expect("loader");
    preload.set("mach_vision", open).expect("preload");
    for m in VISION_MCODES {
        let path = hosts_mach4().join(format!("Macros/m{m}.mcs"));
        let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        lua.load(text).set_name(format!("m{m}.mcs")).exec().unwrap_or_else(|e| panic!("m{m}.mcs: {e}"));
    }
    lua
}

fn fake(lua: &Lua) -> Table {
    lua.globals().get("fake").expect("fake")
}

/// The interpreter's M280–M284 handler that runs the Mach4 macro `mNNN(hParam)`, with the
/// motion calls of `mc` over the interpreter for the length of the call.
struct MacroHandler {
    lua: Lua,
    calls: Vec<Call>,
    /// G-code lines run through `mcCntlGcodeExecuteWait`, per call.
    executed: Vec<Vec<String>>,
}

fn rc(result: Result<(), impl std::fmt::Display>) -> i64 {
    result.map_or(NOT_NOW, |()| NO_ERROR)
}

impl MacroHandler {
    fn run_macro(&self, code: u32, ctx: &mut Context<'_>, executed: &RefCell<Vec<String>>) -> mlua::Result<Call> {
        let lua = &self.lua;
        let mc: Table = lua.globals().get("mc")?;
        let ctx = RefCell::new(ctx);
        lua.scope(|scope| {
            mc.set(
                "mcCntlGcodeExecuteWait",
                scope.create_function(|_, (_, code): (Value, String)| {
                    executed.borrow_mut().push(code.clone());
                    Ok(rc(ctx.borrow_mut().execute(&code)))
                })?,
            )?;
            mc.set(
                "mcCntlGetPoundVar",
                scope.create_function(|_, (_, n): (Value, u32)| {
                    Ok(ctx.borrow().pound(n).map_or((0.0, NOT_NOW), |v| (v, NO_ERROR)))
                })?,
            )?;
            mc.set(
                "mcCntlSetPoundVar",
                scope.create_function(|_, (_, n, v): (Value, u32, f64)| Ok(rc(ctx.borrow_mut().set_pound(n, v))))?,
            )?;
            mc.set(
                "mcToolGetCurrent",
                scope.create_function(|_, _: Value| Ok((ctx.borrow().active_tool(), NO_ERROR)))?,
            )?;
            mc.set(
                "mcToolGetData",
                scope.create_function(|_, (_, field, tool): (Value, i64, u32)| {
                    Ok(match ctx.borrow().tool_offset(tool) {
                        Ok(o) if field == 11 => (o.x, NO_ERROR),
                        Ok(o) if field == 12 => (o.y, NO_ERROR),
                        _ => (0.0, NOT_NOW),
                    })
                })?,
            )?;
            mc.set(
                "mcToolSetData",
                scope.create_function(|_, (_, field, tool, v): (Value, i64, u32, f64)| {
                    let mut ctx = ctx.borrow_mut();
                    let Ok(o) = ctx.tool_offset(tool) else { return Ok(NOT_NOW) };
                    let (x, y) = if field == 11 { (v, o.y) } else { (o.x, v) };
                    Ok(rc(ctx.set_tool_offset(tool, x, y)))
                })?,
            )?;
            mc.set(
                "mcAxisGetPos",
                scope.create_function(|_, (_, axis): (Value, i64)| {
                    let p = ctx.borrow().program_position();
                    Ok(match axis {
                        0 => (p.x, NO_ERROR),
                        1 => (p.y, NO_ERROR),
                        _ => (0.0, NOT_NOW),
                    })
                })?,
            )?;
            mc.set(
                "mcCntlMachineStatePush",
                scope.create_function(|_, _: Value| Ok(rc(ctx.borrow_mut().push_modal_state())))?,
            )?;
            mc.set(
                "mcCntlMachineStatePop",
                scope.create_function(|_, _: Value| Ok(rc(ctx.borrow_mut().pop_modal_state())))?,
            )?;
            mc.set(
                "mcCntlGetUnitsCurrent",
                scope.create_function(|_, _: Value| {
                    Ok((if ctx.borrow().units() == vision_math::LengthUnit::Inch { 200 } else { 210 }, NO_ERROR))
                })?,
            )?;
            let run: Function = lua.globals().get(format!("m{code}"))?;
            let (ok, message, gcode): (bool, Option<String>, Vec<String>) = run.call(H_PARAM)?;
            let result = if ok { Ok(gcode) } else { Err(message.unwrap_or_default()) };
            Ok(Call { mcode: code, result })
        })
    }
}

impl MCodeHandler for MacroHandler {
    fn call(&mut self, call: &UserMCode<'_>, ctx: &mut Context<'_>) -> Result<Vec<String>, HandlerError> {
        let failed = |e: mlua::Error| HandlerError::Failed(format!("Lua: {e}"));
        let fake = fake(&self.lua);
        let mc: Table = self.lua.globals().get("mc").map_err(failed)?;
        let locals = self.lua.create_table().map_err(failed)?;
        for (letter, value) in call.words() {
            let var: i64 = mc.get(format!("SV_{}", letter.to_ascii_uppercase())).map_err(failed)?;
            locals.set(var, *value).map_err(failed)?;
        }
        fake.set("locals", locals).map_err(failed)?;
        fake.set("stopped", false).map_err(failed)?;
        let executed = RefCell::new(Vec::new());
        let done = self.run_macro(call.code(), ctx, &executed).map_err(failed)?;
        self.executed.push(executed.into_inner());
        self.calls.push(done.clone());
        let stopped: bool = fake.get("stopped").map_err(failed)?;
        match (done.result, stopped) {
            // The macro already ran its G-code through mcCntlGcodeExecuteWait.
            (Ok(_), false) => Ok(Vec::new()),
            (Err(message), true) => Err(HandlerError::Failed(message)),
            (result, stopped) => Err(HandlerError::Failed(format!("inconsistent: {result:?}, stopped {stopped}"))),
        }
    }
}

/// `program` through the Mach4 macros on a fresh [`Rig`].
fn through_lua(program: &str, params: Option<Params>, camera: Camera) -> (Trace, MacroHandler) {
    let (rig, module) = Rig::new(params, camera);
    run_on(&rig, module, program)
}

/// `program` through the Mach4 macros on `rig`, the session on `module`.
fn run_on(rig: &Rig, module: vision_core::VisionModule, program: &str) -> (Trace, MacroHandler) {
    let lua = mach4_lua();
    mach_vision::install(&lua, Session::new(module));
    let mut handler = MacroHandler { lua, calls: Vec::new(), executed: Vec::new() };
    let (machine, end) = rig.run(program, &mut handler);
    let trace = Trace::collect(&machine, handler.calls.clone(), end);
    (trace, handler)
}

fn assert_same(program: &str, params: impl Fn() -> Option<Params>, camera: Camera) -> (Trace, MacroHandler) {
    let want = reference(program, params(), camera);
    let (got, handler) = through_lua(program, params(), camera);
    got.assert_matches(&want);
    (got, handler)
}

#[test]
fn rectangle_and_similarity_fits_through_the_macros_match_the_cli() {
    for (name, marks, camera) in [
        ("04-rectangle-fit.nc", 4, Camera::Sim),
        ("05-similarity-fit.nc", 3, Camera::Sim),
        ("04-rectangle-fit.nc", 4, Camera::Keyence),
        ("05-similarity-fit.nc", 3, Camera::Keyence),
    ] {
        let (trace, handler) = assert_same(&example(name), || None, camera);
        assert_eq!(trace.end, Ok("ended"), "{name}");
        let captures = trace.calls.iter().filter(|c| c.mcode == 281 && c.result.is_ok()).count();
        assert_eq!(captures, marks, "{name}");
        let i = trace.calls.iter().position(|c| c.mcode == 282).expect("M282");
        let gcode = trace.calls[i].result.as_ref().expect("M282 succeeds");
        // M282's four lines reached Mach4 through mcCntlGcodeExecuteWait, one call each.
        assert_eq!(&handler.executed[i], gcode, "{name}");
        assert!(gcode[1].starts_with("G52 X") && gcode[3].starts_with("G51 X"), "{gcode:?}");
        let (_, worst) = trace.cut_errors.iter().find(|(f, _)| f == "demo target").expect("the demo part");
        assert!(*worst < 2e-3, "{name}: cut error {worst} in");
        let status: Vec<String> = fake(&handler.lua).get("errors").expect("errors");
        assert_eq!(status.last().map(String::as_str), Some("M282: alignment applied"));
    }
}

/// M281 through the macros undoes the profile's lens: with a simulated lens (k1 −0.10, k2 0.01,
/// p1 0.002, p2 −0.001) and the perfect calibration that carries it, a mark read about 710 px
/// from the image centre, where the lens moves it some 4 px (0.008 in), lands within 0.0005 in
/// of where the simulator put it; with the lens parameters zeroed it misses by more.
#[test]
fn a_capture_through_the_macros_undoes_the_lens() {
    let mut world = World::default_world();
    world.camera.distortion = Some([-0.10, 0.01, 0.002, -0.001, 0.0]);
    // The camera 1.2 in left of and 0.8 in below fid 1 (nominal X0 Y0 of the part).
    let program = "G90 G20 G54\nT98 M6\nG0 X-1.2 Y-0.8\nM281\nM30\n";
    let miss = |lens: bool| {
        let sim = Sim::new(world.clone()).expect("the world with a lens");
        let mut params = sim_params(&sim);
        assert!(params.calibration.lens().is_some(), "the perfect calibration carries the lens");
        // One reading where the camera is: re-centring would read the mark at the centre.
        params.set("VisionRecenterPasses", 0_i64).expect("passes");
        if !lens {
            for name in ["VisionLensK1", "VisionLensK2", "VisionLensP1", "VisionLensP2", "VisionLensFocalPx"] {
                params.set(name, 0.0).expect("a lens parameter");
            }
        }
        let world = sim.world();
        let part = world.fixtures.iter().find(|f| f.name == "demo target").expect("the part");
        let truth = part.true_point(Point2::origin(), world.length_unit());
        let (rig, module) = Rig::with_sim(sim, Some(params), Camera::Sim);
        let (trace, _) = run_on(&rig, module, program);
        assert_eq!(trace.end, Ok("ended"), "{trace:?}");
        // Slot 0 (#500, #501): the observed mark, program frame (G54, so the part's frame).
        (Vector2::new(trace.pound[0], trace.pound[1]) - truth.coords).norm()
    };
    let (with, zeroed) = (miss(true), miss(false));
    assert!(with < 5e-4 && zeroed > 2e-3, "off by {with} in with the lens, {zeroed} in with it zeroed");
}

#[test]
fn calibration_verify_and_job_switch_through_the_macros_match_the_cli() {
    for (name, camera) in [
        ("01-calibrate-sheet.nc", Camera::Sim),
        ("02-verify-calibration.nc", Camera::Sim),
        ("07-switch-jobs.nc", Camera::Sim),
        ("07-switch-jobs.nc", Camera::Keyence),
    ] {
        let (trace, _) = assert_same(&example(name), || None, camera);
        assert_eq!(trace.end, Ok("ended"), "{name}");
        assert!(trace.calls.iter().all(|c| c.result.is_ok()), "{name}: {:?}", trace.calls);
    }
}

/// NG capture, K not calibrated, wrong tool: `mcCntlSetLastError` with the manual's message,
/// the cycle stopped, no G-code run by the macro, the pound block untouched.
#[test]
fn refusals_report_to_mach4_stop_the_program_and_change_nothing() {
    for (case, camera) in REFUSALS.iter().flat_map(|c| [(c, Camera::Sim), (c, Camera::Keyence)]) {
        let (program, says) = (case.program, case.says);
        let (trace, handler) = assert_same(program, || case.params(), camera);
        let last = trace.calls.last().expect("a Vision call");
        let message = last.result.as_ref().expect_err("refused");
        assert!(message.contains(says), "{program:?}: {message}");
        let errors: Vec<String> = fake(&handler.lua).get("errors").expect("errors");
        assert_eq!(errors.last(), Some(message), "{program:?}");
        assert!(fake(&handler.lua).get::<bool>("stopped").expect("flag"), "{program:?}");
        assert!(handler.executed.last().is_some_and(Vec::is_empty), "{program:?}: {:?}", handler.executed);
        assert!(trace.pound.iter().all(|v| *v == 0.0), "{program:?}: {:?}", trace.pound);
        assert!(trace.end.as_ref().is_err_and(|e| e.contains(message.as_str())), "{:?}", trace.end);
    }
}

#[test]
fn without_a_session_the_module_opens_the_profile_beside_mach4s() {
    let dir = std::env::temp_dir().join(format!("mach-vision-lua-{}", std::process::id()));
    let lua = mach4_lua();
    fake(&lua).set("machDir", dir.display().to_string()).expect("dir");
    let run: Function = lua.globals().get("m280").expect("m280");
    let (ok, message, gcode): (bool, Option<String>, Vec<String>) = run.call(H_PARAM).expect("runs");
    // No MachVision.toml yet: a fresh, disabled profile.
    assert!(!ok && gcode.is_empty());
    assert!(message.as_deref().is_some_and(|m| m.contains("not enabled")), "{message:?}");
    assert!(!dir.join("Profiles/Mach4Mill/MachVision.toml").exists());
    // The editor's test block calls the macro without hParam: a clear refusal, not a crash.
    let (ok, message, _): (bool, Option<String>, Vec<String>) =
        lua.globals().get::<Function>("m281").and_then(|f| f.call(())).expect("runs");
    assert!(!ok, "{message:?}");
    assert!(fake(&lua).get::<bool>("stopped").expect("flag"));
}

/// `mach_vision.get`: parameters and telemetry as Lua's own types after example 4; `nil, "why"`
/// for a name no parameter has.
#[test]
fn get_reads_parameters_and_telemetry_as_lua_values() {
    let (_, handler) = through_lua(&example("04-rectangle-fit.nc"), None, Camera::Sim);
    let got: (String, String, i64, bool, String, Value, String) = handler
        .lua
        .load(
            r#"
local v = require("mach_vision")
local status = v.get("VisionLastStatus")
local dots = v.get("VisionRun_DotCount")
local enabled = v.get("visionenabled")
local none, why = v.get("VisionNoSuch")
return status, math.type(dots), dots, enabled, math.type(v.get("VisionCal_K11")), none, why
"#,
        )
        .eval()
        .expect("runs");
    let (status, dots_type, dots, enabled, k_type, none, why) = got;
    assert_eq!(
        (status.as_str(), dots_type.as_str(), dots, enabled, k_type.as_str()),
        ("OK", "integer", 4, true, "float")
    );
    assert!(none.is_nil() && why.contains("unknown parameter \"VisionNoSuch\""), "{why}");
    assert!(!fake(&handler.lua).get::<bool>("stopped").expect("flag"), "a getter never stops the cycle");
}

/// A Mach4 callback that calls `get` while an M-code runs is told the session is busy; no second
/// session is opened, and afterwards `get` reads the M-code's session.
#[test]
fn get_during_an_mcode_says_busy_and_opens_nothing() {
    let (_rig, module) = Rig::new(None, Camera::Sim);
    let lua = mach4_lua();
    mach_vision::install(&lua, Session::new(module));
    let (during, after): (Option<String>, bool) = lua
        .load(
            r#"
local v = require("mach_vision")
local flag = mc.mcCntlGetLocalVarFlag
mc.mcCntlGetLocalVarFlag = function(...)
    local value, why = v.get("VisionEnabled")
    fake.during = fake.during or why
    return flag(...)
end
m280(7)
mc.mcCntlGetLocalVarFlag = flag
return fake.during, v.get("VisionEnabled")
"#,
        )
        .eval()
        .expect("runs");
    assert_eq!(during.as_deref(), Some("the Vision session is busy with an M-code"));
    // A session opened from Mach4's profile folder instead would be a fresh, disabled one.
    assert!(after, "get reads the installed session");
}

/// A session the module opens from a profile publishes its state beside it: after a refused
/// M281, `P.panel/state.json` shows the refusal, as `mach_vision.get` does.
#[test]
fn a_session_opened_from_a_profile_publishes_beside_it() {
    let dir = std::env::temp_dir().join(format!("mach-vision-lua-panel-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("tmp");
    let profile = dir.join("Shop.toml");
    let lua = mach4_lua();
    let open: Function = lua.load(r#"return require("mach_vision").open"#).eval().expect("open");
    let (ok, message, _): (bool, Option<String>, Vec<String>) = open.call(profile.display().to_string()).expect("runs");
    assert!(ok, "{message:?}");
    let m281: Function = lua.globals().get("m281").expect("m281");
    let (ok, message, _): (bool, Option<String>, Vec<String>) = m281.call(H_PARAM).expect("runs");
    let message = message.expect("refused");
    assert!(!ok && message.contains("not enabled"), "{message}");
    let status: String = lua.load(r#"return require("mach_vision").get("VisionLastStatus")"#).eval().expect("get");
    assert!(!status.is_empty() && message.contains(status.as_str()), "{status:?}");

    let folder = dir.join("Shop.panel");
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(10);
    let state = loop {
        match panel::read(&folder) {
            Ok(state) if state.last.is_some() => break state,
            _ if std::time::Instant::now() < deadline => std::thread::sleep(std::time::Duration::from_millis(10)),
            other => panic!("no state with the call: {other:?}"),
        }
    };
    let last = state.last.expect("the call");
    assert!(last.mcode == 281 && !last.ok && last.message == message, "{last:?}");
    assert_eq!(state.telemetry.get("VisionLastStatus"), Some(&PanelValue::Text(status)));
    let _ = std::fs::remove_dir_all(&dir);
}

/// What reaches Mach4's message line is one escaped line, whatever it quotes (here a profile
/// line holding a terminal escape, which the TOML parser's message quotes). The escape is in the
/// file's text, not its name: Windows forbids control characters in file names.
#[test]
fn messages_to_the_operator_are_escaped() {
    let dir = std::env::temp_dir().join(format!("mach-vision-lua-esc-{}", std::process::id()));
    let profile = dir.join("Profiles/Mach4Mill");
    std::fs::create_dir_all(&profile).expect("folder");
    std::fs::write(profile.join("MachVision.toml"), "[vision]\nVisionEnabled = \u{1b}[31m\n").expect("profile");
    let lua = mach4_lua();
    fake(&lua).set("machDir", dir.display().to_string()).expect("dir");
    let run: Function = lua.globals().get("m280").expect("m280");
    let (ok, message, _): (bool, Option<String>, Vec<String>) = run.call(H_PARAM).expect("runs");
    assert!(!ok);
    let message = message.expect("a message");
    assert!(message.contains("\\u{1b}[31m") && !message.contains('\u{1b}'), "{message:?}");
    assert!(!message.contains('\n'), "{message:?}");
    let errors: Vec<String> = fake(&lua).get("errors").expect("errors");
    assert_eq!(errors.last(), Some(&message));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Mach4's own failures (a non-zero return code, an answer that is not a unit) reach the
/// operator naming the call, and stop the cycle.
#[test]
fn mach4_return_codes_are_reported_by_name() {
    let (_rig, module) = Rig::new(None, Camera::Sim);
    let lua = mach4_lua();
    mach_vision::install(&lua, Session::new(module));
    lua.load(
        r#"
        function mc.mcCntlGetPoundVar(inst, n) return 0.0, mc.MERROR_NOERROR end
        function mc.mcToolGetCurrent(inst) return 98, mc.MERROR_NOERROR end
        function mc.mcCntlGetUnitsCurrent(inst) return fake.units, mc.MERROR_NOERROR end
        function mc.mcAxisGetPos(inst, axis) return 0.0, mc.MERROR_NOERROR end
        function mc.mcCntlGcodeExecuteWait(inst, code) return mc.MERROR_NOT_NOW end
        fake.units = 200
        "#,
    )
    .exec()
    .expect("mc");
    let run = |m: &str| -> (bool, Option<String>) {
        let f: Function = lua.globals().get(m).expect("macro");
        let (ok, message, _): (bool, Option<String>, Vec<String>) = f.call(H_PARAM).expect("runs");
        (ok, message)
    };
    let (ok, message) = run("m280");
    assert!(!ok);
    let message = message.expect("a message");
    assert!(message.contains("mc.mcCntlGcodeExecuteWait returned error code -18"), "{message}");
    let errors: Vec<String> = fake(&lua).get("errors").expect("errors");
    assert_eq!(errors.last(), Some(&message));
    assert!(fake(&lua).get::<bool>("stopped").expect("flag"));

    fake(&lua).set("units", 215).expect("units");
    let (ok, message) = run("m281");
    assert!(!ok);
    assert!(message.is_some_and(|m| m.contains("neither 200 (G20) nor 210 (G21)")));
}

/// A refusal whose cycle stop fails (an error code, a Lua error, no such call) raises a Lua
/// error with both messages: Mach4 aborts the macro instead of running on after it.
#[test]
fn a_refusal_that_cannot_stop_the_cycle_raises_a_lua_error_with_both_messages() {
    for (stop, says) in [
        (
            "function mc.mcCntlCycleStop(inst) return mc.MERROR_NOT_NOW end",
            "mc.mcCntlCycleStop returned error code -18",
        ),
        ("function mc.mcCntlCycleStop(inst) error('cycle stop broken') end", "cycle stop broken"),
        ("mc.mcCntlCycleStop = nil", "this Mach4 has no mc.mcCntlCycleStop"),
    ] {
        let lua = mach4_lua();
        let dir = std::env::temp_dir().join(format!("mach-vision-lua-stop-{}", std::process::id()));
        fake(&lua).set("machDir", dir.display().to_string()).expect("dir");
        lua.load(stop).exec().expect("mc");
        // No profile yet: M280 is refused (not enabled), and the stop fails.
        let run: Function = lua.globals().get("m280").expect("m280");
        let e = run.call::<(bool, Option<String>, Vec<String>)>(H_PARAM).expect_err("a Lua error");
        let text = e.to_string();
        assert!(text.contains("not enabled") && text.contains(says) && text.contains("could not be stopped"), "{text}");
        let errors: Vec<String> = fake(&lua).get("errors").expect("errors");
        assert!(errors.last().is_some_and(|m| m.contains("not enabled")), "{errors:?}");
    }
}

/// One Vision call of a Mach4 instance in [`two_mach4_instances_on_one_profile_never_lose_a_calibration_or_a_job`].
#[derive(Debug, Clone, Copy, PartialEq)]
enum Op {
    /// `M283 C1` over the sheet (m283.mcs).
    Calibrate,
    /// `M284 P<job>` (m284.mcs).
    Job(u32),
}

/// Every interleaving of `a` and `b` (each keeps its order), as (instance, op) pairs.
fn interleavings(a: &[Op], b: &[Op]) -> Vec<Vec<(usize, Op)>> {
    let first = |who: usize, op: Op, rest: Vec<Vec<(usize, Op)>>| -> Vec<Vec<(usize, Op)>> {
        rest.into_iter().map(|t| [vec![(who, op)], t].concat()).collect()
    };
    match (a.split_first(), b.split_first()) {
        (None, None) => vec![Vec::new()],
        (Some((x, rest)), None) => first(0, *x, interleavings(rest, b)),
        (None, Some((y, rest))) => first(1, *y, interleavings(a, rest)),
        (Some((x, ra)), Some((y, rb))) => {
            let mut all = first(0, *x, interleavings(ra, b));
            all.extend(first(1, *y, interleavings(a, rb)));
            all
        }
    }
}

/// Two Mach4 instances (two Lua states, each with the module and its own session) on one
/// profile file (issue 26, "calibration lost"): in every interleaving of their M283
/// calibrations and M284 job switches, run through the real m283.mcs and m284.mcs, the file
/// keeps the newest calibration (K and `VisionCal_Date`) and the last job after every call. A
/// save that wrote the session's whole parameter set would put back the stale K (or job) of
/// the instance that read the file before the other's save. Both cameras are one simulated
/// world with one noise stream, so every calibration has its own K.
#[test]
fn two_mach4_instances_on_one_profile_never_lose_a_calibration_or_a_job() {
    let sim = vision_host::testkit::sim();
    let registry = vision_host::cameras(Some(&sim));
    let start = vision_host::testkit::uncalibrated_params(&sim);
    let dir = std::env::temp_dir().join(format!("mach-vision-lua-shared-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("tmp");
    let path = dir.join("MachVision.toml");
    let on_file = || vision_core::ProfileStore::new(&path).with_defaults(registry.params()).load().expect("load");
    let programs = [
        vec![Op::Calibrate],
        vec![Op::Job(2)],
        vec![Op::Calibrate, Op::Job(1)],
        vec![Op::Job(2), Op::Calibrate],
        vec![Op::Calibrate, Op::Calibrate],
    ];
    let mut runs = 0;
    for a in &programs {
        for b in &programs {
            for order in interleavings(a, b) {
                vision_core::ProfileStore::new(&path).save(&start).expect("a fresh profile");
                let mut handlers = [0, 1].map(|_| {
                    let lua = mach4_lua();
                    mach_vision::install(&lua, Session::open(&path, &registry).expect("open"));
                    MacroHandler { lua, calls: Vec::new(), executed: Vec::new() }
                });
                let (mut newest, mut job) = (start.calibration.clone(), 0);
                let mut seen = vec![newest.cal_k()];
                for (who, op) in &order {
                    let program = match op {
                        Op::Calibrate => "G90 G20 G54\nT98 M6\nG0 X-2.5 Y-4.0\nM283 C1\nM30\n".to_string(),
                        Op::Job(j) => format!("M284 P{j}\nM30\n"),
                    };
                    let (_, end) = Rig { sim: sim.clone(), emulator: None }.run(&program, &mut handlers[*who]);
                    assert!(end.is_ok(), "{order:?}: {who}'s {op:?}: {end:?}");
                    let call = handlers[*who].calls.last().expect("a Vision call");
                    assert!(call.result.is_ok(), "{order:?}: {who}'s {op:?}: {call:?}");
                    let file = on_file();
                    match op {
                        Op::Calibrate => {
                            // This instance's calibration, new (never seen in this run) and dated.
                            assert!(!seen.contains(&file.cal_k()), "{order:?}: {who}'s {op:?}: K {}", file.cal_k());
                            assert!(file.cal_date() >= newest.cal_date() && !file.cal_date().is_empty());
                            newest = file.calibration.clone();
                            seen.push(newest.cal_k());
                        }
                        Op::Job(j) => job = i64::from(*j),
                    }
                    assert_eq!(file.calibration, newest, "{order:?}: after {who}'s {op:?}");
                    assert_eq!(file.active_job(), job, "{order:?}: after {who}'s {op:?}");
                    let status: Vec<String> = fake(&handlers[*who].lua).get("errors").expect("errors");
                    let says = if *op == Op::Calibrate { "M283: calibration done and saved" } else { "M284" };
                    assert!(status.last().is_some_and(|m| m.contains(says)), "{order:?}: {status:?}");
                    runs += 1;
                }
            }
        }
    }
    assert!(runs > 150, "{runs}");
    let _ = std::fs::remove_dir_all(&dir);
}
