//! The legged robots of the public corpus (example-robot-data 6.0.0; `testkit::corpus`) as
//! whole robots: a robot file written by `testkit::corpus` (a RobStride actuator on every
//! joint, one bus per leg or limb, `gantry: until_enabled`) and a scenario, run in virtual
//! time through the harness as `armhil run` runs it:
//!
//! 1. the robot hangs on its gantry in its standing pose, feet 1 mm above the ground, powered
//!    but not enabled, for [`HANG_MS`] ms: the base does not move;
//! 2. every actuator gets its hold command (operation control at its start angle, kp and kd
//!    proportional to the joint's torque: `LeggedRobot::kp_per_nm`, `kd_per_nm`), then all are
//!    enabled; the gantry lets go when the last one is;
//! 3. [`SETTLE_MS`] ms later the base stays within [`STAND_TOLERANCE`] of its start height
//!    for [`STAND_MS`] ms: the robot stands on its actuators;
//! 4. every actuator is disabled; [`FALL_MS`] ms later the base lies well below its standing
//!    height and above the ground ([`FALLEN_RANGE`]) and stays there for [`LIE_MS`] ms,
//!    moving less than [`REST_MM`] mm in the last [`REST_MS`] ms: it has come to rest (a
//!    fallen humanoid bounces and settles for 1–2 s; the solo12, braked by twelve RS04 for
//!    its URDF's 1000 N·m efforts, sinks at ~6 cm/s and lies still 3.5 s after disabling).
//!
//! Every robot stands with the same gains per N·m (kp 20, kd 0.05). Measured with this test's
//! checks and an 8 s standing window: all six stand with kp 12 to 60 and kd 0.02 to 0.1 per
//! N·m; the G1 and Talos fall with kp 10; the G1 falls with kd 0.3 (kp 20); the go1 and a1
//! still stand with kp 2 but sag more than 5 %. What does not work is in [`FAILS`], asserted:
//! a stale entry fails. Unset `ARMHIL_URDF_CORPUS`: one `skipped:` line, and every test
//! passes, unless `ARMHIL_REQUIRE_TOOLS=1`.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::PathBuf;
use std::sync::OnceLock;
use std::time::Duration;

use armhil::harness::result::Trace;
use armhil::harness::{load_scenario, run_scenario, Clock, Outcome, ScenarioResult, Verdict};
use testkit::corpus::{self, CorpusRobot, LeggedRobot, LEGGED};

/// How long the robot hangs on its gantry before it is enabled (ms).
const HANG_MS: u64 = 50;
/// Settling time after the gantry lets go (ms).
const SETTLE_MS: u64 = 1000;
/// How long the base must stay at its standing height (ms).
const STAND_MS: u64 = 1000;
/// Standing: the base within this fraction of its start height.
const STAND_TOLERANCE: f64 = 0.05;
/// Time from disabling to the fallen check (ms).
const FALL_MS: u64 = 2000;
/// How long the fallen robot must then lie in [`FALLEN_RANGE`] (ms).
const LIE_MS: u64 = 2000;
/// How long, at the end, the fallen robot must lie still (ms), and how still (mm of base
/// height).
const REST_MS: u64 = 500;
const REST_MM: f64 = 5.0;

/// Longest a `group: {do: enable}` of every actuator may take in virtual time (ms): one
/// request and its answer per actuator, the buses in parallel, each answer a firmware's
/// turnaround after its request (TALOS: 32 actuators on four buses).
const ENABLE_ALL_MAX_MS: f64 = 10.0;

/// Fallen: the base between these fractions of its start height.
const FALLEN_RANGE: (f64, f64) = (0.05, 0.4);

/// Robots that do not stand after hanging longer on the gantry: robot, time on the gantry
/// (ms), why, and what was measured: how long after enabling its base left the standing band
/// (ms). Each still runs and must still fall, at that time ±300 ms.
const FAILS: &[(&str, u64, &str, u64)] = &[(
    "g1_29dof_rev_1_0",
    200,
    "hanging unpowered, its torso pitches forward on the waist (waist_pitch 0.27 rad after \
     200 ms: an RS06's shorted windings only slow it) and its arms swing; released when \
     enabled, with the joints still off their pose, it tips forward and falls (100 ms on the \
     gantry are fine, 150 ms are not). Enabling it on the gantry and releasing it later \
     (`until_released`) does not help at these gains: the waist (kp 700, kd 1.75 N·m·s/rad \
     on ~1 kg·m² of torso and arms, damping ratio ~0.03) still swings ±0.5 rad 500 ms after \
     enabling, and kd 0.3 per N·m makes the stance itself fall (every joint enabled within \
     2 ms, it sags out of the band 1.6 s after enabling; 0.96 s when they were enabled one \
     at a time)",
    1614,
)];

