//! Piper emulator figures (prints them; no pass/fail):
//!
//! 1. Virtual-time speed: simulated seconds per wall second for a 10 s motion sequence on the
//!    virtual bus under a paused clock (current-thread runtime), host node draining every frame.
//! 2. Real-time cost: CPU % of one core (process user + system time from /proc/self/stat)
//!    while the emulator runs on the real clock for 5 s, streaming 3040 frames/s on the
//!    virtual bus to a draining host node. The figure includes the bus's wire task and the host.
//!
//! Run: `cargo bench -p armhil-sim --bench piper_emulator`.

use std::sync::Arc;
use std::time::{Duration, Instant as WallInstant};

use bus::virtual_bus::{VirtualBus, VirtualBusConfig, VirtualNode};
use bus::{BusError, CanBus, CanFrame};
use sim::piper::{FirmwareProfile, PiperConfig, PiperEmulator};

fn frame(id: u16, data: [u8; 8]) -> CanFrame {
    match CanFrame::standard(id, &data) {
        Ok(f) => f,
        Err(e) => panic!("bad bench frame: {e}"),
    }
}

fn joints(mdeg: [i32; 6]) -> [CanFrame; 3] {
    let pair = |id: u16, a: i32, b: i32| {
        let mut d = [0u8; 8];
        d[..4].copy_from_slice(&a.to_be_bytes());
        d[4..].copy_from_slice(&b.to_be_bytes());
        frame(id, d)
    };
    [
        pair(0x155, mdeg[0], mdeg[1]),
        pair(0x156, mdeg[2], mdeg[3]),
        pair(0x157, mdeg[4], mdeg[5]),
    ]
}

async fn send(host: &VirtualNode, f: CanFrame) {
    loop {
        match host.send(f).await {
            Ok(()) => return,
            Err(BusError::TxQueueFull { .. }) => {
                tokio::time::sleep(Duration::from_micros(200)).await
            }
            Err(e) => panic!("send failed: {e}"),
        }
    }
}

fn spawn_drain(host: VirtualNode) -> tokio::task::JoinHandle<u64> {
    tokio::spawn(async move {
        let mut n = 0u64;
        while host.recv().await.is_ok() {
            n += 1;
        }
        n
    })
}

fn start(
    ticks_per_wake: u32,
) -> (
    VirtualBus,
    VirtualNode,
    VirtualNode,
    sim::piper::PiperHandle,
) {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let emu_node = bus.attach("piper");
    let host = bus.attach("host");
    let drain = bus.attach("drain");
    let emu = match PiperEmulator::spawn(
        Arc::new(emu_node),
        PiperConfig {
            firmware: FirmwareProfile::V1_8_2,
            initial_joints_rad: [0.0, 0.5, -0.5, 0.0, 0.0, 0.0],
            ticks_per_wake,
            ..PiperConfig::default()
        },
    ) {
        Ok(e) => e,
        Err(e) => panic!("emulator did not start: {e}"),
    };
    (bus, host, drain, emu)
}

/// A 10 s sequence: enable, MOVE J at 80 % through four targets, 200 Hz command stream.
async fn motion_sequence(host: &VirtualNode) {
    send(host, frame(0x471, [7, 2, 0, 0, 0, 0, 0, 0])).await;
    let targets = [
        [60_000, 60_000, -60_000, 30_000, 40_000, 90_000],
        [-60_000, 90_000, -90_000, -30_000, -40_000, -90_000],
        [30_000, 40_000, -30_000, 0, 20_000, 0],
        [0, 28_648, -28_648, 0, 0, 0],
    ];
    let start = tokio::time::Instant::now();
    let mut tick = tokio::time::interval(Duration::from_millis(5));
    while start.elapsed() < Duration::from_secs(10) {
        tick.tick().await;
        let k = (start.elapsed().as_secs_f64() / 2.5) as usize;
        send(host, frame(0x151, [1, 1, 80, 0, 0, 0, 0, 0])).await;
        for f in joints(targets[k.min(3)]) {
            send(host, f).await;
        }
    }
}

fn virtual_speed(ticks_per_wake: u32) {
    let runtime = match tokio::runtime::Builder::new_current_thread()
        .enable_time()
        .start_paused(true)
        .build()
    {
        Ok(r) => r,
        Err(e) => panic!("runtime: {e}"),
    };
    let wall = WallInstant::now();
    let (frames, simulated) = runtime.block_on(async {
        let (bus, host, drain, emu) = start(ticks_per_wake);
        let counter = spawn_drain(drain);
        let t0 = tokio::time::Instant::now();
        motion_sequence(&host).await;
        let simulated = t0.elapsed();
        let frames = bus.stats().frames;
        emu.shutdown().await;
        counter.abort();
        (frames, simulated)
    });
    let wall = wall.elapsed();
    println!(
        "piper virtual time, {} tick(s) per wake: {:.2} s simulated in {:.3} s wall = {:.1}x real time ({} frames on the bus)",
        ticks_per_wake,
        simulated.as_secs_f64(),
        wall.as_secs_f64(),
        simulated.as_secs_f64() / wall.as_secs_f64(),
        frames
    );
}

