//! The controller's state as `$#`, `$G` and `$$` print it, parsed from the lines
//! [`Sender::command`](crate::stream::Sender::command) returns (feedback without its brackets,
//! other lines as sent). Numbers are in the controller's report units: mm, or inches with
//! `$13=1`.

use crate::response::ParseError;

/// The coordinate offsets of `$#`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Offsets {
    /// G54..G59, X Y Z.
    pub work: [[f64; 3]; 6],
    /// The G28 position (machine coordinates).
    pub g28: [f64; 3],
    /// The G30 position (machine coordinates).
    pub g30: [f64; 3],
    /// The G92 offset.
    pub g92: [f64; 3],
    /// The tool length offset (Z; the first value where grblHAL prints more).
    pub tlo: f64,
}

/// The parser's modal state of `$G` (`[GC:…]`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ParserState {
    /// 1..=6 for G54..G59.
    pub work_system: u8,
    /// G20.
    pub inches: bool,
    /// G91.
    pub incremental: bool,
    /// 17, 18 or 19.
    pub plane: u8,
    /// The `T` word.
    pub tool: u32,
    /// The `F` word (units per minute).
    pub feed: f64,
    /// The `S` word (rpm); 0 when the firmware prints none (Grbl without variable spindle).
    pub spindle: f64,
}

fn finite(s: &str) -> Result<f64, ParseError> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(ParseError::BadNumber(s.to_string())),
    }
}

fn three(s: &str) -> Result<[f64; 3], ParseError> {
    let parts: Vec<&str> = s.split(',').collect();
    if parts.len() < 3 {
        return Err(ParseError::BadNumber(s.to_string()));
    }
    Ok([finite(parts[0])?, finite(parts[1])?, finite(parts[2])?])
}

/// Parses `$#`'s lines (`G54:1.000,2.000,0.000`, … `TLO:0.000`); other lines are skipped
/// (`PRB:`, grblHAL's `G59.1:` and `HOME:`). Every one of G54..G59, G28, G30, G92 and TLO must
/// be there.
pub fn parse_offsets<S: AsRef<str>>(lines: &[S]) -> Result<Offsets, ParseError> {
    const NAMES: [&str; 10] = ["G54", "G55", "G56", "G57", "G58", "G59", "G28", "G30", "G92", "TLO"];
    let mut out = Offsets::default();
    // G54..G59, G28, G30, G92, TLO.
    let mut seen = [false; 10];
    for line in lines {
        let line = line.as_ref().trim();
        let inner = line.strip_prefix('[').and_then(|l| l.strip_suffix(']')).unwrap_or(line);
        let Some((key, value)) = inner.split_once(':') else { continue };
        let slot = match key {
            "G54" | "G55" | "G56" | "G57" | "G58" | "G59" => {
                let i = usize::from(key.as_bytes()[2] - b'4');
                out.work[i] = three(value)?;
                i
            }
            "G28" => {
                out.g28 = three(value)?;
                6
            }
            "G30" => {
                out.g30 = three(value)?;
                7
            }
            "G92" => {
                out.g92 = three(value)?;
                8
            }
            "TLO" => {
                out.tlo = finite(value.split(',').next().unwrap_or(""))?;
                9
            }
            _ => continue,
        };
        seen[slot] = true;
    }
    match seen.iter().position(|s| !s) {
        Some(i) => Err(ParseError::Missing(NAMES[i].to_string())),
        None => Ok(out),
    }
}

/// Parses `$G`'s `GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0` (one of the lines; the others are
/// skipped). Words it does not keep (grblHAL's G40, G49, G98…) are skipped; G54..G59, the
/// plane, the units, the distance mode, `T` and `F` must be there.
pub fn parse_parser_state<S: AsRef<str>>(lines: &[S]) -> Result<ParserState, ParseError> {
    let words = lines
        .iter()
        .map(|l| l.as_ref().trim())
        .find_map(|l| l.strip_prefix("[GC:").and_then(|l| l.strip_suffix(']')).or_else(|| l.strip_prefix("GC:")))
        .ok_or_else(|| ParseError::Missing("GC:".to_string()))?;
    let (mut work, mut plane, mut units, mut distance) = (None, None, None, None);
    let (mut tool, mut feed, mut spindle) = (None, None, 0.0);
    for word in words.split_whitespace() {
        match word {
            "G54" | "G55" | "G56" | "G57" | "G58" | "G59" => work = Some(word.as_bytes()[2] - b'3'),
            "G17" => plane = Some(17),
            "G18" => plane = Some(18),
            "G19" => plane = Some(19),
            "G20" => units = Some(true),
            "G21" => units = Some(false),
            "G90" => distance = Some(false),
            "G91" => distance = Some(true),
            _ => match word.split_at_checked(1) {
                Some(("T", n)) => tool = Some(n.parse::<u32>().map_err(|_| ParseError::BadNumber(word.to_string()))?),
                Some(("F", n)) => feed = Some(finite(n)?),
                Some(("S", n)) => spindle = finite(n)?,
                _ => {}
            },
        }
    }
    let missing = |what: &str| ParseError::Missing(what.to_string());
    Ok(ParserState {
        work_system: work.ok_or_else(|| missing("G54..G59"))?,
        inches: units.ok_or_else(|| missing("G20/G21"))?,
        incremental: distance.ok_or_else(|| missing("G90/G91"))?,
        plane: plane.ok_or_else(|| missing("G17/G18/G19"))?,
        tool: tool.ok_or_else(|| missing("T"))?,
        feed: feed.ok_or_else(|| missing("F"))?,
        spindle,
    })
}

