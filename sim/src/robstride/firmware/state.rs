//! What an actuator shows of itself: its mode state, what survives a restart, and a
//! point-in-time snapshot for the harness.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::{baud_code_bps, can_id_accepted, host_id_accepted, protocol_accepted, MAX_CAN_ID};
use crate::robstride::model::Model;
use crate::state_file::InvalidField;

/// Mode state in bits 23..22 of status frames; [`ModeState::name`] is how the web view and
/// Python show it (`reset`, `calibration`, `run`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, strum::IntoStaticStr)]
#[strum(serialize_all = "snake_case")]
pub enum ModeState {
    /// Torque off (power-on, after stop, fault or CAN timeout).
    Reset,
    /// Encoder calibration (or waiting for it).
    Calibration,
    /// Running (after enable).
    Run,
}

impl ModeState {
    /// Its name: `reset`, `calibration` or `run`.
    pub fn name(self) -> &'static str {
        self.into()
    }

    pub(super) fn bits(self) -> u16 {
        match self {
            ModeState::Reset => 0,
            ModeState::Calibration => 1,
            ModeState::Run => 2,
        }
    }
}

/// What survives an emulator restart (written to the state file).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PersistedMotor {
    /// CAN ID (type 7 takes effect at once and is kept).
    pub can_id: u8,
    /// Host ID replies go to.
    pub master_id: u8,
    /// Mechanical zero: plant angle that reads 0 (rad).
    pub zero_offset_rad: f64,
    /// Saved parameters (type 22), by index.
    pub params: BTreeMap<u16, f64>,
    /// Baud code for the next power-on (1 = 1M, 2 = 500k, 3 = 250k, 4 = 125k).
    pub baud_code: u8,
    /// Protocol for the next power-on (0 private, 1 CANopen, 2 MIT).
    pub protocol: u8,
}

impl PersistedMotor {
    /// Check every value with the rules the commands that store it apply (type 7 for the
    /// CAN ID, 22/23/25 for baud and protocol, any command for the host ID). Saved parameters
    /// are applied at power-on as a type-18 write would apply them (clamped to their range).
    /// The error names the field under `prefix` (`motors.<uid>`).
    pub fn validate(&self, prefix: &str) -> Result<(), InvalidField> {
        let refuse = |field: &str, problem: String| {
            Err(InvalidField::new(format!("{prefix}.{field}"), problem))
        };
        if !can_id_accepted(self.can_id) {
            return refuse(
                "can_id",
                format!("{} is outside 1..={MAX_CAN_ID}", self.can_id),
            );
        }
        if !host_id_accepted(self.master_id) {
            return refuse("master_id", "0 is not a host ID".to_owned());
        }
        if baud_code_bps(self.baud_code).is_none() {
            return refuse(
                "baud_code",
                format!("{} is not a baud code (1–4)", self.baud_code),
            );
        }
        if !protocol_accepted(self.protocol) {
            return refuse(
                "protocol",
                format!("{} is not a protocol (0–2)", self.protocol),
            );
        }
        if !self.zero_offset_rad.is_finite() {
            return refuse("zero_offset_rad", "not a finite angle".to_owned());
        }
        Ok(())
    }
}

/// A point-in-time view of one actuator for the harness.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MotorSnapshot {
    /// Current CAN ID.
    pub can_id: u8,
    /// Model.
    pub model: Model,
    /// Mode state.
    pub mode: ModeState,
    /// run_mode (0..5).
    pub run_mode: u8,
    /// Reported angle (rad, after the mechanical zero, not wrapped).
    pub angle_rad: f64,
    /// Speed (rad/s).
    pub speed_rad_s: f64,
    /// Torque the motor produces (N·m).
    pub torque_nm: f64,
    /// iq (A).
    pub iq_a: f64,
    /// Winding temperature (°C).
    pub temperature_c: f64,
    /// Supply voltage (V).
    pub bus_voltage_v: f64,
    /// Latched fault word (type-21 layout).
    pub fault_word: u32,
    /// Warning word (type-21 layout).
    pub warning_word: u32,
    /// Active reporting on.
    pub active_report: bool,
    /// Host ID replies go to.
    pub master_id: u8,
    /// Baud code in effect (1 = 1 Mbit/s …).
    pub baud_code: u8,
    /// Protocol in effect (0 private, 1 CANopen, 2 MIT).
    pub protocol: u8,
    /// False when a baud or protocol switch made the motor deaf to this bus.
    pub listening: bool,
}
