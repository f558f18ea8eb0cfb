//! `armhil run`: run scenario files or folders and report a verdict per scenario.

use std::io::IsTerminal as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use armhil::harness::report::{
    index_html, junit_xml, write_atomic, write_outputs, IndexEntry, Written,
};
use armhil::harness::{
    discover_suite, run_scenario_with, Clock, Interrupt, Link, Outcome, RunOptions, ScenarioResult,
    SuiteFile, SuiteLoader, Verdict, MAX_TIME_SCALE,
};
use indicatif::{ProgressBar, ProgressStyle};

use super::bus_args::BusArgs;
use super::signals::interrupt_on_signals;

/// Arguments of `armhil run`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scenario files or folders (searched recursively for *.yaml / *.yml).
    #[arg(required = true)]
    paths: Vec<PathBuf>,
    /// Write a JUnit XML report of the suite to this file.
    #[arg(long, value_name = "FILE")]
    junit: Option<PathBuf>,
    /// Output root: each scenario writes into DIR/<its path under the folder it was found in,
    /// without extension>/ (DIR/<file stem>/ for a file named directly).
    #[arg(long, value_name = "DIR", default_value = "out")]
    out: PathBuf,
    /// Scenarios run at once (default: every core). Outputs do not depend on it.
    #[arg(short = 'j', long, value_name = "N")]
    jobs: Option<usize>,
    /// Run only shard K of N (1-based): the K-th of N interleaved slices of the suite in path
    /// order, so N machines running 1/N .. N/N together run every scenario once.
    #[arg(long, value_name = "K/N", value_parser = Short(parse_shard))]
    shard: Option<(usize, usize)>,
    /// Run on the real clock instead of virtual time: on the scenario's `bench.bus.interface`
    /// when it names one, else with the in-process emulator on the virtual bus.
    #[arg(long)]
    realtime: bool,
    /// Run in real time against a separate emulator process on this bus (`--iface IF`, e.g.
    /// `armhil sim piper --iface IF`; or `--socketcand HOST:PORT`, e.g. `armhil sim
    /// piper|robstride --socketcand ADDR`, for machines without kernel CAN). Scenarios that
    /// need the in-process emulator (emulator or bus faults, obstacles, initial joints) are
    /// skipped with the reason.
    #[command(flatten)]
    bus: BusArgs,
    /// Multiply every deadline (wait_until, action and driver timeouts) by this factor, 1 to
    /// 1000, in real-time runs, for slow machines such as a vcan VM under emulation. Ignored
    /// in virtual time.
    #[arg(long, value_name = "FACTOR", default_value_t = 1.0, value_parser = Short(parse_time_scale))]
    time_scale: f64,
    /// Add this many milliseconds to every deadline after scaling, in real-time runs: room for
    /// the multi-second stalls of an emulated VM. Ignored in virtual time.
    #[arg(long, value_name = "MS", default_value_t = 0, value_parser = Short(parse_slack_ms))]
    deadline_slack_ms: u64,
    /// Size limit of each bus recording (bus.log, bus.pcap or bus.pcapng) per scenario, in
    /// MiB, 1 to 16384. A longer recording keeps its first half and its last; the report
    /// says which stretch of the bus was left out.
    #[arg(long, value_name = "MIB", default_value_t = DEFAULT_RECORDING_LIMIT_MIB,
          value_parser = Short(parse_recording_limit_mib))]
    max_recording_mib: u64,
}

/// Default of `--max-recording-mib`.
const DEFAULT_RECORDING_LIMIT_MIB: u64 = armhil::harness::DEFAULT_RECORDING_LIMIT_BYTES >> 20;
/// Largest `--max-recording-mib`: 16 GiB per file.
const MAX_RECORDING_LIMIT_MIB: u64 = 16 << 10;

/// A `--max-recording-mib` value: a whole number of MiB from 1 to 16384.
fn parse_recording_limit_mib(text: &str) -> Result<u64, String> {
    let shown = armhil::harness::elide_long_tokens(text);
    match text.trim().parse::<u64>() {
        Ok(mib) if (1..=MAX_RECORDING_LIMIT_MIB).contains(&mib) => Ok(mib),
        _ => Err(format!(
            "expected a whole number of MiB from 1 to {MAX_RECORDING_LIMIT_MIB}, got `{shown}`"
        )),
    }
}

