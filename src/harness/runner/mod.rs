//! Runs a scenario: builds the bench, executes the steps, applies faults, samples the state.

mod faults;
mod recorder;
mod spool;
mod trace;

use std::sync::Arc;
use std::time::Duration;

use tokio::time::Instant;

pub use crate::wiring::{
    Clock, Link, RunOptions, DEFAULT_RECORDING_LIMIT_BYTES, MAX_DEADLINE, MAX_TIME_SCALE,
};

pub(crate) use recorder::Recorder;
pub(crate) use spool::Spool;
pub use spool::{Omitted, Recording};

use super::bench::{self, BuiltBench};
use super::model::{FaultTrigger, Scenario, Step, StepKind};
use super::result::{BusLoad, BusSummary, Outcome, ScenarioResult, StepResult, Verdict};
use crate::devices::Device;
use faults::FaultControl;
use trace::Sampler;

/// Polling period of `wait_until` and `expect … for_ms`.
const POLL: Duration = Duration::from_millis(1);

/// Run one scenario to completion on its own tokio runtime.
///
/// With [`Clock::Iface`], scenarios that need the in-process emulator (faults, obstacles,
/// initial joints) are skipped with the reason.
pub fn run_scenario(scenario: &Scenario, clock: &Clock) -> ScenarioResult {
    run_scenario_with(scenario, clock, &RunOptions::default())
}

/// [`run_scenario`] with options (deadline scaling for slow real-time runs).
pub fn run_scenario_with(
    scenario: &Scenario,
    clock: &Clock,
    options: &RunOptions,
) -> ScenarioResult {
    // Virtual time is exact: scaling deadlines there would only hide regressions.
    let options = match clock {
        Clock::Virtual => RunOptions {
            interrupt: options.interrupt.clone(),
            recording_limit_bytes: options.recording_limit_bytes,
            ..RunOptions::default()
        },
        Clock::Realtime | Clock::Iface(_) => options.clone(),
    };
    let wall_start = std::time::Instant::now();
    if let Clock::Iface(link) = clock {
        let needs = scenario.in_process_requirements();
        if !needs.is_empty() {
            let reason = format!(
                "needs the in-process emulator (not available with {}): {}",
                link.flag(),
                needs.join(", ")
            );
            return ScenarioResult::not_run(
                &scenario.name,
                scenario.path.clone(),
                Verdict::Skipped(reason),
                &clock.describe(),
            );
        }
    }
    let runtime = match clock {
        Clock::Virtual => tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .start_paused(true)
            .build(),
        Clock::Realtime | Clock::Iface(_) => tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .enable_all()
            .build(),
    };
    let mut result = match runtime {
        Ok(rt) => rt.block_on(run_async(scenario, clock, &options)),
        Err(e) => ScenarioResult::not_run(
            &scenario.name,
            scenario.path.clone(),
            Verdict::Error(format!("cannot start the tokio runtime: {e}")),
            &clock.describe(),
        ),
    };
    result.wall = wall_start.elapsed();
    result
}

