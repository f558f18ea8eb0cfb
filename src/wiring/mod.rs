//! What wires a run, shared by the device kinds (which build on it) and the harness (which
//! runs on it): the run's [`Clock`] and CAN [`Link`], its [`RunOptions`] and [`Interrupt`], and
//! the drivers' node name on the virtual bus. Nothing here knows a scenario or a device kind.
//!
//! Not to be confused with `devices::Wiring`, the per-device bundle a kind's `build` gets: the
//! harness fills one for each device of a scenario's `bench:` from this module's [`Clock`] and
//! [`RunOptions`] plus that device's in-process buses and bit rate. This module is the run's
//! wiring, which every device shares; a `Wiring` is one device's share of it.

mod clock;
mod interrupt;
mod options;

use std::sync::Arc;

pub use clock::{Clock, Link};
pub use interrupt::{Interrupt, InterruptTrigger};
pub use options::{RunOptions, DEFAULT_RECORDING_LIMIT_BYTES, MAX_DEADLINE, MAX_TIME_SCALE};

/// Node name of the drivers on the virtual bus (bus faults can target it as `host`).
pub const HOST_NODE: &str = "host";

/// Open the SocketCAN interface `iface` for `what` (the recorder, the driver), a CAN FD socket
/// when `fd`: the bus crate's error, which names the interface and says what to do, after what
/// it was for.
pub(crate) fn open_iface(
    iface: &str,
    what: &str,
    fd: bool,
) -> Result<Arc<dyn bus::CanBus>, String> {
    bus::open_socketcan_for(iface, fd).map_err(|e| format!("cannot open the {what}'s bus: {e}"))
}
