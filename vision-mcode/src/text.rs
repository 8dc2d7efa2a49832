//! The G-code text of the Vision module's commands, per controller: the one place a
//! [`MachineCommand`] becomes lines.
//!
//! Numbers are written with fixed decimals (`vision_math::chain`: 7 for positions and shifts,
//! 9 for angles, 10 for scale factors), which move no point by more than 1e-6 units and never
//! read `NaN`, `inf` or `-0`. A new controller is one row of [`TEXTS`].

use vision_core::{Controller, MachineCommand, MachineError, MachineErrorKind};
use vision_math::chain::{fixed, ANGLE_DECIMALS, POSITION_DECIMALS, SCALE_DECIMALS};

/// How a controller's G-code holds an alignment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AlignmentWords {
    /// The `G51` scale, `G68` rotation and `G52` shift modals, cancelled together by
    /// `G69 G50 G52 X0 Y0` (Mach4, seed 002's MachineMotion).
    Modal,
    /// No rotation or scale modal: the work offset is rotated (`G10 L2 P0 R`) and `G52` shifts
    /// (LinuxCNC).
    WorkRotation,
    /// No alignment in its G-code at all: the host that runs the program maps its moves
    /// ([`MachineCommand::AlignMoves`]; Grbl).
    Host,
}

/// One controller's G-code text.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ControllerText {
    /// The controller's name ([`Controller::name`]).
    pub controller: &'static str,
    /// How its G-code holds an alignment.
    pub alignment: AlignmentWords,
}

/// Every controller's text, one row each; a test checks that every controller of
/// [`vision_core::CONTROLLERS`] has one.
pub static TEXTS: [ControllerText; 4] = [
    ControllerText { controller: "mach4", alignment: AlignmentWords::Modal },
    ControllerText { controller: "linuxcnc", alignment: AlignmentWords::WorkRotation },
    ControllerText { controller: "machinemotion", alignment: AlignmentWords::Modal },
    ControllerText { controller: "grbl", alignment: AlignmentWords::Host },
];

/// Why a command has no text.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum TextError {
    /// No row of [`TEXTS`] names the controller.
    #[error("no G-code text for the controller '{controller}'")]
    UnknownController {
        /// The controller's name.
        controller: &'static str,
    },
    /// The controller's G-code cannot say it (a rotation modal on LinuxCNC).
    #[error("{controller} has no G-code for {command}")]
    Unsupported {
        /// The controller's name.
        controller: &'static str,
        /// The command's name ([`MachineCommand::name`]).
        command: &'static str,
    },
    /// The command is no G-code on this controller: the host applies it to the moves it sends
    /// (the machine runs no line for it).
    #[error("{controller} runs no G-code for {command}: the host applies it to the moves it sends")]
    AppliedByHost {
        /// The controller's name.
        controller: &'static str,
        /// The command's name ([`MachineCommand::name`]).
        command: &'static str,
    },
    /// A number in the command is NaN or infinite: nothing is written.
    #[error("{command} carries a number that is not finite; no G-code written")]
    NotFinite {
        /// The command's name.
        command: &'static str,
    },
}

impl From<TextError> for MachineError {
    fn from(e: TextError) -> Self {
        MachineError::new(MachineErrorKind::RefusedGcode, e)
    }
}

/// The text of `controller`, if [`TEXTS`] has it.
#[must_use]
pub fn text_of(controller: &dyn Controller) -> Option<&'static ControllerText> {
    TEXTS.iter().find(|t| t.controller == controller.name())
}

