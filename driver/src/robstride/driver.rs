//! One driver per bus: a single receive task decodes every frame and routes it to the handle of
//! the motor it comes from, so no motor handle sees another motor's replies.

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use bus::{BusError, CanBus};
use tokio::sync::{mpsc, watch};
use tokio::task::JoinHandle;

use crate::robstride::codec::{self, FaultReport, Feedback, Incoming};
use crate::robstride::error::RobstrideError;
use crate::robstride::mit::MitMotor;
use crate::robstride::mit_codec::{self, MitIncoming, MitStatus};
use crate::robstride::model::{Model, RangeTable, Ranges};
use crate::robstride::motor::Motor;

/// The host ID the manuals use, and the driver's unless [`DriverConfig::host_id`] says
/// otherwise (motors answer it until another host speaks).
pub const DEFAULT_HOST_ID: u8 = 0xFD;

/// Driver settings.
#[derive(Debug, Clone, PartialEq)]
pub struct DriverConfig {
    /// Our host ID ([`DEFAULT_HOST_ID`] unless set).
    pub host_id: u8,
    /// How long a request waits for its reply.
    pub timeout: Duration,
    /// Which range table new motor handles use.
    pub range_table: RangeTable,
    /// canTimeout ticks per second (manual: 20000).
    pub can_timeout_ticks_per_s: u32,
}

impl Default for DriverConfig {
    fn default() -> Self {
        Self {
            host_id: DEFAULT_HOST_ID,
            timeout: Duration::from_millis(20),
            range_table: RangeTable::Manual,
            can_timeout_ticks_per_s: 20_000,
        }
    }
}

/// Where a scan collects `(motor ID, UID)` announcements.
type ScanSender = mpsc::UnboundedSender<(u8, [u8; 8])>;

/// Per-motor routing entry.
pub(crate) struct Route {
    pub(crate) replies: mpsc::UnboundedSender<Incoming>,
    pub(crate) feedback: watch::Sender<Option<Feedback>>,
    pub(crate) faults: watch::Sender<Option<FaultReport>>,
    pub(crate) ranges: Ranges,
}

/// Per-motor routing entry of the MIT variant (11-bit frames).
pub(crate) struct MitRoute {
    pub(crate) replies: mpsc::UnboundedSender<MitIncoming>,
    pub(crate) status: watch::Sender<Option<MitStatus>>,
    pub(crate) ranges: Ranges,
}

pub(crate) struct Shared {
    pub(crate) bus: Arc<dyn CanBus>,
    pub(crate) config: DriverConfig,
    routes: Mutex<BTreeMap<u8, Route>>,
    /// Handles speaking the MIT variant, by motor ID (separate from `routes`: a motor may have
    /// a private handle and an MIT handle across a protocol switch).
    mit_routes: Mutex<BTreeMap<u8, MitRoute>>,
    /// Type-0 announcements from IDs without a handle (bus scans).
    unclaimed: Mutex<Option<ScanSender>>,
}

impl Shared {
    pub(crate) fn routes(&self) -> MutexGuard<'_, BTreeMap<u8, Route>> {
        // A poisoned lock only means another thread panicked mid-update of a map of senders;
        // the map is still usable.
        self.routes
            .lock()
            .unwrap_or_else(|poison| poison.into_inner())
    }

    pub(crate) fn mit_routes(&self) -> MutexGuard<'_, BTreeMap<u8, MitRoute>> {
        self.mit_routes
            .lock()
            .unwrap_or_else(|poison| poison.into_inner())
    }
}

/// The RobStride driver on one bus.
pub struct RobstrideDriver {
    shared: Arc<Shared>,
    receiver: JoinHandle<()>,
}

impl std::fmt::Debug for RobstrideDriver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RobstrideDriver")
            .field("bus", &self.shared.bus.name())
            .field("config", &self.shared.config)
            .finish_non_exhaustive()
    }
}

impl RobstrideDriver {
    /// Start the driver on `bus` (spawns the receive task on the current runtime).
    pub fn new(bus: Arc<dyn CanBus>, config: DriverConfig) -> Self {
        let shared = Arc::new(Shared {
            bus,
            config,
            routes: Mutex::new(BTreeMap::new()),
            mit_routes: Mutex::new(BTreeMap::new()),
            unclaimed: Mutex::new(None),
        });
        let receiver = tokio::spawn(receive_loop(Arc::clone(&shared)));
        Self { shared, receiver }
    }

    /// The driver's settings.
    pub fn config(&self) -> &DriverConfig {
        &self.shared.config
    }

    /// A handle on motor `can_id` of `model` (one handle per ID at a time).
    pub fn motor(&self, can_id: u8, model: Model) -> Result<Motor, RobstrideError> {
        let ranges = model.ranges(self.shared.config.range_table);
        self.motor_with_ranges(can_id, model, ranges)
    }

