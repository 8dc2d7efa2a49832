//! A camera driver's own settings: the driver declares them ([`SettingsTable`]), names them,
//! checks them and reads them; the core only carries their values in [`Params`](super::Params)
//! ([`DriverSettings`]) so they are read and written by name like every parameter and saved
//! in the profile under the driver's own table.

use std::fmt;

use super::typed::{coerce, kind_reason};
use super::value::{ParamSpec, ParamValue};
use crate::error::VisionError;

/// One setting of a camera driver, as the driver declares it.
#[derive(Debug)]
pub struct Setting {
    /// Its name (the manual's, `Vision…`), type, section and description with units.
    /// `access` is [`Access::Config`](super::Access::Config): a driver setting is written by
    /// the operator and persisted.
    pub spec: ParamSpec,
    /// The value before anything sets it, of `spec.kind`.
    pub default: fn() -> ParamValue,
    /// The driver's range check of a value already read as `spec.kind` (a
    /// [`ParamValue::Int`] for an integer, …): `Err` says what the value must be.
    pub check: fn(&ParamValue) -> Result<(), String>,
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
        DriverSettings { table, values: table.settings.iter().map(|s| (s.default)()).collect() }
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
        (self.table.settings[i].check)(&typed).map_err(invalid)?;
        self.values[i] = typed;
        Ok(true)
    }

    fn index(&self, name: &str) -> Option<usize> {
        self.table.settings.iter().position(|s| s.spec.name.eq_ignore_ascii_case(name))
    }
}
