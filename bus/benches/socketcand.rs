//! socketcand over loopback TCP, real clock: frames per second from one client through the
//! server to another, the round trip client → server → bus node → server → client, and the
//! fan-out of an arm's feedback to 1, 50, 100 and 200 clients at once (what each receives).
//! Prints figures. Run: `cargo bench -p armhil-bus --bench socketcand`.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use bus::socketcand::{ServerConfig, SocketcandBus, SocketcandServer};
use bus::virtual_bus::{NodeOptions, VirtualBus, VirtualBusConfig};
use bus::{BusError, CanBus, CanFrame};

const FRAMES: u32 = 50_000;
const PINGS: usize = 2_000;

async fn send(bus: &dyn CanBus, frame: CanFrame) {
    loop {
        match bus.send(frame).await {
            Ok(()) => return,
            Err(BusError::TxQueueFull { .. }) => tokio::task::yield_now().await,
            Err(error) => panic!("send failed: {error}"),
        }
    }
}

async fn server(bitrate_bps: u32) -> (SocketcandServer, VirtualBus, String) {
    let bus = VirtualBus::new(VirtualBusConfig {
        bitrate_bps,
        ..VirtualBusConfig::default()
    });
    let server = SocketcandServer::bind("127.0.0.1:0", bus.clone(), ServerConfig::default())
        .await
        .expect("server binds");
    let addr = server.local_addr().to_string();
    (server, bus, addr)
}

/// One client sends FRAMES 8-byte frames, another receives them: frames/s end to end, and
/// how many the receiver missed (the server drops frames for a receiver that falls behind,
/// which on a loaded machine can happen with the wire at 1 Gbit/s).
async fn throughput(bitrate_bps: u32) -> (f64, u32) {
    let (_server, _bus, addr) = server(bitrate_bps).await;
    let tx = SocketcandBus::connect(&addr, "can0").await.unwrap();
    let rx = SocketcandBus::connect(&addr, "can0").await.unwrap();
    let start = Instant::now();
    let receiver = tokio::spawn(async move {
        let mut received = 0u32;
        // Until the last frame, or until nothing comes for 2 s (it was dropped).
        while let Ok(Ok(got)) = tokio::time::timeout(Duration::from_secs(2), rx.recv()).await {
            received += 1;
            let mut index = [0u8; 4];
            index.copy_from_slice(&got.frame.data()[..4]);
            if u32::from_le_bytes(index) == FRAMES - 1 {
                break;
            }
        }
        received
    });
    for i in 0..FRAMES {
        let mut data = [0u8; 8];
        data[..4].copy_from_slice(&i.to_le_bytes());
        send(&tx, CanFrame::standard(0x123, &data).unwrap()).await;
    }
    let received = receiver.await.expect("receiver");
    let elapsed = start.elapsed();
    (
        f64::from(received) / elapsed.as_secs_f64(),
        FRAMES - received,
    )
}

/// Client → server → a node on the bus that answers at once → server → client.
async fn round_trip() -> Vec<Duration> {
    let (_server, bus, addr) = server(1_000_000).await;
    let echo = bus.attach_with(
        "echo",
        NodeOptions {
            receive_own: false,
            tx_queue_len: Some(64),
        },
    );
    tokio::spawn(async move {
        while let Ok(received) = echo.recv().await {
            let reply = CanFrame::standard(0x2A1, received.frame.data()).unwrap();
            send(&echo, reply).await;
        }
    });
    let client = SocketcandBus::connect(&addr, "can0").await.unwrap();
    let mut times = Vec::with_capacity(PINGS);
    for i in 0..PINGS {
        let start = Instant::now();
        let tag = (i as u32).to_le_bytes();
        send(&client, CanFrame::standard(0x151, &tag).unwrap()).await;
        loop {
            let frame = client.recv().await.expect("reply").frame;
            if frame.data() == tag {
                break;
            }
        }
        times.push(start.elapsed());
    }
    times.sort();
    times
}

/// Feedback the Piper emulator puts on its bus: 14 frames every 5 ms (0x2A1..0x2A8 and
/// 0x251..0x256), about 2 800 frames/s.
const FEEDBACK_IDS: [u16; 14] = [
    0x2A1, 0x2A2, 0x2A3, 0x2A4, 0x2A5, 0x2A6, 0x2A7, 0x2A8, 0x251, 0x252, 0x253, 0x254, 0x255,
    0x256,
];
const FEEDBACK_PERIOD: Duration = Duration::from_millis(5);
/// Measured after a warm-up, for this long, per client count.
const FAN_OUT_WARM_UP: Duration = Duration::from_millis(500);
const FAN_OUT_WINDOW: Duration = Duration::from_secs(3);

