//! Whole robots, printed (run: `cargo bench --bench robot_speed`).
//!
//! - Virtual time: how many times faster than real time the robot runs on one core (a
//!   current-thread runtime under a paused clock, as `armhil run` does), for the 6-DoF arm,
//!   the humanoid standing (every actuator enabled in operation control, its feet on the
//!   ground), one and two humanoids in one process (20 and 40 actuators), the OpenArm (16
//!   Damiao motors on two CAN FD buses, both arms holding in MIT mode at the vendor's gains),
//!   and a one-actuator
//!   robot (the arm with only its shoulder actuated is not a robot file; the arm with all six
//!   is the smallest shipped).
//! - The Unitree G1 of the public corpus (example-robot-data 6.0.0, when `ARMHIL_URDF_CORPUS`
//!   points at it; skipped with one line otherwise): 29 actuators from
//!   `testkit::corpus::robot_file_for`, its feet's and body's collision shapes (mesh hulls),
//!   standing on its gantry-released feet at the gains of `testkit::corpus::LEGGED`; the world
//!   alone and in virtual time, measured as the humanoid is.
//! - Real time: the humanoid for a few wall seconds on a two-worker runtime (as `armhil sim
//!   robot` runs it), with a host sending every actuator a 1 kHz operation-control stream on
//!   its bus; the process's CPU time per wall second, and each bus's load against its
//!   1 Mbit/s.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use bus::virtual_bus::{VirtualBus, VirtualBusConfig, VirtualNode};
use bus::{CanBus, CanFrame};
use sim::robot::{RobotConfig, RobotEmulator, RobotHandle};

/// Emulated time per virtual-time run.
const VIRTUAL_RUN: Duration = Duration::from_secs(5);
/// Wall time of the real-time run.
const REAL_RUN: Duration = Duration::from_secs(4);
/// Host id the frames are sent from.
const HOST: u32 = 0xFD;

fn robot(name: &str) -> RobotConfig {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("robots/{name}.yaml"));
    armhil::robots::load_robot_file(&file)
        .expect("a shipped robot loads")
        .config
}

/// A robot to measure: its name in the output, what the emulator runs, and each actuator's
/// hold gains (kp N·m/rad, kd N·m·s/rad; configuration order).
#[derive(Clone)]
struct Subject {
    name: String,
    config: RobotConfig,
    gains: Vec<(f64, f64)>,
}

/// The OpenArm vendor's MIT gains per joint (J1..J7, gripper): kp, kd.
const OPENARM_GAINS: [(f64, f64); 8] = [
    (70.0, 2.75),
    (70.0, 2.5),
    (70.0, 2.0),
    (60.0, 2.0),
    (10.0, 0.7),
    (10.0, 0.6),
    (10.0, 0.5),
    (10.0, 0.2),
];

/// A shipped robot (`robots/NAME.yaml`): legs (every actuator but the arms' RS02, ankles
/// included) at kp 300, kd 5; arms at kp 50, kd 1, as `scenarios/robot/humanoid_stand.yaml`;
/// a Damiao motor at the OpenArm's gains for its place on its bus (J1..J7, gripper).
fn shipped(name: &str) -> Subject {
    let config = robot(name);
    let gains = config
        .actuators
        .iter()
        .map(|a| {
            if let Some(m) = a.actuator.downcast_ref::<sim::damiao::MotorConfig>() {
                return OPENARM_GAINS[usize::from(m.esc_id.saturating_sub(1)) % 8];
            }
            let leg = a.actuator.model().name != "RS02" || a.joint.contains("ankle");
            if leg {
                (300.0, 5.0)
            } else {
                (50.0, 1.0)
            }
        })
        .collect();
    Subject {
        name: name.to_owned(),
        config,
        gains,
    }
}

/// The corpus's G1 (29 actuators), as `testkit::corpus` writes its robot file, with the
/// standing gains of `testkit::corpus::LEGGED`; `None` (after one line) without the corpus.
fn corpus_g1() -> Option<Subject> {
    const NAME: &str = "g1_29dof_rev_1_0";
    let Some(root) = std::env::var_os(testkit::corpus::CORPUS_ENV).filter(|v| !v.is_empty()) else {
        println!(
            "skipped: robot_speed: {NAME}: {} not set — pip install example-robot-data==6.0.0 \
             and point it at …/cmeel.prefix/share/example-robot-data",
            testkit::corpus::CORPUS_ENV
        );
        return None;
    };
    let root = PathBuf::from(root);
    let legged = testkit::corpus::LEGGED
        .iter()
        .find(|l| l.name() == NAME)
        .expect("the G1 is a legged robot of testkit::corpus");
    let urdf = root.join(legged.urdf);
    let text = testkit::corpus::robot_file_for(&urdf, &root, &legged.options());
    let plan = legged.plan(&root).expect("the G1 plans");
    let dir = tempfile::tempdir().expect("a temporary folder");
    let file = dir.path().join(format!("{NAME}.yaml"));
    std::fs::write(&file, text).expect("the robot file is written");
    let config = armhil::robots::load_robot_file(&file)
        .expect("the generated robot file loads")
        .config;
    let gains = config
        .actuators
        .iter()
        .map(|a| {
            plan.actuator(&a.joint)
                .expect("every actuator is planned")
                .gains(legged.kp_per_nm, legged.kd_per_nm)
        })
        .collect();
    Some(Subject {
        name: NAME.to_owned(),
        config,
        gains,
    })
}

