//! The SocketCAN bus, `armhil record` and `armhil replay` on a live vcan interface, checked
//! against each other and against can-utils' `candump`.
//!
//! Real clock, multi-thread runtime. Every wait is bounded; the bounds are generous because the
//! suite usually runs under TCG emulation, several times slower than the host.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::mpsc;
use std::time::{Duration, SystemTime};

use bus::candump::{parse_log, read_log, LogEntry};
use bus::socketcan_bus::SocketCanBus;
use bus::{CanBus, CanFrame, ReceivedFrame};
use tokio::time::{sleep, timeout, Instant};

/// How long a frame may take from one socket to another, or a child process to start.
const WAIT: Duration = Duration::from_secs(10);

/// The interface under test.
fn iface() -> String {
    std::env::var("ARMHIL_VCAN_IFACE").unwrap_or_else(|_| "vcan0".to_owned())
}

/// The `armhil` binary: `ARMHIL_BIN` (set by scripts/vcan-e2e.sh) or the one cargo built.
pub fn armhil_bin() -> PathBuf {
    std::env::var_os("ARMHIL_BIN")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_BIN_EXE_armhil")))
}

/// A fresh directory for one test's files: under `ARMHIL_E2E_OUT` (kept after the run for
/// inspection) when set, else under the system temp dir. The repo is read-only in the VM.
fn scratch_dir(test: &str) -> PathBuf {
    let base = std::env::var_os("ARMHIL_E2E_OUT")
        .map(PathBuf::from)
        .unwrap_or_else(std::env::temp_dir);
    let dir = base.join(format!("bus-{test}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create scratch dir");
    dir
}

fn open() -> SocketCanBus {
    let iface = iface();
    SocketCanBus::open(&iface).unwrap_or_else(|error| panic!("open {iface}: {error}"))
}

fn now_since_epoch() -> Duration {
    SystemTime::now()
        .duration_since(SystemTime::UNIX_EPOCH)
        .expect("clock after 1970")
}

fn std_frame(id: u16, data: &[u8]) -> CanFrame {
    CanFrame::standard(id, data).expect("valid standard frame")
}

fn ext_frame(id: u32, data: &[u8]) -> CanFrame {
    CanFrame::extended(id, data).expect("valid extended frame")
}

/// The next frame on `bus` whose identifier is in `ids` (other traffic on the shared interface
/// is skipped), within [`WAIT`].
async fn recv_matching(bus: &SocketCanBus, ids: &[u32]) -> ReceivedFrame {
    let deadline = Instant::now() + WAIT;
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        let received = timeout(left, bus.recv())
            .await
            .unwrap_or_else(|_| panic!("no frame with id in {ids:x?} within {WAIT:?}"))
            .expect("recv");
        if ids.contains(&received.frame.raw_id()) {
            return received;
        }
    }
}

/// A child process killed on drop, so a failing test leaves nothing running on the bus.
struct ChildGuard {
    child: Child,
    what: &'static str,
}

impl ChildGuard {
    fn spawn(what: &'static str, command: &mut Command) -> Self {
        let child = command
            .spawn()
            .unwrap_or_else(|error| panic!("spawn {what}: {error}"));
        Self { child, what }
    }

    /// Lines of the child's stdout, read on a thread.
    fn stdout_lines(&mut self) -> mpsc::Receiver<String> {
        let stdout = self.child.stdout.take().expect("stdout piped");
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        rx
    }

    /// SIGINT (Ctrl-C), then wait for the exit.
    async fn interrupt(&mut self) -> ExitStatus {
        self.signal("INT").await
    }

    /// Send `signal` (`INT`, `TERM`), then wait for the exit.
    async fn signal(&mut self, signal: &str) -> ExitStatus {
        let pid = self.child.id().to_string();
        let sent = Command::new("kill")
            .args([&format!("-{signal}"), &pid])
            .status()
            .expect("run kill");
        assert!(sent.success(), "kill -{signal} {pid} failed");
        self.wait().await
    }

