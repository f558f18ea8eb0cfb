//! The contract of a device kind: what every kind provides, checked by the compiler.
//!
//! A kind is a folder under `src/devices/` whose `mod.rs` implements `KindSpec` for a unit
//! struct `Kind`, and one line in the registry (`device_kinds!` in `src/devices/mod.rs`). The
//! harness, the report, the web view, `armhil decode` and the Python emulators reach a kind
//! only through this trait and the [`Device`] it builds:
//!
//! - its **scenario vocabulary**: the file shapes (`Raw*`, layer 1) and their validation into
//!   `Settings`, actions, checks and faults (layer 2, errors with file:line:col), built from
//!   the grammar core in [`crate::scenario`];
//! - **how to build it on a bench** (`KindSpec::build`): emulator (in-process runs) and
//!   driver, on the transport the device speaks;
//! - what the **views** need: the URDF to draw and the trace columns that pose it (`KindSpec::drawing`) and a decoder for its
//!   frames in reports (`KindSpec::frame_decoder`);
//! - the **protocols** it owns, by which `armhil decode --device NAME` reads a capture without
//!   a scenario (`KindSpec::WIRE_DECODERS`);
//! - its **trace columns**, observations and fault injection, through [`Device`].

pub(crate) mod bus_emulator;
mod device;
mod drawing;
pub(crate) mod health;
pub(crate) mod motor_bus;
pub(crate) mod motor_rig;
mod wire;

use std::fmt::Debug;
use std::sync::Arc;

use async_trait::async_trait;
use bus::CanFrame;

pub(crate) use device::within;
pub use device::{Device, DeviceError, Reply, TraceColumn};
pub use drawing::{BaseColumns, Drawing, JointColumn, Posing};
pub use wire::{WireDecode, WireDecoder, WireMotor, WireOptions};

use crate::interop::DecodedFrame;
use crate::scenario::onekey::OneKey;
use crate::scenario::{Ctx, DeviceStep, Pos, Res, S};
use crate::wiring::{Clock, RunOptions, HOST_NODE};

/// What a kind's `build` gets: the scenario's clock and options, and, for CAN devices, the
/// in-process virtual buses or the SocketCAN interface to open. One device's share of the
/// run's wiring ([`crate::wiring`], which every device of the run shares).
pub(crate) struct Wiring<'a> {
    /// Every in-process bus of the device, in the order of [`KindSpec::buses`] (a robot's).
    pub buses: Vec<&'a bus::virtual_bus::VirtualBus>,
    /// Clock of the run.
    pub clock: &'a Clock,
    /// Run options (deadline scaling).
    pub options: &'a RunOptions,
    /// Bit rate of the device's (first) CAN bus.
    pub bitrate_bps: u32,
}

impl<'a> Wiring<'a> {
    /// The device's (first) in-process virtual bus (virtual and real-time clocks).
    pub fn bus(&self) -> Option<&'a bus::virtual_bus::VirtualBus> {
        self.buses.first().copied()
    }

    /// The driver's end of the device's (first) bus: a node named [`HOST_NODE`] on the
    /// in-process virtual bus, or the link to the real interface opened for the driver;
    /// `name` (the device's) names it in the error when there is neither.
    pub async fn driver_bus(&self, name: &str) -> Result<Arc<dyn bus::CanBus>, String> {
        match (self.bus(), self.clock) {
            (Some(bus), _) => Ok(Arc::new(bus.attach(HOST_NODE))),
            (None, Clock::Iface(link)) => link.open("driver").await,
            (None, _) => Err(format!("device `{name}`: no bus to attach to")),
        }
    }
}

/// A CAN bus a device sits on, as its settings name it.
#[derive(Debug, Clone, PartialEq)]
pub struct BusUse {
    /// The bus's name (its `bus:` setting, a robot's bus), or `None` for the bench's only bus.
    pub name: Option<String>,
    /// The bit rate the device needs, when its settings fix one (a robot's file does).
    pub bitrate_bps: Option<u32>,
    /// The CAN FD data-phase bit rate it needs, when it runs the bus as CAN FD.
    pub data_bitrate_bps: Option<u32>,
    /// Where the name is written, for errors.
    pub at: Pos,
}

/// A CAN device's `bus:` setting, checked, with where it is written.
pub(crate) fn named_bus(ctx: &Ctx<'_>, raw: &Option<S<String>>) -> Res<Option<(String, Pos)>> {
    raw.as_ref()
        .map(|name| Ok((ctx.bus_name(name)?, crate::scenario::pos(name))))
        .transpose()
}

/// The one bus of a CAN device whose settings may name it (`bus:`).
pub(crate) fn one_bus(named: &Option<(String, Pos)>, at: Pos) -> Vec<BusUse> {
    vec![BusUse {
        name: named.as_ref().map(|(name, _)| name.clone()),
        bitrate_bps: None,
        data_bitrate_bps: None,
        at: named.as_ref().map_or(at, |(_, p)| *p),
    }]
}

/// A step as written in a kind's vocabulary: a one-key mapping that may carry an `id:`.
pub(crate) trait RawKindStep: OneKey + Debug {
    /// The step's `id:`, if it has one.
    fn id(&self) -> Option<&S<String>>;
}

/// Names a device's CAN frames for the report's frame table (and `armhil decode`): `None` for
/// a frame that is not this device's, so that on a bench of several devices each frame is
/// decoded by the device it belongs to, never by guessing from the identifier's width.
pub trait FrameDecoder: Send + Sync {
    /// The frame's message name and fields, if it is one of this device's. `bus` is the bus
    /// the frame was captured on when the capture says and the bench has a bus of that name
    /// (`None`: any of the device's buses): CAN ids repeat across buses, and a robot's motor 1
    /// on `can0` may be another model than its motor 1 on `can1`.
    fn decode(&self, bus: Option<&str>, frame: &CanFrame) -> Option<DecodedFrame>;
}

