//! `armhil sim rig` on real SocketCAN: a leader and a follower Piper of a bimanual rig, each
//! on a vxcan pair the rig makes, heard on the peers as a teleoperation program hears them;
//! SIGTERM stops both and the process exits 0.

use std::collections::BTreeSet;
use std::process::{Command, Stdio};
use std::time::Duration;

use bus::socketcan_bus::SocketCanBus;
use bus::CanBus;
use tokio::time::timeout;

use super::bus::armhil_bin;

const LEADER: (&str, &str) = ("armhilbl1", "armhilbl0");
const FOLLOWER: (&str, &str) = ("armhilbf1", "armhilbf0");

async fn open_when_there(iface: &str) -> SocketCanBus {
    for _ in 0..300 {
        if let Ok(bus) = SocketCanBus::open(iface) {
            return bus;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    panic!("{iface} never appeared");
}

/// The IDs heard on `bus` within half a second of the first frame.
async fn ids_heard(bus: &SocketCanBus) -> BTreeSet<u32> {
    let mut ids = BTreeSet::new();
    let first = timeout(Duration::from_secs(30), bus.recv()).await;
    if let Ok(Ok(frame)) = first {
        ids.insert(frame.frame.raw_id());
    }
    let _ = timeout(Duration::from_millis(500), async {
        while let Ok(frame) = bus.recv().await {
            ids.insert(frame.frame.raw_id());
        }
    })
    .await;
    ids
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "needs vcan; run by scripts/vcan-e2e.sh"]
async fn a_rig_serves_a_leader_and_a_follower_on_their_own_interfaces() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("bimanual.yaml");
    std::fs::write(
        &file,
        format!(
            "devices:\n  leader: {{kind: piper, iface: {}, create_vxcan: {}, role: leader}}\n  follower: {{kind: piper, iface: {}, create_vxcan: {}}}\n",
            LEADER.0, LEADER.1, FOLLOWER.0, FOLLOWER.1
        ),
    )
    .unwrap();
    let child = Command::new(armhil_bin())
        .args(["sim", "rig", file.to_str().unwrap()])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("armhil sim rig starts");
    let pid = child.id().to_string();
    let leader = open_when_there(LEADER.1).await;
    let follower = open_when_there(FOLLOWER.1).await;
    let (from_leader, from_follower) = tokio::join!(ids_heard(&leader), ids_heard(&follower));
    let _ = Command::new("kill").args(["-TERM", &pid]).status();
    let output = child.wait_with_output().expect("armhil sim rig exits");
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    for peer in [LEADER.1, FOLLOWER.1] {
        let _ = Command::new("ip").args(["link", "del", peer]).status();
    }
    // A leader sends its joints as commands (0x155-0x157), a follower reports feedback
    // (0x2A5-0x2A7); each interface carries its own arm only.
    let commands = BTreeSet::from([0x155, 0x156, 0x157]);
    let feedback = BTreeSet::from([0x2A5, 0x2A6, 0x2A7]);
    assert!(
        from_leader.is_superset(&commands),
        "{from_leader:X?}: {stderr}"
    );
    assert!(from_leader.is_disjoint(&feedback), "{from_leader:X?}");
    assert!(
        from_follower.is_superset(&feedback),
        "{from_follower:X?}: {stderr}"
    );
    assert!(from_follower.is_disjoint(&commands), "{from_follower:X?}");
    assert!(output.status.success(), "exit {}: {stderr}", output.status);
}