async fn run_async(scenario: &Scenario, clock: &Clock, options: &RunOptions) -> ScenarioResult {
    let built = match bench::build(scenario, clock, options).await {
        Ok(b) => b,
        Err(message) => {
            return ScenarioResult::not_run(
                &scenario.name,
                scenario.path.clone(),
                Verdict::Error(message),
                &clock.describe(),
            )
        }
    };
    let BuiltBench {
        devices,
        buses,
        recorder,
        t0,
        timeline: _timeline,
    } = built;
    let faults = Arc::new(FaultControl::new(
        devices.clone(),
        scenario
            .bench
            .buses
            .iter()
            .zip(&buses)
            .map(|(spec, bus)| (spec.name.clone(), bus.faults()))
            .collect(),
        t0,
    ));
    let sampler = Sampler::start(&scenario.record, devices.clone(), t0);
    for fault in &scenario.faults {
        if let FaultTrigger::At(at) = fault.trigger {
            let delay = at.saturating_sub(t0.elapsed());
            faults.schedule(delay, fault.fault.clone(), fault.duration);
        }
    }

    let mut steps = Vec::new();
    let mut failed = false;
    let mut interrupted: Option<String> = None;
    let mut emulator_error: Option<String> = None;
    for step in &scenario.steps {
        if interrupted.is_none() {
            interrupted = options.interrupt.reason().map(|reason| {
                format!(
                    "interrupted by {reason} before step {} (line {})",
                    step.index + 1,
                    step.line
                )
            });
        }
        if failed || interrupted.is_some() {
            steps.push(StepResult {
                index: step.index,
                line: step.line,
                label: step.label.clone(),
                id: step.id.clone(),
                started: t0.elapsed(),
                took: Duration::ZERO,
                outcome: Outcome::NotRun,
                reply: Vec::new(),
            });
            continue;
        }
        let started = t0.elapsed();
        let step_start = Instant::now();
        let (mut outcome, reply) = tokio::select! {
            ran = run_step(step, &devices, &faults, options) => ran,
            reason = options.interrupt.fired() => {
                interrupted = Some(format!(
                    "interrupted by {reason} during step {} (line {})",
                    step.index + 1,
                    step.line
                ));
                (Outcome::NotRun, Vec::new())
            }
        };
        // A step that passed on an unsound emulator (NaN physics reads as an arm at rest at
        // 0°) did not pass: the emulator's error fails it and ends the scenario.
        if emulator_error.is_none() && outcome != Outcome::NotRun {
            emulator_error = emulator_health(&devices, false).await;
            if let Some(why) = &emulator_error {
                outcome = Outcome::Failed {
                    expected: "a sound emulator".to_owned(),
                    actual: why.clone(),
                };
            }
        }
        failed = !outcome.passed();
        steps.push(StepResult {
            index: step.index,
            line: step.line,
            label: step.label.clone(),
            id: step.id.clone(),
            started,
            took: step_start.elapsed(),
            outcome,
            reply,
        });
        for fault in &scenario.faults {
            if let FaultTrigger::AfterStep { step: after, delay } = fault.trigger {
                if after == step.index {
                    faults.schedule(delay, fault.fault.clone(), fault.duration);
                }
            }
        }
    }
    if emulator_error.is_none() && interrupted.is_none() {
        // Scheduled faults may act after the last step.
        emulator_error = emulator_health(&devices, true).await;
    }
    let duration = t0.elapsed();
    let trace = sampler.finish();
    let (fault_events, fault_errors) = faults.finish();
    for dev in &devices {
        dev.shutdown().await;
    }
    let stats: Vec<_> = buses
        .iter()
        .map(bus::virtual_bus::VirtualBus::stats)
        .collect();
    let (capture, missed) = recorder.finish().await;
    if missed > 0 {
        tracing::warn!(
            scenario = %scenario.name,
            missed,
            "the recorder missed frames: bus.log, bus.pcap and the frame counts are incomplete"
        );
    }

    let summary = BusSummary {
        frames: capture.count,
        frames_by_id: capture.by_id,
        // The busiest bus's load: the one that would saturate first.
        load_percent: stats.iter().map(|s| s.load_percent).reduce(f64::max),
        errors: stats.iter().map(|s| s.errors).sum(),
        dropped: stats.iter().map(|s| s.dropped).sum(),
        recorder_missed: missed,
        per_bus: if buses.len() > 1 {
            scenario
                .bench
                .buses
                .iter()
                .zip(&stats)
                .map(|(spec, s)| BusLoad {
                    name: spec.name.clone(),
                    frames: capture.by_bus.get(&spec.name).copied().unwrap_or(0),
                    load_percent: s.load_percent,
                })
                .collect()
        } else {
            Vec::new()
        },
    };
    let verdict = if let Some(why) = interrupted {
        failed = true;
        Verdict::Error(why)
    } else if let Some(why) = emulator_error {
        failed = true;
        Verdict::Error(format!("emulator error: {why}"))
    } else if let Some(err) = fault_errors.first() {
        failed = true;
        Verdict::Error(format!("scheduled fault failed: {err}"))
    } else if failed {
        Verdict::Failed
    } else {
        Verdict::Passed
    };
    let _ = failed;
    ScenarioResult {
        name: scenario.name.clone(),
        path: scenario.path.clone(),
        verdict,
        clock: clock.describe(),
        steps,
        faults: fault_events,
        trace,
        bus: summary,
        recording: capture.recording,
        duration,
        wall: Duration::ZERO,
        bench_info: crate::harness::report::bench_info(scenario),
    }
}

