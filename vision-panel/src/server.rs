//! [`Panel`]: the HTTP/1.1 server on `std::net`. One thread accepts; each connection gets a
//! thread of its own, at most [`Limits::max_clients`] at a time, and answers one request
//! ([`crate::routes`]). Every read and write has a deadline, so a slow or stalled client
//! costs its own thread until then, and nothing else.

use std::io::{self, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use crate::access::Access;
use crate::{PanelError, PanelHandle};

/// The panel's bounds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Connections served at once; one more is answered `503` and closed.
    pub max_clients: usize,
    /// Of those, event streams (`/events`) open at once.
    pub max_streams: usize,
    /// Time a client has to send its whole request head.
    pub head_deadline: Duration,
    /// Time one write may take before the client is dropped (a stalled browser).
    pub write_timeout: Duration,
    /// Interval of the comment an idle event stream sends to find a closed client.
    pub keepalive: Duration,
}

impl Default for Limits {
    fn default() -> Limits {
        Limits {
            max_clients: 16,
            max_streams: 8,
            head_deadline: Duration::from_secs(5),
            write_timeout: Duration::from_secs(5),
            keepalive: Duration::from_secs(15),
        }
    }
}

/// What every connection thread shares.
#[derive(Debug)]
pub(crate) struct Shared {
    pub(crate) access: Access,
    pub(crate) limits: Limits,
    pub(crate) handle: PanelHandle,
    pub(crate) clients: AtomicUsize,
    pub(crate) streams: AtomicUsize,
}

/// A running panel; dropping it stops accepting and ends the event streams.
#[derive(Debug)]
pub struct Panel {
    addr: SocketAddr,
    shared: Arc<Shared>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl Panel {
    /// Serves the panel on `listen` with the default [`Limits`]; `token`, when given, is
    /// required of every request.
    ///
    /// # Errors
    /// [`PanelError::TokenRequired`] off loopback without a token, [`PanelError::BadToken`], and
    /// [`PanelError::Bind`].
    pub fn bind(listen: SocketAddr, token: Option<&str>) -> Result<Panel, PanelError> {
        Panel::with_limits(listen, token, Limits::default())
    }

    /// [`Panel::bind`] with other bounds.
    ///
    /// # Errors
    /// As [`Panel::bind`].
    pub fn with_limits(listen: SocketAddr, token: Option<&str>, limits: Limits) -> Result<Panel, PanelError> {
        let access = Access::new(listen, token)?;
        let bind = |e: io::Error| PanelError::Bind { listen, reason: e.to_string() };
        let listener = TcpListener::bind(listen).map_err(bind)?;
        // Non-blocking accept, polled, so the thread notices the stop flag.
        listener.set_nonblocking(true).map_err(bind)?;
        let addr = listener.local_addr().map_err(bind)?;
        let shared = Arc::new(Shared {
            access,
            limits,
            handle: PanelHandle::default(),
            clients: AtomicUsize::new(0),
            streams: AtomicUsize::new(0),
        });
        let stop = Arc::new(AtomicBool::new(false));
        let (shared2, stop2) = (shared.clone(), stop.clone());
        let thread = std::thread::Builder::new()
            .name("panel".into())
            .spawn(move || accept(&listener, &shared2, &stop2))
            .map_err(bind)?;
        Ok(Panel { addr, shared, stop, thread: Some(thread) })
    }

    /// Where the views go: publish to it from any thread.
    #[must_use]
    pub fn handle(&self) -> PanelHandle {
        self.shared.handle.clone()
    }

    /// The address it listens on.
    #[must_use]
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// The page's address, `http://<addr>/`.
    #[must_use]
    pub fn url(&self) -> String {
        format!("http://{}/", self.addr)
    }
}

impl Drop for Panel {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        self.shared.handle.close();
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn accept(listener: &TcpListener, shared: &Arc<Shared>, stop: &AtomicBool) {
    while !stop.load(Ordering::SeqCst) {
        match listener.accept() {
            Ok((stream, _)) => admit(stream, shared),
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => std::thread::sleep(Duration::from_millis(5)),
            Err(_) => std::thread::sleep(Duration::from_millis(20)),
        }
    }
}

/// Serves `stream` on a thread of its own, or answers `503` when the panel has as many
/// clients as it serves.
fn admit(mut stream: TcpStream, shared: &Arc<Shared>) {
    if shared.clients.fetch_add(1, Ordering::SeqCst) >= shared.limits.max_clients {
        shared.clients.fetch_sub(1, Ordering::SeqCst);
        // A short answer, sent without waiting on the client.
        let _ = stream.set_nonblocking(true);
        let _ = stream.write_all(b"HTTP/1.1 503 Service Unavailable\r\nContent-Length: 0\r\nConnection: close\r\n\r\n");
        return;
    }
    let shared2 = shared.clone();
    let spawned = std::thread::Builder::new().name("panel-client".into()).spawn(move || {
        let _place = Counted(&shared2.clients);
        let _ = crate::routes::answer(stream, &shared2);
    });
    if spawned.is_err() {
        shared.clients.fetch_sub(1, Ordering::SeqCst);
    }
}

/// Gives back one place of a count when dropped.
pub(crate) struct Counted<'a>(pub(crate) &'a AtomicUsize);

impl Drop for Counted<'_> {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::SeqCst);
    }
}