    /// A handle with explicit scaling ranges (firmware that uses another table).
    pub fn motor_with_ranges(
        &self,
        can_id: u8,
        model: Model,
        ranges: Ranges,
    ) -> Result<Motor, RobstrideError> {
        Motor::register(Arc::clone(&self.shared), can_id, model, ranges)
    }

    /// A handle on motor `can_id` speaking the MIT variant (after a switch with
    /// [`Motor::set_protocol`] and a power cycle); one MIT handle per ID at a time. The MIT
    /// ranges are the model's private ones (CN manuals).
    pub fn mit_motor(&self, can_id: u8, model: Model) -> Result<MitMotor, RobstrideError> {
        let ranges = model.ranges(self.shared.config.range_table);
        MitMotor::register(Arc::clone(&self.shared), can_id, model, ranges)
    }

    /// Ping each ID and collect `(id, uid)` of the motors that answer within `per_id`.
    pub async fn scan(
        &self,
        ids: impl IntoIterator<Item = u8>,
        per_id: Duration,
    ) -> Result<Vec<(u8, [u8; 8])>, RobstrideError> {
        let (tx, mut rx) = mpsc::unbounded_channel();
        *self
            .shared
            .unclaimed
            .lock()
            .unwrap_or_else(|poison| poison.into_inner()) = Some(tx);
        let mut found = Vec::new();
        for id in ids {
            let host = u16::from(self.shared.config.host_id);
            let frame = codec::request(codec::comm::GET_ID, host, id, [0; 8])?;
            self.shared.bus.send(frame).await?;
            if let Ok(Some((motor, uid))) = tokio::time::timeout(per_id, rx.recv()).await {
                if motor == id {
                    found.push((motor, uid));
                }
            }
        }
        *self
            .shared
            .unclaimed
            .lock()
            .unwrap_or_else(|poison| poison.into_inner()) = None;
        Ok(found)
    }
}

impl Drop for RobstrideDriver {
    fn drop(&mut self) {
        self.receiver.abort();
    }
}

async fn receive_loop(shared: Arc<Shared>) {
    let host = shared.config.host_id;
    loop {
        let received = match shared.bus.recv().await {
            Ok(received) => received,
            Err(BusError::Closed) => break,
            Err(error) => {
                tracing::warn!(%error, "robstride driver: receive error");
                tokio::time::sleep(Duration::from_millis(1)).await;
                continue;
            }
        };
        if !received.frame.is_extended() {
            route_mit(&shared, &received.frame);
            continue;
        }
        let decoded = {
            let routes = shared.routes();
            codec::decode(&received.frame, host, received.timestamp, |id| {
                routes.get(&id).map(|route| route.ranges)
            })
        };
        let Some(incoming) = decoded else {
            // Type-0 from a motor without a handle (a scan) decodes without ranges.
            continue;
        };
        let motor = incoming.motor_id();
        let routes = shared.routes();
        let Some(route) = routes.get(&motor) else {
            if let Incoming::DeviceId { motor_id, uid } = incoming {
                if let Some(tx) = shared
                    .unclaimed
                    .lock()
                    .unwrap_or_else(|poison| poison.into_inner())
                    .as_ref()
                {
                    let _ = tx.send((motor_id, uid));
                }
            }
            continue;
        };
        match incoming {
            Incoming::Feedback(feedback) => {
                route.feedback.send_replace(Some(feedback));
                // Active reports are telemetry, not answers to requests.
                if feedback.kind == codec::FeedbackKind::Reply {
                    let _ = route.replies.send(incoming);
                }
            }
            Incoming::Fault { report, .. } => {
                tracing::warn!(
                    motor,
                    fault_word = report.fault_word,
                    warning_word = report.warning_word,
                    "robstride: fault frame"
                );
                route.faults.send_replace(Some(report));
                let _ = route.replies.send(incoming);
            }
            _ => {
                let _ = route.replies.send(incoming);
            }
        }
    }
}

/// Route a standard frame of the MIT variant to its motor's MIT handle (if any).
fn route_mit(shared: &Shared, frame: &bus::CanFrame) {
    let routes = shared.mit_routes();
    let decoded = mit_codec::decode(frame, shared.config.host_id, |id| {
        routes.get(&id).map(|route| route.ranges)
    });
    let Some(incoming) = decoded else {
        return;
    };
    let Some(route) = routes.get(&incoming.motor_id()) else {
        return;
    };
    if let MitIncoming::Status(status) = incoming {
        route.status.send_replace(Some(status));
    }
    let _ = route.replies.send(incoming);
}
