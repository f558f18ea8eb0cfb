//! Building the bench of a scenario: the CAN bus (in-process virtual bus, a SocketCAN
//! interface or a socketcand server) with its recorder, and every device through its kind's `build`.

use std::sync::Arc;

use bus::virtual_bus::{VirtualBus, VirtualBusConfig};
use tokio::time::Instant;

use super::model::Scenario;
use super::runner::{Clock, Recorder, RunOptions, Spool};
use crate::devices::Device;
use crate::devices::Wiring;

pub use crate::bench::HOST_NODE;

/// A built bench.
pub(crate) struct BuiltBench {
    /// Devices, in [`Scenario::bench`] order.
    pub devices: Vec<Arc<dyn Device>>,
    /// The virtual bus (in-process runs).
    pub bus: Option<VirtualBus>,
    /// Records every frame.
    pub recorder: Recorder,
    /// Scenario time zero.
    pub t0: Instant,
}

/// Build the bench: in-process emulators on a virtual bus, or drivers on a real interface.
pub(crate) async fn build(
    scenario: &Scenario,
    clock: &Clock,
    options: &RunOptions,
) -> Result<BuiltBench, String> {
    // Frames are written to the candump / pcap spool files only when asked; counts are kept
    // either way.
    let spool = Spool::create(
        scenario.record.candump,
        scenario.record.pcap,
        options.recording_limit_bytes,
    )
    .map_err(|e| format!("cannot create a temporary file for the bus recording: {e}"))?;
    let (bus, recorder) = match clock {
        Clock::Virtual | Clock::Realtime => {
            let bus = VirtualBus::new(VirtualBusConfig {
                bitrate_bps: scenario.bench.bitrate_bps,
                ..VirtualBusConfig::default()
            });
            let recorder = Recorder::from_tap(bus.tap(), spool);
            (Some(bus), recorder)
        }
        Clock::Iface(link) => (
            None,
            Recorder::from_bus(link.open("recorder").await?, spool),
        ),
    };
    let t0 = Instant::now();
    let wiring = Wiring {
        bus: bus.as_ref(),
        clock,
        options,
        bitrate_bps: scenario.bench.bitrate_bps,
    };
    let mut devices: Vec<Arc<dyn Device>> = Vec::new();
    for spec in &scenario.bench.devices {
        devices.push(spec.kind.build(&spec.name, &wiring).await?);
    }
    Ok(BuiltBench {
        devices,
        bus,
        recorder,
        t0,
    })
}
