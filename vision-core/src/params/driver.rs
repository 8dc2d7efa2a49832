//! A camera driver's own settings: the driver declares them ([`SettingsTable`]), names them,
//! checks them and reads them; the core only carries their values in [`Params`](super::Params)
//! ([`DriverSettings`]) so they are read and written by name like every parameter and saved
//! in the profile under the driver's own table.

use std::fmt;

use super::checks::Check;
use super::typed::{coerce, kind_reason};
use super::value::{ParamKind, ParamSpec, ParamValue};
use crate::error::VisionError;

/// One setting of a camera driver, as the driver declares it: its description, default and
/// range in one place (the description's `range` is the check's).
#[derive(Debug)]
pub struct Setting {
    /// Its name (the manual's, `Vision…`), type, section and description with units.
    /// `access` is [`Access::Config`](super::Access::Config): a driver setting is written by
    /// the operator and persisted.
    pub spec: ParamSpec,
    /// Its default and range check, of `spec.kind`.
    pub value: SettingValue,
}

/// A driver setting's type with its default and range check.
#[derive(Debug)]
pub enum SettingValue {
    /// An integer.
    Int {
        /// The value before anything sets it.
        default: i64,
        /// The values accepted.
        check: Check<i64>,
    },
    /// A real number.
    Float {
        /// The value before anything sets it.
        default: f64,
        /// The values accepted.
        check: Check<f64>,
    },
    /// Free text.
    Text {
        /// The value before anything sets it.
        default: &'static str,
        /// The values accepted.
        check: Check<String>,
    },
    /// One of the words of its [`ParamKind::Choice`].
    Choice {
        /// The word before anything sets it.
        default: &'static str,
    },
}

impl Setting {
    /// An integer setting in `unit` (empty: a count).
    #[must_use]
    pub const fn int(
        name: &'static str,
        unit: &'static str,
        default: i64,
        check: Check<i64>,
        doc: &'static str,
    ) -> Self {
        let spec = ParamSpec::driver_setting(name, ParamKind::Integer, unit, check.range, doc);
        Setting { spec, value: SettingValue::Int { default, check } }
    }

    /// A real-number setting in `unit`.
    #[must_use]
    pub const fn float(
        name: &'static str,
        unit: &'static str,
        default: f64,
        check: Check<f64>,
        doc: &'static str,
    ) -> Self {
        let spec = ParamSpec::driver_setting(name, ParamKind::Float, unit, check.range, doc);
        Setting { spec, value: SettingValue::Float { default, check } }
    }

    /// A text setting.
    #[must_use]
    pub const fn text(name: &'static str, default: &'static str, check: Check<String>, doc: &'static str) -> Self {
        let spec = ParamSpec::driver_setting(name, ParamKind::Text, "", check.range, doc);
        Setting { spec, value: SettingValue::Text { default, check } }
    }

    /// A choice of `words` (read case-insensitively, kept as declared); the reference lists them.
    #[must_use]
    pub const fn choice(
        name: &'static str,
        words: &'static [&'static str],
        default: &'static str,
        doc: &'static str,
    ) -> Self {
        let spec = ParamSpec::driver_setting(name, ParamKind::Choice(words), "", "", doc);
        Setting { spec, value: SettingValue::Choice { default } }
    }

    /// The value before anything sets it.
    #[must_use]
    pub fn default_value(&self) -> ParamValue {
        match &self.value {
            SettingValue::Int { default, .. } => ParamValue::Int(*default),
            SettingValue::Float { default, .. } => ParamValue::Float(*default),
            SettingValue::Text { default, .. } | SettingValue::Choice { default } => {
                ParamValue::Text((*default).to_string())
            }
        }
    }

    /// The range check of a value already read as `spec.kind` (a [`ParamValue::Int`] for an
    /// integer, …).
    ///
    /// # Errors
    /// What the value must be: "must be {range}", or the check's own words.
    pub fn check(&self, v: &ParamValue) -> Result<(), String> {
        match (&self.value, v) {
            (SettingValue::Int { check, .. }, ParamValue::Int(i)) => check.check(i),
            (SettingValue::Float { check, .. }, ParamValue::Float(f)) => check.check(f),
            (SettingValue::Text { check, .. }, ParamValue::Text(t)) => check.check(t),
            (SettingValue::Choice { .. }, ParamValue::Text(_)) => Ok(()),
            _ => Err(kind_reason(self.spec.kind)),
        }
    }
}

/// A camera driver's settings: the profile table that holds them and the settings themselves.
#[derive(Debug)]
pub struct SettingsTable {
    /// The driver's table in the profile file, e.g. `keyence` for `[keyence]`: lower-case
    /// letters, digits and `_`, and not `vision`.
    pub table: &'static str,
    /// The settings, in the order the profile lists them.
    pub settings: &'static [Setting],
}

/// A driver's settings with their values, as [`Params`](super::Params) carries them.
#[derive(Clone)]
pub struct DriverSettings {
    table: &'static SettingsTable,
    values: Vec<ParamValue>,
}

impl fmt::Debug for DriverSettings {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut map = f.debug_map();
        for (s, v) in self.table.settings.iter().zip(&self.values) {
            map.entry(&s.spec.name, v);
        }
        map.finish()
    }
}

