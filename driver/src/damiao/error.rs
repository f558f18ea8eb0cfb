//! Errors of the Damiao driver.

use std::time::Duration;

use crate::damiao::codec::{ControlMode, Feedback, MotorState};
use crate::damiao::model::Ranges;
use crate::damiao::register::{Register, RegisterKind};

/// A motor answered with an error state (over-voltage, communication lost, …).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("motor {motor:#04x} on {bus} reports {state}")]
pub struct MotorError {
    /// The motor's ESC_ID.
    pub motor: u16,
    /// The bus it is on.
    pub bus: String,
    /// The error state of its reply.
    pub state: MotorState,
    /// The whole reply (position, temperatures, …).
    pub feedback: Feedback,
}

/// Why a driver request failed.
#[derive(Debug, thiserror::Error)]
pub enum DamiaoError {
    /// The bus refused the frame or is gone.
    #[error("bus error: {0}")]
    Bus(#[from] bus::BusError),
    /// A frame could not be built (an identifier out of range).
    #[error("frame error: {0}")]
    Frame(#[from] bus::FrameError),
    /// The motor did not answer in time. A command for a control mode other than the motor's
    /// goes unanswered too.
    #[error("motor {motor:#04x} on {bus}: no reply to {request} within {after:?}")]
    Timeout {
        /// The motor's ESC_ID.
        motor: u16,
        /// The bus it is on.
        bus: String,
        /// What was asked.
        request: &'static str,
        /// How long the driver waited.
        after: Duration,
    },
    /// The motor answered with an error state.
    #[error(transparent)]
    Motor(#[from] MotorError),
    /// The motor answered an enable still disabled.
    #[error("motor {motor:#04x} on {bus} did not enable: it reports {state}")]
    EnableRefused {
        /// The motor's ESC_ID.
        motor: u16,
        /// The bus it is on.
        bus: String,
        /// The state of its reply.
        state: MotorState,
    },
    /// The motor is known to be in another control mode, where it would ignore the command;
    /// nothing was sent.
    #[error(
        "motor {motor:#04x} on {bus} is in {mode} mode; a {command} command would go unanswered"
    )]
    WrongMode {
        /// The motor's ESC_ID.
        motor: u16,
        /// The bus it is on.
        bus: String,
        /// The mode the motor is in (last written or read).
        mode: ControlMode,
        /// The mode the command belongs to.
        command: ControlMode,
    },
    /// CTRL_MODE read back another value after a mode change.
    #[error("motor {motor:#04x} on {bus}: CTRL_MODE reads {actual} after writing {wanted} ({wanted_code})", wanted_code = .wanted.code())]
    ModeNotApplied {
        /// The motor's ESC_ID.
        motor: u16,
        /// The bus it is on.
        bus: String,
        /// The mode asked for.
        wanted: ControlMode,
        /// The CTRL_MODE value read back.
        actual: u32,
    },
    /// A command value outside its range (or not finite); nothing was sent.
    #[error("{field} = {value} is outside {min}..={max}")]
    OutOfRange {
        /// Which value.
        field: &'static str,
        /// The value given.
        value: f64,
        /// Smallest allowed.
        min: f64,
        /// Largest allowed.
        max: f64,
    },
    /// A write to a read-only register; nothing was sent.
    #[error("register {register} is read-only")]
    ReadOnlyRegister {
        /// The register.
        register: Register,
    },
    /// A register value of the wrong wire type; nothing was sent.
    #[error("register {register} holds {expected} values")]
    WrongValueType {
        /// The register.
        register: Register,
        /// Its wire type.
        expected: RegisterKind,
    },
    /// An ESC_ID above 0x4FE (0x300 + ESC_ID must stay below 0x7FF) or an MST_ID of 0x7FF.
    #[error("ESC_ID {esc_id:#x} / MST_ID {mst_id:#x}: ESC_ID must be at most 0x4FE, MST_ID at most 0x7FE")]
    InvalidId {
        /// The ESC_ID given.
        esc_id: u16,
        /// The MST_ID given.
        mst_id: u16,
    },
    /// Another handle on this driver already uses this ESC_ID or MST_ID.
    #[error("identifier {id:#x} already belongs to a motor handle on this bus")]
    IdInUse {
        /// The identifier.
        id: u16,
    },
    /// Ranges that are not finite and positive.
    #[error("invalid MIT ranges {ranges:?}: PMAX, VMAX and TMAX must be finite and above zero")]
    InvalidRanges {
        /// The ranges given.
        ranges: Ranges,
    },
    /// The driver's receive task has stopped (the bus closed).
    #[error("the Damiao driver has stopped")]
    Closed,
}
