//! The bus layer every armhil emulator and driver talks through.
//!
//! - [`CanFrame`] / [`CanId`]: plain `Copy` classic CAN frames.
//! - [`CanBus`]: one async interface (send, receive with a timestamp, close).
//! - [`virtual_bus`]: an in-process bus that models bit timing, arbitration, queues, load and
//!   faults, and runs under tokio's paused clock for deterministic virtual time.
//! - `socketcan_bus` (Linux only): real SocketCAN interfaces such as `vcan0` or `can0`.
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
pub mod socketcand;
pub mod timing;
pub mod virtual_bus;
#[cfg(target_os = "linux")]
pub mod vxcan;

pub use error::BusError;
pub use frame::{
    CanFrame, CanId, FrameError, ReceivedFrame, MAX_DATA_LEN, MAX_EXTENDED_ID, MAX_STANDARD_ID,
};
pub use iface::CanBus;
