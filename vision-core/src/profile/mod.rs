//! The TOML profile: calibration and configuration that survive a restart (SPEC §5).
//!
//! Only configuration parameters are stored (telemetry is runtime state). The file looks like
//!
//! ```toml
//! [vision]
//! VisionEnabled = true
//! VisionCal_K11 = 0.00203
//! # …
//!
//! [keyence]   # a camera driver's own settings
//! # …
//! ```
//!
//! `[vision]` holds the core's parameters; each camera driver with settings has its own table
//! (its [`SettingsTable`](crate::params::SettingsTable)), under the manual's names. A store
//! knows the drivers' tables of the parameters it starts from ([`ProfileStore::with_defaults`]).
//! Saving is atomic, and several processes may share one profile
//! ([`ProfileStore::save_changes`]); bad input is refused at load, naming the key. The text is
//! `toml.rs`'s concern, the file system `fs.rs`'s. How a save writes, locks and merges, and what
//! a load refuses: `docs/vision-module.md` (the profile).

mod fs;
mod toml;

use std::path::{Path, PathBuf};

use crate::error::VisionError;
use crate::params::{ParamValue, Params};

use self::fs::dir_of;
pub use self::fs::{ProfileFs, StdFs, MAX_PROFILE_BYTES};
pub use self::toml::{from_toml, from_toml_with, to_toml};

/// Where the profile lives and how it is written.
pub struct ProfileStore {
    path: PathBuf,
    fs: Box<dyn ProfileFs>,
    /// Values saved instead of the module's (see [`ProfileStore::keep`]).
    kept: Vec<(&'static str, ParamValue)>,
    /// What a load starts from (see [`ProfileStore::with_defaults`]).
    base: Params,
    /// The session's parameters as of its last sync with the file (attach or save): a save
    /// writes only what differs from them ([`ProfileStore::save_changes`]).
    synced: Option<Params>,
}

impl std::fmt::Debug for ProfileStore {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ProfileStore").field("path", &self.path).finish_non_exhaustive()
    }
}

impl ProfileStore {
    /// A store for the TOML file `path` on the real file system.
    #[must_use]
    pub fn new(path: impl Into<PathBuf>) -> ProfileStore {
        ProfileStore::with_fs(path, Box::new(StdFs))
    }

    /// A store for `path` whose writes go through `fs`.
    #[must_use]
    pub fn with_fs(path: impl Into<PathBuf>, fs: Box<dyn ProfileFs>) -> ProfileStore {
        ProfileStore { path: path.into(), fs, kept: Vec::new(), base: Params::default(), synced: None }
    }

    /// Loads start from `base` instead of the defaults: the parameters a missing file gives,
    /// and, with them, the drivers' settings tables a file may hold (`DriverRegistry::params`
    /// gives every registered driver's).
    #[must_use]
    pub fn with_defaults(mut self, base: Params) -> ProfileStore {
        self.base = base;
        self
    }

    /// Every later save writes `value` for parameter `name`, whatever the module holds: for a
    /// choice made for one session only (a command line's camera address) that must not
    /// replace the file's.
    #[must_use]
    pub fn keep(mut self, name: &'static str, value: ParamValue) -> ProfileStore {
        self.kept.retain(|(n, _)| *n != name);
        self.kept.push((name, value));
        self
    }

    /// Checks, without changing anything, that a save can succeed as far as the folder goes:
    /// the path is a regular file or absent, and its folder exists and takes a new file. Call
    /// it before the motion whose result is to be saved.
    ///
    /// # Errors
    /// [`VisionError::Profile`] saying what is wrong.
    pub fn check_writable(&self) -> Result<(), VisionError> {
        let target = self.target()?;
        self.require_regular_file(&target)?;
        let dir = dir_of(&target);
        let probe = self.temp_path(&target);
        match std::fs::OpenOptions::new().write(true).create_new(true).open(&probe) {
            Ok(f) => {
                drop(f);
                let _ = std::fs::remove_file(&probe);
                Ok(())
            }
            Err(e) => Err(self.err(format!(
                "cannot be saved: cannot create a file in {}: {e} — create the folder or make it writable",
                dir.display()
            ))),
        }
    }

