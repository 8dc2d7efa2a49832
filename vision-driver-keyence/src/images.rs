//! M281 D1 on a Keyence camera: keep the image the camera pushed for a trigger (SPEC §5
//! "Images", §7).
//!
//! A VS camera FTP-pushes every inspection image into a folder of the PC, `VisionImageWatchDir`
//! ([`ImageWatch`]). After a trigger, [`grab`] waits up to `VisionImageGrabTimeout` for a regular
//! file in that folder whose modification time is not older than the trigger, and copies it into
//! the images folder the core names under a timestamped name (`vision_YYYYMMDD_HHMMSS_mmm.ext`,
//! then `_2`, `_3`, … if taken).
//!
//! Safety rules: only regular files directly inside the watch folder are considered (symbolic
//! links and sub-folders are skipped, so a name can never lead outside the folder); the
//! destination name is built from the timestamp and a sanitised extension only, and is created
//! with `create_new`, so an existing file is never overwritten.

use std::fs::{self, File, OpenOptions};
use std::io;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant, SystemTime};

use vision_core::ImageRequest;

use crate::config::ImageWatch;
use crate::error::KeyenceError;

/// How often the watch folder is polled.
const POLL: Duration = Duration::from_millis(20);
/// Give up on name collisions after this many suffixes.
const MAX_SUFFIX: u32 = 1000;

/// Waits up to `watch.timeout` for an image in `watch.dir` modified at or after
/// `request.since`, copies the newest such image into `request.dir` under
/// `vision_{request.stamp}.ext`, and returns the new path.
///
/// # Errors
/// [`KeyenceError::NoImageFolder`] when `watch.dir` is empty, [`KeyenceError::NoImage`] when no
/// image came in time, [`KeyenceError::Image`] for an unreadable folder or a failed copy. M281
/// reports each as a warning, never as a failed capture.
pub(crate) fn grab(watch: &ImageWatch, request: &ImageRequest<'_>) -> Result<PathBuf, KeyenceError> {
    if watch.dir.as_os_str().is_empty() {
        return Err(KeyenceError::NoImageFolder);
    }
    let start = Instant::now();
    loop {
        if let Some(src) = newest_since(&watch.dir, request.since).map_err(|reason| KeyenceError::Image { reason })? {
            return copy_new(&src, request.dir, request.stamp).map_err(|reason| KeyenceError::Image { reason });
        }
        let elapsed = start.elapsed();
        if elapsed >= watch.timeout {
            return Err(KeyenceError::NoImage { dir: watch.dir.display().to_string(), timeout: watch.timeout });
        }
        std::thread::sleep(POLL.min(watch.timeout - elapsed));
    }
}

/// The most recently modified regular file directly in `dir` with mtime ≥ `since`.
fn newest_since(dir: &Path, since: SystemTime) -> Result<Option<PathBuf>, String> {
    let entries = fs::read_dir(dir).map_err(|e| format!("cannot read image folder {}: {e}", dir.display()))?;
    let mut best: Option<(SystemTime, PathBuf)> = None;
    for entry in entries.flatten() {
        // symlink_metadata: a link is reported as a link, never followed.
        let Ok(meta) = fs::symlink_metadata(entry.path()) else { continue };
        if !meta.file_type().is_file() {
            continue;
        }
        let Ok(modified) = meta.modified() else { continue };
        if modified < since {
            continue;
        }
        if best.as_ref().is_none_or(|(t, _)| modified > *t) {
            best = Some((modified, entry.path()));
        }
    }
    Ok(best.map(|(_, p)| p))
}

/// `.ext` made of at most 8 ASCII alphanumerics from `src`, or empty.
fn extension(src: &Path) -> String {
    match src.extension().and_then(|e| e.to_str()) {
        Some(e) if !e.is_empty() && e.len() <= 8 && e.chars().all(|c| c.is_ascii_alphanumeric()) => {
            format!(".{}", e.to_ascii_lowercase())
        }
        _ => String::new(),
    }
}