/// A scenario for `robot` (robot file `robot.yaml` beside it) and the indices of its steps
/// the checks read: (text, enable step, standing check).
fn scenario(robot: &CorpusRobot, legged: &LeggedRobot, hang_ms: u64) -> (String, usize, usize) {
    let h = robot.start_height_m;
    // One hold step per pair of gains (a step sends one kp and kd to every joint it names).
    let mut by_gains: Vec<((f64, f64), Vec<String>)> = Vec::new();
    for a in &robot.actuators {
        let gains = a.gains(legged.kp_per_nm, legged.kd_per_nm);
        let target = format!("\"{}\": {:?}", a.joint, a.start_rad);
        match by_gains.iter_mut().find(|(g, _)| *g == gains) {
            Some((_, targets)) => targets.push(target),
            None => by_gains.push((gains, vec![target])),
        }
    }
    let mut steps = vec![
        format!("wait_ms: {hang_ms}"),
        format!("expect: {{base_height_m: {h:?}, tolerance_m: 0.0001}}"),
    ];
    for ((kp, kd), targets) in &by_gains {
        steps.push(format!(
            "group: {{do: hold, targets_rad: {{{}}}, kp: {kp:?}, kd: {kd:?}}}",
            targets.join(", ")
        ));
    }
    let enable = steps.len();
    steps.push("group: {do: enable}".to_owned());
    steps.push(format!("wait_ms: {SETTLE_MS}"));
    let stand = steps.len();
    steps.push(format!(
        "expect: {{base_height_m: {h:?}, tolerance_m: {:?}, for_ms: {STAND_MS}}}",
        STAND_TOLERANCE * h
    ));
    steps.push("group: {do: disable}".to_owned());
    steps.push(format!("wait_ms: {FALL_MS}"));
    let (lo, hi) = FALLEN_RANGE;
    steps.push(format!(
        "expect: {{base_height_m: {:?}, tolerance_m: {:?}, for_ms: {LIE_MS}}}",
        (lo + hi) / 2.0 * h,
        (hi - lo) / 2.0 * h
    ));
    let mut text = format!(
        "name: corpus_{}\n\
         bench:\n  devices:\n    robot: {{kind: actuator_group, robot: robot.yaml}}\n\
         record: {{signals: [pose], sample_period_ms: 10, candump: false, pcap: false, \
         plot: false}}\n\
         steps:\n",
        robot.name
    );
    for step in steps {
        text.push_str(&format!("  - {step}\n"));
    }
    (text, enable, stand)
}

/// The base height samples (m) of `trace` from `from` to `to`.
fn heights(trace: &Trace, from: Duration, to: Duration) -> Vec<f64> {
    let column = trace
        .columns
        .iter()
        .position(|c| c.name.ends_with("base_height_m"))
        .expect("a base_height_m column");
    let quantum = trace.columns[column].quantum;
    trace
        .rows
        .iter()
        .filter(|(t, _)| *t >= from && *t <= to)
        .filter_map(|(_, v)| v[column].map(|x| x as f64 * quantum))
        .collect()
}

fn min_max(values: &[f64]) -> (f64, f64) {
    values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(*v), hi.max(*v))
        })
}

/// A robot's scenario, run.
struct Run {
    robot: CorpusRobot,
    legged: LeggedRobot,
    text: String,
    result: ScenarioResult,
    enable: usize,
    stand: usize,
}

impl Run {
    /// The base's lowest and highest height (m) during step `step`.
    fn during(&self, step: usize) -> (f64, f64) {
        let s = &self.result.steps[step];
        min_max(&heights(&self.result.trace, s.started, s.started + s.took))
    }

