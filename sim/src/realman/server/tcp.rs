//! The TCP listener: accepting connections and admitting them to a slot (or evicting the
//! client idle longest).

use std::net::SocketAddr;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Duration;

use tokio::net::TcpListener;
use tokio::sync::{mpsc, watch};
use tokio::time::{sleep, Instant};

use super::connection::serve_connection;
use super::{lock, Activity, Client, Outgoing, Shared, CLIENT_QUEUE, EVICT_IDLE_AFTER};
use crate::realman::firmware::ClientId;

/// Accept TCP connections until the emulator stops, each served by its own task.
pub(super) async fn accept_loop(shared: Arc<Shared>, listener: TcpListener) {
    let mut stop = shared.stop.clone();
    let mut accept_failures: u64 = 0;
    loop {
        let accepted = tokio::select! {
            r = listener.accept() => r,
            _ = stop.changed() => break,
        };
        match accepted {
            Ok((stream, peer)) => {
                // Each reply and event is its own segment, as on the controller.
                let _ = stream.set_nodelay(true);
                tokio::spawn(serve_connection(Arc::clone(&shared), stream, peer));
            }
            Err(e) => {
                // Out of descriptors and the like: wait and keep listening. Logged at the 1st,
                // 2nd, 4th, … failure: at one try every 10 ms a warning each would flood the log.
                accept_failures += 1;
                if accept_failures.is_power_of_two() {
                    tracing::warn!(error = %e, failures = accept_failures, "Realman emulator accept failed");
                }
                sleep(Duration::from_millis(10)).await;
            }
        }
    }
}

/// What a connection's tasks get when it is admitted.
pub(super) struct Admitted {
    pub(super) id: ClientId,
    pub(super) tx: mpsc::Sender<Outgoing>,
    pub(super) rx: mpsc::Receiver<Outgoing>,
    pub(super) kill: watch::Receiver<Option<&'static str>>,
    pub(super) activity: Activity,
}

/// Admit a client, evicting the client idle longest if every slot is taken and it has been
/// idle for [`EVICT_IDLE_AFTER`], or refuse it.
pub(super) fn admit(shared: &Shared, peer: SocketAddr) -> Option<Admitted> {
    let mut clients = lock(&shared.clients);
    // Clients being closed (evicted, dropped) no longer hold a slot.
    let live = clients.values().filter(|c| !c.ending()).count();
    if live >= shared.max_connections {
        let idlest = clients
            .values()
            .filter(|c| !c.ending())
            .min_by_key(|c| c.active_ms.load(Ordering::Relaxed));
        let idle_since = idlest
            .map(|c| shared.epoch + Duration::from_millis(c.active_ms.load(Ordering::Relaxed)));
        match (idlest, idle_since) {
            (Some(client), Some(since)) if since + EVICT_IDLE_AFTER <= Instant::now() => {
                tracing::info!(evicted = %client.peer, %peer, "Realman emulator full: the client idle longest gives its slot to a new one");
                client.end("evicted (idle while the emulator was full)");
                lock(&shared.stats).evicted += 1;
            }
            _ => {
                drop(clients);
                lock(&shared.stats).refused += 1;
                tracing::warn!(%peer, cap = shared.max_connections, "Realman emulator refused a connection: too many clients");
                return None;
            }
        }
    }
    let id = shared.next_client.fetch_add(1, Ordering::Relaxed);
    let (tx, rx) = mpsc::channel(CLIENT_QUEUE);
    let (kill, kill_rx) = watch::channel(None);
    let activity = Activity {
        epoch: shared.epoch,
        ms: Arc::new(AtomicU64::new(0)),
    };
    activity.touch();
    clients.insert(
        id,
        Client {
            peer,
            tx: tx.clone(),
            kill,
            active_ms: Arc::clone(&activity.ms),
        },
    );
    drop(clients);
    lock(&shared.stats).accepted += 1;
    tracing::info!(%peer, client = id, "Realman client connected");
    Some(Admitted {
        id,
        tx,
        rx,
        kill: kill_rx,
        activity,
    })
}
