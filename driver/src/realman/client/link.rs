//! The connection's reader task and the table of requests waiting for replies.
//!
//! Pairing is by reply tag, first come first served among requests with the same tag, so an
//! arrival event or push notice interleaved with replies is never taken for a reply.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use tokio::io::{AsyncRead, AsyncReadExt};
use tokio::sync::{broadcast, oneshot, watch};
use tokio::time::Instant;

use crate::realman::codec::decode::Body;
use crate::realman::codec::types::Arrival;
use crate::realman::codec::{decode_message, Frame, Message, Splitter, Tag};

/// What a waiting request receives.
#[derive(Debug)]
pub(crate) enum Delivery {
    /// Its reply, with the sequence number of the message in the stream.
    Reply { seq: u64, body: Body },
    /// A message that could only be this request's reply but did not decode.
    Malformed { reason: String },
    /// The connection went away.
    Disconnected,
}

struct Waiter {
    id: u64,
    tag: Tag,
    tx: oneshot::Sender<Delivery>,
    /// A reply with this tag was dropped as late while this request waited. If the guess was
    /// wrong (the old reply was lost, this was ours) and this request times out, it must not
    /// mark yet another reply as late: one lost reply costs one request, not a chain.
    passed_over: bool,
}

/// State shared by the client handle and the reader task.
pub(crate) struct Shared {
    waiters: Mutex<Vec<Waiter>>,
    /// Tags of requests that timed out, until when their late reply is expected. The controller
    /// answers in order, so a late reply comes before the reply to a newer request with the
    /// same tag; it is dropped instead of being handed to the newer request.
    late: Mutex<Vec<(Tag, Instant)>>,
    next_id: AtomicU64,
    /// Arrival events with the sequence number of the message.
    pub(crate) arrivals: broadcast::Sender<(u64, Arrival)>,
    /// Notices other than arrival events.
    pub(crate) notices: broadcast::Sender<Message>,
    /// Whether a reader is running on a live connection.
    pub(crate) connected: watch::Sender<bool>,
    /// Messages that could not be decoded or paired.
    pub(crate) malformed: AtomicU64,
}

impl Shared {
    pub(crate) fn new() -> Arc<Self> {
        Arc::new(Self {
            waiters: Mutex::new(Vec::new()),
            late: Mutex::new(Vec::new()),
            next_id: AtomicU64::new(1),
            arrivals: broadcast::channel(64).0,
            notices: broadcast::channel(64).0,
            connected: watch::channel(false).0,
            malformed: AtomicU64::new(0),
        })
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Vec<Waiter>> {
        // A poisoned lock only means another thread panicked while holding it; the Vec is
        // still consistent (every operation on it is a single push/remove).
        self.waiters.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Registers a request waiting for `tag`; returns its id and receiver.
    pub(crate) fn wait_for(&self, tag: Tag) -> (u64, oneshot::Receiver<Delivery>) {
        let id = self.next_id.fetch_add(1, Ordering::Relaxed);
        let (tx, rx) = oneshot::channel();
        self.lock().push(Waiter {
            id,
            tag,
            tx,
            passed_over: false,
        });
        (id, rx)
    }

    /// Drops a waiter (write failure).
    pub(crate) fn forget(&self, id: u64) {
        self.lock().retain(|w| w.id != id);
    }

    /// Drops a waiter whose reply did not come in time; a reply with its tag arriving before
    /// `until` is taken to be that late reply and discarded.
    pub(crate) fn timed_out(&self, id: u64, tag: Tag, until: Instant) {
        let mut waiters = self.lock();
        let Some(pos) = waiters.iter().position(|w| w.id == id) else {
            // Its reply was delivered in the meantime: nothing is late.
            return;
        };
        if !waiters.remove(pos).passed_over {
            self.late
                .lock()
                .unwrap_or_else(|p| p.into_inner())
                .push((tag, until));
        }
    }

    /// True (and the entry consumed) when a reply with `tag` is the late reply of a request
    /// that already timed out.
    fn is_late(&self, tag: &crate::realman::codec::ReplyTag) -> bool {
        let now = Instant::now();
        let mut late = self.late.lock().unwrap_or_else(|p| p.into_inner());
        late.retain(|(_, until)| *until > now);
        match late.iter().position(|(t, _)| tag.is(*t)) {
            Some(p) => {
                late.remove(p);
                true
            }
            None => false,
        }
    }

    /// Fails every waiting request (connection lost or replaced).
    pub(crate) fn fail_all(&self) {
        for w in self.lock().drain(..) {
            let _ = w.tx.send(Delivery::Disconnected);
        }
    }

    fn deliver(&self, seq: u64, message: Message) {
        match message {
            Message::Reply { tag, body } => {
                if self.is_late(&tag) {
                    tracing::debug!(?tag, "late reply to a timed-out request dropped");
                    if let Some(w) = self.lock().iter_mut().find(|w| tag.is(w.tag)) {
                        w.passed_over = true;
                    }
                    return;
                }
                let waiter = {
                    let mut waiters = self.lock();
                    let pos = waiters.iter().position(|w| tag.is(w.tag));
                    pos.map(|p| waiters.remove(p))
                };
                match waiter {
                    Some(w) => {
                        let _ = w.tx.send(Delivery::Reply { seq, body });
                    }
                    None => tracing::debug!(?tag, "reply nobody waits for (late or unsolicited)"),
                }
            }
            Message::Arrival(a) => {
                tracing::debug!(?a, "arrival event");
                let _ = self.arrivals.send((seq, a));
            }
            notice @ Message::Notice { .. } => {
                let _ = self.notices.send(notice);
            }
        }
    }

    /// A message that cannot be decoded: if exactly one request is waiting it can only be its
    /// reply, so that request fails; otherwise pairing would be a guess, and the waiters keep
    /// waiting (and time out).
    fn malformed(&self, reason: String) {
        self.malformed.fetch_add(1, Ordering::Relaxed);
        let mut waiters = self.lock();
        if waiters.len() == 1 {
            let w = waiters.remove(0);
            let _ = w.tx.send(Delivery::Malformed { reason });
        } else {
            tracing::warn!(%reason, waiting = waiters.len(), "undecodable message dropped");
        }
    }
}

/// Reads the stream until it ends, delivering every message.
pub(crate) async fn reader<R: AsyncRead + Unpin>(mut rd: R, shared: Arc<Shared>, max_frame: usize) {
    let mut splitter = Splitter::new(max_frame);
    let mut buf = vec![0u8; 4096];
    let mut seq = 0u64;
    loop {
        let n = match rd.read(&mut buf).await {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) => {
                tracing::warn!(error = %e, "read failed");
                break;
            }
        };
        splitter.push(&buf[..n]);
        while let Some(frame) = splitter.next_frame() {
            seq += 1;
            match frame {
                Frame::Object(text) => match decode_message(&text) {
                    Ok(m) => shared.deliver(seq, m),
                    Err(e) => shared.malformed(format!("{e}: {text}")),
                },
                Frame::Stray(text) => shared.malformed(format!("not a JSON object: {text}")),
                Frame::Truncated(text) => shared.malformed(format!("reply cut short: {text}")),
                Frame::Overflow { discarded } => shared.malformed(format!(
                    "message longer than {max_frame} bytes ({discarded} dropped)"
                )),
            }
        }
    }
    shared.connected.send_replace(false);
    shared.fail_all();
}
