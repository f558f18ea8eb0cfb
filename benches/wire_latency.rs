//! The wire's timing as a host sees it, in real time, against the `armhil` binary itself:
//!
//! - `sim robot robots/humanoid.yaml --socketcand`: a host on the four channels sends the 20
//!   actuators 2,000 operation-control commands a second and times each answer from its send
//!   (p50, p99, max, share answered), in two patterns: **burst** (each bus's five commands at
//!   once every 10 ms, as a 100 Hz control loop does; the five commands and five answers then
//!   queue on the 1 Mbit/s wire, which sets a floor of about 1 ms on the median) and
//!   **spaced** (one command every 2 ms on each bus: one request and its answer alone on the
//!   wire, the firmware's turnaround as the host sees it);
//! - the burst again with 118 more socketcand clients on can0 that never read (their frames
//!   are theirs to lose; the others' answers must all come);
//! - one socketcand client pings another through the bus (client-to-client echo);
//! - CPU of the emulator process (% of one core, from /proc) at rest and under that load, and
//!   at rest for `sim robstride` (five motors) and `sim realman`;
//! - Damiao: `sim damiao --motor 1:DM4310` and `sim robot robots/openarm.yaml` over socketcand,
//!   a host sending enabled motors a zero-gain MIT command (a pure status exchange) and timing
//!   each feedback from its send: one request alone on the wire every 2 ms (the firmware's
//!   turnaround as the host sees it), on both OpenArm buses at once; CPU at rest and under it.
//!
//! Prints figures; judges nothing. Run: `cargo bench --bench wire_latency` (Linux).

use std::collections::{HashMap, VecDeque};
use std::net::TcpListener;
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use bus::socketcand::SocketcandBus;
use bus::{BusError, CanBus, CanFrame};

const HOST_ID: u32 = 0xFD;
const LOAD_SECONDS: u64 = 10;
const IDLE_SECONDS: u64 = 5;
const PINGS: usize = 2_000;

/// The humanoid's buses and actuator ids (robots/humanoid.yaml).
const BUSES: [(&str, [u8; 5]); 4] = [
    ("can0", [11, 12, 13, 14, 15]),
    ("can1", [21, 22, 23, 24, 25]),
    ("can2", [31, 32, 33, 34, 35]),
    ("can3", [41, 42, 43, 44, 45]),
];

fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .expect("a free port")
}

/// The emulator process, killed when dropped.
struct Emulator {
    child: Child,
}

