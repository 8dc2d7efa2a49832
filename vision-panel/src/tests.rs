//! The server's routes and bounds, over real sockets on loopback.

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::sync::Arc;
use std::time::{Duration, Instant};

use vision_driver_camera::Frame;

use crate::{Limits, Mark, Panel, View};

fn short() -> Limits {
    Limits {
        max_clients: 4,
        max_streams: 1,
        head_deadline: Duration::from_millis(300),
        write_timeout: Duration::from_millis(300),
        keepalive: Duration::from_millis(100),
    }
}

fn panel(token: Option<&str>, limits: Limits) -> Panel {
    Panel::with_limits("127.0.0.1:0".parse().expect("address"), token, limits).expect("panel")
}

/// Sends `request` as is and reads the whole answer: its status and body.
fn send(addr: SocketAddr, request: &[u8]) -> (u16, Vec<u8>) {
    let mut s = TcpStream::connect(addr).expect("connect");
    s.set_read_timeout(Some(Duration::from_secs(10))).expect("timeout");
    s.write_all(request).expect("send");
    let mut answer = Vec::new();
    let _ = s.read_to_end(&mut answer);
    status_and_body(&answer)
}

fn status_and_body(answer: &[u8]) -> (u16, Vec<u8>) {
    let text = String::from_utf8_lossy(answer);
    let status = text.get(9..12).and_then(|s| s.parse().ok()).unwrap_or(0);
    let body = answer.windows(4).position(|w| w == b"\r\n\r\n").map_or(Vec::new(), |i| answer[i + 4..].to_vec());
    (status, body)
}

fn get(addr: SocketAddr, path: &str) -> (u16, Vec<u8>) {
    send(addr, format!("GET {path} HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n").as_bytes())
}

fn view_with_frame() -> View {
    let frame = Frame::new(8, 6, vec![200; 48]).expect("frame");
    View {
        frame: Some(Arc::new(frame)),
        mark: Some(Mark { x: 3.25, y: 2.5, diameter: 4.0, score: 0.9 }),
        ..View::default()
    }
}

