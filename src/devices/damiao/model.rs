//! The Damiao kind's validated vocabulary: settings (the motors on the bus), the `damiao`
//! step's commands, per-motor conditions, emulator faults, and the scenario names of the
//! driver's control modes and feedback states.

use std::time::Duration;

use driver::damiao::{ControlMode, MotorState, Register, RegisterValue};
use sim::damiao::{Fault, MotorConfig};
use sim::fault_args::FaultArgs;

use crate::scenario::{Near, Pos};

/// Settings of a `damiao` bench device: the motors on its bus.
#[derive(Debug, Clone, PartialEq)]
pub struct DamiaoSettings {
    /// The bench bus it is on (`bus:`) and where that is written; `None`: the only bus.
    pub bus: Option<(String, Pos)>,
    /// The emulated motors (ESC_ID, MST_ID, model, rig), in file order.
    pub motors: Vec<MotorConfig>,
}

/// One `damiao` step: a command to one motor (or, for `restart`, to the whole bus).
#[derive(Debug, Clone, PartialEq)]
pub struct DamiaoAction {
    /// The motor's ESC_ID (0 for `restart`).
    pub motor: u16,
    /// What to do.
    pub command: DmCommand,
}

/// Commands of the `damiao` step.
#[derive(Debug, Clone, PartialEq)]
pub enum DmCommand {
    /// `FC`: the reply must report enabled.
    Enable,
    /// `FD`.
    Disable,
    /// `FE`: the present position becomes zero (taken only while disabled).
    Zero,
    /// `FB`: clear the latched errors whose cause is gone.
    ClearError,
    /// An MIT command (τ = kp·(p − θ) + kd·(v − ω) + t).
    Mit {
        /// Position target.
        p_rad: f32,
        /// Velocity target.
        v_rad_s: f32,
        /// Position gain (N·m/rad).
        kp: f32,
        /// Velocity gain (N·m·s/rad).
        kd: f32,
        /// Feed-forward torque.
        t_nm: f32,
    },
    /// A position-velocity command: to `p_rad` no faster than `v_rad_s`.
    PosVel {
        /// Target.
        p_rad: f32,
        /// Speed limit.
        v_rad_s: f32,
    },
    /// A velocity command.
    Vel {
        /// Speed.
        v_rad_s: f32,
    },
    /// A force-position command: to `p_rad` no faster than `v_rad_s`, at most `i_limit` of
    /// the board's current.
    ForcePos {
        /// Target.
        p_rad: f32,
        /// Speed limit.
        v_rad_s: f32,
        /// Current limit, per unit.
        i_limit: f32,
    },
    /// Write CTRL_MODE and read it back.
    Mode(ControlMode),
    /// Read a register and compare it with an expectation.
    ReadRegister {
        /// Which register.
        register: Register,
        /// Expected value.
        expect: Option<Near>,
    },
    /// Write a register (volatile until `save`); a value the motor does not store is
    /// `rejected`.
    WriteRegister {
        /// Which register.
        register: Register,
        /// The value, in the register's wire type.
        value: RegisterValue,
    },
    /// `0xAA`: save every register to flash (no reply; ignored while enabled).
    Save,
    /// `0xCC`: ask for a feedback frame.
    Refresh,
    /// How often the host reads the motor's state (refresh); zero: never.
    Poll {
        /// The period.
        period: Duration,
    },
    /// Power-cycle the emulator: the motors come back with what they saved.
    Restart,
    /// Emulator: set the coil temperature.
    SetTemperature {
        /// Temperature.
        temp_c: f64,
    },
    /// Emulator: push the shaft with an external torque.
    ExternalTorque {
        /// Torque.
        torque_nm: f64,
    },
}

impl DmCommand {
    /// Whether the command acts on the emulator (unavailable against a separate process).
    pub fn needs_emulator(&self) -> bool {
        matches!(
            self,
            Self::Restart | Self::SetTemperature { .. } | Self::ExternalTorque { .. }
        )
    }

