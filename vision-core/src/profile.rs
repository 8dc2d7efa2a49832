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
//! (its [`SettingsTable`](crate::params::SettingsTable)), under the manual's names. A driver's
//! settings are read from `[vision]` too, where the manual writes them (and where profiles
//! written before drivers had tables hold them); a save writes them to the driver's table. A
//! store knows the drivers' tables of the parameters it starts from
//! ([`ProfileStore::with_defaults`]).
//!
//! Saving is atomic: the whole profile (so K11..K22 together) is written to a temporary file in
//! the same folder, flushed to disk (`fsync`), and renamed over the old file; the folder is then
//! synced (best effort). A profile path that is a symbolic link is written through to its
//! target, the temporary file beside the target.
//!
//! Several processes may share one profile (two Python sessions, the CLI beside Mach4). A save
//! takes an advisory lock (`.<name>.lock` beside the file, kept), re-reads the file, and writes
//! what is on disk with only what this session changed since it attached the store
//! ([`ProfileStore::save_changes`]): the calibration as one unit (K with its date and units),
//! every other parameter by name. So an older session's M284 job switch never writes back its
//! stale K over a newer M283 of another process; the session takes the other's calibration in
//! memory instead. Where the merge does not hold together (another process's value makes this
//! session's change invalid) the save is refused: "the profile changed on disk …, re-run". A failure at any step removes the temporary file and leaves the
//! previous profile intact. The file system steps go through the small [`ProfileFs`] trait so a
//! test can inject a failure. A save first removes the temporary files that interrupted saves of
//! dead processes left; [`ProfileStore::check_writable`] lets a caller find an unwritable folder
//! before the motion whose result it will save.
//!
//! Bad input refused at load (naming the key): an empty path or one with a NUL byte, a file
//! larger than [`MAX_PROFILE_BYTES`], a path that is not a regular file, unknown keys
//! or tables (a driver's table the store does not know is unknown), values out of range, a K that is singular or of an absurd scale
//! ([`crate::Calibration::check_k`]). Text for a number or yes/no (`"8500"`, `"yes"`) is read
//! as its type, as the host's own profile stores it.

