//! The TOML profile: calibration and configuration that survive a restart (SPEC §5).
//!
//! Only configuration parameters are stored (telemetry is runtime state). The file looks like
//!
//! ```toml
//! [vision]
//! VisionEnabled = true
//! VisionCal_K11 = 0.00203
//! # …
//! ```
//!
//! Saving is atomic: the whole profile (so K11..K22 together) is written to a temporary file in
//! the same folder, flushed to disk (`fsync`), and renamed over the old file; the folder is then
//! synced (best effort). A failure at any step removes the temporary file and leaves the
//! previous profile intact. The file system steps go through the small [`ProfileFs`] trait so a
//! test can inject a failure.

use std::collections::BTreeMap;
use std::fs::{self, File, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use serde::{Deserialize, Serialize};

use crate::error::VisionError;
use crate::params::{ParamValue, Params};

/// The file-system steps of an atomic save.
pub trait ProfileFs: Send {
    /// Creates or truncates `path`, writes all of `bytes`, and flushes it to disk (`fsync`).
    ///
    /// # Errors
    /// Any I/O error; the caller removes `path` afterwards.
    fn write_synced(&mut self, path: &Path, bytes: &[u8]) -> io::Result<()>;
    /// Renames `from` over `to` (atomic on one file system).
    ///
    /// # Errors
    /// Any I/O error.
    fn rename(&mut self, from: &Path, to: &Path) -> io::Result<()>;
    /// Removes `path`.
    ///
    /// # Errors
    /// Any I/O error.
    fn remove(&mut self, path: &Path) -> io::Result<()>;
    /// Flushes the folder entry `dir` to disk (best effort; may be a no-op).
    ///
    /// # Errors
    /// Any I/O error (ignored by the caller).
    fn sync_dir(&mut self, dir: &Path) -> io::Result<()>;
}

/// The real file system.
#[derive(Debug, Clone, Copy, Default)]
pub struct StdFs;

impl ProfileFs for StdFs {
    fn write_synced(&mut self, path: &Path, bytes: &[u8]) -> io::Result<()> {
        let mut f = OpenOptions::new().write(true).create(true).truncate(true).open(path)?;
        f.write_all(bytes)?;
        f.sync_all()
    }
    fn rename(&mut self, from: &Path, to: &Path) -> io::Result<()> {
        fs::rename(from, to)
    }
    fn remove(&mut self, path: &Path) -> io::Result<()> {
        fs::remove_file(path)
    }
    fn sync_dir(&mut self, dir: &Path) -> io::Result<()> {
        File::open(dir)?.sync_all()
    }
}

/// Where the profile lives and how it is written.
pub struct ProfileStore {
    path: PathBuf,
    fs: Box<dyn ProfileFs>,
}

impl std::fmt::Debug for ProfileStore {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ProfileStore").field("path", &self.path).finish_non_exhaustive()
    }
}

#[derive(Serialize, Deserialize)]
struct ProfileFile {
    vision: BTreeMap<String, toml::Value>,
}

static TEMP_COUNTER: AtomicU64 = AtomicU64::new(0);

impl ProfileStore {
    /// A store for the TOML file `path` on the real file system.
    #[must_use]
    pub fn new(path: impl Into<PathBuf>) -> ProfileStore {
        ProfileStore::with_fs(path, Box::new(StdFs))
    }

    /// A store for `path` whose writes go through `fs`.
    #[must_use]
    pub fn with_fs(path: impl Into<PathBuf>, fs: Box<dyn ProfileFs>) -> ProfileStore {
        ProfileStore { path: path.into(), fs }
    }

    /// The profile file.
    #[must_use]
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Reads the profile: defaults, overridden by every parameter in the file (validated).
    ///
    /// # Errors
    /// [`VisionError::Profile`] when the file cannot be read or parsed, or names an unknown or
    /// read-only parameter or an invalid value.
    pub fn load(&self) -> Result<Params, VisionError> {
        let text = fs::read_to_string(&self.path).map_err(|e| self.err(format!("cannot read: {e}")))?;
        from_toml(&text).map_err(|e| self.err(e))
    }

