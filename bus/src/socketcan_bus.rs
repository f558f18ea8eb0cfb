//! Real CAN interfaces (`vcan0`, `can0`) through Linux SocketCAN.
//!
//! Receive timestamps are the kernel's socket arrival time (`SO_TIMESTAMPNS`, time since the
//! Unix epoch), or the time the frame was read if the kernel gave none. The socket also
//! receives error frames: a bus-off report becomes [`BusError::BusOff`], other controller
//! errors are logged and skipped. Remote frames are skipped (the bus carries data frames).
//!
//! CAN FD: a socket opened with [`SocketCanOptions::fd`] sets `CAN_RAW_FD_FRAMES`, so it
//! receives CAN FD frames (72-byte `canfd_frame`) as well as classic ones, and sends CAN FD
//! frames on an interface whose MTU is 72 (`CANFD_MTU`). Sending a CAN FD frame through a
//! classic socket, or to an interface whose MTU is 16 (classic CAN only), fails with
//! [`BusError::Io`] naming the interface and saying what to change. A classic socket (the
//! default) is what it always was: it sees no CAN FD frames.

use std::io;
use std::time::{Duration, SystemTime};

use async_trait::async_trait;
use socketcan::id::FdFlags as RawFdFlags;
use socketcan::{
    CanAnyFrame, CanFdFrame, EmbeddedFrame, ErrorCause, ExtendedId, Id, SocketOptions, StandardId,
};
use tokio::sync::watch;

use crate::{BusError, CanBus, CanFrame, CanId, FdFlags, ReceivedFrame};

/// Size of a classic `struct can_frame`: the MTU of a classic CAN interface.
pub const CAN_MTU: usize = 16;
/// Size of a `struct canfd_frame`: the MTU of a CAN FD capable interface.
pub const CANFD_MTU: usize = 72;

/// Options for [`SocketCanBus::open_with`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SocketCanOptions {
    /// Also receive the frames this socket sends (`CAN_RAW_RECV_OWN_MSGS`).
    pub receive_own: bool,
    /// Open the socket for CAN FD (`CAN_RAW_FD_FRAMES`): it receives classic and CAN FD
    /// frames, and sends CAN FD frames if the interface's MTU is 72. Off by default: a classic
    /// socket neither receives nor sends CAN FD frames.
    pub fd: bool,
}

/// The raw socket: classic (`can_frame` only) or CAN FD capable.
enum Socket {
    Classic(socketcan::tokio::CanSocket),
    Fd(socketcan::tokio::CanFdSocket),
}

