//! `armhil run`: run scenario files or folders and report a verdict per scenario.

use std::io::IsTerminal as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use armhil::harness::report::{junit_xml, write_atomic, write_outputs, Written};
use armhil::harness::{
    discover, load_scenario, run_scenario_with, Clock, Outcome, RunOptions, ScenarioResult, Verdict,
};
use indicatif::{ProgressBar, ProgressStyle};

/// Arguments of `armhil run`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scenario files or folders (searched recursively for *.yaml / *.yml).
    #[arg(required = true)]
    paths: Vec<PathBuf>,
    /// Write a JUnit XML report of the suite to this file.
    #[arg(long, value_name = "FILE")]
    junit: Option<PathBuf>,
    /// Output root: each scenario writes into DIR/<scenario name>/.
    #[arg(long, value_name = "DIR", default_value = "out")]
    out: PathBuf,
    /// Run on the real clock instead of virtual time: on the scenario's `bench.bus.interface`
    /// when it names one, else with the in-process emulator on the virtual bus.
    #[arg(long)]
    realtime: bool,
    /// Run in real time against a separate emulator process (`armhil sim piper --iface IF`)
    /// on this SocketCAN interface. Scenarios that need the in-process emulator (emulator or
    /// bus faults, obstacles, initial joints) are skipped with the reason.
    #[arg(long, value_name = "IF")]
    iface: Option<String>,
    /// Multiply every deadline (wait_until, action and driver timeouts) by this factor in
    /// real-time runs, for slow machines such as a vcan VM under emulation. Ignored in virtual
    /// time.
    #[arg(long, value_name = "FACTOR", default_value_t = 1.0)]
    time_scale: f64,
}

fn secs(d: Duration) -> String {
    format!("{:.2} s", d.as_secs_f64())
}

fn verdict_line(r: &ScenarioResult) -> String {
    match &r.verdict {
        Verdict::Skipped(reason) => return format!("SKIP  {}: {reason}", r.name),
        Verdict::Error(message) => return format!("ERROR {}: {message}", r.name),
        Verdict::Passed | Verdict::Failed => {}
    }
    let passed = r.steps.iter().filter(|s| s.outcome.passed()).count();
    let mut line = format!(
        "{:<5} {} ({}/{} steps, {} scenario time, {} wall)",
        r.verdict.word(),
        r.name,
        passed,
        r.steps.len(),
        secs(r.duration),
        secs(r.wall)
    );
    match &r.verdict {
        Verdict::Skipped(_) | Verdict::Error(_) => {}
        Verdict::Failed => {
            if let Some(step) = r.first_failure() {
                line.push_str(&format!(
                    "\n      step {} `{}` (line {}) {}",
                    step.index + 1,
                    step.label,
                    step.line,
                    step.outcome.name().replace('_', " ")
                ));
                match &step.outcome {
                    Outcome::Failed { expected, actual }
                    | Outcome::TimedOut {
                        expected, actual, ..
                    } => {
                        line.push_str(&format!(
                            "\n      expected: {expected}\n      actual:   {actual}"
                        ));
                    }
                    Outcome::Passed | Outcome::NotRun => {}
                }
            }
        }
        Verdict::Passed => {}
    }
    line
}

fn where_written(w: &Written) -> String {
    let show = |p: &Option<PathBuf>| p.as_deref().map(Path::display).map(|d| d.to_string());
    let mut parts = Vec::new();
    if let Some(s) = show(&w.snapshot) {
        parts.push(format!("      snapshot:  {s}"));
    }
    let recording: Vec<String> = [show(&w.candump), show(&w.pcap)]
        .into_iter()
        .flatten()
        .collect();
    if !recording.is_empty() {
        parts.push(format!("      recording: {}", recording.join(", ")));
    }
    if let Some(s) = show(&w.plot) {
        parts.push(format!("      plot:      {s}"));
    }
    parts.join("\n")
}

