//! A minimal HTTP/1.1 GET client for camera snapshot URLs (mjpg-streamer `/?action=snapshot`,
//! ustreamer `/snapshot`, an IP camera's JPEG URL): one request per connection, the whole
//! exchange under one deadline, bounded headers and body.
//!
//! Every byte read counts against [`MAX_RESPONSE_BYTES`] (headers, body, chunk-size lines with
//! their extensions): a server that pads a chunked body with framing cannot make the client
//! read, or keep, more than that, whatever the decoded body's size. A chunk-size line is at
//! most [`MAX_CHUNK_LINE_BYTES`], and the framing already decoded is not kept.
//!
//! [`read_response`] is the pure part, over any [`Read`], so it is tested on scripted and
//! arbitrary bytes; [`get`] is the thin socket edge around it.

use std::fmt;
use std::io::{self, Read, Write};
use std::net::{SocketAddr, TcpStream, ToSocketAddrs};
use std::time::{Duration, Instant};

use crate::error::{printable, CameraError};

/// Longest header block, bytes.
pub const MAX_HEADER_BYTES: usize = 16 * 1024;
/// Largest body, bytes (a 16-megapixel PNG fits).
pub const MAX_BODY_BYTES: usize = 64 * 1024 * 1024;
/// Longest chunk-size line of a chunked body (the size in hex and any chunk extensions, without
/// its CRLF), bytes. A camera sends a few hex digits and no extension.
pub const MAX_CHUNK_LINE_BYTES: usize = 256;
/// Most bytes of chunked framing (chunk-size lines, CRLFs) read with a body, bytes.
pub const MAX_FRAMING_BYTES: usize = 1024 * 1024;
/// Most bytes read for one response, everything the server sent counted: the header block,
/// the body and its framing.
pub const MAX_RESPONSE_BYTES: usize = MAX_HEADER_BYTES + MAX_BODY_BYTES + MAX_FRAMING_BYTES;

/// An `http://host[:port]/path` URL.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HttpUrl {
    /// Host name or IP address (IPv6 without brackets).
    pub host: String,
    /// TCP port (80 by default).
    pub port: u16,
    /// Path and query, starting with `/`.
    pub path: String,
}

impl HttpUrl {
    /// Parses an `http://` URL.
    ///
    /// # Errors
    /// Why it is not one: another scheme, no host, a bad port, user info, spaces or control
    /// characters.
    pub fn parse(text: &str) -> Result<HttpUrl, String> {
        let rest = text
            .get(..7)
            .filter(|s| s.eq_ignore_ascii_case("http://"))
            .map(|_| &text[7..])
            .ok_or("must start with http://")?;
        if rest.bytes().any(|b| b <= b' ' || b == 0x7f) {
            return Err("must not contain spaces or control characters".into());
        }
        let (authority, path) = match rest.find(['/', '?']) {
            Some(i) if rest.as_bytes()[i] == b'?' => (&rest[..i], format!("/{}", &rest[i..])),
            Some(i) => (&rest[..i], rest[i..].to_string()),
            None => (rest, "/".to_string()),
        };
        let path = path.split('#').next().unwrap_or("/").to_string();
        if authority.contains('@') {
            return Err("must not carry a user name or password (the driver sends no credentials)".into());
        }
        let (host, port) = if let Some(v6) = authority.strip_prefix('[') {
            let (h, after) = v6.split_once(']').ok_or("has an unclosed [ in the host")?;
            let port = match after {
                "" => None,
                _ => Some(after.strip_prefix(':').ok_or("has text after the ] of the host")?),
            };
            (h, port)
        } else {
            match authority.rsplit_once(':') {
                Some((h, p)) => (h, Some(p)),
                None => (authority, None),
            }
        };
        if host.is_empty() {
            return Err("must name a host".into());
        }
        // Brackets only around an IPv6 host, and an IPv6 host only in brackets: so the URL
        // prints back as it was read.
        if host.contains(['[', ']']) || (host.contains(':') && !authority.starts_with('[')) {
            return Err("has a host that is not a name or an address (an IPv6 one is written [::1])".into());
        }
        let port = match port {
            None => 80,
            Some(p) => p.parse::<u16>().ok().filter(|p| *p > 0).ok_or("has a port that is not 1..65535")?,
        };
        Ok(HttpUrl { host: host.to_string(), port, path })
    }