    /// The profile file.
    #[must_use]
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Reads the profile: the defaults ([`ProfileStore::with_defaults`]), overridden by every
    /// parameter in the file (validated).
    ///
    /// # Errors
    /// [`VisionError::Profile`] when the path is empty or holds a NUL byte, or the file cannot
    /// be read, is larger than [`MAX_PROFILE_BYTES`], cannot be parsed, or names an unknown or
    /// read-only parameter or an invalid value.
    pub fn load(&self) -> Result<Params, VisionError> {
        let target = self.target()?;
        self.read(&target)
    }

    /// As [`ProfileStore::load`], but a missing file gives the defaults.
    ///
    /// # Errors
    /// As [`ProfileStore::load`] for a file that exists.
    pub fn load_or_default(&self) -> Result<Params, VisionError> {
        let target = self.target()?;
        if target.exists() {
            self.read(&target)
        } else {
            Ok(self.base.clone())
        }
    }

    /// Remembers `params` as the session's parameters in step with the file: later saves write
    /// only what differs from them ([`ProfileStore::save_changes`]). The module calls it when
    /// the store is attached.
    pub fn mark_synced(&mut self, params: &Params) {
        self.synced = Some(params.clone());
    }

    /// Saves the configuration parameters of `params` atomically (`docs/vision-module.md`), as
    /// [`ProfileStore::save_changes`] does.
    ///
    /// # Errors
    /// As [`ProfileStore::save_changes`].
    pub fn save(&mut self, params: &Params) -> Result<(), VisionError> {
        self.save_changes(params).map(drop)
    }

    /// Saves `params` under the profile's lock and returns the parameters the session holds
    /// now. When the store knows the session's parameters as of its last sync
    /// ([`ProfileStore::mark_synced`]; every save syncs) and the file exists, what is written
    /// is the file as it is now with what `params` changed since the sync (the calibration as
    /// one unit, the rest by name; kept names keep the file's value); what is returned is that,
    /// with `params`' values of the kept names. Otherwise every parameter of `params` is
    /// written (kept names with their kept value) and `params` is returned.
    ///
    /// # Errors
    /// [`VisionError::Profile`]: a bad path, a file on disk that cannot be read, a merge that
    /// does not hold together, or a failed write; the previous file is intact and no temporary
    /// file is left.
    pub fn save_changes(&mut self, params: &Params) -> Result<Params, VisionError> {
        let target = self.target()?;
        self.require_regular_file(&target)?;
        let dir = dir_of(&target);
        let previous = if target.exists() { "the previous profile is intact" } else { "no profile was written" };
        let _lock = self.lock(&target, &dir).map_err(|e| self.err(format!("{e}; {previous}")))?;
        let (file, session) = match (&self.synced, target.exists()) {
            (Some(synced), true) => {
                let disk = self.read(&target).map_err(|e| {
                    self.err(format!("changed on disk and cannot be read now ({e}); nothing was saved — fix or remove it, then re-run"))
                })?;
                self.merge(disk, synced, params)?
            }
            _ => {
                let mut file = params.clone();
                for (name, value) in &self.kept {
                    file.set(name, value.clone()).map_err(|e| self.err(e.to_string()))?;
                }
                (file, params.clone())
            }
        };
        let text = to_toml(&file).map_err(|e| self.err(e))?;
        self.remove_stale_temps(&target, &dir);
        let tmp = self.temp_path(&target);
        if let Err(e) = self.fs.write_synced(&tmp, text.as_bytes()) {
            let _ = self.fs.remove(&tmp);
            return Err(self.err(format!("cannot write {}: {e}; {previous}", tmp.display())));
        }
        if let Err(e) = self.fs.rename(&tmp, &target) {
            let _ = self.fs.remove(&tmp);
            return Err(self.err(format!("cannot replace the profile: {e}; {previous}")));
        }
        let _ = self.fs.sync_dir(&dir);
        self.synced = Some(session.clone());
        Ok(session)
    }

