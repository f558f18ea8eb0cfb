//! One client connection: the reader that splits and answers requests under the controller
//! lock, and the writer that writes each queued reply or event as its own write.

use std::net::SocketAddr;
use std::sync::Arc;

use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt};
use tokio::sync::{mpsc, watch};
use tokio::time::{sleep, sleep_until, Instant};

use super::tcp::admit;
use super::{lock, Activity, Outgoing, Shared, EVENT_HEADROOM, READ_CHUNK};
use crate::realman::firmware::{Answer, ClientId};
use crate::realman::framing::{Splitter, Unit, MAX_REQUEST_BYTES};
use bus::socketcand::http_guard::HttpGuard;

/// Serve one client until it disconnects, is dropped by a fault, or the emulator stops.
pub(super) async fn serve_connection<S>(shared: Arc<Shared>, stream: S, peer: SocketAddr)
where
    S: AsyncRead + AsyncWrite + Send + Unpin + 'static,
{
    let Some(client) = admit(&shared, peer) else {
        drop(stream);
        return;
    };
    let id = client.id;
    let (reader, writer) = tokio::io::split(stream);
    let writer_task = tokio::spawn(write_loop(
        Arc::clone(&shared),
        writer,
        client.rx,
        client.kill.clone(),
        client.activity.clone(),
    ));
    let connection = Connection {
        shared: &shared,
        id,
        tx: client.tx,
        kill: client.kill,
        activity: client.activity,
    };
    let reason = connection.read_loop(reader).await;
    lock(&shared.clients).remove(&id);
    lock(&shared.core).disconnect(id);
    let _ = writer_task.await;
    tracing::info!(%peer, client = id, reason, "Realman client disconnected");
}

/// Why a wait inside the reader ended early.
enum Interrupted {
    /// The connection must end, for this reason.
    End(&'static str),
}

/// The reading side of one connection.
struct Connection<'a> {
    shared: &'a Shared,
    id: ClientId,
    tx: mpsc::Sender<Outgoing>,
    kill: watch::Receiver<Option<&'static str>>,
    activity: Activity,
}

impl Connection<'_> {
    /// Run `work` unless the connection is killed, the emulator stops or the connection has
    /// been idle (no byte either way) for the idle timeout.
    async fn guarded<T>(
        &mut self,
        work: impl std::future::Future<Output = T>,
    ) -> Result<T, Interrupted> {
        let mut stop = self.shared.stop.clone();
        tokio::pin!(work);
        loop {
            let idle_at = self
                .shared
                .idle_timeout
                .and_then(|t| self.activity.last().checked_add(t));
            let idle = async {
                match idle_at {
                    Some(at) => sleep_until(at).await,
                    None => std::future::pending().await,
                }
            };
            tokio::select! {
                out = &mut work => return Ok(out),
                _ = self.kill.changed() => {
                    let reason = (*self.kill.borrow()).unwrap_or("dropped");
                    return Err(Interrupted::End(reason));
                }
                _ = stop.changed() => return Err(Interrupted::End("emulator stopped")),
                _ = idle => {
                    // The writer may have been active meanwhile: look again.
                    let idle_until = self
                        .shared
                        .idle_timeout
                        .and_then(|t| self.activity.last().checked_add(t));
                    if idle_until.is_some_and(|at| at <= Instant::now()) {
                        lock(&self.shared.stats).idle_closed += 1;
                        return Err(Interrupted::End("idle timeout"));
                    }
                }
            }
        }
    }

    async fn read_loop<R: AsyncRead + Unpin>(mut self, mut reader: R) -> &'static str {
        let mut guard = HttpGuard::new();
        let mut splitter = Splitter::new(MAX_REQUEST_BYTES);
        let mut buf = vec![0u8; READ_CHUNK];
        let mut units = Vec::new();
        let id = self.id;
        loop {
            let n = match self.guarded(reader.read(&mut buf)).await {
                Ok(Ok(0)) => return "peer closed",
                Ok(Ok(n)) => n,
                Ok(Err(_)) => return "read error",
                Err(Interrupted::End(reason)) => return reason,
            };
            self.activity.touch();
            // The only way from the socket to the splitter: nothing of an HTTP request runs.
            let clean = match guard.admit(&buf[..n]) {
                Ok(clean) => clean,
                Err(refused) => {
                    lock(&self.shared.stats).http_refused += 1;
                    tracing::warn!(client = id, %refused, "Realman emulator closes a connection that speaks HTTP (a web page's request?)");
                    return "HTTP request";
                }
            };
            if let Err(e) = splitter.feed(clean, &mut units) {
                lock(&self.shared.stats).oversize += 1;
                tracing::warn!(client = id, error = %e, "Realman emulator closes a connection");
                return "request too long";
            }
            for unit in std::mem::take(&mut units) {
                let Unit::Object(bytes) = unit else {
                    handle_junk(self.shared, id, &unit);
                    continue;
                };
                // Take the request only while the queue has room for its reply and the
                // headroom for events; meanwhile this client is not read (D3: a client that
                // never reads its replies used to grow the process without bound).
                let tx = self.tx.clone();
                let permits = match self.guarded(tx.reserve_many(EVENT_HEADROOM + 1)).await {
                    Ok(Ok(permits)) => permits,
                    Ok(Err(_)) => return "writer stopped",
                    Err(Interrupted::End(reason)) => return reason,
                };
                let mut permits = permits;
                let Some(permit) = permits.next() else {
                    return "writer stopped";
                };
                drop(permits);
                handle_request(self.shared, id, &bytes, permit);
            }
        }
    }
}

