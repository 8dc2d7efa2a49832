//! One HTTP/1.1 request head, read within bounds: what the loopback servers (the snapshot
//! server, the operator panel) accept. A head is at most [`MAX_HEAD_BYTES`] and must arrive
//! before a deadline, so a slow or oversized client costs one bounded read; a body is never
//! read (every route is a GET).

use std::io::{self, Read};
use std::net::TcpStream;
use std::time::Instant;

/// The largest request head accepted, bytes (request line and headers).
pub const MAX_HEAD_BYTES: usize = 8 * 1024;

/// The most headers a request may carry.
pub const MAX_HEADERS: usize = 64;

/// A parsed request head.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Request {
    /// The method, as sent (`GET`, `HEAD`, …).
    pub method: String,
    /// The path, without the query (`/frame.png`).
    pub path: String,
    /// The query after `?`, without it (empty when none).
    pub query: String,
    headers: Vec<(String, String)>,
}

impl Request {
    /// The first header named `name` (any case), its value trimmed.
    #[must_use]
    pub fn header(&self, name: &str) -> Option<&str> {
        self.headers.iter().find(|(n, _)| n.eq_ignore_ascii_case(name)).map(|(_, v)| v.as_str())
    }

    /// The first query parameter named `name`, undecoded (`a=1&token=x` → `x` for `token`).
    #[must_use]
    pub fn query_param(&self, name: &str) -> Option<&str> {
        self.query.split('&').find_map(|pair| pair.strip_prefix(name)?.strip_prefix('='))
    }
}

/// Why a request head was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum RequestError {
    /// The head is longer than the limit, bytes.
    #[error("request head over {limit} bytes")]
    TooLarge {
        /// The limit, bytes.
        limit: usize,
    },
    /// The head is not an HTTP/1.x request head.
    #[error("malformed request: {0}")]
    Malformed(&'static str),
    /// The client closed the connection before the head ended.
    #[error("the client closed the connection")]
    Closed,
    /// The head did not arrive before the deadline.
    #[error("the request head did not arrive in time")]
    TimedOut,
    /// Another socket error.
    #[error("socket error: {0}")]
    Io(io::ErrorKind),
}

/// Reads one request head from `stream`, at most `limit` bytes, before `deadline`, and parses
/// it; bytes after the head are left unread.
///
/// # Errors
/// [`RequestError`]: too large, malformed, closed, timed out, or a socket error.
pub fn read_request(stream: &mut TcpStream, limit: usize, deadline: Instant) -> Result<Request, RequestError> {
    let mut head = Vec::new();
    let mut buf = [0u8; 1024];
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() {
            return Err(RequestError::TimedOut);
        }
        stream.set_read_timeout(Some(left)).map_err(|e| RequestError::Io(e.kind()))?;
        let n = match stream.read(&mut buf) {
            Ok(0) => return Err(RequestError::Closed),
            Ok(n) => n,
            Err(e) if matches!(e.kind(), io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut) => {
                return Err(RequestError::TimedOut)
            }
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(RequestError::Io(e.kind())),
        };
        // Search from just before the new bytes: the blank line may straddle two reads.
        let from = head.len().saturating_sub(3);
        head.extend_from_slice(&buf[..n]);
        if let Some(end) = head[from..].windows(4).position(|w| w == b"\r\n\r\n") {
            let end = from + end + 4;
            if end > limit {
                return Err(RequestError::TooLarge { limit });
            }
            return parse(&head[..end]);
        }
        if head.len() > limit {
            return Err(RequestError::TooLarge { limit });
        }
    }
}

