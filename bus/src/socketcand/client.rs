//! The socketcand client: a [`CanBus`] over TCP.
//!
//! `connect` does the handshake (`< hi >`, `< open NAME >`, `< rawmode >`), then two tasks
//! run the connection: a reader that turns `< frame … >` elements into received frames (with
//! the server's timestamps) and a writer that sends queued frames as `< send … >`. When the
//! server closes the connection, `recv` and `send` return [`BusError::Closed`] (the reason is
//! logged with the server's address).

use std::time::Duration;

use async_trait::async_trait;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::tcp::{OwnedReadHalf, OwnedWriteHalf};
use tokio::net::TcpStream;
use tokio::sync::{mpsc, watch, Mutex as AsyncMutex};
use tokio::task::AbortHandle;

use super::protocol::{self, Command, Element, Framer, Reply};
use crate::{BusError, CanBus, CanFrame, ReceivedFrame};

/// How long each handshake step may take.
const HANDSHAKE_TIMEOUT: Duration = Duration::from_secs(5);
/// Frames queued for sending before `send` reports [`BusError::TxQueueFull`].
const TX_QUEUE: usize = 256;
/// Received frames buffered before the reader stops reading (TCP then slows the server,
/// which drops frames for this client rather than wait).
const RX_QUEUE: usize = 8192;

/// Why [`SocketcandBus::connect`] failed.
#[derive(Debug, thiserror::Error)]
pub enum ConnectError {
    /// The TCP connection could not be made (nothing listening, unreachable host, bad name).
    #[error("cannot connect to the socketcand server at {addr}: {source}")]
    Connect {
        /// The address given.
        addr: String,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The server answered something else than the handshake expects.
    #[error("socketcand server at {addr}: expected {expected}, got {got:?}")]
    Handshake {
        /// The address given.
        addr: String,
        /// The element expected.
        expected: &'static str,
        /// What came instead.
        got: String,
    },
    /// The server closed the connection during the handshake.
    #[error("socketcand server at {addr} closed the connection while waiting for {expected}")]
    Closed {
        /// The address given.
        addr: String,
        /// The element expected.
        expected: &'static str,
    },
    /// The server did not answer a handshake step in time.
    #[error("socketcand server at {addr} sent no {expected} within {waited:?}")]
    Timeout {
        /// The address given.
        addr: String,
        /// The element expected.
        expected: &'static str,
        /// How long we waited.
        waited: Duration,
    },
    /// Reading or writing failed during the handshake.
    #[error("I/O error with the socketcand server at {addr}: {source}")]
    Io {
        /// The address given.
        addr: String,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
}

/// A bus on a socketcand server, in raw mode.
pub struct SocketcandBus {
    name: String,
    rx: AsyncMutex<mpsc::Receiver<ReceivedFrame>>,
    tx: mpsc::Sender<CanFrame>,
    closed: watch::Sender<bool>,
    tasks: [AbortHandle; 2],
}

impl std::fmt::Debug for SocketcandBus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SocketcandBus")
            .field("name", &self.name)
            .finish_non_exhaustive()
    }
}

/// The handshake's read side.
struct Handshake<'a> {
    stream: &'a mut TcpStream,
    framer: Framer,
    addr: &'a str,
}

impl Handshake<'_> {
    async fn send(&mut self, command: &Command) -> Result<(), ConnectError> {
        let text = protocol::format_command(command);
        self.stream
            .write_all(text.as_bytes())
            .await
            .map_err(|source| ConnectError::Io {
                addr: self.addr.to_owned(),
                source,
            })
    }

    async fn expect(&mut self, wanted: Reply, expected: &'static str) -> Result<(), ConnectError> {
        let addr = || self.addr.to_owned();
        let mut buf = [0u8; 1024];
        loop {
            if let Some(element) = self.framer.next_element() {
                let text = match element {
                    Element::Complete(text) => text,
                    Element::Garbage(text) => text,
                };
                return match protocol::parse_reply(&text) {
                    Ok(reply) if reply == wanted => Ok(()),
                    _ => Err(ConnectError::Handshake {
                        addr: addr(),
                        expected,
                        got: text,
                    }),
                };
            }
            let read = tokio::time::timeout(HANDSHAKE_TIMEOUT, self.stream.read(&mut buf)).await;
            match read {
                Err(_) => {
                    return Err(ConnectError::Timeout {
                        addr: addr(),
                        expected,
                        waited: HANDSHAKE_TIMEOUT,
                    })
                }
                Ok(Ok(0)) => {
                    return Err(ConnectError::Closed {
                        addr: addr(),
                        expected,
                    })
                }
                Ok(Ok(n)) => self.framer.push(&buf[..n]),
                Ok(Err(source)) => {
                    return Err(ConnectError::Io {
                        addr: addr(),
                        source,
                    })
                }
            }
        }
    }
}

