use std::net::IpAddr;

use tokio::io::{AsyncReadExt, AsyncWriteExt, DuplexStream};
use tokio::time::timeout;

use super::*;
use crate::realman::model::ArmModel;

const PEER: IpAddr = IpAddr::V4(std::net::Ipv4Addr::new(192, 168, 1, 10));
const POWER_OFF: &str = r#"{"command":"set_arm_power","arm_power":0}"#;

async fn emulator(tune: impl FnOnce(&mut EmulatorConfig)) -> RealmanHandle {
    let mut config = EmulatorConfig::new(ControllerConfig::new(ArmModel::rm65b()));
    tune(&mut config);
    RealmanEmulator::spawn(config, Transport::InMemory)
        .await
        .expect("emulator boots")
}

/// Read until the server closes the stream; `None` if it stays open for `within`.
async fn closed_within(stream: &mut DuplexStream, within: Duration) -> Option<Vec<u8>> {
    let mut seen = Vec::new();
    timeout(within, stream.read_to_end(&mut seen))
        .await
        .ok()?
        .ok()?;
    Some(seen)
}

/// One reply line (CRLF-terminated) within `within`.
async fn reply(stream: &mut DuplexStream, within: Duration) -> Option<String> {
    let mut line = Vec::new();
    let mut byte = [0u8; 1];
    timeout(within, async {
        while !line.ends_with(b"\r\n") {
            match stream.read(&mut byte).await {
                Ok(1) => line.push(byte[0]),
                _ => return None,
            }
        }
        Some(String::from_utf8_lossy(&line).into_owned())
    })
    .await
    .ok()?
}

#[tokio::test(start_paused = true)]
async fn a_browser_post_is_closed_and_does_not_power_the_arm_off() {
    let emu = emulator(|_| {}).await;
    assert!(emu.snapshot().power_on);
    let request = format!(
        "POST / HTTP/1.1\r\nHost: 127.0.0.1:8080\r\nOrigin: https://attacker.example\r\n\
         Content-Type: text/plain;charset=UTF-8\r\nContent-Length: {}\r\n\r\n{POWER_OFF}",
        POWER_OFF.len()
    );
    for piece in [request.len(), 3] {
        let mut stream = emu.connect(PEER).unwrap();
        for part in request.as_bytes().chunks(piece) {
            if stream.write_all(part).await.is_err() {
                break;
            }
        }
        let seen = closed_within(&mut stream, Duration::from_secs(2)).await;
        assert_eq!(seen.as_deref(), Some(&b""[..]), "closed without a reply");
    }
    tokio::time::sleep(Duration::from_millis(100)).await;
    assert!(emu.snapshot().power_on, "the page powered the arm off");
    assert_eq!(emu.stats().http_refused, 2);

    // The body alone, from a JSON client, does power it off (so the test can fail).
    let mut stream = emu.connect(PEER).unwrap();
    stream.write_all(POWER_OFF.as_bytes()).await.unwrap();
    assert!(reply(&mut stream, Duration::from_secs(2)).await.is_some());
    assert!(!emu.snapshot().power_on);
}

#[tokio::test(start_paused = true)]
async fn a_client_that_does_not_read_is_not_read_either() {
    let emu = emulator(|c| c.idle_timeout = Some(Duration::from_secs(600))).await;
    let mut stream = emu.connect(PEER).unwrap();
    let request = b"{\"command\":\"get_joint_degree\"}\r\n";
    let total = 8 << 20;
    let many = request.repeat(total / request.len());
    // Without the bound the server reads (and queues replies to) all 8 MiB.
    let wrote = timeout(Duration::from_secs(3), stream.write_all(&many)).await;
    assert!(
        wrote.is_err(),
        "the server kept reading a client that reads nothing"
    );
    assert_eq!(
        emu.connections(),
        1,
        "a client that only sends is not dropped"
    );
    // Once it reads, it gets its replies and the server reads again.
    let (mut read, mut write) = tokio::io::split(stream);
    let drain = tokio::spawn(async move {
        let mut buf = vec![0u8; 64 * 1024];
        let mut lines = 0usize;
        while lines < 1000 {
            match read.read(&mut buf).await {
                Ok(0) | Err(_) => break,
                Ok(n) => lines += buf[..n].iter().filter(|&&b| b == b'\n').count(),
            }
        }
        lines
    });
    write.write_all(request).await.unwrap();
    let lines = timeout(Duration::from_secs(10), drain)
        .await
        .unwrap()
        .unwrap();
    assert!(lines >= 1000, "{lines} replies");
}

