//! Firmware emulators of robot arms and actuators on a rapier3d physics world.
//!
//! - [`actuator`]: the actuator contract: any kind's firmware driving a robot joint.
//! - [`fault_args`]: a named fault's arguments as a front end read them (scenario, web view,
//!   Python), for each emulator's one fault builder.
//! - [`fault_desk`]: the contract a front end (web view, Python) reaches a running emulator's
//!   faults through, and the desk that builds, applies and remembers them.
//! - [`damiao`]: Damiao (DM) joint motors, the OpenArm's actuators (CAN, 11-bit IDs).
//! - [`cpu_budget`]: how much a late real-time wake-up may catch up, bounded by CPU.
//! - [`kinematics`]: modified-DH kinematics (one row type, frames, Jacobian) for every arm.
//! - [`pacer`]: an emulator clock task's wake-ups, on absolute deadlines in real time.
//! - [`physics`]: URDF loading into rapier3d, fixed-step stepping, torque-driven joints.
//! - [`piper`]: the AgileX Piper arm's firmware (CAN, 11-bit IDs).
//! - [`realman`]: the Realman arm controller (JSON over TCP, realtime push over UDP).
//! - [`realtime`]: timing figures a real-time emulator keeps (frame periods, overruns).
//! - [`robstride`]: RobStride quasi-direct-drive actuators (CAN: the private 29-bit
//!   protocol and the 11-bit MIT and CANopen variants).
//! - [`state_file`]: what the emulators' state files share (kind and format header, atomic
//!   write).
//! - [`supervise`]: an emulator task's panic or failure, made observable ([`supervise::DeathWatch`]).
//! - [`robot`]: whole robots (one world, an actuator per joint, several buses) and robot files.
//! - [`yaml_words`]: the YAML reader's errors in a file author's words.

pub mod actuator;
pub mod bounded_read;
pub mod can_runner;
pub mod cpu_budget;
pub mod damiao;
pub mod description;
pub mod fault_args;
pub mod fault_desk;
pub mod kinematics;
pub mod pacer;
pub mod physics;
pub mod piper;
pub mod realman;
pub mod realtime;
pub mod robot;
pub mod robstride;
pub mod state_file;
pub mod supervise;
pub mod yaml_words;
