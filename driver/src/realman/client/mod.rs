//! The async Realman client: one reader task per connection, requests paired with replies by
//! tag, blocking moves completed by arrival events.

mod commands;
mod io;
mod link;
mod peripherals;
mod state;

use std::sync::{Arc, Mutex};
use std::time::Duration;

use tokio::io::{AsyncRead, AsyncWrite, AsyncWriteExt};
use tokio::net::TcpStream;
use tokio::sync::broadcast;
use tokio::task::JoinHandle;

use super::codec::decode::{result_flag, Body};
use super::codec::splitter::DEFAULT_MAX_FRAME;
use super::codec::types::{Arrival, Device};
use super::codec::{Expect, Message, Request};
use super::error::RealmanError;
use link::{Delivery, Shared};

pub use commands::Handshake;
pub use state::StateFeed;

/// Client settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ClientConfig {
    /// How long to wait for a reply (the vendor SDK's default is 500 ms).
    pub reply_timeout: Duration,
    /// How long a blocking move may take to report arrival.
    pub motion_timeout: Duration,
    /// Longest accepted message, bytes.
    pub max_frame: usize,
    /// After a reply timeout, how long a reply with the same tag is taken to be the late
    /// answer (and dropped) rather than the answer to a newer request.
    pub late_reply_window: Duration,
}

impl Default for ClientConfig {
    fn default() -> Self {
        Self {
            reply_timeout: Duration::from_millis(500),
            motion_timeout: Duration::from_secs(120),
            max_frame: DEFAULT_MAX_FRAME,
            late_reply_window: Duration::from_secs(2),
        }
    }
}

type Writer = Box<dyn AsyncWrite + Send + Unpin>;

/// A connection to one Realman controller. Cheap to clone; clones share the connection.
#[derive(Clone)]
pub struct RealmanClient {
    inner: Arc<Inner>,
}

struct Inner {
    config: ClientConfig,
    shared: Arc<Shared>,
    writer: tokio::sync::Mutex<Option<Writer>>,
    reader: Mutex<Option<JoinHandle<()>>>,
    addr: Option<String>,
}

impl Drop for Inner {
    fn drop(&mut self) {
        if let Some(h) = self.reader.get_mut().ok().and_then(Option::take) {
            h.abort();
        }
    }
}

impl RealmanClient {
    /// Connects over TCP (the controller listens on port 8080).
    pub async fn connect(addr: &str, config: ClientConfig) -> Result<Self, RealmanError> {
        let stream = tcp(addr).await?;
        let client = Self::build(config, Some(addr.to_string()));
        client.attach(stream).await;
        Ok(client)
    }

    /// Runs over any byte stream (for example one end of `tokio::io::duplex` in virtual time).
    pub async fn from_stream<S>(stream: S, config: ClientConfig) -> Self
    where
        S: AsyncRead + AsyncWrite + Send + 'static,
    {
        let client = Self::build(config, None);
        client.attach(stream).await;
        client
    }

    fn build(config: ClientConfig, addr: Option<String>) -> Self {
        Self {
            inner: Arc::new(Inner {
                config,
                shared: Shared::new(),
                writer: tokio::sync::Mutex::new(None),
                reader: Mutex::new(None),
                addr,
            }),
        }
    }

    /// Replaces the connection: outstanding requests fail with `Disconnected`.
    async fn attach<S>(&self, stream: S)
    where
        S: AsyncRead + AsyncWrite + Send + 'static,
    {
        let (rd, wr) = tokio::io::split(stream);
        let mut writer = self.inner.writer.lock().await;
        let old = self
            .inner
            .reader
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .take();
        if let Some(h) = old {
            h.abort();
        }
        self.inner.shared.fail_all();
        *writer = Some(Box::new(wr));
        self.inner.shared.connected.send_replace(true);
        let task = tokio::spawn(link::reader(
            rd,
            self.inner.shared.clone(),
            self.inner.config.max_frame,
        ));
        *self.inner.reader.lock().unwrap_or_else(|p| p.into_inner()) = Some(task);
    }

    /// Opens a new TCP connection to the address this client was created with.
    pub async fn reconnect(&self) -> Result<(), RealmanError> {
        let addr = self.inner.addr.as_deref().ok_or(RealmanError::NoAddress)?;
        let stream = tcp(addr).await?;
        self.attach(stream).await;
        Ok(())
    }

    /// Continues over a new byte stream (reconnect in virtual time).
    pub async fn reconnect_with<S>(&self, stream: S)
    where
        S: AsyncRead + AsyncWrite + Send + 'static,
    {
        self.attach(stream).await;
    }

    /// True while the connection's reader is running.
    pub fn is_connected(&self) -> bool {
        *self.inner.shared.connected.borrow()
    }

    /// The settings in use.
    pub fn config(&self) -> &ClientConfig {
        &self.inner.config
    }

    /// Arrival events (`current_trajectory_state`) as they come.
    pub fn arrivals(&self) -> broadcast::Receiver<(u64, Arrival)> {
        self.inner.shared.arrivals.subscribe()
    }

    /// Other unsolicited notices (`program_run_finish`, …).
    pub fn notices(&self) -> broadcast::Receiver<Message> {
        self.inner.shared.notices.subscribe()
    }

