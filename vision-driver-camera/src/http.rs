//! A minimal HTTP/1.1 GET client for camera snapshot URLs (mjpg-streamer `/?action=snapshot`,
//! ustreamer `/snapshot`, an IP camera's JPEG URL): one request per connection, the whole
//! exchange under one deadline, bounded headers and body.
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
            (h, after.strip_prefix(':'))
        } else {
            match authority.rsplit_once(':') {
                Some((h, p)) => (h, Some(p)),
                None => (authority, None),
            }
        };
        if host.is_empty() {
            return Err("must name a host".into());
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
    /// A `multipart/x-mixed-replace` stream.
    Stream,
    /// Another socket error.
    Io(io::Error),
}

/// Reads one response from `r`: status line, headers, then a body framed by `Content-Length`,
/// chunked encoding, or the end of the stream.
pub(crate) fn read_response(r: &mut impl Read) -> Result<Response, ReadError> {
    let mut buf = Vec::with_capacity(1024);
    let header_end = loop {
        if let Some(i) = find(&buf, b"\r\n\r\n") {
            break i;
        }
        if buf.len() > MAX_HEADER_BYTES {
            return Err(ReadError::Malformed(format!("a header block longer than {MAX_HEADER_BYTES} bytes")));
        }
        let waiting = if find(&buf, b"\r\n").is_some() { "the headers" } else { "the status line" };
        if fill(r, &mut buf, waiting)? == 0 {
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
            if fill(r, &mut rest, "the body")? == 0 {
                return Err(ReadError::Closed("the body"));
            }
        }
        rest.truncate(n);
        rest
    } else {
        // No length: the body runs to the end of the stream (HTTP/1.0 style).
        while fill(r, &mut rest, "the body")? > 0 {
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

/// The body of a chunked response; `rest` holds what arrived after the headers.
fn dechunk(r: &mut impl Read, mut rest: Vec<u8>) -> Result<Vec<u8>, ReadError> {
    let mut body = Vec::new();
    let mut at = 0;
    loop {
        let line_end = loop {
            if let Some(i) = find(&rest[at..], b"\r\n") {
                break at + i;
            }
            if rest.len() - at > 1024 {
                return Err(ReadError::Malformed("a chunk size line longer than 1024 bytes".into()));
            }
            if fill(r, &mut rest, "the body")? == 0 {
                return Err(ReadError::Closed("the body"));
            }
        };
        let line = std::str::from_utf8(&rest[at..line_end]).unwrap_or("?");
        let hex = line.split(';').next().unwrap_or_default().trim();
        let size = usize::from_str_radix(hex, 16)
            .map_err(|_| ReadError::Malformed(format!("a chunk size {:?}", printable(line, 20))))?;
        at = line_end + 2;
        if size == 0 {
            return Ok(body);
        }
        if body.len() + size > MAX_BODY_BYTES {
            return Err(ReadError::TooLarge);
        }
        while rest.len() < at + size + 2 {
            if fill(r, &mut rest, "the body")? == 0 {
                return Err(ReadError::Closed("the body"));
            }
        }
        body.extend_from_slice(&rest[at..at + size]);
        if &rest[at + size..at + size + 2] != b"\r\n" {
            return Err(ReadError::Malformed("a chunk not ended by CRLF".into()));
        }
        at += size + 2;
    }
}

/// Reads what is available into `buf`; 0 at the end of the stream.
fn fill(r: &mut impl Read, buf: &mut Vec<u8>, waiting: &'static str) -> Result<usize, ReadError> {
    let mut chunk = [0u8; 16 * 1024];
    loop {
        match r.read(&mut chunk) {
            Ok(n) => {
                buf.extend_from_slice(&chunk[..n]);
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
        for bad in
            ["ftp://x/", "http://", "http://:80/", "http://h:0/", "http://h:99999/", "http://u:p@h/", "http://h/a b"]
        {
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

        /// Any text: a URL or a reason, never a panic; a parsed URL prints and parses back.
        #[test]
        fn any_url_text_parses_or_says_why(text in "(http://)?[ -~]{0,40}") {
            if let Ok(u) = HttpUrl::parse(&text) {
                prop_assert_eq!(HttpUrl::parse(&u.to_string()), Ok(u));
            }
        }
    }
}
