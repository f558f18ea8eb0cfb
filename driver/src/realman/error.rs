//! Errors of the Realman driver.

use std::time::Duration;

use super::codec::types::Device;
use super::codec::EncodeError;

/// Why a Realman request failed.
#[derive(Debug, thiserror::Error)]
pub enum RealmanError {
    /// The TCP connection could not be opened.
    #[error("cannot connect to {addr}: {source}")]
    Connect {
        /// Address tried.
        addr: String,
        /// Underlying error.
        source: std::io::Error,
    },
    /// Writing the request failed.
    #[error("{command}: write failed: {source}")]
    Io {
        /// Command being sent.
        command: &'static str,
        /// Underlying error.
        source: std::io::Error,
    },
    /// The arguments cannot be encoded (out of range, not finite).
    #[error("invalid argument: {0}")]
    Encode(#[from] EncodeError),
    /// No reply within the reply timeout.
    #[error("{command}: no reply within {after:?}")]
    Timeout {
        /// Command sent.
        command: &'static str,
        /// The timeout.
        after: Duration,
    },
    /// The controller answered `false` in the result key.
    #[error("{command}: refused by the controller ({key} = false)")]
    Rejected {
        /// Command sent.
        command: &'static str,
        /// The result key that was false.
        key: &'static str,
    },
    /// The reply could not be decoded (not JSON, missing or mistyped fields).
    #[error("{command}: malformed reply: {reason}")]
    Malformed {
        /// Command sent.
        command: &'static str,
        /// What was wrong.
        reason: String,
    },
    /// The arrival event reported failure (`trajectory_state:false`).
    #[error("{command}: motion of {device:?} failed or was aborted")]
    MotionFailed {
        /// Command sent.
        command: &'static str,
        /// Device the event was about.
        device: Device,
    },
    /// A blocking motion did not arrive within the motion timeout.
    #[error("{command}: no arrival event within {after:?}")]
    MotionTimeout {
        /// Command sent.
        command: &'static str,
        /// The timeout.
        after: Duration,
    },
    /// The connection closed while the request was outstanding (or before it was sent).
    #[error("{command}: connection closed")]
    Disconnected {
        /// Command sent.
        command: &'static str,
    },
    /// `reconnect` was called on a client that was not opened from an address.
    #[error("this client has no address to reconnect to")]
    NoAddress,
}