struct Running {
    handle: RobotHandle,
    hosts: Vec<VirtualNode>,
    config: RobotConfig,
    gains: Vec<(f64, f64)>,
    _buses: Vec<VirtualBus>,
}

fn spawn(subject: &Subject, bus_config: VirtualBusConfig) -> Running {
    let config = subject.config.clone();
    let buses: Vec<VirtualBus> = config
        .buses
        .iter()
        .map(|_| VirtualBus::new(bus_config.clone()))
        .collect();
    let nodes = buses
        .iter()
        .map(|b| Arc::new(b.attach("robot")) as Arc<dyn CanBus>)
        .collect();
    let hosts = buses.iter().map(|b| b.attach("host")).collect();
    let handle = RobotEmulator::spawn(config.clone(), nodes).expect("the robot starts");
    Running {
        handle,
        hosts,
        config,
        gains: subject.gains.clone(),
        _buses: buses,
    }
}

/// A type-1 operation-control frame holding `angle_rad` with kp/kd (the manual's scaling
/// of the model: angle ±4π, speed and torque at their midpoints = 0, kp and kd from 0 to the
/// model's maximum).
fn hold_frame(
    motor: u8,
    model: sim::robstride::Model,
    angle_rad: f64,
    kp: f64,
    kd: f64,
) -> CanFrame {
    let ranges = model.ranges(sim::robstride::RangeTable::Manual);
    let scale =
        |v: f64, lo: f64, hi: f64| (((v - lo) / (hi - lo)).clamp(0.0, 1.0) * 65535.0) as u16;
    let angle = f64::from(ranges.angle_rad);
    let mut data = [0u8; 8];
    data[0..2].copy_from_slice(&scale(angle_rad, -angle, angle).to_be_bytes());
    data[2..4].copy_from_slice(&0x7FFFu16.to_be_bytes());
    data[4..6].copy_from_slice(&scale(kp, 0.0, f64::from(ranges.kp_max)).to_be_bytes());
    data[6..8].copy_from_slice(&scale(kd, 0.0, f64::from(ranges.kd_max)).to_be_bytes());
    let torque_mid = 0x7FFFu32;
    CanFrame::extended((1 << 24) | (torque_mid << 8) | u32::from(motor), &data).expect("a frame")
}

fn enable_frame(motor: u8) -> CanFrame {
    CanFrame::extended((3 << 24) | (HOST << 8) | u32::from(motor), &[0; 8]).expect("a frame")
}

/// A Damiao MIT frame holding `angle_rad` with kp/kd, packed by our Damiao driver's codec (the
/// host's side of the wire, over the model's ranges as the driver knows them).
fn damiao_hold_frame(m: &sim::damiao::MotorConfig, angle_rad: f64, kp: f64, kd: f64) -> CanFrame {
    use driver::damiao::{codec, MitCommand, Model, RangeTable};
    let model = Model::parse(m.model.name()).expect("the driver knows every Damiao model");
    let command = MitCommand {
        p_des_rad: angle_rad as f32,
        v_des_rad_s: 0.0,
        kp: kp as f32,
        kd: kd as f32,
        t_ff_nm: 0.0,
    };
    codec::mit(m.esc_id, &command, &model.ranges(RangeTable::Current)).expect("a frame")
}

/// A Damiao enable (`FF … FC` on its command id).
fn damiao_enable_frame(m: &sim::damiao::MotorConfig) -> CanFrame {
    use driver::damiao::codec;
    codec::special(m.esc_id, codec::special::ENABLE).expect("a frame")
}

/// A RobStride actuator's settings, when `a` is one.
fn robstride(a: &sim::robot::JointActuator) -> Option<&sim::robstride::MotorConfig> {
    a.actuator.downcast_ref()
}

/// A Damiao motor's settings, when `a` is one.
fn damiao(a: &sim::robot::JointActuator) -> Option<&sim::damiao::MotorConfig> {
    a.actuator.downcast_ref()
}