/// Run every scenario; exit 0 only when none failed.
pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let clock_for = |bench_iface: Option<&String>| match (&args.iface, args.realtime, bench_iface) {
        (Some(iface), _, _) => Clock::Iface(iface.clone()),
        (None, true, Some(iface)) => Clock::Iface(iface.clone()),
        (None, true, None) => Clock::Realtime,
        (None, false, _) => Clock::Virtual,
    };
    if !(args.time_scale.is_finite() && args.time_scale >= 1.0) {
        anyhow::bail!(
            "--time-scale must be a number >= 1, got {}",
            args.time_scale
        );
    }
    let files = discover(&args.paths)?;
    if files.is_empty() {
        anyhow::bail!("no scenario files (*.yaml, *.yml) found");
    }
    let progress = (files.len() > 1 && std::io::stderr().is_terminal()).then(|| {
        let bar = ProgressBar::new(files.len() as u64);
        if let Ok(style) = ProgressStyle::with_template("{bar:30} {pos}/{len} {msg}") {
            bar.set_style(style);
        }
        bar
    });
    let print = |text: &str| match &progress {
        Some(bar) => bar.println(text),
        None => println!("{text}"),
    };
    if let Some(iface) = &args.iface {
        print(&format!(
            "running on {iface} in real time against a separate emulator process: bus faults and emulator faults are unavailable; scenarios that use them are skipped"
        ));
    }
    let mut results = Vec::new();
    let mut last_written = None;
    for file in &files {
        if let Some(bar) = &progress {
            bar.set_message(file.display().to_string());
        }
        let result = match load_scenario(file) {
            Ok(scenario) => {
                let options = RunOptions {
                    time_scale: args.time_scale,
                };
                let result = run_scenario_with(
                    &scenario,
                    &clock_for(scenario.bench.interface.as_ref()),
                    &options,
                );
                if !matches!(result.verdict, Verdict::Skipped(_)) {
                    let dir = args.out.join(&scenario.name);
                    match write_outputs(&result, &scenario.record, &dir) {
                        Ok(w) => last_written = Some(w),
                        Err(e) => {
                            print(&format!("error writing outputs to {}: {e}", dir.display()))
                        }
                    }
                }
                result
            }
            Err(e) => {
                let name = file.file_stem().map_or_else(
                    || "scenario".to_owned(),
                    |s| s.to_string_lossy().into_owned(),
                );
                ScenarioResult::not_run(&name, file.clone(), Verdict::Error(e.to_string()), "none")
            }
        };
        print(&verdict_line(&result));
        if files.len() == 1 {
            if let Some(w) = &last_written {
                print(&where_written(w));
            }
        }
        if let Some(bar) = &progress {
            bar.inc(1);
        }
        results.push(result);
    }
    if let Some(bar) = progress {
        bar.finish_and_clear();
    }
    let count = |f: fn(&Verdict) -> bool| results.iter().filter(|r| f(&r.verdict)).count();
    let passed = count(|v| matches!(v, Verdict::Passed));
    let failed = count(|v| matches!(v, Verdict::Failed));
    let errors = count(|v| matches!(v, Verdict::Error(_)));
    let skipped = count(|v| matches!(v, Verdict::Skipped(_)));
    if files.len() > 1 {
        let scenario_time: Duration = results.iter().map(|r| r.duration).sum();
        let wall: Duration = results.iter().map(|r| r.wall).sum();
        println!(
            "{} scenarios: {passed} passed, {failed} failed, {errors} errors, {skipped} skipped ({} scenario time in {} wall)",
            results.len(),
            secs(scenario_time),
            secs(wall)
        );
        println!(
            "outputs: {}/<scenario>/{{result.yaml, bus.log, bus.pcap, plot.svg}}",
            args.out.display()
        );
    }
    if let Some(path) = &args.junit {
        write_atomic(path, junit_xml("armhil", &results).as_bytes())?;
        println!("junit: {}", path.display());
    }
    Ok(if failed == 0 && errors == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}
