//! Connection options (the seed SDK's constructor arguments in Rust form).

use std::sync::Arc;
use std::time::Duration;

use bus::{BusError, CanBus};

use super::super::codec::FirmwareVersion;
use super::super::kinematics::DhVariant;
use super::super::limits::{ClientLimits, LimitPolicy};
use super::{Piper, PiperError};

/// Re-opens a bus after the interface went down (e.g. `SocketCanBus::open("can0")`).
pub type BusOpener = Arc<dyn Fn() -> Result<Arc<dyn CanBus>, BusError> + Send + Sync>;

/// Which firmware profile the driver assumes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FirmwareSelection {
    /// Query 0x4AF at connect and use the reply (falls back to the pre-S-V1.8-8 behaviour,
    /// 8-bit MIT torque, while unknown).
    #[default]
    Auto,
    /// Use this version without asking the arm.
    Forced(FirmwareVersion),
}

/// Which DH table [`Piper::forward_kinematics`] uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DhSelection {
    /// From the firmware version (offset from S-V1.6-3), [`DhVariant::Offset`] while unknown.
    #[default]
    Auto,
    /// Always this variant.
    Fixed(DhVariant),
}

/// Timeouts and retry intervals. All are tokio durations (virtual under a paused clock).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Timeouts {
    /// Wait for the first feedback frame at connect (`None`: do not wait).
    pub first_feedback: Option<Duration>,
    /// Deadline of each query and acknowledged set command.
    pub query: Duration,
    /// Deadline of enable / disable confirmation.
    pub enable: Duration,
    /// Resend interval of the enable / disable command while unconfirmed.
    pub enable_retry: Duration,
    /// Feedback older than this makes [`Piper::is_ok`] false.
    pub link: Duration,
    /// How long a send retries while the transmit queue is full.
    pub send: Duration,
}

impl Default for Timeouts {
    fn default() -> Self {
        Self {
            first_feedback: Some(Duration::from_secs(1)),
            query: Duration::from_millis(500),
            enable: Duration::from_secs(2),
            enable_retry: Duration::from_millis(100),
            link: Duration::from_millis(50),
            send: Duration::from_millis(100),
        }
    }
}

/// The validated connection configuration.
#[derive(Debug, Clone)]
pub struct PiperConfig {
    /// Firmware profile selection.
    pub firmware: FirmwareSelection,
    /// DH table selection.
    pub dh: DhSelection,
    /// Policy for joint targets outside `limits`.
    pub joint_limit_policy: LimitPolicy,
    /// Policy for gripper strokes outside `limits`.
    pub gripper_limit_policy: LimitPolicy,
    /// Client-side limits.
    pub limits: ClientLimits,
    /// Drop feedback with impossible values (the SDK's default-on filter).
    pub abnormal_filter: bool,
    /// Consecutive low-speed frames with the wanted enable bit needed to confirm.
    pub enable_debounce: u32,
    /// Compensate the firmware's MIT quirks (spec §10): negate p/v/t on joints 1, 2, 4, 6
    /// before S-V1.7-3 and send a quarter of the J1–3 torque up to S-V1.8-2, so callers
    /// command the physical values on every firmware. Off by default (raw pass-through).
    pub mit_quirks: bool,
    /// Timeouts.
    pub timeouts: Timeouts,
}

impl Default for PiperConfig {
    fn default() -> Self {
        Self {
            firmware: FirmwareSelection::Auto,
            dh: DhSelection::Auto,
            joint_limit_policy: LimitPolicy::Off,
            gripper_limit_policy: LimitPolicy::Off,
            limits: ClientLimits::default(),
            abnormal_filter: true,
            enable_debounce: 2,
            mit_quirks: false,
            timeouts: Timeouts::default(),
        }
    }
}

/// Where the driver gets its bus.
#[derive(Clone)]
pub(crate) enum BusSource {
    Shared(Arc<dyn CanBus>),
    Opener { name: String, open: BusOpener },
}