/// A `--time-scale` factor: a number from 1 to [`MAX_TIME_SCALE`] (1000). Checked while the
/// arguments are parsed, so `1e300` is a usage error naming the option, not a panic when the
/// first deadline is scaled.
fn parse_time_scale(text: &str) -> Result<f64, String> {
    let shown = armhil::harness::elide_long_tokens(text);
    let factor: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("expected a number from 1 to {MAX_TIME_SCALE}, got `{shown}`"))?;
    if factor.is_finite() && (1.0..=MAX_TIME_SCALE).contains(&factor) {
        Ok(factor)
    } else {
        Err(format!(
            "must be from 1 to {MAX_TIME_SCALE} (a factor beyond that makes a one-hour deadline \
             longer than six weeks), got `{shown}`"
        ))
    }
}

/// A value parser whose error says what is wrong without echoing the value whole: clap's own
/// "invalid value '…'" repeats the raw argument, and a 300-digit number came back in full.
#[derive(Clone)]
struct Short<F>(F);

impl<T, F> clap::builder::TypedValueParser for Short<F>
where
    T: Clone + Send + Sync + 'static,
    F: Fn(&str) -> Result<T, String> + Clone + Send + Sync + 'static,
{
    type Value = T;

    fn parse_ref(
        &self,
        _cmd: &clap::Command,
        arg: Option<&clap::Arg>,
        value: &std::ffi::OsStr,
    ) -> Result<T, clap::Error> {
        let option = arg.map_or_else(String::new, |a| format!(" for '{a}'"));
        (self.0)(&value.to_string_lossy()).map_err(|why| {
            clap::Error::raw(
                clap::error::ErrorKind::ValueValidation,
                armhil::harness::elide_long_tokens(&format!("invalid value{option}: {why}\n")),
            )
        })
    }
}

/// `--deadline-slack-ms`: 0 to 600 000 (ten minutes, longer than any stall a slow VM shows).
fn parse_slack_ms(text: &str) -> Result<u64, String> {
    text.trim()
        .parse::<u64>()
        .ok()
        .filter(|ms| *ms <= 600_000)
        .ok_or_else(|| format!("expected milliseconds from 0 to 600000, got `{text}`"))
}

/// `K/N` with 1 <= K <= N.
fn parse_shard(text: &str) -> Result<(usize, usize), String> {
    let (k, n) = text
        .split_once('/')
        .ok_or_else(|| format!("expected K/N (e.g. 1/4), got `{text}`"))?;
    let k: usize = k.trim().parse().map_err(|_| format!("bad K in `{text}`"))?;
    let n: usize = n.trim().parse().map_err(|_| format!("bad N in `{text}`"))?;
    if n == 0 || k == 0 || k > n {
        return Err(format!("shard K/N needs 1 <= K <= N, got `{text}`"));
    }
    Ok((k, n))
}

/// The files of shard `k` of `n`: every n-th file starting at the k-th.
fn shard_of(files: Vec<SuiteFile>, shard: Option<(usize, usize)>) -> Vec<SuiteFile> {
    match shard {
        None => files,
        Some((k, n)) => files
            .into_iter()
            .enumerate()
            .filter(|(i, _)| i % n == k - 1)
            .map(|(_, f)| f)
            .collect(),
    }
}

/// Refuse a suite where two scenario files would write into one output folder.
fn check_out_dirs(files: &[SuiteFile]) -> anyhow::Result<()> {
    let mut seen: std::collections::BTreeMap<&Path, &Path> = std::collections::BTreeMap::new();
    for f in files {
        if let Some(other) = seen.insert(&f.out_dir, &f.path) {
            anyhow::bail!(
                "{} and {} would both write into {}/: name them through their folder instead",
                other.display(),
                f.path.display(),
                f.out_dir.display()
            );
        }
    }
    Ok(())
}

/// What one scenario produced.
struct Ran {
    result: ScenarioResult,
    written: Option<Written>,
    write_error: Option<String>,
}