/// Process CPU time (user + system) from /proc/self/stat, s.
fn process_cpu_s() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command name, which is in parentheses and may contain spaces.
    let rest = stat.rsplit_once(')')?.1;
    let fields: Vec<&str> = rest.split_whitespace().collect();
    // utime and stime are fields 14 and 15 of the full line: 12th and 13th after ')'.
    let utime: f64 = fields.get(11)?.parse().ok()?;
    let stime: f64 = fields.get(12)?.parse().ok()?;
    // USER_HZ is 100 on every Linux ABI in practice.
    Some((utime + stime) / 100.0)
}

fn real_time_cpu(ticks_per_wake: u32) {
    let runtime = match tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
    {
        Ok(r) => r,
        Err(e) => panic!("runtime: {e}"),
    };
    runtime.block_on(async {
        let (bus, _host, drain, emu) = start(ticks_per_wake);
        let counter = spawn_drain(drain);
        // Let start-up (URDF load, inertia probe) finish before measuring.
        tokio::time::sleep(Duration::from_millis(500)).await;
        let before_stats = bus.stats();
        let cpu0 = process_cpu_s();
        let wall = WallInstant::now();
        tokio::time::sleep(Duration::from_secs(5)).await;
        let wall = wall.elapsed().as_secs_f64();
        let cpu1 = process_cpu_s();
        let after_stats = bus.stats();
        let frames = after_stats.frames.saturating_sub(before_stats.frames);
        match (cpu0, cpu1) {
            (Some(a), Some(b)) => println!(
                "piper real time, {} tick(s) per wake: {:.0} frames/s on the virtual bus, process CPU {:.1} % of one core over {:.1} s",
                ticks_per_wake,
                frames as f64 / wall,
                (b - a) / wall * 100.0,
                wall
            ),
            _ => println!("piper real time: /proc/self/stat unavailable, CPU not measured"),
        }
        emu.shutdown().await;
        counter.abort();
    });
}

/// The synchronous core alone (physics + firmware + frame encoding), no bus, no runtime.
fn core_alone() {
    let mut fw = match sim::piper::Firmware::new(PiperConfig {
        firmware: FirmwareProfile::V1_8_2,
        initial_joints_rad: [0.0, 0.5, -0.5, 0.0, 0.0, 0.0],
        ..PiperConfig::default()
    }) {
        Ok(f) => f,
        Err(e) => panic!("firmware: {e}"),
    };
    fw.handle_frame(&frame(0x471, [7, 2, 0, 0, 0, 0, 0, 0]));
    fw.handle_frame(&frame(0x151, [1, 1, 80, 0, 0, 0, 0, 0]));
    for f in joints([60_000, 60_000, -60_000, 30_000, 40_000, 90_000]) {
        fw.handle_frame(&f);
    }
    let mut out = Vec::new();
    let ticks = 10_000;
    let wall = WallInstant::now();
    for _ in 0..ticks {
        fw.tick();
        fw.drain_output_into(&mut out);
        out.clear();
    }
    let per_tick = wall.elapsed().as_secs_f64() / f64::from(ticks);
    println!(
        "piper core alone: {:.1} µs per 1 ms tick = {:.0}x real time",
        per_tick * 1e6,
        1e-3 / per_tick
    );
}

/// A bus that accepts every frame and never delivers one: isolates the emulator's own cost.
struct NullBus;

#[async_trait::async_trait]
impl CanBus for NullBus {
    async fn send(&self, _frame: CanFrame) -> Result<(), BusError> {
        Ok(())
    }
    async fn recv(&self) -> Result<bus::ReceivedFrame, BusError> {
        std::future::pending().await
    }
    async fn close(&self) {}
    fn name(&self) -> &str {
        "null"
    }
}

fn real_time_cpu_null_bus(ticks_per_wake: u32) {
    let runtime = match tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
    {
        Ok(r) => r,
        Err(e) => panic!("runtime: {e}"),
    };
    runtime.block_on(async {
        let config = PiperConfig {
            ticks_per_wake,
            ..PiperConfig::default()
        };
        let emu = match PiperEmulator::spawn(Arc::new(NullBus), config) {
            Ok(e) => e,
            Err(e) => panic!("emulator did not start: {e}"),
        };
        tokio::time::sleep(Duration::from_millis(500)).await;
        let t0 = emu.snapshot().time_s;
        let cpu0 = process_cpu_s();
        let wall = WallInstant::now();
        tokio::time::sleep(Duration::from_secs(5)).await;
        let wall = wall.elapsed().as_secs_f64();
        let cpu1 = process_cpu_s();
        let simulated = emu.snapshot().time_s - t0;
        if let (Some(a), Some(b)) = (cpu0, cpu1) {
            println!(
                "piper real time, emulator alone (null bus), {} tick(s) per wake: CPU {:.1} % of one core, {:.2} s simulated in {:.2} s",
                ticks_per_wake,
                (b - a) / wall * 100.0,
                simulated,
                wall
            );
        }
        emu.shutdown().await;
    });
}

fn main() {
    core_alone();
    virtual_speed(1);
    virtual_speed(5);
    for ticks_per_wake in [1, 5] {
        real_time_cpu(ticks_per_wake);
        real_time_cpu_null_bus(ticks_per_wake);
    }
}
