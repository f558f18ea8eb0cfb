//! Realman: the emulator's request framing and command handler, the driver's reply side.

use driver::realman::codec::{self as dcodec, decode, JointSpeedUnit, Message};
use sim::realman::framing::{Splitter as EmuSplitter, Unit};
use sim::realman::model::ArmModel;
use sim::realman::{Answer, Controller, ControllerConfig};

use super::input::{assert_finite, Input};

/// Splitter limit in the targets: small, so the oversize paths are reached.
const LIMIT_BYTES: usize = 512;

/// Most requests one input may send to the controller.
const MAX_REQUESTS: usize = 32;

/// Cut `stream` into pieces whose lengths come from `sizes` (cycled; 0 means 1).
fn chunks<'a>(stream: &'a [u8], sizes: &[u8]) -> Vec<&'a [u8]> {
    let mut out = Vec::new();
    let mut rest = stream;
    let mut i = 0;
    while !rest.is_empty() {
        let size = sizes
            .get(i % sizes.len().max(1))
            .copied()
            .unwrap_or(0)
            .max(1);
        let (head, tail) = rest.split_at(usize::from(size).min(rest.len()));
        out.push(head);
        rest = tail;
        i += 1;
    }
    out
}

/// Every unit of the emulator's splitter over `pieces`, or `None` once a unit is too long.
fn emu_units(pieces: &[&[u8]]) -> Option<Vec<Unit>> {
    let mut splitter = EmuSplitter::new(LIMIT_BYTES);
    let mut units = Vec::new();
    for piece in pieces {
        splitter.feed(piece, &mut units).ok()?;
    }
    Some(units)
}

/// Arbitrary bytes through the emulator's request splitter, whole and in pieces.
///
/// Input: byte 0 gives how many of the next bytes are piece sizes (`% 8`), then the sizes,
/// then the TCP byte stream.
///
/// Asserts: no panic; how the stream is cut into TCP reads changes nothing (same units, same
/// oversize verdict); every object unit starts with `{`, ends with `}` and fits the limit.
pub fn realman_framing(data: &[u8]) {
    let mut input = Input::new(data);
    let n_sizes = usize::from(input.byte().unwrap_or(0) % 8);
    let sizes = input.take(n_sizes);
    let stream = input.take(usize::MAX);
    let whole = emu_units(&[stream]);
    let pieces = emu_units(&chunks(stream, sizes));
    assert_eq!(whole, pieces, "splitting depends on how the stream is cut");
    for unit in whole.into_iter().flatten() {
        if let Unit::Object(bytes) = unit {
            assert_eq!(bytes.first(), Some(&b'{'));
            assert_eq!(bytes.last(), Some(&b'}'));
            assert!(bytes.len() <= LIMIT_BYTES);
        }
    }
}

/// Requests into a freshly booted RM65-B controller, with time passing between them.
///
/// Input: a TCP byte stream (split by the emulator's splitter, each object parsed as JSON
/// and answered); 5 ms pass after each request and 100 ms after the last (few, as the
/// physics dominates the cost of an execution).
///
/// Asserts: no panic; every reply and arrival event is one compact JSON object that the
/// driver's decoder accepts; the arm's joints, speeds and pose stay finite.
pub fn realman_command(data: &[u8]) {
    let mut splitter = EmuSplitter::new(LIMIT_BYTES);
    let mut units = Vec::new();
    // Too long a request closes the connection: what came before it is still answered.
    let _ = splitter.feed(data, &mut units);
    let mut controller = Controller::new(ControllerConfig::new(ArmModel::rm65b()))
        .expect("the default RM65-B boots");
    let client = 1;
    let requests = units.into_iter().filter_map(|u| match u {
        Unit::Object(bytes) => serde_json::from_slice::<serde_json::Value>(&bytes).ok(),
        Unit::Junk(_) => None,
    });
    for request in requests.take(MAX_REQUESTS) {
        if let Answer::Reply(text) = controller.handle(client, &request) {
            check_sent(&text);
        }
        run(&mut controller, 5);
    }
    run(&mut controller, 100);
}

fn run(controller: &mut Controller, ms: u32) {
    for _ in 0..ms {
        controller.tick();
    }
    for event in controller.take_events() {
        check_sent(&event.text);
    }
    let s = controller.snapshot();
    assert_finite("joints_rad", &s.joints_rad);
    assert_finite("speeds_rad_s", &s.speeds_rad_s);
    assert_finite("setpoint_rad", &s.setpoint_rad);
    assert_finite("pose", s.pose.position_m.iter().chain(&s.pose.euler_rad));
}

