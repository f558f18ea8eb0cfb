//! Tests of the virtual bus: timing, arbitration, queues, determinism, faults, lifecycle.

use std::time::Duration;

use super::*;
use crate::timing::frame_bits;
use crate::CanId;

fn sff(id: u16, data: &[u8]) -> CanFrame {
    CanFrame::standard(id, data).unwrap()
}

fn config(bitrate_bps: u32, stuffing: StuffingPolicy) -> VirtualBusConfig {
    VirtualBusConfig {
        bitrate_bps,
        stuffing,
        ..VirtualBusConfig::default()
    }
}

/// Everything a node has received so far, after letting the bus run for `settle`.
async fn drain(node: &VirtualNode, settle: Duration) -> Vec<ReceivedFrame> {
    tokio::time::sleep(settle).await;
    let mut frames = Vec::new();
    while let Some(frame) = node.try_recv().unwrap() {
        frames.push(frame);
    }
    frames
}

fn ids(frames: &[ReceivedFrame]) -> Vec<u32> {
    frames.iter().map(|f| f.frame.raw_id()).collect()
}

fn micros(frames: &[ReceivedFrame]) -> Vec<u128> {
    frames.iter().map(|f| f.timestamp.as_micros()).collect()
}

#[tokio::test(start_paused = true)]
async fn lowest_id_wins_arbitration_among_three_nodes() {
    let bus = VirtualBus::new(config(1_000_000, StuffingPolicy::None));
    let a = bus.attach("a");
    let b = bus.attach("b");
    let c = bus.attach("c");
    let observer = bus.attach("observer");
    // Queued at the same instant, in the opposite order of priority.
    a.send(sff(0x300, &[0; 8])).await.unwrap();
    b.send(sff(0x200, &[0; 8])).await.unwrap();
    c.send(sff(0x100, &[0; 8])).await.unwrap();
    let got = drain(&observer, Duration::from_millis(5)).await;
    assert_eq!(ids(&got), vec![0x100, 0x200, 0x300]);
    // Back to back, 111 bit times each.
    assert_eq!(micros(&got), vec![111, 222, 333]);
    // Senders see each other's frames but not their own.
    assert_eq!(ids(&drain(&c, Duration::ZERO).await), vec![0x200, 0x300]);
    assert_eq!(ids(&drain(&a, Duration::ZERO).await), vec![0x100, 0x200]);
}

#[tokio::test(start_paused = true)]
async fn a_frame_on_the_wire_is_not_preempted_and_later_frames_arbitrate_at_its_end() {
    let bus = VirtualBus::new(config(1_000_000, StuffingPolicy::None));
    let a = bus.attach("a");
    let b = bus.attach("b");
    let observer = bus.attach("observer");
    a.send(sff(0x400, &[0; 8])).await.unwrap();
    a.send(sff(0x401, &[0; 8])).await.unwrap();
    // Let 0x400 start alone, then a higher-priority frame arrives while it is on the wire.
    tokio::task::yield_now().await;
    tokio::task::yield_now().await;
    b.send(sff(0x001, &[0; 8])).await.unwrap();
    let got = drain(&observer, Duration::from_millis(5)).await;
    assert_eq!(ids(&got), vec![0x400, 0x001, 0x401]);
    assert_eq!(micros(&got), vec![111, 222, 333]);
}

#[tokio::test(start_paused = true)]
async fn extended_frame_loses_to_standard_frame_with_same_base_id() {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let a = bus.attach("a");
    let b = bus.attach("b");
    let observer = bus.attach("observer");
    a.send(CanFrame::extended(0x123 << 18, &[1]).unwrap())
        .await
        .unwrap();
    b.send(sff(0x123, &[1])).await.unwrap();
    let got = drain(&observer, Duration::from_millis(2)).await;
    assert_eq!(
        got.iter().map(|f| f.frame.id()).collect::<Vec<_>>(),
        vec![CanId::Standard(0x123), CanId::Extended(0x123 << 18)]
    );
}