use std::collections::BTreeMap;
use std::fs::{self, File, OpenOptions};
use std::io::{self, Read, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use serde::Serialize;

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

/// Decision: a profile holds `[vision]` and the known drivers' tables and nothing else, and
/// each table only the manual's names; anything more is refused naming it. A save rewrites the
/// whole file, so a key kept only in memory would be silently deleted; a host bridge keeps its
/// own settings in its own file.
#[derive(Serialize)]
struct ProfileFile {
    vision: BTreeMap<String, toml::Value>,
    #[serde(flatten)]
    drivers: BTreeMap<String, BTreeMap<String, toml::Value>>,
}

/// The name of the core's table.
const VISION: &str = "vision";

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
        match OpenOptions::new().write(true).create_new(true).open(&probe) {
            Ok(f) => {
                drop(f);
                let _ = fs::remove_file(&probe);
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

    /// Saves the configuration parameters of `params` atomically (see the module doc), as
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

    /// Takes the profile's advisory lock (`.<name>.lock` beside `target`), held until the
    /// returned file is dropped. A separate file, because the save replaces the profile's own.
    fn lock(&self, target: &Path, dir: &Path) -> Result<File, String> {
        let path = dir.join(format!(".{}.lock", file_name(target)));
        let file = OpenOptions::new().read(true).write(true).create(true).truncate(false).open(&path).map_err(|e| {
            format!(
                "cannot be saved: cannot create a file in {}: {e} — create the folder or make it writable",
                dir.display()
            )
        })?;
        file.lock().map_err(|e| format!("cannot be saved: cannot lock {}: {e}", path.display()))?;
        Ok(file)
    }

    /// The file the path names: the path itself, or the target of its chain of symbolic links
    /// (which may not exist yet). Refuses an empty path, a NUL byte, and a loop of links.
    fn target(&self) -> Result<PathBuf, VisionError> {
        if self.path.as_os_str().is_empty() {
            return Err(self.err("no profile path was given — give the path of a TOML file".into()));
        }
        if self.path.as_os_str().as_encoded_bytes().contains(&0) {
            return Err(self.err("the path holds a NUL byte — give the path of a TOML file".into()));
        }
        let mut path = self.path.clone();
        for _ in 0..MAX_LINKS {
            match fs::symlink_metadata(&path) {
                Ok(m) if m.file_type().is_symlink() => {
                    let to = fs::read_link(&path).map_err(|e| self.err(format!("cannot read the link: {e}")))?;
                    path = dir_of(&path).join(to);
                }
                _ => return Ok(path),
            }
        }
        Err(self.err(format!("more than {MAX_LINKS} symbolic links (a loop?) — give the path of a TOML file")))
    }

    /// Reads and parses `target`, refusing a file larger than [`MAX_PROFILE_BYTES`].
    fn read(&self, target: &Path) -> Result<Params, VisionError> {
        self.require_regular_file(target)?;
        let too_big = |bytes: u64| {
            self.err(format!(
                "is {bytes} bytes; a profile is at most {MAX_PROFILE_BYTES} bytes (a few kB is usual) — give the \
                 path of a mach-vision profile"
            ))
        };
        let file = File::open(target).map_err(|e| self.err(format!("cannot read: {e}")))?;
        let len = file.metadata().map_err(|e| self.err(format!("cannot read: {e}")))?.len();
        if len > MAX_PROFILE_BYTES {
            return Err(too_big(len));
        }
        let mut bytes = Vec::new();
        // Bounded even when the file grows while it is read.
        file.take(MAX_PROFILE_BYTES + 1).read_to_end(&mut bytes).map_err(|e| self.err(format!("cannot read: {e}")))?;
        if bytes.len() as u64 > MAX_PROFILE_BYTES {
            return Err(too_big(bytes.len() as u64));
        }
        let text = String::from_utf8(bytes).map_err(|e| self.err(format!("cannot read: not UTF-8 text ({e})")))?;
        from_toml_with(&text, self.base.clone()).map_err(|e| self.err(e))
    }

    fn temp_prefix(target: &Path) -> String {
        format!(".{}.tmp-", file_name(target))
    }

    /// A fresh temporary name beside `target`: `.<name>.tmp-<pid>-<n>`.
    fn temp_path(&self, target: &Path) -> PathBuf {
        let n = TEMP_COUNTER.fetch_add(1, Ordering::Relaxed);
        dir_of(target).join(format!("{}{}-{n}", ProfileStore::temp_prefix(target), std::process::id()))
    }

    /// Removes the temporary files interrupted saves of dead processes left beside the profile
    /// (best effort). A file whose process is alive, or whose liveness cannot be told (no
    /// `/proc`), is left alone: it may be a save in progress.
    fn remove_stale_temps(&mut self, target: &Path, dir: &Path) {
        let prefix = ProfileStore::temp_prefix(target);
        let Ok(entries) = fs::read_dir(dir) else { return };
        let stale: Vec<PathBuf> = entries
            .flatten()
            .filter(|e| {
                let name = e.file_name();
                let Some(rest) = name.to_str().and_then(|n| n.strip_prefix(&prefix)) else { return false };
                let Some((pid, n)) = rest.split_once('-') else { return false };
                match (pid.parse::<u32>(), n.parse::<u64>()) {
                    (Ok(pid), Ok(_)) => process_is_dead(pid),
                    _ => false,
                }
            })
            .map(|e| e.path())
            .collect();
        for path in stale {
            let _ = self.fs.remove(&path);
        }
    }

    /// Refuses a path that is not a regular file (a FIFO would block the read for ever, a
    /// device would be read or overwritten, a folder cannot be replaced).
    fn require_regular_file(&self, target: &Path) -> Result<(), VisionError> {
        match fs::metadata(target) {
            Ok(m) if !m.is_file() => {
                Err(self.err("is not a regular file (a folder, FIFO or device) — give the path of a TOML file".into()))
            }
            _ => Ok(()),
        }
    }

    fn err(&self, reason: String) -> VisionError {
        VisionError::Profile { path: self.path.display().to_string(), reason }
    }
}

/// The largest profile read, bytes (a real one is a few kB; a bigger file is not a profile).
pub const MAX_PROFILE_BYTES: u64 = 1 << 20;

/// The most symbolic links followed to the profile's file (as Linux's `ELOOP` bound).
const MAX_LINKS: usize = 40;

/// The folder of `path` (`.` for a bare name).
fn dir_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// The file name of `path`, for the names beside it.
fn file_name(path: &Path) -> String {
    path.file_name().map_or_else(|| "profile".into(), |n| n.to_string_lossy().into_owned())
}

/// True when process `pid` is known not to exist (Linux `/proc`); false when it exists or
/// when this cannot be told.
fn process_is_dead(pid: u32) -> bool {
    let proc_root = Path::new("/proc");
    pid != std::process::id() && proc_root.join("self").exists() && !proc_root.join(pid.to_string()).exists()
}

/// A parameter value as TOML.
fn toml_value(v: ParamValue) -> toml::Value {
    match v {
        ParamValue::Bool(b) => toml::Value::Boolean(b),
        ParamValue::Int(i) => toml::Value::Integer(i),
        ParamValue::Float(f) => toml::Value::Float(f),
        ParamValue::Text(s) => toml::Value::String(s),
    }
}

/// The profile text for `params` (configuration parameters only): `[vision]`, then each
/// driver's table.
///
/// # Errors
/// A serialisation failure (not expected for validated parameters).
pub fn to_toml(params: &Params) -> Result<String, String> {
    let named = |values: Vec<(&'static str, ParamValue)>| {
        values.into_iter().map(|(name, v)| (name.to_string(), toml_value(v))).collect::<BTreeMap<_, _>>()
    };
    let vision = named(params.core_values());
    let drivers = params.drivers_settings().map(|d| (d.table().to_string(), named(d.values()))).collect();
    let body = toml::to_string(&ProfileFile { vision, drivers }).map_err(|e| format!("cannot serialise: {e}"))?;
    Ok(format!(
        "# mach-vision: Vision OEM parameters (calibration and configuration).\n\
         # Written atomically by the Vision module; do not edit VisionCal_K11..K22 by hand.\n{body}"
    ))
}

/// Parameters from profile text, starting from the defaults (which know no driver's table).
///
/// # Errors
/// As [`from_toml_with`].
pub fn from_toml(text: &str) -> Result<Params, String> {
    from_toml_with(text, Params::default())
}

/// Parameters from profile text: `base` overridden by every entry of `[vision]` and of the
/// drivers' tables `base` has.
///
/// # Errors
/// A parse error, a missing `[vision]`, an unknown table or key, an unknown or telemetry name,
/// or an invalid value (the message says which).
pub fn from_toml_with(text: &str, base: Params) -> Result<Params, String> {
    if text.trim().is_empty() {
        return Err("cannot parse: the file is empty — a profile holds a [vision] table; remove the file to start \
                    from the defaults"
            .into());
    }
    let mut file: toml::Table =
        toml::from_str(text).map_err(|e| format!("cannot parse: {}", crate::text::toml_error(&e, text)))?;
    let known: Vec<&str> = base.drivers_settings().map(|d| d.table()).collect();
    if let Some(key) = file.keys().find(|k| *k != VISION && !known.contains(&k.as_str())) {
        let tables: String = std::iter::once(VISION).chain(known.iter().copied()).map(|t| format!("[{t}]")).collect();
        return Err(format!(
            "cannot parse: unknown table or key `{key}`: a profile holds {tables} — move it into [vision] or remove it"
        ));
    }
    let mut params = base;
    let tables = |v: toml::Value, name: &str| match v {
        toml::Value::Table(t) => Ok(t),
        other => Err(format!("cannot parse: `{name}` must be a table [{name}], not {}", shown(&other))),
    };
    let vision = tables(file.remove(VISION).ok_or("cannot parse: missing table [vision]")?, VISION)?;
    for (name, value) in vision {
        params.set(&name, param_value(&name, value)?).map_err(|e| match e {
            VisionError::UnknownParam { .. } => unknown_key(&name, &params),
            other => other.to_string(),
        })?;
    }
    for (table, entries) in file {
        let entries = tables(entries, &table)?;
        let Some(settings) = params.driver_settings_mut(&table) else { continue };
        for (name, value) in entries {
            let value = param_value(&name, value)?;
            if !settings.set(&name, &value).map_err(|e| e.to_string())? {
                let names: Vec<&str> = settings.specs().map(|s| s.name).collect();
                let hint = did_you_mean(&name, names.iter().copied()).map(|n| format!(" (did you mean {n}?)"));
                return Err(format!(
                    "[{table}] {name}: unknown setting{} — [{table}] holds {}; the core's parameters go in [vision]",
                    hint.unwrap_or_default(),
                    names.join(", ")
                ));
            }
        }
    }
    params.calibration.check_k().map_err(|e| e.to_string())?;
    Ok(params)
}

/// The message for `name`, a key of `[vision]` that no parameter has: the name a typo or a
/// name cut short most likely meant, from the parameters `params` holds (the core's and every
/// driver's), when one is that close.
fn unknown_key(name: &str, params: &Params) -> String {
    let e = VisionError::UnknownParam { name: name.to_string() };
    let known = Params::specs().chain(params.drivers_settings().flat_map(|d| d.specs())).map(|s| s.name);
    match did_you_mean(name, known) {
        Some(near) => format!("{e} (did you mean {near}?)"),
        None => e.to_string(),
    }
}

/// The one name of `known` that `name` is one edit away from, ignoring case: a letter wrong,
/// missing or extra, two letters swapped, or the name cut short (a prefix of at least
/// [`MIN_PREFIX_CHARS`] characters that only one known name starts with). `None` when no name
/// is that close, or two are equally close (a guess between them would mislead).
fn did_you_mean<'a>(name: &str, known: impl Iterator<Item = &'a str>) -> Option<&'a str> {
    let lower = name.to_ascii_lowercase();
    let mut typo = Vec::new();
    let mut cut = Vec::new();
    for k in known {
        let k_lower = k.to_ascii_lowercase();
        if k_lower == lower {
            continue;
        }
        if edit_distance(&lower, &k_lower) <= 1 {
            typo.push(k);
        } else if lower.chars().count() >= MIN_PREFIX_CHARS && k_lower.starts_with(&lower) {
            cut.push(k);
        }
    }
    typo.dedup();
    cut.dedup();
    match (typo.as_slice(), cut.as_slice()) {
        ([one], _) | ([], [one]) => Some(*one),
        _ => None,
    }
}