    /// The file to write (`disk` with what `params` changed since `synced`) and the session's
    /// parameters after the save.
    fn merge(&self, disk: Params, synced: &Params, params: &Params) -> Result<(Params, Params), VisionError> {
        let conflict = |e: String| {
            self.err(format!(
                "changed on disk since this session read it, and this session's change does not fit it: {e} — \
                 nothing was saved; re-run"
            ))
        };
        let is_kept = |name: &str| self.kept.iter().any(|(n, _)| *n == name);
        let mut file = disk;
        // The calibration is one unit: K with its date, units and axis flags.
        if params.calibration != synced.calibration {
            file.calibration = params.calibration.clone();
        }
        for (name, value) in params.config_values() {
            let changed = synced.get(name).ok().as_ref() != Some(&value);
            if changed && params.calibration.get(name).is_none() && !is_kept(name) {
                file.set(name, value).map_err(|e| conflict(e.to_string()))?;
            }
        }
        file.calibration.check_k().map_err(|e| conflict(e.to_string()))?;
        let mut session = file.clone();
        for (name, _) in &self.kept {
            let value = params.get(name).map_err(|e| self.err(e.to_string()))?;
            session.set(name, value).map_err(|e| self.err(e.to_string()))?;
        }
        Ok((file, session))
    }

    fn err(&self, reason: String) -> VisionError {
        VisionError::Profile { path: self.path.display().to_string(), reason }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::tests::PROBE;
    use std::fs::{self, OpenOptions};
    use std::io;
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
        p.set("VisionCameraResX", 1600).expect("set");
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
        assert_eq!(back.camera_res_x(), 1600);
        assert_eq!(back, p);
        // No temporary file is left behind; the lock file stays (removing it would race).
        let mut names: Vec<_> = fs::read_dir(&dir).expect("dir").flatten().map(|e| e.file_name()).collect();
        names.sort();
        assert_eq!(names, [".vision.toml.lock", "vision.toml"].map(std::ffi::OsString::from));
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_drivers_settings_load_from_its_table_or_vision_and_save_to_its_table() {
        let base = Params::default().with_driver_settings(&PROBE);
        // The manual's flat form (and profiles written before drivers had tables).
        let flat =
            from_toml_with("[vision]\nVisionEnabled = true\nVisionProbeLevel = 7\n", base.clone()).expect("flat");
        assert_eq!(flat.get("VisionProbeLevel"), Ok(ParamValue::Int(7)));
        let text = to_toml(&flat).expect("save");
        assert!(text.contains("[probe]\nVisionProbeLevel = 7\nVisionProbeMode = \"fast\"\n"), "{text}");
        assert!(text.find("[vision]") < text.find("[probe]"), "{text}");
        assert!(!text[..text.find("[probe]").unwrap_or(0)].contains("VisionProbe"), "{text}");
        assert_eq!(from_toml_with(&text, base.clone()), Ok(flat.clone()), "nothing is lost");
        // A table's own keys only, checked by the driver; a table the store does not know is refused.
        let e = from_toml_with("[vision]\n[probe]\nVisionEnabled = true\n", base.clone()).expect_err("core key");
        assert!(e.contains("[probe] VisionEnabled: unknown setting") && e.contains("VisionProbeLevel"), "{e}");
        let e = from_toml_with("[vision]\n[probe]\nVisionProbeLevel = 0\n", base.clone()).expect_err("range");
        assert!(e.contains("VisionProbeLevel = 0 is invalid"), "{e}");
        let e = from_toml(&text).expect_err("no such driver");
        assert!(e.contains("unknown table or key `probe`"), "{e}");
        // A missing file gives the store's defaults.
        let dir = tmp_dir("drivers");
        let store = ProfileStore::new(dir.join("vision.toml")).with_defaults(base.clone());
        assert_eq!(store.load_or_default(), Ok(base));
        let _ = fs::remove_dir_all(&dir);
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
            assert_eq!(count, 2, "the temporary file was removed (the profile and its lock file stay)");
        }
        let _ = fs::remove_dir_all(&dir);
    }

