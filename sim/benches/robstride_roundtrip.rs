//! Round trips (operation-control command → status reply) per second for 8 RobStride motors
//! on one virtual 1 Mbit/s bus, against the bus's theoretical frame capacity.
//!
//! The host keeps one command outstanding per motor (all 8 in flight) and sends the next as
//! soon as a motor's reply arrives. Run: `cargo bench -p armhil-sim --bench robstride_roundtrip`.

use std::sync::Arc;
use std::time::{Duration, Instant};

use bus::virtual_bus::{VirtualBus, VirtualBusConfig};
use bus::{CanBus, CanFrame};
use sim::robstride::{Model, MotorConfig, RobstrideBus, RobstrideConfig};

const MOTORS: u8 = 8;
const HOST: u32 = 0xFD;

fn command(motor: u8) -> CanFrame {
    // Type 1, zero torque feed-forward, p = v = 0, kp = kd = 0: a pure status exchange.
    let id = (1 << 24) | (0x7FFF << 8) | u32::from(motor);
    CanFrame::extended(id, &[0x7F, 0xFF, 0x7F, 0xFF, 0, 0, 0, 0]).expect("valid frame")
}

async fn run(virtual_seconds: u64) -> (u64, f64, Duration, f64, f64) {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let motors = (1..=MOTORS)
        .map(|id| MotorConfig::new(id, Model::RS03))
        .collect();
    let node: Arc<dyn CanBus> = Arc::new(bus.attach("emulator"));
    let emulator = RobstrideBus::spawn(node, RobstrideConfig::new(motors)).expect("spawn");
    let host = bus.attach("host");
    let start = tokio::time::Instant::now();
    let wall = Instant::now();
    for id in 1..=MOTORS {
        host.send(command(id)).await.expect("send");
    }
    let mut round_trips = 0u64;
    let end = start + Duration::from_secs(virtual_seconds);
    while tokio::time::Instant::now() < end {
        let Ok(Ok(received)) = tokio::time::timeout(Duration::from_millis(100), host.recv()).await
        else {
            break;
        };
        let id = received.frame.raw_id();
        if (id >> 24) & 0x1F == 2 && id & 0xFF == HOST {
            round_trips += 1;
            let motor = ((id >> 8) & 0xFF) as u8;
            host.send(command(motor)).await.expect("send");
        }
    }
    let elapsed = start.elapsed().as_secs_f64();
    let stats = bus.stats();
    emulator.shutdown().await;
    (
        round_trips,
        elapsed,
        wall.elapsed(),
        stats.load_percent,
        stats.bits as f64 / stats.frames.max(1) as f64,
    )
}

fn main() {
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .start_paused(true)
        .build()
        .expect("runtime");
    let seconds = 5;
    let (round_trips, elapsed, wall, load, bits_per_frame) = runtime.block_on(run(seconds));
    let per_s = round_trips as f64 / elapsed;
    // An extended 8-byte data frame is 131 bits without stuffing, 160 with worst-case
    // stuffing (`bus::timing`); a round trip is two frames.
    let best = 1_000_000.0 / 131.0 / 2.0;
    let worst = 1_000_000.0 / 160.0 / 2.0;
    println!("robstride_roundtrip: {MOTORS} motors, 1 Mbit/s virtual bus, {elapsed:.2} s virtual");
    println!(
        "  round trips: {round_trips} = {per_s:.0}/s ({:.0}/s per motor)",
        per_s / f64::from(MOTORS)
    );
    println!("  theoretical: {worst:.0}..{best:.0}/s (2 extended frames of 160..131 bits each)");
    println!("  bus load: {load:.1} %, mean frame {bits_per_frame:.1} bits (stuffing included)");
    println!(
        "  utilisation: {:.1} % of the no-stuffing capacity",
        100.0 * per_s / best
    );
    println!(
        "  wall time: {:.2} s ({:.1}x real time)",
        wall.as_secs_f64(),
        elapsed / wall.as_secs_f64()
    );
}