/// Several decoders as one: a frame is named by the first that knows it (a robot whose
/// actuators are of several kinds, each kind's decoder knowing its own motors by bus and id).
pub(crate) struct FirstOf(pub Vec<Box<dyn FrameDecoder>>);

impl FrameDecoder for FirstOf {
    fn decode(&self, bus: Option<&str>, frame: &CanFrame) -> Option<DecodedFrame> {
        self.0.iter().find_map(|d| d.decode(bus, frame))
    }
}

/// One device kind. Implemented by a unit struct `Kind` in each kind's `mod.rs`.
#[async_trait]
pub(crate) trait KindSpec: 'static {
    /// The kind's name in scenario files (`kind: piper`).
    const NAME: &'static str;

    /// Validated settings of one device of this kind.
    type Settings: Debug + Clone + PartialEq + Send + Sync;
    /// A validated action.
    type Action: Debug + Clone + PartialEq + Send + Sync;
    /// A validated condition on the device's state.
    type Check: Debug + Clone + PartialEq + Send + Sync;
    /// A validated emulator fault.
    type Fault: Debug + Clone + PartialEq + Send + Sync;

    /// The device entry as written (after `kind:`).
    type RawSettings: for<'de> serde::Deserialize<'de> + Debug;
    /// A step as written (one-key mapping).
    type RawStep: RawKindStep;
    /// The conditions of `expect` / `wait_until` as written.
    type RawConds: for<'de> serde::Deserialize<'de> + Debug;
    /// A fault as written (one-key mapping).
    type RawFault: OneKey + Debug;

    /// Every key [`Self::RawConds`] reads (how a condition map finds its kind).
    const CONDITION_KEYS: &'static [&'static str];

    /// Layer 2 of a device entry.
    fn validate_settings(ctx: &Ctx<'_>, raw: &Self::RawSettings, at: Pos) -> Res<Self::Settings>;
    /// Layer 2 of a step: its label for reports and the device step.
    fn validate_step(
        ctx: &Ctx<'_>,
        raw: &Self::RawStep,
        at: Pos,
    ) -> Res<(&'static str, DeviceStep<Self::Action>)>;
    /// Layer 2 of conditions on device `device` (`step` names the step for messages).
    fn validate_checks(
        ctx: &Ctx<'_>,
        raw: &Self::RawConds,
        device: usize,
        step: &str,
        at: Pos,
    ) -> Res<Vec<Self::Check>>;
    /// Layer 2 of a fault; `device` is the device it is on when that is already known (the
    /// entry's `device:`, or the only device on the bench).
    fn validate_fault(
        ctx: &Ctx<'_>,
        raw: &Self::RawFault,
        device: Option<usize>,
        at: Pos,
    ) -> Res<Self::Fault>;

    /// What a condition wants, for reports.
    fn describe_check(check: &Self::Check) -> String;
    /// Short description of a fault for logs and reports.
    fn describe_fault(fault: &Self::Fault) -> String;
    /// Why an action needs the in-process emulator, if it does.
    fn action_needs_emulator(action: &Self::Action) -> Option<String>;
    /// What `settings` need from the in-process emulator (a separate emulator process on a
    /// real interface cannot be configured from the scenario); `device` names it in messages.
    fn in_process_requirements(settings: &Self::Settings, device: &str) -> Vec<String>;

    /// Start the device: its emulator (in-process runs) and its driver.
    async fn build(
        name: &str,
        settings: &Self::Settings,
        wiring: &Wiring<'_>,
    ) -> Result<Arc<dyn Device>, String>;

    /// The names of the device's parts that steps, checks and faults address (a group's
    /// joints); empty for kinds that address none by name.
    fn parts(settings: &Self::Settings) -> Vec<String> {
        let _ = settings;
        Vec::new()
    }

    /// The actuator behind each of [`Self::parts`] (its kind and model, whose fault table a
    /// scenario's `actuator_fault` is checked by); empty for kinds whose parts are not
    /// actuators.
    fn part_actuators(settings: &Self::Settings) -> Vec<sim::actuator::ActuatorModel> {
        let _ = settings;
        Vec::new()
    }

    /// The CAN buses the device sits on: one for a CAN device (named by its `bus:` or the
    /// bench's only bus), a robot's several, none for a device that speaks no CAN.
    fn buses(settings: &Self::Settings, at: Pos) -> Vec<BusUse>;

    /// How the 3D views draw this device (its URDF, the trace columns that pose it), if it
    /// is a robot or arm.
    fn drawing(settings: &Self::Settings) -> Option<Drawing>;

    /// A decoder of this device's CAN frames for reports, if it speaks CAN. `buses` names the
    /// device's buses on its bench, in the order [`KindSpec::buses`] lists them.
    fn frame_decoder(settings: &Self::Settings, buses: &[String]) -> Option<Arc<dyn FrameDecoder>>;

    /// The protocols `armhil decode --device` reads captures by (without a scenario) that this
    /// kind owns. Each protocol is registered once, by its owner: a kind that speaks another
    /// kind's protocol (`arm` the Piper's, `actuator_group` RobStride's) lists none, and so does
    /// a kind that speaks no CAN (the default).
    const WIRE_DECODERS: &'static [WireDecoder] = &[];
}