/// The hold frame of every actuator (where it is, at its gains), with the bus it goes on.
fn hold_frames(running: &Running, start: &sim::robot::RobotSnapshot) -> Vec<(usize, CanFrame)> {
    running
        .config
        .actuators
        .iter()
        .zip(&start.joints)
        .zip(&running.gains)
        .map(|((a, j), (kp, kd))| {
            let angle = j.actuator.angle_rad;
            let frame = match (robstride(a), damiao(a)) {
                (Some(m), _) => hold_frame(m.can_id, m.model, angle, *kp, *kd),
                (_, Some(m)) => damiao_hold_frame(m, angle, *kp, *kd),
                _ => unreachable!("the robots here carry RobStride and Damiao actuators"),
            };
            (a.bus, frame)
        })
        .collect()
}

async fn send(host: &VirtualNode, frame: CanFrame) {
    while host.send(frame).await.is_err() {
        tokio::time::sleep(Duration::from_micros(100)).await;
    }
}

/// Send every actuator one hold command, enable it, and send the command again. The firmware
/// keeps an operation-control command it gets while disabled, so a robot whose gantry lets
/// go at the last enable (the G1) lands with every joint already holding.
async fn hold_all(running: &Running) {
    let start = running.handle.snapshot().await.expect("a snapshot");
    let frames = hold_frames(running, &start);
    for (bus, frame) in &frames {
        send(&running.hosts[*bus], *frame).await;
    }
    for a in &running.config.actuators {
        let enable = match (robstride(a), damiao(a)) {
            (Some(m), _) => enable_frame(m.can_id),
            (_, Some(m)) => damiao_enable_frame(m),
            _ => unreachable!("the robots here carry RobStride and Damiao actuators"),
        };
        send(&running.hosts[a.bus], enable).await;
    }
    for (bus, frame) in frames {
        send(&running.hosts[bus], frame).await;
    }
}

/// Drains every host's receive queue (the robot's replies), so no queue overflows.
fn drain(hosts: &[VirtualNode]) -> Vec<tokio::task::JoinHandle<()>> {
    hosts
        .iter()
        .map(|h| {
            let h = h.clone();
            tokio::spawn(async move { while h.recv().await.is_ok() {} })
        })
        .collect()
}

/// Emulated seconds per wall second for `count` copies of `subject` in one process, its
/// actuators, and the first copy's base height at the end (m).
fn virtual_speed(subject: &Subject, count: usize) -> (f64, usize, f64) {
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .start_paused(true)
        .build()
        .expect("a runtime");
    runtime.block_on(async {
        let robots: Vec<Running> = (0..count)
            .map(|_| spawn(subject, VirtualBusConfig::default()))
            .collect();
        let mut drains = Vec::new();
        for r in &robots {
            drains.extend(drain(&r.hosts));
            hold_all(r).await;
        }
        let actuators = robots.iter().map(|r| r.config.actuators.len()).sum();
        let wall = Instant::now();
        tokio::time::sleep(VIRTUAL_RUN).await;
        let speed = VIRTUAL_RUN.as_secs_f64() / wall.elapsed().as_secs_f64();
        let mut base_m = f64::NAN;
        for r in &robots {
            let s = r.handle.snapshot().await.expect("a snapshot");
            assert!(s.base_position_m[2].is_finite());
            if base_m.is_nan() {
                base_m = s.base_position_m[2];
            }
        }
        for d in drains {
            d.abort();
        }
        for r in robots {
            r.handle.shutdown().await;
        }
        (speed, actuators, base_m)
    })
}

/// CPU seconds this process has used.
fn cpu_seconds() -> f64 {
    // SAFETY: getrusage fills the struct it is given.
    #[allow(unsafe_code)]
    let usage = unsafe {
        let mut usage: libc::rusage = std::mem::zeroed();
        libc::getrusage(libc::RUSAGE_SELF, &mut usage);
        usage
    };
    let t = |tv: libc::timeval| tv.tv_sec as f64 + tv.tv_usec as f64 * 1e-6;
    t(usage.ru_utime) + t(usage.ru_stime)
}

/// Bits on the wire of an extended data frame with `bytes` data bytes, without stuffing
/// (SOF, 29-bit id with SRR/IDE, RTR, r1/r0, DLC, data, CRC + delimiter, ACK, EOF, IFS).
fn extended_frame_bits(bytes: usize) -> f64 {
    (1 + 11 + 1 + 1 + 18 + 1 + 2 + 4 + 8 * bytes + 15 + 1 + 2 + 7 + 3) as f64
}

