//! Parsing of reply lines (untrusted text): the Data Output line, `ER,<cmd>,<nn>`, `PR`, `FVR`.
//!
//! Every function returns a typed refusal instead of panicking, and never yields a non-finite
//! number.

use vision_core::{Judgment, Reading};

/// Largest coordinate, width or height accepted from a camera that reports a mark, pixels
/// (the largest image `VisionCameraResX/Y` allows is 100 000 px).
pub(crate) const MAX_ABS_PIXELS: f64 = 1.0e6;
/// Largest mark angle accepted, degrees (Keyence reports −180…180 or 0…360).
pub(crate) const MAX_ABS_ANGLE_DEG: f64 = 360.0;
/// Largest match score accepted (Keyence scores are 0–100 or 0–1000).
pub(crate) const MAX_ABS_SCORE: f64 = 1.0e6;
/// Largest mark count accepted.
pub(crate) const MAX_COUNT: u32 = 1_000_000;
/// Longest numeric field accepted, characters (a fixed-width number is 18).
const MAX_NUMBER_LEN: usize = 32;
/// Longest line quoted in an error message, characters.
const MAX_QUOTE: usize = 120;

/// A camera refusal, `ER,<cmd>,<nn>`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct ErrorReply<'a> {
    /// The refused command's name.
    pub(crate) command: &'a str,
    /// The two-digit code.
    pub(crate) code: &'a str,
}

/// Reads `ER,<cmd>,<nn>`; `None` when the line is not an error reply.
///
/// `Some(Err(..))` is a line that starts `ER,` but is not of that form.
#[must_use]
pub(crate) fn parse_error_reply(line: &str) -> Option<Result<ErrorReply<'_>, String>> {
    let rest = line.strip_prefix("ER,")?;
    let mut fields = rest.split(',');
    let command = fields.next().unwrap_or("");
    let code = fields.next().unwrap_or("");
    let ok = !command.is_empty()
        && command.bytes().all(|b| b.is_ascii_alphanumeric())
        && code.len() == 2
        && code.bytes().all(|b| b.is_ascii_digit())
        && fields.next().is_none();
    Some(if ok {
        Ok(ErrorReply { command, code })
    } else {
        Err("an ER reply must be ER,<command>,<two digits>".into())
    })
}

/// Parses one Data Output line: `x,y`, `judgment,x,y`, or
/// `judgment,count,x,y,width,height,angle,score`; or a bare NG judgment (`0`/`NG`: a camera
/// whose job found nothing may send only that), read as an NG reading at (0, 0).
///
/// Numbers may be plain (`150.0`, `-3`) or Keyence fixed width (`+0000000888.123000`); spaces
/// around a field are ignored; exponents, `inf` and `NaN` are refused. The judgment is `1`/`OK`
/// or `0`/`NG` (any case, or a number equal to 1 or 0). The count is a whole number ≥ 0.
///
/// A reading that claims a mark (not NG, count not 0) must have coordinates, width and height
/// within ±10⁶ px (width and height ≥ 0), angle within ±360° and score within ±10⁶; the count
/// is at most 10⁶. NG and count-0 readings keep whatever finite numbers the camera sent: a
/// camera that found nothing may report sentinels, and the core ignores them.
///
/// # Errors
/// The reason, as text.
pub fn parse_data_line(line: &str) -> Result<Reading, String> {
    let mut fields = [""; 8];
    let mut n = 0;
    for f in line.split(',') {
        if n == fields.len() {
            return Err("more than 8 fields".into());
        }
        fields[n] = f;
        n += 1;
    }
    let reading = match n {
        1 => match judgment(fields[0]) {
            Ok(Judgment::Ng) => Reading { judgment: Judgment::Ng, ..Reading::position(0.0, 0.0) },
            Ok(_) => return Err("1 field: an OK judgment without the mark's position".into()),
            Err(_) => return Err("1 field".into()),
        },
        2 => Reading::position(number(fields[0], "x")?, number(fields[1], "y")?),
        3 => Reading {
            judgment: judgment(fields[0])?,
            ..Reading::position(number(fields[1], "x")?, number(fields[2], "y")?)
        },
        8 => Reading {
            judgment: judgment(fields[0])?,
            count: Some(count(fields[1])?),
            x_px: number(fields[2], "x")?,
            y_px: number(fields[3], "y")?,
            width_px: number(fields[4], "width")?,
            height_px: number(fields[5], "height")?,
            angle_deg: number(fields[6], "angle")?,
            score: number(fields[7], "score")?,
        },
        7 => {
            return Err("7 fields, the shape of a robot pose (a judgment, X, Y, Z and three rotations): the Data \
                        Output looks set to a robot pose, not to the mark in image pixels"
                .into())
        }
        _ => return Err(format!("{n} fields, not 2, 3 or 8")),
    };
    if reading.judgment != Judgment::Ng && reading.count != Some(0) {
        check_range(&reading)?;
    }
    Ok(reading)
}