/// The lines `controller` runs for `command`, in order.
///
/// # Errors
/// [`TextError`]: an unknown controller, a command its G-code cannot say, a non-finite number.
pub fn gcode(controller: &dyn Controller, command: &MachineCommand) -> Result<Vec<String>, TextError> {
    let text = text_of(controller).ok_or(TextError::UnknownController { controller: controller.name() })?;
    if !command.is_finite() {
        return Err(TextError::NotFinite { command: command.name() });
    }
    let unsupported = || TextError::Unsupported { controller: text.controller, command: command.name() };
    let modal = text.alignment == AlignmentWords::Modal;
    let host = text.alignment == AlignmentWords::Host;
    let p = |v: f64| fixed(v, POSITION_DECIMALS);
    let line = match *command {
        MachineCommand::CancelAlignment if modal => "G69 G50 G52 X0 Y0".to_string(),
        MachineCommand::ClearShift if !host => "G52 X0 Y0".to_string(),
        MachineCommand::SetShift(v) if !host => format!("G52 X{} Y{}", p(v.x), p(v.y)),
        MachineCommand::SetRotation { centre, deg } if modal => {
            format!("G68 X{} Y{} R{}", p(centre.x), p(centre.y), fixed(deg, ANGLE_DECIMALS))
        }
        MachineCommand::SetScale(s) if modal => {
            format!("G51 X{} Y{}", fixed(s.x, SCALE_DECIMALS), fixed(s.y, SCALE_DECIMALS))
        }
        MachineCommand::SetWorkRotation { deg } if text.alignment == AlignmentWords::WorkRotation => {
            format!("G10 L2 P0 R{}", fixed(deg, ANGLE_DECIMALS))
        }
        MachineCommand::MoveTo(t) => format!("G90 G0 X{} Y{}", p(t.x), p(t.y)),
        MachineCommand::MoveBy(d) => return Ok(vec![format!("G91 G0 X{} Y{}", p(d.x), p(d.y)), "G90".to_string()]),
        MachineCommand::MoveZBy(dz) => return Ok(vec![format!("G91 G0 Z{}", p(dz)), "G90".to_string()]),
        MachineCommand::AlignMoves(_) | MachineCommand::CancelMoveAlignment if host => {
            return Err(TextError::AppliedByHost { controller: text.controller, command: command.name() })
        }
        MachineCommand::CancelAlignment
        | MachineCommand::ClearShift
        | MachineCommand::SetShift(_)
        | MachineCommand::SetRotation { .. }
        | MachineCommand::SetScale(_)
        | MachineCommand::SetWorkRotation { .. }
        | MachineCommand::AlignMoves(_)
        | MachineCommand::CancelMoveAlignment => return Err(unsupported()),
    };
    Ok(vec![line])
}

