//! The OEM parameters (SPEC §5, manual appendix A) under the manual's own names.
//!
//! The parameters fall into parts with one owner each:
//! * [`Config`]: the driver's name, camera, output and quality gates — the operator's settings;
//! * [`DriverSettings`]: a camera driver's own settings (a camera's address, its timeouts, …),
//!   declared, checked and read by the driver ([`SettingsTable`]); the core
//!   only carries them, by name, and the profile keeps them in the driver's own table;
//! * [`Calibration`]: K, the axis flags, `Cal_Units`, `Cal_Date`, the pixel centre offset —
//!   replaced as a whole by M283;
//! * [`Telemetry`]: `Last*` and `Run_*` — written by the module after each operation, read-only
//!   by name, never persisted and never read back to decide anything.
//!
//! [`Params`] is the persisted profile (configuration and calibration). The alignment run's
//! state (mode, open or not, the dot list) is typed in [`crate::module::Run`], not here.
//! Read parameters with the typed getters (`params.cal_k()`, `params.pound_var_base()`, …) or by
//! name with [`Params::get`] (case-insensitive); write them by name with [`Params::set`], which
//! validates the value and refuses telemetry. Units: lengths follow the parameter's doc; times
//! are seconds. The units and the additions to the manual's set: `docs/vision-module.md`.
//!
//! The code, by concern: [`ParamValue`] and the other descriptions in `value.rs`; the Rust types a
//! parameter can have in `typed.rs`; the range checks in `checks.rs`; the table machinery
//! (`param_struct!`, `profile_part!`) in `table.rs`; one file per part (`config.rs`,
//! `calibration.rs` with the K limits, `telemetry.rs`); the drivers' settings in `driver.rs`;
//! [`Params`] here.

#[macro_use]
mod table;
mod calibration;
mod checks;
mod config;
mod driver;
mod telemetry;
pub(crate) mod typed;
mod value;

use vision_math::{Matrix2, Remap};

pub use calibration::{Calibration, K_MAX_ANISOTROPY, K_SCALE_MAX_IN, K_SCALE_MIN_IN};
pub use checks::{Check, Ordered};
pub use config::Config;
pub use driver::{DriverSettings, Setting, SettingValue, SettingsTable};
pub use telemetry::Telemetry;
pub use value::{Access, ParamKind, ParamSpec, ParamValue, Section};

use crate::error::VisionError;

/// The persisted profile (SPEC §5): the [`Config`], the [`Calibration`] and the camera
/// drivers' own settings ([`DriverSettings`]), read and written by the manual's names. The
/// module's run state and its [`Telemetry`] are not part of it.
///
/// Every configuration and calibration getter is also available on `Params` directly
/// (`params.pound_var_base()`, `params.cal_k()`). A driver's settings are known by name once
/// their table is added ([`Params::with_driver_settings`]; `DriverRegistry::params` adds every
/// registered driver's): `Params::default()` knows none.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Params {
    /// The driver's name, camera, output and quality gates.
    pub config: Config,
    /// K, the axis flags, `Cal_Units`, `Cal_Date` and the pixel centre offset.
    pub calibration: Calibration,
    /// The drivers' settings tables, in the order they were added.
    pub(crate) drivers: Vec<DriverSettings>,
}

impl Params {
    /// These parameters with `table`'s settings at their defaults added (kept as they are when
    /// the table is already there).
    #[must_use]
    pub fn with_driver_settings(mut self, table: &'static SettingsTable) -> Params {
        if self.driver_settings(table.table).is_none() {
            self.drivers.push(DriverSettings::new(table));
        }
        self
    }

    /// The settings of the driver whose profile table is `table` (`keyence`), if added.
    #[must_use]
    pub fn driver_settings(&self, table: &str) -> Option<&DriverSettings> {
        self.drivers.iter().find(|d| d.table() == table)
    }

    /// As [`Params::driver_settings`], to write.
    pub fn driver_settings_mut(&mut self, table: &str) -> Option<&mut DriverSettings> {
        self.drivers.iter_mut().find(|d| d.table() == table)
    }

    /// Every driver settings table, in the order they were added.
    pub fn drivers_settings(&self) -> impl Iterator<Item = &DriverSettings> {
        self.drivers.iter()
    }