fn check_range(r: &Reading) -> Result<(), String> {
    let checks = [
        ("x", r.x_px, -MAX_ABS_PIXELS, MAX_ABS_PIXELS),
        ("y", r.y_px, -MAX_ABS_PIXELS, MAX_ABS_PIXELS),
        ("width", r.width_px, 0.0, MAX_ABS_PIXELS),
        ("height", r.height_px, 0.0, MAX_ABS_PIXELS),
        ("angle", r.angle_deg, -MAX_ABS_ANGLE_DEG, MAX_ABS_ANGLE_DEG),
        ("score", r.score, -MAX_ABS_SCORE, MAX_ABS_SCORE),
    ];
    for (name, v, lo, hi) in checks {
        if !(v >= lo && v <= hi) {
            return Err(format!("{name} {v} is outside {lo}..={hi}"));
        }
    }
    Ok(())
}

/// A decimal number: optional sign, digits, optional point and digits; at least one digit, at
/// most [`MAX_NUMBER_LEN`] characters. The characters are checked first, so no exponent, `inf`
/// or `NaN` reaches the standard parser, which then reads the value (correctly rounded).
fn number(field: &str, name: &str) -> Result<f64, String> {
    let t = field.trim_matches(' ');
    let bad = || format!("{name} \"{}\" is not a number", quote(t));
    if t.len() > MAX_NUMBER_LEN {
        return Err(bad());
    }
    let (mut digit, mut point) = (false, false);
    for b in t.strip_prefix(|c| c == '+' || c == '-').unwrap_or(t).bytes() {
        match b {
            b'0'..=b'9' => digit = true,
            b'.' if !point => point = true,
            _ => return Err(bad()),
        }
    }
    match t.parse::<f64>() {
        Ok(v) if digit && v.is_finite() => Ok(v),
        _ => Err(bad()),
    }
}

fn judgment(field: &str) -> Result<Judgment, String> {
    let t = field.trim_matches(' ');
    if t.eq_ignore_ascii_case("OK") {
        return Ok(Judgment::Ok);
    }
    if t.eq_ignore_ascii_case("NG") {
        return Ok(Judgment::Ng);
    }
    match number(t, "judgment") {
        Ok(1.0) => Ok(Judgment::Ok),
        Ok(0.0) => Ok(Judgment::Ng),
        _ => Err(format!("judgment \"{}\" is not 1/OK or 0/NG", quote(t))),
    }
}

fn count(field: &str) -> Result<u32, String> {
    let v = number(field, "count")?;
    if v >= 0.0 && v <= f64::from(MAX_COUNT) && v.fract() == 0.0 {
        #[expect(
            clippy::cast_possible_truncation,
            clippy::cast_sign_loss,
            reason = "In range and whole, so the conversion is exact."
        )]
        Ok(v as u32)
    } else {
        Err(format!("count {v} is not a whole number 0..={MAX_COUNT}"))
    }
}

/// Reads `PR,d,nnn`: memory device 1–2 and job 0–999.
///
/// # Errors
/// The reason, as text.
pub(crate) fn parse_program(line: &str) -> Result<(u8, u32), String> {
    let mut f = line.split(',');
    let (Some("PR"), Some(d), Some(n), None) = (f.next(), f.next(), f.next(), f.next()) else {
        return Err("expected PR,<device>,<job>".into());
    };
    let device = match d.trim_matches(' ') {
        "1" => 1,
        "2" => 2,
        _ => return Err(format!("memory device \"{}\" is not 1 or 2", quote(d))),
    };
    let n = n.trim_matches(' ');
    let job = if !n.is_empty() && n.len() <= 4 && n.bytes().all(|b| b.is_ascii_digit()) {
        n.parse::<u32>().ok().filter(|j| *j <= 999)
    } else {
        None
    };
    let job = job.ok_or_else(|| format!("job \"{}\" is not 0..=999", quote(n)))?;
    Ok((device, job))
}

/// Reads `FVR,<version>`: the version text, which must be non-empty printable ASCII.
///
/// # Errors
/// The reason, as text.
pub(crate) fn parse_version(line: &str) -> Result<String, String> {
    match line.strip_prefix("FVR,") {
        Some(v) if !v.trim().is_empty() && v.bytes().all(|b| (0x20..0x7f).contains(&b)) => Ok(v.trim().to_string()),
        _ => Err("expected FVR,<version>".into()),
    }
}

/// A line as an operator should see it: printable ASCII kept, anything else escaped, long lines
/// shortened.
#[must_use]
pub(crate) fn quote(line: &str) -> String {
    quote_bytes(line.as_bytes())
}

