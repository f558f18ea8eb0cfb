//! `armhil sim piper --create-vxcan PEER` makes the vxcan pair itself (the VM runs as root)
//! and a client on the peer talks to the emulator through it; a second start reuses the pair.

use std::process::{Command, Stdio};
use std::time::Duration;

use bus::socketcan_bus::SocketCanBus;
use bus::CanBus;
use tokio::time::timeout;

use super::bus::armhil_bin;

const OURS: &str = "armhilvx1";
const PEER: &str = "armhilvx0";

/// Start the emulator with `--create-vxcan`, wait for its feedback on the peer, stop it and
/// return what it said about the pair.
async fn start_and_hear_feedback() -> String {
    let child = Command::new(armhil_bin())
        .args(["sim", "piper", "--iface", OURS, "--create-vxcan", PEER])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("armhil sim piper starts");
    let pid = child.id().to_string();
    // The pair appears once the emulator made it; the first start needs a moment.
    let mut peer = None;
    for _ in 0..300 {
        if let Ok(bus) = SocketCanBus::open(PEER) {
            peer = Some(bus);
            break;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    let peer = peer.unwrap_or_else(|| panic!("{PEER} never appeared"));
    let heard = timeout(Duration::from_secs(30), async {
        loop {
            if let Ok(frame) = peer.recv().await {
                if frame.frame.raw_id() == 0x2A1 {
                    return;
                }
            }
        }
    })
    .await;
    let _ = Command::new("kill").args(["-TERM", &pid]).status();
    let output = child.wait_with_output().expect("armhil sim piper exits");
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(heard.is_ok(), "no Piper feedback on {PEER}: {stderr}");
    assert!(output.status.success(), "exit {}: {stderr}", output.status);
    stderr
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "needs vcan; run by scripts/vcan-e2e.sh"]
async fn create_vxcan_makes_the_pair_and_reuses_it() {
    // A pair left over from an earlier run would make the first start reuse it.
    let _ = Command::new("ip")
        .args(["link", "del", PEER])
        .stderr(Stdio::null())
        .status();
    let first = start_and_hear_feedback().await;
    assert!(
        first.contains(&format!("created vxcan pair {OURS} ↔ {PEER}")),
        "{first}"
    );
    let second = start_and_hear_feedback().await;
    assert!(second.contains("using the existing vxcan pair"), "{second}");
    let _ = Command::new("ip").args(["link", "del", PEER]).status();
}