    /// The core's parameters: configuration, calibration, then telemetry (a driver's settings
    /// are listed by its [`DriverSettings::specs`]).
    pub fn specs() -> impl Iterator<Item = &'static ParamSpec> {
        Config::SPECS.iter().chain(Calibration::SPECS).chain(Telemetry::SPECS)
    }

    /// The spec of parameter `name` (case-insensitive), telemetry included.
    #[must_use]
    pub fn spec(name: &str) -> Option<&'static ParamSpec> {
        Params::specs().find(|s| s.name.eq_ignore_ascii_case(name))
    }

    /// Reads configuration or calibration parameter `name` (case-insensitive). Telemetry is
    /// not in the profile: read it with [`Telemetry::get`] or [`crate::VisionModule::param`].
    ///
    /// # Errors
    /// [`VisionError::UnknownParam`] (also for a telemetry name).
    pub fn get(&self, name: &str) -> Result<ParamValue, VisionError> {
        self.config
            .get(name)
            .or_else(|| self.calibration.get(name))
            .or_else(|| self.drivers.iter().find_map(|d| d.get(name).cloned()))
            .ok_or_else(|| VisionError::UnknownParam { name: name.to_string() })
    }

    /// Writes configuration, calibration or driver setting `name` (case-insensitive) after
    /// validating `value`.
    ///
    /// Text is accepted for every type (`"Yes"`, `"8500"`, `"0.00203"`, `"mm"`), so a CLI can
    /// pass what the user typed.
    ///
    /// # Errors
    /// [`VisionError::UnknownParam`], [`VisionError::ReadOnlyParam`] for telemetry,
    /// [`VisionError::InvalidParam`] for a wrong type or an out-of-range value; on error the
    /// parameter keeps its value.
    pub fn set(&mut self, name: &str, value: impl Into<ParamValue>) -> Result<(), VisionError> {
        let value = value.into();
        if self.config.set_raw(name, &value)? || self.calibration.set_raw(name, &value)? {
            return Ok(());
        }
        for driver in &mut self.drivers {
            if driver.set(name, &value)? {
                return Ok(());
            }
        }
        match Telemetry::SPECS.iter().find(|s| s.name.eq_ignore_ascii_case(name)) {
            Some(spec) => Err(VisionError::ReadOnlyParam { name: spec.name.to_string() }),
            None => Err(VisionError::UnknownParam { name: name.to_string() }),
        }
    }

    /// K as a matrix `[[K11, K12], [K21, K22]]`, `Cal_Units` per pixel.
    #[must_use]
    pub fn cal_k(&self) -> Matrix2<f64> {
        self.calibration.cal_k()
    }

    /// As [`Calibration::set_cal_k`].
    ///
    /// # Errors
    /// [`VisionError::InvalidParam`] for a non-finite entry.
    pub fn set_cal_k(&mut self, k: Matrix2<f64>) -> Result<(), VisionError> {
        self.calibration.set_cal_k(k)
    }

    /// The axis remap from the three `VisionCamera*` flags.
    #[must_use]
    pub fn remap(&self) -> Remap {
        self.calibration.remap()
    }

    /// As [`Calibration::set_remap`].
    pub fn set_remap(&mut self, r: Remap) {
        self.calibration.set_remap(r);
    }

    /// The camera tool number, or `None` when the check is disabled (0).
    #[must_use]
    pub fn camera_tool(&self) -> Option<u32> {
        self.config.camera_tool()
    }

    /// Every persisted parameter with its value: configuration, calibration, then each driver's
    /// settings.
    #[must_use]
    pub fn config_values(&self) -> Vec<(&'static str, ParamValue)> {
        let mut values = self.core_values();
        values.extend(self.drivers.iter().flat_map(DriverSettings::values));
        values
    }

    /// The core's persisted parameters with their values: configuration, then calibration.
    #[must_use]
    pub fn core_values(&self) -> Vec<(&'static str, ParamValue)> {
        Config::SPECS
            .iter()
            .filter_map(|s| self.config.get(s.name).map(|v| (s.name, v)))
            .chain(Calibration::SPECS.iter().filter_map(|s| self.calibration.get(s.name).map(|v| (s.name, v))))
            .collect()
    }
}

#[cfg(test)]
#[expect(clippy::float_cmp, reason = "tests compare exact values")]
pub(crate) mod tests {
    use vision_math::{LengthUnit, Vector2};

    use super::*;

