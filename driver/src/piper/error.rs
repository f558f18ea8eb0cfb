//! The driver's error type.

use std::time::Duration;

use bus::BusError;

use super::codec::{AckedCommand, DecodeError, FirmwareVersion, JointMask};

/// What a client-side limit applies to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum LimitedAxis {
    /// Joint 1–6 (values in rad).
    Joint(u8),
    /// The gripper stroke (values in m).
    Gripper,
}

impl std::fmt::Display for LimitedAxis {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Joint(joint) => write!(f, "joint {joint}"),
            Self::Gripper => write!(f, "gripper"),
        }
    }
}

/// Why a driver operation failed.
#[derive(Debug, thiserror::Error)]
pub enum PiperError {
    /// The bus refused a frame or failed.
    #[error("bus error: {source}")]
    Bus {
        /// The bus's error.
        #[from]
        source: BusError,
    },
    /// No reply (or confirmation) arrived within the deadline.
    #[error("timed out after {waited:?} waiting for {what}")]
    Timeout {
        /// What was awaited.
        what: &'static str,
        /// How long the driver waited.
        waited: Duration,
    },
    /// The arm answered but refused the request (e.g. a 0x476 ack with a failed zero-set).
    #[error("arm rejected {command:?}: {reason}")]
    Rejected {
        /// The acknowledged command.
        command: AckedCommand,
        /// Why it counts as a rejection.
        reason: &'static str,
    },
    /// A value is outside the client-side limit and the policy is `Reject`.
    #[error(
        "{joint} target {value} is outside the limit {limit} (rad for joints, m for the gripper)"
    )]
    OutOfLimit {
        /// Joint or gripper.
        joint: LimitedAxis,
        /// The requested value (rad or m).
        value: f64,
        /// The limit it crossed (rad or m).
        limit: f64,
    },
    /// A joint index outside 1–6.
    #[error("joint {joint} is not 1-6")]
    InvalidJoint {
        /// The index given.
        joint: u8,
    },
    /// A numeric argument outside what the wire can carry (NaN, speed above 100 %, …).
    #[error("{field} = {value} is not a valid value")]
    InvalidValue {
        /// The argument's name.
        field: &'static str,
        /// The value given.
        value: f64,
    },
    /// Motors did not confirm enable/disable through the 0x261–0x266 bit 6 in time.
    #[error("{} not confirmed after {waited:?}: wanted joints {:?}, confirmed {:?}", if *.enable { "enable" } else { "disable" }, .wanted.joints(), .confirmed.joints())]
    EnableTimeout {
        /// True for enable, false for disable.
        enable: bool,
        /// Joints that had to confirm.
        wanted: JointMask,
        /// Joints that did confirm.
        confirmed: JointMask,
        /// How long the driver waited.
        waited: Duration,
    },
    /// Another driver instance already owns this bus.
    #[error("bus {bus} already has a Piper driver attached")]
    AlreadyOwned {
        /// Bus name.
        bus: String,
    },
    /// The driver was disconnected.
    #[error("driver is disconnected")]
    Disconnected,
    /// A reply frame could not be decoded.
    #[error("undecodable reply: {source}")]
    Decode {
        /// The decoder's error.
        #[from]
        source: DecodeError,
    },
    /// The feature needs a newer firmware than the arm runs.
    #[error("{feature} needs a newer firmware than {firmware}")]
    Unsupported {
        /// The feature.
        feature: &'static str,
        /// The arm's firmware.
        firmware: FirmwareVersion,
    },
}
