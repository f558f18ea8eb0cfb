//! The RobStride kind's validated vocabulary: settings (the motors on the bus), the
//! `robstride` step's commands, per-motor conditions, emulator faults, and the scenario names
//! of the driver's and the emulator's enums.

use std::time::Duration;

use driver::robstride::{MitMode, OpControl, Param, Protocol, RunMode};
use sim::robstride::{Fault, MotorConfig};

use crate::scenario::{Near, Pos};

/// Settings of a `robstride` bench device: the motors on its bus.
#[derive(Debug, Clone, PartialEq)]
pub struct RobstrideSettings {
    /// The bench bus it is on (`bus:`) and where that is written; `None`: the only bus.
    pub bus: Option<(String, Pos)>,
    /// The emulated motors (CAN ID, model, load), in file order.
    pub motors: Vec<MotorConfig>,
}

/// One `robstride` step: a command to one motor (or, for `restart`, to the whole bus).
#[derive(Debug, Clone, PartialEq)]
pub struct RobstrideAction {
    /// Target CAN ID (0 for bus-wide commands).
    pub motor: u8,
    /// What to do.
    pub command: RsCommand,
}

/// Commands of the `robstride` step.
#[derive(Debug, Clone, PartialEq)]
pub enum RsCommand {
    /// Enable (type 3); the motor must report run mode.
    Enable,
    /// Stop (type 4), optionally clearing latched faults.
    Disable {
        /// Clear latched faults whose cause is gone.
        clear: bool,
    },
    /// Stop, write run_mode, read it back, enable.
    Mode(RunMode),
    /// Operation-control frame (type 1).
    OpControl(OpControl),
    /// Velocity-mode setpoint.
    Velocity {
        /// Speed.
        speed_rad_s: f32,
        /// Current limit.
        limit_cur_a: f32,
        /// Acceleration.
        acc_rad_s2: f32,
    },
    /// Profile-position move.
    Profile {
        /// Target angle.
        target_rad: f32,
        /// Speed limit.
        vel_max_rad_s: f32,
        /// Acceleration.
        acc_rad_s2: f32,
    },
    /// Current-mode setpoint.
    Current {
        /// iq reference.
        iq_a: f32,
    },
    /// Cyclic-synchronous-position setpoint.
    Csp {
        /// Target angle.
        target_rad: f32,
        /// Speed limit.
        limit_spd_rad_s: f32,
    },
    /// Set the mechanical zero here (type 6).
    SetZero,
    /// Stop, set zero, enable again.
    ZeroHere,
    /// Read a parameter and compare it with an expectation.
    ReadParam {
        /// Which parameter.
        param: Param,
        /// Expected value.
        expect: Option<Near>,
    },
    /// Write a parameter (volatile until `save`).
    WriteParam {
        /// Which parameter.
        param: Param,
        /// New value.
        value: f64,
    },
    /// Change the CAN ID (type 7); later steps address the new ID.
    SetCanId {
        /// New ID 1..=127.
        new_id: u8,
    },
    /// Save parameters to flash (type 22).
    Save,
    /// Power-cycle the emulator: motors restart from their saved state.
    Restart,
    /// Active reporting on / off (type 24).
    ActiveReport {
        /// On.
        on: bool,
    },
    /// Active-report period (EPScan_time).
    ReportPeriod {
        /// Period.
        period: Duration,
    },
    /// CAN watchdog window (canTimeout), zero = off.
    CanTimeout {
        /// Window.
        window: Duration,
    },
    /// Ask the motor for its status (type 2 poll).
    Poll,
    /// Protocol for the next power-on (type 25); `restart` makes it take effect.
    SetProtocol(Protocol),
    /// MIT variant: enable (command 1); the motor must report run mode.
    MitEnable,
    /// MIT variant: stop (command 2).
    MitStop,
    /// MIT variant: the MIT setpoint (command 3).
    MitControl(OpControl),
    /// MIT variant: run mode (command 6), read back with command 14.
    MitMode(MitMode),
    /// MIT variant: position-mode setpoint (command 10).
    MitPosition {
        /// Target angle.
        target_rad: f32,
        /// Speed limit.
        limit_spd_rad_s: f32,
    },
    /// MIT variant: velocity-mode setpoint (command 11).
    MitVelocity {
        /// Speed.
        speed_rad_s: f32,
        /// Current limit.
        limit_cur_a: f32,
    },
    /// MIT variant: set the mechanical zero (command 4).
    MitZero,
    /// MIT variant: clear latched faults (command 5, F_CMD 0xFF).
    MitClear,
    /// MIT variant: read a parameter (command 14) and compare it with an expectation.
    MitReadParam {
        /// Which parameter.
        param: Param,
        /// Expected value.
        expect: Option<Near>,
    },
    /// MIT variant: protocol for the next power-on (command 8).
    MitSetProtocol(Protocol),
    /// MIT variant: active reporting of Response 1 frames on / off (command 13).
    MitActiveReport {
        /// On.
        on: bool,
    },
    /// Emulator: inject a fault (its cause is set, or a one-shot event latched).
    Inject(Fault),
    /// Emulator: remove a fault's cause (the latched bit stays until `disable` with clear).
    RemoveCause(Fault),
    /// Emulator: set the winding temperature.
    SetTemperature {
        /// Temperature.
        temp_c: f64,
    },
    /// Emulator: set the supply voltage.
    SetBusVoltage {
        /// Voltage.
        voltage_v: f64,
    },
    /// Emulator: push the load with an external torque.
    ExternalTorque {
        /// Torque.
        torque_nm: f64,
    },
}

