//! The device abstraction the runner drives: one implementation per device kind (Piper now;
//! RobStride and others plug in by implementing [`Device`] and adding a [`DeviceKind`] arm in
//! [`crate::harness::bench`]).
//!
//! [`DeviceKind`]: super::model::DeviceKind

use std::collections::BTreeMap;
use std::time::Duration;

use async_trait::async_trait;

use super::model::{Action, EmulatorFault, ErrorClass};

/// Why a device action failed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{message}")]
pub struct DeviceError {
    /// Class used by `expect_error`.
    pub class: ErrorClass,
    /// The driver's message.
    pub message: String,
}

impl DeviceError {
    /// An error of `class`.
    pub fn new(class: ErrorClass, message: impl Into<String>) -> Self {
        Self {
            class,
            message: message.into(),
        }
    }

    /// The action or fault is not available on this device / in this mode.
    pub fn unsupported(message: impl Into<String>) -> Self {
        Self::new(ErrorClass::InvalidArgument, message)
    }
}

/// What a successful action returned: named values in display form (query replies), in a
/// stable order, and mismatches against the values the step expected.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Reply {
    /// `(name, value)` pairs, e.g. `("firmware", "S-V1.8-8")`.
    pub values: Vec<(String, String)>,
    /// `(name, expected, actual)` for every expected reply value that did not match.
    pub mismatches: Vec<(String, String, String)>,
}

/// A device's state as the driver sees it, in physical units, for expectations and traces.
/// Empty vectors / `None` mean "not known yet" (no feedback received).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Observation {
    /// Joint angles.
    pub joints_deg: Vec<f64>,
    /// Joint speeds.
    pub speeds_deg_s: Vec<f64>,
    /// Motor currents.
    pub currents_a: Vec<f64>,
    /// Motor temperatures.
    pub motor_temps_c: Vec<f64>,
    /// Flange position.
    pub position_mm: Option<[f64; 3]>,
    /// Flange orientation.
    pub orientation_deg: Option<[f64; 3]>,
    /// Gripper stroke.
    pub gripper_mm: Option<f64>,
    /// Named status values (`arm_status`, `ctrl_mode`, `move_mode`, `motion`, `feedback`,
    /// `leader_frames`).
    pub status: BTreeMap<&'static str, String>,
    /// Raw arm status code (for the trace).
    pub arm_status_code: Option<u8>,
    /// Per-joint enable bits.
    pub enabled: Vec<bool>,
    /// Gripper enable bit.
    pub gripper_enabled: Option<bool>,
    /// Joints with the comm-error bit set.
    pub comm_error_joints: Vec<u8>,
    /// Joints with the angle-limit bit set.
    pub limit_error_joints: Vec<u8>,
    /// Per-joint driver fault flags (sorted names).
    pub joint_flags: Vec<Vec<String>>,
    /// Gripper fault flags (sorted names).
    pub gripper_flags: Vec<String>,
    /// RobStride motors by CAN ID (empty for other devices).
    pub motors: BTreeMap<u8, super::robstride::MotorObservation>,
}

/// A device on the bench: its driver (always) and its emulator (in-process runs).
#[async_trait]
pub trait Device: Send + Sync {
    /// The device's name in the scenario.
    fn name(&self) -> &str;

    /// Perform a driver action. `timeout` overrides the driver's default deadline.
    async fn perform(
        &self,
        action: &Action,
        timeout: Option<Duration>,
    ) -> Result<Reply, DeviceError>;

    /// The current state as the driver sees it.
    fn observe(&self) -> Observation;

    /// Apply an emulator fault (needs the in-process emulator).
    fn inject(&self, fault: &EmulatorFault) -> Result<(), DeviceError>;

    /// Clear an emulator fault, or every one when `None`.
    fn clear(&self, fault: Option<&EmulatorFault>) -> Result<(), DeviceError>;

    /// Stop the driver and the emulator.
    async fn shutdown(&self);
}
