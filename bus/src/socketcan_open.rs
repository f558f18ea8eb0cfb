//! The one way front ends open a SocketCAN interface, on every platform.

use std::sync::Arc;

use crate::{BusError, CanBus};

/// Open the SocketCAN interface `iface` (`vcan0`, `can0`) as a shared bus endpoint without
/// own-loopback: [`SocketCanBus::open`](crate::socketcan_bus::SocketCanBus::open) on Linux. Must
/// be called inside a tokio runtime with I/O enabled; the socket belongs to that runtime.
///
/// Front ends show the error as it is (at most prefixed with what they were opening for), so
/// every one says the same thing.
///
/// # Errors
///
/// Each names `iface` and says what to do: [`BusError::NoSuchInterface`] (how to create a
/// vcan), [`BusError::InterfaceDown`] (how to bring it up), [`BusError::Io`] for anything else
/// with the operating system's error (no permission, a kernel without SocketCAN, a device that
/// is not CAN). On other platforms than Linux always [`BusError::Unsupported`].
#[cfg(target_os = "linux")]
pub fn open_socketcan(iface: &str) -> Result<Arc<dyn CanBus>, BusError> {
    Ok(Arc::new(crate::socketcan_bus::SocketCanBus::open(iface)?))
}

/// Open the SocketCAN interface `iface` (`vcan0`, `can0`) as a shared bus endpoint: SocketCAN
/// exists only on Linux.
///
/// # Errors
///
/// Always [`BusError::Unsupported`] on this platform.
#[cfg(not(target_os = "linux"))]
pub fn open_socketcan(iface: &str) -> Result<Arc<dyn CanBus>, BusError> {
    let _ = iface;
    Err(BusError::Unsupported)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[cfg(target_os = "linux")]
    #[tokio::test]
    async fn a_missing_interface_is_named_with_how_to_create_it() {
        let Err(error) = open_socketcan("armhil-nosuch0") else {
            panic!("a missing interface opened");
        };
        assert!(matches!(&error, BusError::NoSuchInterface { iface } if iface == "armhil-nosuch0"));
        let text = error.to_string();
        assert!(
            text.starts_with("CAN interface armhil-nosuch0 does not exist"),
            "{text}"
        );
        assert!(
            text.contains(
                "`sudo ip link add dev armhil-nosuch0 type vcan && sudo ip link set up armhil-nosuch0`"
            ),
            "{text}"
        );
    }

    #[cfg(not(target_os = "linux"))]
    #[test]
    fn socketcan_is_refused_off_linux() {
        let Err(error) = open_socketcan("vcan0") else {
            panic!("SocketCAN opened off Linux");
        };
        assert!(matches!(error, BusError::Unsupported));
        assert!(error.to_string().contains("only on Linux"), "{error}");
    }
}