    fn authority(&self) -> String {
        if self.host.contains(':') {
            format!("[{}]:{}", self.host, self.port)
        } else {
            format!("{}:{}", self.host, self.port)
        }
    }
}

impl fmt::Display for HttpUrl {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "http://{}{}", self.authority(), self.path)
    }
}

/// A response's status and body.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Response {
    /// The status code.
    pub status: u16,
    /// The reason phrase, as sent (escaped).
    pub phrase: String,
    /// The `Content-Type`, when sent.
    pub content_type: Option<String>,
    /// The body (de-chunked).
    pub body: Vec<u8>,
}

/// Why a response could not be read, before it is given its URL.
#[derive(Debug)]
pub(crate) enum ReadError {
    /// The peer sent something that is not HTTP/1.x.
    Malformed(String),
    /// The stream ended early.
    Closed(&'static str),
    /// A read timed out.
    TimedOut(&'static str),
    /// The body is larger than the bound.
    TooLarge,
    /// The response, framing and all, is longer than [`MAX_RESPONSE_BYTES`].
    TooLong,
    /// A `multipart/x-mixed-replace` stream.
    Stream,
    /// Another socket error.
    Io(io::Error),
}

/// Reads one response from `r`: status line, headers, then a body framed by `Content-Length`,
/// chunked encoding, or the end of the stream.
pub(crate) fn read_response(r: &mut impl Read) -> Result<Response, ReadError> {
    let r = &mut Limited { r, left: MAX_RESPONSE_BYTES };
    let mut buf = Vec::with_capacity(1024);
    let header_end = loop {
        if let Some(i) = find(&buf, b"\r\n\r\n") {
            break i;
        }
        if buf.len() > MAX_HEADER_BYTES {
            return Err(ReadError::Malformed(format!("a header block longer than {MAX_HEADER_BYTES} bytes")));
        }
        let waiting = if find(&buf, b"\r\n").is_some() { "the headers" } else { "the status line" };
        if r.fill(&mut buf, waiting)? == 0 {
            return Err(ReadError::Closed(waiting));
        }
    };
    let head = std::str::from_utf8(&buf[..header_end])
        .map_err(|_| ReadError::Malformed("a header block that is not text".into()))?;
    let mut lines = head.split("\r\n");
    let status_line = lines.next().unwrap_or_default();
    let (status, phrase) = status(status_line)?;
    let mut length = None;
    let mut chunked = false;
    let mut content_type = None;
    for line in lines {
        let (name, value) = line
            .split_once(':')
            .ok_or_else(|| ReadError::Malformed(format!("a header line {:?}", printable(line, 60))))?;
        let value = value.trim();
        if name.eq_ignore_ascii_case("content-length") {
            let n = value.parse::<usize>().map_err(|_| ReadError::Malformed(format!("Content-Length {value:?}")))?;
            if length.is_some_and(|l| l != n) {
                return Err(ReadError::Malformed("two different Content-Length headers".into()));
            }
            length = Some(n);
        } else if name.eq_ignore_ascii_case("transfer-encoding") {
            chunked = value.to_ascii_lowercase().split(',').any(|c| c.trim() == "chunked");
        } else if name.eq_ignore_ascii_case("content-type") {
            content_type = Some(printable(value, 80));
        }
    }
    if content_type.as_deref().is_some_and(|t| t.to_ascii_lowercase().starts_with("multipart/")) {
        return Err(ReadError::Stream);
    }
    let mut rest = buf.split_off(header_end + 4);
    let body = if chunked {
        dechunk(r, rest)?
    } else if let Some(n) = length {
        if n > MAX_BODY_BYTES {
            return Err(ReadError::TooLarge);
        }
        rest.truncate(n);
        while rest.len() < n {
            if r.fill(&mut rest, "the body")? == 0 {
                return Err(ReadError::Closed("the body"));
            }
        }
        rest.truncate(n);
        rest
    } else {
        // No length: the body runs to the end of the stream (HTTP/1.0 style).
        while r.fill(&mut rest, "the body")? > 0 {
            if rest.len() > MAX_BODY_BYTES {
                return Err(ReadError::TooLarge);
            }
        }
        rest
    };
    Ok(Response { status, phrase, content_type, body })
}

fn status(line: &str) -> Result<(u16, String), ReadError> {
    let bad = || ReadError::Malformed(format!("a status line {:?}", printable(line, 60)));
    let mut parts = line.splitn(3, ' ');
    let version = parts.next().ok_or_else(bad)?;
    if !(version == "HTTP/1.1" || version == "HTTP/1.0") {
        return Err(bad());
    }
    let code = parts.next().filter(|c| c.len() == 3).and_then(|c| c.parse::<u16>().ok()).ok_or_else(bad)?;
    if !(100..=599).contains(&code) {
        return Err(bad());
    }
    Ok((code, printable(parts.next().unwrap_or_default(), 60)))
}

/// The body of a chunked response; `rest` holds what arrived after the headers. The framing
/// decoded is dropped as it goes, so memory holds the body and at most one chunk besides.
fn dechunk<R: Read>(r: &mut Limited<'_, R>, mut rest: Vec<u8>) -> Result<Vec<u8>, ReadError> {
    let mut body = Vec::new();
    let too_long = || ReadError::Malformed(format!("a chunk size line longer than {MAX_CHUNK_LINE_BYTES} bytes"));
    loop {
        let line_end = loop {
            if let Some(i) = find(&rest, b"\r\n") {
                break i;
            }
            // The line and its CR may have arrived without the LF.
            if rest.len() > MAX_CHUNK_LINE_BYTES + 1 {
                return Err(too_long());
            }
            if r.fill(&mut rest, "the body")? == 0 {
                return Err(ReadError::Closed("the body"));
            }
        };
        if line_end > MAX_CHUNK_LINE_BYTES {
            return Err(too_long());
        }
        let line = std::str::from_utf8(&rest[..line_end]).unwrap_or("?");
        let hex = line.split(';').next().unwrap_or_default().trim();
        let size = usize::from_str_radix(hex, 16)
            .map_err(|_| ReadError::Malformed(format!("a chunk size {:?}", printable(line, 20))))?;
        let at = line_end + 2;
        if size == 0 {
            return Ok(body);
        }
        if body.len() + size > MAX_BODY_BYTES {
            return Err(ReadError::TooLarge);
        }
        while rest.len() < at + size + 2 {
            if r.fill(&mut rest, "the body")? == 0 {
                return Err(ReadError::Closed("the body"));
            }
        }
        body.extend_from_slice(&rest[at..at + size]);
        if &rest[at + size..at + size + 2] != b"\r\n" {
            return Err(ReadError::Malformed("a chunk not ended by CRLF".into()));
        }
        rest.drain(..at + size + 2);
    }
}

/// A reader that may still give `left` bytes of the response.
struct Limited<'a, R> {
    r: &'a mut R,
    left: usize,
}

impl<R: Read> Limited<'_, R> {
    /// Reads what is available into `buf`, within the bytes left; 0 at the end of the stream.
    fn fill(&mut self, buf: &mut Vec<u8>, waiting: &'static str) -> Result<usize, ReadError> {
        if self.left == 0 {
            return Err(ReadError::TooLong);
        }
        let mut chunk = [0u8; 16 * 1024];
        let want = chunk.len().min(self.left);
        loop {
            match self.r.read(&mut chunk[..want]) {
                Ok(n) => {
                    buf.extend_from_slice(&chunk[..n]);
                    self.left -= n;
                    return Ok(n);
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) if matches!(e.kind(), io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut) => {
                    return Err(ReadError::TimedOut(waiting))
                }
                Err(e) if matches!(e.kind(), io::ErrorKind::ConnectionReset | io::ErrorKind::ConnectionAborted) => {
                    return Err(ReadError::Closed(waiting))
                }
                Err(e) => return Err(ReadError::Io(e)),
            }
        }
    }
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

/// A stream whose every read waits at most until `deadline`: the whole exchange has one time
/// budget, so a server that dribbles bytes cannot stretch it.
struct Deadlined<'a> {
    stream: &'a TcpStream,
    deadline: Instant,
}

