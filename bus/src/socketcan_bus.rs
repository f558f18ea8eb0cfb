//! Real CAN interfaces (`vcan0`, `can0`) through Linux SocketCAN.
//!
//! Receive timestamps are the kernel's socket arrival time (`SO_TIMESTAMPNS`, time since the
//! Unix epoch), or the time the frame was read if the kernel gave none. The socket also
//! receives error frames: a bus-off report becomes [`BusError::BusOff`], other controller
//! errors are logged and skipped. Remote frames are skipped (the bus carries data frames).

use std::io;
use std::time::{Duration, SystemTime};

use async_trait::async_trait;
use socketcan::{EmbeddedFrame, ErrorCause, ExtendedId, Id, SocketOptions, StandardId};
use tokio::sync::watch;

use crate::{BusError, CanBus, CanFrame, CanId, ReceivedFrame};

/// Options for [`SocketCanBus::open_with`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SocketCanOptions {
    /// Also receive the frames this socket sends (`CAN_RAW_RECV_OWN_MSGS`).
    pub receive_own: bool,
}

/// A SocketCAN raw socket bound to one interface.
pub struct SocketCanBus {
    socket: socketcan::tokio::CanSocket,
    iface: String,
    tx_queue_len: usize,
    closed: watch::Sender<bool>,
}

impl std::fmt::Debug for SocketCanBus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SocketCanBus")
            .field("iface", &self.iface)
            .finish_non_exhaustive()
    }
}

impl SocketCanBus {
    /// Open `iface` without own-loopback. Must be called inside a tokio runtime with I/O
    /// enabled. [`crate::open_socketcan`] does the same on every platform.
    ///
    /// # Errors
    ///
    /// The interface errors of [`BusError`], each naming `iface` and saying what to do:
    /// [`BusError::NoSuchInterface`], [`BusError::InterfaceDown`] (checked here, not left
    /// for the first receive), and [`BusError::Io`] for anything else, such as no permission,
    /// a kernel without SocketCAN, or an interface that is not a CAN device.
    pub fn open(iface: &str) -> Result<Self, BusError> {
        Self::open_with(iface, SocketCanOptions::default())
    }

    /// Open `iface` with options; errors as [`SocketCanBus::open`].
    pub fn open_with(iface: &str, options: SocketCanOptions) -> Result<Self, BusError> {
        let addr = socketcan::CanAddr::from_iface(iface).map_err(|error| io_error(iface, error))?;
        let socket = socketcan::tokio::CanSocket::open_addr(&addr).map_err(|error| {
            // The name resolved, so ENODEV from the bind means a device of another type.
            if matches!(error.raw_os_error(), Some(libc::ENODEV)) {
                return BusError::Io {
                    iface: iface.to_owned(),
                    source: io::Error::new(
                        io::ErrorKind::InvalidInput,
                        "not a CAN device (SocketCAN binds only CAN interfaces, such as vcan0 \
                         or can0)",
                    ),
                };
            }
            io_error(iface, error)
        })?;
        let configure = || -> io::Result<()> {
            // Binding to a down interface succeeds and leaves ENETDOWN pending for the first
            // read: report it now, as the opener's error.
            match socket.get_socket_option_int(libc::SOL_SOCKET, libc::SO_ERROR)? {
                0 => {}
                pending => return Err(io::Error::from_raw_os_error(pending)),
            }
            socket.set_recv_own_msgs(options.receive_own)?;
            socket.set_error_filter_accept_all()?;
            socket.set_recv_timestamp(true)
        };
        configure().map_err(|error| io_error(iface, error))?;
        // Only for the error a full queue reports; the kernel default is 10 for CAN devices.
        let tx_queue_len = std::fs::read_to_string(format!("/sys/class/net/{iface}/tx_queue_len"))
            .ok()
            .and_then(|text| text.trim().parse().ok())
            .unwrap_or(10);
        tracing::debug!(iface, receive_own = options.receive_own, "SocketCAN opened");
        Ok(Self {
            socket,
            iface: iface.to_owned(),
            tx_queue_len,
            closed: watch::Sender::new(false),
        })
    }

    /// Read until a data frame (or a bus-off report) arrives.
    async fn read_data_frame(&self) -> Result<ReceivedFrame, BusError> {
        loop {
            let (frame, stamps) = self
                .socket
                .read_frame_with_timestamps()
                .await
                .map_err(|error| io_error(&self.iface, error))?;
            let arrived = stamps.socket.unwrap_or_else(SystemTime::now);
            let timestamp = arrived
                .duration_since(SystemTime::UNIX_EPOCH)
                .unwrap_or(Duration::ZERO);
            match frame {
                socketcan::CanFrame::Data(data) => match from_socketcan(data.id(), data.data()) {
                    Some(frame) => return Ok(ReceivedFrame { frame, timestamp }),
                    None => tracing::warn!(iface = %self.iface, "skipping undecodable frame"),
                },
                socketcan::CanFrame::Remote(_) => {
                    tracing::trace!(iface = %self.iface, "skipping remote frame");
                }
                socketcan::CanFrame::Error(error_frame) => {
                    let error = error_frame.into_error();
                    if error
                        .causes()
                        .any(|cause| matches!(cause, ErrorCause::BusOff))
                    {
                        tracing::warn!(iface = %self.iface, "controller is bus-off");
                        return Err(BusError::BusOff);
                    }
                    tracing::warn!(iface = %self.iface, %error, "CAN error frame");
                }
            }
        }
    }
}

