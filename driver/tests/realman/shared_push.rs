//! Several arms of one process on one local UDP push port (issue 20 item 3): before, the second
//! arm's bind failed (`ARM_DATA_RECEIVE_FAILED`); now the feeds share the socket and each gets
//! the datagrams of its own controller.

use std::net::SocketAddr;
use std::time::Duration;

use driver::realman::{ArmState, JointSpeedUnit, StateFeed};
use testkit::transcript::{realman_fixtures_dir, Transcript};
use tokio::net::UdpSocket;

fn datagram(name: &str) -> String {
    Transcript::load(realman_fixtures_dir().join("push.jsonl"))
        .expect("fixture")
        .get(name)
        .expect("vector")
        .replies[0]
        .clone()
}

async fn free_udp_port() -> u16 {
    UdpSocket::bind("127.0.0.1:0")
        .await
        .and_then(|s| s.local_addr())
        .expect("free port")
        .port()
}

/// Joint 1 of the next sample a feed gets within `wait`, degrees (the idle vector has 0°, the
/// moving one 10°).
async fn next_j1_deg(feed: &StateFeed, wait: Duration) -> Option<f64> {
    let mut rx = feed.subscribe();
    tokio::time::timeout(wait, rx.recv())
        .await
        .ok()
        .and_then(Result::ok)
        .map(|s| j1_deg(&s))
}

fn j1_deg(s: &ArmState) -> f64 {
    (s.joints_rad[0].to_degrees() * 1000.0).round() / 1000.0
}

#[tokio::test]
async fn two_controllers_on_one_port_each_feed_gets_its_own() {
    // Two "controllers" on one host, told apart by the port they push from.
    let left = UdpSocket::bind("127.0.0.1:0").await.unwrap();
    let right = UdpSocket::bind("127.0.0.1:0").await.unwrap();
    let port = free_udp_port().await;
    let local: SocketAddr = format!("127.0.0.1:{port}").parse().unwrap();
    let unit = JointSpeedUnit::default();
    let a = StateFeed::shared(local, left.local_addr().unwrap(), unit)
        .await
        .expect("first feed binds");
    let b = StateFeed::shared(local, right.local_addr().unwrap(), unit)
        .await
        .expect("second feed on the same port shares the socket");
    assert_eq!(a.local_addr(), b.local_addr());

    let idle = datagram("udp_boot_idle");
    let moving = datagram("udp_moving_legacy");
    let wait = Duration::from_secs(2);
    let (got_a, got_b, _) = tokio::join!(next_j1_deg(&a, wait), next_j1_deg(&b, wait), async {
        tokio::time::sleep(Duration::from_millis(50)).await;
        left.send_to(idle.as_bytes(), local).await.unwrap();
        right.send_to(moving.as_bytes(), local).await.unwrap();
    });
    assert_eq!(got_a, Some(0.0), "left arm sees the left push");
    assert_eq!(got_b, Some(10.0), "right arm sees the right push");
    // Each got only its own datagram.
    assert_eq!(j1_deg(&a.latest().unwrap()), 0.0);
    assert_eq!(j1_deg(&b.latest().unwrap()), 10.0);

    // A third sender on the same IP matches neither controller: dropped and counted.
    let stranger = UdpSocket::bind("127.0.0.1:0").await.unwrap();
    stranger.send_to(idle.as_bytes(), local).await.unwrap();
    tokio::time::sleep(Duration::from_millis(100)).await;
    assert_eq!(a.unrouted(), 1);
    assert_eq!(j1_deg(&b.latest().unwrap()), 10.0);

    // The socket lives while a feed does, and is bound afresh after the last one goes.
    drop(a);
    right.send_to(idle.as_bytes(), local).await.unwrap();
    tokio::time::sleep(Duration::from_millis(100)).await;
    assert_eq!(
        j1_deg(&b.latest().unwrap()),
        0.0,
        "the right arm alone: any source"
    );
    drop(b);
    tokio::time::sleep(Duration::from_millis(50)).await;
    let c = StateFeed::shared(local, left.local_addr().unwrap(), unit)
        .await
        .expect("rebinds once every feed is gone");
    drop(c);
}

#[tokio::test]
async fn two_arms_of_one_controller_both_get_its_push() {
    let controller = UdpSocket::bind("127.0.0.1:0").await.unwrap();
    let port = free_udp_port().await;
    let local: SocketAddr = format!("127.0.0.1:{port}").parse().unwrap();
    // The arms know the controller by its command address, not its push source port.
    let command_addr: SocketAddr = "127.0.0.1:8080".parse().unwrap();
    let unit = JointSpeedUnit::default();
    let a = StateFeed::shared(local, command_addr, unit).await.unwrap();
    let b = StateFeed::shared(local, command_addr, unit).await.unwrap();
    let moving = datagram("udp_moving_legacy");
    let wait = Duration::from_secs(2);
    let (got_a, got_b, _) = tokio::join!(next_j1_deg(&a, wait), next_j1_deg(&b, wait), async {
        tokio::time::sleep(Duration::from_millis(50)).await;
        controller.send_to(moving.as_bytes(), local).await.unwrap();
    });
    assert_eq!(got_a, Some(10.0));
    assert_eq!(got_b, Some(10.0));
    assert_eq!(a.unrouted(), 0);
}
