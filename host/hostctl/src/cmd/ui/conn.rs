//! The connections of `hostctl ui`: the accept loop that hands each TCP connection to hyper
//! (HTTP/1.1, with upgrades for the WebSocket), with the limits that keep a long working
//! session's server small whatever clients do.
//!
//! Limits (docs/UI.md lists them):
//! - at most [`MAX_CONNECTIONS`] connections at once (HTTP and WebSocket alike); one more is
//!   answered `503` and closed;
//! - the request line and headers must arrive within [`HEADER_TIMEOUT`] of the connection
//!   opening or of the previous response (hyper's header-read timeout: a client that sends a
//!   partial header, or keeps an idle keep-alive connection, is dropped);
//! - a connection on which no byte moves either way for [`IDLE_TIMEOUT`] is dropped (a request
//!   body sent too slowly, a page that stopped reading its WebSocket; the WebSocket pings the
//!   page well within it, see [`super::ws`]), except while the server itself is working on
//!   one of its requests ([`Busy`]: a release test or a tune over `POST /api/cmd` may take
//!   minutes).
//!
//! Invariants: a connection's slot is held by its socket, so an upgraded WebSocket keeps its
//! slot until it closes; nothing here reads or answers a request (that is the router's).

use axum::Router;
use hyper::server::conn::http1;
use hyper_util::rt::{TokioIo, TokioTimer};
use hyper_util::service::TowerToHyperService;
use std::future::Future;
use std::io;
use std::pin::Pin;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use std::task::{Context, Poll};
use std::time::Duration;
use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::{OwnedSemaphorePermit, Semaphore};
use tokio::time::{Instant, Sleep};
use tower::ServiceExt as _;

/// Most connections served at once.
pub const MAX_CONNECTIONS: usize = 64;
/// Time allowed for a request's line and headers (from the connection or the previous answer).
pub const HEADER_TIMEOUT: Duration = Duration::from_secs(5);
/// A connection with no traffic either way for this long is closed.
pub const IDLE_TIMEOUT: Duration = Duration::from_secs(30);

/// Serves `router` on `listener` until `stop` completes, then gives open connections half a
/// second to finish.
///
/// # Errors
/// None so far: failed accepts (e.g. out of file descriptors) are retried after a pause.
pub async fn serve(
    listener: TcpListener,
    router: Router,
    stop: impl Future<Output = ()>,
) -> io::Result<()> {
    let slots = Arc::new(Semaphore::new(MAX_CONNECTIONS));
    tokio::pin!(stop);
    loop {
        let stream = tokio::select! {
            () = &mut stop => break,
            r = listener.accept() => match r {
                Ok((s, _)) => s,
                Err(_) => {
                    tokio::time::sleep(Duration::from_millis(50)).await;
                    continue;
                }
            },
        };
        match Arc::clone(&slots).try_acquire_owned() {
            Ok(slot) => {
                let busy = Busy::default();
                let io = Watched::new(stream, slot, busy.clone());
                tokio::spawn(connection(io, busy, router.clone()));
            }
            Err(_) => refuse(&stream),
        }
    }
    let end = Instant::now() + Duration::from_millis(500);
    while slots.available_permits() < MAX_CONNECTIONS && Instant::now() < end {
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    Ok(())
}

async fn connection(io: Watched, busy: Busy, router: Router) {
    // Each request carries its connection's `Busy`, for the handlers that work long.
    let svc = TowerToHyperService::new(router.map_request(
        move |mut req: axum::http::Request<hyper::body::Incoming>| {
            req.extensions_mut().insert(busy.clone());
            req
        },
    ));
    let _ = http1::Builder::new()
        .timer(TokioTimer::new())
        .header_read_timeout(HEADER_TIMEOUT)
        .serve_connection(TokioIo::new(io), svc)
        .with_upgrades()
        .await;
}

/// One connection too many: a best-effort `503` (never waiting for the client), then closed.
fn refuse(stream: &TcpStream) {
    let body = format!("503 Service Unavailable: more than {MAX_CONNECTIONS} connections\n");
    let head = format!(
        "HTTP/1.1 503 Service Unavailable\r\nContent-Type: text/plain; charset=utf-8\r\n\
         Content-Length: {}\r\nConnection: close\r\n\r\n{body}",
        body.len()
    );
    let _ = stream.try_write(head.as_bytes());
}

/// Whether the server is working on a request of this connection (a request extension):
/// the connection is not idle meanwhile.
#[derive(Debug, Clone, Default)]
pub struct Busy(Arc<AtomicUsize>);

/// Held while a handler works; see [`Busy::hold`].
#[derive(Debug)]
pub struct BusyGuard(Arc<AtomicUsize>);

impl Busy {
    /// Marks the connection busy until the guard is dropped.
    #[must_use]
    pub fn hold(&self) -> BusyGuard {
        self.0.fetch_add(1, Ordering::Relaxed);
        BusyGuard(Arc::clone(&self.0))
    }

    fn active(&self) -> bool {
        self.0.load(Ordering::Relaxed) > 0
    }
}

impl Drop for BusyGuard {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::Relaxed);
    }
}