    /// How many received messages could not be decoded.
    pub fn malformed_count(&self) -> u64 {
        self.inner
            .shared
            .malformed
            .load(std::sync::atomic::Ordering::Relaxed)
    }

    async fn write(&self, req: &Request) -> Result<(), RealmanError> {
        let mut guard = self.inner.writer.lock().await;
        let command = req.command;
        let w = guard
            .as_mut()
            .ok_or(RealmanError::Disconnected { command })?;
        let result = async {
            w.write_all(req.wire.as_bytes()).await?;
            w.flush().await
        }
        .await;
        result.map_err(|source| match source.kind() {
            std::io::ErrorKind::BrokenPipe | std::io::ErrorKind::ConnectionReset => {
                RealmanError::Disconnected { command }
            }
            _ => RealmanError::Io { command, source },
        })
    }

    /// Sends a request and waits for its reply; returns the reply's stream sequence number and
    /// body. Requests that expect nothing return `(0, empty)` once written.
    pub(crate) async fn call(&self, req: &Request) -> Result<(u64, Body), RealmanError> {
        let command = req.command;
        let Some(tag) = req.expect.tag() else {
            self.write(req).await?;
            return Ok((0, Body::new()));
        };
        // Register before writing so a fast reply cannot slip past.
        let (id, rx) = self.inner.shared.wait_for(tag);
        if let Err(e) = self.write(req).await {
            self.inner.shared.forget(id);
            return Err(e);
        }
        let after = self.inner.config.reply_timeout;
        match tokio::time::timeout(after, rx).await {
            Err(_) => {
                let until = tokio::time::Instant::now() + self.inner.config.late_reply_window;
                self.inner.shared.timed_out(id, tag, until);
                Err(RealmanError::Timeout { command, after })
            }
            Ok(Err(_)) | Ok(Ok(Delivery::Disconnected)) => {
                Err(RealmanError::Disconnected { command })
            }
            Ok(Ok(Delivery::Malformed { reason })) => {
                Err(RealmanError::Malformed { command, reason })
            }
            Ok(Ok(Delivery::Reply { seq, body })) => Ok((seq, body)),
        }
    }

    /// Sends a query and decodes its reply with `decode`.
    pub(crate) async fn query<T>(
        &self,
        req: Request,
        decode: impl FnOnce(&Body) -> Result<T, super::codec::DecodeError>,
    ) -> Result<T, RealmanError> {
        let (_, body) = self.call(&req).await?;
        decode(&body).map_err(|e| RealmanError::Malformed {
            command: req.command,
            reason: e.to_string(),
        })
    }

    /// Sends a setter and checks its result flag; returns the reply's sequence number.
    pub(crate) async fn set(&self, req: Request) -> Result<u64, RealmanError> {
        let (seq, body) = self.call(&req).await?;
        let Expect::Flag { key, .. } = req.expect else {
            return Ok(seq);
        };
        let command = req.command;
        match result_flag(&body, key) {
            Ok(true) => Ok(seq),
            Ok(false) => Err(RealmanError::Rejected {
                command,
                key: key.unwrap_or("result"),
            }),
            Err(e) => Err(RealmanError::Malformed {
                command,
                reason: e.to_string(),
            }),
        }
    }

    /// Sends a motion command; with `block`, waits for the device's final arrival event that
    /// follows the acknowledgement.
    pub(crate) async fn motion(
        &self,
        req: Request,
        device: Device,
        block: bool,
    ) -> Result<(), RealmanError> {
        // Subscribe before sending so an early event is buffered, and only accept events that
        // come after our own ack in the stream: an older move's late event is not ours.
        let mut events = self.inner.shared.arrivals.subscribe();
        let command = req.command;
        let ack_seq = self.set(req).await?;
        if !block {
            return Ok(());
        }
        let after = self.inner.config.motion_timeout;
        let wait = async {
            loop {
                match events.recv().await {
                    Ok((seq, a)) if seq > ack_seq && a.device == device => {
                        if !a.ok {
                            return Err(RealmanError::MotionFailed { command, device });
                        }
                        if !a.more_follow {
                            return Ok(());
                        }
                    }
                    Ok(_) | Err(broadcast::error::RecvError::Lagged(_)) => {}
                    Err(broadcast::error::RecvError::Closed) => {
                        return Err(RealmanError::Disconnected { command })
                    }
                }
            }
        };
        let disconnected = async {
            let mut rx = self.inner.shared.connected.subscribe();
            let _ = rx.wait_for(|c| !*c).await;
        };
        tokio::select! {
            r = tokio::time::timeout(after, wait) => r.unwrap_or(Err(RealmanError::MotionTimeout { command, after })),
            _ = disconnected => Err(RealmanError::Disconnected { command }),
        }
    }
}

async fn tcp(addr: &str) -> Result<TcpStream, RealmanError> {
    let stream = TcpStream::connect(addr)
        .await
        .map_err(|source| RealmanError::Connect {
            addr: addr.to_string(),
            source,
        })?;
    // Requests are small and latency matters more than packing.
    let _ = stream.set_nodelay(true);
    Ok(stream)
}