impl RsCommand {
    /// Whether the command acts on the emulator (unavailable against a separate process).
    pub fn needs_emulator(&self) -> bool {
        matches!(
            self,
            Self::Restart
                | Self::Inject(_)
                | Self::RemoveCause(_)
                | Self::SetTemperature { .. }
                | Self::SetBusVoltage { .. }
                | Self::ExternalTorque { .. }
        )
    }

    /// Whether the command speaks the MIT variant (11-bit frames).
    pub fn is_mit(&self) -> bool {
        matches!(
            self,
            Self::MitEnable
                | Self::MitStop
                | Self::MitControl(_)
                | Self::MitMode(_)
                | Self::MitPosition { .. }
                | Self::MitVelocity { .. }
                | Self::MitZero
                | Self::MitClear
                | Self::MitReadParam { .. }
                | Self::MitSetProtocol(_)
                | Self::MitActiveReport { .. }
        )
    }

    /// The command's name as written after `do:`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Enable => "enable",
            Self::Disable { .. } => "disable",
            Self::Mode(_) => "mode",
            Self::OpControl(_) => "op_control",
            Self::Velocity { .. } => "velocity",
            Self::Profile { .. } => "profile",
            Self::Current { .. } => "current",
            Self::Csp { .. } => "csp",
            Self::SetZero => "set_zero",
            Self::ZeroHere => "zero_here",
            Self::ReadParam { .. } => "read_param",
            Self::WriteParam { .. } => "write_param",
            Self::SetCanId { .. } => "set_can_id",
            Self::Save => "save",
            Self::Restart => "restart",
            Self::ActiveReport { .. } => "active_report",
            Self::ReportPeriod { .. } => "report_period",
            Self::CanTimeout { .. } => "can_timeout",
            Self::Poll => "poll",
            Self::SetProtocol(_) => "set_protocol",
            Self::MitEnable => "mit_enable",
            Self::MitStop => "mit_stop",
            Self::MitControl(_) => "mit_control",
            Self::MitMode(_) => "mit_mode",
            Self::MitPosition { .. } => "mit_position",
            Self::MitVelocity { .. } => "mit_velocity",
            Self::MitZero => "mit_zero",
            Self::MitClear => "mit_clear",
            Self::MitReadParam { .. } => "mit_read_param",
            Self::MitSetProtocol(_) => "mit_set_protocol",
            Self::MitActiveReport { .. } => "mit_active_report",
            Self::Inject(_) => "inject",
            Self::RemoveCause(_) => "remove_cause",
            Self::SetTemperature { .. } => "set_temperature",
            Self::SetBusVoltage { .. } => "set_bus_voltage",
            Self::ExternalTorque { .. } => "external_torque",
        }
    }
}

