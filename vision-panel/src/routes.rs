//! The panel's routes, all read-only: `GET /` the page, `/frame.png` the frame it shows
//! (`?seq=N`: view N's, while kept), `/fit.svg` a run's last fit picture (same `?seq=N`),
//! `/state.json` the last view, `/events` the views as Server-Sent Events. Anything else is
//! `404`; a method other than GET or HEAD is `405`. No route writes a parameter or moves the
//! machine.

use std::io::{self, Write};
use std::net::TcpStream;
use std::sync::atomic::Ordering;
use std::time::Instant;

use vision_driver_camera::server::request::{read_request, Request, RequestError, MAX_HEAD_BYTES};

use crate::server::{Counted, Shared};

/// The page: HTML, CSS and script in one built-in file.
const PAGE: &str = include_str!("page.html");

/// What the page may load: itself and the panel's own routes; no other site.
const POLICY: &str = "default-src 'none'; img-src 'self'; connect-src 'self'; style-src 'unsafe-inline'; \
                      script-src 'unsafe-inline'; base-uri 'none'; form-action 'none'; frame-ancestors 'none'";

/// Answers one request on `stream`.
pub(crate) fn answer(mut stream: TcpStream, shared: &Shared) -> io::Result<()> {
    stream.set_nonblocking(false)?;
    stream.set_write_timeout(Some(shared.limits.write_timeout))?;
    let request = match read_request(&mut stream, MAX_HEAD_BYTES, Instant::now() + shared.limits.head_deadline) {
        Ok(r) => r,
        Err(RequestError::TooLarge { .. }) => {
            reply(&mut stream, 431, "text/plain", b"request too large", false)?;
            return drain(&mut stream, shared);
        }
        Err(RequestError::Malformed(why)) => return reply(&mut stream, 400, "text/plain", why.as_bytes(), false),
        Err(_) => return Ok(()),
    };
    let head_only = request.method == "HEAD";
    if request.method != "GET" && !head_only {
        return reply(&mut stream, 405, "text/plain", b"the panel is read-only: GET only", false);
    }
    if !shared.access.allows(token(&request)) {
        return reply(&mut stream, 401, "text/plain", b"give the panel's token: ?token=...", head_only);
    }
    if !shared.access.allows_host(request.header("host")) {
        return reply(&mut stream, 403, "text/plain", b"open the panel as http://127.0.0.1:PORT/", head_only);
    }
    let handle = &shared.handle;
    match request.path.as_str() {
        "/" | "/index.html" => reply(&mut stream, 200, "text/html; charset=utf-8", PAGE.as_bytes(), head_only),
        "/state.json" => {
            let json = handle.latest().map_or_else(|| serde_json::json!({"seq": 0}), |e| e.view.to_json(e.seq));
            reply(&mut stream, 200, "application/json", json.to_string().as_bytes(), head_only)
        }
        "/frame.png" => {
            let entry = match request.query_param("seq") {
                Some(n) => n.parse().ok().and_then(|n| handle.get(n)),
                None => handle.latest(),
            };
            match entry.and_then(|e| e.png()) {
                Some(png) => reply(&mut stream, 200, "image/png", &png, head_only),
                None => reply(&mut stream, 404, "text/plain", b"no such frame", head_only),
            }
        }
        "/fit.svg" => {
            let entry = match request.query_param("seq") {
                Some(n) => n.parse().ok().and_then(|n| handle.get(n)),
                None => handle.latest(),
            };
            match entry.and_then(|e| e.view.fit.as_ref().and_then(|f| f.svg.clone())) {
                Some(svg) => reply(&mut stream, 200, "image/svg+xml", svg.as_bytes(), head_only),
                None => reply(&mut stream, 404, "text/plain", b"no such fit", head_only),
            }
        }
        "/events" => events(stream, shared, head_only),
        _ => reply(&mut stream, 404, "text/plain", b"not found", head_only),
    }
}

/// The token a request gives: `?token=`, or the `X-Panel-Token` header, or
/// `Authorization: Bearer …`.
fn token(request: &Request) -> Option<&str> {
    request
        .query_param("token")
        .or_else(|| request.header("x-panel-token"))
        .or_else(|| request.header("authorization").and_then(|a| a.strip_prefix("Bearer ")))
}

fn reason(status: u16) -> &'static str {
    match status {
        200 => "OK",
        400 => "Bad Request",
        401 => "Unauthorized",
        403 => "Forbidden",
        404 => "Not Found",
        405 => "Method Not Allowed",
        431 => "Request Header Fields Too Large",
        _ => "Service Unavailable",
    }
}

fn head(status: u16, kind: &str, length: Option<usize>) -> String {
    let length = length.map(|n| format!("Content-Length: {n}\r\n")).unwrap_or_default();
    format!(
        "HTTP/1.1 {status} {}\r\nContent-Type: {kind}\r\n{length}Cache-Control: no-store\r\n\
         X-Content-Type-Options: nosniff\r\nContent-Security-Policy: {POLICY}\r\nConnection: close\r\n\r\n",
        reason(status)
    )
}

fn reply(stream: &mut TcpStream, status: u16, kind: &str, body: &[u8], head_only: bool) -> io::Result<()> {
    stream.write_all(head(status, kind, Some(body.len())).as_bytes())?;
    if !head_only {
        stream.write_all(body)?;
    }
    stream.flush()
}

/// Closes after an answer sent before the whole request was read: reads and drops what the
/// client still sends (at most 1 MiB, within the head deadline), so that closing with unread
/// bytes does not reset the connection before the client has read the answer.
fn drain(stream: &mut TcpStream, shared: &Shared) -> io::Result<()> {
    stream.shutdown(std::net::Shutdown::Write)?;
    stream.set_read_timeout(Some(shared.limits.head_deadline))?;
    let _ = io::copy(&mut io::Read::take(stream, 1 << 20), &mut io::sink());
    Ok(())
}

/// The event stream: the last view at once, then each new one; a comment when idle. Ends when
/// a write fails or times out (the client left or stalled) or the panel closes.
fn events(mut stream: TcpStream, shared: &Shared, head_only: bool) -> io::Result<()> {
    if shared.streams.fetch_add(1, Ordering::SeqCst) >= shared.limits.max_streams {
        shared.streams.fetch_sub(1, Ordering::SeqCst);
        return reply(&mut stream, 503, "text/plain", b"too many event streams", head_only);
    }
    let _place = Counted(&shared.streams);
    stream.write_all(head(200, "text/event-stream", None).as_bytes())?;
    if head_only {
        return Ok(());
    }
    let handle = &shared.handle;
    let mut next = handle.latest();
    let mut seen = 0;
    loop {
        match next {
            Some(entry) => {
                seen = entry.seq;
                let data = entry.view.to_json(entry.seq).to_string();
                stream.write_all(format!("id: {seen}\ndata: {data}\n\n").as_bytes())?;
            }
            None if handle.closed() => return Ok(()),
            None => stream.write_all(b": idle\n\n")?,
        }
        stream.flush()?;
        next = handle.after(seen, shared.limits.keepalive);
    }
}
