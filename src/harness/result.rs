//! What a run produces: per-step outcomes, fault events, the sampled trace, bus figures.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Duration;

use super::runner::Recording;

/// How one step ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// Everything as expected.
    Passed,
    /// A condition or reply did not match.
    Failed {
        /// What the step wanted.
        expected: String,
        /// What it got.
        actual: String,
    },
    /// A `wait_until` (or a driver confirmation) ran out of time.
    TimedOut {
        /// How long it waited.
        waited: Duration,
        /// What it waited for.
        expected: String,
        /// The state when it gave up.
        actual: String,
    },
    /// Not run (an earlier step failed).
    NotRun,
}

impl Outcome {
    /// Short name: `passed`, `failed`, `timed_out`, `not_run`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Passed => "passed",
            Self::Failed { .. } => "failed",
            Self::TimedOut { .. } => "timed_out",
            Self::NotRun => "not_run",
        }
    }

    /// Whether the step passed.
    pub fn passed(&self) -> bool {
        matches!(self, Self::Passed)
    }
}

/// One step's result.
#[derive(Debug, Clone, PartialEq)]
pub struct StepResult {
    /// 0-based index.
    pub index: usize,
    /// Line in the scenario file.
    pub line: u64,
    /// Step label (`move_j`...).
    pub label: String,
    /// Step id, if any.
    pub id: Option<String>,
    /// Scenario time when it started.
    pub started: Duration,
    /// Scenario time it took.
    pub took: Duration,
    /// How it ended.
    pub outcome: Outcome,
    /// Values a query returned.
    pub reply: Vec<(String, String)>,
}

/// A fault being applied or removed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FaultEvent {
    /// Scenario time.
    pub at: Duration,
    /// `inject` or `clear`.
    pub action: &'static str,
    /// What.
    pub fault: String,
    /// Device name for emulator faults, `bus` for bus faults.
    pub target: String,
}

/// One trace column: a name and the quantum its integer samples count.
#[derive(Debug, Clone, PartialEq)]
pub struct Column {
    /// Name with unit (`j1_deg`).
    pub name: String,
    /// Value of one integer step (0.1 for 0.1°).
    pub quantum: f64,
    /// Group for plotting (`joints`, `currents`...).
    pub group: &'static str,
}

/// The sampled state: quantised integers per column, so snapshots are stable.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Trace {
    /// Sample period.
    pub period: Duration,
    /// Columns (without time).
    pub columns: Vec<Column>,
    /// `(scenario time, values)`; `None` where the driver had no value yet.
    pub rows: Vec<(Duration, Vec<Option<i64>>)>,
}

/// Bus figures at the end of the run.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BusSummary {
    /// Frames seen on the wire, per identifier.
    pub frames_by_id: BTreeMap<u32, u64>,
    /// Total frames.
    pub frames: u64,
    /// Bus load in percent over the run (virtual bus only).
    pub load_percent: Option<f64>,
    /// Frames lost to CRC errors (corrupt faults).
    pub errors: u64,
    /// Frames dropped by faults.
    pub dropped: u64,
    /// Frames the recorder missed (its queue overflowed): the recording and `frames` are
    /// incomplete by this many.
    pub recorder_missed: u64,
    /// Each bus's frames and load, in bench order, when the bench has several (empty with
    /// one: the totals above are its own).
    pub per_bus: Vec<BusLoad>,
}

/// One bus's share of a several-bus bench, to hold against its bit rate.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BusLoad {
    /// The bus's name.
    pub name: String,
    /// Frames seen on it.
    pub frames: u64,
    /// Its load in percent over the run.
    pub load_percent: f64,
}

/// The verdict of a scenario.
#[derive(Debug, Clone, PartialEq)]
pub enum Verdict {
    /// Every step passed.
    Passed,
    /// A step failed or timed out.
    Failed,
    /// Not run, with the reason (e.g. needs the in-process emulator).
    Skipped(String),
    /// The bench could not be built.
    Error(String),
}