    /// Wait for the exit, at most [`WAIT`] (plus the timeout's own scale for slow starts).
    async fn wait(&mut self) -> ExitStatus {
        let deadline = Instant::now() + 3 * WAIT;
        loop {
            if let Some(status) = self.child.try_wait().expect("try_wait") {
                return status;
            }
            assert!(
                Instant::now() < deadline,
                "{} did not exit within {:?}",
                self.what,
                3 * WAIT
            );
            sleep(Duration::from_millis(50)).await;
        }
    }
}

impl Drop for ChildGuard {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

/// `candump -L <iface>` with line-buffered output, started and proven to be listening: probe
/// frames (id `probe_id`) are sent until one shows up in its output.
async fn start_candump(
    probe: &SocketCanBus,
    probe_id: u16,
) -> (ChildGuard, mpsc::Receiver<String>) {
    let mut candump = ChildGuard::spawn(
        "candump",
        Command::new("stdbuf")
            .args(["-oL", "candump", "-L", &iface()])
            .stdout(Stdio::piped()),
    );
    let lines = candump.stdout_lines();
    let deadline = Instant::now() + WAIT;
    let marker = format!(" {probe_id:03X}#");
    loop {
        probe
            .send(std_frame(probe_id, &[0xEE]))
            .await
            .expect("send probe");
        sleep(Duration::from_millis(100)).await;
        if lines.try_iter().any(|line| line.contains(&marker)) {
            return (candump, lines);
        }
        assert!(
            Instant::now() < deadline,
            "candump did not start within {WAIT:?}"
        );
    }
}

/// candump lines until one contains `last` (or [`WAIT`] passes), parsed by our reader.
async fn collect_candump(lines: &mpsc::Receiver<String>, last: &CanFrame) -> Vec<LogEntry> {
    let deadline = Instant::now() + WAIT;
    let mut text = String::new();
    let last = format!(" {last}");
    loop {
        let mut done = false;
        for line in lines.try_iter() {
            done |= line.ends_with(&last);
            text.push_str(&line);
            text.push('\n');
        }
        if done {
            break;
        }
        assert!(
            Instant::now() < deadline,
            "candump did not show {last} within {WAIT:?}; got:\n{text}"
        );
        sleep(Duration::from_millis(50)).await;
    }
    parse_log(&text)
        .unwrap_or_else(|error| panic!("our reader rejects candump output: {error}\n{text}"))
}

fn frames_with_ids(entries: &[LogEntry], ids: &[u32]) -> Vec<LogEntry> {
    entries
        .iter()
        .filter(|entry| ids.contains(&entry.frame.raw_id()))
        .cloned()
        .collect()
}

fn assert_monotonic(timestamps: impl IntoIterator<Item = Duration>, what: &str) {
    let timestamps: Vec<Duration> = timestamps.into_iter().collect();
    for (index, pair) in timestamps.windows(2).enumerate() {
        assert!(
            pair[0] <= pair[1],
            "{what}: timestamps go backwards between frames {index} and {}: {pair:?} (all: {timestamps:?})",
            index + 1
        );
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "needs vcan; run by scripts/vcan-e2e.sh"]
async fn two_endpoints_exchange_standard_and_extended_frames() {
    let a = open();
    let b = open();
    let sent = [
        std_frame(0x123, &[0x11, 0x22, 0x33]),
        std_frame(0x7FF, &[]),
        ext_frame(0x1ABC_DE0F, &[0, 1, 2, 3, 4, 5, 6, 7]),
        ext_frame(0x1FFF_FFFF, &[0xFF]),
        // Same numeric id in both formats: the format flag must survive the trip.
        ext_frame(0x123, &[0x44]),
    ];
    let ids: Vec<u32> = sent.iter().map(|frame| frame.raw_id()).collect();
    for frame in sent {
        a.send(frame).await.expect("send from a");
    }
    for want in sent {
        let got = recv_matching(&b, &ids).await;
        assert_eq!(got.frame, want);
        assert_eq!(got.frame.is_extended(), want.is_extended());
    }

    // The other direction; `a` must see `b`'s reply and not its own earlier frames (no
    // own-loopback by default).
    let reply = ext_frame(0x0200_FD01, &[0xAB, 0xCD]);
    b.send(reply).await.expect("send from b");
    let mut reply_ids = ids.clone();
    reply_ids.push(reply.raw_id());
    let got = recv_matching(&a, &reply_ids).await;
    assert_eq!(
        got.frame, reply,
        "a received something other than b's reply"
    );

    a.close().await;
    assert!(matches!(a.recv().await, Err(bus::BusError::Closed)));
    assert!(matches!(a.send(reply).await, Err(bus::BusError::Closed)));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "needs vcan; run by scripts/vcan-e2e.sh"]
async fn timestamps_are_monotonic_and_close_to_wall_clock() {
    // Kernel timestamps can be a few clock ticks off the userspace clock read around them.
    const SLACK: Duration = Duration::from_millis(50);
    let a = open();
    let b = open();
    // Linux turns receive timestamping on for the whole stack lazily (a static key flipped from
    // a workqueue) when the first socket asks for it; until then a frame is stamped when it is
    // read, not when it arrived. Let that settle, and exchange one frame, before measuring.
    sleep(Duration::from_millis(250)).await;
    a.send(std_frame(0x3A1, &[])).await.expect("send warm-up");
    recv_matching(&b, &[0x3A1]).await;
    let count: u8 = 40;
    let before = now_since_epoch();
    for seq in 0..count {
        a.send(std_frame(0x3A0, &[seq])).await.expect("send");
        sleep(Duration::from_millis(2)).await;
    }
    let mut received = Vec::new();
    for _ in 0..count {
        received.push(recv_matching(&b, &[0x3A0]).await);
    }
    let after = now_since_epoch();

    let seqs: Vec<u8> = received.iter().map(|r| r.frame.data()[0]).collect();
    assert_eq!(
        seqs,
        (0..count).collect::<Vec<_>>(),
        "frames reordered or lost"
    );
    assert_monotonic(received.iter().map(|r| r.timestamp), "SocketCanBus");
    for r in &received {
        assert!(
            r.timestamp + SLACK >= before && r.timestamp <= after + SLACK,
            "timestamp {:?} outside the send/receive window {before:?}..{after:?}",
            r.timestamp
        );
    }
    // 2 ms pauses between sends: the first and last frame cannot share a timestamp.
    let span = received[received.len() - 1].timestamp - received[0].timestamp;
    assert!(
        span >= Duration::from_millis(2 * u64::from(count - 1)),
        "span {span:?}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "needs vcan; run by scripts/vcan-e2e.sh"]
async fn recording_round_trips_through_the_candump_reader() {
    let dir = scratch_dir("record");
    let log = dir.join("recorded.log");
    let iface = iface();
    let bus = open();
    let (mut candump, candump_lines) = start_candump(&bus, 0x7F0).await;

    let mut recorder = ChildGuard::spawn(
        "armhil record",
        Command::new(armhil_bin())
            .args(["record", "--iface", &iface, "-o"])
            .arg(&log),
    );
    // The recorder gives no ready signal on stdout: wait until it has written a probe frame
    // (it flushes as it goes), or at worst until WAIT has passed, probing all along.
    let deadline = Instant::now() + WAIT;
    while Instant::now() < deadline && !file_mentions(&log, " 7F1#") {
        bus.send(std_frame(0x7F1, &[0xEE]))
            .await
            .expect("send probe");
        sleep(Duration::from_millis(100)).await;
    }

    let sent = [
        std_frame(0x2A1, &[1, 0, 0, 0, 0, 0, 0, 0]),
        ext_frame(0x0200_FD01, &[]),
        std_frame(0x000, &[0xFF; 8]),
        ext_frame(0x1FFF_FFFF, &[0x5A, 0xA5]),
    ];
    let ids: Vec<u32> = sent.iter().map(|frame| frame.raw_id()).collect();
    let window_start = now_since_epoch();
    for frame in sent {
        bus.send(frame).await.expect("send");
        sleep(Duration::from_millis(5)).await;
    }
    let seen_by_candump = frames_with_ids(
        &collect_candump(&candump_lines, &sent[sent.len() - 1]).await,
        &ids,
    );
    let status = recorder.interrupt().await;
    let window_end = now_since_epoch();
    assert!(status.success(), "armhil record exited with {status}");
    candump.interrupt().await;

    let recorded = read_log(&log).unwrap_or_else(|error| panic!("read {}: {error}", log.display()));
    let ours = frames_with_ids(&recorded, &ids);
    let frames: Vec<CanFrame> = ours.iter().map(|entry| entry.frame).collect();
    assert_eq!(frames, sent, "recorded frames differ from the frames sent");
    assert!(ours.iter().all(|entry| entry.iface == iface), "{ours:?}");
    assert_monotonic(
        recorded.iter().map(|entry| entry.timestamp),
        "armhil record",
    );
    for entry in &ours {
        assert!(
            entry.timestamp + Duration::from_millis(50) >= window_start
                && entry.timestamp <= window_end,
            "recorded timestamp {:?} outside {window_start:?}..{window_end:?}",
            entry.timestamp
        );
    }

    // can-utils saw the same frames at (nearly) the same kernel timestamps.
    let theirs: Vec<CanFrame> = seen_by_candump.iter().map(|entry| entry.frame).collect();
    assert_eq!(theirs, sent, "candump saw different frames");
    for (ours, theirs) in ours.iter().zip(&seen_by_candump) {
        let gap = ours.timestamp.abs_diff(theirs.timestamp);
        assert!(
            gap <= Duration::from_millis(20),
            "timestamps {ours:?} vs {theirs:?}"
        );
    }
}

fn file_mentions(path: &Path, needle: &str) -> bool {
    std::fs::read_to_string(path).is_ok_and(|text| text.contains(needle))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "needs vcan; run by scripts/vcan-e2e.sh"]
async fn replay_is_seen_by_candump() {
    let dir = scratch_dir("replay");
    let capture = dir.join("capture.log");
    let iface = iface();
    // 50 ms apart in the capture; the replay keeps the original timing.
    let frames = [
        std_frame(0x151, &[0x01, 0x02]),
        ext_frame(0x0300_0A01, &[0, 0, 0, 0, 0, 0, 0, 1]),
        std_frame(0x151, &[]),
        ext_frame(0x0000_0001, &[0xC0, 0xFF, 0xEE]),
        std_frame(0x2B5, &[0x7F; 8]),
    ];
    let spacing = Duration::from_millis(50);
    let mut text = String::from("# written by tests/vcan_e2e/bus.rs\n");
    let epoch = Duration::from_secs(1_700_000_000);
    for (index, frame) in (0u32..).zip(frames) {
        let timestamp = epoch + spacing * index;
        text.push_str(&format!(
            "({}.{:06}) {iface} {frame}\n",
            timestamp.as_secs(),
            timestamp.subsec_micros()
        ));
    }
    std::fs::write(&capture, &text).expect("write capture");
    // Our own reader agrees with what we wrote, so a mismatch below is the replay's fault.
    let parsed: Vec<CanFrame> = read_log(&capture)
        .expect("read capture")
        .iter()
        .map(|e| e.frame)
        .collect();
    assert_eq!(parsed, frames);

    let probe = open();
    let (mut candump, lines) = start_candump(&probe, 0x7F2).await;
    let mut replay = ChildGuard::spawn(
        "armhil replay",
        Command::new(armhil_bin())
            .arg("replay")
            .arg(&capture)
            .args(["--iface", &iface]),
    );
    let status = replay.wait().await;
    assert!(status.success(), "armhil replay exited with {status}");

    let ids: Vec<u32> = frames.iter().map(|frame| frame.raw_id()).collect();
    let seen = frames_with_ids(
        &collect_candump(&lines, &frames[frames.len() - 1]).await,
        &ids,
    );
    candump.interrupt().await;
    let seen_frames: Vec<CanFrame> = seen.iter().map(|entry| entry.frame).collect();
    assert_eq!(seen_frames, frames, "candump saw a different sequence");
    // The replay keeps the capture's pacing rather than sending a burst (a span near zero).
    // Its schedule is anchored at the start, so a late first frame shortens the observed span:
    // under emulation on a busy host the first send was seen 113 ms late once (one spacing of
    // tolerance failed), so two are allowed, still far from a burst.
    let span = seen[seen.len() - 1].timestamp - seen[0].timestamp;
    let original = spacing * (frames.len() as u32 - 1);
    assert!(
        span + 2 * spacing >= original,
        "replay took {span:?} for a capture spanning {original:?}"
    );
}

/// Wait (probing the bus with `probe_id` frames) until `done` says the file shows them.
async fn wait_for_file(bus: &SocketCanBus, probe_id: u16, done: impl Fn() -> bool) {
    let deadline = Instant::now() + 3 * WAIT;
    while !done() {
        assert!(
            Instant::now() < deadline,
            "nothing recorded within {:?}",
            3 * WAIT
        );
        bus.send(std_frame(probe_id, &[0xEE]))
            .await
            .expect("send probe");
        sleep(Duration::from_millis(100)).await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "needs vcan; run by scripts/vcan-e2e.sh"]
async fn sigterm_leaves_complete_recordings_on_socketcan() {
    let dir = scratch_dir("signals");
    let iface = iface();
    let bus = open();

    // `armhil record` into a pcap, stopped by SIGTERM.
    let pcap = dir.join("recorded.pcap");
    let mut recorder = ChildGuard::spawn(
        "armhil record",
        Command::new(armhil_bin())
            .args(["record", "--iface", &iface, "-o"])
            .arg(&pcap),
    );
    // The pcap header is 24 bytes; each frame record 32 more, flushed every second.
    wait_for_file(&bus, 0x7E1, || {
        std::fs::metadata(&pcap).is_ok_and(|m| m.len() > 24)
    })
    .await;
    let status = recorder.signal("TERM").await;
    assert!(status.success(), "armhil record exited with {status}");
    let bytes = std::fs::read(&pcap).expect("read the pcap");
    let frames = bus::pcap::parse_capture(&bytes)
        .unwrap_or_else(|e| panic!("{} is incomplete: {e:?}", pcap.display()));
    assert!(
        frames.iter().any(|f| f.frame.raw_id() == 0x7E1),
        "no probe frame in {}",
        pcap.display()
    );

    // `armhil sim piper --record` into a candump log, stopped by SIGTERM.
    let log = dir.join("sim.log");
    let mut sim = ChildGuard::spawn(
        "armhil sim piper",
        Command::new(armhil_bin())
            .args(["sim", "piper", "--iface", &iface, "--record"])
            .arg(&log)
            .stderr(Stdio::null()),
    );
    // Both the probe and the emulator's own feedback (which under emulation starts a while
    // after the recording does).
    wait_for_file(&bus, 0x7E2, || {
        file_mentions(&log, " 7E2#") && file_mentions(&log, " 2A1#")
    })
    .await;
    let status = sim.signal("TERM").await;
    assert!(status.success(), "armhil sim piper exited with {status}");
    let text = std::fs::read_to_string(&log).expect("read the log");
    assert!(text.ends_with('\n'), "{} ends mid-line", log.display());
    let entries = parse_log(&text).unwrap_or_else(|e| panic!("{}: {e}", log.display()));
    assert!(
        entries.iter().any(|e| e.frame.raw_id() == 0x2A1),
        "no Piper feedback in {}",
        log.display()
    );
}
