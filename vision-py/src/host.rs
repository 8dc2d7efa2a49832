//! [`PyHost`]: [`Host`] over the Python object LinuxCNC's remap hands the session
//! (`hosts/linuxcnc/remap.py`'s `Host`).

use pyo3::call::PyCallArgs;
use pyo3::prelude::*;
use vision_host::{printable_line, Controller, Host, HostError, MAX_MESSAGE_CHARS};
use vision_math::{LengthUnit, Point2, Vector2};

use crate::words::shown;
use crate::VisionError;

/// The controller behind a Python `Host` object: each [`Host`] call is a method call on it
/// (`program_position()`, `pound(n)`, `execute(line)`, …; the table in
/// `hosts/linuxcnc/README.md`). Lengths are in the program's units, angles in degrees.
///
/// It is [`Controller::LinuxCnc`]: M282 rotates the G5x system and shifts with G52, and the
/// alignment's state is read from the host at every call.
///
/// A Python exception raised by a method, or a value of the wrong type, becomes
/// [`HostError::Host`] with Python's message; nothing here panics on what Python returns.
pub struct PyHost<'py> {
    object: Bound<'py, PyAny>,
}

impl<'py> PyHost<'py> {
    /// The host over `object` (a `remap.Host`).
    #[must_use]
    pub fn new(object: Bound<'py, PyAny>) -> PyHost<'py> {
        PyHost { object }
    }

    /// The Python object.
    #[must_use]
    pub fn object(&self) -> &Bound<'py, PyAny> {
        &self.object
    }

    /// `object.method(*args)`.
    ///
    /// # Errors
    /// [`HostError::Host`] with the exception's message when the method is missing or raises.
    pub fn call(&self, method: &str, args: impl PyCallArgs<'py>) -> Result<Bound<'py, PyAny>, HostError> {
        self.object.call_method1(method, args).map_err(|e| python_error(self.object.py(), method, &e))
    }

    /// `object.method(*args)` as a `T`.
    ///
    /// # Errors
    /// As [`PyHost::call`], and when the result is not a `T` (`what` names it in the message).
    pub fn value<T>(&self, method: &str, args: impl PyCallArgs<'py>, what: &str) -> Result<T, HostError>
    where
        T: FromPyObjectOwned<'py>,
    {
        let value = self.call(method, args)?;
        value
            .extract::<T>()
            .map_err(|_| HostError::host(format!("Host.{method}() returned {}, not {what}", shown(&value))))
    }

    /// `object.method(*args)` as an X, Y pair (`(x, y)`).
    fn pair(&self, method: &str, args: impl PyCallArgs<'py>) -> Result<(f64, f64), HostError> {
        self.value(method, args, "an (x, y) pair of numbers")
    }
}

/// The operator's view of Python exception `e`, raised by `Host.method`: a `VisionError`'s
/// message as it is (the remap wrote it for the operator), any other exception with its type.
fn python_error(py: Python<'_>, method: &str, e: &PyErr) -> HostError {
    let text =
        if e.is_instance_of::<VisionError>(py) { e.value(py).to_string() } else { format!("Host.{method}(): {e}") };
    HostError::host(printable_line(&text, MAX_MESSAGE_CHARS))
}

impl Host for PyHost<'_> {
    fn execute(&mut self, line: &str) -> Result<(), HostError> {
        self.call("execute", (line,)).map(|_| ())
    }

    fn pound(&self, index: u32) -> Result<f64, HostError> {
        self.value("pound", (index,), "a number")
    }

    fn set_pound(&mut self, index: u32, value: f64) -> Result<(), HostError> {
        self.call("set_pound", (index, value)).map(|_| ())
    }

    fn active_tool(&self) -> Result<u32, HostError> {
        self.value("tool", (), "a tool number")
    }

    fn tool_offset(&self, tool: u32) -> Result<Vector2<f64>, HostError> {
        let (x, y) = self.pair("tool_offset", (tool,))?;
        Ok(Vector2::new(x, y))
    }

    fn set_tool_offset(&mut self, tool: u32, offset: Vector2<f64>) -> Result<(), HostError> {
        self.call("set_tool_offset", (tool, offset.x, offset.y)).map(|_| ())
    }

    fn position(&self) -> Result<Point2<f64>, HostError> {
        let (x, y) = self.pair("program_position", ())?;
        Ok(Point2::new(x, y))
    }

    fn units(&self) -> Result<LengthUnit, HostError> {
        let metric: bool = self.value("metric", (), "True or False")?;
        Ok(if metric { LengthUnit::Millimetre } else { LengthUnit::Inch })
    }

    fn dwell(&mut self, seconds: f64) -> Result<(), HostError> {
        self.call("dwell", (seconds,)).map(|_| ())
    }

    fn controller(&self) -> Controller {
        Controller::LinuxCnc
    }

    fn xy_rotation_deg(&self) -> Result<f64, HostError> {
        self.value("xy_rotation_deg", (), "a number")
    }

    fn g92_offset(&self) -> Result<Vector2<f64>, HostError> {
        let (x, y) = self.pair("g92_offset", ())?;
        Ok(Vector2::new(x, y))
    }

    fn message(&mut self, text: &str) {
        // A status line only: a message LinuxCNC refuses is not worth failing the M-code for.
        let _ = self.call("message", (printable_line(text, MAX_MESSAGE_CHARS),));
    }
}
