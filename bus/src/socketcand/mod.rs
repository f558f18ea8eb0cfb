//! socketcand: CAN over TCP in the ASCII protocol of linux-can/socketcand, raw mode.
//!
//! - [`SocketcandServer`] serves one [`VirtualBus`](crate::virtual_bus::VirtualBus) to any
//!   number of TCP clients: each client is a node on that bus, so its frames reach the emulator
//!   and every other client, and it receives every frame but its own, like a socket on a real
//!   interface. Tools that speak socketcand (python-can's `socketcand` interface, and through
//!   it vendor SDKs) reach an emulator on machines without kernel CAN.
//! - [`SocketcandBus`] is the client side: a [`CanBus`](crate::CanBus) over TCP for armhil's
//!   own drivers and recorder.
//! - [`protocol`]: parsing and formatting of the `< … >` elements.
//! - [`http_guard`]: the detector that closes connections carrying HTTP (a web page's
//!   cross-protocol request), used by this server and by the Realman emulator's JSON port.

mod client;
pub mod http_guard;
mod log_limit;
pub mod protocol;
mod server;

pub use client::{ConnectError, SocketcandBus};
pub use server::{ServerConfig, ServerError, ServerStats, SocketcandServer};

/// The TCP port socketcand listens on by default.
pub const DEFAULT_PORT: u16 = 29536;