/// A SocketCAN raw socket bound to one interface.
pub struct SocketCanBus {
    socket: Socket,
    iface: String,
    tx_queue_len: usize,
    /// The interface's MTU read when a CAN FD socket was opened (`None`: a classic socket, or
    /// not readable; the kernel's answer to a write then decides).
    mtu: Option<usize>,
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
        let socket = if options.fd {
            socketcan::tokio::CanFdSocket::open_addr(&addr).map(Socket::Fd)
        } else {
            socketcan::tokio::CanSocket::open_addr(&addr).map(Socket::Classic)
        }
        .map_err(|error| {
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
        match &socket {
            Socket::Classic(socket) => configure(socket, options),
            Socket::Fd(socket) => configure(socket, options),
        }
        .map_err(|error| io_error(iface, error))?;
        // Only for the error a full queue reports; the kernel default is 10 for CAN devices.
        let tx_queue_len = read_sysfs(iface, "tx_queue_len").unwrap_or(10);
        let mtu = if options.fd {
            read_sysfs(iface, "mtu")
        } else {
            None
        };
        tracing::debug!(
            iface,
            receive_own = options.receive_own,
            fd = options.fd,
            ?mtu,
            "SocketCAN opened"
        );
        Ok(Self {
            socket,
            iface: iface.to_owned(),
            tx_queue_len,
            mtu,
            closed: watch::Sender::new(false),
        })
    }

    /// Whether this socket was opened for CAN FD ([`SocketCanOptions::fd`]).
    pub fn is_fd(&self) -> bool {
        matches!(self.socket, Socket::Fd(_))
    }

    /// Read until a data frame (or a bus-off report) arrives.
    async fn read_data_frame(&self) -> Result<ReceivedFrame, BusError> {
        loop {
            let read = match &self.socket {
                Socket::Classic(socket) => socket
                    .read_frame_with_timestamps()
                    .await
                    .map(|(frame, stamps)| (CanAnyFrame::from(frame), stamps)),
                Socket::Fd(socket) => socket.read_frame_with_timestamps().await,
            };
            let (frame, stamps) = read.map_err(|error| io_error(&self.iface, error))?;
            let arrived = stamps.socket.unwrap_or_else(SystemTime::now);
            let timestamp = arrived
                .duration_since(SystemTime::UNIX_EPOCH)
                .unwrap_or(Duration::ZERO);
            match frame {
                CanAnyFrame::Normal(data) => match from_socketcan(data.id(), data.data()) {
                    Some(frame) => return Ok(ReceivedFrame { frame, timestamp }),
                    None => tracing::warn!(iface = %self.iface, "skipping undecodable frame"),
                },
                CanAnyFrame::Fd(fd) => match from_socketcan_fd(&fd) {
                    Some(frame) => return Ok(ReceivedFrame { frame, timestamp }),
                    None => {
                        tracing::warn!(iface = %self.iface, "skipping undecodable CAN FD frame")
                    }
                },
                CanAnyFrame::Remote(_) => {
                    tracing::trace!(iface = %self.iface, "skipping remote frame");
                }
                CanAnyFrame::Error(error_frame) => {
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

    /// Write a CAN FD frame: refused with the reason on a classic socket or interface.
    fn write_fd(&self, frame: &CanFrame) -> io::Result<()> {
        let Socket::Fd(socket) = &self.socket else {
            return Err(fd_refused(frame, FdRefusal::ClassicSocket, &self.iface));
        };
        if self.mtu == Some(CAN_MTU) {
            return Err(fd_refused(frame, FdRefusal::ClassicInterface, &self.iface));
        }
        let Some(raw) = to_socketcan_fd(frame) else {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("frame {frame}"),
            ));
        };
        match socket.try_write_frame(&raw) {
            // The kernel's answer to a CAN FD frame on an interface whose MTU is 16 (its MTU
            // changed after the socket was opened, or could not be read then).
            Err(error) if error.raw_os_error() == Some(libc::EINVAL) => {
                Err(fd_refused(frame, FdRefusal::ClassicInterface, &self.iface))
            }
            other => other,
        }
    }

    /// Write a classic frame.
    fn write_classic(&self, frame: &CanFrame) -> io::Result<()> {
        // Our frames are validated on construction, so this cannot fail in practice.
        let Some(raw) = to_socketcan(frame) else {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("frame {frame}"),
            ));
        };
        match &self.socket {
            Socket::Classic(socket) => socket.try_write_frame(raw),
            Socket::Fd(socket) => socket.try_write_frame(&raw),
        }
    }
}

/// The socket options every socket gets.
fn configure<S: SocketOptions>(socket: &S, options: SocketCanOptions) -> io::Result<()> {
    // Binding to a down interface succeeds and leaves ENETDOWN pending for the first read:
    // report it now, as the opener's error.
    match socket.get_socket_option_int(libc::SOL_SOCKET, libc::SO_ERROR)? {
        0 => {}
        pending => return Err(io::Error::from_raw_os_error(pending)),
    }
    socket.set_recv_own_msgs(options.receive_own)?;
    socket.set_error_filter_accept_all()?;
    socket.set_recv_timestamp(true)
}

/// A number from `/sys/class/net/IFACE/NAME`, if it reads.
fn read_sysfs(iface: &str, name: &str) -> Option<usize> {
    std::fs::read_to_string(format!("/sys/class/net/{iface}/{name}"))
        .ok()
        .and_then(|text| text.trim().parse().ok())
}

/// Why a CAN FD frame cannot be sent.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum FdRefusal {
    /// The socket was opened without `CAN_RAW_FD_FRAMES`.
    ClassicSocket,
    /// The interface's MTU is 16: a classic CAN interface.
    ClassicInterface,
}

/// The error for a CAN FD frame that cannot be sent, saying what to change (wrapped into
/// [`BusError::Io`] with the interface's name by the caller).
fn fd_refused(frame: &CanFrame, why: FdRefusal, iface: &str) -> io::Error {
    let what = format!(
        "CAN FD frame {} ({} bytes) not sent",
        frame.id(),
        frame.len()
    );
    let text = match why {
        FdRefusal::ClassicSocket => format!(
            "{what}: the socket was opened for classic CAN only (open it with \
             SocketCanOptions {{ fd: true, .. }})"
        ),
        FdRefusal::ClassicInterface => format!(
            "{what}: {iface} is a classic CAN interface (MTU {CAN_MTU}; CAN FD needs MTU \
             {CANFD_MTU}): for a vcan `sudo ip link set {iface} down && sudo ip link set \
             {iface} mtu {CANFD_MTU} && sudo ip link set {iface} up`, for an adapter set it \
             down and up again with `type can bitrate 1000000 dbitrate 5000000 fd on`"
        ),
    };
    io::Error::new(io::ErrorKind::InvalidInput, text)
}

fn from_socketcan(id: Id, data: &[u8]) -> Option<CanFrame> {
    let id = match id {
        Id::Standard(id) => CanId::standard(id.as_raw()).ok()?,
        Id::Extended(id) => CanId::extended(id.as_raw()).ok()?,
    };
    CanFrame::new(id, data).ok()
}

/// Our CAN FD frame of a received `canfd_frame` (BRS and ESI kept; the kernel's length is
/// always a CAN FD length, the crate rounds up any other).
fn from_socketcan_fd(frame: &CanFdFrame) -> Option<CanFrame> {
    let id = match frame.id() {
        Id::Standard(id) => CanId::standard(id.as_raw()).ok()?,
        Id::Extended(id) => CanId::extended(id.as_raw()).ok()?,
    };
    let flags = FdFlags {
        brs: frame.is_brs(),
        esi: frame.is_esi(),
    };
    CanFrame::fd(id, frame.data(), flags).ok()
}

