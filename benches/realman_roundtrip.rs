//! Realman figures, printed (run: `cargo bench --bench realman_roundtrip`):
//!
//! 1. Command round trips per second on loopback TCP against the emulator: our driver
//!    (`get_joint_degree` back to back) and, against the same emulator, the vendor's Python SDK
//!    (`rm_get_joint_degree` in a loop, in a `python3` subprocess; skipped when the SDK is not
//!    installed), and their ratio (target ≥ 10×).
//! 2. CPU of the UDP realtime push at cycle 1 (5 ms, 200 datagrams/s): the process's CPU time
//!    over a few seconds of real time with the push on, minus the same with it off, as % of
//!    one core (target < 2 %); also with the driver decoding every datagram.
//! 3. Speed of a Realman session in virtual time (paused tokio clock, in-memory streams):
//!    simulated seconds per wall second (target ≥ 30×).

use std::net::{Ipv4Addr, SocketAddr};
use std::process::Command;
use std::time::{Duration, Instant};

use driver::realman::{
    ClientConfig, Connect, JointSpeedUnit, MoveOpts, Pose, PushCustom, PushSettings, RealmanClient,
    StateFeed,
};
use sim::realman::model::ArmModel;
use sim::realman::{
    kinematics, ControllerConfig, EmulatorConfig, RealmanEmulator, RealmanHandle, Transport,
};
use tokio::runtime::Runtime;

/// Driver round trips measured (after a warm-up).
const DRIVER_CALLS: u32 = 20_000;
/// How long the SDK loops, s.
const SDK_SECONDS: f64 = 5.0;
/// Real time per push measurement, s.
const CPU_SECONDS: u64 = 6;

/// The vendor SDK loop: connect (11-query handshake), then `rm_get_joint_degree` for a while;
/// prints `RATE <calls/s> <calls> <failures>`.
const SDK_SCRIPT: &str = r#"
import sys, time
try:
    from Robotic_Arm.rm_robot_interface import RoboticArm, rm_thread_mode_e
except ImportError as e:
    print("NOSDK", e)
    sys.exit(0)
port, secs = int(sys.argv[1]), float(sys.argv[2])
robot = RoboticArm(rm_thread_mode_e.RM_SINGLE_MODE_E)
handle = robot.rm_create_robot_arm("127.0.0.1", port)
if handle.id < 1:
    print("ERROR handshake failed")
    sys.exit(2)
for _ in range(50):
    robot.rm_get_joint_degree()
calls = failures = 0
start = time.perf_counter()
while time.perf_counter() - start < secs:
    ret, _ = robot.rm_get_joint_degree()
    failures += ret != 0
    calls += 1
elapsed = time.perf_counter() - start
print(f"RATE {calls / elapsed:.1f} {calls} {failures}", flush=True)
robot.rm_delete_robot_arm()
"#;

fn emulator_config() -> EmulatorConfig {
    EmulatorConfig::new(ControllerConfig::new(ArmModel::rm65b()))
}

fn push(port: u16, enable: bool) -> PushSettings {
    PushSettings {
        period_ms: 5,
        enable,
        port,
        ip: Ipv4Addr::LOCALHOST,
        force_coordinate: None,
        custom: PushCustom::default(),
    }
}

