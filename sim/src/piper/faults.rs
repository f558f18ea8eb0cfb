//! Faults the harness can trigger at run time ([`PiperFault`]) and how they show on the wire.
//!
//! | Fault | Wire effect | Cleared by |
//! |---|---|---|
//! | `JointCommLoss` | 0x2A1 byte 7 bit, arm_status 0x05, that joint's 0x25x/0x26x stop, motor off | `clear` |
//! | `MotorOverTemp` / `DriverOverTemp` | temperature forced above threshold: 0x26x bit 1 / bit 3, driver disables, arm_status 0x09 | `clear` (temperature returns to the thermal model); re-enable |
//! | `OverCurrent`, `DriverError`, `Stall` | latched 0x26x bit 2 / 5 / 7, driver disables, arm_status 0x09 | 0x475 clear error, 0x150 reset or `clear` |
//! | `UnderVoltage` | bus voltage in 0x26x drops, bit 0 on every joint, drivers disable, arm_status 0x09 | `clear`; re-enable |
//! | `ExternalTorque` | torque applied in the physics world; above the collision threshold the arm stops with arm_status 0x07 and 0x26x bit 4 | `clear` removes the torque; the collision latch clears with 0x150 reset or 0x475 clear error |
//! | `Collision` | forced collision latch on a joint | as above |
//! | `EStop` | physical e-stop: damping mode, arm_status 0x01 | 0x150 reset or `clear` |
//! | `MainControlOverTemp` / `ResistorOverTemp` | arm_status 0x0E / 0x0F, motion stops | `clear` |
//! | `GripperSensorFault` | 0x2A8 bit 4, gripper stops | `clear` |
//! | `TeachButton` | ctrl_mode 0x02, arm compliant (gravity compensation) | `clear` (button pressed again → standby) |

/// A fault the harness injects into a running emulator. Joints are numbered 1–6 as on the wire.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PiperFault {
    /// The master loses contact with one joint driver.
    JointCommLoss {
        /// Joint 1–6.
        joint: u8,
    },
    /// Motor winding over-temperature (temperature forced to `temp_c`).
    MotorOverTemp {
        /// Joint 1–6.
        joint: u8,
        /// Forced winding temperature, °C.
        temp_c: f64,
    },
    /// Driver over-temperature (temperature forced to `temp_c`).
    DriverOverTemp {
        /// Joint 1–6.
        joint: u8,
        /// Forced driver temperature, °C.
        temp_c: f64,
    },
    /// Driver over-current protection trips (latched).
    OverCurrent {
        /// Joint 1–6.
        joint: u8,
    },
    /// Supply voltage sags to `voltage_v` (all joints).
    UnderVoltage {
        /// Bus voltage, V.
        voltage_v: f64,
    },
    /// Generic driver error (latched).
    DriverError {
        /// Joint 1–6.
        joint: u8,
    },
    /// Stall protection trips (latched).
    Stall {
        /// Joint 1–6.
        joint: u8,
    },
    /// A persistent external torque on a joint, applied in the physics world.
    ExternalTorque {
        /// Joint 1–6.
        joint: u8,
        /// Torque, N·m.
        torque_nm: f64,
    },
    /// Collision protection triggered on a joint without a physical cause.
    Collision {
        /// Joint 1–6.
        joint: u8,
    },
    /// The physical e-stop.
    EStop,
    /// Main-control board NTC over-temperature.
    MainControlOverTemp,
    /// Brake-resistor NTC over-temperature.
    ResistorOverTemp,
    /// Gripper sensor fault.
    GripperSensorFault,
    /// The teach (drag) button on the arm is pressed.
    TeachButton,
}