impl Read for Deadlined<'_> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let left = self.deadline.saturating_duration_since(Instant::now());
        if left.is_zero() {
            return Err(io::ErrorKind::TimedOut.into());
        }
        self.stream.set_read_timeout(Some(left))?;
        (&mut &*self.stream).read(buf)
    }
}

/// GETs `url` and returns the body of a 200 response, all within `timeout`.
///
/// # Errors
/// [`CameraError::Resolve`], [`CameraError::ConnectTimeout`], [`CameraError::Refused`],
/// [`CameraError::Timeout`], [`CameraError::Closed`], [`CameraError::Http`],
/// [`CameraError::Status`], [`CameraError::Stream`], [`CameraError::TooLarge`],
/// [`CameraError::Io`].
pub fn get(url: &HttpUrl, timeout: Duration) -> Result<Vec<u8>, CameraError> {
    let deadline = Instant::now() + timeout;
    let authority = url.authority();
    let addrs: Vec<SocketAddr> = (url.host.as_str(), url.port)
        .to_socket_addrs()
        .map_err(|e| CameraError::Resolve { addr: authority.clone(), reason: e.to_string() })?
        .collect();
    let mut last = None;
    let mut stream = None;
    for addr in addrs {
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() {
            break;
        }
        match TcpStream::connect_timeout(&addr, left) {
            Ok(s) => {
                stream = Some(s);
                break;
            }
            Err(e) => last = Some(e),
        }
    }
    let stream = stream.ok_or_else(|| match last {
        Some(e) if e.kind() == io::ErrorKind::ConnectionRefused => {
            CameraError::Refused { addr: authority.clone(), reason: e.to_string() }
        }
        Some(e) if e.kind() != io::ErrorKind::TimedOut && e.kind() != io::ErrorKind::WouldBlock => {
            CameraError::Io { from: url.to_string(), reason: e.to_string() }
        }
        _ => CameraError::ConnectTimeout { addr: authority.clone(), timeout },
    })?;
    let _ = stream.set_nodelay(true);
    let request = format!(
        "GET {} HTTP/1.1\r\nHost: {}\r\nUser-Agent: mach-vision\r\nAccept: image/*\r\nConnection: close\r\n\r\n",
        url.path, authority
    );
    stream
        .set_write_timeout(Some(deadline.saturating_duration_since(Instant::now()).max(Duration::from_millis(1))))
        .map_err(|e| CameraError::Io { from: url.to_string(), reason: e.to_string() })?;
    (&stream).write_all(request.as_bytes()).map_err(|e| match e.kind() {
        io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut => {
            CameraError::Timeout { from: url.to_string(), timeout, waiting_for: "the request's sending" }
        }
        _ => CameraError::Io { from: url.to_string(), reason: e.to_string() },
    })?;
    let response = read_response(&mut Deadlined { stream: &stream, deadline }).map_err(|e| match e {
        ReadError::Malformed(reason) => CameraError::Http { url: url.to_string(), reason },
        ReadError::Closed(waiting_for) => CameraError::Closed { url: url.to_string(), waiting_for },
        ReadError::TimedOut(waiting_for) => CameraError::Timeout { from: url.to_string(), timeout, waiting_for },
        ReadError::TooLarge => CameraError::TooLarge { from: url.to_string(), limit: MAX_BODY_BYTES, what: "bytes" },
        ReadError::TooLong => CameraError::TooLarge {
            from: url.to_string(),
            limit: MAX_RESPONSE_BYTES,
            what: "bytes with its HTTP headers and framing",
        },
        ReadError::Stream => CameraError::Stream { url: url.to_string() },
        ReadError::Io(e) => CameraError::Io { from: url.to_string(), reason: e.to_string() },
    })?;
    if response.status != 200 {
        return Err(CameraError::Status { url: url.to_string(), code: response.status, phrase: response.phrase });
    }
    Ok(response.body)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn read(bytes: &[u8]) -> Result<Response, ReadError> {
        read_response(&mut &bytes[..])
    }

    #[test]
    fn urls_parse_with_their_defaults() {
        let u = HttpUrl::parse("http://cam.local:8080/?action=snapshot").expect("url");
        assert_eq!((u.host.as_str(), u.port, u.path.as_str()), ("cam.local", 8080, "/?action=snapshot"));
        let u = HttpUrl::parse("HTTP://10.0.0.5").expect("url");
        assert_eq!((u.port, u.path.as_str()), (80, "/"));
        assert_eq!(HttpUrl::parse("http://h?x=1").expect("url").path, "/?x=1");
        let u = HttpUrl::parse("http://[::1]:81/snapshot#frag").expect("v6");
        assert_eq!((u.host.as_str(), u.port, u.path.as_str()), ("::1", 81, "/snapshot"));
        assert_eq!(u.to_string(), "http://[::1]:81/snapshot");
        assert_eq!(HttpUrl::parse("http://[::1]/").expect("v6, port 80").port, 80);
        for bad in [
            "ftp://x/",
            "http://",
            "http://:80/",
            "http://h:0/",
            "http://h:99999/",
            "http://u:p@h/",
            "http://h/a b",
            "http://]::1",
            "http://[::1]x/",
            "http://a:b:80/",
            "http://h]:80/",
        ] {
            assert!(HttpUrl::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn a_body_is_framed_by_length_by_chunks_or_by_the_close() {
        let r = read(b"HTTP/1.1 200 OK\r\nContent-Type: image/jpeg\r\nContent-Length: 3\r\n\r\nabcdef").expect("len");
        assert_eq!((r.status, r.body.as_slice(), r.content_type.as_deref()), (200, &b"abc"[..], Some("image/jpeg")));
        let r = read(b"HTTP/1.1 200 OK\r\nTransfer-Encoding: chunked\r\n\r\n3\r\nabc\r\n2;x=y\r\nde\r\n0\r\n\r\n")
            .expect("chunked");
        assert_eq!(r.body, b"abcde");
        let r = read(b"HTTP/1.0 200 OK\r\n\r\nto the end").expect("close");
        assert_eq!(r.body, b"to the end");
        let r = read(b"HTTP/1.1 404 Not Found\r\nContent-Length: 0\r\n\r\n").expect("404");
        assert_eq!((r.status, r.phrase.as_str()), (404, "Not Found"));
    }

    #[test]
    fn broken_responses_say_what_is_wrong() {
        assert!(matches!(read(b""), Err(ReadError::Closed("the status line"))));
        assert!(matches!(read(b"HTTP/1.1 200 OK\r\nX: y"), Err(ReadError::Closed("the headers"))));
        assert!(matches!(read(b"HTTP/1.1 200 OK\r\nContent-Length: 9\r\n\r\nabc"), Err(ReadError::Closed("the body"))));
        assert!(matches!(read(b"SSH-2.0-OpenSSH\r\n\r\n"), Err(ReadError::Malformed(_))));
        assert!(matches!(read(b"HTTP/1.1 200 OK\r\nContent-Length: x\r\n\r\n"), Err(ReadError::Malformed(_))));
        assert!(matches!(read(b"HTTP/1.1 200 OK\r\nContent-Length: 99999999999\r\n\r\n"), Err(ReadError::TooLarge)));
        assert!(matches!(
            read(b"HTTP/1.1 200 OK\r\nContent-Type: multipart/x-mixed-replace;boundary=b\r\n\r\n"),
            Err(ReadError::Stream)
        ));
        assert!(matches!(
            read(b"HTTP/1.1 200 OK\r\nTransfer-Encoding: chunked\r\n\r\n3\r\nabcX\r\n"),
            Err(ReadError::Malformed(_))
        ));
        let long = [b"HTTP/1.1 200 OK\r\nX: ".as_slice(), &vec![b'a'; MAX_HEADER_BYTES + 10]].concat();
        assert!(matches!(read(&long), Err(ReadError::Malformed(_))));
    }

    /// A chunked body of one-byte chunks behind chunk extensions, `total` bytes in all, that
    /// counts the bytes read from it.
    struct Padded {
        sent: usize,
        total: usize,
        unit: Vec<u8>,
    }

    impl Read for Padded {
        fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
            let head: &[u8] = b"HTTP/1.1 200 OK\r\nTransfer-Encoding: chunked\r\n\r\n";
            let n = buf.len().min(self.total - self.sent);
            for (i, b) in buf[..n].iter_mut().enumerate() {
                let at = self.sent + i;
                *b = head.get(at).copied().unwrap_or_else(|| self.unit[(at - head.len()) % self.unit.len()]);
            }
            self.sent += n;
            Ok(n)
        }
    }

    #[test]
    fn the_raw_bytes_read_are_bounded_not_only_the_body() {
        let unit = [format!("1;{}\r\n", "e".repeat(MAX_CHUNK_LINE_BYTES - 2)).as_bytes(), b"A\r\n"].concat();
        let mut padded = Padded { sent: 0, total: MAX_RESPONSE_BYTES + (8 << 20), unit };
        let r = read_response(&mut padded);
        assert!(matches!(r, Err(ReadError::TooLong)), "{r:?}");
        assert_eq!(padded.sent, MAX_RESPONSE_BYTES, "not one byte past the bound is read");
        // One byte over the line limit is refused as soon as it is read.
        let unit = [format!("1;{}\r\n", "e".repeat(MAX_CHUNK_LINE_BYTES - 1)).as_bytes(), b"A\r\n"].concat();
        let mut padded = Padded { sent: 0, total: MAX_RESPONSE_BYTES, unit };
        let Err(ReadError::Malformed(reason)) = read_response(&mut padded) else { panic!("accepted") };
        assert_eq!(reason, format!("a chunk size line longer than {MAX_CHUNK_LINE_BYTES} bytes"));
        assert!(padded.sent <= 32 * 1024, "{} bytes read", padded.sent);
    }

    proptest! {
        /// Any bytes: an answer or a typed error, never a panic; a body never exceeds its bound.
        #[test]
        fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
            if let Ok(r) = read(&bytes) {
                prop_assert!(r.body.len() <= bytes.len());
            }
        }

        /// A well-formed response with any body and any chunking reads back exactly.
        #[test]
        fn any_body_reads_back(body in proptest::collection::vec(any::<u8>(), 0..300), cut in 1usize..50) {
            let mut chunked = b"HTTP/1.1 200 OK\r\nTransfer-Encoding: chunked\r\n\r\n".to_vec();
            for part in body.chunks(cut) {
                chunked.extend_from_slice(format!("{:x}\r\n", part.len()).as_bytes());
                chunked.extend_from_slice(part);
                chunked.extend_from_slice(b"\r\n");
            }
            chunked.extend_from_slice(b"0\r\n\r\n");
            prop_assert_eq!(read(&chunked).expect("chunked").body, body.clone());
            let mut framed = format!("HTTP/1.1 200 OK\r\nContent-Length: {}\r\n\r\n", body.len()).into_bytes();
            framed.extend_from_slice(&body);
            prop_assert_eq!(read(&framed).expect("length").body, body);
        }

        /// Any text: a URL or a reason, never a panic; a parsed URL prints and parses back
        /// (`http://]::1` once parsed to a host `]:` that printed as `[]:]`).
        #[test]
        fn any_url_text_parses_or_says_why(text in "(http://)?[ -~]{0,40}") {
            if let Ok(u) = HttpUrl::parse(&text) {
                prop_assert_eq!(HttpUrl::parse(&u.to_string()), Ok(u));
            }
        }
    }
}
