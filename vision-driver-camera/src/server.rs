//! A snapshot server (cargo feature `server`): what mjpg-streamer's `/?action=snapshot` or
//! ustreamer's `/snapshot` serves — one image per GET — from frames a closure makes, on a
//! loopback port. For tests, benchmarks and `mach-vision run --camera camera`, which serve the
//! simulated camera's rendered frames through it so a run goes through HTTP end to end.
//! [`request`] reads a request head within bounds, for it and for the operator panel
//! (`vision-panel`), which also serves its frames with [`encode`].
//!
//! ```
//! use vision_driver_camera::server::{Encoding, SnapshotServer};
//! use vision_driver_camera::{http, Frame};
//!
//! let server = SnapshotServer::bind("127.0.0.1:0", Encoding::Png, || {
//!     Frame::new(4, 2, vec![9; 8]).ok_or_else(|| "no frame".to_string())
//! })?;
//! let url = http::HttpUrl::parse(&server.url("/snapshot"))?;
//! let png = http::get(&url, std::time::Duration::from_secs(2))?;
//! assert_eq!(vision_driver_camera::decode_image(&png, "t")?.pixels(), [9; 8]);
//! assert_eq!(server.served(), 1);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod request;

use std::io::{self, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crate::frame::Frame;
use request::{read_request, MAX_HEAD_BYTES};

/// How the server encodes frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Encoding {
    /// Lossless PNG.
    Png,
    /// JPEG at this quality (1–100), as MJPEG cameras send.
    Jpeg(u8),
}

/// A running server; dropping it stops it and joins its thread.
#[derive(Debug)]
pub struct SnapshotServer {
    addr: SocketAddr,
    stop: Arc<AtomicBool>,
    served: Arc<AtomicU64>,
    thread: Option<JoinHandle<()>>,
}

impl SnapshotServer {
    /// Serves `frame()` on `addr` (e.g. `127.0.0.1:0` for an ephemeral loopback port): every
    /// GET, whatever its path, gets a fresh frame; a frame error is a `503` with the text.
    ///
    /// # Errors
    /// The bind error.
    pub fn bind<F>(addr: &str, encoding: Encoding, frame: F) -> io::Result<SnapshotServer>
    where
        F: FnMut() -> Result<Frame, String> + Send + 'static,
    {
        let listener = TcpListener::bind(addr)?;
        // Non-blocking accept, polled, so the thread notices the stop flag.
        listener.set_nonblocking(true)?;
        let addr = listener.local_addr()?;
        let stop = Arc::new(AtomicBool::new(false));
        let served = Arc::new(AtomicU64::new(0));
        let (stop2, served2) = (stop.clone(), served.clone());
        let thread = std::thread::Builder::new()
            .name("snapshot-server".into())
            .spawn(move || serve(&listener, encoding, frame, &stop2, &served2))?;
        Ok(SnapshotServer { addr, stop, served, thread: Some(thread) })
    }

    /// The address it listens on.
    #[must_use]
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// `http://<addr><path>`.
    #[must_use]
    pub fn url(&self, path: &str) -> String {
        format!("http://{}{path}", self.addr)
    }

    /// How many frames it has served.
    #[must_use]
    pub fn served(&self) -> u64 {
        self.served.load(Ordering::SeqCst)
    }
}

impl Drop for SnapshotServer {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn serve<F>(listener: &TcpListener, encoding: Encoding, mut frame: F, stop: &AtomicBool, served: &AtomicU64)
where
    F: FnMut() -> Result<Frame, String>,
{
    while !stop.load(Ordering::SeqCst) {
        match listener.accept() {
            Ok((stream, _)) => {
                // One request per connection; a broken client only costs its own answer.
                let _ = answer(stream, encoding, &mut frame, served);
            }
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => std::thread::sleep(Duration::from_millis(2)),
            Err(_) => std::thread::sleep(Duration::from_millis(20)),
        }
    }
}

/// Answers one connection; counts the frame in `served` before sending it (so a client that
/// has its frame sees it counted).
fn answer<F>(mut stream: TcpStream, encoding: Encoding, frame: &mut F, served: &AtomicU64) -> io::Result<()>
where
    F: FnMut() -> Result<Frame, String>,
{
    stream.set_nonblocking(false)?;
    stream.set_write_timeout(Some(Duration::from_secs(5)))?;
    // A head that does not come whole within the bounds is answered with nothing.
    let Ok(request) = read_request(&mut stream, MAX_HEAD_BYTES, Instant::now() + Duration::from_secs(5)) else {
        return Ok(());
    };
    if request.method != "GET" {
        stream.write_all(b"HTTP/1.1 405 Method Not Allowed\r\nContent-Length: 0\r\nConnection: close\r\n\r\n")?;
        return Ok(());
    }
    let encoded = frame().and_then(|f| encode(&f, encoding));
    match encoded {
        Ok((body, kind)) => {
            let head = format!(
                "HTTP/1.1 200 OK\r\nContent-Type: {kind}\r\nContent-Length: {}\r\nConnection: close\r\n\r\n",
                body.len()
            );
            served.fetch_add(1, Ordering::SeqCst);
            stream.write_all(head.as_bytes())?;
            stream.write_all(&body)
        }
        Err(text) => {
            let head = format!(
                "HTTP/1.1 503 Service Unavailable\r\nContent-Type: text/plain\r\nContent-Length: {}\r\nConnection: close\r\n\r\n",
                text.len()
            );
            stream.write_all(head.as_bytes())?;
            stream.write_all(text.as_bytes())
        }
    }
}

/// `frame` encoded, with its content type (`image/png`, `image/jpeg`).
///
/// # Errors
/// The encoder's message.
pub fn encode(frame: &Frame, encoding: Encoding) -> Result<(Vec<u8>, &'static str), String> {
    let mut out = io::Cursor::new(Vec::new());
    match encoding {
        Encoding::Png => {
            // Fast deflate: the server is on loopback, where bytes are cheap and time is not.
            image::codecs::png::PngEncoder::new_with_quality(
                &mut out,
                image::codecs::png::CompressionType::Fast,
                image::codecs::png::FilterType::Sub,
            )
            .write_image_luma8(frame)
            .map_err(|e| e.to_string())?;
            Ok((out.into_inner(), "image/png"))
        }
        Encoding::Jpeg(q) => {
            image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, q.clamp(1, 100))
                .write_image_luma8(frame)
                .map_err(|e| e.to_string())?;
            Ok((out.into_inner(), "image/jpeg"))
        }
    }
}

/// Writing a grey frame with either encoder.
trait WriteLuma8 {
    fn write_image_luma8(self, frame: &Frame) -> image::ImageResult<()>;
}

impl<E: image::ImageEncoder> WriteLuma8 for E {
    fn write_image_luma8(self, frame: &Frame) -> image::ImageResult<()> {
        self.write_image(frame.pixels(), frame.width(), frame.height(), image::ExtendedColorType::L8)
    }
}