    #[cfg(unix)]
    #[test]
    fn a_path_that_is_not_a_regular_file_is_refused_without_blocking() {
        let dir = tmp_dir("fifo");
        let fifo = dir.join("vision.toml");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status().map(|s| s.success());
        for path in
            [dir.clone(), PathBuf::from("/dev/null")].into_iter().chain(made.ok().filter(|ok| *ok).map(|_| fifo))
        {
            let store = ProfileStore::new(&path);
            let e = store.load_or_default().expect_err("not a file");
            assert!(e.to_string().contains("not a regular file"), "{e}");
            assert!(store.check_writable().is_err());
            assert!(ProfileStore::new(&path).save(&Params::default()).is_err());
        }
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_missing_folder_is_found_before_saving_and_nothing_claims_a_previous_profile() {
        let dir = tmp_dir("missing");
        let path = dir.join("no-such-folder").join("vision.toml");
        let store = ProfileStore::new(&path);
        let e = store.check_writable().expect_err("missing folder");
        assert!(e.to_string().contains("create the folder"), "{e}");
        let e = ProfileStore::new(&path).save(&calibrated()).expect_err("missing folder");
        assert!(e.to_string().contains("no profile was written"), "{e}");
        assert!(!e.to_string().contains("intact"), "{e}");
        ProfileStore::new(dir.join("vision.toml")).check_writable().expect("writable");
        assert_eq!(fs::read_dir(&dir).expect("dir").count(), 0, "the check leaves nothing");
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn kept_values_are_saved_instead_of_the_modules() {
        let dir = tmp_dir("kept");
        let path = dir.join("vision.toml");
        let mut store = ProfileStore::new(&path).keep("VisionCameraResX", ParamValue::from(1600));
        let mut p = calibrated();
        p.set("VisionDriver", "Sim").expect("set");
        store.save(&p).expect("save");
        let back = ProfileStore::new(&path).load().expect("load");
        assert_eq!(back.camera_res_x(), 1600);
        assert_eq!(back.driver(), "Sim", "only kept names are replaced");
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn stale_temporary_files_of_dead_processes_are_removed_on_save() {
        let dir = tmp_dir("stale");
        let path = dir.join("vision.toml");
        // A process that has exited: its pid is free (until reused, which the check rechecks).
        let mut child = std::process::Command::new("true").spawn().expect("spawn");
        let dead = child.id();
        child.wait().expect("wait");
        let live = std::process::id();
        let stale = dir.join(format!(".vision.toml.tmp-{dead}-3"));
        let in_progress = dir.join(format!(".vision.toml.tmp-{live}-999999"));
        let other = dir.join(format!(".other.toml.tmp-{dead}-3"));
        for f in [&stale, &in_progress, &other] {
            fs::write(f, "half").expect("write");
        }
        ProfileStore::new(&path).save(&calibrated()).expect("save");
        if Path::new("/proc/self").exists() {
            assert!(!stale.exists(), "a dead process's temporary file is removed");
        }
        assert!(in_progress.exists(), "a live process's is kept");
        assert!(other.exists(), "another profile's is kept");
        let _ = fs::remove_dir_all(&dir);
    }

    fn job(p: &Params) -> ParamValue {
        p.get("VisionActiveJob").expect("job")
    }

    /// Two sessions attached to one file: each save writes only its own change, and the
    /// session takes the other's calibration in memory.
    #[test]
    fn a_save_writes_only_what_the_session_changed() {
        let dir = tmp_dir("merge");
        let path = dir.join("vision.toml");
        let start = Params::default();
        ProfileStore::new(&path).save(&start).expect("first save");
        let (mut a, mut b) = (ProfileStore::new(&path), ProfileStore::new(&path));
        a.mark_synced(&start);
        b.mark_synced(&start);
        // A calibrates (M283), then B, still holding the old K, switches the job (M284).
        let a_now = a.save_changes(&calibrated()).expect("a saves");
        let mut b_next = start.clone();
        b_next.set("VisionActiveJob", 12).expect("job");
        let b_now = b.save_changes(&b_next).expect("b saves");
        let file = ProfileStore::new(&path).load().expect("load");
        assert_eq!(file.calibration, calibrated().calibration, "A's calibration is not lost");
        assert_eq!(job(&file), ParamValue::Int(12), "B's job is saved");
        assert_eq!(file.enabled(), calibrated().enabled(), "A's change by name is kept");
        assert_eq!(b_now, file, "B now holds A's calibration");
        // A's next save (nothing changed) keeps B's job, and A takes it.
        assert_eq!(a.save_changes(&a_now).expect("a again"), file);
        assert_eq!(ProfileStore::new(&path).load().expect("load"), file);
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_save_over_a_file_that_became_unreadable_is_refused_and_writes_nothing() {
        let dir = tmp_dir("unreadable");
        let path = dir.join("vision.toml");
        let start = Params::default();
        ProfileStore::new(&path).save(&start).expect("first save");
        let mut b = ProfileStore::new(&path);
        b.mark_synced(&start);
        fs::write(&path, "[vision]\nVisionBogus = 1\n").expect("hand edit");
        let e = b.save_changes(&calibrated()).expect_err("cannot merge");
        assert!(
            e.to_string().contains("changed on disk and cannot be read now") && e.to_string().contains("VisionBogus"),
            "{e}"
        );
        assert_eq!(fs::read_to_string(&path).expect("read"), "[vision]\nVisionBogus = 1\n");
        let _ = fs::remove_dir_all(&dir);
    }

    /// A save waits for another process's save: the lock is held from the read to the rename.
    #[test]
    fn a_save_waits_for_the_lock() {
        let dir = tmp_dir("lock");
        let path = dir.join("vision.toml");
        ProfileStore::new(&path).save(&Params::default()).expect("first save");
        let lock = OpenOptions::new().write(true).open(dir.join(".vision.toml.lock")).expect("lock file");
        lock.lock().expect("lock");
        let saver = {
            let path = path.clone();
            std::thread::spawn(move || {
                let mut store = ProfileStore::new(&path);
                store.mark_synced(&Params::default());
                store.save_changes(&calibrated()).map(|_| ())
            })
        };
        std::thread::sleep(std::time::Duration::from_millis(200));
        assert_eq!(ProfileStore::new(&path).load().expect("load"), Params::default(), "not saved while locked");
        lock.unlock().expect("unlock");
        saver.join().expect("thread").expect("save");
        assert_eq!(ProfileStore::new(&path).load().expect("load").calibration, calibrated().calibration);
        let _ = fs::remove_dir_all(&dir);
    }

    #[cfg(unix)]
    #[test]
    fn a_symbolic_link_is_written_through_to_its_target() {
        let dir = tmp_dir("symlink");
        let real = dir.join("real");
        fs::create_dir_all(&real).expect("dir");
        let target = real.join("vision.toml");
        let link = dir.join("link.toml");
        // A relative link, through a second link.
        std::os::unix::fs::symlink("real/vision.toml", dir.join("hop.toml")).expect("link");
        std::os::unix::fs::symlink("hop.toml", &link).expect("link");
        let mut store = ProfileStore::new(&link);
        assert!(store.check_writable().is_ok(), "a dangling link to a writable folder");
        store.save(&calibrated()).expect("save");
        assert!(fs::symlink_metadata(&link).expect("link").file_type().is_symlink(), "still a link");
        assert_eq!(ProfileStore::new(&target).load().expect("target"), calibrated());
        let mut names: Vec<_> = fs::read_dir(&real).expect("dir").flatten().map(|e| e.file_name()).collect();
        names.sort();
        assert_eq!(names, [".vision.toml.lock", "vision.toml"].map(std::ffi::OsString::from));
        // A loop of links is refused.
        std::os::unix::fs::symlink("loop.toml", dir.join("loop.toml")).expect("link");
        let e = ProfileStore::new(dir.join("loop.toml")).load_or_default().expect_err("loop");
        assert!(e.to_string().contains("symbolic links (a loop?)"), "{e}");
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_file_larger_than_a_profile_is_refused_unread() {
        let dir = tmp_dir("big");
        let path = dir.join("vision.toml");
        let mut text = "[vision]\n".to_string();
        text.push_str(&"#".repeat(usize::try_from(MAX_PROFILE_BYTES).expect("fits")));
        fs::write(&path, &text).expect("write");
        let e = ProfileStore::new(&path).load().expect_err("too big");
        assert!(e.to_string().contains(&format!("is {} bytes; a profile is at most 1048576 bytes", text.len())), "{e}");
        fs::write(&path, &text[..usize::try_from(MAX_PROFILE_BYTES).expect("fits")]).expect("write");
        assert!(ProfileStore::new(&path).load().is_ok(), "exactly the bound is read");
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn an_empty_path_or_a_nul_byte_is_refused() {
        for (path, says) in [("", "no profile path was given"), ("vision\0.toml", "NUL byte")] {
            let mut store = ProfileStore::new(path);
            for e in [
                store.load_or_default().expect_err(path),
                store.check_writable().expect_err(path),
                store.save(&Params::default()).expect_err(path),
            ] {
                assert!(e.to_string().contains(says), "{e}");
            }
        }
    }
}