fn check_sent(text: &str) {
    assert!(
        !text.contains(['\r', '\n']),
        "a reply carries its own line end: {text:?}"
    );
    if let Err(e) = dcodec::decode_message(text) {
        panic!("the driver cannot read the emulator's reply {text:?}: {e}");
    }
}

/// Arbitrary bytes through the driver's reply side: its stream splitter (whole and in
/// pieces), the message classifier, every body decoder, and the UDP push decoder.
///
/// Input: as [`realman_framing`]; the stream is also taken as one push datagram.
///
/// Asserts: no panic; splitting does not depend on how the stream is cut; decoded numbers
/// are finite.
pub fn realman_reply(data: &[u8]) {
    let mut input = Input::new(data);
    let n_sizes = usize::from(input.byte().unwrap_or(0) % 8);
    let sizes = input.take(n_sizes);
    let stream = input.take(usize::MAX);
    let whole = driver_frames(&[stream]);
    let pieces = driver_frames(&chunks(stream, sizes));
    assert_eq!(whole, pieces, "splitting depends on how the stream is cut");
    for frame in whole {
        if let dcodec::Frame::Object(text) = frame {
            match dcodec::decode_message(&text) {
                Ok(Message::Reply { body, .. }) | Ok(Message::Notice { body, .. }) => {
                    decode_body(&body)
                }
                Ok(Message::Arrival(_)) | Err(_) => {}
            }
        }
    }
    for unit in [
        JointSpeedUnit::CentiDegPerSecond,
        JointSpeedUnit::CentiRpm,
        JointSpeedUnit::FiftiethRpm,
    ] {
        if let Ok(state) = dcodec::decode_push(stream, unit) {
            assert_finite("push joints", &state.joints_rad);
            assert_finite("push speeds", state.joint_speeds_rad_s.iter().flatten());
            assert_finite("push currents", &state.currents_a);
            assert_finite("push temperatures", &state.temperatures_c);
            assert_finite("push voltages", &state.voltages_v);
            assert_finite("push quaternion", &state.quaternion_wxyz);
            check_pose(&state.pose);
        }
    }
}

fn driver_frames(pieces: &[&[u8]]) -> Vec<dcodec::Frame> {
    let mut splitter = dcodec::Splitter::new(LIMIT_BYTES);
    let mut frames = Vec::new();
    for piece in pieces {
        splitter.push(piece);
        while let Some(frame) = splitter.next_frame() {
            frames.push(frame);
        }
    }
    frames
}

fn check_pose(pose: &dcodec::types::Pose) {
    assert_finite("pose", pose.position_m.iter().chain(&pose.euler_rad));
}

/// Every body decoder the client uses on replies: errors are fine, non-finite numbers not.
fn decode_body(body: &decode::Body) {
    let _ = decode::result_flag(body, None);
    if let Ok(p) = decode::pose(body, "pose") {
        check_pose(&p);
    }
    for key in ["joint", "min_pos", "max_pos"] {
        if let Ok(v) = decode::joints_rad(body, key) {
            assert_finite(key, &v);
        }
        if let Ok(v) = decode::joint_limits(body, key) {
            assert_finite(key, &v);
        }
    }
    for key in ["speed", "acc", "temperature", "current", "voltage"] {
        if let Ok(v) = decode::joint_rates(body, key) {
            assert_finite(key, &v);
        }
        if let Ok(v) = decode::joint_measure(body, key) {
            assert_finite(key, &v);
        }
        if let Ok(v) = decode::milli_scalar(body, key) {
            assert!(v.is_finite());
        }
    }
    if let Ok(v) = decode::install_pose(body) {
        assert_finite("install pose", &v);
    }
    let _ = format!(
        "{:?}{:?}{:?}{:?}{:?}{:?}{:?}{:?}{:?}{:?}{:?}{:?}{:?}{:?}{:?}",
        decode::software_info(body),
        decode::current_trajectory(body),
        decode::push_config(body),
        decode::work_frame(body),
        decode::tool_frame(body),
        decode::dh_table(body),
        decode::errors(body),
        decode::arm_snapshot(body),
        decode::all_state(body),
        decode::joint_flags(body),
        decode::controller_state(body),
        decode::gripper_state(body),
        decode::power_state(body),
        decode::collision_stage(body),
        decode::self_collision(body),
    );
}
