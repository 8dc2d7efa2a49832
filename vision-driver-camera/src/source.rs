//! Frame sources: where the driver's frames come from, behind one small trait, so the driver
//! (and its tests, and the simulator) need not know whether a frame came from a USB camera, a
//! snapshot URL, a file, or a renderer.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::time::Duration;

use crate::error::CameraError;
use crate::file::{open_regular, OpenError};
use crate::frame::{decode_image, Frame};
use crate::http::{self, HttpUrl, MAX_BODY_BYTES};

/// Something that delivers grey frames.
pub trait FrameSource: Send {
    /// One frame. A live source gives one taken no earlier than the call it answers, as far as
    /// it can tell; the driver flushes the frames a source may have queued before that
    /// ([`FrameSource::is_live`]).
    ///
    /// # Errors
    /// The source's [`CameraError`].
    fn frame(&mut self) -> Result<Frame, CameraError>;

    /// What the source is, for `test_connection` and messages (`/dev/video0 YUYV 1280×960`).
    fn describe(&self) -> String;

    /// True for a camera that may hand out frames taken before the last move (a device queue,
    /// a snapshot server's buffer): the driver then throws `VisionCameraFlushFrames` frames
    /// away first. False for replayed files, where every frame counts.
    fn is_live(&self) -> bool {
        true
    }

    /// True when the source has camera jobs to switch (M284); a plain camera has none.
    fn has_jobs(&self) -> bool {
        false
    }

    /// Switches to camera job `job` (1–999).
    ///
    /// # Errors
    /// [`CameraError::Unsupported`] for a source without jobs (the default), or
    /// [`CameraError::Job`] when the source has no such job.
    fn select_job(&mut self, job: u32) -> Result<(), CameraError> {
        let _ = job;
        Err(CameraError::Unsupported { what: "switch camera jobs: it has none" })
    }
}

/// Image files: one file, read again at every trigger, or a folder whose images (`.jpg`,
/// `.jpeg`, `.png`, `.pgm`, `.pnm`, any case) are taken one per trigger in name order.
#[derive(Debug, Clone)]
pub struct FileSource {
    path: PathBuf,
    /// The folder's images, listed at the first frame; `None` for a single file or before.
    replay: Option<Vec<PathBuf>>,
    next: usize,
}

impl FileSource {
    /// A source reading `path` (a file or a folder; looked at on the first frame).
    #[must_use]
    pub fn new(path: impl Into<PathBuf>) -> FileSource {
        FileSource { path: path.into(), replay: None, next: 0 }
    }

    /// How many frames have been taken.
    #[must_use]
    pub fn taken(&self) -> usize {
        self.next
    }
}

fn is_image(p: &Path) -> bool {
    p.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| ["jpg", "jpeg", "png", "pgm", "pnm"].iter().any(|x| x.eq_ignore_ascii_case(e)))
}

/// Reads `path`, a regular file of at most [`MAX_BODY_BYTES`]: a FIFO or a device is refused
/// unread and without blocking ([`crate::file::open_regular`]), and the read stops at the bound
/// even if the file grows meanwhile.
fn read_file(path: &Path) -> Result<Vec<u8>, CameraError> {
    let shown = || path.display().to_string();
    let file_err = |e: std::io::Error| CameraError::File { path: shown(), reason: e.to_string() };
    let file = open_regular(path).map_err(|e| match e {
        OpenError::NotRegular { kind } => CameraError::NotAFile { path: shown(), kind },
        OpenError::Io(e) => file_err(e),
    })?;
    let too_large = || CameraError::TooLarge { from: shown(), limit: MAX_BODY_BYTES, what: "bytes" };
    if file.metadata().map_err(file_err)?.len() > MAX_BODY_BYTES as u64 {
        return Err(too_large());
    }
    let mut bytes = Vec::new();
    file.take(MAX_BODY_BYTES as u64 + 1).read_to_end(&mut bytes).map_err(file_err)?;
    if bytes.len() > MAX_BODY_BYTES {
        return Err(too_large());
    }
    Ok(bytes)
}