/// The shortest prefix [`did_you_mean`] takes for a name cut short: longer than the shared
/// `Vision` and a word, so `VisionCamera` alone suggests nothing.
const MIN_PREFIX_CHARS: usize = 14;

/// The optimal-string-alignment distance between `a` and `b`: the fewest single-character
/// insertions, deletions, substitutions and swaps of two neighbours that turn one into the other.
fn edit_distance(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.chars().collect();
    let b: Vec<char> = b.chars().collect();
    // Rows i-2, i-1 and i of the table; d[j] = distance between a[..i] and b[..j].
    let mut before: Vec<usize> = vec![0; b.len() + 1];
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for i in 1..=a.len() {
        let mut row = vec![i; b.len() + 1];
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            row[j] = (prev[j] + 1).min(row[j - 1] + 1).min(prev[j - 1] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                row[j] = row[j].min(before[j - 2] + 1);
            }
        }
        before = std::mem::replace(&mut prev, row);
    }
    prev[b.len()]
}

/// A TOML value as a parameter value.
fn param_value(name: &str, value: toml::Value) -> Result<ParamValue, String> {
    Ok(match value {
        toml::Value::Boolean(b) => ParamValue::Bool(b),
        toml::Value::Integer(i) => ParamValue::Int(i),
        toml::Value::Float(f) => ParamValue::Float(f),
        toml::Value::String(s) => ParamValue::Text(s),
        // Read as its text, as a number written as text is read as its type.
        toml::Value::Datetime(d) => ParamValue::Text(d.to_string()),
        other => return Err(format!("{name}: unsupported value {}", shown(&other))),
    })
}