async fn run_step(
    step: &Step,
    devices: &[Arc<dyn Device>],
    faults: &Arc<FaultControl>,
    options: &RunOptions,
) -> (Outcome, Vec<(String, String)>) {
    let device = |index: usize| devices.get(index).cloned();
    match &step.kind {
        StepKind::Wait(d) => {
            tokio::time::sleep(*d).await;
            (Outcome::Passed, Vec::new())
        }
        StepKind::Action {
            device: index,
            action,
            timeout,
            expect_error,
        } => {
            let Some(dev) = device(*index) else {
                return (missing_device(*index), Vec::new());
            };
            let start = Instant::now();
            match (
                dev.perform(action, timeout.map(|t| options.deadline(t)))
                    .await,
                expect_error,
            ) {
                (Ok(reply), None) => {
                    if reply.mismatches.is_empty() {
                        (Outcome::Passed, reply.values)
                    } else {
                        let expected: Vec<String> = reply
                            .mismatches
                            .iter()
                            .map(|(k, e, _)| format!("{k} {e}"))
                            .collect();
                        let actual: Vec<String> = reply
                            .mismatches
                            .iter()
                            .map(|(k, _, a)| format!("{k} {a}"))
                            .collect();
                        (
                            Outcome::Failed {
                                expected: expected.join("; "),
                                actual: actual.join("; "),
                            },
                            reply.values,
                        )
                    }
                }
                (Ok(reply), Some(class)) => (
                    Outcome::Failed {
                        expected: format!("error ({})", class.name()),
                        actual: "success".to_owned(),
                    },
                    reply.values,
                ),
                (Err(e), None) => {
                    if e.class == super::model::ErrorClass::Timeout {
                        (
                            Outcome::TimedOut {
                                waited: start.elapsed(),
                                expected: "success".to_owned(),
                                actual: e.message,
                            },
                            Vec::new(),
                        )
                    } else {
                        (
                            Outcome::Failed {
                                expected: "success".to_owned(),
                                actual: format!("error ({}): {}", e.class.name(), e.message),
                            },
                            Vec::new(),
                        )
                    }
                }
                (Err(e), Some(class)) => {
                    let reply = vec![(
                        "error".to_owned(),
                        format!("{} — {}", e.class.name(), e.message),
                    )];
                    if *class == super::model::ErrorClass::Any || e.class == *class {
                        (Outcome::Passed, reply)
                    } else {
                        (
                            Outcome::Failed {
                                expected: format!("error ({})", class.name()),
                                actual: format!("error ({}): {}", e.class.name(), e.message),
                            },
                            reply,
                        )
                    }
                }
            }
        }
        StepKind::Expect {
            device: index,
            checks,
            hold,
        } => {
            let Some(dev) = device(*index) else {
                return (missing_device(*index), Vec::new());
            };
            if let Err((expected, actual)) = dev.evaluate(checks) {
                return (Outcome::Failed { expected, actual }, Vec::new());
            }
            if let Some(hold) = hold {
                let start = Instant::now();
                while start.elapsed() < *hold {
                    tokio::time::sleep(POLL).await;
                    if let Err((expected, actual)) = dev.evaluate(checks) {
                        let at = start.elapsed().as_millis();
                        return (
                            Outcome::Failed {
                                expected: format!("{expected} for {} ms", hold.as_millis()),
                                actual: format!("after {at} ms: {actual}"),
                            },
                            Vec::new(),
                        );
                    }
                }
            }
            (Outcome::Passed, Vec::new())
        }
        StepKind::WaitUntil {
            device: index,
            checks,
            timeout,
        } => {
            let Some(dev) = device(*index) else {
                return (missing_device(*index), Vec::new());
            };
            let timeout = options.deadline(*timeout);
            let start = Instant::now();
            loop {
                let last = match dev.evaluate(checks) {
                    Ok(()) => return (Outcome::Passed, Vec::new()),
                    Err((_, actual)) => actual,
                };
                if start.elapsed() >= timeout {
                    return (
                        Outcome::TimedOut {
                            waited: start.elapsed(),
                            expected: checks
                                .iter()
                                .map(crate::devices::Check::describe)
                                .collect::<Vec<_>>()
                                .join("; "),
                            actual: last,
                        },
                        Vec::new(),
                    );
                }
                tokio::time::sleep(POLL).await;
            }
        }
        StepKind::Inject { fault, duration } => match faults.apply(fault, *duration).await {
            Ok(()) => (Outcome::Passed, Vec::new()),
            Err(e) => (
                Outcome::Failed {
                    expected: format!("fault `{}` applied", fault.describe()),
                    actual: e,
                },
                Vec::new(),
            ),
        },
        StepKind::ClearFaults { device: index } => match faults.clear_all(*index).await {
            Ok(()) => (Outcome::Passed, Vec::new()),
            Err(e) => (
                Outcome::Failed {
                    expected: "faults cleared".to_owned(),
                    actual: e,
                },
                Vec::new(),
            ),
        },
    }
}

/// The first device whose emulator is unsound, as `device `name`: why` (`last`: see
/// [`Device::emulator_health`]).
async fn emulator_health(devices: &[Arc<dyn Device>], last: bool) -> Option<String> {
    for dev in devices {
        if let Err(why) = dev.emulator_health(last).await {
            return Some(format!("device `{}`: {why}", dev.name()));
        }
    }
    None
}

fn missing_device(index: usize) -> Outcome {
    Outcome::Failed {
        expected: format!("device #{index}"),
        actual: "not on the bench".to_owned(),
    }
}

#[cfg(test)]
mod deadline_tests {
    use super::*;

    #[test]
    fn deadlines_are_scaled_then_given_the_slack() {
        let options = RunOptions {
            time_scale: 10.0,
            deadline_slack: Duration::from_secs(3),
            ..RunOptions::default()
        };
        assert_eq!(
            options.deadline(Duration::from_millis(20)),
            Duration::from_millis(3200)
        );
        assert_eq!(
            options.deadline(Duration::from_secs(3)),
            Duration::from_secs(33)
        );
        assert_eq!(
            RunOptions::default().deadline(Duration::from_millis(20)),
            Duration::from_millis(20)
        );
    }

    #[test]
    fn an_absurd_factor_gives_the_longest_deadline_instead_of_a_panic() {
        for time_scale in [1e300, f64::MAX, 1e20] {
            let options = RunOptions {
                time_scale,
                deadline_slack: Duration::from_secs(600),
                ..RunOptions::default()
            };
            assert_eq!(options.deadline(Duration::from_secs(3600)), MAX_DEADLINE);
        }
        let largest = RunOptions {
            time_scale: MAX_TIME_SCALE,
            ..RunOptions::default()
        };
        assert_eq!(largest.deadline(Duration::from_secs(3600)), MAX_DEADLINE);
    }
}
