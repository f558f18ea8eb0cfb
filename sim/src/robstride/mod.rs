//! RobStride actuator emulator: the private 29-bit CAN protocol (spec
//! `docs/protocols/robstride.md`), any number of motors on one bus, each driving a rig.
//!
//! - [`Actuator`]: one motor's firmware (pure: frames in, frames out, 1 ms ticks).
//! - [`model`]: per-model ranges (manual table by default, SDK table selectable, or explicit
//!   [`Ranges`] per motor) and electrical/thermal facts; [`params`]: the 0x70xx table;
//!   [`host_params`]: the per-model host-tool tables 0x20xx/0x30xx that type 17 also serves.
//! - [`rig`]: the load the motor drives ([`Load`]), its URDF, and two integrators
//!   ([`RigPlant`], or [`WorldPlant`] on `sim::physics::RapierWorld`, chosen by [`PlantKind`]).
//! - [`RobstrideBus::spawn`]: many actuators on one [`bus::CanBus`], with a
//!   [`RobstrideHandle`] for the harness: `inject` / `clear` typed [`Fault`]s,
//!   `set_bus_voltage`, `set_temperature`, `set_external_torque`, `snapshot`, `shutdown`.
//!   Works under a paused tokio clock; a state file (atomic JSON) is the motors' flash.
//!
//! Behaviour the spec leaves open, and what the emulator does:
//! - The motors' CAN controllers are classic: a CAN FD frame reaches none of them (a real one
//!   would destroy it with an error frame; the emulator only ignores it).
//! - Replies go to the last host ID seen in bits 15..8 (type 1 carries none).
//! - Type 7 is refused (no reply) while running; the new ID is kept at once (persisted).
//! - A write to a read-only or unknown index is answered with the type-17 failure flag
//!   (bits 23..16 = 1, index echoed); reads of unknown indices get the captured zero echo.
//! - Out-of-range writes are clamped into the table's range; run_mode writes while running
//!   are ignored but acknowledged with a status frame.
//! - Enabling holds the current position (loc_ref and the PP target are set to it) and is
//!   refused while a fault is latched. Faults stop the motor; stop + clear (type 4, byte0 = 1)
//!   clears the bits whose cause is gone.
//! - Baud and protocol switches take effect at the next spawn: a motor at another bit rate
//!   ignores the bus; one switched to MIT or CANopen speaks that protocol instead (the MIT
//!   variant on 11-bit IDs; CANopen as a CiA-301 node with the CiA-402 drive objects, see
//!   `docs/protocols/robstride.md` §12 and §13).

pub mod actuator;
pub mod codec;
pub mod control;
pub mod faults;
mod firmware;
pub mod host_params;
pub mod model;
pub mod params;
pub mod rig;
mod runner;
pub mod state_file;

pub use faults::{build_fault, Fault, FaultParam, MotorFault, Phase};
pub use firmware::{
    baud_code_bps, Actuator, ModeState, MotorConfig, MotorSnapshot, PersistedMotor, PlantKind,
    ReportType, ACTUATOR_KIND, DEFAULT_HOST_ID, TURNAROUND,
};
pub use model::{Model, ModelSpec, RangeTable, Ranges};
pub use rig::{finite_or_zero, Load, Plant, RigPlant, WorldPlant};
pub use runner::{
    RobstrideBus, RobstrideConfig, RobstrideError, RobstrideHandle, RobstrideMonitor,
};