fn real_time_humanoid() {
    // The runtime `armhil sim robot` runs on.
    let runtime = sim::pacer::real_time_runtime().expect("a runtime");
    runtime.block_on(async {
        let epoch = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap_or_default();
        let running = spawn(
            &shipped("humanoid"),
            VirtualBusConfig {
                epoch,
                ..VirtualBusConfig::default()
            },
        );
        let received: Vec<_> = running
            .hosts
            .iter()
            .map(|h| {
                let h = h.clone();
                tokio::spawn(async move {
                    let mut frames = 0u64;
                    while h.recv().await.is_ok() {
                        frames += 1;
                    }
                    frames
                })
            })
            .collect();
        hold_all(&running).await;
        let start = running.handle.snapshot().await.expect("a snapshot");
        let frames = hold_frames(&running, &start);
        let cpu_before = cpu_seconds();
        let wall = Instant::now();
        let mut sent = vec![0u64; running.hosts.len()];
        let mut ticks = tokio::time::interval(Duration::from_millis(1));
        while wall.elapsed() < REAL_RUN {
            ticks.tick().await;
            for (bus, frame) in &frames {
                if running.hosts[*bus].send(*frame).await.is_ok() {
                    sent[*bus] += 1;
                }
            }
        }
        let elapsed = wall.elapsed().as_secs_f64();
        let cpu = cpu_seconds() - cpu_before;
        let snapshot = running.handle.snapshot().await.expect("a snapshot");
        running.handle.shutdown().await;
        let mut replies = Vec::new();
        for r in received {
            r.abort();
            replies.push(r.await.unwrap_or(0));
        }
        println!(
            "humanoid in real time, 1 kHz command streams: {:.0} % of one core (host and robot \
             together), {:.2} s emulated in {elapsed:.2} s, pelvis at {:.3} m",
            100.0 * cpu / elapsed,
            snapshot.time_s,
            snapshot.base_position_m[2]
        );
        if snapshot.time_s < 0.95 * elapsed {
            // The figures above are then of a robot that did not keep up (a stalled step loop
            // once read as a cheap one here).
            println!(
                "  WARNING: the robot fell behind the wall clock ({:.2} s of {elapsed:.2} s); its CPU share is not the cost of real time",
                snapshot.time_s
            );
        }
        let bits = extended_frame_bits(8);
        for (k, bus) in running.config.buses.iter().enumerate() {
            let per_s = sent[k] as f64 / elapsed;
            // Replies: the emulator answers each command; the count the host read was
            // aborted mid-run, so the load is given for one reply per command.
            let load = 2.0 * per_s * bits / f64::from(bus.bitrate_bps);
            println!(
                "  {}: {:.0} commands/s + as many replies = {:.0} % of {} kbit/s (unstuffed; \
                 bit stuffing adds up to ~20 %)",
                bus.name,
                per_s,
                100.0 * load,
                bus.bitrate_bps / 1000
            );
        }
    });
}

/// The physics alone: the robot's world stepped with zero torques (no firmware, no buses),
/// µs per 1 ms step (after 200 steps).
fn world_step_us(subject: &Subject) -> f64 {
    let (mut world, _plants) = sim::robot::RobotWorld::new(&subject.config).expect("a world");
    for _ in 0..200 {
        world.step().expect("finite");
    }
    let steps = 2000;
    let wall = Instant::now();
    for _ in 0..steps {
        world.step().expect("finite");
    }
    wall.elapsed().as_secs_f64() * 1e6 / f64::from(steps)
}

fn main() {
    if std::env::args().any(|a| a == "--list") {
        return;
    }
    let arm = shipped("robstride_arm6");
    let humanoid = shipped("humanoid");
    let openarm = shipped("openarm");
    let g1 = corpus_g1();
    for subject in [Some(&arm), Some(&humanoid), g1.as_ref()]
        .into_iter()
        .flatten()
    {
        println!(
            "{}: the world alone (no firmware, zero torques) {:.0} µs per 1 ms step",
            subject.name,
            world_step_us(subject)
        );
    }
    println!(
        "virtual time ({} s emulated per run, one core):",
        VIRTUAL_RUN.as_secs()
    );
    let mut runs = vec![(&arm, 1), (&humanoid, 1), (&humanoid, 2), (&openarm, 1)];
    if let Some(g1) = &g1 {
        runs.push((g1, 1));
    }
    for (subject, count) in runs {
        let (speed, actuators, base_m) = virtual_speed(subject, count);
        let base = if subject.config.base == sim::robot::Base::Fixed {
            String::new()
        } else {
            format!(", base at {base_m:.3} m at the end")
        };
        println!(
            "  {count} × {}: {actuators} actuators, {speed:.1}× real time ({:.0} µs per 1 ms \
             step){base}",
            subject.name,
            1000.0 / speed
        );
    }
    real_time_humanoid();
}
