//! Layer 2: a validated scenario. Every value here has been range-checked; units are in the
//! field names.

use std::path::PathBuf;
use std::time::Duration;

pub use crate::devices::{Action, Check, DeviceFault, DeviceKind};
pub use crate::scenario::vocab::{ErrorClass, Near, Signal};

/// A validated scenario, ready to run.
#[derive(Debug, Clone, PartialEq)]
pub struct Scenario {
    /// Name (from `name:` or the file stem); names the output folder.
    pub name: String,
    /// The file it was loaded from.
    pub path: PathBuf,
    /// Free text.
    pub description: Option<String>,
    /// Tags; `vcan` marks scenarios that can run against a separate emulator process.
    pub tags: Vec<String>,
    /// The value of the file's `matrix:` this scenario was loaded for (`piper` of
    /// `matrix: {vendor: [piper, realman]}`); `None` for a file without a matrix.
    pub variant: Option<String>,
    /// Bus and devices.
    pub bench: Bench,
    /// What to record.
    pub record: Record,
    /// Faults scheduled by time or after a step.
    pub faults: Vec<ScheduledFault>,
    /// The steps, in order.
    pub steps: Vec<Step>,
}

impl Scenario {
    /// Whether the scenario carries `tag`.
    pub fn has_tag(&self, tag: &str) -> bool {
        self.tags.iter().any(|t| t == tag)
    }

    /// Why this scenario needs the in-process emulator and virtual bus (empty when it can run
    /// against a separate emulator process on a real interface).
    pub fn in_process_requirements(&self) -> Vec<String> {
        let mut needs = Vec::new();
        for fault in &self.faults {
            needs.push(format!(
                "scheduled fault `{}` (line {})",
                fault.fault.describe(),
                fault.line
            ));
        }
        for step in &self.steps {
            match &step.kind {
                StepKind::Inject { fault, .. } => needs.push(format!(
                    "inject `{}` (line {})",
                    fault.describe(),
                    step.line
                )),
                StepKind::ClearFaults { .. } => {
                    needs.push(format!("clear_faults (line {})", step.line))
                }
                StepKind::Action { action, .. } => {
                    if let Some(what) = action.needs_emulator() {
                        needs.push(format!("{what} (line {})", step.line));
                    }
                }
                _ => {}
            }
        }
        for device in &self.bench.devices {
            needs.extend(device.kind.in_process_requirements(&device.name));
        }
        needs
    }
}

/// The buses and the devices on them.
#[derive(Debug, Clone, PartialEq)]
pub struct Bench {
    /// The CAN buses, never empty: [`DEFAULT_BUS`] alone unless the scenario names its buses
    /// (`bench.buses`, or a device's `bus:`, or a robot's file).
    pub buses: Vec<BusSpec>,
    /// Interface to use with `--iface` when the command line names none.
    pub interface: Option<String>,
    /// Devices, in file order (sorted by name: the file's mapping order is not kept).
    pub devices: Vec<DeviceSpec>,
}

/// The name of a bench's bus when the scenario names none (as candump logs have always said).
pub const DEFAULT_BUS: &str = "vcan0";

/// One CAN bus of a bench.
#[derive(Debug, Clone, PartialEq)]
pub struct BusSpec {
    /// Its name: in bus.log, in bus faults (`bus:`), and a robot's bus names.
    pub name: String,
    /// Its bit rate (the arbitration phase's, for CAN FD).
    pub bitrate_bps: u32,
    /// CAN FD's data-phase bit rate, when a device on it runs CAN FD (a robot file's
    /// `data_bitrate`); `None`: classic CAN.
    pub data_bitrate_bps: Option<u32>,
}

/// One device on the bench.
#[derive(Debug, Clone, PartialEq)]
pub struct DeviceSpec {
    /// Its name in the scenario (also its node name on the virtual bus).
    pub name: String,
    /// What it is and its settings.
    pub kind: DeviceKind,
    /// Its buses, as indices into [`Bench::buses`] in the order its kind lists them (one for
    /// a CAN device, a robot's several; none for a device that speaks no CAN).
    pub buses: Vec<usize>,
}

impl Bench {
    /// The bit rate of the first bus (the only one, on most benches).
    pub fn bitrate_bps(&self) -> u32 {
        self.buses.first().map_or(1_000_000, |b| b.bitrate_bps)
    }
}

/// What a run records.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// Period of the state trace.
    pub sample_period: Duration,
    /// Signals in the trace.
    pub signals: Vec<Signal>,
    /// Write a candump log of the bus.
    pub candump: bool,
    /// Write a pcap of the bus.
    pub pcap: bool,
    /// Write an SVG plot.
    pub plot: bool,
}

/// A fault and when to apply it.
#[derive(Debug, Clone, PartialEq)]
pub struct ScheduledFault {
    /// Line of the entry in the file.
    pub line: u64,
    /// When.
    pub trigger: FaultTrigger,
    /// Cleared after this long; `None` keeps it until the end (or `clear_faults`).
    pub duration: Option<Duration>,
    /// What.
    pub fault: FaultSpec,
}

