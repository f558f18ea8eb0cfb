//! Errors a bus reports to its users.
//!
//! The interface errors ([`BusError::NoSuchInterface`], [`BusError::InterfaceDown`],
//! [`BusError::Io`]) are the one set of messages every front end shows (the CLI, the harness,
//! the Python bindings): each names the interface and says what to do about it.

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
    #[error(
        "CAN interface {iface} does not exist (is its adapter plugged in?); for a virtual one: \
         `sudo ip link add dev {iface} type vcan && sudo ip link set up {iface}`"
    )]
    NoSuchInterface {
        /// Interface name, e.g. `vcan0`.
        iface: String,
    },
    /// The network interface exists but is down (ENETDOWN).
    #[error(
        "CAN interface {iface} is down; bring it up with `sudo ip link set up {iface}` (a real \
         adapter also needs a bitrate, e.g. `sudo ip link set {iface} up type can bitrate 1000000`)"
    )]
    InterfaceDown {
        /// Interface name, e.g. `vcan0`.
        iface: String,
    },
    /// Any other operating-system error from a real interface, or an interface that is not a
    /// CAN device. No permission and a kernel without SocketCAN come with what to do. Also a
    /// CAN FD frame the endpoint cannot carry (a classic virtual bus, socket or interface,
    /// socketcand), `iface` then naming the endpoint and `source` saying what to change.
    #[error("CAN interface {iface}: {source}{}", io_hint(.source))]
    Io {
        /// Interface name, e.g. `vcan0`.
        iface: String,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// SocketCAN is not available on this platform.
    #[error("SocketCAN exists only on Linux; on this system reach the bus through socketcand")]
    Unsupported,
}

/// What to do about an interface's I/O error, when there is something to say.
fn io_hint(source: &std::io::Error) -> &'static str {
    #[cfg(target_os = "linux")]
    if source.raw_os_error() == Some(libc::EAFNOSUPPORT) {
        return "; this kernel has no SocketCAN loaded: `sudo modprobe can_raw`";
    }
    if source.kind() == std::io::ErrorKind::PermissionDenied {
        return "; this process may not use CAN sockets: run it as root, or allow CAN sockets \
                in the container or the security policy";
    }
    ""
}