/// Load, run and write one scenario.
fn run_one(file: &SuiteFile, args: &Args, interrupt: &Interrupt, loader: &mut SuiteLoader) -> Ran {
    let clock_for =
        |bench_iface: Option<&String>| match (args.bus.link(), args.realtime, bench_iface) {
            (Some(link), _, _) => Clock::Iface(link),
            (None, true, Some(iface)) => Clock::Iface(Link::SocketCan(iface.clone())),
            (None, true, None) => Clock::Realtime,
            (None, false, _) => Clock::Virtual,
        };
    let scenario = match loader.load(file) {
        Ok(s) => s,
        Err(e) => {
            let name = file.out_dir.to_string_lossy().into_owned();
            return Ran {
                result: ScenarioResult::not_run(
                    &name,
                    file.path.clone(),
                    Verdict::Error(e.to_string()),
                    "none",
                ),
                written: None,
                write_error: None,
            };
        }
    };
    let options = RunOptions {
        time_scale: args.time_scale,
        deadline_slack: std::time::Duration::from_millis(args.deadline_slack_ms),
        interrupt: interrupt.clone(),
        recording_limit_bytes: args.max_recording_mib << 20,
    };
    let result = run_scenario_with(
        &scenario,
        &clock_for(scenario.bench.interface.as_ref()),
        &options,
    );
    let mut ran = Ran {
        result,
        written: None,
        write_error: None,
    };
    if !matches!(ran.result.verdict, Verdict::Skipped(_)) {
        let dir = args.out.join(&file.out_dir);
        match write_outputs(&ran.result, &scenario.record, &dir) {
            Ok(w) => ran.written = Some(w),
            Err(e) => ran.write_error = Some(format!("writing outputs to {}: {e}", dir.display())),
        }
    }
    ran
}

/// Run `files` on `jobs` threads; results in file order whatever order they finish in. Once
/// `interrupt` fires no further file is started, so fewer results than files come back.
fn run_parallel(
    files: &[SuiteFile],
    args: &Args,
    jobs: usize,
    interrupt: &Interrupt,
    done: &(dyn Fn(&Ran) + Sync),
) -> Vec<Ran> {
    let next = std::sync::atomic::AtomicUsize::new(0);
    let slots: Vec<std::sync::Mutex<Option<Ran>>> =
        files.iter().map(|_| std::sync::Mutex::new(None)).collect();
    std::thread::scope(|scope| {
        for _ in 0..jobs.clamp(1, files.len().max(1)) {
            // One loader per worker: a file's matrix variants are parsed once per worker
            // that runs one of them, not once per variant.
            scope.spawn(|| {
                let mut loader = SuiteLoader::new();
                loop {
                    if interrupt.reason().is_some() {
                        break;
                    }
                    let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let Some(file) = files.get(i) else { break };
                    let ran = run_one(file, args, interrupt, &mut loader);
                    done(&ran);
                    *slots[i]
                        .lock()
                        .unwrap_or_else(std::sync::PoisonError::into_inner) = Some(ran);
                }
            });
        }
    });
    slots
        .into_iter()
        .filter_map(|s| {
            s.into_inner()
                .unwrap_or_else(std::sync::PoisonError::into_inner)
        })
        .collect()
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
    if let Some(s) = show(&w.html) {
        parts.push(format!("      report:    {s}"));
    }
    parts.join("\n")
}

/// Write `out/index.html`: every scenario of the run with its verdict and a link to its
/// report.html.
fn write_index(out: &Path, files: &[SuiteFile], ran: &[Ran]) -> Result<(), String> {
    let entries: Vec<IndexEntry<'_>> = files
        .iter()
        .zip(ran)
        .map(|(file, r)| IndexEntry {
            result: &r.result,
            report: r.written.as_ref().and_then(|w| w.html.as_ref()).map(|_| {
                let rel = file.out_dir.join("report.html");
                rel.to_string_lossy().replace('\\', "/")
            }),
        })
        .collect();
    let path = out.join("index.html");
    write_atomic(&path, index_html("armhil run", &entries).as_bytes())
        .map_err(|e| format!("writing {}: {e}", path.display()))
}

