//! One driver per bus: a single receive task takes every standard frame, finds the motor by
//! the frame's identifier (its MST_ID), decodes it with that motor's ESC_ID and ranges and
//! hands it to the motor's handle. Frames on no handle's MST_ID, and feedback whose D0 carries
//! another motor's nibble, are dropped.

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use bus::{BusError, CanBus};
use tokio::sync::{mpsc, watch};
use tokio::task::JoinHandle;

use crate::damiao::codec::{self, Feedback, Reply, VelocityLen};
use crate::damiao::error::DamiaoError;
use crate::damiao::model::{Model, RangeTable, Ranges};
use crate::damiao::motor::DamiaoMotor;

/// Largest ESC_ID: the force-position command's identifier (0x300 + ESC_ID) must stay below
/// the register identifier 0x7FF.
pub const MAX_ESC_ID: u16 = 0x4FE;
/// Largest MST_ID (0x7FF carries the register requests).
pub const MAX_MST_ID: u16 = 0x7FE;

/// Driver settings.
#[derive(Debug, Clone, PartialEq)]
pub struct DriverConfig {
    /// How long a request waits for its reply (20 ms unless set; the firmware answers within
    /// a few hundred microseconds).
    pub timeout: Duration,
    /// Which range table new motor handles use ([`RangeTable::Current`] unless set).
    pub range_table: RangeTable,
    /// The velocity command's length ([`VelocityLen::Eight`] unless set).
    pub velocity_len: VelocityLen,
}

impl Default for DriverConfig {
    fn default() -> Self {
        Self {
            timeout: Duration::from_millis(20),
            range_table: RangeTable::Current,
            velocity_len: VelocityLen::Eight,
        }
    }
}

/// Where the receive task sends one motor's replies.
pub(crate) struct Route {
    pub(crate) esc_id: u16,
    pub(crate) ranges: Ranges,
    pub(crate) replies: mpsc::UnboundedSender<Reply>,
    pub(crate) feedback: watch::Sender<Option<Feedback>>,
}

pub(crate) struct Shared {
    pub(crate) bus: Arc<dyn CanBus>,
    pub(crate) config: DriverConfig,
    /// Handles by MST_ID.
    routes: Mutex<BTreeMap<u16, Route>>,
}

impl Shared {
    pub(crate) fn routes(&self) -> MutexGuard<'_, BTreeMap<u16, Route>> {
        // A poisoned lock only means a thread panicked while holding a map of senders; the map
        // is still usable.
        self.routes
            .lock()
            .unwrap_or_else(|poison| poison.into_inner())
    }
}

/// The Damiao driver on one bus: hands out [`DamiaoMotor`] handles.
///
/// ```no_run
/// # async fn demo(bus: std::sync::Arc<dyn bus::CanBus>) -> Result<(), driver::damiao::DamiaoError> {
/// use driver::damiao::{ControlMode, DamiaoDriver, DriverConfig, Model};
/// let driver = DamiaoDriver::new(bus, DriverConfig::default());
/// let motor = driver.motor(0x01, 0x11, Model::DM4310)?;
/// motor.set_control_mode(ControlMode::Mit).await?;
/// motor.enable().await?;
/// let feedback = motor.mit(0.5, 0.0, 10.0, 0.5, 0.0).await?;
/// println!("{} rad", feedback.position_rad);
/// # Ok(()) }
/// ```
pub struct DamiaoDriver {
    shared: Arc<Shared>,
    receiver: JoinHandle<()>,
}

impl std::fmt::Debug for DamiaoDriver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DamiaoDriver")
            .field("bus", &self.shared.bus.name())
            .field("config", &self.shared.config)
            .finish_non_exhaustive()
    }
}

impl DamiaoDriver {
    /// Start the driver on `bus` (spawns the receive task on the current tokio runtime).
    pub fn new(bus: Arc<dyn CanBus>, config: DriverConfig) -> Self {
        let shared = Arc::new(Shared {
            bus,
            config,
            routes: Mutex::new(BTreeMap::new()),
        });
        let receiver = tokio::spawn(receive_loop(Arc::clone(&shared)));
        Self { shared, receiver }
    }

    /// The driver's settings.
    pub fn config(&self) -> &DriverConfig {
        &self.shared.config
    }

    /// The bus's name, as errors name it.
    pub fn bus_name(&self) -> &str {
        self.shared.bus.name()
    }

    /// A handle on the motor with command identifier `esc_id` that answers on `mst_id`, with
    /// the model's ranges from the configured table. One handle per ESC_ID and per MST_ID.
    pub fn motor(
        &self,
        esc_id: u16,
        mst_id: u16,
        model: Model,
    ) -> Result<DamiaoMotor, DamiaoError> {
        let ranges = model.ranges(self.shared.config.range_table);
        self.motor_with_ranges(esc_id, mst_id, model, ranges)
    }

    /// A handle with explicit MIT ranges (a motor whose PMAX/VMAX/TMAX registers differ from
    /// the model's table).
    pub fn motor_with_ranges(
        &self,
        esc_id: u16,
        mst_id: u16,
        model: Model,
        ranges: Ranges,
    ) -> Result<DamiaoMotor, DamiaoError> {
        if esc_id > MAX_ESC_ID || mst_id > MAX_MST_ID {
            return Err(DamiaoError::InvalidId { esc_id, mst_id });
        }
        if !ranges.is_valid() {
            return Err(DamiaoError::InvalidRanges { ranges });
        }
        let (replies, replies_rx) = mpsc::unbounded_channel();
        let (feedback, feedback_rx) = watch::channel(None);
        {
            let mut routes = self.shared.routes();
            if routes.contains_key(&mst_id) {
                return Err(DamiaoError::IdInUse { id: mst_id });
            }
            if routes.values().any(|route| route.esc_id == esc_id) {
                return Err(DamiaoError::IdInUse { id: esc_id });
            }
            routes.insert(
                mst_id,
                Route {
                    esc_id,
                    ranges,
                    replies,
                    feedback,
                },
            );
        }
        Ok(DamiaoMotor::new(
            Arc::clone(&self.shared),
            esc_id,
            mst_id,
            model,
            ranges,
            replies_rx,
            feedback_rx,
        ))
    }
}

impl Drop for DamiaoDriver {
    fn drop(&mut self) {
        self.receiver.abort();
    }
}

async fn receive_loop(shared: Arc<Shared>) {
    loop {
        let received = match shared.bus.recv().await {
            Ok(received) => received,
            Err(BusError::Closed) => break,
            Err(error) => {
                tracing::warn!(%error, "damiao driver: receive error");
                tokio::time::sleep(Duration::from_millis(1)).await;
                continue;
            }
        };
        let frame = received.frame;
        if frame.is_extended() {
            continue;
        }
        // The identifier fits 11 bits: it is a standard frame.
        let mst_id = frame.raw_id() as u16;
        let routes = shared.routes();
        let Some(route) = routes.get(&mst_id) else {
            continue;
        };
        let Some(reply) = codec::decode_reply(&frame, route.esc_id, &route.ranges) else {
            tracing::debug!(%frame, esc_id = route.esc_id, "damiao: frame on MST_ID from another motor or malformed; ignored");
            continue;
        };
        if let Reply::Feedback(feedback) = reply {
            route.feedback.send_replace(Some(feedback));
        }
        let _ = route.replies.send(reply);
    }
    // Dropping the senders makes every waiting request return `Closed`.
    shared.routes().clear();
}