async fn first_two_timestamps(bitrate_bps: u32, stuffing: StuffingPolicy) -> Vec<u128> {
    let bus = VirtualBus::new(config(bitrate_bps, stuffing));
    let tx = bus.attach("tx");
    let rx = bus.attach("rx");
    let frame = sff(0x2A1, &[0x00, 0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77]);
    tx.send(frame).await.unwrap();
    tx.send(frame).await.unwrap();
    let got = drain(&rx, Duration::from_millis(10)).await;
    assert_eq!(got.len(), 2);
    got.iter().map(|f| f.timestamp.as_nanos()).collect()
}

#[tokio::test(start_paused = true)]
async fn an_eight_byte_standard_frame_takes_its_documented_bit_times() {
    // 47 + 8*8 = 111 bits without stuffing, 55 + 10*8 = 135 worst case.
    assert_eq!(
        first_two_timestamps(1_000_000, StuffingPolicy::None).await,
        vec![111_000, 222_000]
    );
    assert_eq!(
        first_two_timestamps(500_000, StuffingPolicy::None).await,
        vec![222_000, 444_000]
    );
    assert_eq!(
        first_two_timestamps(1_000_000, StuffingPolicy::WorstCase).await,
        vec![135_000, 270_000]
    );
    assert_eq!(
        first_two_timestamps(500_000, StuffingPolicy::WorstCase).await,
        vec![270_000, 540_000]
    );
    let frame = sff(0x2A1, &[0x00, 0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77]);
    let exact_bits = u128::from(frame_bits(&frame, StuffingPolicy::Exact));
    assert!((111..=135).contains(&exact_bits));
    assert_eq!(
        first_two_timestamps(500_000, StuffingPolicy::Exact).await,
        vec![exact_bits * 2_000, exact_bits * 4_000]
    );
}

fn fd_config(nominal_bps: u32, data_bps: u32) -> VirtualBusConfig {
    VirtualBusConfig {
        bitrate_bps: nominal_bps,
        data_bitrate_bps: Some(data_bps),
        ..VirtualBusConfig::default()
    }
}

fn fd_frame(id: u16, data: &[u8], brs: bool) -> CanFrame {
    let flags = crate::FdFlags { brs, esi: false };
    CanFrame::fd(CanId::Standard(id), data, flags).unwrap()
}

/// Computed by hand, independently of `timing`: id 0x555 and 0x55 bytes never make five
/// equal bits, so a 64-byte frame with BRS is SOF + 11 id bits + RRS, IDE, FDF, res, BRS (17)
/// and ACK, ACK delimiter, EOF (7), intermission (3): 29 bits at 1 Mbit/s = 29 µs; ESI + DLC
/// (5) + 512 data bits + stuff count (4) + CRC-21 + 7 fixed stuff bits + CRC delimiter: 550
/// bits at 5 Mbit/s = 110 µs. 139 µs in all. 64 zero bytes add one stuff bit per five zeros,
/// 102 bits = 20.4 µs.
#[tokio::test(start_paused = true)]
async fn a_64_byte_fd_frame_at_1m_5m_takes_its_time_on_the_wire() {
    let bus = VirtualBus::new(fd_config(1_000_000, 5_000_000));
    let tx = bus.attach("tx");
    let rx = bus.attach("rx");
    let sparse = fd_frame(0x555, &[0x55; 64], true);
    let zeros = fd_frame(0x555, &[0; 64], true);
    let slow = fd_frame(0x555, &[0x55; 64], false);
    tx.send(sparse).await.unwrap();
    tx.send(zeros).await.unwrap();
    tx.send(slow).await.unwrap();
    tx.send(sff(0x2A1, &[0; 8])).await.unwrap();
    let got = drain(&rx, Duration::from_millis(5)).await;
    let nanos: Vec<u128> = got.iter().map(|f| f.timestamp.as_nanos()).collect();
    let sparse_ns = 29_000 + 550 * 200;
    let zeros_ns = 29_000 + (550 + 102) * 200;
    // Without BRS: all 579 bits at 1 Mbit/s.
    let slow_ns = 579_000;
    // The classic frame after them: 8 zero bytes, exact stuffing (the bus default).
    let classic_ns = 1000 * u128::from(frame_bits(&sff(0x2A1, &[0; 8]), StuffingPolicy::Exact));
    assert_eq!(
        nanos,
        [
            sparse_ns,
            sparse_ns + zeros_ns,
            sparse_ns + zeros_ns + slow_ns,
            sparse_ns + zeros_ns + slow_ns + classic_ns
        ]
    );
    assert_eq!(
        got.iter().map(|f| f.frame).collect::<Vec<_>>(),
        [sparse, zeros, slow, sff(0x2A1, &[0; 8])]
    );
    let stats = bus.stats();
    assert_eq!(stats.frames, 4);
    assert_eq!(
        stats.busy,
        Duration::from_nanos((sparse_ns + zeros_ns + slow_ns + classic_ns) as u64)
    );
}

