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

/// Open `iface` as [`open_socketcan`] does, for CAN FD: the socket receives classic and CAN FD
/// frames and sends CAN FD frames when the interface's MTU is 72 (`ip link set IFACE mtu 72`;
/// on an interface of MTU 16 it works as a classic socket, and an FD frame sent is refused
/// with an error that says how to set the MTU). For an emulator whose devices speak CAN FD.
///
/// # Errors
///
/// As [`open_socketcan`].
#[cfg(target_os = "linux")]
pub fn open_socketcan_fd(iface: &str) -> Result<Arc<dyn CanBus>, BusError> {
    let options = crate::socketcan_bus::SocketCanOptions {
        fd: true,
        ..Default::default()
    };
    Ok(Arc::new(crate::socketcan_bus::SocketCanBus::open_with(
        iface, options,
    )?))
}

/// Open `iface` for CAN FD: SocketCAN exists only on Linux.
///
/// # Errors
///
/// Always [`BusError::Unsupported`] on this platform.
#[cfg(not(target_os = "linux"))]
pub fn open_socketcan_fd(iface: &str) -> Result<Arc<dyn CanBus>, BusError> {
    let _ = iface;
    Err(BusError::Unsupported)
}

/// Open `iface` for CAN FD when `fd`, else classic: [`open_socketcan_fd`] or
/// [`open_socketcan`].
///
/// # Errors
///
/// As [`open_socketcan`].
pub fn open_socketcan_for(iface: &str, fd: bool) -> Result<Arc<dyn CanBus>, BusError> {
    if fd {
        open_socketcan_fd(iface)
    } else {
        open_socketcan(iface)
    }
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