    #[test]
    fn defaults_match_the_manual() {
        let p = Params::default();
        assert!(!p.enabled());
        assert_eq!(p.driver(), "Keyence");
        assert!(matches!(p.get("VisionProbeLevel"), Err(VisionError::UnknownParam { .. })), "a driver's");
        assert_eq!(p.camera_res_x(), 1776);
        assert_eq!(p.pound_var_base(), 500);
        assert_eq!(p.cal_units(), LengthUnit::Inch);
        assert_eq!(p.cal_k(), Matrix2::zeros());
        assert_eq!(Telemetry::default().last_judgment(), -1);
        assert_eq!(Telemetry::default().get("visionrun_mode"), Some(ParamValue::Int(4)));
        assert_eq!(p.get("visionenabled"), Ok(ParamValue::Bool(false)));
        assert_eq!(p.get("VisionCal_Units"), Ok(ParamValue::Text("in".into())));
        assert_eq!(p.fit_max_scale_dev_pct(), 2.0);
        assert_eq!(p.fit_max_shift_in(), 2.5);
        assert_eq!(p.outlier_factor(), 6.0);
        assert_eq!(p.camera_noise_px(), 0.1);
        assert_eq!(p.fit_max_residual_in(), 0.020);
        // Every name carries the prefix, is unique, and is read by the part its access says.
        let specs: Vec<_> = Params::specs().collect();
        for (i, s) in specs.iter().enumerate() {
            assert!(s.name.starts_with("Vision"), "{}", s.name);
            assert!(specs[i + 1..].iter().all(|t| !t.name.eq_ignore_ascii_case(s.name)));
            assert_eq!(p.get(s.name).is_ok(), s.access == Access::Config, "{}", s.name);
            assert_eq!(Telemetry::default().get(s.name).is_some(), s.access == Access::Telemetry, "{}", s.name);
            assert_eq!(Params::spec(&s.name.to_ascii_lowercase()), Some(*s));
        }
        assert!(matches!(p.get("VisionLastStatus"), Err(VisionError::UnknownParam { .. })));
    }

    #[test]
    fn every_spec_says_who_writes_it_and_a_refusal_quotes_its_range() {
        for s in Params::specs() {
            assert!(!s.writer.is_empty(), "{}: who writes it", s.name);
            assert!(!s.doc.trim().is_empty(), "{}: what it means", s.name);
        }
        let mut p = Params::default();
        for (name, bad) in [("VisionCameraResX", 1), ("VisionPoundVarBase", 5050), ("VisionRecenterPasses", 11)] {
            let spec = Params::spec(name).expect("known");
            assert!(!spec.range.is_empty(), "{name}");
            let refusal = p.set(name, bad).expect_err("out of range").to_string();
            if name != "VisionPoundVarBase" {
                assert!(refusal.ends_with(&format!("must be {}", spec.range)), "{refusal}");
            }
        }
        assert_eq!(Params::spec("VisionEnabled").map(|s| s.range), Some(""), "a flag takes every value of its kind");
        assert_eq!(Params::spec("VisionCalibrationLift").map(|s| s.unit), Some("in"));
    }

    #[test]
    fn writes_are_validated_and_telemetry_refused() {
        let mut p = Params::default();
        p.set("VisionEnabled", "Yes").expect("yes");
        assert!(p.enabled());
        p.set("VisionCameraResX", "1600").expect("resolution text");
        assert_eq!(p.camera_res_x(), 1600);
        p.set("VisionCal_K11", 0.00203).expect("k");
        p.set("VisionCal_Units", "mm").expect("mm");
        assert_eq!(p.cal_units(), LengthUnit::Millimetre);
        assert!(matches!(p.set("VisionCameraResX", 170_000), Err(VisionError::InvalidParam { .. })));
        assert_eq!(p.camera_res_x(), 1600);
        assert!(matches!(p.set("VisionCal_K12", f64::NAN), Err(VisionError::InvalidParam { .. })));
        assert!(matches!(p.set("VisionEnabled", "maybe"), Err(VisionError::InvalidParam { .. })));
        assert!(matches!(p.set("VisionCal_Units", "ft"), Err(VisionError::InvalidParam { .. })));
        assert!(matches!(p.set("VisionPoundVarBase", 5050), Err(VisionError::InvalidParam { .. })));
        assert!(matches!(p.set("VisionPoundVarBase", 99), Err(VisionError::InvalidParam { .. })));
        p.set("VisionPoundVarBase", 100).expect("100 is allowed");
        assert_eq!(
            p.set("VisionLastStatus", "OK"),
            Err(VisionError::ReadOnlyParam { name: "VisionLastStatus".into() })
        );
        assert_eq!(p.set("VisionRun_Tx", 1.0), Err(VisionError::ReadOnlyParam { name: "VisionRun_Tx".into() }));
        assert!(matches!(p.set("VisionNope", 1), Err(VisionError::UnknownParam { .. })));
        assert!(matches!(p.set("VisionActiveJob", 1000), Err(VisionError::InvalidParam { .. })));
        assert!(matches!(p.set("VisionCameraResX", 1.5), Err(VisionError::InvalidParam { .. })));
        let e = p.set("VisionCameraResX", "x").expect_err("not a number");
        assert_eq!(e.to_string(), "VisionCameraResX = \"x\" is invalid: must be an integer");
    }