    /// Time from enabling until the base first left the standing band (ms), if it did
    /// while the trace ran.
    fn left_standing_band_after_ms(&self) -> Option<u64> {
        let from = self.result.steps[self.enable].started;
        let h = self.robot.start_height_m;
        let column = self
            .result
            .trace
            .columns
            .iter()
            .position(|c| c.name.ends_with("base_height_m"))
            .expect("a base_height_m column");
        let quantum = self.result.trace.columns[column].quantum;
        let in_trace = self
            .result
            .trace
            .rows
            .iter()
            .filter(|(t, _)| *t >= from)
            .find(|(_, v)| {
                v[column].is_some_and(|x| (x as f64 * quantum - h).abs() > STAND_TOLERANCE * h)
            })
            .map(|(t, _)| *t);
        // The standing check samples every step, the trace less often: a run that ends at
        // the check's failure may leave the band between two trace rows.
        let stand = &self.result.steps[self.stand];
        let at_check =
            matches!(stand.outcome, Outcome::Failed { .. }).then_some(stand.started + stand.took);
        [in_trace, at_check]
            .into_iter()
            .flatten()
            .min()
            .map(|t| (t - from).as_millis() as u64)
    }

    /// The base's lowest and highest height (m) in the last [`REST_MS`].
    fn at_rest(&self) -> (f64, f64) {
        let end = self.result.duration;
        let from = end.saturating_sub(Duration::from_millis(REST_MS));
        min_max(&heights(&self.result.trace, from, end))
    }

    /// Actuators per model and per bus, for the report line.
    fn layout(&self) -> String {
        let mut models: BTreeMap<&str, usize> = BTreeMap::new();
        let mut buses = vec![0; self.robot.buses.len()];
        for a in &self.robot.actuators {
            *models.entry(a.model.name()).or_default() += 1;
            buses[a.bus] += 1;
        }
        let models: Vec<String> = models.iter().map(|(m, n)| format!("{n} {m}")).collect();
        let buses: Vec<String> = buses.iter().map(usize::to_string).collect();
        format!(
            "{} actuators ({}) on {} buses ({})",
            self.robot.actuators.len(),
            models.join(", "),
            self.robot.buses.len(),
            buses.join("+")
        )
    }

    fn steps(&self) -> String {
        self.result
            .steps
            .iter()
            .map(|s| format!("  {} {}: {:?}", s.index, s.label, s.outcome))
            .collect::<Vec<_>>()
            .join("\n")
    }

    /// Everything needed to see what happened: steps, robot file, scenario.
    fn details(&self) -> String {
        format!(
            "verdict {:?}\n{}\nrobot file:\n{}\nscenario:\n{}",
            self.result.verdict,
            self.steps(),
            self.robot.to_yaml(),
            self.text
        )
    }
}

/// The corpus folder, or `None` after one `skipped:` line for all the tests (a panic under
/// `ARMHIL_REQUIRE_TOOLS=1`, in every test).
fn corpus_root() -> Option<PathBuf> {
    static ROOT: OnceLock<Option<PathBuf>> = OnceLock::new();
    ROOT.get_or_init(|| corpus::corpus_root("corpus_robots"))
        .clone()
}

/// Writes `name`'s robot file and scenario into a temporary folder and runs it; `None` (after
/// one `skipped:` line) without the corpus.
fn run(name: &str, hang_ms: u64) -> Option<Run> {
    let root = corpus_root()?;
    let legged = *LEGGED
        .iter()
        .find(|l| l.name() == name)
        .expect("a robot of testkit::corpus::LEGGED");
    assert!(
        root.join(legged.urdf).is_file(),
        "{}: not in the corpus at {}",
        legged.urdf,
        root.display()
    );
    let robot = legged.plan(&root).unwrap_or_else(|e| panic!("{name}: {e}"));
    let (text, enable, stand) = scenario(&robot, &legged, hang_ms);
    let dir = tempfile::tempdir().expect("a temporary folder");
    std::fs::write(dir.path().join("robot.yaml"), robot.to_yaml()).expect("robot file written");
    let path = dir.path().join("scenario.yaml");
    std::fs::write(&path, &text).expect("scenario written");
    let scenario = load_scenario(&path).unwrap_or_else(|e| panic!("{name}: {e}\n{text}"));
    let result = run_scenario(&scenario, &Clock::Virtual);
    Some(Run {
        robot,
        legged,
        text,
        result,
        enable,
        stand,
    })
}

