//! The `$` settings: Grbl's generic defaults, `$$`, and `$N=value`.

use super::status;

/// Settings in the order `$$` prints them, with Grbl's generic defaults (`defaults.h`,
/// `DEFAULTS_GENERIC`) and the decimals `report.c` prints them with (`None`: an integer).
const TABLE: &[(u16, f64, Option<usize>)] = &[
    (0, 10.0, None),
    (1, 25.0, None),
    (2, 0.0, None),
    (3, 0.0, None),
    (4, 0.0, None),
    (5, 0.0, None),
    (6, 0.0, None),
    (10, 1.0, None),
    (11, 0.010, Some(3)),
    (12, 0.002, Some(3)),
    (13, 0.0, None),
    (20, 0.0, None),
    (21, 0.0, None),
    (22, 0.0, None),
    (23, 0.0, None),
    (24, 25.0, Some(3)),
    (25, 500.0, Some(3)),
    (26, 250.0, None),
    (27, 1.0, Some(3)),
    (30, 1000.0, Some(0)),
    (31, 0.0, Some(0)),
    (32, 0.0, None),
    (100, 250.0, Some(3)),
    (101, 250.0, Some(3)),
    (102, 250.0, Some(3)),
    (110, 500.0, Some(3)),
    (111, 500.0, Some(3)),
    (112, 500.0, Some(3)),
    (120, 10.0, Some(3)),
    (121, 10.0, Some(3)),
    (122, 10.0, Some(3)),
    (130, 200.0, Some(3)),
    (131, 200.0, Some(3)),
    (132, 200.0, Some(3)),
];

/// The machine's settings (`$N`), in Grbl's units: mm, mm/min, mm/s², steps/mm.
#[derive(Debug, Clone)]
pub(crate) struct Settings {
    values: Vec<f64>,
}

impl Default for Settings {
    fn default() -> Self {
        Self { values: TABLE.iter().map(|&(_, v, _)| v).collect() }
    }
}

impl Settings {
    fn index(number: u16) -> Option<usize> {
        TABLE.iter().position(|&(n, _, _)| n == number)
    }

    /// The value of `$number`, 0 for a number Grbl does not have.
    pub(crate) fn get(&self, number: u16) -> f64 {
        Self::index(number).map_or(0.0, |i| self.values[i])
    }

    /// `$number=value`, with `settings.c`'s checks; `Err` is Grbl's status code.
    #[expect(
        clippy::cast_possible_truncation,
        clippy::cast_sign_loss,
        reason = "setting numbers are checked whole and small first"
    )]
    pub(crate) fn store(&mut self, number: f64, value: f64) -> Result<(), u8> {
        // system.c: a parameter above 255 is an invalid statement; settings.c: negative values.
        if number > 255.0 {
            return Err(status::INVALID_STATEMENT);
        }
        if value < 0.0 {
            return Err(status::NEGATIVE_VALUE);
        }
        let n = number.trunc() as u16;
        let Some(i) = Self::index(n) else { return Err(status::INVALID_STATEMENT) };
        let v = match TABLE[i].2 {
            None => value.trunc().min(255.0),
            Some(_) => value,
        };
        if n == 0 && v < 3.0 {
            return Err(status::SETTING_STEP_PULSE_MIN);
        }
        self.values[i] = v;
        Ok(())
    }

    /// `$$`: one `$N=value` line each.
    #[expect(clippy::cast_possible_truncation, reason = "whole settings print as integers, as Grbl does")]
    pub(crate) fn report(&self) -> String {
        let mut out = String::new();
        for (i, &(n, _, decimals)) in TABLE.iter().enumerate() {
            let v = self.values[i];
            match decimals {
                None => out.push_str(&format!("${n}={}\r\n", v as i64)),
                Some(d) => out.push_str(&format!("${n}={v:.d$}\r\n")),
            }
        }
        out
    }

    /// Steps per mm of each axis (`$100`–`$102`), never below 1.
    #[expect(clippy::cast_possible_truncation, reason = "axis indices are 0..3")]
    pub(crate) fn steps_per_mm(&self) -> [f64; 3] {
        std::array::from_fn(|i| self.get(100 + i as u16).max(1.0))
    }
}

#[cfg(test)]
#[expect(clippy::float_cmp, reason = "tests compare exact values")]
mod tests {
    use super::*;

    #[test]
    fn stores_with_grbl_checks_and_reports_in_order() {
        let mut s = Settings::default();
        assert_eq!(s.store(110.0, 5000.0), Ok(()));
        assert_eq!(s.get(110), 5000.0);
        assert_eq!(s.store(0.0, 2.0), Err(status::SETTING_STEP_PULSE_MIN));
        assert_eq!(s.store(7.0, 1.0), Err(status::INVALID_STATEMENT));
        assert_eq!(s.store(300.0, 1.0), Err(status::INVALID_STATEMENT));
        assert_eq!(s.store(1.0, -1.0), Err(status::NEGATIVE_VALUE));
        let report = s.report();
        assert!(report.starts_with("$0=10\r\n$1=25\r\n"));
        assert!(report.contains("$11=0.010\r\n"));
        assert!(report.contains("$110=5000.000\r\n"));
        assert!(report.contains("$30=1000\r\n"));
    }
}