/// What `clients` connected clients received of the feedback in the window.
struct FanOut {
    clients: usize,
    /// Frames the arm put on the bus per second.
    produced: f64,
    /// Frames per second each client received, sorted.
    per_client: Vec<f64>,
    /// Frames the server dropped (client queues full) in the window.
    dropped: u64,
}

/// The arm's feedback served to `clients` socketcand clients at once (each one of armhil's
/// own clients, all in this process: the figures are for server and clients together on the
/// machine's cores).
async fn fan_out(clients: usize) -> FanOut {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let config = ServerConfig {
        // Past the default cap of 128: the figures say what the cap protects.
        max_clients: clients + 1,
        ..ServerConfig::default()
    };
    let server = SocketcandServer::bind("127.0.0.1:0", bus.clone(), config)
        .await
        .expect("server binds");
    let addr = server.local_addr().to_string();
    let mut counts = Vec::with_capacity(clients);
    let mut readers = Vec::with_capacity(clients);
    for _ in 0..clients {
        let client = SocketcandBus::connect(&addr, "can0")
            .await
            .expect("client connects");
        let count = Arc::new(AtomicU64::new(0));
        counts.push(Arc::clone(&count));
        readers.push(tokio::spawn(async move {
            while client.recv().await.is_ok() {
                count.fetch_add(1, Ordering::Relaxed);
            }
        }));
    }
    let arm = bus.attach_with(
        "arm",
        NodeOptions {
            receive_own: false,
            tx_queue_len: Some(64),
        },
    );
    let produced = Arc::new(AtomicU64::new(0));
    let producer = {
        let produced = Arc::clone(&produced);
        tokio::spawn(async move {
            let mut tick = tokio::time::interval(FEEDBACK_PERIOD);
            tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
            loop {
                tick.tick().await;
                for id in FEEDBACK_IDS {
                    send(&arm, CanFrame::standard(id, &[0x5A; 8]).unwrap()).await;
                    produced.fetch_add(1, Ordering::Relaxed);
                }
            }
        })
    };
    tokio::time::sleep(FAN_OUT_WARM_UP).await;
    let snapshot = |counts: &[Arc<AtomicU64>]| -> Vec<u64> {
        counts.iter().map(|c| c.load(Ordering::Relaxed)).collect()
    };
    let (before, produced_before, dropped_before) = (
        snapshot(&counts),
        produced.load(Ordering::Relaxed),
        server.stats().frames_dropped,
    );
    let start = Instant::now();
    tokio::time::sleep(FAN_OUT_WINDOW).await;
    let after = snapshot(&counts);
    let produced_after = produced.load(Ordering::Relaxed);
    let dropped = server.stats().frames_dropped - dropped_before;
    let seconds = start.elapsed().as_secs_f64();
    producer.abort();
    for reader in &readers {
        reader.abort();
    }
    let mut per_client: Vec<f64> = before
        .iter()
        .zip(&after)
        .map(|(b, a)| (a - b) as f64 / seconds)
        .collect();
    per_client.sort_by(f64::total_cmp);
    FanOut {
        clients,
        produced: (produced_after - produced_before) as f64 / seconds,
        per_client,
        dropped,
    }
}

fn main() {
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .expect("runtime");
    runtime.block_on(async {
        for bitrate in [1_000_000, 1_000_000_000] {
            let (fps, missed) = throughput(bitrate).await;
            println!(
                "socketcand throughput, modelled wire at {} Mbit/s: {fps:.0} frames/s ({FRAMES} frames, client to client, {missed} missed)",
                bitrate / 1_000_000
            );
        }
        let times = round_trip().await;
        let pick = |q: f64| times[((times.len() - 1) as f64 * q) as usize];
        println!(
            "socketcand round trip (client -> bus node -> client, 1 Mbit/s wire, {PINGS} pings): median {:?}, p99 {:?}, max {:?}",
            pick(0.5),
            pick(0.99),
            times[times.len() - 1]
        );
        for clients in [1, 50, 100, 200] {
            let fan = fan_out(clients).await;
            let pick = |q: f64| fan.per_client[((fan.per_client.len() - 1) as f64 * q) as usize];
            let total: f64 = fan.per_client.iter().sum();
            println!(
                "socketcand fan-out, {} clients: arm produced {:.0} frames/s; each client received min {:.0}, median {:.0}, max {:.0} frames/s ({:.0}% of the feedback at the median); {:.0} frames/s delivered in all; {} dropped by the server in {} s",
                fan.clients,
                fan.produced,
                pick(0.0),
                pick(0.5),
                pick(1.0),
                100.0 * pick(0.5) / fan.produced.max(1.0),
                total,
                fan.dropped,
                FAN_OUT_WINDOW.as_secs()
            );
        }
    });
}