fn socketcan_id(id: CanId) -> Option<Id> {
    Some(match id {
        CanId::Standard(id) => StandardId::new(id)?.into(),
        CanId::Extended(id) => ExtendedId::new(id)?.into(),
    })
}

/// The classic `can_frame` of a classic frame.
fn to_socketcan(frame: &CanFrame) -> Option<socketcan::CanFrame> {
    if frame.is_fd() {
        return None;
    }
    socketcan::CanFrame::new(socketcan_id(frame.id())?, frame.data())
}

/// The `canfd_frame` of a CAN FD frame (FDF set, BRS and ESI as the frame has them).
fn to_socketcan_fd(frame: &CanFrame) -> Option<CanFdFrame> {
    let flags = frame.fd_flags()?;
    let mut raw = RawFdFlags::empty();
    raw.set(RawFdFlags::BRS, flags.brs);
    raw.set(RawFdFlags::ESI, flags.esi);
    CanFdFrame::with_flags(socketcan_id(frame.id())?, frame.data(), raw)
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
        // Non-blocking like the virtual bus: a full driver queue is an error, not a wait.
        let written = if frame.is_fd() {
            self.write_fd(&frame)
        } else {
            self.write_classic(&frame)
        };
        match written {
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
    fn fd_frames_convert_both_ways_with_their_flags() {
        let brs = FdFlags {
            brs: true,
            esi: false,
        };
        let esi = FdFlags {
            brs: false,
            esi: true,
        };
        let data: Vec<u8> = (0..64).collect();
        for frame in [
            CanFrame::fd(CanId::Standard(0x123), &data, brs).unwrap(),
            CanFrame::fd(CanId::Extended(0x1FFF_FFFF), &[], esi).unwrap(),
            CanFrame::fd(CanId::Standard(0x7FF), &data[..12], FdFlags::default()).unwrap(),
            CanFrame::fd(CanId::Extended(0x5), &data[..8], brs).unwrap(),
        ] {
            let raw = to_socketcan_fd(&frame).unwrap();
            assert_eq!(raw.is_extended(), frame.is_extended());
            assert_eq!(raw.data(), frame.data());
            assert_eq!(raw.is_brs(), frame.brs());
            assert_eq!(raw.is_esi(), frame.esi());
            assert!(raw.flags().contains(RawFdFlags::FDF));
            assert_eq!(from_socketcan_fd(&raw), Some(frame));
            // Neither form stands in for the other.
            assert!(to_socketcan(&frame).is_none());
        }
        let classic = CanFrame::standard(0x100, &[1, 2]).unwrap();
        assert!(to_socketcan_fd(&classic).is_none());
    }

    /// A `canfd_frame` whose length is not a CAN FD length (only a raw writer makes one) is
    /// padded up by the crate, so it still reads as a frame rather than failing.
    #[test]
    fn an_fd_frame_of_an_odd_length_reads_padded() {
        let raw = CanFdFrame::with_flags(
            Id::Standard(StandardId::new(0x10).unwrap()),
            &[7; 13],
            RawFdFlags::BRS,
        )
        .unwrap();
        let frame = from_socketcan_fd(&raw).unwrap();
        assert_eq!(frame.len(), 16);
        assert_eq!(&frame.data()[..13], &[7; 13]);
        assert_eq!(&frame.data()[13..], &[0; 3]);
        assert!(frame.is_fd() && frame.brs());
    }

    #[test]
    fn an_fd_frame_that_cannot_be_sent_names_the_interface_and_the_fix() {
        let frame = CanFrame::fd(CanId::Standard(0x123), &[0; 64], FdFlags::default()).unwrap();
        let as_bus_error = |why| BusError::Io {
            iface: "can0".to_owned(),
            source: fd_refused(&frame, why, "can0"),
        };
        let text = as_bus_error(FdRefusal::ClassicInterface).to_string();
        assert!(
            text.starts_with(
                "CAN interface can0: CAN FD frame 123 (64 bytes) not sent: can0 is a classic CAN \
                 interface (MTU 16; CAN FD needs MTU 72)"
            ),
            "{text}"
        );
        assert!(text.contains("sudo ip link set can0 mtu 72"), "{text}");
        assert!(text.contains("fd on"), "{text}");
        let text = as_bus_error(FdRefusal::ClassicSocket).to_string();
        assert!(
            text.starts_with(
                "CAN interface can0: CAN FD frame 123 (64 bytes) not sent: the socket was opened \
                 for classic CAN only"
            ),
            "{text}"
        );
        assert!(text.contains("SocketCanOptions { fd: true, .. }"), "{text}");
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
    async fn opening_a_missing_interface_for_can_fd_names_it_too() {
        let options = SocketCanOptions {
            fd: true,
            ..SocketCanOptions::default()
        };
        let Err(error) = SocketCanBus::open_with("armhil-nosuch0", options) else {
            panic!("a missing interface opened");
        };
        assert!(matches!(&error, BusError::NoSuchInterface { iface } if iface == "armhil-nosuch0"));
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
