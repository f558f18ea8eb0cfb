//! Our socketcand client against our socketcand server, over real TCP on 127.0.0.1.

use std::time::Duration;

use bus::socketcand::{ConnectError, ServerConfig, SocketcandBus, SocketcandServer};
use bus::virtual_bus::{VirtualBus, VirtualBusConfig, VirtualNode};
use bus::{CanBus, CanFrame};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use tokio::time::timeout;

const WAIT: Duration = Duration::from_secs(5);

/// A server on a free port with one node (the "emulator") on its bus.
async fn server() -> (SocketcandServer, VirtualNode, String) {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let emulator = bus.attach("emulator");
    let server = SocketcandServer::bind("127.0.0.1:0", bus, ServerConfig::default())
        .await
        .unwrap();
    let addr = server.local_addr().to_string();
    (server, emulator, addr)
}

async fn recv(bus: &dyn CanBus) -> CanFrame {
    timeout(WAIT, bus.recv())
        .await
        .expect("no frame within 5 s")
        .expect("receive failed")
        .frame
}

/// Send, retrying while the node's small transmit queue is full.
async fn send(bus: &dyn CanBus, frame: CanFrame) {
    for _ in 0..10_000 {
        match bus.send(frame).await {
            Ok(()) => return,
            Err(bus::BusError::TxQueueFull { .. }) => {
                tokio::time::sleep(Duration::from_micros(200)).await;
            }
            Err(e) => panic!("send failed: {e}"),
        }
    }
    panic!("transmit queue stayed full");
}

/// Read from a raw TCP connection until `needle` has arrived; returns everything read.
async fn read_until(stream: &mut TcpStream, needle: &str) -> String {
    let mut seen = String::new();
    let mut buf = [0u8; 1024];
    timeout(WAIT, async {
        while !seen.contains(needle) {
            let n = stream.read(&mut buf).await.unwrap();
            assert!(n > 0, "server closed the connection; got {seen:?}");
            seen.push_str(&String::from_utf8_lossy(&buf[..n]));
        }
    })
    .await
    .unwrap_or_else(|_| panic!("no {needle:?} within 5 s; got {seen:?}"));
    seen
}

/// A raw TCP client past the handshake, in raw mode.
async fn raw_client(addr: &str) -> TcpStream {
    let stream = TcpStream::connect(addr).await.unwrap();
    handshake(stream).await
}

async fn handshake(mut stream: TcpStream) -> TcpStream {
    read_until(&mut stream, "< hi >").await;
    stream.write_all(b"< open can0 >").await.unwrap();
    read_until(&mut stream, "< ok >").await;
    stream.write_all(b"< rawmode >").await.unwrap();
    read_until(&mut stream, "< ok >").await;
    stream
}

