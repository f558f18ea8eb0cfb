//! Virtual-bus throughput: one sender, eight receivers, paused clock (virtual wire time).
//! Prints frames delivered per wall-clock second. Run: `cargo bench -p armhil-bus`.

use std::time::{Duration, Instant};

use bus::virtual_bus::{NodeOptions, StuffingPolicy, VirtualBus, VirtualBusConfig};
use bus::{BusError, CanBus, CanFrame};

const FRAMES: u32 = 200_000;
const RECEIVERS: usize = 8;

async fn run(stuffing: StuffingPolicy) -> (Duration, Duration) {
    let bus = VirtualBus::new(VirtualBusConfig {
        stuffing,
        ..VirtualBusConfig::default()
    });
    // A queue deep enough to keep the wire busy across a millisecond timer tick, so the wire
    // (not the sender's pacing) is the bottleneck in virtual time.
    let sender = bus.attach_with(
        "sender",
        NodeOptions {
            receive_own: false,
            tx_queue_len: Some(64),
        },
    );
    let receivers: Vec<_> = (0..RECEIVERS)
        .map(|index| {
            let node = bus.attach(&format!("rx{index}"));
            tokio::spawn(async move {
                let mut count = 0u32;
                let mut last = Duration::ZERO;
                while count < FRAMES {
                    match node.recv().await {
                        Ok(frame) => {
                            count += 1;
                            last = frame.timestamp;
                        }
                        Err(error) => panic!("receiver failed: {error}"),
                    }
                }
                last
            })
        })
        .collect();
    let wall = Instant::now();
    let mut sent = 0u32;
    while sent < FRAMES {
        let frame = match CanFrame::standard(0x100 + (sent % 0x100) as u16, &sent.to_le_bytes()) {
            Ok(frame) => frame,
            Err(error) => panic!("bad frame: {error}"),
        };
        match sender.send(frame).await {
            Ok(()) => sent += 1,
            // Queue full: let the wire drain for a (virtual) millisecond.
            Err(BusError::TxQueueFull { .. }) => tokio::time::sleep(Duration::from_millis(1)).await,
            Err(error) => panic!("send failed: {error}"),
        }
    }
    let mut virtual_end = Duration::ZERO;
    for receiver in receivers {
        match receiver.await {
            Ok(last) => virtual_end = virtual_end.max(last),
            Err(error) => panic!("receiver task failed: {error}"),
        }
    }
    (wall.elapsed(), virtual_end)
}

fn main() {
    for stuffing in [StuffingPolicy::None, StuffingPolicy::Exact] {
        let runtime = match tokio::runtime::Builder::new_current_thread()
            .enable_time()
            .start_paused(true)
            .build()
        {
            Ok(runtime) => runtime,
            Err(error) => panic!("no runtime: {error}"),
        };
        let (wall, virtual_time) = runtime.block_on(run(stuffing));
        let frames = f64::from(FRAMES);
        println!(
            "virtual_bus 1 sender -> {RECEIVERS} receivers, 4-byte frames, 1 Mbit/s, stuffing {stuffing:?}: \
             {FRAMES} frames in {:.3} s wall ({:.0} frames/wall-s, {:.0} deliveries/wall-s), \
             {:.3} s virtual ({:.0} frames/virtual-s, {:.1}x real time)",
            wall.as_secs_f64(),
            frames / wall.as_secs_f64(),
            frames * RECEIVERS as f64 / wall.as_secs_f64(),
            virtual_time.as_secs_f64(),
            frames / virtual_time.as_secs_f64(),
            virtual_time.as_secs_f64() / wall.as_secs_f64(),
        );
    }
}