    /// The command's name as written after `do:`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Enable => "enable",
            Self::Disable => "disable",
            Self::Zero => "zero",
            Self::ClearError => "clear_error",
            Self::Mit { .. } => "mit",
            Self::PosVel { .. } => "pos_vel",
            Self::Vel { .. } => "vel",
            Self::ForcePos { .. } => "force_pos",
            Self::Mode(_) => "mode",
            Self::ReadRegister { .. } => "read_register",
            Self::WriteRegister { .. } => "write_register",
            Self::Save => "save",
            Self::Refresh => "refresh",
            Self::Poll { .. } => "poll",
            Self::Restart => "restart",
            Self::SetTemperature { .. } => "set_temperature",
            Self::ExternalTorque { .. } => "external_torque",
        }
    }
}

/// Names of the control modes (`mode:`), as the commands of each mode are named.
pub const MODES: [(ControlMode, &str); 4] = [
    (ControlMode::Mit, "mit"),
    (ControlMode::PosVel, "pos_vel"),
    (ControlMode::Velocity, "vel"),
    (ControlMode::ForcePos, "force_pos"),
];

/// The feedback states a `state:` condition names (the driver's names, as `armhil decode`
/// prints them), by their nibble.
pub const STATES: [(u8, &str); 9] = [
    (0x0, "disabled"),
    (0x1, "enabled"),
    (0x8, "over_voltage"),
    (0x9, "under_voltage"),
    (0xA, "over_current"),
    (0xB, "mos_over_temperature"),
    (0xC, "rotor_over_temperature"),
    (0xD, "communication_lost"),
    (0xE, "overload"),
];

/// The state a feedback nibble names ([`STATES`]'s name, or `unknown` for an undocumented
/// nibble).
pub fn state_name(state: MotorState) -> &'static str {
    STATES
        .iter()
        .find(|(code, _)| *code == state.code())
        .map_or("unknown", |(_, name)| *name)
}

/// The state a `state:` condition names, by a [`STATES`] name or by the emulator's fault
/// that latches it (`comm_lost` for `communication_lost`, `coil_over_temperature` for
/// `rotor_over_temperature`).
pub fn state_named(name: &str) -> Option<(u8, &'static str)> {
    STATES
        .iter()
        .find(|(_, n)| *n == name)
        .or_else(|| {
            let code = Fault::ALL.into_iter().find(|f| f.name() == name)?.code();
            STATES.iter().find(|(c, _)| *c == code)
        })
        .copied()
}

/// A condition on one motor (`motors: {ESC_ID: {...}}` in `expect` / `wait_until`).
#[derive(Debug, Clone, PartialEq)]
pub enum MotorCond {
    /// Position near.
    Position(Near),
    /// Velocity near.
    Velocity(Near),
    /// Torque near.
    Torque(Near),
    /// The feedback's state nibble is this one.
    State(&'static str),
    /// The driver board (MOS) temperature near.
    MosTemp(Near),
    /// The coil (rotor) temperature near.
    RotorTemp(Near),
}

/// A condition on one motor.
#[derive(Debug, Clone, PartialEq)]
pub struct MotorCheck {
    /// ESC_ID.
    pub motor: u16,
    /// The condition.
    pub cond: MotorCond,
}

/// An emulator fault on one motor of the bus (`fault: {over_voltage: {motor: 1}}`): the
/// emulator's fault and its values as written, checked against the motor's model.
#[derive(Debug, Clone, PartialEq)]
pub struct DmFault {
    /// ESC_ID of the motor.
    pub motor: u16,
    /// The emulator's fault.
    pub fault: Fault,
    /// Its values (`voltage_v`, `temperature_c`; empty: the fault's defaults).
    pub values: FaultArgs,
    /// How reports name it (`over_voltage voltage_v=40`).
    pub label: String,
}

impl DmFault {
    /// Short description for logs and reports.
    pub fn describe(&self) -> String {
        format!("{} motor {}", self.label, self.motor)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The error states are the emulator's faults, nibble for nibble, and each fault's name
    /// reads as the state it latches.
    #[test]
    fn the_states_follow_the_driver_and_the_faults_name_theirs() {
        for (code, name) in STATES {
            assert_eq!(state_name(MotorState::from_code(code)), name);
            assert_eq!(MotorState::from_code(code).name(), name);
        }
        for fault in Fault::ALL {
            let (code, _) = state_named(fault.name()).expect("a state");
            assert_eq!(code, fault.code());
        }
        assert_eq!(state_named("comm_lost"), Some((0xD, "communication_lost")));
        assert_eq!(state_named("melted"), None);
        assert_eq!(state_name(MotorState::from_code(0x5)), "unknown");
    }
}