/// `name` stands after [`HANG_MS`] on its gantry and falls when let go (see the module's
/// documentation).
fn stands_while_held_and_falls_when_let_go(name: &str) {
    let Some(run) = run(name, HANG_MS) else {
        return;
    };
    let h = run.robot.start_height_m;
    let (stand_lo, stand_hi) = run.during(run.stand);
    let (rest_lo, rest_hi) = run.at_rest();
    let enable_ms = run.result.steps[run.enable].took.as_secs_f64() * 1e3;
    let line = format!(
        "corpus_robots: {name}: {:.1} kg, {}; hung {HANG_MS} ms, start height {h:.4} m; every \
         actuator enabled in {:.1} ms; held at kp {}/N·m, kd {}/N·m: base \
         {stand_lo:.3}..{stand_hi:.3} m for {STAND_MS} ms; disabled: rests at \
         {rest_lo:.3}..{rest_hi:.3} m; {:.1} s emulated in {:.2} s",
        run.robot.mass_kg,
        run.layout(),
        enable_ms,
        run.legged.kp_per_nm,
        run.legged.kd_per_nm,
        run.result.duration.as_secs_f64(),
        run.result.wall.as_secs_f64(),
    );
    let _ = writeln!(std::io::stderr(), "{line}");
    assert_eq!(
        run.result.verdict,
        Verdict::Passed,
        "{name}:\n{line}\n{}",
        run.details()
    );
    assert!(
        enable_ms <= ENABLE_ALL_MAX_MS,
        "{name}: enabling every actuator took {enable_ms:.1} ms (at most {ENABLE_ALL_MAX_MS})\n{line}"
    );
    assert!(
        (rest_hi - rest_lo) * 1000.0 <= REST_MM,
        "{name}: not at rest {REST_MS} ms before the end: {rest_lo:.4}..{rest_hi:.4} m\n{line}"
    );
}

#[test]
fn go1_stands_while_held_and_falls_when_let_go() {
    stands_while_held_and_falls_when_let_go("go1");
}

#[test]
fn a1_stands_while_held_and_falls_when_let_go() {
    stands_while_held_and_falls_when_let_go("a1");
}

#[test]
fn anymal_b_stands_while_held_and_falls_when_let_go() {
    stands_while_held_and_falls_when_let_go("anymal");
}

#[test]
fn solo12_stands_while_held_and_falls_when_let_go() {
    stands_while_held_and_falls_when_let_go("solo12");
}

#[test]
fn g1_stands_while_held_and_falls_when_let_go() {
    stands_while_held_and_falls_when_let_go("g1_29dof_rev_1_0");
}

#[test]
fn talos_stands_while_held_and_falls_when_let_go() {
    stands_while_held_and_falls_when_let_go("talos_reduced");
}

/// Every robot of [`LEGGED`] has a test above, and every entry of [`FAILS`] still fails: the
/// standing check does not pass, and the base leaves the standing band when measured.
#[test]
fn listed_failures_still_fail() {
    let tested = [
        "go1",
        "a1",
        "anymal",
        "solo12",
        "g1_29dof_rev_1_0",
        "talos_reduced",
    ];
    for legged in LEGGED {
        assert!(
            tested.contains(&legged.name()),
            "{}: a legged robot without a test here",
            legged.name()
        );
    }
    for (name, hang_ms, why, measured_ms) in FAILS {
        let Some(run) = run(name, *hang_ms) else {
            return;
        };
        let stood = run.result.steps[run.stand].outcome == Outcome::Passed;
        let fell_ms = run.left_standing_band_after_ms().unwrap_or(u64::MAX);
        let _ = writeln!(
            std::io::stderr(),
            "corpus_robots: {name} hung {hang_ms} ms: stood {stood}, left the standing band \
             {fell_ms} ms after enabling (listed: {measured_ms} ms) — {why}"
        );
        assert!(
            !stood,
            "{name} hung {hang_ms} ms is listed as falling ({why}) but stood: take it off \
             FAILS\n{}",
            run.details()
        );
        assert!(
            fell_ms.abs_diff(*measured_ms) <= 300,
            "{name} hung {hang_ms} ms: listed as falling {measured_ms} ms after enabling, fell \
             after {fell_ms} ms\n{}",
            run.details()
        );
    }
}
