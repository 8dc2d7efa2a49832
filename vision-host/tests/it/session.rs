//! The session on the simulated machine: the examples run through it as `mach-vision run` runs
//! them, and refusals stop the program changing nothing.

use vision_host::testkit::{clock, example, reference, sim, Camera, Rig, REFUSALS};
use vision_host::{registry, HostError, ProgramHandler, Session};
use vision_mcode::McodeError;

#[test]
fn alignment_examples_emit_the_modal_lines_and_cut_the_part() {
    for (name, marks) in [("04-rectangle-fit.nc", 4), ("05-similarity-fit.nc", 3)] {
        let trace = reference(&example(name), None, Camera::Sim);
        assert_eq!(trace.end, Ok("ended"), "{name}");
        let m281 = trace.calls.iter().filter(|c| c.mcode == 281 && c.result.is_ok()).count();
        assert_eq!(m281, marks, "{name}");
        let m282 = trace.calls.iter().find(|c| c.mcode == 282).expect("M282");
        let gcode = m282.result.as_ref().expect("M282 succeeds");
        assert_eq!(gcode.len(), 4, "{name}: {gcode:?}");
        assert!(gcode[2].starts_with("G68 X"), "{name}: {gcode:?}");
        let (_, worst) = trace.cut_errors.iter().find(|(f, _)| f == "demo target").expect("the demo part");
        assert!(*worst < 2e-3, "{name}: cut error {worst} in");
    }
}

#[test]
fn the_keyence_driver_against_the_loopback_emulator_runs_example_7() {
    let trace = reference(&example("07-switch-jobs.nc"), None, Camera::Keyence);
    assert_eq!(trace.end, Ok("ended"));
    assert!(trace.calls.iter().all(|c| c.result.is_ok()), "{:?}", trace.calls);
}

#[test]
fn calibration_verify_and_job_examples_run_to_their_end() {
    for name in ["01-calibrate-sheet.nc", "02-verify-calibration.nc", "07-switch-jobs.nc"] {
        let trace = reference(&example(name), None, Camera::Sim);
        assert_eq!(trace.end, Ok("ended"), "{name}");
        assert!(trace.calls.iter().all(|c| c.result.is_ok()), "{name}: {:?}", trace.calls);
    }
}

/// The error paths stop the program at the M-code with the manual's message and leave the
/// pound block as it was.
#[test]
fn refusals_stop_the_program_and_change_nothing() {
    for case in REFUSALS {
        let (program, says) = (case.program, case.says);
        let trace = reference(program, case.params(), Camera::Sim);
        let last = trace.calls.last().expect("a Vision call");
        let message = last.result.as_ref().expect_err("refused");
        assert!(message.contains(says), "{program:?}: {message}");
        let end = trace.end.as_ref().expect_err("stopped");
        assert!(end.contains(message.as_str()), "{end}");
        assert!(trace.pound.iter().all(|v| *v == 0.0), "{program:?}: {:?}", trace.pound);
    }
}

#[test]
fn a_fresh_profile_is_disabled_until_enabled() {
    let path = std::env::temp_dir().join(format!("vision-host-fresh-{}.toml", std::process::id()));
    let mut session = Session::open(&path, &registry()).expect("a missing profile is a fresh one");
    let sim = sim();
    let mut interp = vision_driver_sim::SimMachine::new(&sim).expect("machine").interpreter().clone();
    let mut sink = |_: &vision_gcode::Event| {};
    let mut ctx = interp.context(&mut sink);
    let clock = clock();
    let mut host = vision_host::ContextMachine::new(&mut ctx, &clock, &vision_host::controller::Mach4);
    let e = session.mcode(&mut host, 280, &[]).expect_err("disabled");
    assert!(matches!(e, HostError::Mcode(McodeError::Vision(_))), "{e:?}");
    assert!(e.to_string().contains("not enabled"), "{e}");
    let e = session.mcode(&mut host, 281, &[('X', 1.0)]).expect_err("bad word");
    assert!(matches!(e, HostError::Mcode(McodeError::UnknownWord { .. })), "{e:?}");
    assert!(!path.exists(), "a refusal saves nothing");
}

/// After an aligned program that cancelled its alignment itself, the simulated machine (which
/// can tell) lets the next program calibrate; the session forgets the alignment.
#[test]
fn a_program_after_an_aligned_one_sees_the_cancel() {
    let first = example("04-rectangle-fit.nc");
    // Example 1 from where example 4 left the head: back over the sheet's start dot first.
    let second = "G90 G20 G54\nT98 M6\nG0 X-2.5 Y-4.0\nM283 C1\nM30\n".to_string();
    let (rig, module) = Rig::new(None, Camera::Sim);
    let mut handler = ProgramHandler::new(Session::new(module), &vision_host::controller::Mach4, clock());
    let mut machine = vision_driver_sim::SimMachine::new(&rig.sim).expect("machine");
    for program in [&first, &second] {
        machine.run_program(program, Some(&mut handler), &mut |_: &vision_gcode::Event| {}).ok();
    }
    let records = handler.take_records();
    let m283 = records.last().expect("M283");
    assert_eq!(m283.mcode, 283);
    assert!(m283.result.is_ok(), "{m283:?}");
    assert!(handler.session().alignment().is_none());
}
