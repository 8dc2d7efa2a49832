//! [`PyHost`]: [`Machine`] over the Python object LinuxCNC's remap hands the session
//! (`hosts/linuxcnc/remap.py`'s `Host`).

use std::cell::RefCell;

use pyo3::call::PyCallArgs;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use vision_host::{
    printable_line, Controller, Machine, MachineCommand, MachineError, MachineErrorKind, MAX_MESSAGE_CHARS,
};
use vision_math::{LengthUnit, Point2, Vector2};

use crate::words::shown;
use crate::VisionError;

/// The controller behind a Python `Host` object: each [`Machine`] call is a method call on it
/// (`program_position()`, `pound(n)`, `execute(line)`, …; the table in
/// `hosts/linuxcnc/README.md`). Lengths are in the program's units, angles in degrees.
///
/// It is [`vision_host::controller::LinuxCnc`]: M282 rotates the G5x system and shifts with
/// G52, and the alignment's state is read from the machine at every call.
///
/// A Python exception raised by a method, or a value of the wrong type, becomes
/// a [`MachineError`] with Python's message; nothing here panics on what Python returns. A
/// `BaseException` that is not an `Exception` (`KeyboardInterrupt`, `SystemExit`) fails the
/// call too, and is kept to be raised unchanged ([`PyHost::take_interrupt`]).
pub struct PyHost<'py> {
    object: Bound<'py, PyAny>,
    /// The first `KeyboardInterrupt`, `SystemExit` or other non-`Exception` a method raised.
    interrupt: RefCell<Option<PyErr>>,
}

impl<'py> PyHost<'py> {
    /// The host over `object` (a `remap.Host`).
    #[must_use]
    pub fn new(object: Bound<'py, PyAny>) -> PyHost<'py> {
        PyHost { object, interrupt: RefCell::new(None) }
    }

    /// The first `BaseException` that is not an `Exception` a method raised (the operator's
    /// Ctrl-C, `sys.exit`): the session raises it unchanged instead of a `VisionError`.
    pub fn take_interrupt(&self) -> Option<PyErr> {
        self.interrupt.borrow_mut().take()
    }

    /// The Python object.
    #[must_use]
    pub fn object(&self) -> &Bound<'py, PyAny> {
        &self.object
    }

    /// `object.method(*args)`.
    ///
    /// # Errors
    /// A [`MachineError`] with the exception's message when the method is missing or raises.
    pub fn call(&self, method: &str, args: impl PyCallArgs<'py>) -> Result<Bound<'py, PyAny>, MachineError> {
        self.object.call_method1(method, args).map_err(|e| {
            let py = self.object.py();
            if !e.is_instance_of::<PyException>(py) {
                let mut kept = self.interrupt.borrow_mut();
                if kept.is_none() {
                    *kept = Some(e.clone_ref(py));
                }
            }
            python_error(py, method, &e)
        })
    }

    /// `object.method(*args)` as a `T`.
    ///
    /// # Errors
    /// As [`PyHost::call`], and when the result is not a `T` (`what` names it in the message).
    pub fn value<T>(&self, method: &str, args: impl PyCallArgs<'py>, what: &str) -> Result<T, MachineError>
    where
        T: FromPyObjectOwned<'py>,
    {
        let value = self.call(method, args)?;
        value.extract::<T>().map_err(|_| comm(format!("Host.{method}() returned {}, not {what}", shown(&value))))
    }

    /// `object.method(*args)` as an X, Y pair (`(x, y)`).
    fn pair(&self, method: &str, args: impl PyCallArgs<'py>) -> Result<(f64, f64), MachineError> {
        self.value(method, args, "an (x, y) pair of numbers")
    }
}

/// The operator's view of Python exception `e`, raised by `Host.method`: a `VisionError`'s
/// message as it is (the remap wrote it for the operator), any other exception with its type.
/// A failed call or an unusable answer.
fn comm(message: impl Into<String>) -> MachineError {
    MachineError::new(MachineErrorKind::Communication, message.into())
}

fn python_error(py: Python<'_>, method: &str, e: &PyErr) -> MachineError {
    let text =
        if e.is_instance_of::<VisionError>(py) { e.value(py).to_string() } else { format!("Host.{method}(): {e}") };
    comm(printable_line(&text, MAX_MESSAGE_CHARS))
}

impl Machine for PyHost<'_> {
    fn controller(&self) -> &'static dyn Controller {
        &vision_host::controller::LinuxCnc
    }