#[tokio::test(start_paused = true)]
async fn a_classic_bus_refuses_fd_frames_naming_the_node() {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let tx = bus.attach("arm");
    let rx = bus.attach("rx");
    let error = tx.send(fd_frame(0x123, &[0; 64], true)).await.unwrap_err();
    assert!(
        matches!(&error, BusError::Io { iface, .. } if iface == "arm"),
        "{error:?}"
    );
    let text = error.to_string();
    assert!(
        text.starts_with(
            "CAN interface arm: CAN FD frame 123 (64 bytes) refused: this virtual bus is \
             classic CAN"
        ),
        "{text}"
    );
    assert!(
        text.contains("VirtualBusConfig::data_bitrate_bps"),
        "{text}"
    );
    // Also when sent with a delay, and without BRS: the format is what a classic bus lacks.
    let later = tx.send_after(fd_frame(0x124, &[1], false), Duration::from_millis(1));
    assert!(later.await.is_err());
    // Nothing reached the wire; classic frames still do.
    tx.send(sff(0x125, &[1])).await.unwrap();
    let got = drain(&rx, Duration::from_millis(3)).await;
    assert_eq!(ids(&got), [0x125]);
    assert_eq!(bus.stats().frames, 1);
    assert_eq!(tx.pending_tx(), 0);
}

#[tokio::test(start_paused = true)]
async fn fd_and_classic_frames_arbitrate_by_identifier() {
    let bus = VirtualBus::new(fd_config(500_000, 2_000_000));
    let a = bus.attach("a");
    let b = bus.attach("b");
    let observer = bus.attach("observer");
    a.send(sff(0x300, &[1])).await.unwrap();
    b.send(fd_frame(0x200, &[2; 48], true)).await.unwrap();
    a.send(fd_frame(0x100, &[3; 12], false)).await.unwrap();
    let got = drain(&observer, Duration::from_millis(5)).await;
    // a's own frames leave in FIFO order; b's FD frame wins against a's classic 0x300.
    assert_eq!(ids(&got), [0x200, 0x300, 0x100]);
    assert!(got[0].frame.is_fd() && got[0].frame.brs());
    assert!(!got[1].frame.is_fd());
    assert!(got[2].frame.is_fd() && !got[2].frame.brs());
}

#[tokio::test(start_paused = true)]
async fn frames_sent_after_an_idle_gap_start_when_sent() {
    let bus = VirtualBus::new(config(1_000_000, StuffingPolicy::None));
    let tx = bus.attach("tx");
    let rx = bus.attach("rx");
    tokio::time::sleep(Duration::from_millis(7)).await;
    tx.send(sff(0x10, &[0; 8])).await.unwrap();
    let got = drain(&rx, Duration::from_millis(3)).await;
    assert_eq!(micros(&got), vec![7_111]);
}

