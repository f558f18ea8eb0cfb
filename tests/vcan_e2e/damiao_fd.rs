//! CAN FD over real SocketCAN: `armhil sim damiao --create-vxcan` and `armhil sim robot
//! robots/openarm.yaml --create-vxcan` give their vxcan pairs the CAN FD MTU (72) and answer a
//! CAN FD request in CAN FD (bit-rate switch kept) and a classic one in classic CAN, on the
//! peer a client such as the OpenArm's own library opens with `CAN_RAW_FD_FRAMES`. can-utils'
//! `candump -L` shows the FD replies in its `##` syntax, `armhil record` keeps them and
//! `armhil replay` sends a log's FD frames as FD.

use std::process::{Child, Command, Stdio};
use std::time::Duration;

use bus::socketcan_bus::{SocketCanBus, SocketCanOptions};
use bus::{CanBus, CanFrame, CanId, FdFlags};
use tokio::time::timeout;

use super::bus::armhil_bin;

/// Long enough for a TCG-emulated VM to start the emulator (the OpenArm loads its URDF).
const WAIT: Duration = Duration::from_secs(60);

/// Damiao's enable command (the last byte FC after seven FF).
const ENABLE: [u8; 8] = [0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFC];

/// The bit-rate switch alone, as the OpenArm's library sends.
const BRS: FdFlags = FdFlags {
    brs: true,
    esi: false,
};

/// Kills its child on drop so a failing test leaves nothing on the bus.
struct Killed(Option<Child>);

impl Killed {
    /// Stop the emulator with SIGTERM and return what it printed on stderr.
    fn stop(mut self) -> String {
        let child = self.0.take().expect("running");
        let _ = Command::new("kill")
            .args(["-TERM", &child.id().to_string()])
            .status();
        let output = child.wait_with_output().expect("armhil exits");
        String::from_utf8_lossy(&output.stderr).into_owned()
    }
}