/// Builds a [`Piper`] connection.
///
/// ```no_run
/// # async fn demo(node: std::sync::Arc<dyn bus::CanBus>) -> Result<(), driver::piper::PiperError> {
/// use driver::piper::{LimitPolicy, PiperBuilder};
/// let piper = PiperBuilder::new(node)
///     .joint_limits(LimitPolicy::Clamp)
///     .connect()
///     .await?;
/// println!("firmware {:?}", piper.firmware_version());
/// # Ok(()) }
/// ```
#[derive(Clone)]
pub struct PiperBuilder {
    pub(crate) source: BusSource,
    pub(crate) config: PiperConfig,
}

impl std::fmt::Debug for PiperBuilder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PiperBuilder")
            .field("config", &self.config)
            .finish_non_exhaustive()
    }
}

impl PiperBuilder {
    /// Use an already open bus endpoint (virtual node or SocketCAN).
    pub fn new(bus: Arc<dyn CanBus>) -> Self {
        Self {
            source: BusSource::Shared(bus),
            config: PiperConfig::default(),
        }
    }

    /// Open the bus through `open`, and again whenever the interface goes down. `name`
    /// identifies the interface (one driver per name).
    pub fn with_opener(name: &str, open: BusOpener) -> Self {
        Self {
            source: BusSource::Opener {
                name: name.to_owned(),
                open,
            },
            config: PiperConfig::default(),
        }
    }

    /// A SocketCAN interface by name (`can0`, `vcan0`), opened at connect and re-opened when
    /// it goes down.
    #[cfg(target_os = "linux")]
    pub fn interface(name: &str) -> Self {
        let iface = name.to_owned();
        let open: BusOpener = Arc::new(move || {
            let bus = bus::socketcan_bus::SocketCanBus::open(&iface)?;
            Ok(Arc::new(bus) as Arc<dyn CanBus>)
        });
        Self::with_opener(name, open)
    }

    /// Firmware profile: auto-detected from 0x4AF (default) or forced.
    pub fn firmware(mut self, firmware: FirmwareSelection) -> Self {
        self.config.firmware = firmware;
        self
    }

    /// DH table for forward kinematics (the SDK's `dh_is_offset`).
    pub fn dh(mut self, dh: DhSelection) -> Self {
        self.config.dh = dh;
        self
    }

    /// Client-side joint limit policy (the SDK's `start_sdk_joint_limit`).
    pub fn joint_limits(mut self, policy: LimitPolicy) -> Self {
        self.config.joint_limit_policy = policy;
        self
    }

    /// Client-side gripper limit policy (the SDK's `start_sdk_gripper_limit`).
    pub fn gripper_limits(mut self, policy: LimitPolicy) -> Self {
        self.config.gripper_limit_policy = policy;
        self
    }

    /// The limit values both policies use.
    pub fn limits(mut self, limits: ClientLimits) -> Self {
        self.config.limits = limits;
        self
    }

    /// Switch the abnormal-data filter (on by default, as in the SDK).
    pub fn abnormal_filter(mut self, on: bool) -> Self {
        self.config.abnormal_filter = on;
        self
    }

    /// Consecutive confirming low-speed frames per joint for enable/disable (default 2).
    pub fn enable_debounce(mut self, frames: u32) -> Self {
        self.config.enable_debounce = frames.max(1);
        self
    }

    /// Compensate the firmware's MIT sign flip and J1–3 torque scaling (see
    /// [`PiperConfig::mit_quirks`]).
    pub fn mit_quirks(mut self, on: bool) -> Self {
        self.config.mit_quirks = on;
        self
    }

    /// Replace all timeouts.
    pub fn timeouts(mut self, timeouts: Timeouts) -> Self {
        self.config.timeouts = timeouts;
        self
    }

    /// Connect: claim the bus, start the receive and link-monitor tasks, wait for the first
    /// feedback (if configured) and detect the firmware (if [`FirmwareSelection::Auto`]).
    pub async fn connect(self) -> Result<Piper, PiperError> {
        Piper::connect(self).await
    }
}