/// Which fault to clear: the same variants as [`PiperFault`] without their values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum PiperFaultKind {
    /// See [`PiperFault::JointCommLoss`].
    JointCommLoss {
        /// Joint 1–6.
        joint: u8,
    },
    /// See [`PiperFault::MotorOverTemp`].
    MotorOverTemp {
        /// Joint 1–6.
        joint: u8,
    },
    /// See [`PiperFault::DriverOverTemp`].
    DriverOverTemp {
        /// Joint 1–6.
        joint: u8,
    },
    /// See [`PiperFault::OverCurrent`].
    OverCurrent {
        /// Joint 1–6.
        joint: u8,
    },
    /// See [`PiperFault::UnderVoltage`].
    UnderVoltage,
    /// See [`PiperFault::DriverError`].
    DriverError {
        /// Joint 1–6.
        joint: u8,
    },
    /// See [`PiperFault::Stall`].
    Stall {
        /// Joint 1–6.
        joint: u8,
    },
    /// See [`PiperFault::ExternalTorque`].
    ExternalTorque {
        /// Joint 1–6.
        joint: u8,
    },
    /// See [`PiperFault::Collision`].
    Collision {
        /// Joint 1–6.
        joint: u8,
    },
    /// See [`PiperFault::EStop`].
    EStop,
    /// See [`PiperFault::MainControlOverTemp`].
    MainControlOverTemp,
    /// See [`PiperFault::ResistorOverTemp`].
    ResistorOverTemp,
    /// See [`PiperFault::GripperSensorFault`].
    GripperSensorFault,
    /// See [`PiperFault::TeachButton`].
    TeachButton,
}

impl PiperFault {
    /// The kind, for [`crate::piper::PiperHandle::clear`].
    pub fn kind(&self) -> PiperFaultKind {
        match *self {
            Self::JointCommLoss { joint } => PiperFaultKind::JointCommLoss { joint },
            Self::MotorOverTemp { joint, .. } => PiperFaultKind::MotorOverTemp { joint },
            Self::DriverOverTemp { joint, .. } => PiperFaultKind::DriverOverTemp { joint },
            Self::OverCurrent { joint } => PiperFaultKind::OverCurrent { joint },
            Self::UnderVoltage { .. } => PiperFaultKind::UnderVoltage,
            Self::DriverError { joint } => PiperFaultKind::DriverError { joint },
            Self::Stall { joint } => PiperFaultKind::Stall { joint },
            Self::ExternalTorque { joint, .. } => PiperFaultKind::ExternalTorque { joint },
            Self::Collision { joint } => PiperFaultKind::Collision { joint },
            Self::EStop => PiperFaultKind::EStop,
            Self::MainControlOverTemp => PiperFaultKind::MainControlOverTemp,
            Self::ResistorOverTemp => PiperFaultKind::ResistorOverTemp,
            Self::GripperSensorFault => PiperFaultKind::GripperSensorFault,
            Self::TeachButton => PiperFaultKind::TeachButton,
        }
    }
}

/// A fault named a joint outside 1–6 or a non-finite value.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FaultError {
    /// Joint number outside 1–6.
    #[error("joint {joint} does not exist (Piper joints are 1–6)")]
    NoSuchJoint {
        /// The joint given.
        joint: u8,
    },
    /// A temperature, voltage or torque that is NaN or infinite.
    #[error("fault value {value} is not finite")]
    NotFinite {
        /// The value given.
        value: f64,
    },
}

/// Driver status bits of 0x261–0x266 byte 5 (spec §4.6).
pub mod driver_bits {
    /// Supply under-voltage.
    pub const UNDER_VOLTAGE: u8 = 1 << 0;
    /// Motor over-temperature.
    pub const MOTOR_OVER_TEMP: u8 = 1 << 1;
    /// Driver over-current.
    pub const OVER_CURRENT: u8 = 1 << 2;
    /// Driver over-temperature.
    pub const DRIVER_OVER_TEMP: u8 = 1 << 3;
    /// Collision protection triggered.
    pub const COLLISION: u8 = 1 << 4;
    /// Driver error.
    pub const DRIVER_ERROR: u8 = 1 << 5;
    /// Driver enabled.
    pub const ENABLED: u8 = 1 << 6;
    /// Stall protection triggered.
    pub const STALL: u8 = 1 << 7;
}

/// Gripper status bits of 0x2A8 byte 6 (spec §4.4).
pub mod gripper_bits {
    /// Supply under-voltage.
    pub const UNDER_VOLTAGE: u8 = 1 << 0;
    /// Sensor fault.
    pub const SENSOR_FAULT: u8 = 1 << 4;
    /// Driver enabled.
    pub const ENABLED: u8 = 1 << 6;
    /// Has been zeroed.
    pub const HOMED: u8 = 1 << 7;
}
