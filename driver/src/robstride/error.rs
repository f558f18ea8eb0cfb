//! Errors of the RobStride driver.

use std::time::Duration;

use crate::robstride::codec::StatusFaults;

/// Why a driver request failed.
#[derive(Debug, thiserror::Error)]
pub enum RobstrideError {
    /// The bus refused the frame or is gone.
    #[error("bus error: {0}")]
    Bus(#[from] bus::BusError),
    /// A frame could not be built (an identifier out of range).
    #[error("frame error: {0}")]
    Frame(#[from] bus::FrameError),
    /// The motor did not answer in time.
    #[error("motor {motor}: no reply to {request} within {after:?}")]
    Timeout {
        /// Motor CAN ID.
        motor: u8,
        /// What was asked.
        request: &'static str,
        /// The timeout.
        after: Duration,
    },
    /// A command value outside the model's range.
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
    /// The motor refused a parameter write (read-only or unknown index).
    #[error("motor {motor} refused writing parameter {index:#06x}")]
    ParamRefused {
        /// Motor CAN ID.
        motor: u8,
        /// Index.
        index: u16,
    },
    /// The motor answered a read with the failure flag.
    #[error("motor {motor} cannot read parameter {index:#06x}")]
    ParamReadFailed {
        /// Motor CAN ID.
        motor: u8,
        /// Index.
        index: u16,
    },
    /// The motor stayed out of run mode after enable (faults shown).
    #[error("motor {motor} did not enter run mode (fault bits {faults:?})")]
    EnableRefused {
        /// Motor CAN ID.
        motor: u8,
        /// Fault bits of its reply.
        faults: StatusFaults,
    },
    /// An MIT enable (command 1) answered with a mode other than run.
    #[error("motor {motor} did not enter run mode (MIT fault flag {fault})")]
    MitEnableRefused {
        /// Motor CAN ID.
        motor: u8,
        /// The fault flag of its Response 1.
        fault: bool,
    },
    /// Reading back run_mode after a switch gave another mode.
    #[error("motor {motor} is in run_mode {actual}, wanted {wanted}")]
    ModeNotApplied {
        /// Motor CAN ID.
        motor: u8,
        /// The mode asked for.
        wanted: u8,
        /// The mode read back.
        actual: u8,
    },
    /// A CAN ID outside 1..=127.
    #[error("CAN ID {id} is outside 1..=127")]
    InvalidCanId {
        /// The ID.
        id: u8,
    },
    /// Another handle already drives this motor ID.
    #[error("motor {motor} already has a handle on this bus")]
    MotorInUse {
        /// Motor CAN ID.
        motor: u8,
    },
    /// The driver's receive task has stopped.
    #[error("the RobStride driver has stopped")]
    Closed,
}