/// Two tables are equal when they are the same table with the same values.
impl PartialEq for DriverSettings {
    fn eq(&self, other: &Self) -> bool {
        self.table.table == other.table.table && self.values == other.values
    }
}

impl DriverSettings {
    /// `table`'s settings at their defaults.
    #[must_use]
    pub fn new(table: &'static SettingsTable) -> DriverSettings {
        DriverSettings { table, values: table.settings.iter().map(Setting::default_value).collect() }
    }

    /// The profile table's name (`keyence`).
    #[must_use]
    pub fn table(&self) -> &'static str {
        self.table.table
    }

    /// The settings' descriptions, in the table's order.
    pub fn specs(&self) -> impl Iterator<Item = &'static ParamSpec> {
        self.table.settings.iter().map(|s| &s.spec)
    }

    /// Every setting with its value, in the table's order.
    #[must_use]
    pub fn values(&self) -> Vec<(&'static str, ParamValue)> {
        self.table.settings.iter().zip(&self.values).map(|(s, v)| (s.spec.name, v.clone())).collect()
    }

    /// The value of setting `name` (case-insensitive); `None` when the table has no such setting.
    #[must_use]
    pub fn get(&self, name: &str) -> Option<&ParamValue> {
        self.index(name).map(|i| &self.values[i])
    }

    /// The integer setting `name`; `None` when the table has no such integer setting.
    #[must_use]
    pub fn int(&self, name: &str) -> Option<i64> {
        match self.get(name)? {
            ParamValue::Int(v) => Some(*v),
            _ => None,
        }
    }

    /// The real-number setting `name`, finite and in its range; `None` when the table has no
    /// such setting.
    #[must_use]
    pub fn float(&self, name: &str) -> Option<f64> {
        match self.get(name)? {
            ParamValue::Float(v) => Some(*v),
            _ => None,
        }
    }

    /// The text or choice setting `name` (a choice as declared); `None` when the table has no
    /// such setting.
    #[must_use]
    pub fn text(&self, name: &str) -> Option<&str> {
        match self.get(name)? {
            ParamValue::Text(v) => Some(v),
            _ => None,
        }
    }

    /// Sets `name` (case-insensitive) to `value` read as the setting's type and checked by the
    /// driver; `Ok(false)` when the table has no such setting.
    ///
    /// # Errors
    /// [`VisionError::InvalidParam`] for a value of the wrong type or out of range; the setting
    /// keeps its value.
    pub fn set(&mut self, name: &str, value: &ParamValue) -> Result<bool, VisionError> {
        let Some(i) = self.index(name) else { return Ok(false) };
        let spec = &self.table.settings[i].spec;
        let invalid = |reason: String| VisionError::InvalidParam {
            name: spec.name.to_string(),
            value: value.to_string(),
            reason,
        };
        let typed = coerce(spec.kind, value).ok_or_else(|| invalid(kind_reason(spec.kind)))?;
        self.table.settings[i].check(&typed).map_err(invalid)?;
        self.values[i] = typed;
        Ok(true)
    }

    fn index(&self, name: &str) -> Option<usize> {
        self.table.settings.iter().position(|s| s.spec.name.eq_ignore_ascii_case(name))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    static TABLE: SettingsTable = SettingsTable {
        table: "fake",
        settings: &[
            Setting::int("FakeCount", "", 2, Check::closed("0 to 9", 0, 9), "A count."),
            Setting::float("FakeSeconds", "s", 1.5, Check::closed("0 to 3 seconds", 0.0, 3.0), "A time."),
            Setting::text("FakeName", "cam", Check::test("not empty", |t: &String| !t.is_empty()), "A name."),
            Setting::choice("FakeMode", &["on", "off"], "on", "A mode."),
        ],
    };

    #[test]
    fn each_kind_of_setting_checks_its_own_kind_and_range() {
        let [count, seconds, name, mode] = TABLE.settings else { panic!("four settings") };
        assert_eq!(count.check(&ParamValue::Int(9)), Ok(()));
        assert!(count.check(&ParamValue::Int(10)).is_err() && count.check(&ParamValue::Float(1.0)).is_err());
        assert_eq!(seconds.check(&ParamValue::Float(3.0)), Ok(()));
        assert!(seconds.check(&ParamValue::Float(3.5)).is_err() && seconds.check(&ParamValue::Int(1)).is_err());
        assert_eq!(name.check(&ParamValue::Text("x".into())), Ok(()));
        assert!(name.check(&ParamValue::Text(String::new())).is_err() && name.check(&ParamValue::Int(1)).is_err());
        assert_eq!(mode.check(&ParamValue::Text("off".into())), Ok(()));
        assert!(mode.check(&ParamValue::Float(1.0)).is_err());
    }

    #[test]
    fn the_settings_show_as_a_map_of_names_to_values() {
        let shown = format!("{:?}", DriverSettings::new(&TABLE));
        assert_eq!(
            shown,
            r#"{"FakeCount": Int(2), "FakeSeconds": Float(1.5), "FakeName": Text("cam"), "FakeMode": Text("on")}"#
        );
    }
}
