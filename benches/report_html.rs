//! What report.html costs, printed (run: `cargo bench --bench report_html`): every scenario of
//! `scenarios/` is run in virtual time, then its report is built; the figures are the total
//! run time, the total report time (decoding the listed frames included), the largest
//! reports and the total size. `armhil run` and the scenario tests write one per scenario.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use armhil::harness::report::report_html;
use armhil::harness::{discover_suite, load_suite_file, run_scenario, Clock};

fn main() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    let files = match discover_suite(&[root]) {
        Ok(f) => f,
        Err(e) => {
            println!("cannot list the scenarios: {e}");
            return;
        }
    };
    let (mut run, mut report, mut bytes) = (Duration::ZERO, Duration::ZERO, 0usize);
    let mut rows = Vec::new();
    for file in &files {
        let Ok(scenario) = load_suite_file(file) else {
            continue;
        };
        let started = Instant::now();
        let result = run_scenario(&scenario, &Clock::Virtual);
        let ran = started.elapsed();
        let started = Instant::now();
        let html = report_html(&result);
        let built = started.elapsed();
        run += ran;
        report += built;
        bytes += html.len();
        rows.push((built, ran, html.len(), result.bus.frames, result.name));
    }
    rows.sort_by_key(|r| std::cmp::Reverse(r.0));
    println!(
        "{:<40} {:>8} {:>10} {:>12} {:>10}",
        "slowest reports", "frames", "run (ms)", "report (ms)", "size (KB)"
    );
    for (built, ran, size, frames, name) in rows.iter().take(5) {
        println!(
            "{name:<40} {frames:>8} {:>10.1} {:>12.2} {:>10.1}",
            ran.as_secs_f64() * 1e3,
            built.as_secs_f64() * 1e3,
            *size as f64 / 1024.0
        );
    }
    println!(
        "{} scenarios: run {:.2} s, reports {:.2} s (+{:.1} %), {:.1} MB of HTML ({:.0} KB each on average)",
        rows.len(),
        run.as_secs_f64(),
        report.as_secs_f64(),
        100.0 * report.as_secs_f64() / run.as_secs_f64().max(1e-9),
        bytes as f64 / 1e6,
        bytes as f64 / 1024.0 / rows.len().max(1) as f64
    );
}