impl Drop for Emulator {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn start(args: &[&str]) -> Emulator {
    let child = Command::new(env!("CARGO_BIN_EXE_armhil"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("armhil starts");
    Emulator { child }
}

fn wait_for_port(port: u16) {
    let deadline = Instant::now() + Duration::from_secs(60);
    while Instant::now() < deadline {
        if std::net::TcpStream::connect(("127.0.0.1", port)).is_ok() {
            return;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    panic!("nothing listens on port {port}");
}

/// CPU time (user + system) of a process so far.
fn cpu_time(pid: u32) -> Duration {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap_or_default();
    // Fields after the parenthesised command name; utime and stime are the 14th and 15th.
    let after = stat.rsplit(')').next().unwrap_or("");
    let fields: Vec<&str> = after.split_whitespace().collect();
    let ticks: u64 = fields
        .get(11..13)
        .map(|f| f.iter().filter_map(|v| v.parse::<u64>().ok()).sum())
        .unwrap_or(0);
    // SAFETY: sysconf with a constant name.
    #[allow(unsafe_code)]
    let per_second = unsafe { libc::sysconf(libc::_SC_CLK_TCK) }.max(1) as u64;
    Duration::from_nanos(ticks * 1_000_000_000 / per_second)
}

/// Percent of one core the process used over `during`.
fn cpu_percent(pid: u32, during: impl FnOnce()) -> f64 {
    let (cpu0, wall0) = (cpu_time(pid), Instant::now());
    during();
    let (cpu1, wall1) = (cpu_time(pid), Instant::now());
    100.0 * (cpu1 - cpu0).as_secs_f64() / (wall1 - wall0).as_secs_f64()
}

fn op_command(motor: u8) -> CanFrame {
    // Type 1 with zero torque, p = v = 0, kp = kd = 0: a pure status exchange.
    let id = (1 << 24) | (0x7FFF << 8) | u32::from(motor);
    CanFrame::extended(id, &[0x7F, 0xFF, 0x7F, 0xFF, 0, 0, 0, 0]).expect("valid frame")
}

/// A zero-gain MIT command to Damiao motor `esc_id` (a DM4310's ranges), packed by our
/// driver's codec: the motor answers with its feedback and applies no torque.
fn damiao_status_command(esc_id: u16) -> CanFrame {
    use driver::damiao::{codec, MitCommand, Model, RangeTable};
    let ranges = Model::parse("DM4310")
        .expect("a model the driver knows")
        .ranges(RangeTable::Current);
    codec::mit(esc_id, &MitCommand::default(), &ranges).expect("a frame")
}

/// On each `(channel, motor ids)` at once: enable the motors, then one zero-gain MIT command
/// every 2 ms, the motors in turn, for `LOAD_SECONDS`; the latency of each feedback (on
/// ESC_ID + 0x10) from its send, and how many were sent.
async fn damiao_round_trips(addr: &str, buses: &[(&str, &[u16])]) -> (Vec<Duration>, u64, u64) {
    let mut channels = Vec::new();
    for &(name, ids) in buses {
        let bus = SocketcandBus::connect(addr, name)
            .await
            .expect("channel opens");
        for &id in ids {
            let enable = driver::damiao::codec::special(id, driver::damiao::codec::special::ENABLE)
                .expect("a frame");
            send(&bus, enable).await;
        }
        // The enables' feedback, before the timed exchanges.
        tokio::time::sleep(Duration::from_millis(100)).await;
        while let Ok(Ok(_)) = tokio::time::timeout(Duration::from_millis(5), bus.recv()).await {}
        channels.push((Arc::new(bus) as Arc<dyn CanBus>, ids.to_vec()));
    }
    let exchange = Exchange {
        period: Duration::from_millis(2),
        per_tick: 1,
        command: damiao_status_command,
        answering_motor: |id| (0x10..0x30).contains(&id).then(|| (id - 0x10) as u16),
    };
    timed_exchanges(channels, exchange).await
}

/// Start `sim ARGS --socketcand` on a free port, measure its CPU at rest and under
/// [`damiao_round_trips`] on `buses`, and print both.
fn damiao_figures(
    runtime: &tokio::runtime::Runtime,
    label: &str,
    args: &[&str],
    buses: &[(&str, &[u16])],
) {
    let port = free_port();
    let addr = format!("127.0.0.1:{port}");
    let mut command = vec!["sim"];
    command.extend(args.iter().copied());
    command.extend(["--socketcand", &addr]);
    let emulator = start(&command);
    wait_for_port(port);
    std::thread::sleep(Duration::from_secs(1));
    let pid = emulator.child.id();
    let idle = cpu_percent(pid, || {
        std::thread::sleep(Duration::from_secs(IDLE_SECONDS))
    });
    let mut trips = None;
    let loaded = cpu_percent(pid, || {
        trips = Some(runtime.block_on(damiao_round_trips(&addr, buses)));
    });
    println!("{label} over socketcand, real time:");
    print_latencies(
        "MIT status exchange, 1 per bus every 2 ms",
        trips.as_ref().expect("ran"),
    );
    println!("  CPU: {idle:.1} % of a core at rest, {loaded:.1} % under the exchanges");
}

fn percentile(sorted: &[Duration], p: f64) -> Duration {
    if sorted.is_empty() {
        return Duration::ZERO;
    }
    let index = ((sorted.len() - 1) as f64 * p).round() as usize;
    sorted[index]
}

fn ms(d: Duration) -> String {
    format!("{:.3} ms", d.as_secs_f64() * 1e3)
}

async fn send(bus: &dyn CanBus, frame: CanFrame) {
    loop {
        match bus.send(frame).await {
            Ok(()) => return,
            Err(BusError::TxQueueFull { .. }) => tokio::task::yield_now().await,
            Err(error) => panic!("send failed: {error}"),
        }
    }
}

/// How the host spreads its 2,000 commands a second.
#[derive(Clone, Copy)]
enum Pattern {
    /// Each bus's five commands at once every 10 ms.
    Burst,
    /// One command every 2 ms on each bus, the motors in turn.
    Spaced,
}

/// 2,000 commands/s over the four channels; the answers' latencies and how many came.
async fn commands_under_load(addr: &str, pattern: Pattern) -> (Vec<Duration>, u64, u64) {
    let mut channels = Vec::new();
    for (name, ids) in BUSES {
        let bus = SocketcandBus::connect(addr, name)
            .await
            .expect("channel opens");
        channels.push((
            Arc::new(bus) as Arc<dyn CanBus>,
            ids.iter().copied().map(u16::from).collect(),
        ));
    }
    let (period, per_tick) = match pattern {
        Pattern::Burst => (Duration::from_millis(10), BUSES[0].1.len()),
        Pattern::Spaced => (Duration::from_millis(2), 1),
    };
    let exchange = Exchange {
        period,
        per_tick,
        command: |motor| op_command(motor as u8),
        // A type-2 status frame to our host id names the motor in bits 15..8.
        answering_motor: |id| {
            ((id >> 24) & 0x1F == 2 && id & 0xFF == HOST_ID).then_some(((id >> 8) & 0x7F) as u16)
        },
    };
    timed_exchanges(channels, exchange).await
}

/// How a host exchanges frames with a bus's motors in [`timed_exchanges`].
#[derive(Clone, Copy)]
struct Exchange {
    /// Time between ticks.
    period: Duration,
    /// Commands sent at each tick, to the motors in turn.
    per_tick: usize,
    /// The command to a motor.
    command: fn(u16) -> CanFrame,
    /// The motor a received frame answers for, if it is an answer.
    answering_motor: fn(u32) -> Option<u16>,
}

/// On every channel at once for `LOAD_SECONDS`: `per_tick` commands each `period`, the motors
/// in turn, each answer timed from its command's send; the latencies (sorted), how many
/// answers and how many commands. A motor answers in order, so an answer is its oldest
/// unanswered command's (a late answer is never paired with a later command).
async fn timed_exchanges(
    channels: Vec<(Arc<dyn CanBus>, Vec<u16>)>,
    exchange: Exchange,
) -> (Vec<Duration>, u64, u64) {
    let latencies = Arc::new(Mutex::new(Vec::new()));
    let sent_total = Arc::new(AtomicU64::new(0));
    let end = Instant::now() + Duration::from_secs(LOAD_SECONDS);
    let mut tasks = Vec::new();
    for (bus, ids) in channels {
        let sent_at: Arc<Mutex<HashMap<u16, VecDeque<Instant>>>> = Arc::default();
        let receiver = {
            let (bus, sent_at, latencies) = (
                Arc::clone(&bus),
                Arc::clone(&sent_at),
                Arc::clone(&latencies),
            );
            tokio::spawn(async move {
                while let Ok(Ok(received)) =
                    tokio::time::timeout(Duration::from_millis(200), bus.recv()).await
                {
                    let Some(motor) = (exchange.answering_motor)(received.frame.raw_id()) else {
                        continue;
                    };
                    let sent = sent_at
                        .lock()
                        .unwrap()
                        .get_mut(&motor)
                        .and_then(VecDeque::pop_front);
                    if let Some(at) = sent {
                        latencies.lock().unwrap().push(at.elapsed());
                    }
                }
            })
        };
        let sender = {
            let sent_total = Arc::clone(&sent_total);
            tokio::spawn(async move {
                let mut ticks = tokio::time::interval(exchange.period);
                let mut next = ids.iter().copied().cycle();
                while Instant::now() < end {
                    ticks.tick().await;
                    for motor in next.by_ref().take(exchange.per_tick) {
                        sent_at
                            .lock()
                            .unwrap()
                            .entry(motor)
                            .or_default()
                            .push_back(Instant::now());
                        send(bus.as_ref(), (exchange.command)(motor)).await;
                        sent_total.fetch_add(1, Ordering::Relaxed);
                    }
                }
                bus
            })
        };
        tasks.push((sender, receiver));
    }
    for (sender, receiver) in tasks {
        let _bus = sender.await.expect("sender");
        receiver.await.expect("receiver");
    }
    let mut latencies = std::mem::take(&mut *latencies.lock().unwrap());
    latencies.sort();
    let answered = latencies.len() as u64;
    (latencies, answered, sent_total.load(Ordering::Relaxed))
}

/// One client pings another on the same channel through the bus.
async fn client_to_client(addr: &str) -> Vec<Duration> {
    let a = SocketcandBus::connect(addr, "can0").await.expect("a");
    let b = SocketcandBus::connect(addr, "can0").await.expect("b");
    tokio::time::sleep(Duration::from_millis(300)).await;
    let mut times = Vec::with_capacity(PINGS);
    for n in 0..PINGS {
        let frame = CanFrame::standard(0x7F0, &(n as u32).to_le_bytes()).expect("frame");
        let sent = Instant::now();
        send(&a, frame).await;
        loop {
            let Ok(Ok(received)) = tokio::time::timeout(Duration::from_secs(1), b.recv()).await
            else {
                break;
            };
            if received.frame == frame {
                times.push(sent.elapsed());
                break;
            }
        }
        tokio::time::sleep(Duration::from_micros(500)).await;
    }
    times.sort();
    times
}

/// Socketcand clients on `channel` that open it, enter raw mode and then never read.
fn silent_clients(addr: &str, channel: &str, count: usize) -> Vec<std::net::TcpStream> {
    use std::io::{Read, Write};
    let mut clients = Vec::with_capacity(count);
    for _ in 0..count {
        let Ok(mut stream) = std::net::TcpStream::connect(addr) else {
            break;
        };
        let _ = stream.set_read_timeout(Some(Duration::from_secs(2)));
        let mut greeting = [0u8; 64];
        let _ = stream.read(&mut greeting);
        let _ = write!(stream, "< open {channel} >");
        let _ = stream.read(&mut greeting);
        let _ = write!(stream, "< rawmode >");
        let _ = stream.read(&mut greeting);
        clients.push(stream);
    }
    clients
}

fn print_latencies(label: &str, (latencies, answered, sent): &(Vec<Duration>, u64, u64)) {
    println!(
        "  {label}: p50 {}, p99 {}, max {}; answered {answered} of {sent} ({:.2} %)",
        ms(percentile(latencies, 0.5)),
        ms(percentile(latencies, 0.99)),
        ms(latencies.last().copied().unwrap_or_default()),
        100.0 * *answered as f64 / (*sent).max(1) as f64,
    );
}

fn main() {
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .expect("runtime");

    let port = free_port();
    let addr = format!("127.0.0.1:{port}");
    let robot = start(&[
        "sim",
        "robot",
        "robots/humanoid.yaml",
        "--socketcand",
        &addr,
    ]);
    wait_for_port(port);
    std::thread::sleep(Duration::from_secs(1));
    let pid = robot.child.id();
    let idle = cpu_percent(pid, || {
        std::thread::sleep(Duration::from_secs(IDLE_SECONDS))
    });
    let mut burst = None;
    let loaded_burst = cpu_percent(pid, || {
        burst = Some(runtime.block_on(commands_under_load(&addr, Pattern::Burst)));
    });
    let mut spaced = None;
    let loaded_spaced = cpu_percent(pid, || {
        spaced = Some(runtime.block_on(commands_under_load(&addr, Pattern::Spaced)));
    });
    let echo = runtime.block_on(client_to_client(&addr));
    let silent = silent_clients(&addr, "can0", 118);
    let beside_silent = runtime.block_on(commands_under_load(&addr, Pattern::Burst));
    let silent_count = silent.len();
    drop(silent);
    // At rest again, long after start: its hanging joints have crept to rest by now (about
    // 20 s after power-on), so this is the robot doing nothing.
    std::thread::sleep(Duration::from_secs(1));
    let idle_after = cpu_percent(pid, || {
        std::thread::sleep(Duration::from_secs(IDLE_SECONDS))
    });
    drop(robot);

    println!("humanoid (20 actuators, 4 channels) over socketcand, real time:");
    println!("  reply latency at 2,000 commands/s, from the host's send to the answer:");
    print_latencies(
        "burst (5 per bus every 10 ms)",
        burst.as_ref().expect("ran"),
    );
    print_latencies(
        "spaced (1 per bus every 2 ms)",
        spaced.as_ref().expect("ran"),
    );
    print_latencies(
        &format!("burst beside {silent_count} clients that never read"),
        &beside_silent,
    );
    println!(
        "  client-to-client echo: p50 {}, p99 {} ({} of {PINGS} pings)",
        ms(percentile(&echo, 0.5)),
        ms(percentile(&echo, 0.99)),
        echo.len()
    );
    println!(
        "  CPU: {idle:.1} % of a core at rest 1 s after start, {loaded_burst:.1} % under the burst, {loaded_spaced:.1} % spaced, {idle_after:.1} % at rest after the load"
    );

    for (label, args) in [
        (
            "sim robstride (5 motors)",
            vec![
                "--motor", "1:RS03", "--motor", "2:RS03", "--motor", "3:RS02", "--motor", "4:RS02",
                "--motor", "5:RS04",
            ],
        ),
        ("sim realman", vec![]),
    ] {
        let port = free_port();
        let mut command = vec!["sim"];
        let addr = format!("127.0.0.1:{port}");
        let port_text = port.to_string();
        if label.starts_with("sim realman") {
            command.extend(["realman", "--port", &port_text]);
        } else {
            command.extend(["robstride", "--socketcand", &addr]);
        }
        command.extend(args.iter().copied());
        let emulator = start(&command);
        wait_for_port(port);
        std::thread::sleep(Duration::from_secs(1));
        let idle = cpu_percent(emulator.child.id(), || {
            std::thread::sleep(Duration::from_secs(IDLE_SECONDS))
        });
        println!("{label}: {idle:.1} % of a core at rest");
    }

    damiao_figures(
        &runtime,
        "sim damiao (one DM4310)",
        &["damiao", "--motor", "1:DM4310"],
        &[("can0", &[1])],
    );
    let arm: &[u16] = &[1, 2, 3, 4, 5, 6, 7, 8];
    damiao_figures(
        &runtime,
        "sim robot robots/openarm.yaml (16 Damiao motors, 2 channels)",
        &["robot", "robots/openarm.yaml"],
        &[("can0", arm), ("can1", arm)],
    );
}
