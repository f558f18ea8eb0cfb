//! Errors a bus reports to its users.

/// Why a bus operation failed.
#[derive(Debug, thiserror::Error)]
pub enum BusError {
    /// The node's transmit queue is full (the virtual bus's equivalent of ENOBUFS).
    #[error("transmit queue full ({capacity} frames pending)")]
    TxQueueFull {
        /// The queue's capacity in frames.
        capacity: usize,
    },
    /// The bus or this endpoint was closed.
    #[error("bus closed")]
    Closed,
    /// The controller is bus-off and transmits nothing until it recovers.
    #[error("bus-off")]
    BusOff,
    /// The network interface does not exist (ENODEV / ENXIO: never created, or removed).
    #[error("no such interface {iface}")]
    NoSuchInterface {
        /// Interface name, e.g. `vcan0`.
        iface: String,
    },
    /// The network interface exists but is down (ENETDOWN).
    #[error("interface {iface} is down")]
    InterfaceDown {
        /// Interface name, e.g. `vcan0`.
        iface: String,
    },
    /// An operating-system I/O error from a real interface.
    #[error("I/O error on {iface}: {source}")]
    Io {
        /// Interface name, e.g. `vcan0`.
        iface: String,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// SocketCAN is not available on this platform.
    #[error("SocketCAN is only available on Linux")]
    Unsupported,
}