impl Drop for Killed {
    fn drop(&mut self) {
        if let Some(mut child) = self.0.take() {
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

fn spawn(args: &[&str]) -> Killed {
    let child = Command::new(armhil_bin())
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("armhil starts");
    Killed(Some(child))
}

fn delete_link(name: &str) {
    let _ = Command::new("ip")
        .args(["link", "del", name])
        .stderr(Stdio::null())
        .status();
}

fn mtu(name: &str) -> String {
    std::fs::read_to_string(format!("/sys/class/net/{name}/mtu"))
        .map(|text| text.trim().to_owned())
        .unwrap_or_else(|e| format!("unreadable: {e}"))
}

/// A CAN FD socket on `iface` once the emulator has made it.
async fn open_fd_peer(iface: &str) -> SocketCanBus {
    let options = SocketCanOptions {
        fd: true,
        ..Default::default()
    };
    for _ in 0..(WAIT.as_millis() / 100) {
        if let Ok(bus) = SocketCanBus::open_with(iface, options) {
            return bus;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    panic!("{iface} never appeared");
}

/// Send `request` until a frame on `reply_id` comes back (the emulator may still be starting),
/// and return it.
async fn ask(peer: &SocketCanBus, request: &CanFrame, reply_id: u32) -> CanFrame {
    // Replies to an earlier request sent more than once are not this one's.
    while let Ok(Ok(_)) = timeout(Duration::from_millis(300), peer.recv()).await {}
    let answered = timeout(WAIT, async {
        loop {
            peer.send(*request).await.expect("the request is sent");
            let deadline = tokio::time::Instant::now() + Duration::from_millis(200);
            while let Ok(Ok(received)) = tokio::time::timeout_at(deadline, peer.recv()).await {
                if received.frame.raw_id() == reply_id {
                    return received.frame;
                }
            }
        }
    })
    .await;
    answered.unwrap_or_else(|_| panic!("no reply on 0x{reply_id:03X} to {request:?}"))
}

fn classic(id: u16, data: &[u8]) -> CanFrame {
    CanFrame::new(CanId::Standard(id), data).expect("a classic frame")
}

fn fd(id: u16, data: &[u8]) -> CanFrame {
    CanFrame::fd(CanId::Standard(id), data, BRS).expect("an FD frame")
}

/// The state nibble and ESC_ID nibble of a feedback frame's first byte.
fn state_and_id(frame: &CanFrame) -> (u8, u8) {
    let d0 = frame.data()[0];
    (d0 >> 4, d0 & 0x0F)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "needs vcan; run by scripts/vcan-e2e.sh"]
async fn sim_damiao_answers_can_fd_in_can_fd_and_classic_in_classic() {
    const OURS: &str = "armhildm1";
    const PEER: &str = "armhildm0";
    delete_link(PEER);
    let emulator = spawn(&[
        "sim",
        "damiao",
        "--iface",
        OURS,
        "--create-vxcan",
        PEER,
        "--motor",
        "1:DM4310",
    ]);
    let peer = open_fd_peer(PEER).await;
    let candump = Command::new("candump")
        .args(["-L", PEER])
        .stdout(Stdio::piped())
        .spawn()
        .expect("candump (can-utils) runs");
    // armhil's own recorder on the emulator's end: it opens a CAN FD socket.
    let files = tempfile::tempdir().expect("a temporary folder");
    let recording = files.path().join("fd.log");
    let recorder = spawn(&[
        "record",
        "--iface",
        OURS,
        "-o",
        recording.to_str().expect("a UTF-8 path"),
    ]);
    tokio::time::sleep(Duration::from_millis(500)).await;

    let reply = ask(&peer, &fd(0x001, &ENABLE), 0x011).await;
    assert!(reply.is_fd(), "an FD enable answered classic: {reply:?}");
    assert_eq!(reply.fd_flags(), Some(BRS), "{reply:?}");
    assert_eq!(reply.data().len(), 8);
    assert_eq!(state_and_id(&reply), (1, 1), "enabled, motor 1: {reply:?}");

    let disable = [0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFD];
    let reply = ask(&peer, &classic(0x001, &disable), 0x011).await;
    assert!(
        !reply.is_fd(),
        "a classic disable answered in FD: {reply:?}"
    );
    assert_eq!(state_and_id(&reply), (0, 1), "disabled, motor 1: {reply:?}");

    // `armhil replay` sends a log's CAN FD frames as CAN FD: an FD enable, answered in FD.
    let replayed = files.path().join("enable.log");
    std::fs::write(&replayed, "(0.000000) vcan0 001##1FFFFFFFFFFFFFFFC\n").expect("written");
    while let Ok(Ok(_)) = timeout(Duration::from_millis(300), peer.recv()).await {}
    let replay = Command::new(armhil_bin())
        .args(["replay", replayed.to_str().expect("UTF-8"), "--iface", PEER])
        .output()
        .expect("armhil replay runs");
    assert!(
        replay.status.success(),
        "replay: {}",
        String::from_utf8_lossy(&replay.stderr)
    );
    let reply = timeout(WAIT, async {
        loop {
            if let Ok(received) = peer.recv().await {
                if received.frame.raw_id() == 0x011 {
                    return received.frame;
                }
            }
        }
    })
    .await
    .expect("the replayed enable is answered");
    assert!(reply.is_fd(), "{reply:?}");
    assert_eq!(state_and_id(&reply), (1, 1), "{reply:?}");

    let recorder_stderr = recorder.stop();
    let recorded = std::fs::read_to_string(&recording)
        .unwrap_or_else(|e| panic!("{}: {e}; {recorder_stderr}", recording.display()));
    assert!(
        recorded
            .lines()
            .any(|l| l.ends_with(" 001##1FFFFFFFFFFFFFFFC")),
        "the FD enable in armhil's recording: {recorded}"
    );
    assert!(
        recorded.lines().any(|l| l.contains(" 011##1")),
        "an FD reply in armhil's recording: {recorded}"
    );
    let _ = Command::new("kill")
        .args(["-TERM", &candump.id().to_string()])
        .status();
    let dump = candump.wait_with_output().expect("candump exits");
    let dump = String::from_utf8_lossy(&dump.stdout).into_owned();
    let stderr = emulator.stop();
    assert_eq!(mtu(OURS), "72", "{stderr}");
    assert_eq!(mtu(PEER), "72", "{stderr}");
    assert!(stderr.contains("(CAN FD, MTU 72)"), "{stderr}");
    // candump's CAN FD syntax: `ID##F` then the data, F the flags nibble: BRS (1), with
    // CANFD_FDF (4) on kernels that set it on received frames.
    let fd_with_brs = |line: &str, prefix: &str| {
        [format!(" {prefix}##1"), format!(" {prefix}##5")]
            .iter()
            .any(|form| line.contains(form.as_str()))
    };
    assert!(
        dump.lines()
            .any(|l| fd_with_brs(l, "001") && l.ends_with("FFFFFFFFFFFFFFFC")),
        "the FD request in candump: {dump}"
    );
    assert!(
        dump.lines().any(|l| fd_with_brs(l, "011")),
        "an FD reply in candump: {dump}"
    );
    assert!(
        dump.lines().any(|l| l.contains(" 001#FFFFFFFFFFFFFFFD")),
        "the classic request in candump: {dump}"
    );
    delete_link(PEER);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "needs vcan; run by scripts/vcan-e2e.sh"]
async fn sim_robot_serves_the_openarm_on_can_fd_vxcan_pairs() {
    // The client keeps the bus names the robot file gives (can0 right arm, can1 left arm).
    for peer in ["can0", "can1"] {
        delete_link(peer);
    }
    let robot = format!("{}/robots/openarm.yaml", env!("CARGO_MANIFEST_DIR"));
    let emulator = spawn(&["sim", "robot", &robot, "--create-vxcan"]);
    let right = open_fd_peer("can0").await;
    let left = open_fd_peer("can1").await;

    // J4 of the right arm (a DM4340) and the left arm's gripper (a DM4310, id 8).
    let reply = ask(&right, &fd(0x004, &ENABLE), 0x014).await;
    assert!(reply.is_fd(), "{reply:?}");
    assert_eq!(state_and_id(&reply), (1, 4), "{reply:?}");
    let reply = ask(&left, &fd(0x008, &ENABLE), 0x018).await;
    assert!(reply.is_fd(), "{reply:?}");
    assert_eq!(state_and_id(&reply), (1, 8), "{reply:?}");
    // Each arm has motors 1..=8 (the gripper is 8): nothing answers on 9.
    right.send(fd(0x009, &ENABLE)).await.expect("sent");
    let silent = timeout(Duration::from_millis(500), async {
        loop {
            if let Ok(received) = right.recv().await {
                if received.frame.raw_id() == 0x019 {
                    return received.frame;
                }
            }
        }
    })
    .await;
    assert!(silent.is_err(), "a motor 9 answered on can0: {silent:?}");

    let stderr = emulator.stop();
    for end in ["sim-can0", "sim-can1", "can0", "can1"] {
        assert_eq!(mtu(end), "72", "{end}: {stderr}");
    }
    assert!(
        stderr.contains("sim-can0 (CAN FD), sim-can1 (CAN FD)"),
        "{stderr}"
    );
    for peer in ["can0", "can1"] {
        delete_link(peer);
    }
}