/// A socket that fails with `TimedOut` once no byte has moved for [`IDLE_TIMEOUT`] (unless the
/// server is busy with one of its requests), and holds its connection slot until dropped.
#[derive(Debug)]
pub struct Watched {
    io: TcpStream,
    deadline: Pin<Box<Sleep>>,
    busy: Busy,
    _slot: OwnedSemaphorePermit,
}

impl Watched {
    fn new(io: TcpStream, slot: OwnedSemaphorePermit, busy: Busy) -> Self {
        let _ = io.set_nodelay(true);
        Self {
            io,
            deadline: Box::pin(tokio::time::sleep(IDLE_TIMEOUT)),
            busy,
            _slot: slot,
        }
    }

    fn moved(&mut self) {
        self.deadline.as_mut().reset(Instant::now() + IDLE_TIMEOUT);
    }

    /// `Pending` unless the idle time ran out (then the error).
    fn pending<T>(&mut self, cx: &mut Context<'_>) -> Poll<io::Result<T>> {
        if self.deadline.as_mut().poll(cx).is_pending() {
            return Poll::Pending;
        }
        if self.busy.active() {
            self.moved();
            // Registers the new deadline's wake-up (it is in the future: pending).
            let _ = self.deadline.as_mut().poll(cx);
            return Poll::Pending;
        }
        Poll::Ready(Err(io::Error::new(
            io::ErrorKind::TimedOut,
            "no traffic within the idle timeout",
        )))
    }
}

impl AsyncRead for Watched {
    fn poll_read(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        let me = self.get_mut();
        let before = buf.filled().len();
        match Pin::new(&mut me.io).poll_read(cx, buf) {
            Poll::Ready(r) => {
                if buf.filled().len() > before {
                    me.moved();
                }
                Poll::Ready(r)
            }
            Poll::Pending => me.pending(cx),
        }
    }
}

impl AsyncWrite for Watched {
    fn poll_write(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &[u8],
    ) -> Poll<io::Result<usize>> {
        let me = self.get_mut();
        match Pin::new(&mut me.io).poll_write(cx, buf) {
            Poll::Ready(r) => {
                if matches!(r, Ok(n) if n > 0) {
                    me.moved();
                }
                Poll::Ready(r)
            }
            Poll::Pending => me.pending(cx),
        }
    }

    fn poll_flush(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        let me = self.get_mut();
        match Pin::new(&mut me.io).poll_flush(cx) {
            Poll::Ready(r) => Poll::Ready(r),
            Poll::Pending => me.pending(cx),
        }
    }

    fn poll_shutdown(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.get_mut().io).poll_shutdown(cx)
    }
}