fn from_socketcan(id: Id, data: &[u8]) -> Option<CanFrame> {
    let id = match id {
        Id::Standard(id) => CanId::standard(id.as_raw()).ok()?,
        Id::Extended(id) => CanId::extended(id.as_raw()).ok()?,
    };
    CanFrame::new(id, data).ok()
}

fn to_socketcan(frame: &CanFrame) -> Option<socketcan::CanFrame> {
    let id: Id = match frame.id() {
        CanId::Standard(id) => StandardId::new(id)?.into(),
        CanId::Extended(id) => ExtendedId::new(id)?.into(),
    };
    socketcan::CanFrame::new(id, frame.data())
}

fn io_error(iface: &str, error: io::Error) -> BusError {
    let iface = iface.to_owned();
    match error.raw_os_error() {
        Some(libc::ENETDOWN) => BusError::InterfaceDown { iface },
        Some(libc::ENODEV | libc::ENXIO) => BusError::NoSuchInterface { iface },
        _ => BusError::Io {
            iface,
            source: error,
        },
    }
}

#[async_trait]
impl CanBus for SocketCanBus {
    async fn send(&self, frame: CanFrame) -> Result<(), BusError> {
        if *self.closed.borrow() {
            return Err(BusError::Closed);
        }
        // Our frames are validated on construction, so this cannot fail in practice.
        let Some(raw) = to_socketcan(&frame) else {
            return Err(BusError::Io {
                iface: self.iface.clone(),
                source: io::Error::new(io::ErrorKind::InvalidInput, format!("frame {frame}")),
            });
        };
        // Non-blocking like the virtual bus: a full driver queue is an error, not a wait.
        match self.socket.try_write_frame(raw) {
            Ok(()) => Ok(()),
            Err(error)
                if error.raw_os_error() == Some(libc::ENOBUFS)
                    || error.kind() == io::ErrorKind::WouldBlock =>
            {
                Err(BusError::TxQueueFull {
                    capacity: self.tx_queue_len,
                })
            }
            Err(error) => Err(io_error(&self.iface, error)),
        }
    }

    async fn recv(&self) -> Result<ReceivedFrame, BusError> {
        let mut closed = self.closed.subscribe();
        tokio::select! {
            received = self.read_data_frame() => received,
            _ = closed.wait_for(|closed| *closed) => Err(BusError::Closed),
        }
    }

    async fn close(&self) {
        self.closed.send_replace(true);
    }

    fn name(&self) -> &str {
        &self.iface
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_convert_both_ways() {
        for frame in [
            CanFrame::standard(0x7FF, &[1, 2, 3]).unwrap(),
            CanFrame::extended(0x1FFF_FFFF, &[]).unwrap(),
            CanFrame::extended(0x5, &[0xFF; 8]).unwrap(),
        ] {
            let raw = to_socketcan(&frame).unwrap();
            assert_eq!(raw.is_extended(), frame.is_extended());
            assert_eq!(from_socketcan(raw.id(), raw.data()), Some(frame));
        }
    }

    #[test]
    fn interface_errors_are_classified() {
        let down = io_error("vcan0", io::Error::from_raw_os_error(libc::ENETDOWN));
        assert!(matches!(&down, BusError::InterfaceDown { iface } if iface == "vcan0"));
        assert!(
            down.to_string().starts_with(
                "CAN interface vcan0 is down; bring it up with `sudo ip link set up vcan0`"
            ),
            "{down}"
        );
        let missing = io_error("vcan0", io::Error::from_raw_os_error(libc::ENODEV));
        assert!(matches!(&missing, BusError::NoSuchInterface { iface } if iface == "vcan0"));
        let denied = io_error("vcan0", io::Error::from_raw_os_error(libc::EPERM));
        assert!(matches!(denied, BusError::Io { .. }));
        let text = denied.to_string();
        assert!(text.starts_with("CAN interface vcan0: "), "{text}");
        assert!(text.contains("(os error 1)"), "{text}");
        assert!(text.contains("run it as root"), "{text}");
        let no_can = io_error("vcan0", io::Error::from_raw_os_error(libc::EAFNOSUPPORT));
        assert!(
            no_can.to_string().ends_with("`sudo modprobe can_raw`"),
            "{no_can}"
        );
        let other = io_error("vcan0", io::Error::from_raw_os_error(libc::EIO));
        assert_eq!(
            other.to_string(),
            format!(
                "CAN interface vcan0: {}",
                io::Error::from_raw_os_error(libc::EIO)
            )
        );
    }

    #[tokio::test]
    async fn opening_a_missing_interface_names_it_and_says_how_to_create_it() {
        let Err(error) = SocketCanBus::open("armhil-nosuch0") else {
            panic!("a missing interface opened");
        };
        assert!(matches!(&error, BusError::NoSuchInterface { iface } if iface == "armhil-nosuch0"));
        assert_eq!(
            error.to_string(),
            "CAN interface armhil-nosuch0 does not exist (is its adapter plugged in?); for a \
             virtual one: `sudo ip link add dev armhil-nosuch0 type vcan && sudo ip link set up \
             armhil-nosuch0`"
        );
    }

    #[tokio::test]
    async fn opening_an_interface_that_is_not_can_says_so() {
        // `lo` exists everywhere; a kernel without SocketCAN refuses the socket first.
        let Err(error) = SocketCanBus::open("lo") else {
            panic!("the loopback interface opened as a CAN interface");
        };
        let text = error.to_string();
        assert!(text.starts_with("CAN interface lo: "), "{text}");
        assert!(
            text.contains("not a CAN device") || text.contains("`sudo modprobe can_raw`"),
            "{text}"
        );
    }
}
