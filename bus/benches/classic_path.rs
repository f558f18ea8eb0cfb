//! The classic-frame hot path: what one classic (8-byte) frame costs to build, copy and send
//! through the virtual bus. Written to check that carrying CAN FD frames in `CanFrame` did not
//! make classic frames dearer. Run: `cargo bench -p armhil-bus --bench classic_path`.
//!
//! Prints, for 1 000 000 frames, the best and the median of five runs in ns per frame:
//! - `build+copy`: `CanFrame::standard` with 8 bytes, then the frame copied into a ring of
//!   1024 frames that stays in cache (every frame a fresh id and payload, so nothing is
//!   hoisted): the CPU cost of making and moving a frame;
//! - `build+store`: the same into a preallocated `Vec` of all 1 000 000 frames: the cost of the
//!   frame's size in memory (pages touched, cache lines written);
//! - `virtual bus`: the same frames sent by one node and received by another on a paused
//!   clock (virtual wire time; the figure is wall time, i.e. the bus's own cost per frame).

use std::hint::black_box;
use std::time::{Duration, Instant};

use bus::virtual_bus::{NodeOptions, StuffingPolicy, VirtualBus, VirtualBusConfig};
use bus::{BusError, CanBus, CanFrame, ReceivedFrame};

const FRAMES: u32 = 1_000_000;
const RUNS: usize = 5;

fn frame(i: u32) -> CanFrame {
    let bytes = (u64::from(i) * 0x0101_0101).to_le_bytes();
    match CanFrame::standard((i % 0x800) as u16, &bytes) {
        Ok(frame) => frame,
        Err(error) => panic!("bad frame: {error}"),
    }
}

fn build_and_copy() -> Duration {
    let mut ring = [frame(0); 1024];
    let start = Instant::now();
    for i in 0..FRAMES {
        ring[i as usize % 1024] = black_box(frame(black_box(i)));
        black_box(&ring);
    }
    let elapsed = start.elapsed();
    black_box(&ring);
    elapsed
}

fn build_and_store() -> Duration {
    let mut out: Vec<CanFrame> = Vec::with_capacity(FRAMES as usize);
    let start = Instant::now();
    for i in 0..FRAMES {
        out.push(black_box(frame(black_box(i))));
    }
    let elapsed = start.elapsed();
    black_box(&out);
    elapsed
}

async fn through_the_bus() -> Duration {
    let bus = VirtualBus::new(VirtualBusConfig {
        // The wire runs in virtual time here; a fast one drains the whole queue in each
        // virtual millisecond the sender waits.
        bitrate_bps: 1_000_000_000,
        stuffing: StuffingPolicy::None,
        ..VirtualBusConfig::default()
    });
    let sender = bus.attach_with(
        "sender",
        NodeOptions {
            receive_own: false,
            tx_queue_len: Some(1024),
        },
    );
    let receiver = bus.attach("receiver");
    let reader = tokio::spawn(async move {
        let mut last: Option<ReceivedFrame> = None;
        for _ in 0..FRAMES {
            match receiver.recv().await {
                Ok(received) => last = Some(black_box(received)),
                Err(error) => panic!("receiver failed: {error}"),
            }
        }
        last
    });
    let start = Instant::now();
    let mut sent = 0u32;
    while sent < FRAMES {
        match sender.send(frame(sent)).await {
            Ok(()) => sent += 1,
            // Queue full: let the wire drain for a (virtual) millisecond; a yield would keep the
            // paused clock from ever advancing.
            Err(BusError::TxQueueFull { .. }) => tokio::time::sleep(Duration::from_millis(1)).await,
            Err(error) => panic!("send failed: {error}"),
        }
    }
    let last = match reader.await {
        Ok(last) => last,
        Err(error) => panic!("receiver task failed: {error}"),
    };
    let elapsed = start.elapsed();
    assert_eq!(last.map(|r| r.frame), Some(frame(FRAMES - 1)));
    elapsed
}

fn report(what: &str, mut runs: Vec<Duration>) {
    runs.sort();
    let per_frame = |d: Duration| d.as_nanos() as f64 / f64::from(FRAMES);
    println!(
        "classic_path {what}: best {:.1} ns/frame, median {:.1} ns/frame ({RUNS} runs of {FRAMES})",
        per_frame(runs[0]),
        per_frame(runs[runs.len() / 2]),
    );
}

fn main() {
    println!(
        "size_of::<CanFrame>() = {} bytes, size_of::<ReceivedFrame>() = {} bytes",
        std::mem::size_of::<CanFrame>(),
        std::mem::size_of::<ReceivedFrame>()
    );
    report("build+copy", (0..RUNS).map(|_| build_and_copy()).collect());
    report(
        "build+store",
        (0..RUNS).map(|_| build_and_store()).collect(),
    );
    let runtime = match tokio::runtime::Builder::new_current_thread()
        .enable_time()
        .start_paused(true)
        .build()
    {
        Ok(runtime) => runtime,
        Err(error) => panic!("no runtime: {error}"),
    };
    report(
        "virtual bus send->recv",
        (0..RUNS)
            .map(|_| runtime.block_on(through_the_bus()))
            .collect(),
    );
}