    /// As [`ProfileStore::load`], but a missing file gives the defaults.
    ///
    /// # Errors
    /// As [`ProfileStore::load`] for a file that exists.
    pub fn load_or_default(&self) -> Result<Params, VisionError> {
        if self.path.exists() {
            self.load()
        } else {
            Ok(Params::default())
        }
    }

    /// Saves every configuration parameter of `params` atomically (see the module doc).
    ///
    /// # Errors
    /// [`VisionError::Profile`]; the previous file is intact and no temporary file is left.
    pub fn save(&mut self, params: &Params) -> Result<(), VisionError> {
        let text = to_toml(params).map_err(|e| self.err(e))?;
        let dir = match self.path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let name = self.path.file_name().map_or_else(|| "profile".into(), |n| n.to_string_lossy().into_owned());
        let n = TEMP_COUNTER.fetch_add(1, Ordering::Relaxed);
        let tmp = dir.join(format!(".{name}.tmp-{}-{n}", std::process::id()));
        if let Err(e) = self.fs.write_synced(&tmp, text.as_bytes()) {
            let _ = self.fs.remove(&tmp);
            return Err(self.err(format!("cannot write {}: {e}; the previous profile is intact", tmp.display())));
        }
        if let Err(e) = self.fs.rename(&tmp, &self.path) {
            let _ = self.fs.remove(&tmp);
            return Err(self.err(format!("cannot replace the profile: {e}; the previous profile is intact")));
        }
        let _ = self.fs.sync_dir(&dir);
        Ok(())
    }

    fn err(&self, reason: String) -> VisionError {
        VisionError::Profile { path: self.path.display().to_string(), reason }
    }
}

/// The profile text for `params` (configuration parameters only).
///
/// # Errors
/// A serialisation failure (not expected for validated parameters).
pub fn to_toml(params: &Params) -> Result<String, String> {
    let vision = params
        .config_values()
        .into_iter()
        .map(|(name, v)| {
            let value = match v {
                ParamValue::Bool(b) => toml::Value::Boolean(b),
                ParamValue::Int(i) => toml::Value::Integer(i),
                ParamValue::Float(f) => toml::Value::Float(f),
                ParamValue::Text(s) => toml::Value::String(s),
            };
            (name.to_string(), value)
        })
        .collect();
    let body = toml::to_string(&ProfileFile { vision }).map_err(|e| format!("cannot serialise: {e}"))?;
    Ok(format!(
        "# mach-vision: Vision OEM parameters (calibration and configuration).\n\
         # Written atomically by the Vision module; do not edit VisionCal_K11..K22 by hand.\n{body}"
    ))
}

/// Parameters from profile text: defaults overridden by every entry of `[vision]`.
///
/// # Errors
/// A parse error, an unknown or telemetry name, or an invalid value (the message says which).
pub fn from_toml(text: &str) -> Result<Params, String> {
    let file: ProfileFile = toml::from_str(text).map_err(|e| format!("cannot parse: {e}"))?;
    let mut params = Params::default();
    for (name, value) in file.vision {
        let v = match value {
            toml::Value::Boolean(b) => ParamValue::Bool(b),
            toml::Value::Integer(i) => ParamValue::Int(i),
            toml::Value::Float(f) => ParamValue::Float(f),
            toml::Value::String(s) => ParamValue::Text(s),
            other => return Err(format!("{name}: unsupported value {other}")),
        };
        params.set(&name, v).map_err(|e| e.to_string())?;
    }
    Ok(params)
}

#[cfg(test)]
#[allow(clippy::float_cmp)]
mod tests {
    use super::*;
    use vision_math::{LengthUnit, Matrix2};

    fn tmp_dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("vision-core-profile-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).expect("tmp");
        d
    }

