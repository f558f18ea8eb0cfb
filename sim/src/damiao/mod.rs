//! Damiao (DM) joint-motor emulator: the 11-bit CAN protocol of DM-J4310/4340/8009/… motors
//! (protocol page `docs/protocols/damiao.md`), the OpenArm's actuators. Any number of motors
//! on one bus, each driving a single shaft.
//!
//! - [`DamiaoMotor`]: one motor's firmware (pure: frames in, frames out, 1 ms ticks), also
//!   [`crate::actuator::ActuatorFirmware`] for robots.
//! - [`model`]: the models' MIT ranges (PMAX/VMAX/TMAX) and plant facts; [`registers`]: the
//!   register table and values; [`codec`]: the wire layouts; [`faults`]: the errors of the
//!   state nibble as injectable faults.
//! - [`DamiaoBus::spawn`]: several motors on one [`bus::CanBus`], with a [`DamiaoHandle`] for
//!   the harness (`inject`, `clear`, `set_temperature`, `set_external_torque`, `snapshot`,
//!   `shutdown`) and a [`DamiaoMonitor`] for front ends (`target`: its faults through
//!   [`crate::fault_desk::FaultTarget`]). Works under a paused tokio clock. With a state file
//!   ([`state_file`]) the motors keep their saved registers, ids and zero across restarts.
//!
//! Behaviour the note leaves open, and what the emulator does:
//! - Frames: standard frames only (extended ones are ignored), classic or CAN FD (the OpenArm
//!   runs its buses as CAN FD with the classic payloads inside): a motor answers in the format
//!   it was addressed in, a CAN FD request with CAN FD frames carrying its flags (BRS, ESI).
//! - A command whose payload is shorter than its layout (MIT, pos-vel, force-pos and
//!   specials 8 bytes; velocity 4; register requests 3, plus the RID for read/write and the
//!   value for write) is ignored without a reply. A NaN or infinite f32 setpoint leaves the
//!   setpoint unchanged and is still answered.
//! - Every frame on one of the motor's identifiers (well formed or not, any mode) feeds the
//!   CAN timeout; a frame on 0x7FF does when D0..D1 carry the motor's ESC_ID.
//! - The timeout is checked once per 1 ms tick, so it fires on the first tick at or past
//!   TIMEOUT × 50 µs of silence (a resolution of 1 ms).
//! - Enabling holds: the position modes' target becomes the present angle, velocity mode's
//!   0 rad/s, and MIT's gains and torque are zero until the first setpoint. A setpoint sent
//!   while disabled is answered and kept (a later enable resets it as above).
//! - `FE` (set zero) is taken only while disabled; while enabled it is answered and ignored.
//!   The zero is kept in flash at once (a persist request), like a save.
//! - Several latched errors: the feedback shows the lowest code. `FB` answers with the state
//!   after clearing (0 when every cause is gone).
//! - Register writes: a read-only register, an out-of-range value (the note's ranges; PMAX,
//!   VMAX, TMAX positive; every f32 finite) is refused and the unchanged value echoed; an
//!   unknown RID gets no reply. The echo (and a read's reply) goes out on the MST_ID and with
//!   the ESC_ID in force when the request arrived, so writing ESC_ID or MST_ID answers where
//!   the host waits and moves the motor from the next frame on.
//! - CTRL_MODE may be written while enabled; the new mode starts by holding the present state.
//! - Save (0xAA) gets no reply (none is documented) and is ignored while enabled; refresh
//!   (0xCC) gets a feedback frame. can_br is stored and saved but the emulated bus keeps its
//!   bit rate.
//! - Registers 60–62 and 80–81 read the live supply, temperatures and positions; the loop
//!   gains 25–28 are served but the emulator's loops derive their gains from the plant's
//!   inertia (see `firmware/control.rs`).
//! - Position feedback saturates at ±PMAX (the note's clamp-then-scale), it does not wrap.
//! - Force-position: the current limit scales the model's peak torque (Imax drives the peak).
//! - Temperatures stay where set (ambient, or a fault's); there is no thermal model yet.

pub mod actuator;
pub mod codec;
pub mod faults;
mod firmware;
pub mod model;
pub mod registers;
mod runner;
pub mod state_file;
mod target;

pub use faults::{ErrorSet, Fault, Injection, Thresholds};
pub use firmware::{
    ControlMode, DamiaoMotor, MotorConfig, PersistedMotor, EXTERNAL_TORQUE_PEAK_MULTIPLE, KIND,
    MAX_ID, OPENARM_MST_OFFSET, TURNAROUND,
};
pub use model::{MitRanges, Model, ModelSpec};
pub use runner::{DamiaoBus, DamiaoConfig, DamiaoError, DamiaoHandle, DamiaoMonitor};
pub use target::{MotorFault, MOTOR};
