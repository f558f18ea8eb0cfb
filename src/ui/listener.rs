//! The web view's listener: a cap on open connections and deadlines on each, so unfinished
//! requests cannot use up the process's file descriptors (which the emulator's own ports
//! need too).
//!
//! - At most [`Limits::max_connections`] connections are open; the next one is accepted only
//!   when one closes (meanwhile it waits in the kernel's backlog and costs no descriptor).
//! - A connection must be answered within [`Limits::request_timeout`] of the first byte of a
//!   request (or of being accepted): a client that sends its headers slowly, or nothing, is
//!   closed. Any byte written to the client (a response, a WebSocket state message) ends
//!   that wait, so a live page, which gets a state message every 20 ms, is never affected.
//! - A connection on which nothing moved either way for [`Limits::idle_timeout`] is closed
//!   (an idle keep-alive connection; browsers open a new one when they need it).

use std::future::Future as _;
use std::io;
use std::net::SocketAddr;
use std::pin::Pin;
use std::sync::Arc;
use std::task::{Context, Poll};
use std::time::Duration;

use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::{OwnedSemaphorePermit, Semaphore};
use tokio::time::{Instant, Sleep};

/// Caps and deadlines of the web view's connections.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Most connections open at once.
    pub max_connections: usize,
    /// Time from a request's first byte (or from the accept) to the first byte of its answer.
    pub request_timeout: Duration,
    /// Time without any byte either way after which a connection is closed.
    pub idle_timeout: Duration,
}

impl Default for Limits {
    /// 64 connections (a page uses one WebSocket and a few requests; several pages and
    /// scripts fit), 10 s to send a request (a browser on loopback takes milliseconds), 60 s
    /// idle.
    fn default() -> Self {
        Self {
            max_connections: 64,
            request_timeout: Duration::from_secs(10),
            idle_timeout: Duration::from_secs(60),
        }
    }
}

/// A TCP listener that applies [`Limits`].
pub struct LimitedListener {
    inner: TcpListener,
    slots: Arc<Semaphore>,
    limits: Limits,
}

impl LimitedListener {
    /// Wrap a bound listener.
    pub fn new(inner: TcpListener, limits: Limits) -> Self {
        Self {
            inner,
            slots: Arc::new(Semaphore::new(limits.max_connections.max(1))),
            limits,
        }
    }
}

impl axum::serve::Listener for LimitedListener {
    type Io = LimitedStream;
    type Addr = SocketAddr;

    async fn accept(&mut self) -> (Self::Io, Self::Addr) {
        loop {
            // Wait for a free slot before accepting: the connections beyond the cap wait in
            // the backlog instead of holding descriptors.
            let Ok(slot) = Arc::clone(&self.slots).acquire_owned().await else {
                // The semaphore is never closed; should it be, accept nothing more.
                return std::future::pending().await;
            };
            match self.inner.accept().await {
                Ok((stream, peer)) => return (LimitedStream::new(stream, slot, self.limits), peer),
                Err(error) => {
                    tracing::warn!(%error, "web view accept failed");
                    tokio::time::sleep(Duration::from_millis(50)).await;
                }
            }
        }
    }

    fn local_addr(&self) -> io::Result<Self::Addr> {
        self.inner.local_addr()
    }
}

/// One connection under [`Limits`]; its slot is freed when it is dropped.
pub struct LimitedStream {
    inner: TcpStream,
    _slot: OwnedSemaphorePermit,
    limits: Limits,
    /// When the request now awaiting an answer began (`None`: nothing awaits an answer).
    waiting_since: Option<Instant>,
    /// Last time a byte moved either way.
    active: Instant,
    timer: Pin<Box<Sleep>>,
}

impl LimitedStream {
    fn new(inner: TcpStream, slot: OwnedSemaphorePermit, limits: Limits) -> Self {
        let now = Instant::now();
        Self {
            inner,
            _slot: slot,
            limits,
            // A connection that sends nothing is a request that never completes.
            waiting_since: Some(now),
            active: now,
            timer: Box::pin(tokio::time::sleep_until(now + limits.request_timeout)),
        }
    }

    /// The earlier of the two deadlines.
    fn deadline(&self) -> Instant {
        let idle = self.active + self.limits.idle_timeout;
        match self.waiting_since {
            Some(since) => idle.min(since + self.limits.request_timeout),
            None => idle,
        }
    }

    /// `Err` once a deadline has passed; otherwise arms the timer to wake the reader then.
    fn check_deadline(&mut self, cx: &mut Context<'_>) -> io::Result<()> {
        let deadline = self.deadline();
        if self.timer.deadline() != deadline {
            self.timer.as_mut().reset(deadline);
        }
        match self.timer.as_mut().poll(cx) {
            Poll::Ready(()) => Err(io::Error::new(
                io::ErrorKind::TimedOut,
                "web view connection timed out (request too slow, or idle)",
            )),
            Poll::Pending => Ok(()),
        }
    }
}

impl AsyncRead for LimitedStream {
    fn poll_read(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        let this = self.get_mut();
        if let Err(e) = this.check_deadline(cx) {
            return Poll::Ready(Err(e));
        }
        let before = buf.filled().len();
        let polled = Pin::new(&mut this.inner).poll_read(cx, buf);
        if matches!(polled, Poll::Ready(Ok(()))) && buf.filled().len() > before {
            let now = Instant::now();
            this.active = now;
            this.waiting_since.get_or_insert(now);
        }
        polled
    }
}

impl AsyncWrite for LimitedStream {
    fn poll_write(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        data: &[u8],
    ) -> Poll<io::Result<usize>> {
        let this = self.get_mut();
        let polled = Pin::new(&mut this.inner).poll_write(cx, data);
        if matches!(polled, Poll::Ready(Ok(n)) if n > 0) {
            this.active = Instant::now();
            this.waiting_since = None;
        }
        polled
    }

    fn poll_flush(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.get_mut().inner).poll_flush(cx)
    }

    fn poll_shutdown(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.get_mut().inner).poll_shutdown(cx)
    }

    fn poll_write_vectored(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        bufs: &[io::IoSlice<'_>],
    ) -> Poll<io::Result<usize>> {
        let this = self.get_mut();
        let polled = Pin::new(&mut this.inner).poll_write_vectored(cx, bufs);
        if matches!(polled, Poll::Ready(Ok(n)) if n > 0) {
            this.active = Instant::now();
            this.waiting_since = None;
        }
        polled
    }

    fn is_write_vectored(&self) -> bool {
        self.inner.is_write_vectored()
    }
}