impl SocketcandBus {
    /// Connect to the server at `addr` (`HOST:PORT`), open `bus_name` and switch to raw
    /// mode. Must be called inside a tokio runtime.
    pub async fn connect(addr: &str, bus_name: &str) -> Result<Self, ConnectError> {
        let mut stream =
            TcpStream::connect(addr)
                .await
                .map_err(|source| ConnectError::Connect {
                    addr: addr.to_owned(),
                    source,
                })?;
        if let Err(error) = stream.set_nodelay(true) {
            tracing::debug!(addr, %error, "cannot set TCP_NODELAY");
        }
        let mut handshake = Handshake {
            stream: &mut stream,
            framer: Framer::default(),
            addr,
        };
        handshake.expect(Reply::Hi, "< hi >").await?;
        handshake.send(&Command::Open(bus_name.to_owned())).await?;
        handshake.expect(Reply::Ok, "< ok > to < open >").await?;
        handshake.send(&Command::RawMode).await?;
        handshake.expect(Reply::Ok, "< ok > to < rawmode >").await?;
        // Tells the server we have read that `< ok >`, so it forwards frames at once instead
        // of after its grace period (see `ServerConfig::rawmode_grace`). The answer is ignored.
        handshake.send(&Command::Echo).await?;
        // Frames that followed the last `< ok >` in the same read are still in the framer.
        let framer = handshake.framer;
        let name = format!("socketcand {addr} {bus_name}");
        let (read, write) = stream.into_split();
        let (rx_tx, rx) = mpsc::channel(RX_QUEUE);
        let (tx, tx_rx) = mpsc::channel(TX_QUEUE);
        let reader = tokio::spawn(read_loop(read, framer, rx_tx, name.clone()));
        let writer = tokio::spawn(write_loop(write, tx_rx, name.clone()));
        tracing::debug!(bus = %name, "socketcand connected");
        Ok(Self {
            name,
            rx: AsyncMutex::new(rx),
            tx,
            closed: watch::Sender::new(false),
            tasks: [reader.abort_handle(), writer.abort_handle()],
        })
    }
}

async fn read_loop(
    mut read: OwnedReadHalf,
    mut framer: Framer,
    frames: mpsc::Sender<ReceivedFrame>,
    name: String,
) {
    let mut buf = vec![0u8; 16 * 1024];
    loop {
        while let Some(element) = framer.next_element() {
            let text = match element {
                Element::Complete(text) => text,
                Element::Garbage(text) => {
                    tracing::debug!(bus = %name, text, "text outside < > from the server");
                    continue;
                }
            };
            match protocol::parse_reply(&text) {
                Ok(Reply::Frame { frame, timestamp }) => {
                    if frames
                        .send(ReceivedFrame { frame, timestamp })
                        .await
                        .is_err()
                    {
                        return;
                    }
                }
                Ok(Reply::Error(message)) => {
                    tracing::warn!(bus = %name, message, "socketcand server reports an error");
                }
                Ok(other) => tracing::debug!(bus = %name, ?other, "socketcand reply"),
                Err(error) => {
                    tracing::debug!(bus = %name, %error, text, "undecodable element skipped");
                }
            }
        }
        match read.read(&mut buf).await {
            Ok(0) => {
                tracing::warn!(bus = %name, "socketcand server closed the connection");
                return;
            }
            Ok(n) => framer.push(&buf[..n]),
            Err(error) => {
                tracing::warn!(bus = %name, %error, "reading from the socketcand server failed");
                return;
            }
        }
    }
}

async fn write_loop(mut write: OwnedWriteHalf, mut frames: mpsc::Receiver<CanFrame>, name: String) {
    let mut batch = String::with_capacity(4096);
    while let Some(frame) = frames.recv().await {
        batch.clear();
        batch.push_str(&protocol::format_send(&frame));
        while batch.len() < 16 * 1024 {
            match frames.try_recv() {
                Ok(more) => batch.push_str(&protocol::format_send(&more)),
                Err(_) => break,
            }
        }
        if let Err(error) = write.write_all(batch.as_bytes()).await {
            tracing::warn!(bus = %name, %error, "writing to the socketcand server failed");
            return;
        }
    }
}

#[async_trait]
impl CanBus for SocketcandBus {
    async fn send(&self, frame: CanFrame) -> Result<(), BusError> {
        if *self.closed.borrow() {
            return Err(BusError::Closed);
        }
        if frame.is_fd() {
            return Err(BusError::Io {
                iface: self.name.clone(),
                source: std::io::Error::new(
                    std::io::ErrorKind::Unsupported,
                    format!(
                        "CAN FD frame {} ({} bytes) not sent: the socketcand protocol carries \
                         classic CAN frames only",
                        frame.id(),
                        frame.len()
                    ),
                ),
            });
        }
        match self.tx.try_send(frame) {
            Ok(()) => Ok(()),
            Err(mpsc::error::TrySendError::Full(_)) => {
                Err(BusError::TxQueueFull { capacity: TX_QUEUE })
            }
            Err(mpsc::error::TrySendError::Closed(_)) => Err(BusError::Closed),
        }
    }

    async fn recv(&self) -> Result<ReceivedFrame, BusError> {
        let mut closed = self.closed.subscribe();
        let receive = async {
            let mut rx = self.rx.lock().await;
            rx.recv().await.ok_or(BusError::Closed)
        };
        tokio::select! {
            received = receive => received,
            _ = closed.wait_for(|closed| *closed) => Err(BusError::Closed),
        }
    }

    async fn close(&self) {
        self.closed.send_replace(true);
        for task in &self.tasks {
            task.abort();
        }
    }

    fn name(&self) -> &str {
        &self.name
    }
}

impl Drop for SocketcandBus {
    fn drop(&mut self) {
        for task in &self.tasks {
            task.abort();
        }
    }
}