/// Names of the run modes (`mode:`).
pub const RUN_MODES: [(RunMode, &str); 6] = [
    (RunMode::OperationControl, "op_control"),
    (RunMode::ProfilePosition, "profile"),
    (RunMode::Velocity, "velocity"),
    (RunMode::Current, "current"),
    (RunMode::ZeroReturn, "zero_return"),
    (RunMode::CyclicPosition, "csp"),
];

/// Names of the protocols (`protocol:`).
pub const PROTOCOLS: [(Protocol, &str); 3] = [
    (Protocol::Private, "private"),
    (Protocol::CanOpen, "canopen"),
    (Protocol::Mit, "mit"),
];

/// Names of the MIT variant's run modes (`mode:` of `mit_mode`).
pub const MIT_MODES: [(MitMode, &str); 3] = [
    (MitMode::Mit, "mit"),
    (MitMode::Position, "position"),
    (MitMode::Velocity, "velocity"),
];

/// Names of the parameters (`param:`): the driver's (the manual's, in snake case).
pub fn params() -> Vec<(Param, &'static str)> {
    Param::ALL.iter().map(|p| (*p, p.name())).collect()
}

/// Names of the status-frame fault bits (bits 16..21), in bit order.
pub const STATUS_FAULTS: [&str; 6] = [
    "under_voltage",
    "over_current",
    "over_temperature",
    "encoder",
    "stall_overload",
    "uncalibrated",
];

/// Names of the type-21 fault-report flags.
pub const REPORT_FLAGS: [&str; 10] = [
    "over_temperature",
    "gate_driver",
    "under_voltage",
    "over_voltage",
    "phase_a_over_current",
    "phase_b_over_current",
    "phase_c_over_current",
    "uncalibrated",
    "stall_overload",
    "over_temperature_warning",
];

/// Mode-state names (`mode_state:`).
pub const MODE_STATES: [&str; 4] = ["reset", "calibration", "run", "brake"];

/// Kinds of the last feedback frame (`feedback:`).
pub const FEEDBACK_KINDS: [&str; 2] = ["reply", "active_report"];

/// A condition on one motor (`motors: {ID: {...}}` in `expect` / `wait_until`).
#[derive(Debug, Clone, PartialEq)]
pub enum MotorCond {
    /// Angle near.
    Position(Near),
    /// Speed near.
    Velocity(Near),
    /// Torque near.
    Torque(Near),
    /// Temperature at or above.
    TempMin(f64),
    /// Temperature at or below.
    TempMax(f64),
    /// Mode state equals.
    ModeState(&'static str),
    /// Exactly these status fault bits.
    StatusFaults(Vec<&'static str>),
    /// Exactly these type-21 flags.
    FaultReport(Vec<&'static str>),
    /// Kind of the last status frame.
    Feedback(&'static str),
}

/// A condition on one motor.
#[derive(Debug, Clone, PartialEq)]
pub struct MotorCheck {
    /// CAN ID.
    pub motor: u8,
    /// The condition.
    pub cond: MotorCond,
}

/// An emulator fault on one motor of the bus (`fault: {over_temperature: {motor: 1}}`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RsFault {
    /// CAN ID of the motor.
    pub motor: u8,
    /// The emulator's fault.
    pub fault: Fault,
}

impl RsFault {
    /// Short description for logs and reports.
    pub fn describe(&self) -> String {
        format!("{} motor {}", self.fault.label(), self.motor)
    }
}

/// The scenario name of an emulator fault: the emulator's own.
pub fn fault_name(fault: Fault) -> &'static str {
    fault.name()
}