/// Parses `$$`'s `$N=value` lines, in their order. A value that is not a number (grblHAL's text
/// settings, a host name) is skipped; text after the value (Grbl 0.9's `(step pulse, usec)`) is
/// ignored; lines not starting with `$` are skipped.
pub fn parse_settings<S: AsRef<str>>(lines: &[S]) -> Result<Vec<(u16, f64)>, ParseError> {
    let mut out = Vec::new();
    for line in lines {
        let line = line.as_ref().trim();
        let Some(rest) = line.strip_prefix('$') else { continue };
        let (n, value) = rest.split_once('=').ok_or_else(|| ParseError::BadNumber(line.to_string()))?;
        let n = n.parse::<u16>().map_err(|_| ParseError::BadNumber(line.to_string()))?;
        let value = value.split_whitespace().next().unwrap_or("");
        match value.parse::<f64>() {
            Ok(v) if v.is_finite() => out.push((n, v)),
            Ok(_) => return Err(ParseError::BadNumber(line.to_string())),
            Err(_) => {}
        }
    }
    Ok(out)
}

#[cfg(test)]
#[expect(clippy::float_cmp, reason = "the values are exact in binary")]
mod tests {
    use super::*;

    #[test]
    fn reads_what_grbl_and_grblhal_print() {
        let hash = [
            "G54:1.000,2.000,3.000",
            "G55:4.000,5.000,6.000",
            "G56:0.000,0.000,0.000",
            "G57:0.000,0.000,0.000",
            "G58:0.000,0.000,0.000",
            "G59:0.000,0.000,-9.500",
            "G59.1:9.000,9.000,9.000",
            "G28:10.000,0.000,0.000",
            "G30:0.000,20.000,0.000",
            "G92:0.000,0.000,30.000",
            "TLO:1.250",
            "PRB:0.000,0.000,0.000:0",
        ];
        let o = parse_offsets(&hash).expect("offsets");
        assert_eq!(o.work[0], [1.0, 2.0, 3.0]);
        assert_eq!(o.work[1], [4.0, 5.0, 6.0]);
        assert_eq!(o.work[5], [0.0, 0.0, -9.5]);
        assert_eq!((o.g28, o.g30, o.g92), ([10.0, 0.0, 0.0], [0.0, 20.0, 0.0], [0.0, 0.0, 30.0]));
        assert_eq!(o.tlo, 1.25);
        assert_eq!(parse_offsets(&hash[..10]), Err(ParseError::Missing("TLO".into())));
        assert_eq!(parse_offsets(&["G54:1,2"]), Err(ParseError::BadNumber("1,2".into())));
        assert_eq!(parse_offsets(&["TLO:inf"]), Err(ParseError::BadNumber("inf".into())));

        let p = parse_parser_state(&["[GC:G1 G56 G18 G20 G91 G94 M3 M8 T7 F12.5 S1000]"]).expect("state");
        let want = ParserState {
            work_system: 3,
            inches: true,
            incremental: true,
            plane: 18,
            tool: 7,
            feed: 12.5,
            spindle: 1000.0,
        };
        assert_eq!(p, want);
        let p = parse_parser_state(&["GC:G0 G59 G19 G21 G90 G94 G40 G49 G98 M5 M9 T0 F0"]).expect("no S");
        assert_eq!((p.work_system, p.plane, p.inches, p.incremental, p.spindle), (6, 19, false, false, 0.0));
        assert_eq!(parse_parser_state(&["GC:G0 G54 G17 G21 G90 T0"]), Err(ParseError::Missing("F".into())));
        assert_eq!(parse_parser_state(&["GC:G0 G17 G21 G90 T0 F0"]), Err(ParseError::Missing("G54..G59".into())));
        assert!(matches!(parse_parser_state(&["GC:G54 G17 G21 G90 T-1 F0"]), Err(ParseError::BadNumber(_))));
        assert_eq!(parse_parser_state(&["MSG:x"]), Err(ParseError::Missing("GC:".into())));

        let s = parse_settings(&["$0=10", "$13=1", "$110=500.000 (x max rate, mm/min)", "$71=grblHAL", "ok"]);
        assert_eq!(s, Ok(vec![(0, 10.0), (13, 1.0), (110, 500.0)]));
        assert!(matches!(parse_settings(&["$70000=1"]), Err(ParseError::BadNumber(_))));
        assert!(matches!(parse_settings(&["$13"]), Err(ParseError::BadNumber(_))));
        assert!(matches!(parse_settings(&["$13=NaN"]), Err(ParseError::BadNumber(_))));
    }
}
