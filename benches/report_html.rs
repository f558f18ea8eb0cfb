//! What report.html costs per scenario, printed (run: `cargo bench --bench report_html`):
//! for a few scenarios of the suite, the time to build the page (decoding the listed frames
//! included) next to the time the scenario itself took to run in virtual time, and the page's
//! size. `armhil run` and the scenario tests write one per scenario.

use std::path::Path;
use std::time::Instant;

use armhil::harness::report::report_html;
use armhil::harness::{load_scenario, run_scenario, Clock};

const SCENARIOS: [&str; 4] = [
    "scenarios/piper/fault_comm_loss.yaml",
    "scenarios/piper/bus_lossy_feedback.yaml",
    "scenarios/realman/fault_joint_error.yaml",
    "scenarios/robstride/csp_pendulum.yaml",
];

/// Pages built per scenario for the timing.
const ROUNDS: u32 = 20;

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    println!(
        "{:<44} {:>8} {:>10} {:>12} {:>10}",
        "scenario", "frames", "run (ms)", "report (ms)", "size (KB)"
    );
    for name in SCENARIOS {
        let path = root.join(name);
        let Ok(scenario) = load_scenario(&path) else {
            println!("{name:<44} (not found, skipped)");
            continue;
        };
        let started = Instant::now();
        let result = run_scenario(&scenario, &Clock::Virtual);
        let run_ms = started.elapsed().as_secs_f64() * 1e3;
        let started = Instant::now();
        let mut size = 0;
        for _ in 0..ROUNDS {
            size = report_html(&result).len();
        }
        let report_ms = started.elapsed().as_secs_f64() * 1e3 / f64::from(ROUNDS);
        println!(
            "{name:<44} {:>8} {run_ms:>10.1} {report_ms:>12.2} {:>10.1}",
            result.frames.len(),
            size as f64 / 1024.0
        );
    }
}
