//! How a bench is wired, shared by the device kinds (which build on it) and the harness (which
//! runs on it): the run's [`Clock`] and CAN [`Link`], its [`RunOptions`] and [`Interrupt`], and
//! the drivers' node name on the virtual bus. Nothing here knows a scenario or a device kind.

mod clock;
mod interrupt;
mod options;

use std::sync::Arc;

pub use clock::{Clock, Link};
pub use interrupt::{Interrupt, InterruptTrigger};
pub use options::{RunOptions, DEFAULT_RECORDING_LIMIT_BYTES, MAX_DEADLINE, MAX_TIME_SCALE};

/// Node name of the drivers on the virtual bus (bus faults can target it as `host`).
pub const HOST_NODE: &str = "host";

/// Open a SocketCAN socket on `iface` for `what`.
#[cfg(target_os = "linux")]
pub(crate) fn open_iface(iface: &str, what: &str) -> Result<Arc<dyn bus::CanBus>, String> {
    bus::socketcan_bus::SocketCanBus::open(iface)
        .map(|b| Arc::new(b) as Arc<dyn bus::CanBus>)
        .map_err(|e| format!("cannot open {iface} for the {what}: {e}"))
}

/// Open a SocketCAN socket on `iface` for `what`.
#[cfg(not(target_os = "linux"))]
pub(crate) fn open_iface(iface: &str, _what: &str) -> Result<Arc<dyn bus::CanBus>, String> {
    Err(format!("SocketCAN interface `{iface}` needs Linux"))
}
