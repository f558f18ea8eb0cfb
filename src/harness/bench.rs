//! Building the bench of a scenario: the CAN bus (in-process virtual bus, a SocketCAN
//! interface or a socketcand server) with its recorder, and every device through its kind's `build`.

use std::sync::Arc;

use bus::fine_timer::{FineTimer, TimelineGuard, VirtualTimeline};
use bus::virtual_bus::{VirtualBus, VirtualBusConfig};
use tokio::time::Instant;

use super::model::Scenario;
use super::runner::{Clock, Recorder, RunOptions, Spool};
use crate::devices::Device;
use crate::devices::Wiring;

pub use crate::wiring::HOST_NODE;

/// A built bench.
pub(crate) struct BuiltBench {
    /// Devices, in [`Scenario::bench`] order.
    pub devices: Vec<Arc<dyn Device>>,
    /// The virtual buses (in-process runs), in [`Bench::buses`](super::model::Bench) order.
    pub buses: Vec<VirtualBus>,
    /// Records every frame.
    pub recorder: Recorder,
    /// Scenario time zero.
    pub t0: Instant,
    /// Moves virtual time to each frame's microsecond (virtual runs; see
    /// [`bus::fine_timer`]); the buses stop using it when it is dropped.
    pub timeline: Option<TimelineGuard>,
}

/// Build the bench: in-process emulators on virtual buses, or drivers on a real interface.
pub(crate) async fn build(
    scenario: &Scenario,
    clock: &Clock,
    options: &RunOptions,
) -> Result<BuiltBench, String> {
    // Frames are written to the candump / pcap spool files only when asked; counts are kept
    // either way.
    let bus_names: Vec<String> = scenario
        .bench
        .buses
        .iter()
        .map(|b| b.name.clone())
        .collect();
    let spool = Spool::create(
        scenario.record.candump,
        scenario.record.pcap,
        options.recording_limit_bytes,
        &bus_names,
    )
    .map_err(|e| format!("cannot create a temporary file for the bus recording: {e}"))?;
    // Virtual time moves to each frame's microsecond, not tokio's next millisecond: a
    // request and its answer take a fraction of a millisecond, as on the wire.
    let timeline = match clock {
        Clock::Virtual => VirtualTimeline::start(),
        Clock::Realtime | Clock::Iface(_) => None,
    };
    let timer = timeline.as_ref().map_or(FineTimer::Auto, |guard| {
        FineTimer::Virtual(guard.timeline().clone())
    });
    let (buses, recorder) = match clock {
        Clock::Virtual | Clock::Realtime => {
            let buses: Vec<VirtualBus> = scenario
                .bench
                .buses
                .iter()
                .map(|spec| {
                    VirtualBus::new(VirtualBusConfig {
                        bitrate_bps: spec.bitrate_bps,
                        data_bitrate_bps: spec.data_bitrate_bps,
                        timer: timer.clone(),
                        ..VirtualBusConfig::default()
                    })
                })
                .collect();
            let taps = scenario
                .bench
                .buses
                .iter()
                .zip(&buses)
                .map(|(spec, bus)| (spec.name.clone(), bus.tap()))
                .collect();
            let recorder = Recorder::from_taps(taps, spool);
            (buses, recorder)
        }
        Clock::Iface(link) => {
            if let [_, _, ..] = scenario.bench.buses.as_slice() {
                let names: Vec<&str> = scenario
                    .bench
                    .buses
                    .iter()
                    .map(|b| b.name.as_str())
                    .collect();
                return Err(format!(
                    "this bench has {} buses ({}); a run on a real interface serves one, so it runs in process only",
                    names.len(),
                    names.join(", ")
                ));
            }
            (
                Vec::new(),
                Recorder::from_bus(link.open_fd("recorder").await?, spool),
            )
        }
    };
    let t0 = Instant::now();
    let mut devices: Vec<Arc<dyn Device>> = Vec::new();
    for spec in &scenario.bench.devices {
        let device_buses: Vec<&VirtualBus> =
            spec.buses.iter().filter_map(|&i| buses.get(i)).collect();
        let wiring = Wiring {
            buses: device_buses,
            clock,
            options,
            bitrate_bps: spec
                .buses
                .first()
                .and_then(|&i| scenario.bench.buses.get(i))
                .map_or(scenario.bench.bitrate_bps(), |b| b.bitrate_bps),
        };
        devices.push(spec.kind.build(&spec.name, &wiring).await?);
    }
    Ok(BuiltBench {
        devices,
        buses,
        recorder,
        t0,
        timeline,
    })
}