/// The lines `controller` runs for `commands`, in order ([`gcode`] of each).
///
/// # Errors
/// The first command's [`TextError`].
pub fn lines(controller: &dyn Controller, commands: &[MachineCommand]) -> Result<Vec<String>, TextError> {
    let mut all = Vec::new();
    for command in commands {
        all.extend(gcode(controller, command)?);
    }
    Ok(all)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use vision_core::controller::{linuxcnc, modal_commands, Grbl, LinuxCnc, Mach4, MachineMotion};
    use vision_core::CONTROLLERS;
    use vision_math::linuxcnc::LinuxCncAlignment;
    use vision_math::{AlignmentChain, Point2, Vector2};

    /// One of each command, with numbers that show the decimals and the sign of zero.
    fn each_command() -> [MachineCommand; 11] {
        [
            MachineCommand::CancelAlignment,
            MachineCommand::ClearShift,
            MachineCommand::SetShift(Vector2::new(-0.000_000_01, 0.125)),
            MachineCommand::SetRotation { centre: Point2::new(3.0, -2.0), deg: -0.000_000_000_01 },
            MachineCommand::SetScale(Vector2::new(1.0, 0.999_5)),
            MachineCommand::SetWorkRotation { deg: -10.75 },
            MachineCommand::MoveTo(Point2::new(1.0, -0.25)),
            MachineCommand::MoveBy(Vector2::new(0.1, -0.1)),
            MachineCommand::MoveZBy(-0.5),
            MachineCommand::AlignMoves(AlignmentChain::IDENTITY),
            MachineCommand::CancelMoveAlignment,
        ]
    }

    #[test]
    fn every_command_on_every_controller_is_its_exact_text() {
        let modal: [Option<&[&str]>; 11] = [
            Some(&["G69 G50 G52 X0 Y0"]),
            Some(&["G52 X0 Y0"]),
            Some(&["G52 X0.0000000 Y0.1250000"]),
            Some(&["G68 X3.0000000 Y-2.0000000 R0.000000000"]),
            Some(&["G51 X1.0000000000 Y0.9995000000"]),
            None,
            Some(&["G90 G0 X1.0000000 Y-0.2500000"]),
            Some(&["G91 G0 X0.1000000 Y-0.1000000", "G90"]),
            Some(&["G91 G0 Z-0.5000000", "G90"]),
            None,
            None,
        ];
        let mut linuxcnc = modal;
        linuxcnc[0] = None;
        linuxcnc[3] = None;
        linuxcnc[4] = None;
        linuxcnc[5] = Some(&["G10 L2 P0 R-10.750000000"]);
        let mut grbl = modal;
        grbl[..6].fill(None);
        let controllers =
            [(&Mach4 as &dyn Controller, modal), (&MachineMotion, modal), (&LinuxCnc, linuxcnc), (&Grbl, grbl)];
        for (controller, want) in controllers {
            for (command, want) in each_command().iter().zip(want) {
                let got = gcode(controller, command);
                match want {
                    Some(lines) => assert_eq!(got, Ok(lines.iter().map(|l| (*l).to_string()).collect())),
                    None if controller.name() == "grbl"
                        && matches!(command, MachineCommand::AlignMoves(_) | MachineCommand::CancelMoveAlignment) =>
                    {
                        assert_eq!(got, Err(TextError::AppliedByHost { controller: "grbl", command: command.name() }));
                    }
                    None => assert_eq!(
                        got,
                        Err(TextError::Unsupported { controller: controller.name(), command: command.name() })
                    ),
                }
            }
        }
    }

    #[test]
    fn every_controller_has_a_text() {
        for c in CONTROLLERS {
            assert!(text_of(c).is_some(), "{}", c.name());
        }
        assert_eq!(TEXTS.len(), CONTROLLERS.len());
    }

    #[test]
    fn an_alignment_is_the_lines_the_controllers_run() {
        let chain = AlignmentChain {
            scale: Vector2::new(1.0, 0.999_5),
            center: Point2::new(3.0, -2.0),
            rotation_deg: -0.000_000_000_01,
            shift: Vector2::new(-0.000_000_01, 0.125),
        };
        let mach4 = lines(&Mach4, &modal_commands(&chain).expect("finite")).expect("text");
        let want = [
            "G69 G50 G52 X0 Y0",
            "G52 X0.0000000 Y0.1250000",
            "G68 X3.0000000 Y-2.0000000 R0.000000000",
            "G51 X1.0000000000 Y0.9995000000",
        ];
        assert_eq!(mach4, want);
        let quarter = AlignmentChain {
            scale: Vector2::new(1.0, 1.0),
            center: Point2::new(1.0, 0.0),
            rotation_deg: 90.0,
            shift: Vector2::new(0.0, 2.0),
        };
        let a = LinuxCncAlignment::from_chain(&quarter, 0.0, 2.0).expect("rigid");
        let applied = lines(&LinuxCnc, &linuxcnc::alignment_commands(&a).expect("finite")).expect("text");
        assert_eq!(applied, ["G10 L2 P0 R90.000000000", "G52 X1.0000000 Y-1.0000000"]);
        let cancel = lines(&LinuxCnc, &linuxcnc::cancel_commands(-12.25).expect("finite")).expect("text");
        assert_eq!(cancel, ["G52 X0 Y0", "G10 L2 P0 R-12.250000000"]);
    }

    #[test]
    fn a_non_finite_number_is_refused_as_a_machine_refusal() {
        let e = gcode(&Mach4, &MachineCommand::MoveTo(Point2::new(f64::NAN, 0.0))).expect_err("NaN");
        assert_eq!(e, TextError::NotFinite { command: "MoveTo" });
        let m = MachineError::from(e);
        assert_eq!(m.kind(), MachineErrorKind::RefusedGcode);
        assert_eq!(m.to_string(), "machine: MoveTo carries a number that is not finite; no G-code written");
    }

    /// Finite numbers of every size, tiny negatives (that round to zero) included.
    fn number() -> impl Strategy<Value = f64> {
        prop_oneof![-1e6..1e6f64, -1e-6..1e-6f64, proptest::num::f64::NORMAL.prop_filter("finite", |v| v.abs() < 1e9)]
    }

    fn command() -> impl Strategy<Value = MachineCommand> {
        (0usize..9, number(), number(), number()).prop_map(|(k, a, b, c)| match k {
            0 => MachineCommand::CancelAlignment,
            1 => MachineCommand::ClearShift,
            2 => MachineCommand::SetShift(Vector2::new(a, b)),
            3 => MachineCommand::SetRotation { centre: Point2::new(a, b), deg: c },
            4 => MachineCommand::SetScale(Vector2::new(a, b)),
            5 => MachineCommand::SetWorkRotation { deg: c },
            6 => MachineCommand::MoveTo(Point2::new(a, b)),
            7 => MachineCommand::MoveBy(Vector2::new(a, b)),
            _ => MachineCommand::MoveZBy(c),
        })
    }

    proptest! {
        /// No command with finite numbers writes NaN, inf or a negative zero, on any controller.
        #[test]
        fn finite_commands_write_finite_words(command in command()) {
            for controller in CONTROLLERS {
                let Ok(lines) = gcode(controller, &command) else { continue };
                for line in &lines {
                    for word in line.split(' ') {
                        let value = &word[1..];
                        prop_assert!(!value.is_empty() && word.starts_with(|c: char| c.is_ascii_uppercase()), "{line}");
                        let v: f64 = value.parse().map_err(|_| TestCaseError::fail(format!("{word} in {line}")))?;
                        prop_assert!(v.is_finite(), "{line}");
                        prop_assert!(!(v == 0.0 && value.starts_with('-')), "negative zero in {line}");
                    }
                }
            }
        }
    }
}
