//! Real-time lock of the Piper emulator, printed (run: `cargo bench --bench realtime_jitter`).
//!
//! The emulator runs in real time on a virtual bus (the runtime `armhil sim piper` runs on,
//! `sim::pacer::real_time_runtime`) for a few seconds, once idle and once with every core
//! loaded by a busy thread. For each run it prints the emulated steps per wall second (1000 when the clock
//! keeps up), late wake-ups, overruns, the clock task's wake-up period p50/p99/max (nominal
//! 1 ms or 5 ms: the pacer's own precision), and the send period p50/p99/max of 0x2A1 (200 Hz
//! arm status) and 0x2A5 (200 Hz joint feedback) — nominal 5 ms. "error" is p99 − nominal.
//! By default the emulator is paced as `sim::pacer` chooses (a kernel timer);
//! `ARMHIL_REALTIME_PRIORITY=1` measures with the runtime's workers at real-time priority,
//! `ARMHIL_PACER=kernel|thread|tokio` with another pacer.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread;
use std::time::Duration;

use bus::virtual_bus::{VirtualBus, VirtualBusConfig};
use bus::CanBus;
use sim::piper::{PiperConfig, PiperEmulator};
use sim::realtime::RealtimeStats;

/// Wall time per run.
const RUN: Duration = Duration::from_secs(4);

fn run_emulator(ticks_per_wake: u32) -> RealtimeStats {
    let runtime = sim::pacer::real_time_runtime().expect("a tokio runtime");
    runtime.block_on(async {
        let bus = VirtualBus::new(VirtualBusConfig::default());
        let emu_node = bus.attach("piper");
        let host = bus.attach("host");
        // A host that reads everything, as a driver would.
        let reader = tokio::spawn(async move { while host.recv().await.is_ok() {} });
        let emu = PiperEmulator::spawn(
            Arc::new(emu_node),
            PiperConfig {
                ticks_per_wake,
                ..PiperConfig::default()
            },
        )
        .expect("the emulator starts");
        tokio::time::sleep(RUN).await;
        let stats = emu.stats();
        emu.shutdown().await;
        reader.abort();
        stats
    })
}

/// Busy threads, one per core, until the returned flag is cleared.
fn load_cores() -> (Arc<AtomicBool>, Vec<thread::JoinHandle<()>>) {
    let run = Arc::new(AtomicBool::new(true));
    let cores = thread::available_parallelism().map_or(2, |n| n.get());
    let threads = (0..cores)
        .map(|_| {
            let run = Arc::clone(&run);
            thread::spawn(move || {
                let mut x = 0u64;
                while run.load(Ordering::Relaxed) {
                    x = std::hint::black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
                }
            })
        })
        .collect();
    (run, threads)
}

fn print(label: &str, s: &RealtimeStats, wake_period_ms: f64) {
    let ms = |d: Option<Duration>| d.map_or(f64::NAN, |d| d.as_secs_f64() * 1e3);
    println!(
        "{label}: {:.0} steps/s, {} late wake-ups, {} overruns ({} steps dropped)",
        s.steps as f64 / s.elapsed.as_secs_f64(),
        s.late_wakeups,
        s.overruns,
        s.skipped_steps
    );
    println!(
        "  wake-ups: period p50 {:.3} ms, p99 {:.3} ms (error {:+.3} ms), max {:.3} ms",
        ms(s.wake_period_p50),
        ms(s.wake_period_p99),
        ms(s.wake_period_p99) - wake_period_ms,
        ms(s.wake_period_max)
    );
    for id in [0x2A1, 0x2A5] {
        if let Some(i) = s.id(id) {
            println!(
                "  {id:#x}: {:.1} Hz, period p50 {:.3} ms, p99 {:.3} ms (error {:+.3} ms), max {:.3} ms",
                i.rate_hz,
                ms(i.period_p50),
                ms(i.period_p99),
                ms(i.period_p99) - 5.0,
                ms(i.period_max)
            );
        }
    }
}

fn main() {
    // `cargo test --benches` runs this binary too; only measure under `cargo bench`.
    if !std::env::args().any(|a| a == "--bench") {
        return;
    }
    for ticks_per_wake in [5, 1] {
        let idle = run_emulator(ticks_per_wake);
        let wake_ms = f64::from(ticks_per_wake);
        print(
            &format!("idle, {ticks_per_wake} steps/wake"),
            &idle,
            wake_ms,
        );
        let (flag, threads) = load_cores();
        let loaded = run_emulator(ticks_per_wake);
        flag.store(false, Ordering::Relaxed);
        for t in threads {
            let _ = t.join();
        }
        print(
            &format!("all cores busy, {ticks_per_wake} steps/wake"),
            &loaded,
            wake_ms,
        );
    }
}
