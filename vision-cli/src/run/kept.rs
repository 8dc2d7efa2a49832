//! The simulated machine's kept state beside the profile: `run --profile P.toml` keeps the tool
//! table and stored offsets in `P.machine.toml`, as a controller keeps them between sessions
//! ([`vision_driver_sim::KeptState`]), so a calibration's camera offset is still in the table
//! in the next `run`.

use std::io::Read;
use std::path::{Path, PathBuf};

use vision_driver_sim::{KeptState, SimMachine, MAX_KEPT_BYTES};

use crate::Failure;

/// The kept state's file beside `profile`: `P.toml` → `P.machine.toml`.
pub(crate) fn kept_path(profile: &Path) -> PathBuf {
    let stem = profile.file_stem().map_or_else(|| "profile".into(), |s| s.to_string_lossy().into_owned());
    profile.with_file_name(format!("{stem}.machine.toml"))
}

/// Puts the state kept beside `profile` back on `machine`; nothing when there is none.
///
/// # Errors
/// [`Failure::Input`] naming the file for one that cannot be read or is not a kept state.
pub(crate) fn restore(profile: &Path, machine: &mut SimMachine) -> Result<(), Failure> {
    let path = kept_path(profile);
    let bad = |reason: String| Failure::Input(format!("{}: {reason} — fix or delete the file", path.display()));
    let file = match std::fs::File::open(&path) {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(bad(e.to_string())),
    };
    if !file.metadata().map_err(|e| bad(e.to_string()))?.is_file() {
        return Err(bad("not a regular file".into()));
    }
    let mut text = String::new();
    let limit = u64::try_from(MAX_KEPT_BYTES + 1).unwrap_or(u64::MAX);
    file.take(limit).read_to_string(&mut text).map_err(|e| bad(e.to_string()))?;
    let kept = KeptState::from_toml(&text).map_err(|e| bad(e.to_string()))?;
    machine.restore(&kept).map_err(|e| bad(e.to_string()))
}

/// Writes `machine`'s kept state beside `profile`: a temporary file in the same folder, renamed
/// over the old one, so an interrupted write leaves the previous state whole.
///
/// # Errors
/// [`Failure::Input`] naming the file when it cannot be written.
pub(crate) fn save(profile: &Path, machine: &SimMachine) -> Result<(), Failure> {
    let path = kept_path(profile);
    let bad =
        |reason: String| Failure::Input(format!("cannot keep the machine's state in {}: {reason}", path.display()));
    let text = machine.kept_state().to_toml().map_err(|e| bad(e.to_string()))?;
    let tmp = path.with_file_name(format!(
        ".{}.tmp{}",
        path.file_name().map_or_else(String::new, |n| n.to_string_lossy().into_owned()),
        std::process::id()
    ));
    let written = std::fs::write(&tmp, text).and_then(|()| std::fs::rename(&tmp, &path));
    if let Err(e) = written {
        let _ = std::fs::remove_file(&tmp);
        return Err(bad(e.to_string()));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_kept_file_sits_beside_the_profile() {
        assert_eq!(kept_path(Path::new("/a/P.toml")), PathBuf::from("/a/P.machine.toml"));
        assert_eq!(kept_path(Path::new("shop")), PathBuf::from("shop.machine.toml"));
    }
}
