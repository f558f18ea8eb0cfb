//! CPU cost of the Piper receive path: per received feedback frame (decode + state update),
//! and frames/s the driver's receive task sustains on one core (current-thread runtime).
//!
//! Run: `cargo bench -p armhil-driver --bench piper_decode`. Prints figures; asserts nothing.

use std::hint::black_box;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant as WallClock};

use async_trait::async_trait;
use bus::{BusError, CanBus, CanFrame, ReceivedFrame};
use driver::piper::codec::decode;
use driver::piper::{FirmwareSelection, FirmwareVersion, PiperBuilder, PiperState, Timeouts};

/// One second of a real arm's feedback mix (spec §2.2): 0x2A1–0x2A8 and 0x251–0x256 at
/// 200 Hz, 0x261–0x266 at 40 Hz = 3040 frames.
fn feedback_mix() -> Vec<CanFrame> {
    let mut frames = Vec::new();
    for tick in 0..200u32 {
        let angle = (tick as i32) * 100;
        frames.push(CanFrame::standard(0x2A1, &[1, 0, 1, 0, 1, 0, 0, 0]).expect("frame"));
        for id in 0x2A2..=0x2A7u16 {
            let mut d = [0u8; 8];
            d[..4].copy_from_slice(&angle.to_be_bytes());
            d[4..].copy_from_slice(&(-angle).to_be_bytes());
            frames.push(CanFrame::standard(id, &d).expect("frame"));
        }
        frames.push(
            CanFrame::standard(0x2A8, &[0, 0, 0xC3, 0x50, 0xFF, 0xF4, 0x40, 0]).expect("frame"),
        );
        for id in 0x251..=0x256u16 {
            frames.push(
                CanFrame::standard(id, &[0x05, 0xDC, 0xF6, 0x3C, 0, 0, 0x06, 0x23]).expect("frame"),
            );
        }
        if tick.is_multiple_of(5) {
            for id in 0x261..=0x266u16 {
                frames.push(
                    CanFrame::standard(id, &[0x01, 0xE0, 0, 25, 25, 0x40, 0, 0]).expect("frame"),
                );
            }
        }
    }
    frames
}

fn bench_decode_and_apply(frames: &[CanFrame]) {
    let rounds = 2_000;
    let mut state = PiperState::default();
    let now = tokio::time::Instant::now();
    let start = WallClock::now();
    for round in 0..rounds {
        for (i, frame) in frames.iter().enumerate() {
            if let Ok(Some(message)) = decode(black_box(frame)) {
                state.apply(
                    &message,
                    Duration::from_micros((round * frames.len() + i) as u64),
                    now,
                );
            }
        }
    }
    let elapsed = start.elapsed();
    let n = (rounds * frames.len()) as f64;
    black_box(&state);
    println!(
        "decode + state update: {:.1} ns/frame, {:.2} M frames/s on one core ({} frames)",
        elapsed.as_nanos() as f64 / n,
        n / elapsed.as_secs_f64() / 1e6,
        n
    );
}

/// A bus that hands out the feedback mix as fast as the receiver takes it.
struct FloodBus {
    frames: Vec<CanFrame>,
    next: AtomicU64,
    limit: u64,
}

#[async_trait]
impl CanBus for FloodBus {
    async fn send(&self, _frame: CanFrame) -> Result<(), BusError> {
        Ok(())
    }

    async fn recv(&self) -> Result<ReceivedFrame, BusError> {
        let n = self.next.fetch_add(1, Ordering::Relaxed);
        if n >= self.limit {
            std::future::pending::<()>().await;
        }
        // Yield now and then so the runtime's other tasks (link monitor) run, as on a real bus.
        if n.is_multiple_of(64) {
            tokio::task::yield_now().await;
        }
        let frame = self.frames[(n % self.frames.len() as u64) as usize];
        Ok(ReceivedFrame {
            frame,
            timestamp: Duration::from_micros(n),
        })
    }

    async fn close(&self) {}

    fn name(&self) -> &str {
        "flood"
    }
}

fn bench_receive_task(frames: Vec<CanFrame>) {
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_time()
        .build()
        .expect("runtime");
    let limit = 3_000_000u64;
    let flood = Arc::new(FloodBus {
        frames,
        next: AtomicU64::new(0),
        limit,
    });
    runtime.block_on(async {
        let timeouts = Timeouts { first_feedback: None, ..Timeouts::default() };
        let piper = PiperBuilder::new(flood.clone())
            .timeouts(timeouts)
            .firmware(FirmwareSelection::Forced(FirmwareVersion::new(1, 8, 8)))
            .connect()
            .await
            .expect("connect");
        let start = WallClock::now();
        while flood.next.load(Ordering::Relaxed) < limit {
            tokio::time::sleep(Duration::from_millis(5)).await;
        }
        let elapsed = start.elapsed();
        let seq = piper.state().arm_status.map_or(0, |s| s.seq);
        println!(
            "receive task (bus recv + decode + watch update + rates): {:.1} ns/frame, {:.2} M frames/s \
             sustained on one core = {:.0}x a real arm's 3040 frames/s ({} status updates)",
            elapsed.as_nanos() as f64 / limit as f64,
            limit as f64 / elapsed.as_secs_f64() / 1e6,
            limit as f64 / elapsed.as_secs_f64() / 3040.0,
            seq
        );
        piper.disconnect().await;
    });
}

fn main() {
    let frames = feedback_mix();
    assert_eq!(frames.len(), 3040);
    bench_decode_and_apply(&frames);
    bench_receive_task(frames);
}