#[test]
fn the_page_its_frame_and_its_state_are_served_and_nothing_else() {
    let panel = panel(None, short());
    let addr = panel.addr();
    let (status, page) = get(addr, "/");
    assert_eq!(status, 200);
    assert!(String::from_utf8_lossy(&page).contains(r#"id="mark""#));
    assert_eq!(get(addr, "/frame.png").0, 404, "no frame yet");
    assert_eq!(get(addr, "/state.json"), (200, br#"{"seq":0}"#.to_vec()));
    let seq = panel.handle().publish(view_with_frame());
    let (status, png) = get(addr, &format!("/frame.png?seq={seq}"));
    assert_eq!(status, 200);
    let decoded = vision_driver_camera::decode_image(&png, "the panel").expect("a PNG");
    assert_eq!((decoded.width(), decoded.height()), (8, 6));
    let (_, state) = get(addr, "/state.json");
    let state: serde_json::Value = serde_json::from_slice(&state).expect("JSON");
    assert_eq!((state["seq"].as_u64(), state["mark"]["x"].as_f64()), (Some(seq), Some(3.25)));
    for outside in ["/../../etc/passwd", "/page.html", "/src/page.html", "/frame.png/..", "//etc/passwd", "/%2e%2e/"] {
        assert_eq!(get(addr, outside).0, 404, "{outside}");
    }
    assert_eq!(get(addr, "/frame.png?seq=99").0, 404, "a frame not kept");
    for method in ["POST", "PUT", "DELETE"] {
        assert_eq!(send(addr, format!("{method} / HTTP/1.1\r\n\r\n").as_bytes()).0, 405, "{method}");
    }
    assert_eq!(send(addr, b"GET / HTTP/1.1\r\n\r\n".as_slice()).0, 200, "HEAD and GET only, no Host needed");
    let rebound = b"GET /frame.png HTTP/1.1\r\nHost: evil.example:8090\r\n\r\n";
    assert_eq!(send(addr, rebound).0, 403, "another site's name for 127.0.0.1");
}

#[test]
fn a_runs_fit_is_in_the_state_and_its_picture_served_as_svg() {
    let panel = panel(None, short());
    let addr = panel.addr();
    assert_eq!(get(addr, "/fit.svg").0, 404, "no fit yet");
    let fit = crate::Fit {
        title: "M282 rectangle fit, line 20".into(),
        line: 20,
        bound99: Some(0.002),
        unit: "in".into(),
        gcode: vec!["G68 X0 Y0 R0.1".into()],
        svg: Some(Arc::new("<svg xmlns=\"http://www.w3.org/2000/svg\"/>".into())),
        ..crate::Fit::default()
    };
    let seq = panel.handle().publish(View { fit: Some(fit), ..view_with_frame() });
    let (status, svg) = get(addr, &format!("/fit.svg?seq={seq}"));
    assert_eq!(status, 200);
    assert!(svg.starts_with(b"<svg"));
    let (_, state) = get(addr, "/state.json");
    let state: serde_json::Value = serde_json::from_slice(&state).expect("JSON");
    assert_eq!(state["fit"]["line"], 20);
    assert_eq!(state["fit"]["svg"], true);
    assert_eq!(state["fit"]["gcode"][0], "G68 X0 Y0 R0.1");
    assert_eq!(get(addr, "/fit.svg?seq=99").0, 404, "a fit not kept");
}

#[test]
fn with_a_token_only_the_token_opens_it() {
    let panel = panel(Some("s3cret"), short());
    let addr = panel.addr();
    assert_eq!(get(addr, "/").0, 401);
    assert_eq!(get(addr, "/?token=wrong").0, 401);
    assert_eq!(get(addr, "/?token=s3cret").0, 200);
    assert_eq!(send(addr, b"GET /state.json HTTP/1.1\r\nX-Panel-Token: s3cret\r\n\r\n").0, 200);
    assert_eq!(send(addr, b"GET /state.json HTTP/1.1\r\nAuthorization: Bearer s3cret\r\n\r\n").0, 200);
}

#[test]
fn an_oversized_or_malformed_request_is_refused_and_the_server_goes_on() {
    let panel = panel(None, short());
    let addr = panel.addr();
    let huge = format!("GET / HTTP/1.1\r\nX-Big: {}\r\n\r\n", "a".repeat(64 * 1024));
    assert_eq!(send(addr, huge.as_bytes()).0, 431);
    assert_eq!(send(addr, b"\x16\x03\x01 binary\r\n\r\n").0, 400);
    assert_eq!(get(addr, "/").0, 200);
}

#[test]
fn a_slow_client_is_dropped_at_the_deadline_and_others_are_served_meanwhile() {
    let panel = panel(None, short());
    let addr = panel.addr();
    let mut slow = TcpStream::connect(addr).expect("connect");
    slow.write_all(b"GET / HTTP/1.1\r\n").expect("half a head");
    assert_eq!(get(addr, "/").0, 200, "served while the slow one waits");
    slow.set_read_timeout(Some(Duration::from_secs(10))).expect("timeout");
    let start = Instant::now();
    let mut rest = Vec::new();
    let _ = slow.read_to_end(&mut rest);
    assert!(rest.is_empty(), "no answer to half a head");
    assert!(start.elapsed() < Duration::from_secs(5), "closed at the deadline, not at the test's timeout");
}

#[test]
fn clients_past_the_bound_get_503_and_their_places_come_back() {
    let limits = short();
    let panel = panel(None, limits);
    let addr = panel.addr();
    let idle: Vec<TcpStream> = (0..limits.max_clients).map(|_| TcpStream::connect(addr).expect("connect")).collect();
    std::thread::sleep(Duration::from_millis(50));
    assert_eq!(get(addr, "/").0, 503, "every place taken");
    drop(idle);
    // The idle ones are dropped at the head deadline at the latest.
    let start = Instant::now();
    while get(addr, "/").0 != 200 {
        assert!(start.elapsed() < Duration::from_secs(5), "the places never came back");
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn a_stalled_event_stream_never_blocks_publishing_and_is_dropped() {
    let limits = short();
    let panel = panel(None, limits);
    let addr = panel.addr();
    let handle = panel.handle();
    let mut stalled = TcpStream::connect(addr).expect("connect");
    stalled.write_all(b"GET /events HTTP/1.1\r\n\r\n").expect("send");
    // Views of ~1 MB of JSON each, published on: the socket's buffers fill and stay full.
    let big = View { params: vec![("p".into(), "x".repeat(1 << 20))], ..view_with_frame() };
    let start = Instant::now();
    loop {
        for _ in 0..10 {
            handle.publish(big.clone());
        }
        // Its place comes back once a write times out: a new stream is accepted.
        let mut s = TcpStream::connect(addr).expect("connect");
        s.set_read_timeout(Some(Duration::from_secs(2))).expect("timeout");
        s.write_all(b"GET /events HTTP/1.1\r\n\r\n").expect("send");
        let mut first = [0u8; 12];
        if s.read_exact(&mut first).is_ok() && &first == b"HTTP/1.1 200" {
            break;
        }
        assert!(start.elapsed() < Duration::from_secs(10), "the stalled stream was never dropped");
        std::thread::sleep(Duration::from_millis(50));
    }
    assert!(handle.seq() >= 10, "every publish returned while the client read nothing");
    drop(stalled);
}

#[test]
fn an_event_stream_sends_each_new_view() {
    let panel = panel(None, short());
    let handle = panel.handle();
    handle.publish(view_with_frame());
    let mut s = TcpStream::connect(panel.addr()).expect("connect");
    s.set_read_timeout(Some(Duration::from_secs(5))).expect("timeout");
    s.write_all(b"GET /events HTTP/1.1\r\n\r\n").expect("send");
    let mut seen = String::new();
    let mut buf = [0u8; 4096];
    let mut published = false;
    while !seen.contains("id: 2\n") {
        let n = s.read(&mut buf).expect("the stream goes on");
        seen.push_str(&String::from_utf8_lossy(&buf[..n]));
        if seen.contains("id: 1\n") && !published {
            handle.publish(View::default());
            published = true;
        }
    }
    assert!(seen.starts_with("HTTP/1.1 200 OK\r\nContent-Type: text/event-stream"), "{seen}");
    assert!(seen.contains(r#"data: {"#), "{seen}");
}