    /// A driver's table, as a driver crate declares one.
    pub(crate) static PROBE: SettingsTable = SettingsTable {
        table: "probe",
        settings: &[
            Setting::int(
                "VisionProbeLevel",
                "",
                5,
                Check::closed("a level 1..9", 1, 9),
                "`VisionProbeLevel`: a level 1..9.",
            ),
            Setting::choice("VisionProbeMode", &["fast", "slow"], "fast", "`VisionProbeMode`: fast or slow."),
        ],
    };

    #[test]
    fn a_drivers_settings_are_read_and_written_by_name_once_its_table_is_added() {
        let mut p = Params::default();
        assert!(matches!(p.set("VisionProbeLevel", 3), Err(VisionError::UnknownParam { .. })));
        p = p.with_driver_settings(&PROBE);
        assert_eq!(p.get("visionprobelevel"), Ok(ParamValue::Int(5)));
        p.set("VisionProbeLevel", "7").expect("text is read as the setting's type");
        p.set("VisionProbeMode", "SLOW").expect("a choice, case-insensitive");
        assert_eq!(p.get("VisionProbeMode"), Ok(ParamValue::Text("slow".into())));
        let e = p.set("VisionProbeLevel", 10).expect_err("the driver's check");
        assert_eq!(e.to_string(), "VisionProbeLevel = 10 is invalid: must be a level 1..9");
        let e = p.set("VisionProbeLevel", "x").expect_err("the type");
        assert_eq!(e.to_string(), "VisionProbeLevel = \"x\" is invalid: must be an integer");
        assert!(matches!(p.set("VisionProbeMode", "medium"), Err(VisionError::InvalidParam { .. })));
        assert_eq!(p.get("VisionProbeLevel"), Ok(ParamValue::Int(7)), "a refused value changes nothing");
        // Adding the table again keeps its values; the values are listed after the core's.
        let p = p.with_driver_settings(&PROBE);
        assert_eq!(p.driver_settings("probe").and_then(|d| d.get("VisionProbeLevel")), Some(&ParamValue::Int(7)));
        let values = p.config_values();
        assert_eq!(values.len(), p.core_values().len() + 2);
        assert_eq!(values.last(), Some(&("VisionProbeMode", ParamValue::Text("slow".into()))));
        assert_ne!(p, Params::default().with_driver_settings(&PROBE));
    }

    #[test]
    fn k_and_remap_helpers() {
        let mut p = Params::default();
        let k = Matrix2::new(1.0, 2.0, 3.0, 4.0);
        p.set_cal_k(k).expect("finite");
        assert_eq!(p.cal_k(), k);
        assert!(p.set_cal_k(Matrix2::new(1.0, f64::INFINITY, 0.0, 0.0)).is_err());
        assert_eq!(p.cal_k(), k);
        let r = Remap { swap_xy: true, invert_x: false, invert_y: true };
        p.set_remap(r);
        assert_eq!(p.remap(), r);
        assert_eq!(p.camera_tool(), None);
        p.set("VisionCameraToolNumber", 98).expect("tool");
        assert_eq!(p.camera_tool(), Some(98));
        assert!(p.config_values().iter().all(|(n, _)| Params::spec(n).map(|s| s.access) == Some(Access::Config)));
        assert_eq!(p.config_values().len(), Config::SPECS.len() + Calibration::SPECS.len());
        // A solved calibration keeps the pixel centre offset and leaves the original alone.
        p.set("VisionPxCenterOffsetX", 3.5).expect("offset");
        let next = p.calibration.solved(Matrix2::identity(), Remap::IDENTITY, LengthUnit::Millimetre, "D").expect("ok");
        assert_eq!(
            (next.cal_k(), next.cal_units(), next.cal_date()),
            (Matrix2::identity(), LengthUnit::Millimetre, "D")
        );
        assert_eq!(next.center_offset(), Vector2::new(3.5, 0.0));
        assert_eq!(p.cal_k(), k);
        assert!(p.calibration.solved(Matrix2::from_element(f64::NAN), Remap::IDENTITY, LengthUnit::Inch, "").is_err());
    }
}