/// CPU time of this process so far: the sum of its threads' run time (ns) from
/// `/proc/self/task/*/schedstat`, else utime + stime from `/proc/self/stat` (clock ticks).
fn process_cpu() -> Option<Duration> {
    let mut total_ns = 0u64;
    let mut found = false;
    for task in std::fs::read_dir("/proc/self/task").ok()?.flatten() {
        let text = std::fs::read_to_string(task.path().join("schedstat")).ok();
        if let Some(ns) = text.and_then(|t| t.split_whitespace().next()?.parse::<u64>().ok()) {
            total_ns += ns;
            found = true;
        }
    }
    if found {
        return Some(Duration::from_nanos(total_ns));
    }
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command name (which may contain spaces) start at the last ')'.
    let rest = &stat[stat.rfind(')')? + 2..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks: u64 = fields.get(11)?.parse::<u64>().ok()? + fields.get(12)?.parse::<u64>().ok()?;
    // USER_HZ is 100 on Linux.
    Some(Duration::from_millis(ticks * 10))
}

fn driver_round_trips(rt: &Runtime, addr: &str) -> f64 {
    rt.block_on(async {
        let arm = RealmanClient::connect(addr, ClientConfig::default())
            .await
            .expect("driver connects");
        for _ in 0..500 {
            arm.joint_positions().await.expect("warm-up");
        }
        let start = Instant::now();
        for _ in 0..DRIVER_CALLS {
            arm.joint_positions().await.expect("get_joint_degree");
        }
        let elapsed = start.elapsed();
        let rate = f64::from(DRIVER_CALLS) / elapsed.as_secs_f64();
        println!(
            "driver: {DRIVER_CALLS} get_joint_degree round trips in {elapsed:.2?} = {rate:.0}/s ({:.1} µs each)",
            elapsed.as_secs_f64() * 1e6 / f64::from(DRIVER_CALLS)
        );
        rate
    })
}

/// The SDK's rate, or `None` (with the reason printed) if it could not run.
fn sdk_round_trips(port: u16) -> Option<f64> {
    let output = Command::new("python3")
        .args([
            "-c",
            SDK_SCRIPT,
            &port.to_string(),
            &SDK_SECONDS.to_string(),
        ])
        .output();
    let output = match output {
        Ok(o) => o,
        Err(e) => {
            println!("vendor SDK: skipped, python3 cannot run: {e}");
            return None;
        }
    };
    let stdout = String::from_utf8_lossy(&output.stdout);
    for line in stdout.lines() {
        if let Some(rest) = line.strip_prefix("RATE ") {
            let parts: Vec<&str> = rest.split_whitespace().collect();
            let rate: f64 = parts.first()?.parse().ok()?;
            println!(
                "vendor SDK 1.1.6 (python3): {} rm_get_joint_degree calls in {SDK_SECONDS} s = {rate:.0}/s, {} failed",
                parts.get(1).unwrap_or(&"?"),
                parts.get(2).unwrap_or(&"?")
            );
            return Some(rate);
        }
        if line.starts_with("NOSDK") {
            println!("vendor SDK: not installed (pip install Robotic_Arm==1.1.6); skipped");
            return None;
        }
    }
    println!(
        "vendor SDK: no rate reported (exit {:?}): {} {}",
        output.status.code(),
        stdout.trim(),
        String::from_utf8_lossy(&output.stderr).trim()
    );
    None
}

/// CPU used by the whole process over `CPU_SECONDS` of real time, % of one core.
/// (The runtime's worker threads run the emulator meanwhile; this thread only sleeps.)
fn cpu_percent_over_window() -> f64 {
    std::thread::sleep(Duration::from_millis(300));
    let (cpu0, wall0) = (process_cpu().expect("/proc readable"), Instant::now());
    std::thread::sleep(Duration::from_secs(CPU_SECONDS));
    let cpu = process_cpu().expect("/proc readable") - cpu0;
    100.0 * cpu.as_secs_f64() / wall0.elapsed().as_secs_f64()
}

fn push_cpu(rt: &Runtime, emu: &RealmanHandle) {
    let addr = emu.local_addr().expect("TCP").to_string();
    let (arm, counter) = rt.block_on(async {
        let arm = RealmanClient::connect(&addr, ClientConfig::default())
            .await
            .expect("driver connects");
        // A plain receiver that only counts: the cost of the push itself.
        let socket = tokio::net::UdpSocket::bind("127.0.0.1:0")
            .await
            .expect("bind");
        let port = socket.local_addr().expect("addr").port();
        let counter = std::sync::Arc::new(std::sync::atomic::AtomicU64::new(0));
        let c = counter.clone();
        tokio::spawn(async move {
            let mut buf = vec![0u8; 65_536];
            while socket.recv(&mut buf).await.is_ok() {
                c.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            }
        });
        arm.set_realtime_push(&push(port, false))
            .await
            .expect("push off");
        (arm, (counter, port))
    });
    let (counter, port) = counter;
    let off = cpu_percent_over_window();
    rt.block_on(arm.set_realtime_push(&push(port, true)))
        .expect("push on");
    let before = counter.load(std::sync::atomic::Ordering::Relaxed);
    let on = cpu_percent_over_window();
    let got = counter.load(std::sync::atomic::Ordering::Relaxed) - before;
    let feed = rt.block_on(async {
        let feed = StateFeed::bind("127.0.0.1:0", JointSpeedUnit::default())
            .await
            .expect("bind");
        let port = feed.local_addr().expect("addr").port();
        arm.set_realtime_push(&push(port, true))
            .await
            .expect("push to feed");
        feed
    });
    let decoded = cpu_percent_over_window();
    println!(
        "push CPU (cycle 1, 5 ms): emulator idle with push off {off:.2} % of a core, push on {on:.2} % \
         ({got} datagrams sent in ~{CPU_SECONDS} s = {:.0}/s), with the driver decoding {decoded:.2} %",
        got as f64 / (CPU_SECONDS as f64 + 0.3),
    );
    println!(
        "push CPU: the push itself costs {:.2} % of one core (target < 2 %); push + driver decode {:.2} %",
        on - off,
        decoded - off
    );
    drop(feed);
}

/// A scripted session in virtual time; returns simulated and wall time.
async fn virtual_session(ticks_per_wake: u32) -> (Duration, Duration) {
    let wall = Instant::now();
    let start = tokio::time::Instant::now();
    let mut config = emulator_config();
    config.ticks_per_wake = ticks_per_wake;
    let emu = RealmanEmulator::spawn(config, Transport::InMemory)
        .await
        .expect("emulator starts");
    let mut datagrams = emu.take_datagrams().expect("datagrams");
    let (tx, rx) = tokio::sync::mpsc::channel(1024);
    tokio::spawn(async move {
        while let Some(d) = datagrams.recv().await {
            if tx.send(d.payload.into_bytes()).await.is_err() {
                break;
            }
        }
    });
    let feed = StateFeed::from_channel(rx, JointSpeedUnit::default());
    let stream = emu
        .connect(std::net::IpAddr::V4(Ipv4Addr::new(192, 168, 1, 10)))
        .expect("connect");
    let arm = RealmanClient::from_stream(stream, ClientConfig::default()).await;
    arm.handshake().await.expect("handshake");
    let rad = |d: [f64; 6]| d.map(f64::to_radians);
    let model = ArmModel::rm65b();
    for round in 0..3 {
        let spread = 10.0 * f64::from(round);
        arm.movej(
            &rad([10.0 + spread, 20.0, 30.0, 40.0, 50.0, 60.0]),
            MoveOpts::speed(30),
            true,
        )
        .await
        .expect("movej");
        let aim = kinematics::forward(&model, &rad([20.0 + spread, 25.0, 40.0, 30.0, 45.0, 50.0]));
        let pose = Pose {
            position_m: aim.position_m,
            euler_rad: aim.euler_rad,
        };
        arm.movel(&pose, MoveOpts::speed(30), true)
            .await
            .expect("movel");
        let queued = MoveOpts {
            speed_percent: 40,
            blend_percent: 30,
            connect: Connect::Queue,
        };
        arm.movej(&rad([0.0, 10.0, 20.0, 0.0, 30.0, 0.0]), queued, true)
            .await
            .expect("queued");
        arm.movej(
            &[0.0; 6],
            MoveOpts {
                connect: Connect::Start,
                ..queued
            },
            true,
        )
        .await
        .expect("group");
        arm.gripper_position(300, true).await.expect("gripper");
        arm.gripper_release(1000, true).await.expect("release");
        for _ in 0..50 {
            arm.joint_positions().await.expect("query");
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
    }
    assert!(feed.latest().is_some(), "the push reached the driver");
    emu.shutdown().await;
    (start.elapsed(), wall.elapsed())
}

fn main() {
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .expect("runtime");
    let emu = rt
        .block_on(RealmanEmulator::spawn(
            emulator_config(),
            Transport::Tcp(SocketAddr::from((Ipv4Addr::LOCALHOST, 0))),
        ))
        .expect("emulator listens");
    let addr = emu.local_addr().expect("TCP address");

    println!("== command round trips on loopback TCP (emulator at {addr}) ==");
    let driver = driver_round_trips(&rt, &addr.to_string());
    match sdk_round_trips(addr.port()) {
        Some(sdk) if sdk > 0.0 => println!("driver / SDK = {:.1}× (target ≥ 10×)", driver / sdk),
        _ => println!("driver / SDK: no SDK figure"),
    }

    println!("== UDP push CPU, real time ==");
    push_cpu(&rt, &emu);
    rt.block_on(emu.shutdown());
    drop(rt);

    println!("== virtual time ==");
    let paused = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .start_paused(true)
        .build()
        .expect("paused runtime");
    // 1 physics step per wake-up is the default; the emulator can run up to 10 per wake-up
    // (less timer overhead, replies up to that many ms later).
    for ticks in [1, 5] {
        let (simulated, wall) = paused.block_on(virtual_session(ticks));
        println!(
            "virtual-time session ({ticks} ms per wake-up): {simulated:.2?} simulated in {wall:.2?} wall = {:.1}× real time (target ≥ 30×)",
            simulated.as_secs_f64() / wall.as_secs_f64()
        );
    }
}