/// A TOML value for a message: a date-time as written (toml's `Display` shows its private
/// table), anything else as TOML.
fn shown(value: &toml::Value) -> String {
    match value {
        toml::Value::Datetime(d) => d.to_string(),
        other => other.to_string(),
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)]
mod tests {
    use super::*;
    use crate::params::tests::PROBE;
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

    #[test]
    fn bad_profiles_are_refused_with_the_reason() {
        assert!(from_toml("[vision]\nVisionCameraResX = 0\n").expect_err("range").contains("VisionCameraResX"));
        assert!(from_toml("[vision]\nVisionLastStatus = \"x\"\n").expect_err("ro").contains("read-only"));
        assert!(from_toml("[vision]\nVisionBogus = 1\n").expect_err("unknown").contains("unknown parameter"));
        assert!(from_toml("not toml [").expect_err("parse").starts_with("cannot parse"));
        assert!(from_toml("[vision]\nVisionDriver = [1]\n").expect_err("array").contains("unsupported"));
        assert!(from_toml("vision = 1\n").expect_err("not a table").contains("[vision]"));
        assert!(from_toml("# nothing\n").expect_err("no [vision]").contains("missing table [vision]"));
        assert!(from_toml(" \n").expect_err("empty").contains("the file is empty — a profile holds a [vision] table"));
        let e = from_toml("[vision]\nVisionCameraResX = 16x\n").expect_err("syntax");
        assert!(e.starts_with("cannot parse: line 2, column ") && e.contains("(`VisionCameraResX = 16x`)"), "{e}");
        assert!(!e.contains('\n'), "{e}");
        // A date-time is read as its text (a calibration date written unquoted), and shown as
        // written, never as toml's private table.
        let p = from_toml("[vision]\nVisionCal_Date = 2024-01-02T03:04:05Z\n").expect("a date");
        assert_eq!(p.cal_date(), "2024-01-02T03:04:05Z");
        let e = from_toml("vision = 2024-01-02\n").expect_err("not a table");
        assert!(e.ends_with("not 2024-01-02"), "{e}");
        let e = from_toml("[vision]\nVisionCameraResX = 2024-01-02\n").expect_err("not a number");
        assert!(e.contains("VisionCameraResX") && !e.contains("$__toml"), "{e}");
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
            assert_eq!(count, 2, "the temporary file was removed (the profile and its lock file stay)");
        }
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn edit_distance_counts_single_edits_and_swaps() {
        assert_eq!(edit_distance("", ""), 0);
        assert_eq!(edit_distance("abc", ""), 3);
        assert_eq!(edit_distance("", "ab"), 2);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert_eq!(edit_distance("visionport", "visonport"), 1, "a letter missing");
        assert_eq!(edit_distance("visionport", "visionportt"), 1, "a letter extra");
        assert_eq!(edit_distance("visionport", "visionpart"), 1, "a letter wrong");
        assert_eq!(edit_distance("visionport", "visionprot"), 1, "two letters swapped");
        assert_eq!(edit_distance("visionport", "ivsionport"), 1, "the first two letters swapped");
        assert_eq!(edit_distance("ab", "ba"), 1);
        assert_eq!(edit_distance("visionport", "visionip"), 4);
    }