/// Copies `src` into `dir` under a fresh name; never overwrites.
fn copy_new(src: &Path, dir: &Path, stamp: &str) -> Result<PathBuf, String> {
    let stamp: String = stamp.chars().filter(|c| c.is_ascii_alphanumeric() || *c == '_' || *c == '-').collect();
    let ext = extension(src);
    fs::create_dir_all(dir).map_err(|e| format!("cannot create image folder {}: {e}", dir.display()))?;
    let mut input = File::open(src).map_err(|e| format!("cannot open image {}: {e}", src.display()))?;
    for n in 1..=MAX_SUFFIX {
        let name = if n == 1 { format!("vision_{stamp}{ext}") } else { format!("vision_{stamp}_{n}{ext}") };
        let dest = dir.join(name);
        match OpenOptions::new().write(true).create_new(true).open(&dest) {
            Ok(mut out) => {
                return match io::copy(&mut input, &mut out).and_then(|_| out.sync_all()) {
                    Ok(()) => Ok(dest),
                    Err(e) => {
                        drop(out);
                        let _ = fs::remove_file(&dest);
                        Err(format!("cannot copy image to {}: {e}", dest.display()))
                    }
                };
            }
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => {}
            Err(e) => return Err(format!("cannot create {}: {e}", dest.display())),
        }
    }
    Err(format!("too many images named vision_{stamp}* in {}", dir.display()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::UNIX_EPOCH;

    fn tmp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("vision-keyence-grab-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).expect("tmp");
        d
    }

    /// `grab` from `watch` (waiting `timeout`) into `images`, for a trigger at `since`.
    fn grab_into(
        watch: &Path,
        images: &Path,
        since: SystemTime,
        timeout: Duration,
        stamp: &str,
    ) -> Result<PathBuf, KeyenceError> {
        grab(&ImageWatch { dir: watch.to_path_buf(), timeout }, &ImageRequest { dir: images, since, stamp })
    }

    fn write_at(path: &Path, bytes: &[u8], t: SystemTime) {
        fs::write(path, bytes).expect("write");
        File::options().write(true).open(path).and_then(|f| f.set_modified(t)).expect("mtime");
    }

    #[test]
    fn copies_the_newest_fresh_image_and_never_overwrites() {
        let root = tmp("copy");
        let watch = root.join("watch");
        let images = root.join("images");
        fs::create_dir_all(&watch).expect("watch");
        let trigger = UNIX_EPOCH + Duration::from_secs(1_700_000_000);
        write_at(&watch.join("old.bmp"), b"old", trigger - Duration::from_secs(5));
        write_at(&watch.join("new.BMP"), b"new", trigger + Duration::from_secs(1));
        let a = grab_into(&watch, &images, trigger, Duration::from_millis(0), "20231114_221320_000").expect("grab");
        assert_eq!(a, images.join("vision_20231114_221320_000.bmp"));
        assert_eq!(fs::read(&a).expect("read"), b"new");
        let b = grab_into(&watch, &images, trigger, Duration::from_millis(0), "20231114_221320_000").expect("grab");
        assert_eq!(b, images.join("vision_20231114_221320_000_2.bmp"));
        assert_eq!(fs::read(&a).expect("read"), b"new");
        let _ = fs::remove_dir_all(&root);
    }

    #[test]
    fn times_out_without_a_fresh_image_and_skips_links_and_folders() {
        let root = tmp("timeout");
        let watch = root.join("watch");
        fs::create_dir_all(watch.join("sub")).expect("watch");
        let trigger = SystemTime::now() + Duration::from_secs(3600);
        write_at(&watch.join("stale.png"), b"x", trigger - Duration::from_secs(1));
        #[cfg(unix)]
        {
            let outside = root.join("secret.png");
            write_at(&outside, b"secret", trigger + Duration::from_secs(1));
            std::os::unix::fs::symlink(&outside, watch.join("link.png")).expect("symlink");
        }
        let t0 = Instant::now();
        let e = grab_into(&watch, &root.join("images"), trigger, Duration::from_millis(60), "s").expect_err("none");
        assert!(matches!(e, KeyenceError::NoImage { .. }), "{e:?}");
        assert!(e.to_string().starts_with("no image newer than the trigger"), "{e}");
        assert!(e.to_string().contains("VisionImageWatchDir"), "{e}");
        assert!(t0.elapsed() >= Duration::from_millis(60));
        assert!(!root.join("images").exists() || fs::read_dir(root.join("images")).expect("dir").next().is_none());
        let e =
            grab_into(&root.join("missing"), &root.join("images"), trigger, Duration::ZERO, "s").expect_err("no dir");
        assert!(e.to_string().starts_with("cannot read image folder"), "{e}");
        let e = grab_into(Path::new(""), &root.join("images"), trigger, Duration::ZERO, "s").expect_err("empty");
        assert_eq!(e, KeyenceError::NoImageFolder);
        assert!(e.to_string().starts_with("VisionImageWatchDir is empty"), "{e}");
        let _ = fs::remove_dir_all(&root);
    }

    #[test]
    fn extensions_are_sanitised() {
        assert_eq!(extension(Path::new("a.JPG")), ".jpg");
        assert_eq!(extension(Path::new("a")), "");
        assert_eq!(extension(Path::new("a.t/x")), "");
        assert_eq!(extension(Path::new("a.verylongextension")), "");
    }
}