impl FrameSource for FileSource {
    fn frame(&mut self) -> Result<Frame, CameraError> {
        let dir = self.path.display().to_string();
        let meta = std::fs::metadata(&self.path)
            .map_err(|e| CameraError::File { path: dir.clone(), reason: e.to_string() })?;
        if !meta.is_dir() {
            self.next += 1;
            return decode_image(&read_file(&self.path)?, &dir);
        }
        if self.replay.is_none() {
            let entries = std::fs::read_dir(&self.path)
                .map_err(|e| CameraError::File { path: dir.clone(), reason: e.to_string() })?;
            let mut files: Vec<PathBuf> =
                entries.filter_map(Result::ok).map(|e| e.path()).filter(|p| p.is_file() && is_image(p)).collect();
            files.sort();
            self.replay = Some(files);
        }
        let files = self.replay.as_deref().unwrap_or_default();
        if files.is_empty() {
            return Err(CameraError::EmptyFolder { dir });
        }
        let Some(path) = files.get(self.next) else {
            return Err(CameraError::ReplayEnded { dir, count: files.len() });
        };
        let path = path.clone();
        self.next += 1;
        decode_image(&read_file(&path)?, &path.display().to_string())
    }

    fn describe(&self) -> String {
        match &self.replay {
            Some(files) => format!("replay of {} ({} images)", self.path.display(), files.len()),
            None => format!("image file(s) at {}", self.path.display()),
        }
    }

    fn is_live(&self) -> bool {
        false
    }
}

/// An HTTP snapshot URL: every frame is one GET.
#[derive(Debug, Clone)]
pub struct HttpSource {
    url: HttpUrl,
    timeout: Duration,
}

impl HttpSource {
    /// A source fetching `url`, each frame within `timeout`.
    #[must_use]
    pub fn new(url: HttpUrl, timeout: Duration) -> HttpSource {
        HttpSource { url, timeout }
    }
}

impl FrameSource for HttpSource {
    fn frame(&mut self) -> Result<Frame, CameraError> {
        let body = http::get(&self.url, self.timeout)?;
        decode_image(&body, &self.url.to_string())
    }

    fn describe(&self) -> String {
        format!("HTTP snapshots from {}", self.url)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn png(value: u8) -> Vec<u8> {
        let img = image::GrayImage::from_pixel(3, 2, image::Luma([value]));
        let mut out = std::io::Cursor::new(Vec::new());
        image::DynamicImage::ImageLuma8(img).write_to(&mut out, image::ImageFormat::Png).expect("png");
        out.into_inner()
    }

    fn temp_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("vision-camera-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("temp dir");
        dir
    }

    #[test]
    fn a_folder_replays_in_name_order_then_says_it_is_used_up() {
        let dir = temp_dir("replay");
        std::fs::write(dir.join("b.PNG"), png(2)).expect("write");
        std::fs::write(dir.join("a.png"), png(1)).expect("write");
        std::fs::write(dir.join("notes.txt"), "not a frame").expect("write");
        let mut source = FileSource::new(&dir);
        assert!(!source.is_live());
        assert_eq!(source.frame().expect("a").pixels()[0], 1);
        assert_eq!(source.frame().expect("b").pixels()[0], 2);
        assert!(source.describe().contains("2 images"), "{}", source.describe());
        let e = source.frame().expect_err("used up");
        assert_eq!(e, CameraError::ReplayEnded { dir: dir.display().to_string(), count: 2 });
        std::fs::remove_dir_all(&dir).expect("clean up");
    }

    #[test]
    fn one_file_is_read_at_every_trigger_and_missing_paths_are_named() {
        let dir = temp_dir("single");
        let file = dir.join("frame.png");
        std::fs::write(&file, png(7)).expect("write");
        let mut source = FileSource::new(&file);
        for _ in 0..2 {
            assert_eq!(source.frame().expect("frame").pixels()[0], 7);
        }
        let empty = dir.join("empty");
        std::fs::create_dir(&empty).expect("dir");
        assert!(matches!(FileSource::new(&empty).frame(), Err(CameraError::EmptyFolder { .. })));
        let e = FileSource::new(dir.join("nope.png")).frame().expect_err("missing");
        assert!(matches!(&e, CameraError::File { path, .. } if path.ends_with("nope.png")), "{e}");
        std::fs::remove_dir_all(&dir).expect("clean up");
    }
}
