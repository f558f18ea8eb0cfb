//! End-to-end tests over a real SocketCAN interface (`vcan0`).
//!
//! Every test is `#[ignore]`d: they need a live vcan interface and are run by
//! `scripts/vcan-e2e.sh` (in a VM on machines whose kernel lacks CAN) with `--ignored`.
//! `ARMHIL_VCAN_IFACE` names the interface (default `vcan0`); `ARMHIL_BIN` the `armhil` binary.

mod bus;
mod damiao_fd;
mod piper_driver;
mod piper_sdk;
mod robstride;
mod scenarios;
mod sim_rig;
mod vxcan;
