//! Emulator configuration and start-up errors.

use std::path::PathBuf;

use super::flash::{Flash, FlashError};
use super::profile::FirmwareProfile;
use crate::physics::PhysicsError;
use crate::state_file::InvalidField;

/// The project's Piper URDF, compiled in so the emulator works from any working directory.
pub const BUNDLED_URDF: &str =
    include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/../urdf/piper.urdf"));

/// How to start a [`super::PiperEmulator`].
#[derive(Debug, Clone, PartialEq)]
pub struct PiperConfig {
    /// The firmware release to impersonate.
    pub firmware: FirmwareProfile,
    /// Reported joint angles at power-on, rad (J1…J6).
    pub initial_joints_rad: [f64; 6],
    /// Gripper opening at power-on, m.
    pub initial_gripper_stroke_m: f64,
    /// JSON file holding the "flash" parameters across restarts (written atomically on change).
    pub state_file: Option<PathBuf>,
    /// Flash contents at boot when the state file is absent or does not exist yet (defaults
    /// of spec §9 when `None`).
    pub flash: Option<Flash>,
    /// URDF to simulate instead of the bundled `urdf/piper.urdf`.
    pub urdf_path: Option<PathBuf>,
    /// Supply voltage the drivers report, V (the real capture shows 48.0 V).
    pub bus_voltage_v: f64,
    /// 0x477 byte 2 value that switches periodic 0x481–0x486 feedback *on* (spec §14 #7:
    /// majority 0x01; the other value switches it off).
    pub periodic_48x_on_code: u8,
    /// Physics steps run per wake-up of the core task (1–25, default 1). Physics always steps
    /// at 1 kHz and feedback keeps its 200/40 Hz cadence; a larger value only batches the
    /// steps (fewer timer wake-ups, less CPU in real time) at the cost of up to
    /// `ticks_per_wake − 1` ms extra latency before a host command is seen. `armhil sim piper`
    /// uses 5 (one wake-up per 200 Hz feedback group).
    pub ticks_per_wake: u32,
    /// Most missed 1 ms steps one wake-up catches up in real time (`None`: 100). A machine too
    /// slow to run physics in real time (an emulated VM) does better with a small budget: the
    /// emulator then falls behind the wall clock instead of starving the other processes.
    pub max_catch_up_steps: Option<u64>,
}

impl Default for PiperConfig {
    fn default() -> Self {
        Self {
            firmware: FirmwareProfile::V1_8_2,
            initial_joints_rad: [0.0; 6],
            initial_gripper_stroke_m: 0.0,
            state_file: None,
            flash: None,
            urdf_path: None,
            bus_voltage_v: 48.0,
            periodic_48x_on_code: 0x01,
            ticks_per_wake: 1,
            max_catch_up_steps: None,
        }
    }
}

/// Why the emulator could not start.
#[derive(Debug, thiserror::Error)]
pub enum PiperError {
    /// The URDF could not be loaded or the world not built.
    #[error(transparent)]
    Physics(#[from] PhysicsError),
    /// The state file could not be read, or holds a value the firmware's commands refuse.
    #[error(transparent)]
    Flash(#[from] FlashError),
    /// [`PiperConfig::flash`] holds a value the firmware's commands refuse.
    #[error("PiperConfig::flash: {0}")]
    InvalidFlash(InvalidField),
    /// The URDF lacks a joint the Piper needs (`joint1`…`joint8`).
    #[error("URDF has no joint named {name}")]
    MissingJoint {
        /// The missing joint.
        name: String,
    },
    /// An initial joint angle lies outside the URDF's range.
    #[error(
        "initial angle of joint {joint} ({value_rad} rad) is outside [{lower_rad}, {upper_rad}]"
    )]
    InitialJointOutOfRange {
        /// Joint 1–6.
        joint: usize,
        /// The value given.
        value_rad: f64,
        /// URDF lower limit.
        lower_rad: f64,
        /// URDF upper limit.
        upper_rad: f64,
    },
    /// `spawn` was called outside a tokio runtime.
    #[error("PiperEmulator::spawn must be called inside a tokio runtime")]
    NoRuntime,
}
