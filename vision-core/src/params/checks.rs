//! The range checks of the parameter tables: each says, when it refuses, what the value must be.

use crate::pound::PoundBlock;

/// A range check: `Err` says what the value must be.
pub(super) type Check<T> = fn(&T) -> Result<(), String>;

pub(super) fn any<T>(_: &T) -> Result<(), String> {
    Ok(())
}
pub(super) fn finite(v: &f64) -> Result<(), String> {
    if v.is_finite() {
        Ok(())
    } else {
        Err("must be a finite number".into())
    }
}
pub(super) fn non_negative(v: &f64) -> Result<(), String> {
    if v.is_finite() && *v >= 0.0 {
        Ok(())
    } else {
        Err("must be a finite number ≥ 0 (0 disables)".into())
    }
}
pub(super) fn seconds_60(v: &f64) -> Result<(), String> {
    if v.is_finite() && (0.0..=60.0).contains(v) {
        Ok(())
    } else {
        Err("must be between 0 and 60 seconds".into())
    }
}
pub(super) fn pixel_offset(v: &f64) -> Result<(), String> {
    if v.is_finite() && v.abs() <= 100_000.0 {
        Ok(())
    } else {
        Err("must be a finite number of pixels (|v| ≤ 100000)".into())
    }
}
pub(super) fn noise_px(v: &f64) -> Result<(), String> {
    if v.is_finite() && (0.0..=10.0).contains(v) {
        Ok(())
    } else {
        Err("must be between 0 and 10 pixels".into())
    }
}
pub(super) fn noise_px_wide(v: &f64) -> Result<(), String> {
    if v.is_finite() && (0.0..=1000.0).contains(v) {
        Ok(())
    } else {
        Err("must be between 0 and 1000 pixels".into())
    }
}
pub(super) fn lift_in(v: &f64) -> Result<(), String> {
    if v.is_finite() && (0.0..=2.0).contains(v) {
        Ok(())
    } else {
        Err("must be between 0 and 2 inches (0 = calibrate at one height)".into())
    }
}
pub(super) fn passes(v: &i64) -> Result<(), String> {
    if (0..=10).contains(v) {
        Ok(())
    } else {
        Err("must be 0..10 passes (0 reads in one shot)".into())
    }
}
pub(super) fn job(v: &i64) -> Result<(), String> {
    if (0..=999).contains(v) {
        Ok(())
    } else {
        Err("must be a camera job 0..999 (0 = leave the camera's job)".into())
    }
}
pub(super) fn resolution(v: &i64) -> Result<(), String> {
    if (2..=100_000).contains(v) {
        Ok(())
    } else {
        Err("must be an image size of 2..100000 pixels".into())
    }
}
pub(super) fn resolution_record(v: &i64) -> Result<(), String> {
    if *v == 0 || (2..=100_000).contains(v) {
        Ok(())
    } else {
        Err("must be an image size of 2..100000 pixels (0 = not recorded)".into())
    }
}
pub(super) fn tool(v: &i64) -> Result<(), String> {
    if (0..=i64::from(u32::MAX)).contains(v) {
        Ok(())
    } else {
        Err("must be a tool number ≥ 0 (0 disables the camera-tool check)".into())
    }
}
pub(super) fn pound_base(v: &i64) -> Result<(), String> {
    PoundBlock::new(*v).map(|_| ()).map_err(|e| e.to_string())
}
#[allow(clippy::ptr_arg)] // the signature is `Check<String>`
pub(super) fn driver_name(v: &String) -> Result<(), String> {
    if !v.is_empty() && v.len() <= 64 && v.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-') {
        Ok(())
    } else {
        Err("must be a driver name (letters, digits, _ or -), e.g. Keyence".into())
    }
}
#[allow(clippy::ptr_arg)]
pub(super) fn driver_record(v: &String) -> Result<(), String> {
    if v.is_empty() || driver_name(v).is_ok() {
        Ok(())
    } else {
        Err("must be a driver name (letters, digits, _ or -), or empty (not recorded)".into())
    }
}
#[allow(clippy::ptr_arg)]
pub(super) fn short_text(v: &String) -> Result<(), String> {
    if v.len() <= 4096 && !v.contains('\0') {
        Ok(())
    } else {
        Err("must be text of at most 4096 bytes".into())
    }
}