/// [`quote`] for raw bytes (a line that is not valid text).
#[must_use]
pub(crate) fn quote_bytes(line: &[u8]) -> String {
    let mut s = String::new();
    for &b in line {
        if s.len() >= MAX_QUOTE {
            s.push_str(&format!("… ({} bytes)", line.len()));
            break;
        }
        if (0x20..0x7f).contains(&b) {
            s.push(char::from(b));
        } else {
            s.push_str(&format!("\\x{b:02x}"));
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::super::generate::{data_line, edit};
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn the_three_formats() {
        let r = parse_data_line("150.0,-75.5").expect("x,y");
        assert_eq!((r.judgment, r.count, r.x_px, r.y_px), (Judgment::Unknown, None, 150.0, -75.5));
        let r = parse_data_line("OK,150,75").expect("j,x,y");
        assert_eq!((r.judgment, r.x_px, r.y_px), (Judgment::Ok, 150.0, 75.0));
        let r = parse_data_line("0,1,2").expect("NG");
        assert_eq!(r.judgment, Judgment::Ng);
        let r = parse_data_line("1,1,888.123,-12.5,40,41,-3.25,97.5").expect("full");
        assert_eq!(r.count, Some(1));
        assert_eq!((r.width_px, r.height_px, r.angle_deg, r.score), (40.0, 41.0, -3.25, 97.5));
    }

    #[test]
    fn keyence_fixed_width_numbers() {
        let line = "+0000000001.000000,+0000000001.000000,+0000000888.123000,-0000000012.500000,\
                    +0000000040.000000,+0000000041.000000,-0000000003.250000,+0000000097.500000";
        let r = parse_data_line(line).expect("fixed width");
        assert_eq!((r.judgment, r.count, r.x_px, r.y_px), (Judgment::Ok, Some(1), 888.123, -12.5));
        let r = parse_data_line("NG, +0000000000.000000 , 5").expect("spaces");
        assert_eq!((r.judgment, r.x_px, r.y_px), (Judgment::Ng, 0.0, 5.0));
    }

    #[test]
    fn no_mark_and_ng_are_readings_even_with_sentinels() {
        let r = parse_data_line("1,0,0,0,0,0,0,0").expect("count 0");
        assert_eq!(r.count, Some(0));
        assert!(!r.found());
        let r = parse_data_line("NG,+9999999999.999999,-9999999999.999999").expect("NG sentinel");
        assert!(!r.found());
        assert!(r.x_px.is_finite());
    }

    #[test]
    fn bad_lines_are_refused_with_a_reason() {
        for (line, why) in [
            ("", "1 field"),
            ("150.0", "1 field"),
            ("1", "an OK judgment without the mark's position"),
            ("OK", "an OK judgment without the mark's position"),
            ("1,2,3,4,5,6,7", "the Data Output looks set to a robot pose"),
            ("1,2,3,4", "4 fields"),
            ("1,2,3,4,5,6,7,8,9", "more than 8"),
            ("nan,1", "x \"nan\""),
            ("inf,1", "x \"inf\""),
            ("1e3,1", "x \"1e3\""),
            ("1.2.3,1", "x \"1.2.3\""),
            ("+,1", "x \"+\""),
            (",1", "x \"\""),
            ("MAYBE,1,2", "judgment"),
            ("2,1,2", "judgment"),
            ("1,1.5,1,2,3,4,5,6", "count 1.5"),
            ("1,-1,1,2,3,4,5,6", "count -1"),
            ("1,2000000,1", "x 2000000"),
            ("1,1,1,2,-3,4,5,6", "width -3"),
            ("1,1,1,2,3,4,400,6", "angle 400"),
            ("1,1,1,2,3,4,5,1e9", "score"),
            ("00000000000000000000000000000000001,1", "not a number"),
        ] {
            let e = parse_data_line(line).expect_err(line);
            assert!(e.contains(why), "{line:?}: {e}");
        }
    }

    #[test]
    fn a_bare_ng_is_an_ng_reading() {
        for line in ["0", "NG", "ng", " 0 ", "+0000000000.000000"] {
            let r = parse_data_line(line).expect(line);
            assert_eq!(r.judgment, Judgment::Ng, "{line}");
            assert!(!r.found());
            assert!(r.x_px.is_finite() && r.y_px.is_finite());
        }
    }

    #[test]
    fn reasons_read_as_english() {
        assert_eq!(parse_data_line("150.0").expect_err("one field"), "1 field");
        assert_eq!(parse_data_line("1,2,3,4").expect_err("four"), "4 fields, not 2, 3 or 8");
        // A quoted byte is escaped once, not again by a debug format.
        assert_eq!(parse_data_line("1\x00,2").expect_err("nul"), "x \"1\\x00\" is not a number");
        assert_eq!(parse_program("PR,\x01,5").expect_err("device"), "memory device \"\\x01\" is not 1 or 2");
    }

    #[test]
    fn error_replies() {
        assert_eq!(parse_error_reply("ER,TRG,06"), Some(Ok(ErrorReply { command: "TRG", code: "06" })));
        assert_eq!(parse_error_reply("1,2,3"), None);
        for bad in ["ER,TRG", "ER,TRG,6", "ER,,06", "ER,TRG,06,x", "ER,T G,06", "ER,TRG,0a"] {
            assert!(matches!(parse_error_reply(bad), Some(Err(_))), "{bad}");
        }
    }

    #[test]
    fn program_and_version() {
        assert_eq!(parse_program("PR,1,005"), Ok((1, 5)));
        assert_eq!(parse_program("PR,2,0999"), Ok((2, 999)));
        for bad in ["PR,3,005", "PR,1,1000", "PR,1", "PR,1,5,6", "PW,1,5", "PR,1,-5", "PR,1,"] {
            assert!(parse_program(bad).is_err(), "{bad}");
        }
        assert_eq!(parse_version("FVR,1.20.0001"), Ok("1.20.0001".into()));
        assert!(parse_version("FVR,").is_err());
        assert!(parse_version("FVR").is_err());
        assert!(parse_version("FVR,\x01").is_err());
    }

    #[test]
    fn quoting_escapes_and_shortens() {
        assert_eq!(quote_bytes(b"A\x00\xff"), "A\\x00\\xff");
        let long = "x".repeat(1000);
        let q = quote(&long);
        assert!(q.len() < 150 && q.ends_with("(1000 bytes)"), "{q}");
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(512))]

        /// Structured lines in every format and number style read back exactly as written, or
        /// are refused exactly when they claim a mark with a value out of range; after a random
        /// edit, a line is still a reading with finite numbers (within range when it claims a
        /// mark) or a reason, never a panic.
        #[test]
        fn lines_read_as_written_or_are_refused(
            line in data_line(),
            edit in proptest::option::weighted(0.25, edit()),
        ) {
            let text = edit.as_ref().map_or_else(|| line.text.clone(), |e| e.apply(&line.text));
            let got = parse_data_line(&text);
            if edit.is_none() {
                match (&got, &line.expected) {
                    (Ok(r), Some(want)) => prop_assert_eq!(r, want, "{}", text),
                    (Err(_), None) => {}
                    (got, want) => prop_assert!(false, "{text}: got {got:?}, want {want:?}"),
                }
            }
            if let Ok(r) = &got {
                for v in [r.x_px, r.y_px, r.width_px, r.height_px, r.angle_deg, r.score] {
                    prop_assert!(v.is_finite(), "{}", text);
                }
                if r.found() {
                    prop_assert!(r.x_px.abs() <= MAX_ABS_PIXELS && r.y_px.abs() <= MAX_ABS_PIXELS, "{}", text);
                    prop_assert!((0.0..=MAX_ABS_PIXELS).contains(&r.width_px), "{}", text);
                    prop_assert!(r.angle_deg.abs() <= MAX_ABS_ANGLE_DEG && r.score.abs() <= MAX_ABS_SCORE, "{}", text);
                }
            }
            let _ = parse_error_reply(&text);
            let _ = parse_program(&text);
            let _ = parse_version(&text);
        }

        /// Arbitrary text, mostly not a data line: never a panic, and anything accepted is finite.
        #[test]
        fn arbitrary_text_never_panics(line in "[-+0-9.,OKNGok \\x00-\\x7f]{0,80}") {
            if let Ok(r) = parse_data_line(&line) {
                for v in [r.x_px, r.y_px, r.width_px, r.height_px, r.angle_deg, r.score] {
                    prop_assert!(v.is_finite());
                }
            }
            let _ = parse_error_reply(&line);
            let _ = parse_program(&line);
            let _ = parse_version(&line);
        }

        /// What the emulator writes in either number style reads back exactly.
        #[test]
        fn numbers_round_trip(x in -999_999.0f64..999_999.0, y in -999_999.0f64..999_999.0) {
            let x = (x * 1000.0).round() / 1000.0;
            let y = (y * 1000.0).round() / 1000.0;
            let plain = parse_data_line(&format!("{x:.3},{y:.3}")).expect("plain");
            prop_assert!((plain.x_px - x).abs() < 1e-9 && (plain.y_px - y).abs() < 1e-9);
            let fixed = |v: f64| format!("{}{:017.6}", if v < 0.0 { '-' } else { '+' }, v.abs());
            let r = parse_data_line(&format!("{},{}", fixed(x), fixed(y))).expect("fixed");
            prop_assert!((r.x_px - x).abs() < 1e-9 && (r.y_px - y).abs() < 1e-9);
        }
    }
}
