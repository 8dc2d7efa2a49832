//! How the emulated camera is set up: output format, series, timings; and the Data Output line
//! it writes for a reading.

use std::time::Duration;

use vision_core::{Judgment, Reading};

/// Which fields the Data Output (Non-Procedural) tool emits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum OutputFormat {
    /// `x,y`.
    Xy,
    /// `judgment,x,y`.
    JudgmentXy,
    /// `judgment,count,x,y,width,height,angle,score` (the recommended one).
    #[default]
    Full,
}

/// How numbers are written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum NumberStyle {
    /// `150.000`, three decimals; counts as whole numbers.
    #[default]
    Plain,
    /// Keyence fixed width: sign, 10 integer digits, 6 decimals (`+0000000888.123000`), counts
    /// included.
    FixedWidth,
}

/// How the judgment is written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum JudgmentStyle {
    /// `1` / `0`.
    #[default]
    Digit,
    /// `OK` / `NG`.
    Word,
}

/// What ends each line the camera writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Delimiter {
    /// CR, the Keyence default.
    #[default]
    Cr,
    /// CR LF.
    CrLf,
    /// LF.
    Lf,
}

impl Delimiter {
    /// The bytes.
    #[must_use]
    pub fn bytes(self) -> &'static [u8] {
        match self {
            Delimiter::Cr => b"\r",
            Delimiter::CrLf => b"\r\n",
            Delimiter::Lf => b"\n",
        }
    }
}

/// Which job command the camera knows; the other one answers `ER,<cmd>,01`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Series {
    /// VS series: `PL,d,nnn`.
    #[default]
    Vs,
    /// CV-X and IV style: `PW,d,nnn`.
    CvX,
}

/// The camera's operating mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Mode {
    /// Run mode: inspections on `TRG`.
    #[default]
    Run,
    /// Setup mode: `TRG`, `PR`, `PL`/`PW` answer `ER,<cmd>,06`.
    Setup,
}

/// Everything configurable about the emulated camera.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EmulatorSettings {
    /// Data Output fields.
    pub format: OutputFormat,
    /// Number style.
    pub numbers: NumberStyle,
    /// Judgment style.
    pub judgment: JudgmentStyle,
    /// Line delimiter the camera writes (it accepts CR, LF and CRLF from clients).
    pub delimiter: Delimiter,
    /// Job command series.
    pub series: Series,
    /// Text after `FVR,` (printable ASCII).
    pub version: String,
    /// Mode at start.
    pub mode: Mode,
    /// Memory device (1 or 2) and job `PR` reports at start.
    pub program: (u8, u32),
    /// Highest job that exists on the camera; `PL`/`PW` beyond it answer `03`.
    pub max_job: u32,
    /// A command whose delimiter has not arrived this long after its first byte is answered
    /// `ER,<cmd>,07` and discarded (the VS's 3 s).
    pub command_timeout: Duration,
    /// Time between the `TRG` echo and the data line (the inspection).
    pub inspection_time: Duration,
    /// Time after a job switch during which `TRG`, `PR`, `PL`/`PW`, `RUN` and `SET` answer
    /// `ER,<cmd>,05` (loading the job).
    pub load_time: Duration,
    /// How long a new client waits for the previous one's connection to wind down before it
    /// is turned away.
    pub handover_grace: Duration,
}

impl Default for EmulatorSettings {
    fn default() -> Self {
        EmulatorSettings {
            format: OutputFormat::default(),
            numbers: NumberStyle::default(),
            judgment: JudgmentStyle::default(),
            delimiter: Delimiter::default(),
            series: Series::default(),
            version: "1.00.0000 mach-vision VS emulator".into(),
            mode: Mode::default(),
            program: (1, 0),
            max_job: 999,
            command_timeout: Duration::from_secs(3),
            inspection_time: Duration::ZERO,
            load_time: Duration::ZERO,
            handover_grace: Duration::from_millis(100),
        }
    }
}

impl EmulatorSettings {
    /// The Data Output line for `r`, without delimiter.
    ///
    /// A reading with an unknown judgment is written as OK (a real camera always judges); a
    /// reading without a count is written with count 1, or 0 when NG.
    #[must_use]
    pub fn data_line(&self, r: &Reading) -> String {
        let ok = r.judgment != Judgment::Ng;
        let judgment = match (self.judgment, ok) {
            (JudgmentStyle::Digit, true) => "1",
            (JudgmentStyle::Digit, false) => "0",
            (JudgmentStyle::Word, true) => "OK",
            (JudgmentStyle::Word, false) => "NG",
        };
        let n = |v: f64| self.number(v);
        match self.format {
            OutputFormat::Xy => format!("{},{}", n(r.x_px), n(r.y_px)),
            OutputFormat::JudgmentXy => format!("{judgment},{},{}", n(r.x_px), n(r.y_px)),
            OutputFormat::Full => {
                let count = r.count.unwrap_or(u32::from(ok));
                let count = match self.numbers {
                    NumberStyle::Plain => count.to_string(),
                    NumberStyle::FixedWidth => n(f64::from(count)),
                };
                format!(
                    "{judgment},{count},{},{},{},{},{},{}",
                    n(r.x_px),
                    n(r.y_px),
                    n(r.width_px),
                    n(r.height_px),
                    n(r.angle_deg),
                    n(r.score)
                )
            }
        }
    }

    fn number(&self, v: f64) -> String {
        match self.numbers {
            NumberStyle::Plain => format!("{v:.3}"),
            NumberStyle::FixedWidth => format!("{}{:017.6}", if v < 0.0 { '-' } else { '+' }, v.abs()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::parse_data_line;

    #[test]
    fn every_format_and_style_reads_back() {
        let r = Reading {
            judgment: Judgment::Ok,
            count: Some(1),
            x_px: 888.123,
            y_px: -12.5,
            width_px: 40.0,
            height_px: 41.0,
            angle_deg: -3.25,
            score: 97.5,
        };
        let mut s = EmulatorSettings::default();
        assert_eq!(s.data_line(&r), "1,1,888.123,-12.500,40.000,41.000,-3.250,97.500");
        s.numbers = NumberStyle::FixedWidth;
        s.judgment = JudgmentStyle::Word;
        assert_eq!(
            s.data_line(&r),
            "OK,+0000000001.000000,+0000000888.123000,-0000000012.500000,+0000000040.000000,\
             +0000000041.000000,-0000000003.250000,+0000000097.500000"
        );
        for format in [OutputFormat::Xy, OutputFormat::JudgmentXy, OutputFormat::Full] {
            for numbers in [NumberStyle::Plain, NumberStyle::FixedWidth] {
                for judgment in [JudgmentStyle::Digit, JudgmentStyle::Word] {
                    let s = EmulatorSettings { format, numbers, judgment, ..EmulatorSettings::default() };
                    let back = parse_data_line(&s.data_line(&r)).expect("reads back");
                    assert!((back.x_px - r.x_px).abs() < 1e-9 && (back.y_px - r.y_px).abs() < 1e-9);
                    if format != OutputFormat::Xy {
                        assert_eq!(back.judgment, Judgment::Ok);
                    }
                    if format == OutputFormat::Full {
                        assert_eq!(back, r);
                    }
                }
            }
        }
        let ng = Reading { judgment: Judgment::Ng, count: None, ..Reading::position(0.0, 0.0) };
        assert!(EmulatorSettings::default().data_line(&ng).starts_with("0,0,"));
        assert_eq!(Delimiter::CrLf.bytes(), b"\r\n");
    }
}