/// Wait until frames reach a client connected right now (rawmode has a short grace period).
async fn settle() {
    tokio::time::sleep(ServerConfig::default().rawmode_grace + Duration::from_millis(50)).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn standard_and_extended_frames_cross_both_ways() {
    let (_server, emulator, addr) = server().await;
    let client = SocketcandBus::connect(&addr, "can0").await.unwrap();
    // No wait: our client ends the server's rawmode grace period itself.
    let to_client = [
        CanFrame::standard(0x2A1, &[1, 2, 3, 4, 5, 6, 7, 8]).unwrap(),
        CanFrame::extended(0x0200_FD01, &[0xAB]).unwrap(),
        CanFrame::standard(0x7FF, &[]).unwrap(),
        CanFrame::extended(0x0000_0123, &[]).unwrap(),
    ];
    for frame in to_client {
        send(&emulator, frame).await;
    }
    for frame in to_client {
        assert_eq!(recv(&client).await, frame);
    }
    let to_emulator = [
        CanFrame::standard(0x151, &[0x01, 0x01, 0x32]).unwrap(),
        CanFrame::extended(0x1FFF_FFFF, &[0xFF; 8]).unwrap(),
        CanFrame::extended(0x7, &[0]).unwrap(),
    ];
    for frame in to_emulator {
        send(&client, frame).await;
    }
    for frame in to_emulator {
        assert_eq!(recv(&emulator).await, frame);
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn two_clients_see_each_others_frames_but_not_their_own() {
    let (server, emulator, addr) = server().await;
    let a = SocketcandBus::connect(&addr, "can0").await.unwrap();
    let b = SocketcandBus::connect(&addr, "any-name").await.unwrap();
    settle().await;
    let from_a = CanFrame::standard(0x100, &[0xA]).unwrap();
    let from_b = CanFrame::extended(0x0010_0000, &[0xB]).unwrap();
    send(&a, from_a).await;
    assert_eq!(recv(&b).await, from_a);
    assert_eq!(recv(&emulator).await, from_a);
    send(&b, from_b).await;
    assert_eq!(recv(&a).await, from_b);
    assert_eq!(recv(&emulator).await, from_b);
    // Neither got its own frame back: the next frame each sees is the emulator's.
    let marker = CanFrame::standard(0x001, &[]).unwrap();
    send(&emulator, marker).await;
    assert_eq!(recv(&a).await, marker);
    assert_eq!(recv(&b).await, marker);
    let stats = server.stats();
    assert_eq!(stats.clients, 2);
    assert_eq!(stats.frames_from_clients, 2);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_malformed_line_gets_an_error_and_the_connection_survives() {
    let (server, emulator, addr) = server().await;
    let mut raw = raw_client(&addr).await;
    raw.write_all(b"< send 123 2 11 >").await.unwrap();
    let reply = read_until(&mut raw, "< error").await;
    assert!(reply.contains("DLC"), "reply {reply:?}");
    raw.write_all(b"< frobnicate >").await.unwrap();
    read_until(&mut raw, "unknown command").await;
    // Still usable: a valid frame goes through and echo answers.
    raw.write_all(b"< send 123 2 11 22 >< echo >")
        .await
        .unwrap();
    assert_eq!(
        recv(&emulator).await,
        CanFrame::standard(0x123, &[0x11, 0x22]).unwrap()
    );
    read_until(&mut raw, "< echo >").await;
    assert_eq!(server.stats().errors, 2);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_client_vanishing_mid_line_does_not_disturb_the_other() {
    let (server, emulator, addr) = server().await;
    let steady = SocketcandBus::connect(&addr, "can0").await.unwrap();
    let mut doomed = raw_client(&addr).await;
    settle().await;
    doomed.write_all(b"< send 12").await.unwrap();
    // Unread data in our receive queue makes the close a reset, not an orderly FIN.
    send(&emulator, CanFrame::standard(0x2A1, &[0xFF]).unwrap()).await;
    tokio::time::sleep(Duration::from_millis(50)).await;
    drop(doomed);
    assert_eq!(recv(&steady).await.data(), [0xFF]);
    for i in 0..50u8 {
        send(&emulator, CanFrame::standard(0x2A1, &[i]).unwrap()).await;
    }
    for i in 0..50u8 {
        assert_eq!(recv(&steady).await.data(), [i]);
    }
    let frame = CanFrame::extended(0x0300_0001, &[1, 2]).unwrap();
    send(&steady, frame).await;
    assert_eq!(recv(&emulator).await, frame);
    let deadline = tokio::time::Instant::now() + WAIT;
    while server.stats().clients != 1 {
        assert!(
            tokio::time::Instant::now() < deadline,
            "dead client never removed"
        );
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_client_that_never_reads_can_still_send() {
    // piper_sdk opens a second connection only to send on it.
    let config = ServerConfig {
        client_queue: 16,
        ..ServerConfig::default()
    };
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let emulator = bus.attach("emulator");
    let server = SocketcandServer::bind("127.0.0.1:0", bus, config)
        .await
        .unwrap();
    // A small receive buffer, so that the server's side backs up soon.
    let socket = tokio::net::TcpSocket::new_v4().unwrap();
    socket.set_recv_buffer_size(4096).unwrap();
    let stream = socket.connect(server.local_addr()).await.unwrap();
    let mut sender = handshake(stream).await;
    settle().await;
    // Far more than its queue and socket buffers hold.
    let payload = [0x55; 8];
    for _ in 0..10_000 {
        send(&emulator, CanFrame::standard(0x2A5, &payload).unwrap()).await;
    }
    sender.write_all(b"< send 155 1 7 >").await.unwrap();
    loop {
        let frame = recv(&emulator).await;
        if frame.raw_id() == 0x155 {
            assert_eq!(frame.data(), [7]);
            break;
        }
    }
    assert!(server.stats().frames_dropped > 0, "{:?}", server.stats());
}

#[tokio::test]
async fn connection_refused_names_the_address() {
    // Bind then drop a listener: the port is free and nothing listens on it.
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let addr = format!("127.0.0.1:{port}");
    let error = SocketcandBus::connect(&addr, "can0").await.unwrap_err();
    assert!(matches!(&error, ConnectError::Connect { addr: a, .. } if *a == addr));
    assert!(error.to_string().contains(&addr), "{error}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn server_shutdown_closes_the_client() {
    let (server, _emulator, addr) = server().await;
    let client = SocketcandBus::connect(&addr, "can0").await.unwrap();
    server.shutdown().await;
    let result = timeout(WAIT, client.recv()).await.expect("recv hung");
    assert!(matches!(result, Err(bus::BusError::Closed)), "{result:?}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_server_that_is_not_socketcand_fails_the_handshake() {
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    tokio::spawn(async move {
        let (mut stream, _) = listener.accept().await.unwrap();
        stream.write_all(b"SSH-2.0-OpenSSH\r\n").await.unwrap();
        tokio::time::sleep(WAIT).await;
    });
    let error = SocketcandBus::connect(&addr, "can0").await.unwrap_err();
    assert!(
        matches!(
            &error,
            ConnectError::Handshake {
                expected: "< hi >",
                ..
            }
        ),
        "{error}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn named_channels_keep_each_bus_to_the_clients_that_opened_it() {
    let names = ["can0".to_string(), "can1".to_string()];
    let (buses, server) = SocketcandServer::bind_realtime_channels("127.0.0.1:0", &names)
        .await
        .unwrap();
    let addr = server.local_addr().to_string();
    let robot: Vec<VirtualNode> = buses.iter().map(|b| b.attach("robot")).collect();
    let on_can0 = SocketcandBus::connect(&addr, "can0").await.unwrap();
    let on_can1 = SocketcandBus::connect(&addr, "can1").await.unwrap();
    settle().await;
    send(&on_can1, CanFrame::extended(0x0300_FD05, &[1; 8]).unwrap()).await;
    assert_eq!(recv(&robot[1]).await.raw_id(), 0x0300_FD05);
    send(&robot[0], CanFrame::standard(0x123, &[2]).unwrap()).await;
    assert_eq!(recv(&on_can0).await.raw_id(), 0x123);
    // Neither frame crossed to the other bus.
    settle().await;
    assert!(timeout(Duration::from_millis(100), robot[0].recv())
        .await
        .is_err());
    assert!(timeout(Duration::from_millis(100), on_can1.recv())
        .await
        .is_err());
    // A name the server does not have is refused with the ones it has.
    let mut stream = TcpStream::connect(&addr).await.unwrap();
    read_until(&mut stream, "< hi >").await;
    stream.write_all(b"< open can7 >").await.unwrap();
    let refusal = read_until(&mut stream, ">").await;
    assert!(
        refusal.contains("< error no bus can7 here; this server has can0 can1 >"),
        "{refusal}"
    );
    server.shutdown().await;
}
