//! What a Grbl controller sends, one line at a time, parsed into typed values (the messages of
//! Grbl 1.1's `report.c`; grblHAL's are a superset).

use thiserror::Error;

/// One line from the controller.
#[derive(Debug, Clone, PartialEq)]
pub enum Response {
    /// `ok`: the line was executed (or planned).
    Ok,
    /// `error:N`: the line was refused; nothing of it ran.
    Error(u8),
    /// `ALARM:N`: the controller stopped and locked itself.
    Alarm(u8),
    /// `<…>`: a status report.
    Status(Status),
    /// The welcome line after a power-up or a reset, e.g. `Grbl 1.1h ['$' for help]`.
    Welcome {
        /// Whether it is grblHAL.
        grblhal: bool,
        /// The version word, e.g. `1.1h`.
        version: String,
    },
    /// `[…]`: a feedback message (`[MSG:…]`, `[GC:…]`, `[OPT:…]`…), without the brackets.
    Feedback(String),
    /// Anything else: settings lines (`$0=10`), blank lines.
    Other(String),
}

/// The machine state word of a status report.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MachineState {
    /// Nothing to do.
    Idle,
    /// Running motion.
    Run,
    /// Feed hold; the sub-state is 0 when stopped and ready to resume.
    Hold,
    /// Jogging.
    Jog,
    /// Locked by an alarm.
    Alarm,
    /// Safety door open.
    Door,
    /// Check mode (`$C`).
    Check,
    /// Homing.
    Home,
    /// Sleeping.
    Sleep,
    /// grblHAL: waiting for a tool change.
    Tool,
}

/// A parsed status report (mm, mm/min, rpm).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Status {
    /// The state; `None` only in `Default`.
    pub state: Option<MachineState>,
    /// The state's sub-code, e.g. the 0 of `Hold:0`.
    pub substate: Option<u8>,
    /// `MPos` (machine position).
    pub mpos: Option<[f64; 3]>,
    /// `WPos` (work position).
    pub wpos: Option<[f64; 3]>,
    /// `WCO` (work coordinate offset), present only in some reports.
    pub wco: Option<[f64; 3]>,
    /// Current feed (`FS:` or `F:`).
    pub feed: Option<f64>,
    /// Current spindle speed (`FS:`).
    pub spindle: Option<f64>,
    /// `Bf:`: free planner blocks and free receive-buffer bytes.
    pub buffer: Option<(u32, u32)>,
}

/// Why a line could not be read.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum ParseError {
    /// The bytes are not UTF-8.
    #[error("not UTF-8 text")]
    NotUtf8,
    /// `error:`, `ALARM:` or a field whose number is missing or not a number.
    #[error("bad number in {0:?}")]
    BadNumber(String),
    /// A status report that is not `<State|…>`.
    #[error("malformed status report {0:?}")]
    BadStatus(String),
    /// A state word no Grbl sends.
    #[error("unknown machine state {0:?}")]
    UnknownState(String),
    /// A report lacks a field every Grbl prints (`$#`, `$G`).
    #[error("no {0} in the report")]
    Missing(String),
}

/// Parses one line (without its line end; a trailing CR or LF is ignored).
pub fn parse_line(bytes: &[u8]) -> Result<Response, ParseError> {
    let text = std::str::from_utf8(bytes).map_err(|_| ParseError::NotUtf8)?;
    let line = text.trim_end_matches(['\r', '\n']);
    if line == "ok" {
        return Ok(Response::Ok);
    }
    if let Some(code) = line.strip_prefix("error:") {
        return code.parse().map(Response::Error).map_err(|_| ParseError::BadNumber(line.into()));
    }
    if let Some(code) = line.strip_prefix("ALARM:") {
        return code.parse().map(Response::Alarm).map_err(|_| ParseError::BadNumber(line.into()));
    }
    if line.starts_with('<') {
        return parse_status(line).map(Response::Status);
    }
    if let Some(inner) = line.strip_prefix('[').and_then(|l| l.strip_suffix(']')) {
        return Ok(Response::Feedback(inner.to_string()));
    }
    for (prefix, grblhal) in [("Grbl ", false), ("GrblHAL ", true)] {
        if let Some(rest) = line.strip_prefix(prefix) {
            if rest.contains("['$") {
                let version = rest.split_whitespace().next().unwrap_or("").to_string();
                return Ok(Response::Welcome { grblhal, version });
            }
        }
    }
    Ok(Response::Other(line.to_string()))
}