    #[test]
    fn a_key_one_edit_away_gets_did_you_mean() {
        let e = from_toml("[vision]\nVisionCameraTool = 98\n").expect_err("cut short");
        assert!(
            e.contains("unknown parameter \"VisionCameraTool\"") && e.contains("did you mean VisionCameraToolNumber?"),
            "{e}"
        );
        let e = from_toml("[vision]\nVisionEnabeld = true\n").expect_err("swapped");
        assert!(e.contains("did you mean VisionEnabled?"), "{e}");
        let p = from_toml("[vision]\nvisionenabled = true\n").expect("any case is the name itself");
        assert_eq!(p.get("VisionEnabled"), Ok(ParamValue::Bool(true)));
        let e = from_toml("[vision]\nVisionBogus = 1\n").expect_err("far from all");
        assert!(!e.contains("did you mean"), "{e}");
        // `VisionCal_K1` is one edit from K11 and K12 alike: no guess.
        let e = from_toml("[vision]\nVisionCal_K1 = 1\n").expect_err("ambiguous");
        assert!(!e.contains("did you mean"), "{e}");
        let e =
            from_toml_with("[vision]\n[probe]\nVisionProbeLevl = 3\n", Params::default().with_driver_settings(&PROBE))
                .expect_err("a driver's table");
        assert!(e.contains("did you mean VisionProbeLevel?"), "{e}");
    }