#[tokio::test(start_paused = true)]
async fn an_idle_connection_is_closed_and_a_busy_one_is_not() {
    let emu = emulator(|c| c.idle_timeout = Some(Duration::from_secs(2))).await;
    let mut idle = emu.connect(PEER).unwrap();
    let mut busy = emu.connect(PEER).unwrap();
    for _ in 0..5 {
        busy.write_all(b"{\"command\":\"get_arm_power_state\"}")
            .await
            .unwrap();
        assert!(reply(&mut busy, Duration::from_secs(1)).await.is_some());
        tokio::time::sleep(Duration::from_millis(900)).await;
    }
    assert!(closed_within(&mut idle, Duration::from_millis(100))
        .await
        .is_some());
    assert_eq!(emu.connections(), 1);
    assert_eq!(emu.stats().idle_closed, 1);
}

#[tokio::test(start_paused = true)]
async fn at_the_cap_a_newcomer_takes_the_slot_of_a_long_idle_client() {
    let emu = emulator(|c| {
        c.max_connections = 2;
        c.idle_timeout = None;
    })
    .await;
    let mut first = emu.connect(PEER).unwrap();
    tokio::time::sleep(Duration::from_secs(1)).await;
    let mut second = emu.connect(PEER).unwrap();
    // Nobody has been idle for EVICT_IDLE_AFTER yet: refused.
    let mut refused = emu.connect(PEER).unwrap();
    let seen = closed_within(&mut refused, Duration::from_millis(100)).await;
    assert_eq!(seen.as_deref(), Some(&b""[..]));
    assert_eq!(emu.stats().refused, 1);

    tokio::time::sleep(EVICT_IDLE_AFTER).await;
    second
        .write_all(b"{\"command\":\"get_arm_power_state\"}")
        .await
        .unwrap();
    assert!(reply(&mut second, Duration::from_secs(1)).await.is_some());
    let mut newcomer = emu.connect(PEER).unwrap();
    newcomer
        .write_all(b"{\"command\":\"get_arm_power_state\"}")
        .await
        .unwrap();
    assert!(reply(&mut newcomer, Duration::from_secs(1)).await.is_some());
    // The idlest one (the first) made room; the second, just active, stays.
    assert!(closed_within(&mut first, Duration::from_millis(100))
        .await
        .is_some());
    assert_eq!(emu.stats().evicted, 1);
    assert_eq!(emu.connections(), 2);
}

#[tokio::test(start_paused = true)]
async fn the_push_stops_when_the_last_client_leaves() {
    let emu = emulator(|_| {}).await;
    let mut datagrams = emu.take_datagrams().unwrap();
    let mut stream = emu.connect(PEER).unwrap();
    let set = r#"{"command":"set_realtime_push","ip":"10.0.0.7","port":9000}"#;
    stream.write_all(set.as_bytes()).await.unwrap();
    assert!(reply(&mut stream, Duration::from_secs(2)).await.is_some());
    tokio::time::sleep(Duration::from_millis(100)).await;
    let mut seen = 0;
    while datagrams.try_recv().is_ok() {
        seen += 1;
    }
    assert!(seen > 10, "{seen} datagrams while a client is connected");
    // D7: with no client left, the stored target gets nothing.
    drop(stream);
    tokio::time::sleep(Duration::from_millis(50)).await;
    while datagrams.try_recv().is_ok() {}
    tokio::time::sleep(Duration::from_millis(500)).await;
    assert!(
        datagrams.try_recv().is_err(),
        "pushed with no client connected"
    );
    assert_eq!(emu.connections(), 0);
}