#[tokio::test(start_paused = true)]
async fn sustained_overload_fills_the_queue_then_reports_tx_queue_full() {
    let bus = VirtualBus::new(config(1_000_000, StuffingPolicy::None));
    let tx = bus.attach_with(
        "tx",
        NodeOptions {
            receive_own: false,
            tx_queue_len: Some(20),
        },
    );
    let rx = bus.attach("rx");
    // 111 µs frames: about 9 fit in a millisecond; offer 12 per millisecond, so the queue
    // grows by about 3 a millisecond. Frames that started by m ms: ceil(1000 m / 111), so after
    // the sends at m ms the queue holds 12, 14, 17, 20 (full), then overflows at 4 ms.
    let mut accepted = 0u64;
    let mut first_error_at_ms = None;
    for ms in 0..20u32 {
        for _ in 0..12 {
            match tx.send(sff(0x100, &[0; 8])).await {
                Ok(()) => accepted += 1,
                Err(BusError::TxQueueFull { capacity }) => {
                    assert_eq!(capacity, 20);
                    first_error_at_ms.get_or_insert(ms);
                }
                Err(other) => panic!("unexpected {other}"),
            }
        }
        tokio::time::sleep(Duration::from_millis(1)).await;
    }
    let first_error_at_ms = first_error_at_ms.expect("overload never reported");
    // Not at once (the queue absorbs the excess first) but within a few milliseconds.
    assert_eq!(first_error_at_ms, 4);
    let stats = bus.stats();
    assert_eq!(stats.tx_queue_full, 20 * 12 - accepted);
    assert!(stats.load_percent > 95.0, "load {}", stats.load_percent);
    let got = drain(&rx, Duration::from_millis(5)).await;
    assert_eq!(got.len() as u64, accepted);
    // Back to back while saturated.
    for pair in got.windows(2) {
        assert_eq!(
            pair[1].timestamp - pair[0].timestamp,
            Duration::from_micros(111)
        );
    }
}

#[tokio::test(start_paused = true)]
async fn per_node_queue_length_overrides_the_default() {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let tx = bus.attach_with(
        "tx",
        NodeOptions {
            receive_own: false,
            tx_queue_len: Some(3),
        },
    );
    for _ in 0..3 {
        tx.send(sff(0x1, &[])).await.unwrap();
    }
    assert_eq!(tx.pending_tx(), 3);
    assert!(matches!(
        tx.send(sff(0x1, &[])).await,
        Err(BusError::TxQueueFull { capacity: 3 })
    ));
}

/// A busy little bus: three talkers at different periods, a seeded lossy link.
async fn scripted_run() -> Vec<(Duration, String)> {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    bus.faults()
        .inject(Fault::drop_with_probability(FrameFilter::All, 0.2, 42));
    let observer = bus.attach("observer");
    let mut tasks = Vec::new();
    for (index, period_us) in [(0u16, 1000u64), (1, 2000), (2, 3000)] {
        let node = bus.attach(&format!("n{index}"));
        tasks.push(tokio::spawn(async move {
            let mut tick = tokio::time::interval(Duration::from_micros(period_us));
            for seq in 0..30u8 {
                tick.tick().await;
                for k in 0..3u16 {
                    let id = 0x700 - index * 0x100 - k;
                    let _ = node.send(sff(id, &[seq, k as u8, index as u8])).await;
                }
            }
        }));
    }
    for task in tasks {
        task.await.unwrap();
    }
    drain(&observer, Duration::from_millis(10))
        .await
        .into_iter()
        .map(|f| (f.timestamp, f.frame.to_string()))
        .collect()
}

#[test]
fn the_same_run_twice_gives_identical_timestamps_and_order() {
    let run = || {
        tokio::runtime::Builder::new_current_thread()
            .enable_time()
            .start_paused(true)
            .build()
            .unwrap()
            .block_on(scripted_run())
    };
    let first = run();
    let second = run();
    assert!(first.len() > 100, "only {} frames", first.len());
    assert_eq!(first, second);
    // Timestamps strictly increase: one frame at a time on the wire.
    assert!(first.windows(2).all(|pair| pair[0].0 < pair[1].0));
}

#[tokio::test(start_paused = true)]
async fn stats_count_frames_per_id_and_load() {
    let bus = VirtualBus::new(config(1_000_000, StuffingPolicy::None));
    let tx = bus.attach("tx");
    for _ in 0..3 {
        tx.send(sff(0x10, &[0; 8])).await.unwrap();
    }
    tx.send(CanFrame::extended(0x10, &[]).unwrap())
        .await
        .unwrap();
    tokio::time::sleep(Duration::from_millis(1)).await;
    let stats = bus.stats();
    assert_eq!(stats.frames, 4);
    assert_eq!(stats.frames_by_id.get(&CanId::Standard(0x10)), Some(&3));
    assert_eq!(stats.frames_by_id.get(&CanId::Extended(0x10)), Some(&1));
    assert_eq!(stats.bits, 3 * 111 + 67);
    assert_eq!(stats.busy, Duration::from_micros(3 * 111 + 67));
    assert_eq!(stats.elapsed, Duration::from_millis(1));
    assert!((stats.load_percent - 40.0).abs() < 1e-9);
    bus.reset_stats();
    tokio::time::sleep(Duration::from_millis(1)).await;
    let stats = bus.stats();
    assert_eq!(stats.frames, 0);
    assert_eq!(stats.load_percent, 0.0);
}