fn number(s: &str, whole: &str) -> Result<f64, ParseError> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(ParseError::BadNumber(whole.to_string())),
    }
}

fn axes(s: &str, whole: &str) -> Result<[f64; 3], ParseError> {
    let mut out = [0.0; 3];
    let mut n = 0;
    for (i, part) in s.split(',').enumerate() {
        // Controllers with more axes send more values; the first three are X, Y, Z.
        if i < 3 {
            out[i] = number(part, whole)?;
        }
        n += 1;
    }
    if n < 3 {
        return Err(ParseError::BadStatus(whole.to_string()));
    }
    Ok(out)
}

/// Parses a status report, `<Idle|MPos:0.000,0.000,0.000|FS:0,0|WCO:…>`.
pub fn parse_status(line: &str) -> Result<Status, ParseError> {
    let inner = line
        .strip_prefix('<')
        .and_then(|l| l.strip_suffix('>'))
        .ok_or_else(|| ParseError::BadStatus(line.to_string()))?;
    let mut fields = inner.split('|');
    let state_field = fields.next().unwrap_or("");
    let (word, sub) = match state_field.split_once(':') {
        Some((w, s)) => (w, Some(s.parse::<u8>().map_err(|_| ParseError::BadNumber(line.to_string()))?)),
        None => (state_field, None),
    };
    let state = match word {
        "Idle" => MachineState::Idle,
        "Run" => MachineState::Run,
        "Hold" => MachineState::Hold,
        "Jog" => MachineState::Jog,
        "Alarm" => MachineState::Alarm,
        "Door" => MachineState::Door,
        "Check" => MachineState::Check,
        "Home" => MachineState::Home,
        "Sleep" => MachineState::Sleep,
        "Tool" => MachineState::Tool,
        _ => return Err(ParseError::UnknownState(word.to_string())),
    };
    let mut status = Status { state: Some(state), substate: sub, ..Status::default() };
    for field in fields {
        let Some((key, value)) = field.split_once(':') else { continue };
        match key {
            "MPos" => status.mpos = Some(axes(value, line)?),
            "WPos" => status.wpos = Some(axes(value, line)?),
            "WCO" => status.wco = Some(axes(value, line)?),
            "FS" => {
                let (f, s) = value.split_once(',').ok_or_else(|| ParseError::BadStatus(line.to_string()))?;
                status.feed = Some(number(f, line)?);
                status.spindle = Some(number(s, line)?);
            }
            "F" => status.feed = Some(number(value, line)?),
            "Bf" => {
                let (b, r) = value.split_once(',').ok_or_else(|| ParseError::BadStatus(line.to_string()))?;
                let parse = |s: &str| s.parse::<u32>().map_err(|_| ParseError::BadNumber(line.to_string()));
                status.buffer = Some((parse(b)?, parse(r)?));
            }
            _ => {} // Ln, Pn, Ov, A and grblHAL's extras are not needed here.
        }
    }
    Ok(status)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_the_messages_grbl_sends() {
        assert_eq!(parse_line(b"ok\r"), Ok(Response::Ok));
        assert_eq!(parse_line(b"error:23"), Ok(Response::Error(23)));
        assert_eq!(parse_line(b"ALARM:3"), Ok(Response::Alarm(3)));
        assert_eq!(parse_line(b"[MSG:Pgm End]"), Ok(Response::Feedback("MSG:Pgm End".into())));
        assert_eq!(
            parse_line(b"Grbl 1.1h ['$' for help]"),
            Ok(Response::Welcome { grblhal: false, version: "1.1h".into() })
        );
        assert!(matches!(parse_line(b"error:x"), Err(ParseError::BadNumber(_))));
        let Ok(Response::Status(s)) =
            parse_line(b"<Hold:0|MPos:1.000,-2.500,0.000|Bf:15,128|FS:0,0|WCO:1.000,0.000,0.000>")
        else {
            panic!("status")
        };
        assert_eq!(s.state, Some(MachineState::Hold));
        assert_eq!(s.substate, Some(0));
        assert_eq!(s.mpos, Some([1.0, -2.5, 0.0]));
        assert_eq!(s.wco, Some([1.0, 0.0, 0.0]));
        assert_eq!(s.buffer, Some((15, 128)));
        assert!(matches!(parse_status("<Walk|MPos:0,0,0>"), Err(ParseError::UnknownState(_))));
        assert!(matches!(parse_status("<Idle|MPos:0,nan,0>"), Err(ParseError::BadNumber(_))));
    }
}