    #[test]
    fn unknown_keys_and_tables_are_refused_naming_them() {
        let e = from_toml("[vision]\nVisionEnabled = true\n[mach4]\nPlugin = 1\n").expect_err("table");
        assert!(e.contains("mach4"), "{e}");
        let e = from_toml("VisionEnabled = true\n").expect_err("top-level key");
        assert!(e.contains("VisionEnabled"), "{e}");
    }

    #[test]
    fn k_is_checked_as_a_whole_at_load_naming_it() {
        let k = |k11: f64, k12: f64, k21: f64, k22: f64| {
            format!("[vision]\nVisionCal_K11 = {k11:e}\nVisionCal_K12 = {k12:e}\nVisionCal_K21 = {k21:e}\nVisionCal_K22 = {k22:e}\n")
        };
        assert!(from_toml(&k(0.0, 0.0, 0.0, 0.0)).is_ok(), "all zero = not calibrated");
        assert!(from_toml(&k(0.00203, 1e-5, -1e-5, 0.00204)).is_ok());
        for (bad, why) in [
            (k(1e300, 0.0, 0.0, 1e300), "in per pixel"),
            (k(1e-12, 0.0, 0.0, 1e-12), "in per pixel"),
            (k(0.002, 0.002, 0.002, 0.002), "singular"),
            (k(0.002, 0.0, 0.0, 0.0), "singular"),
            (k(1e300, 1e300, -1e300, 1e300), "in per pixel"),
        ] {
            let e = from_toml(&bad).expect_err(&bad);
            assert!(e.contains("VisionCal_K11..K22") && e.contains(why), "{bad}: {e}");
        }
        // 1 mm per pixel is fine in mm, absurd (25 in) as inches.
        let mm = format!("{}VisionCal_Units = \"mm\"\n", k(1.0, 0.0, 0.0, 1.0));
        assert!(from_toml(&mm).is_ok(), "1 mm per pixel");
        assert!(from_toml(&k(1.0, 0.0, 0.0, 1.0)).is_err(), "1 in per pixel");
    }

    #[test]
    fn a_pound_block_past_9999_is_refused_at_load() {
        let e = from_toml("[vision]\nVisionPoundVarBase = 9990\n").expect_err("past #9999");
        assert!(e.contains("VisionPoundVarBase") && e.contains("#9990..#10029"), "{e}");
        assert!(from_toml("[vision]\nVisionPoundVarBase = 9960\n").is_ok(), "#9960..#9999");
    }

    /// Decision: text values are read like the host's own profile (Mach4 stores every value
    /// as text), and the next save writes them typed.
    #[test]
    fn text_values_are_read_as_their_type() {
        let p = from_toml("[vision]\nVisionCameraResX = \"1601\"\nVisionEnabled = \"yes\"\n").expect("text");
        assert_eq!(p.camera_res_x(), 1601);
        assert!(p.enabled());
        assert!(to_toml(&p).expect("save").contains("VisionCameraResX = 1601\n"));
        let e = from_toml("[vision]\nVisionCameraResX = \"85x\"\n").expect_err("not a number");
        assert!(e.contains("VisionCameraResX"), "{e}");
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