#[tokio::test(start_paused = true)]
async fn receive_own_echoes_the_senders_frames() {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let echo = bus.attach_with(
        "echo",
        NodeOptions {
            receive_own: true,
            tx_queue_len: None,
        },
    );
    let plain = bus.attach("plain");
    echo.send(sff(0x5, &[1])).await.unwrap();
    plain.send(sff(0x6, &[2])).await.unwrap();
    assert_eq!(
        ids(&drain(&echo, Duration::from_millis(1)).await),
        vec![0x5, 0x6]
    );
    assert_eq!(ids(&drain(&plain, Duration::ZERO).await), vec![0x5]);
}

#[tokio::test(start_paused = true)]
async fn tap_sees_every_frame_and_closes_when_the_bus_is_gone() {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let mut tap = bus.tap();
    let a = bus.attach("a");
    let b = bus.attach("b");
    a.send(sff(0x1, &[])).await.unwrap();
    b.send(sff(0x2, &[])).await.unwrap();
    assert_eq!(tap.recv().await.unwrap().frame.raw_id(), 0x1);
    assert_eq!(tap.recv().await.unwrap().frame.raw_id(), 0x2);
    drop((bus, a));
    // A remaining node keeps the wire alive.
    b.send(sff(0x3, &[])).await.unwrap();
    assert_eq!(tap.recv().await.unwrap().frame.raw_id(), 0x3);
    drop(b);
    // The wire task exits, dropping the tap's sender.
    let end = tokio::time::timeout(Duration::from_secs(1), tap.recv()).await;
    assert!(matches!(
        end,
        Ok(Err(tokio::sync::broadcast::error::RecvError::Closed))
    ));
}

#[tokio::test(start_paused = true)]
async fn idle_bus_lets_virtual_time_advance() {
    // A wire task that spun while idle would keep the paused runtime busy, and this sleep
    // would never be auto-advanced.
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let node = bus.attach("a");
    let started = tokio::time::Instant::now();
    tokio::time::sleep(Duration::from_secs(3600)).await;
    assert_eq!(started.elapsed(), Duration::from_secs(3600));
    assert_eq!(bus.now(), Duration::from_secs(3600));
    assert_eq!(node.try_recv().unwrap(), None);
}