impl Verdict {
    /// `PASS`, `FAIL`, `SKIP`, `ERROR`.
    pub fn word(&self) -> &'static str {
        match self {
            Self::Passed => "PASS",
            Self::Failed => "FAIL",
            Self::Skipped(_) => "SKIP",
            Self::Error(_) => "ERROR",
        }
    }

    /// Whether this verdict keeps the exit code at 0.
    pub fn ok(&self) -> bool {
        matches!(self, Self::Passed | Self::Skipped(_))
    }
}

/// What the HTML report needs to know about the bench to draw and decode (never in
/// snapshots).
#[derive(Clone, Default)]
pub struct BenchInfo {
    /// How to draw the arm or robot the scenario drives (its URDF, the columns that pose it).
    pub drawing: Option<crate::devices::Drawing>,
    /// Each CAN device's frame decoder, in bench order: a frame is named by the first that
    /// knows it.
    pub frame_decoders: Vec<DeviceFrames>,
}

/// One CAN device's frame decoder and the names of the bench's buses it sits on.
#[derive(Clone)]
pub struct DeviceFrames {
    /// The device's buses.
    pub buses: Vec<String>,
    /// Its decoder.
    pub decoder: std::sync::Arc<dyn crate::devices::FrameDecoder>,
}

impl BenchInfo {
    /// The frame's name and fields by the first device that knows it (`None`: no device on
    /// the bench does). `bus` is the bus the capture says the frame was on: when the bench
    /// has a bus of that name only its devices are asked, by that bus; a name the bench does
    /// not have (a capture of the robot's own interfaces, named otherwise) is no evidence.
    pub fn decode(
        &self,
        bus: Option<&str>,
        frame: &bus::CanFrame,
    ) -> Option<crate::interop::DecodedFrame> {
        let on = |d: &DeviceFrames, bus: &str| d.buses.iter().any(|b| b == bus);
        let bus = bus.filter(|bus| self.frame_decoders.iter().any(|d| on(d, bus)));
        self.frame_decoders
            .iter()
            .filter(|d| bus.is_none_or(|bus| on(d, bus)))
            .find_map(|d| d.decoder.decode(bus, frame))
    }
}

impl std::fmt::Debug for BenchInfo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BenchInfo")
            .field("urdf_bytes", &self.drawing.as_ref().map(|d| d.urdf.len()))
            .field("frame_decoders", &self.frame_decoders.len())
            .finish()
    }
}

/// Everything one scenario run produced.
#[derive(Debug, Clone)]
pub struct ScenarioResult {
    /// Scenario name.
    pub name: String,
    /// Scenario file.
    pub path: PathBuf,
    /// Verdict.
    pub verdict: Verdict,
    /// `virtual`, `realtime` or `iface <name>`.
    pub clock: String,
    /// Per-step results.
    pub steps: Vec<StepResult>,
    /// Faults applied and removed.
    pub faults: Vec<FaultEvent>,
    /// The sampled trace.
    pub trace: Trace,
    /// Bus figures.
    pub bus: BusSummary,
    /// The bus recordings asked for (temporary files until the report copies them).
    pub recording: Recording,
    /// Scenario time the run took.
    pub duration: Duration,
    /// Wall-clock time the run took (never in snapshots).
    pub wall: Duration,
    /// The bench, for the HTML report.
    pub bench_info: BenchInfo,
}

impl ScenarioResult {
    /// A result for a scenario that did not run.
    pub fn not_run(name: &str, path: PathBuf, verdict: Verdict, clock: &str) -> Self {
        Self {
            name: name.to_owned(),
            path,
            verdict,
            clock: clock.to_owned(),
            steps: Vec::new(),
            faults: Vec::new(),
            trace: Trace::default(),
            bus: BusSummary::default(),
            recording: Recording::default(),
            duration: Duration::ZERO,
            wall: Duration::ZERO,
            bench_info: BenchInfo::default(),
        }
    }

    /// The first failing step, if any.
    pub fn first_failure(&self) -> Option<&StepResult> {
        self.steps
            .iter()
            .find(|s| !matches!(s.outcome, Outcome::Passed | Outcome::NotRun))
    }
}
