//! socketcand over loopback TCP, real clock: frames per second from one client through the
//! server to another, and the round trip client → server → bus node → server → client.
//! Prints figures. Run: `cargo bench -p armhil-bus --bench socketcand`.

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

/// One client sends FRAMES 8-byte frames, another receives them: frames/s end to end.
async fn throughput(bitrate_bps: u32) -> f64 {
    let (server, _bus, addr) = server(bitrate_bps).await;
    let tx = SocketcandBus::connect(&addr, "can0").await.unwrap();
    let rx = SocketcandBus::connect(&addr, "can0").await.unwrap();
    let start = Instant::now();
    let receiver = tokio::spawn(async move {
        for i in 0..FRAMES {
            let frame = rx.recv().await.expect("frame").frame;
            assert_eq!(frame.data()[..4], i.to_le_bytes(), "order or loss");
        }
    });
    for i in 0..FRAMES {
        let mut data = [0u8; 8];
        data[..4].copy_from_slice(&i.to_le_bytes());
        send(&tx, CanFrame::standard(0x123, &data).unwrap()).await;
    }
    receiver.await.expect("receiver");
    let elapsed = start.elapsed();
    assert_eq!(server.stats().frames_dropped, 0);
    f64::from(FRAMES) / elapsed.as_secs_f64()
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

fn main() {
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .expect("runtime");
    runtime.block_on(async {
        for bitrate in [1_000_000, 1_000_000_000] {
            let fps = throughput(bitrate).await;
            println!(
                "socketcand throughput, modelled wire at {} Mbit/s: {fps:.0} frames/s ({FRAMES} frames, client to client)",
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
    });
}