    fn calibrated() -> Params {
        let mut p = Params::default();
        p.set("VisionEnabled", true).expect("set");
        p.set_cal_k(Matrix2::new(0.00203, 1e-5, -1e-5, 0.00204)).expect("k");
        p.set("VisionCal_Units", "mm").expect("set");
        p.set("VisionCal_Date", "2025-01-02T03:04:05+00:00").expect("set");
        p.set("VisionIP", "10.0.0.7").expect("set");
        p
    }

    #[test]
    fn round_trip_keeps_config_and_drops_telemetry() {
        let dir = tmp_dir("roundtrip");
        let mut store = ProfileStore::new(dir.join("vision.toml"));
        assert_eq!(store.load_or_default(), Ok(Params::default()));
        let p = calibrated();
        store.save(&p).expect("save");
        let back = store.load().expect("load");
        assert_eq!(back.cal_k(), p.cal_k());
        assert_eq!(back.cal_units(), LengthUnit::Millimetre);
        assert_eq!(back.ip(), "10.0.0.7");
        assert_eq!(back, p);
        // No temporary file is left behind.
        let names: Vec<_> = fs::read_dir(&dir).expect("dir").flatten().map(|e| e.file_name()).collect();
        assert_eq!(names, vec![std::ffi::OsString::from("vision.toml")]);
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn bad_profiles_are_refused_with_the_reason() {
        assert!(from_toml("[vision]\nVisionPort = 0\n").expect_err("range").contains("VisionPort"));
        assert!(from_toml("[vision]\nVisionLastStatus = \"x\"\n").expect_err("ro").contains("read-only"));
        assert!(from_toml("[vision]\nVisionBogus = 1\n").expect_err("unknown").contains("unknown parameter"));
        assert!(from_toml("not toml [").expect_err("parse").starts_with("cannot parse"));
        assert!(from_toml("[vision]\nVisionIP = [1]\n").expect_err("array").contains("unsupported"));
        assert_eq!(from_toml("[vision]\n"), Ok(Params::default()));
    }

    /// Writes half the bytes, then fails — a crash or a full disk mid-save.
    struct FailingFs {
        fail_rename: bool,
    }

    impl ProfileFs for FailingFs {
        fn write_synced(&mut self, path: &Path, bytes: &[u8]) -> io::Result<()> {
            if self.fail_rename {
                return StdFs.write_synced(path, bytes);
            }
            fs::write(path, &bytes[..bytes.len() / 2])?;
            Err(io::Error::other("disk full"))
        }
        fn rename(&mut self, from: &Path, to: &Path) -> io::Result<()> {
            if self.fail_rename {
                Err(io::Error::other("rename refused"))
            } else {
                StdFs.rename(from, to)
            }
        }
        fn remove(&mut self, path: &Path) -> io::Result<()> {
            StdFs.remove(path)
        }
        fn sync_dir(&mut self, dir: &Path) -> io::Result<()> {
            StdFs.sync_dir(dir)
        }
    }

    #[test]
    fn a_failed_save_leaves_the_previous_file_intact() {
        let dir = tmp_dir("failing");
        let path = dir.join("vision.toml");
        let old = calibrated();
        ProfileStore::new(&path).save(&old).expect("first save");
        let before = fs::read(&path).expect("read");
        let mut new = old.clone();
        new.set_cal_k(Matrix2::new(9.0, 9.0, 9.0, 9.0)).expect("k");
        for fail_rename in [false, true] {
            let mut store = ProfileStore::with_fs(&path, Box::new(FailingFs { fail_rename }));
            let e = store.save(&new).expect_err("injected failure");
            assert!(e.to_string().contains("previous profile is intact"), "{e}");
            assert_eq!(fs::read(&path).expect("read"), before);
            assert_eq!(ProfileStore::new(&path).load().expect("load").cal_k(), old.cal_k());
            let count = fs::read_dir(&dir).expect("dir").count();
            assert_eq!(count, 1, "the temporary file was removed");
        }
        let _ = fs::remove_dir_all(&dir);
    }
}