/// When a scheduled fault starts.
#[derive(Debug, Clone, PartialEq)]
pub enum FaultTrigger {
    /// At this scenario time.
    At(Duration),
    /// This long after the step with this index (0-based) finished.
    AfterStep {
        /// Index of the step.
        step: usize,
        /// Extra delay.
        delay: Duration,
    },
}

/// A fault on a device's emulator or on the bus.
#[derive(Debug, Clone, PartialEq)]
pub enum FaultSpec {
    /// Applied by the device's emulator.
    Emulator {
        /// Index into [`Bench::devices`].
        device: usize,
        /// The fault.
        fault: DeviceFault,
    },
    /// Applied by a virtual bus.
    Bus {
        /// Index into [`Bench::buses`].
        bus: usize,
        /// The fault.
        fault: BusFault,
    },
}

impl FaultSpec {
    /// Short description for logs and reports.
    pub fn describe(&self) -> String {
        match self {
            Self::Emulator { fault, .. } => fault.describe(),
            Self::Bus { fault, .. } => fault.describe(),
        }
    }
}

/// Which frames a bus fault hits.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum FrameSelector {
    /// Every frame.
    All,
    /// One identifier.
    Id(u32),
    /// Frames sent by this node (device name, or `host` for the driver).
    Node(String),
}

impl FrameSelector {
    fn describe(&self) -> String {
        match self {
            Self::All => "all frames".to_owned(),
            Self::Id(id) => format!("id 0x{id:03X}"),
            Self::Node(node) => format!("node {node}"),
        }
    }
}

/// Faults on the virtual bus.
#[derive(Debug, Clone, PartialEq)]
pub enum BusFault {
    /// Drop frames (all, or with a seeded probability).
    Drop {
        /// Which frames.
        frames: FrameSelector,
        /// Probability and seed, `None` for every frame.
        probability: Option<(f64, u64)>,
    },
    /// Delay frames.
    Delay {
        /// Which frames.
        frames: FrameSelector,
        /// How long.
        delay: Duration,
    },
    /// Corrupt frames (CRC error: nobody receives them).
    Corrupt {
        /// Which frames.
        frames: FrameSelector,
    },
    /// Deliver frames twice.
    Duplicate {
        /// Which frames.
        frames: FrameSelector,
    },
    /// Silence a node: its frames never reach the wire.
    Silence {
        /// Node name.
        node: String,
    },
    /// Put a node into bus-off (needs a duration).
    BusOff {
        /// Node name.
        node: String,
    },
}

impl BusFault {
    /// Short description.
    pub fn describe(&self) -> String {
        match self {
            Self::Drop {
                frames,
                probability: None,
            } => format!("drop {}", frames.describe()),
            Self::Drop {
                frames,
                probability: Some((p, seed)),
            } => format!("drop {} p={p} seed={seed}", frames.describe()),
            Self::Delay { frames, delay } => {
                format!("delay {} by {} ms", frames.describe(), delay.as_millis())
            }
            Self::Corrupt { frames } => format!("corrupt {}", frames.describe()),
            Self::Duplicate { frames } => format!("duplicate {}", frames.describe()),
            Self::Silence { node } => format!("silence node {node}"),
            Self::BusOff { node } => format!("bus_off node {node}"),
        }
    }
}

/// One step.
#[derive(Debug, Clone, PartialEq)]
pub struct Step {
    /// 0-based index.
    pub index: usize,
    /// Line in the file.
    pub line: u64,
    /// Optional label (`id:`), referenced by `after:` in the fault schedule.
    pub id: Option<String>,
    /// Short text for reports (`move_j`, `wait_until`...).
    pub label: String,
    /// What it does.
    pub kind: StepKind,
}

/// What a step does.
#[derive(Debug, Clone, PartialEq)]
pub enum StepKind {
    /// Let time pass.
    Wait(Duration),
    /// A driver action on a device.
    Action {
        /// Index into [`Bench::devices`].
        device: usize,
        /// The action.
        action: Action,
        /// Overrides the driver's default timeout.
        timeout: Option<Duration>,
        /// The action must fail with this error class instead of succeeding.
        expect_error: Option<ErrorClass>,
    },
    /// Conditions that must hold now (or throughout `hold`).
    Expect {
        /// Index into [`Bench::devices`].
        device: usize,
        /// The conditions.
        checks: Vec<Check>,
        /// Must hold for this long (sampled every millisecond of scenario time).
        hold: Option<Duration>,
    },
    /// Poll until the conditions hold, at most `timeout`.
    WaitUntil {
        /// Index into [`Bench::devices`].
        device: usize,
        /// The conditions.
        checks: Vec<Check>,
        /// Give up after this long.
        timeout: Duration,
    },
    /// Inject a fault now.
    Inject {
        /// The fault.
        fault: FaultSpec,
        /// Cleared after this long.
        duration: Option<Duration>,
    },
    /// Clear every injected fault (emulator and bus).
    ClearFaults {
        /// Index into [`Bench::devices`].
        device: usize,
    },
}
