//! The emulator against every shared Realman transcript vector (fixtures/realman/*.jsonl), in
//! virtual time. Each file is one session on a freshly booted controller; vectors with a
//! `profile` run on an emulator put into that situation.

use std::time::Duration;

use sim::realman::{FirmwareProfile, RealmanFault, RealmanFaultKind, RealmanHandle};
use testkit::emulators::realman::{client, emulator, emulator_with, LineClient};
use testkit::transcript::{self, Channel, Transcript, Vector};
use tokio::io::DuplexStream;

/// Longest a vector's replies may take (a slow move at v 20).
const REPLY_WAIT: Duration = Duration::from_secs(60);
/// How long "no reply" is awaited.
const SILENCE: Duration = Duration::from_millis(600);

type Client = LineClient<DuplexStream>;

fn check_replies(v: &Vector, got: &[String], failures: &mut Vec<String>) {
    if got.len() != v.replies.len() {
        failures.push(format!(
            "{} (line {}): expected {} replies, got {}: {got:?}",
            v.name,
            v.line,
            v.replies.len(),
            got.len()
        ));
        return;
    }
    for (want, have) in v.replies.iter().zip(got) {
        if let Err(m) = transcript::matches(v.compare, want, have) {
            failures.push(format!("{} (line {}): {m}\n  got {have}", v.name, v.line));
        }
    }
}

/// Send the request and collect as many lines as the vector has replies (or silence).
async fn exchange(c: &mut Client, v: &Vector) -> Vec<String> {
    c.send(&v.request).await;
    collect(c, v.replies.len()).await
}

async fn collect(c: &mut Client, n: usize) -> Vec<String> {
    let mut got = Vec::new();
    for _ in 0..n {
        match c.line(REPLY_WAIT).await {
            Some(line) => got.push(line),
            None => break,
        }
    }
    if let Some(extra) = c.line(SILENCE).await {
        got.push(extra);
    }
    got
}

async fn next_datagram(
    emu_rx: &mut tokio::sync::mpsc::UnboundedReceiver<sim::realman::push::Datagram>,
) -> Option<String> {
    tokio::time::timeout(Duration::from_millis(100), emu_rx.recv())
        .await
        .ok()
        .flatten()
        .map(|d| d.payload)
}

async fn run_profiled(v: &Vector, failures: &mut Vec<String>) {
    let profile = v.profile.as_deref().unwrap_or_default();
    let emu: RealmanHandle = match profile {
        "legacy_err" => emulator_with(|c| c.controller.firmware = FirmwareProfile::V1_6_5).await,
        _ => emulator().await,
    };
    let mut c = client(&emu);
    match (profile, v.channel) {
        ("legacy_err", Channel::Udp) => {
            let mut rx = emu.take_datagrams().expect("datagram channel");
            c.ask(r#"{"command":"set_realtime_push","custom":{"joint_speed":true,"arm_current_status":true}}"#)
                .await;
            c.ask(r#"{"command":"movej","joint":[10000,20000,30000,40000,50000,60000],"v":20,"r":0,"trajectory_connect":0}"#)
                .await;
            tokio::time::sleep(Duration::from_millis(50)).await;
            while rx.try_recv().is_ok() {}
            let got: Vec<String> = next_datagram(&mut rx).await.into_iter().collect();
            check_replies(v, &got, failures);
        }
        ("legacy_err", Channel::Tcp) => {
            let got = exchange(&mut c, v).await;
            check_replies(v, &got, failures);
        }
        ("during_motion", _) => {
            c.ask(r#"{"command":"movej","joint":[10000,20000,30000,40000,50000,60000],"v":20,"r":0,"trajectory_connect":0}"#)
                .await;
            tokio::time::sleep(Duration::from_millis(200)).await;
            c.send(&v.request).await;
            let got: Vec<String> = c.line(REPLY_WAIT).await.into_iter().collect();
            check_replies(v, &got, failures);
        }
        _ => failures.push(format!("{}: unknown profile {profile:?}", v.name)),
    }
    emu.shutdown().await;
}

async fn check_boot_datagram(v: &Vector, failures: &mut Vec<String>) {
    let emu = emulator().await;
    let mut rx = emu.take_datagrams().expect("datagram channel");
    // The push aims at connected hosts: one client must be connected.
    let _c = client(&emu);
    tokio::time::sleep(Duration::from_millis(20)).await;
    while rx.try_recv().is_ok() {}
    let got: Vec<String> = next_datagram(&mut rx).await.into_iter().collect();
    check_replies(v, &got, failures);
    emu.shutdown().await;
}

async fn run_session(t: &Transcript, failures: &mut Vec<String>) -> usize {
    let emu = emulator().await;
    let mut c = client(&emu);
    let mut checked = 0;
    for v in &t.vectors {
        checked += 1;
        match (v.profile.as_deref(), v.channel) {
            (Some("fault_collision"), _) => {
                c.send(&v.request).await;
                let mut got: Vec<String> = c.line(REPLY_WAIT).await.into_iter().collect();
                tokio::time::sleep(Duration::from_millis(100)).await;
                emu.inject(RealmanFault::Collision).expect("inject");
                got.extend(collect(&mut c, v.replies.len().saturating_sub(1)).await);
                check_replies(v, &got, failures);
                emu.clear(RealmanFaultKind::Collision);
                c.ask(r#"{"command":"clear_system_err"}"#).await;
            }
            (Some(_), _) => run_profiled(v, failures).await,
            // Datagram vectors describe a freshly booted controller (default push flags).
            (None, Channel::Udp) => check_boot_datagram(v, failures).await,
            (None, Channel::Tcp) => {
                let got = exchange(&mut c, v).await;
                check_replies(v, &got, failures);
            }
        }
    }
    emu.shutdown().await;
    checked
}

#[tokio::test(start_paused = true)]
async fn emulator_answers_every_transcript_vector() {
    let transcripts =
        transcript::load_dir(transcript::realman_fixtures_dir()).expect("fixtures load");
    assert!(transcripts.len() >= 7, "expected the seven fixture files");
    let mut failures = Vec::new();
    let mut checked = 0;
    for t in &transcripts {
        checked += run_session(t, &mut failures).await;
    }
    assert!(checked >= 100, "only {checked} vectors checked");
    assert!(
        failures.is_empty(),
        "{} of {checked} vectors failed:\n{}",
        failures.len(),
        failures.join("\n")
    );
}