/// Parses a request head (request line, headers, the blank line optional).
///
/// # Errors
/// [`RequestError::Malformed`] for anything but `METHOD TARGET HTTP/1.x` with an
/// origin-form target (starting with `/`) and `name: value` headers of printable ASCII;
/// [`RequestError::TooLarge`] for more than [`MAX_HEADERS`] headers.
pub fn parse(head: &[u8]) -> Result<Request, RequestError> {
    let text = std::str::from_utf8(head).map_err(|_| RequestError::Malformed("not ASCII"))?;
    if !text.bytes().all(|b| b == b'\r' || b == b'\n' || b == b'\t' || (b' '..=b'~').contains(&b)) {
        return Err(RequestError::Malformed("not printable ASCII"));
    }
    let mut lines = text.split("\r\n");
    let line = lines.next().unwrap_or_default();
    let mut words = line.split(' ');
    let (Some(method), Some(target), Some(version), None) = (words.next(), words.next(), words.next(), words.next())
    else {
        return Err(RequestError::Malformed("the request line is not METHOD TARGET VERSION"));
    };
    if method.is_empty() || !method.bytes().all(|b| b.is_ascii_uppercase()) {
        return Err(RequestError::Malformed("the method is not a word in capitals"));
    }
    if version != "HTTP/1.1" && version != "HTTP/1.0" {
        return Err(RequestError::Malformed("not HTTP/1.0 or HTTP/1.1"));
    }
    if !target.starts_with('/') {
        return Err(RequestError::Malformed("the target is not a path"));
    }
    let (path, query) = target.split_once('?').unwrap_or((target, ""));
    let mut headers = Vec::new();
    for line in lines.take_while(|l| !l.is_empty()) {
        if headers.len() == MAX_HEADERS {
            return Err(RequestError::TooLarge { limit: MAX_HEADERS });
        }
        let (name, value) = line.split_once(':').ok_or(RequestError::Malformed("a header without a colon"))?;
        if name.is_empty() || name.contains([' ', '\t']) {
            return Err(RequestError::Malformed("a header name with white space"));
        }
        headers.push((name.to_string(), value.trim().to_string()));
    }
    Ok(Request { method: method.to_string(), path: path.to_string(), query: query.to_string(), headers })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn a_get_is_parsed_with_its_query_and_headers() {
        let r = parse(b"GET /frame.png?seq=3&token=ab HTTP/1.1\r\nHost: x\r\nX-Token:  t \r\n\r\n").expect("parsed");
        assert_eq!((r.method.as_str(), r.path.as_str(), r.query.as_str()), ("GET", "/frame.png", "seq=3&token=ab"));
        assert_eq!(r.header("x-token"), Some("t"));
        assert_eq!(r.query_param("token"), Some("ab"));
        assert_eq!(r.query_param("tok"), None);
    }

    #[test]
    fn anything_but_a_request_head_is_malformed() {
        for bad in [
            &b"GET /\r\n\r\n"[..],
            b"GET http://x/ HTTP/1.1\r\n\r\n",
            b"GET / HTTP/2\r\n\r\n",
            b"get / HTTP/1.1\r\n\r\n",
            b"GET  / HTTP/1.1\r\n\r\n",
            b"GET / HTTP/1.1\r\nNoColon\r\n\r\n",
            b"GET /\x1b HTTP/1.1\r\n\r\n",
            b"\xff\xfe",
        ] {
            assert!(matches!(parse(bad), Err(RequestError::Malformed(_))), "{bad:?}");
        }
        let many = format!("GET / HTTP/1.1\r\n{}\r\n", "A: b\r\n".repeat(MAX_HEADERS + 1));
        assert_eq!(parse(many.as_bytes()), Err(RequestError::TooLarge { limit: MAX_HEADERS }));
    }

    proptest! {
        #[test]
        fn any_bytes_parse_or_fail_without_panicking(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
            let _ = parse(&bytes);
        }

        #[test]
        fn a_printable_path_and_header_come_back_as_sent(
            path in "/[a-zA-Z0-9._~/-]{0,40}",
            query in "[a-zA-Z0-9=&]{0,30}",
            value in "[ -~]{0,60}",
        ) {
            let head = format!("GET {path}?{query} HTTP/1.1\r\nX-V: {value}\r\n\r\n");
            let r = parse(head.as_bytes()).expect("a valid head");
            prop_assert_eq!(&r.path, &path);
            prop_assert_eq!(&r.query, &query);
            prop_assert_eq!(r.header("x-v"), Some(value.trim()));
        }
    }
}