    fn gcode(&self, command: &MachineCommand) -> Result<Vec<String>, MachineError> {
        Ok(vision_mcode::gcode(self.controller(), command)?)
    }

    fn execute(&mut self, line: &str) -> Result<(), MachineError> {
        self.call("execute", (line,)).map(|_| ()).map_err(|e| e.with_kind(MachineErrorKind::RefusedGcode))
    }

    /// `Host.save_modal_state()`: LinuxCNC's `M70`, and the motion mode, which `M72` does not
    /// put back.
    fn save_modal_state(&mut self) -> Result<(), MachineError> {
        self.call("save_modal_state", ()).map(|_| ()).map_err(|e| e.with_kind(MachineErrorKind::RefusedGcode))
    }

    /// `Host.restore_modal_state()`: `M72`, then the saved motion mode set again.
    fn restore_modal_state(&mut self) -> Result<(), MachineError> {
        self.call("restore_modal_state", ()).map(|_| ()).map_err(|e| e.with_kind(MachineErrorKind::RefusedGcode))
    }

    fn pound(&self, index: u32) -> Result<f64, MachineError> {
        self.value("pound", (index,), "a number")
    }

    fn set_pound(&mut self, index: u32, value: f64) -> Result<(), MachineError> {
        self.call("set_pound", (index, value)).map(|_| ())
    }

    fn active_tool(&self) -> Result<u32, MachineError> {
        self.value("tool", (), "a tool number")
    }

    fn tool_offset(&self, tool: u32) -> Result<Vector2<f64>, MachineError> {
        let (x, y) = self.pair("tool_offset", (tool,))?;
        Ok(Vector2::new(x, y))
    }

    fn set_tool_offset(&mut self, tool: u32, offset: Vector2<f64>) -> Result<(), MachineError> {
        self.call("set_tool_offset", (tool, offset.x, offset.y)).map(|_| ())
    }

    /// `Host.applied_tool_offset()`, when the host has it (LinuxCNC's remap: the offset `G43`
    /// applied); `None` for a host without it, or whose method returns `None` (cannot tell).
    fn applied_tool_offset(&self) -> Result<Option<Vector2<f64>>, MachineError> {
        if !self.object.hasattr("applied_tool_offset").unwrap_or(false) {
            return Ok(None);
        }
        let pair: Option<(f64, f64)> = self.value("applied_tool_offset", (), "an (x, y) pair of numbers or None")?;
        Ok(pair.map(|(x, y)| Vector2::new(x, y)))
    }

    fn program_position(&self) -> Result<Point2<f64>, MachineError> {
        let (x, y) = self.pair("program_position", ())?;
        Ok(Point2::new(x, y))
    }

    fn units(&self) -> Result<LengthUnit, MachineError> {
        let metric: bool = self.value("metric", (), "True or False")?;
        Ok(if metric { LengthUnit::Millimetre } else { LengthUnit::Inch })
    }

    fn dwell(&mut self, seconds: f64) -> Result<(), MachineError> {
        self.call("dwell", (seconds,)).map(|_| ())
    }

    fn xy_rotation_deg(&self) -> Result<f64, MachineError> {
        self.value("xy_rotation_deg", (), "a number")
    }

    fn g92_offset(&self) -> Result<Vector2<f64>, MachineError> {
        let (x, y) = self.pair("g92_offset", ())?;
        Ok(Vector2::new(x, y))
    }

    fn message(&mut self, text: &str) {
        // A status line only: a message LinuxCNC refuses is not worth failing the M-code for.
        let _ = self.call("message", (printable_line(text, MAX_MESSAGE_CHARS),));
    }
}