#[tokio::test(start_paused = true)]
async fn close_ends_pending_and_later_receives() {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let node = bus.attach("a");
    let other = bus.attach("b");
    let waiting = {
        let node = node.clone();
        tokio::spawn(async move { node.recv().await })
    };
    tokio::task::yield_now().await;
    node.close().await;
    assert!(matches!(waiting.await.unwrap(), Err(BusError::Closed)));
    assert!(matches!(node.recv().await, Err(BusError::Closed)));
    assert!(matches!(
        node.send(sff(1, &[])).await,
        Err(BusError::Closed)
    ));
    // The rest of the bus carries on.
    other.send(sff(2, &[])).await.unwrap();
    tokio::time::sleep(Duration::from_millis(1)).await;
    assert_eq!(bus.stats().frames, 1);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn works_under_the_real_clock() {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let tx = bus.attach("tx");
    let rx = bus.attach("rx");
    for seq in 0..20u8 {
        tx.send(sff(0x100 + u16::from(seq), &[seq])).await.unwrap();
        if seq % 5 == 4 {
            tokio::time::sleep(Duration::from_millis(2)).await;
        }
    }
    let mut got = Vec::new();
    for _ in 0..20 {
        let frame = tokio::time::timeout(Duration::from_secs(5), rx.recv())
            .await
            .unwrap()
            .unwrap();
        got.push(frame);
    }
    assert_eq!(ids(&got), (0x100..0x114).collect::<Vec<_>>());
    assert!(got
        .windows(2)
        .all(|pair| pair[0].timestamp < pair[1].timestamp));
}

mod faults {
    use super::*;

    async fn bus_with_faults() -> (VirtualBus, VirtualNode, VirtualNode, FaultHandle) {
        let bus = VirtualBus::new(config(1_000_000, StuffingPolicy::None));
        let tx = bus.attach("tx");
        let rx = bus.attach("rx");
        let faults = bus.faults();
        (bus, tx, rx, faults)
    }

    #[tokio::test(start_paused = true)]
    async fn drop_all_loses_every_frame_until_removed() {
        let (bus, tx, rx, faults) = bus_with_faults().await;
        let fault = faults.inject(Fault::drop(FrameFilter::All));
        tx.send(sff(0x1, &[])).await.unwrap();
        tx.send(sff(0x2, &[])).await.unwrap();
        assert!(drain(&rx, Duration::from_millis(1)).await.is_empty());
        assert!(faults.remove(fault));
        assert!(!faults.remove(fault));
        tx.send(sff(0x3, &[])).await.unwrap();
        assert_eq!(ids(&drain(&rx, Duration::from_millis(1)).await), vec![0x3]);
        let stats = bus.stats();
        assert_eq!((stats.dropped, stats.frames), (2, 1));
    }

    #[tokio::test(start_paused = true)]
    async fn drop_by_id_spares_other_ids() {
        let (_bus, tx, rx, faults) = bus_with_faults().await;
        faults.inject(Fault::drop(FrameFilter::Id(CanId::Standard(0x2))));
        for id in 1..=3 {
            tx.send(sff(id, &[])).await.unwrap();
        }
        assert_eq!(
            ids(&drain(&rx, Duration::from_millis(1)).await),
            vec![0x1, 0x3]
        );
    }

    async fn survivors_with_seed(seed: u64) -> Vec<u8> {
        let (_bus, tx, rx, faults) = bus_with_faults().await;
        faults.inject(Fault::drop_with_probability(FrameFilter::All, 0.5, seed));
        for seq in 0..200u8 {
            tx.send(sff(0x10, &[seq])).await.unwrap();
            if seq % 8 == 7 {
                tokio::time::sleep(Duration::from_millis(1)).await;
            }
        }
        drain(&rx, Duration::from_millis(5))
            .await
            .iter()
            .map(|f| f.frame.data()[0])
            .collect()
    }

    #[tokio::test(start_paused = true)]
    async fn probabilistic_drop_is_seeded() {
        let first = survivors_with_seed(1).await;
        assert_eq!(first, survivors_with_seed(1).await);
        assert_ne!(first, survivors_with_seed(2).await);
        assert!(
            (60..140).contains(&first.len()),
            "{} of 200 survived",
            first.len()
        );
    }

    #[tokio::test(start_paused = true)]
    async fn delay_holds_frames_back() {
        let (_bus, tx, rx, faults) = bus_with_faults().await;
        faults.inject(Fault::delay(
            FrameFilter::Id(CanId::Standard(0x1)),
            Duration::from_micros(500),
        ));
        tx.send(sff(0x1, &[0; 8])).await.unwrap();
        let other = rx.clone();
        let observer = _bus.attach("observer");
        other.send(sff(0x2, &[0; 8])).await.unwrap();
        let got = drain(&observer, Duration::from_millis(2)).await;
        // 0x2 goes first; 0x1 starts 500 µs late.
        assert_eq!(ids(&got), vec![0x2, 0x1]);
        assert_eq!(micros(&got), vec![111, 611]);
    }

    #[tokio::test(start_paused = true)]
    async fn corrupt_uses_wire_time_delivers_nothing_and_counts_an_error() {
        let (bus, tx, rx, faults) = bus_with_faults().await;
        faults.inject(Fault::corrupt(FrameFilter::All).times(1));
        tx.send(sff(0x1, &[0; 8])).await.unwrap();
        tx.send(sff(0x2, &[0; 8])).await.unwrap();
        let got = drain(&rx, Duration::from_millis(1)).await;
        assert_eq!(ids(&got), vec![0x2]);
        assert_eq!(micros(&got), vec![222]);
        let stats = bus.stats();
        assert_eq!((stats.errors, stats.frames, stats.bits), (1, 1, 222));
    }

    #[tokio::test(start_paused = true)]
    async fn duplicate_delivers_twice_back_to_back() {
        let (bus, tx, rx, faults) = bus_with_faults().await;
        faults.inject(Fault::duplicate(FrameFilter::Id(CanId::Standard(0x1))));
        tx.send(sff(0x1, &[0; 8])).await.unwrap();
        tx.send(sff(0x2, &[0; 8])).await.unwrap();
        let got = drain(&rx, Duration::from_millis(1)).await;
        assert_eq!(ids(&got), vec![0x1, 0x1, 0x2]);
        assert_eq!(micros(&got), vec![111, 222, 333]);
        assert_eq!(
            bus.stats().frames_by_id.get(&CanId::Standard(0x1)),
            Some(&2)
        );
    }

    #[tokio::test(start_paused = true)]
    async fn silenced_node_sends_nothing_but_still_receives() {
        let (_bus, tx, rx, faults) = bus_with_faults().await;
        let silence = faults.silence_node("tx");
        tx.send(sff(0x1, &[])).await.unwrap();
        rx.send(sff(0x2, &[])).await.unwrap();
        tokio::time::sleep(Duration::from_millis(1)).await;
        assert!(drain(&rx, Duration::ZERO).await.is_empty());
        assert_eq!(ids(&drain(&tx, Duration::ZERO).await), vec![0x2]);
        faults.remove(silence);
        tx.send(sff(0x3, &[])).await.unwrap();
        assert_eq!(ids(&drain(&rx, Duration::from_millis(1)).await), vec![0x3]);
    }

    #[tokio::test(start_paused = true)]
    async fn bus_off_rejects_sends_and_receives_nothing_then_recovers() {
        let (bus, tx, rx, faults) = bus_with_faults().await;
        tx.send(sff(0x1, &[])).await.unwrap();
        tx.send(sff(0x2, &[])).await.unwrap();
        tokio::task::yield_now().await;
        tokio::task::yield_now().await;
        assert_eq!(faults.bus_off("tx", Duration::from_millis(10)), 1);
        assert!(matches!(
            tx.send(sff(0x3, &[])).await,
            Err(BusError::BusOff)
        ));
        rx.send(sff(0x4, &[])).await.unwrap();
        tokio::time::sleep(Duration::from_millis(2)).await;
        // 0x1 was already on the wire; 0x2 was flushed from the queue.
        assert_eq!(ids(&drain(&rx, Duration::ZERO).await), vec![0x1]);
        assert!(drain(&tx, Duration::ZERO).await.is_empty());
        assert_eq!(bus.stats().dropped, 1);
        tokio::time::sleep(Duration::from_millis(10)).await;
        tx.send(sff(0x5, &[])).await.unwrap();
        rx.send(sff(0x6, &[])).await.unwrap();
        assert_eq!(ids(&drain(&rx, Duration::from_millis(1)).await), vec![0x5]);
        assert_eq!(ids(&drain(&tx, Duration::ZERO).await), vec![0x6]);
    }

    #[tokio::test(start_paused = true)]
    async fn faults_expire_after_their_duration() {
        let (_bus, tx, rx, faults) = bus_with_faults().await;
        faults.inject(Fault::drop(FrameFilter::All).for_duration(Duration::from_millis(5)));
        tx.send(sff(0x1, &[])).await.unwrap();
        tokio::time::sleep(Duration::from_millis(5)).await;
        tx.send(sff(0x2, &[])).await.unwrap();
        assert_eq!(ids(&drain(&rx, Duration::from_millis(1)).await), vec![0x2]);
    }

    #[tokio::test(start_paused = true)]
    async fn clear_removes_all_faults() {
        let (_bus, tx, rx, faults) = bus_with_faults().await;
        faults.inject(Fault::drop(FrameFilter::All));
        faults.inject(Fault::corrupt(FrameFilter::All));
        faults.clear();
        tx.send(sff(0x1, &[])).await.unwrap();
        assert_eq!(ids(&drain(&rx, Duration::from_millis(1)).await), vec![0x1]);
    }
}
