//! The profile on the file system: the atomic save's steps, the lock, the temporary files, and
//! the path checks.

use std::fs::{self, File, OpenOptions};
use std::io::{self, Read, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use super::{from_toml_with, ProfileStore};
use crate::error::VisionError;
use crate::params::Params;

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

static TEMP_COUNTER: AtomicU64 = AtomicU64::new(0);

impl ProfileStore {
    /// Takes the profile's advisory lock (`.<name>.lock` beside `target`), held until the
    /// returned file is dropped. A separate file, because the save replaces the profile's own.
    pub(super) fn lock(&self, target: &Path, dir: &Path) -> Result<File, String> {
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
    pub(super) fn target(&self) -> Result<PathBuf, VisionError> {
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
    pub(super) fn read(&self, target: &Path) -> Result<Params, VisionError> {
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

    pub(super) fn temp_prefix(target: &Path) -> String {
        format!(".{}.tmp-", file_name(target))
    }

    /// A fresh temporary name beside `target`: `.<name>.tmp-<pid>-<n>`.
    pub(super) fn temp_path(&self, target: &Path) -> PathBuf {
        let n = TEMP_COUNTER.fetch_add(1, Ordering::Relaxed);
        dir_of(target).join(format!("{}{}-{n}", ProfileStore::temp_prefix(target), std::process::id()))
    }

    /// Removes the temporary files interrupted saves of dead processes left beside the profile
    /// (best effort). A file whose process is alive, or whose liveness cannot be told (no
    /// `/proc`), is left alone: it may be a save in progress.
    pub(super) fn remove_stale_temps(&mut self, target: &Path, dir: &Path) {
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
    pub(super) fn require_regular_file(&self, target: &Path) -> Result<(), VisionError> {
        match fs::metadata(target) {
            Ok(m) if !m.is_file() => {
                Err(self.err("is not a regular file (a folder, FIFO or device) — give the path of a TOML file".into()))
            }
            _ => Ok(()),
        }
    }
}

/// The largest profile read, bytes (a real one is a few kB; a bigger file is not a profile).
pub const MAX_PROFILE_BYTES: u64 = 1 << 20;

/// The most symbolic links followed to the profile's file (as Linux's `ELOOP` bound).
const MAX_LINKS: usize = 40;

/// The folder of `path` (`.` for a bare name).
pub(super) fn dir_of(path: &Path) -> PathBuf {
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