/// Run every scenario; exit 0 only when none failed and every output was written.
pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    // Also checked while parsing; kept for `Args` built in code.
    if parse_time_scale(&args.time_scale.to_string()).is_err() {
        anyhow::bail!("--time-scale must be a number from 1 to {MAX_TIME_SCALE}");
    }
    let all = discover_suite(&args.paths)?;
    if all.is_empty() {
        anyhow::bail!("no scenario files (*.yaml, *.yml) found");
    }
    check_out_dirs(&all)?;
    let files = shard_of(all, args.shard);
    let jobs = args
        .jobs
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
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
    let link = args.bus.link();
    if let Some(iface) = &link {
        print(&format!(
            "running on {iface} in real time against a separate emulator process: bus faults and emulator faults are unavailable; scenarios that use them are skipped"
        ));
    }
    let single = files.len() == 1;
    let done = |ran: &Ran| {
        print(&verdict_line(&ran.result));
        if ran.result.bus.recorder_missed > 0 {
            print(&format!(
                "      warning: the recorder missed {} frames; the recording is incomplete",
                ran.result.bus.recorder_missed
            ));
        }
        if let Some(omitted) = &ran.result.recording.omitted {
            print(&format!(
                "      note: {} (--max-recording-mib raises the limit)",
                omitted.describe()
            ));
        }
        if let Some(e) = &ran.write_error {
            print(&format!("      error {e}"));
        }
        if single {
            if let Some(w) = &ran.written {
                print(&where_written(w));
            }
        }
        if let Some(bar) = &progress {
            bar.inc(1);
        }
    };
    let (trigger, interrupt) = Interrupt::new();
    interrupt_on_signals(trigger)?;
    // The suite's own wall time: with several jobs the scenarios' times overlap, and their
    // sum (2.01 s for a 1.42 s process at -j 2) is no figure of how long it took.
    let suite_start = std::time::Instant::now();
    let ran = run_parallel(&files, &args, jobs, &interrupt, &done);
    let suite_wall = suite_start.elapsed();
    if let Some(bar) = progress {
        bar.finish_and_clear();
    }
    // Scenarios whose outputs failed, and the suite's index apart: one scenario and its index
    // under an `--out` that is a file is one scenario that could not write, not two.
    let write_errors = ran.iter().filter(|r| r.write_error.is_some()).count();
    let index_failed = match write_index(&args.out, &files, &ran) {
        Ok(()) => false,
        Err(e) => {
            println!("error {e}");
            true
        }
    };
    let results: Vec<ScenarioResult> = ran.into_iter().map(|r| r.result).collect();
    let count = |f: fn(&Verdict) -> bool| results.iter().filter(|r| f(&r.verdict)).count();
    let passed = count(|v| matches!(v, Verdict::Passed));
    let failed = count(|v| matches!(v, Verdict::Failed));
    let errors = count(|v| matches!(v, Verdict::Error(_)));
    let skipped = count(|v| matches!(v, Verdict::Skipped(_)));
    if files.len() > 1 {
        let scenario_time: Duration = results.iter().map(|r| r.duration).sum();
        println!(
            "{} scenarios: {passed} passed, {failed} failed, {errors} errors, {skipped} skipped ({} scenario time in {} wall, {jobs} jobs)",
            results.len(),
            secs(scenario_time),
            secs(suite_wall)
        );
        println!(
            "outputs: {}/<scenario path>/{{result.yaml, bus.log, bus.pcap or .pcapng, plot.svg, report.html}}, {}/index.html",
            args.out.display(),
            args.out.display()
        );
    }
    if write_errors > 0 {
        println!("{write_errors} scenario(s) could not write their outputs");
    }
    if index_failed {
        println!("the suite's index could not be written");
    }
    if let Some(path) = &args.junit {
        let xml = junit_xml("armhil", &results)?;
        write_atomic(path, xml.as_bytes()).map_err(|e| {
            anyhow::anyhow!("cannot write the JUnit report {}: {e}", path.display())
        })?;
        println!("junit: {}", path.display());
    }
    if let Some(reason) = interrupt.reason() {
        println!(
            "interrupted by {reason}: {} of {} scenario files not run",
            files.len() - results.len(),
            files.len()
        );
        // 128 + SIGINT, the shell's convention for a run stopped by the user.
        return Ok(ExitCode::from(130));
    }
    Ok(
        if failed == 0 && errors == 0 && write_errors == 0 && !index_failed {
            ExitCode::SUCCESS
        } else {
            ExitCode::FAILURE
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file(path: &str, out: &str) -> SuiteFile {
        SuiteFile {
            path: PathBuf::from(path),
            out_dir: PathBuf::from(out),
            variant: None,
        }
    }

    #[test]
    fn shards_partition_the_suite() {
        let files: Vec<SuiteFile> = (0..10)
            .map(|i| file(&format!("{i}.yaml"), &i.to_string()))
            .collect();
        let mut seen = Vec::new();
        for k in 1..=4 {
            seen.extend(shard_of(files.clone(), Some((k, 4))));
        }
        seen.sort_by(|a, b| a.path.cmp(&b.path));
        assert_eq!(seen, files);
        assert_eq!(parse_shard("2/4"), Ok((2, 4)));
        assert!(parse_shard("0/4").is_err());
        assert!(parse_shard("5/4").is_err());
        assert!(parse_shard("x").is_err());
    }

    #[test]
    fn recording_limit_is_a_bounded_whole_number_of_mib() {
        assert_eq!(parse_recording_limit_mib("64"), Ok(64));
        assert_eq!(parse_recording_limit_mib("1"), Ok(1));
        assert_eq!(parse_recording_limit_mib("16384"), Ok(16384));
        for bad in ["0", "16385", "-1", "1.5", "lots", "99999999999999999999999"] {
            let err = parse_recording_limit_mib(bad).unwrap_err();
            assert!(err.contains("from 1 to 16384"), "{bad}: {err}");
        }
    }

    #[test]
    fn time_scale_is_bounded_when_parsed() {
        assert_eq!(parse_time_scale("1"), Ok(1.0));
        assert_eq!(parse_time_scale("20"), Ok(20.0));
        assert_eq!(parse_time_scale("1000"), Ok(1000.0));
        for bad in ["1e300", "1000.5", "0.5", "0", "-3", "NaN", "inf", "x"] {
            let err = parse_time_scale(bad).unwrap_err();
            assert!(err.contains("from 1 to 1000"), "{bad}: {err}");
        }
        let digits = "9".repeat(300);
        let err = parse_time_scale(&digits).unwrap_err();
        assert!(err.len() < 200, "{err}");
    }

    #[test]
    fn option_errors_do_not_echo_huge_values() {
        use clap::Parser as _;
        #[derive(clap::Parser)]
        struct Cli {
            #[command(flatten)]
            args: Args,
        }
        let digits = format!("1{}", "0".repeat(300));
        for option in ["--time-scale", "--deadline-slack-ms", "--shard"] {
            let err = Cli::try_parse_from(["armhil", option, &digits, "x.yaml"])
                .err()
                .expect("refused")
                .to_string();
            assert!(err.contains(option), "{err}");
            assert!(err.len() < 300, "{option}: {err}");
        }
        let ok = Cli::try_parse_from(["armhil", "--deadline-slack-ms", "150", "x.yaml"]).unwrap();
        assert_eq!(ok.args.deadline_slack_ms, 150);
    }

    #[test]
    fn an_absurd_time_scale_is_a_usage_error_not_a_panic() {
        use clap::Parser as _;
        #[derive(clap::Parser)]
        struct Cli {
            #[command(flatten)]
            args: Args,
        }
        let err = Cli::try_parse_from(["armhil", "--realtime", "--time-scale", "1e300", "x.yaml"])
            .err()
            .expect("refused");
        assert_eq!(err.kind(), clap::error::ErrorKind::ValueValidation);
        assert!(err.to_string().contains("--time-scale"), "{err}");
        let ok = Cli::try_parse_from(["armhil", "--time-scale", "30", "x.yaml"]).expect("valid");
        assert_eq!(ok.args.time_scale, 30.0);
    }

    #[test]
    fn two_files_sharing_an_output_folder_are_refused() {
        let ok = [file("a/x.yaml", "a/x"), file("b/x.yaml", "b/x")];
        assert!(check_out_dirs(&ok).is_ok());
        let clash = [file("a/x.yaml", "x"), file("b/x.yaml", "x")];
        assert!(check_out_dirs(&clash).is_err());
    }
}
