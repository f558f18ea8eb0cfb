//! Building the bench of a scenario: the bus, the emulators and the drivers.

use std::sync::Arc;

use bus::virtual_bus::{VirtualBus, VirtualBusConfig};
use bus::CanBus;
use driver::piper::{PiperBuilder, Timeouts};
use tokio::time::Instant;

use super::device::Device;
use super::emulator::PiperSim;
use super::model::{DeviceKind, PiperSettings, Scenario};
use super::piper::{EmulatorControl, PiperDevice};
use super::robstride::RobstrideDevice;
use super::runner::{Clock, Recorder, RunOptions};

/// Node name of the drivers on the virtual bus (bus faults can target it as `host`).
pub const HOST_NODE: &str = "host";

/// How long the RobStride driver waits for each reply (its default, before time scaling).
const RS_DRIVER_TIMEOUT: std::time::Duration = std::time::Duration::from_millis(20);

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
    match clock {
        Clock::Virtual | Clock::Realtime => build_virtual(scenario, options).await,
        Clock::Iface(iface) => build_iface(scenario, iface, options).await,
    }
}

/// The driver's timeouts, scaled for slow real-time runs.
fn driver_timeouts(options: &RunOptions) -> Timeouts {
    let d = Timeouts::default();
    Timeouts {
        first_feedback: d.first_feedback.map(|t| options.deadline(t)),
        query: options.deadline(d.query),
        enable: options.deadline(d.enable),
        link: options.deadline(d.link),
        send: options.deadline(d.send),
        ..d
    }
}

async fn build_virtual(scenario: &Scenario, options: &RunOptions) -> Result<BuiltBench, String> {
    let bus = VirtualBus::new(VirtualBusConfig {
        bitrate_bps: scenario.bench.bitrate_bps,
        ..VirtualBusConfig::default()
    });
    let t0 = Instant::now();
    let recorder = Recorder::from_tap(bus.tap());
    let mut devices: Vec<Arc<dyn Device>> = Vec::new();
    for spec in &scenario.bench.devices {
        match &spec.kind {
            DeviceKind::Piper(settings) => {
                let emulator = spawn_piper_emulator(&bus, &spec.name, settings)?;
                let host: Arc<dyn CanBus> = Arc::new(bus.attach(HOST_NODE));
                let driver = PiperBuilder::new(host).connect().await.map_err(|e| {
                    format!("device `{}`: driver could not connect: {e}", spec.name)
                })?;
                devices.push(Arc::new(PiperDevice::new(
                    &spec.name,
                    driver,
                    Some(emulator),
                    *options,
                )));
            }
            DeviceKind::Robstride(settings) => {
                let host: Arc<dyn CanBus> = Arc::new(bus.attach(HOST_NODE));
                devices.push(Arc::new(RobstrideDevice::start(
                    &spec.name,
                    settings,
                    host,
                    Some(&bus),
                    scenario.bench.bitrate_bps,
                    options.deadline(RS_DRIVER_TIMEOUT),
                )?));
            }
        }
    }
    Ok(BuiltBench {
        devices,
        bus: Some(bus),
        recorder,
        t0,
    })
}

fn spawn_piper_emulator(
    bus: &VirtualBus,
    name: &str,
    settings: &PiperSettings,
) -> Result<Box<dyn EmulatorControl>, String> {
    let node: Arc<dyn CanBus> = Arc::new(bus.attach(name));
    let sim =
        PiperSim::spawn(node, settings).map_err(|e| format!("device `{name}`: emulator: {e}"))?;
    Ok(Box::new(sim))
}

#[cfg(target_os = "linux")]
async fn build_iface(
    scenario: &Scenario,
    iface: &str,
    options: &RunOptions,
) -> Result<BuiltBench, String> {
    use bus::socketcan_bus::SocketCanBus;
    let open = |what: &str| {
        SocketCanBus::open(iface)
            .map(|b| Arc::new(b) as Arc<dyn CanBus>)
            .map_err(|e| format!("cannot open {iface} for the {what}: {e}"))
    };
    // A second socket sees every frame on the interface (the driver's and the emulator's).
    let recorder = Recorder::from_bus(open("recorder")?);
    let t0 = Instant::now();
    let mut devices: Vec<Arc<dyn Device>> = Vec::new();
    for spec in &scenario.bench.devices {
        match &spec.kind {
            DeviceKind::Piper(_) => {
                let driver = PiperBuilder::new(open("driver")?)
                    .timeouts(driver_timeouts(options))
                    .connect()
                    .await
                    .map_err(|e| {
                        format!(
                            "device `{}`: driver could not connect on {iface} (is `armhil sim piper --iface {iface}` running?): {e}",
                            spec.name
                        )
                    })?;
                devices.push(Arc::new(PiperDevice::new(
                    &spec.name, driver, None, *options,
                )));
            }
            DeviceKind::Robstride(settings) => {
                devices.push(Arc::new(RobstrideDevice::start(
                    &spec.name,
                    settings,
                    open("driver")?,
                    None,
                    scenario.bench.bitrate_bps,
                    options.deadline(RS_DRIVER_TIMEOUT),
                )?));
            }
        }
    }
    Ok(BuiltBench {
        devices,
        bus: None,
        recorder,
        t0,
    })
}

#[cfg(not(target_os = "linux"))]
async fn build_iface(
    _scenario: &Scenario,
    iface: &str,
    _options: &RunOptions,
) -> Result<BuiltBench, String> {
    Err(format!("SocketCAN interface `{iface}` needs Linux"))
}