fn handle_junk(shared: &Shared, id: ClientId, unit: &Unit) {
    lock(&shared.stats).malformed += 1;
    let len = match unit {
        Unit::Object(bytes) | Unit::Junk(bytes) => bytes.len(),
    };
    tracing::debug!(
        client = id,
        len,
        "Realman emulator ignores bytes outside a JSON object"
    );
}

/// Answer one request; its reply (if any) goes out through `permit`, reserved beforehand.
fn handle_request(shared: &Shared, id: ClientId, bytes: &[u8], permit: mpsc::Permit<'_, Outgoing>) {
    let request: serde_json::Value = match serde_json::from_slice(bytes) {
        Ok(v) => v,
        Err(e) => {
            lock(&shared.stats).malformed += 1;
            tracing::debug!(client = id, error = %e, "Realman emulator ignores malformed JSON");
            return;
        }
    };
    let answer = lock(&shared.core).handle(id, &request);
    match answer {
        Answer::Reply(text) => permit.send(Outgoing { text }),
        Answer::Silent => {}
        Answer::Unknown => {
            lock(&shared.stats).unknown += 1;
            let command = request.get("command").map(ToString::to_string);
            tracing::debug!(
                client = id,
                command,
                "Realman emulator ignores an unknown command"
            );
        }
    }
    // A command can end a move at once (disable, power off): its event follows the reply.
    route_events(shared);
}

/// Hand the controller's events to their clients' writers.
pub(super) fn route_events(shared: &Shared) {
    let events = lock(&shared.core).take_events();
    if events.is_empty() {
        return;
    }
    let clients = lock(&shared.clients);
    for event in events {
        let Some(client) = clients.get(&event.to) else {
            continue;
        };
        match client.tx.try_send(Outgoing { text: event.text }) {
            Ok(()) | Err(mpsc::error::TrySendError::Closed(_)) => {}
            Err(mpsc::error::TrySendError::Full(_)) => {
                // The reader keeps EVENT_HEADROOM free: this client has not read for a while.
                if !client.ending() {
                    lock(&shared.stats).slow_dropped += 1;
                    tracing::warn!(peer = %client.peer, client = event.to, "Realman client dropped: it does not read (no room for an event)");
                }
                client.end("not reading (queue full)");
            }
        }
    }
}

async fn write_loop<W: AsyncWrite + Unpin>(
    shared: Arc<Shared>,
    mut writer: W,
    mut rx: mpsc::Receiver<Outgoing>,
    mut kill: watch::Receiver<Option<&'static str>>,
    activity: Activity,
) {
    loop {
        let msg = tokio::select! {
            m = rx.recv() => match m {
                Some(m) => m,
                None => break,
            },
            _ = kill.changed() => break,
        };
        let (delay, truncate) = {
            let mut wire = lock(&shared.wire);
            let truncate = wire.truncate_next > 0;
            if truncate {
                wire.truncate_next -= 1;
            }
            (wire.reply_delay, truncate)
        };
        if let Some(d) = delay {
            sleep(d).await;
        }
        let mut text = msg.text;
        if truncate {
            let mut cut = text.len() / 2;
            while !text.is_char_boundary(cut) {
                cut -= 1;
            }
            text.truncate(cut);
        }
        text.push_str("\r\n");
        let written = async {
            writer.write_all(text.as_bytes()).await?;
            writer.flush().await
        };
        let written = tokio::select! {
            w = written => w,
            // A peer that does not read must not keep the writer (and the slot) for ever.
            _ = kill.changed() => break,
        };
        if written.is_err() {
            // The peer went away mid-reply; the reader notices and cleans up.
            break;
        }
        activity.touch();
    }
    let _ = writer.shutdown().await;
}
