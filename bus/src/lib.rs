//! The bus layer every armhil emulator and driver talks through.
//!
//! - [`CanFrame`] / [`CanId`]: plain `Copy` CAN frames, classic and CAN FD ([`FdFlags`]).
//! - [`CanBus`]: one async interface (send, receive with a timestamp, close).
//! - [`virtual_bus`]: an in-process bus that models bit timing, arbitration, queues, load and
//!   faults, and runs under tokio's paused clock for deterministic virtual time.
//! - [`open_socketcan`]: a real SocketCAN interface such as `vcan0` or `can0`, the one opener
//!   every front end uses (on every platform; SocketCAN itself is Linux only, in
//!   `socketcan_bus`).
//! - `vxcan` (Linux only): creating a vxcan pair for a vendor SDK and an emulator.
//! - [`socketcand`]: CAN over TCP (the socketcand protocol), server and client.
//! - [`candump`], [`pcap`] and [`recorder`]: logs for can-utils and Wireshark, and a reader.
//! - [`timing`]: how many bit times a frame occupies.
//! - [`fine_timer`]: sleeping to sub-millisecond deadlines, in real and virtual time.

pub mod candump;
mod error;
pub mod fine_timer;
mod frame;
mod iface;
pub mod pcap;
pub mod pcapng;
pub mod recorder;
#[cfg(target_os = "linux")]
pub mod socketcan_bus;
mod socketcan_open;
pub mod socketcand;
pub mod timing;
pub mod virtual_bus;
#[cfg(target_os = "linux")]
pub mod vxcan;

pub use error::BusError;
pub use frame::{
    is_fd_data_len, CanFrame, CanId, FdFlags, FrameError, ReceivedFrame, FD_DATA_LENS,
    MAX_DATA_LEN, MAX_EXTENDED_ID, MAX_FD_DATA_LEN, MAX_STANDARD_ID,
};
pub use iface::CanBus;
pub use socketcan_open::{open_socketcan, open_socketcan_fd, open_socketcan_for};
