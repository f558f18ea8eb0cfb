//! Driver conformance against the shared fixtures (`fixtures/robstride/`: the worked examples and
//! the reply matrix of docs/protocols/robstride.md): the driver
//! sends exactly the fixture's request bytes and decodes the fixture's replies to the fields
//! written beside them. A scripted node on the virtual bus plays the motor.

use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Duration;

use bus::virtual_bus::{VirtualBus, VirtualBusConfig};
use bus::{CanBus, CanFrame};
use driver::robstride::codec::{self, Incoming};
use driver::robstride::{
    Baud, DriverConfig, FeedbackKind, Model, MotorMode, OpControl, Param, ParamValue, Protocol,
    RangeTable, RobstrideDriver, RobstrideError,
};
use testkit::fixtures::Vector;

/// The vectors of one fixture file (a missing file or a malformed line fails).
fn parse_fixture(name: &str) -> Vec<Vector> {
    testkit::fixtures::read_file(testkit::fixtures::repo_path("robstride").join(name))
        .unwrap_or_else(|e| panic!("{e}"))
}

/// Both RobStride fixture files by vector name; a name used twice fails.
fn fixtures() -> BTreeMap<String, Vector> {
    let mut all = BTreeMap::new();
    for v in parse_fixture("spec_examples.log")
        .into_iter()
        .chain(parse_fixture("reply_matrix.log"))
    {
        if let Some(old) = all.insert(v.name.clone(), v) {
            panic!("{}: vector name {} used twice", old.at, old.name);
        }
    }
    all
}

fn num(v: &Vector, key: &str) -> f64 {
    // Integers (hex allowed) first; reals such as `angle_rad=3.812` otherwise.
    match v.int(key) {
        Ok(int) => int as f64,
        Err(_) => v.float(key).unwrap_or_else(|e| panic!("{e}")),
    }
}

fn model_of(v: &Vector) -> Model {
    Model::parse(v.text("model").unwrap_or_else(|e| panic!("{e}"))).expect("model field")
}

#[test]
fn status_fixtures_decode_to_their_fields() {
    let all = fixtures();
    let mut checked = 0;
    for v in all.values() {
        let kind = v.fields["type"].as_str();
        if v.fields["dir"] != "m2h"
            || !(kind == "2" || kind == "24")
            || v.fields.contains_key("version")
        {
            continue;
        }
        let ranges = model_of(v).ranges(RangeTable::Manual);
        let decoded = codec::decode(&v.frame, 0xFD, Duration::ZERO, |_| Some(ranges));
        let Some(Incoming::Feedback(fb)) = decoded else {
            panic!("{} did not decode as feedback: {decoded:?}", v.name);
        };
        let tol = num(v, "tol");
        assert_eq!(f64::from(fb.motor_id), num(v, "motor"));
        let mode = match fb.mode {
            MotorMode::Reset => 0.0,
            MotorMode::Calibration => 1.0,
            MotorMode::Run => 2.0,
            MotorMode::Brake => 3.0,
        };
        assert_eq!(mode, num(v, "state"), "{}", v.name);
        assert_eq!(f64::from(fb.faults.0), num(v, "faults"));
        assert!(
            (f64::from(fb.angle_rad) - num(v, "angle_rad")).abs() <= tol,
            "{fb:?}"
        );
        assert!((f64::from(fb.speed_rad_s) - num(v, "speed_rad_s")).abs() <= tol);
        assert!((f64::from(fb.torque_nm) - num(v, "torque_nm")).abs() <= tol);
        assert!((f64::from(fb.temperature_c) - num(v, "temp_c")).abs() <= 0.05);
        let expected_kind = if kind == "24" {
            FeedbackKind::ActiveReport
        } else {
            FeedbackKind::Reply
        };
        assert_eq!(fb.kind, expected_kind);
        checked += 1;
    }
    assert!(checked >= 5, "only {checked} status vectors");
}

#[test]
fn other_reply_fixtures_decode() {
    let all = fixtures();
    let decode = |name: &str| codec::decode(&all[name].frame, 0xFD, Duration::ZERO, |_| None);
    assert_eq!(
        decode("ping_reply"),
        Some(Incoming::DeviceId {
            motor_id: 0x7F,
            uid: [1, 2, 3, 4, 5, 6, 7, 8]
        })
    );
    assert_eq!(
        decode("version_reply"),
        Some(Incoming::Version {
            motor_id: 0x7F,
            version: [0, 3, 1, 41]
        })
    );
    let Some(Incoming::Param {
        ok: true,
        index: 0x701E,
        value,
        ..
    }) = decode("read_loc_kp_reply")
    else {
        panic!("loc_kp reply");
    };
    assert_eq!(
        f64::from(f32::from_le_bytes(value)),
        num(&all["read_loc_kp_reply"], "value")
    );
    assert!(matches!(
        decode("read_failure_reply"),
        Some(Incoming::Param {
            ok: false,
            motor_id: 0x15,
            ..
        })
    ));
    let Some(Incoming::Fault { report, .. }) = decode("fault_frame_stall") else {
        panic!("fault")
    };
    assert_eq!(
        f64::from(report.fault_word),
        num(&all["fault_frame_stall"], "fault_word")
    );
    assert!(report.stall_overload() && report.phase_over_current()[0]);
    let Some(Incoming::Fault { report, .. }) = decode("fault_frame") else {
        panic!("fault")
    };
    assert!(report.over_temperature() && report.over_temperature_warning());
    // Requests (host to motor) are not replies.
    assert_eq!(decode("enable"), None);
    assert_eq!(decode("read_loc_kp"), None);
}

#[test]
fn op_control_encodes_the_worked_example() {
    let all = fixtures();
    let v = &all["op_control"];
    let cmd = OpControl {
        angle_rad: num(v, "angle_rad") as f32,
        speed_rad_s: num(v, "speed_rad_s") as f32,
        kp: num(v, "kp") as f32,
        kd: num(v, "kd") as f32,
        torque_nm: num(v, "torque_nm") as f32,
    };
    let frame =
        codec::op_control_frame(0x7F, &cmd, &Model::RS03.ranges(RangeTable::Manual)).unwrap();
    assert_eq!(frame, v.frame);
}

/// A scripted motor: for each expected request, check the bytes and answer with a frame.
async fn scripted_motor(
    node: bus::virtual_bus::VirtualNode,
    script: Vec<(CanFrame, Option<CanFrame>)>,
) -> Result<(), String> {
    for (expected, reply) in script {
        let received = node.recv().await.map_err(|e| e.to_string())?;
        if received.frame != expected {
            return Err(format!("expected {expected}, got {}", received.frame));
        }
        if let Some(reply) = reply {
            node.send(reply).await.map_err(|e| e.to_string())?;
        }
    }
    // Dropping the node would discard a reply still queued for the wire.
    tokio::time::sleep(Duration::from_millis(100)).await;
    Ok(())
}

#[tokio::test(start_paused = true)]
async fn driver_requests_match_the_fixture_bytes() {
    let all = fixtures();
    let f = |name: &str| all[name].frame;
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let host: Arc<dyn CanBus> = Arc::new(bus.attach("host"));
    let motor_node = bus.attach("motor");
    let enable_reply = f("enable_reply");
    let status = f("enable_reply");
    let script = vec![
        (f("ping"), Some(f("ping_reply"))),
        (f("enable"), Some(enable_reply)),
        (f("stop_clear"), Some(status)),
        (f("version_read"), Some(f("version_reply"))),
        (f("set_zero"), Some(status)),
        (f("write_run_mode"), Some(status)),
        (f("write_limit_spd"), Some(status)),
        (f("read_loc_kp"), Some(f("read_loc_kp_reply"))),
        (f("active_report_on"), None),
        (f("save"), Some(status)),
        (f("baud_500k"), Some(f("ping_reply"))),
        (f("protocol_mit"), Some(f("ping_reply"))),
        (f("op_control"), Some(status)),
        (f("write_spd_ref"), Some(status)),
        (f("set_can_id"), Some(f("set_can_id_reply"))),
    ];
    let responder = tokio::spawn(scripted_motor(motor_node, script));
    let driver = RobstrideDriver::new(host, DriverConfig::default());
    let mut motor = driver.motor(0x7F, Model::RS03).unwrap();
    assert_eq!(motor.device_id().await.unwrap(), [1, 2, 3, 4, 5, 6, 7, 8]);
    assert_eq!(motor.enable().await.unwrap().mode, MotorMode::Run);
    motor.disable(true).await.unwrap();
    assert_eq!(motor.firmware_version().await.unwrap(), [0, 3, 1, 41]);
    motor.set_zero().await.unwrap();
    motor.write_param(Param::RunMode, 5.0).await.unwrap();
    motor.write_param(Param::LimitSpd, 2.0).await.unwrap();
    assert_eq!(
        motor.read_param(Param::LocKp).await.unwrap(),
        ParamValue::F32(30.0)
    );
    motor.set_active_reporting(true).await.unwrap();
    motor.save().await.unwrap();
    motor.set_baud(Baud::K500).await.unwrap();
    motor.set_protocol(Protocol::Mit).await.unwrap();
    motor
        .op_control(OpControl {
            angle_rad: 0.0,
            speed_rad_s: 0.0,
            kp: 20.0,
            kd: 1.0,
            torque_nm: 0.0,
        })
        .await
        .unwrap();
    motor.write_param(Param::SpdRef, -3.5).await.unwrap();
    motor.set_can_id(0x01).await.unwrap();
    assert_eq!(motor.can_id(), 0x01);
    responder.await.unwrap().unwrap();
}

#[tokio::test(start_paused = true)]
async fn silence_is_a_typed_timeout_and_bad_values_are_refused() {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let host: Arc<dyn CanBus> = Arc::new(bus.attach("host"));
    let _silent = bus.attach("silent");
    let driver = RobstrideDriver::new(host, DriverConfig::default());
    let motor = driver.motor(0x11, Model::RS00).unwrap();
    assert!(matches!(
        motor.enable().await,
        Err(RobstrideError::Timeout { motor: 0x11, .. })
    ));
    let too_fast = OpControl {
        speed_rad_s: 40.0,
        ..OpControl::default()
    };
    assert!(matches!(
        motor.op_control(too_fast).await,
        Err(RobstrideError::OutOfRange {
            field: "speed_rad_s",
            ..
        })
    ));
    assert!(matches!(
        motor.set_current(-17.0).await,
        Err(RobstrideError::OutOfRange { .. })
    ));
    assert!(matches!(
        driver.motor(0x11, Model::RS00),
        Err(RobstrideError::MotorInUse { motor: 0x11 })
    ));
    assert!(matches!(
        driver.motor(0x80, Model::RS00),
        Err(RobstrideError::InvalidCanId { id: 0x80 })
    ));
}

#[tokio::test(start_paused = true)]
async fn read_failures_and_write_refusals_are_typed() {
    let all = fixtures();
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let host: Arc<dyn CanBus> = Arc::new(bus.attach("host"));
    let node = bus.attach("motor");
    let read_string = CanFrame::extended(0x1100_FD15, &[0x03, 0x10, 0, 0, 0, 0, 0, 0]).unwrap();
    let write_ro = CanFrame::extended(0x1200_FD15, &[0x19, 0x70, 0, 0, 0, 0, 0, 0]).unwrap();
    let refusal = CanFrame::extended(0x1101_15FD, &[0x19, 0x70, 0, 0, 0, 0, 0, 0]).unwrap();
    let responder = tokio::spawn(scripted_motor(
        node,
        vec![
            (read_string, Some(all["read_failure_reply"].frame)),
            (write_ro, Some(refusal)),
        ],
    ));
    let driver = RobstrideDriver::new(host, DriverConfig::default());
    let motor = driver.motor(0x15, Model::RS03).unwrap();
    let read = motor
        .read_raw(0x1003, driver::robstride::ParamType::U32)
        .await;
    assert!(matches!(
        read,
        Err(RobstrideError::ParamReadFailed {
            motor: 0x15,
            index: 0x1003
        })
    ));
    let write = motor.write_param(Param::MechPos, 0.0).await;
    assert!(
        matches!(
            write,
            Err(RobstrideError::ParamRefused {
                motor: 0x15,
                index: 0x7019
            })
        ),
        "{write:?}"
    );
    responder.await.unwrap().unwrap();
}

/// Every vector, whichever other test replays it: a request is never taken for a reply, and a
/// reply decodes to the message its type names, from the motor its annotation names. A
/// vector without a direction or type, or with an unknown one, fails.
#[test]
fn every_vector_decodes_by_its_direction_and_type() {
    let all = fixtures();
    assert!(all.len() >= 30, "{} vectors", all.len());
    for v in all.values() {
        let int = |key: &str| v.int(key).unwrap_or_else(|e| panic!("{e}"));
        let ranges = v
            .has("model")
            .then(|| model_of(v).ranges(RangeTable::Manual));
        let decoded = codec::decode(&v.frame, 0xFD, Duration::ZERO, |_| ranges);
        let dir = v.text("dir").unwrap_or_else(|e| panic!("{e}"));
        if dir == "h2m" {
            assert_eq!(decoded, None, "{v}: a request decoded as a reply");
            continue;
        }
        assert_eq!(dir, "m2h", "{v}: unknown direction");
        let incoming = decoded.unwrap_or_else(|| panic!("{v}: reply not decoded"));
        assert_eq!(i64::from(incoming.motor_id()), int("motor"), "{v}");
        match (int("type"), incoming) {
            (0, Incoming::DeviceId { uid, .. }) => {
                let hex: String = uid.iter().map(|b| format!("{b:02X}")).collect();
                assert_eq!(hex, v.text("uid").unwrap(), "{v}");
            }
            (2, Incoming::Version { version, .. }) => {
                let text = version.map(|b| b.to_string()).join(".");
                assert_eq!(text, v.text("version").unwrap(), "{v}");
            }
            (2 | 24, Incoming::Feedback(fb)) => {
                assert_eq!(f64::from(fb.faults.0), num(v, "faults"), "{v}");
            }
            (17, Incoming::Param { ok, index, .. }) => {
                assert_eq!(ok, int("status") == 0, "{v}");
                if v.has("index") {
                    assert_eq!(i64::from(index), int("index"), "{v}");
                }
            }
            (21, Incoming::Fault { report, .. }) => {
                assert_eq!(i64::from(report.fault_word), int("fault_word"), "{v}");
                assert_eq!(i64::from(report.warning_word), int("warning_word"), "{v}");
            }
            (kind, other) => panic!("{v}: type {kind} decoded as {other:?}"),
        }
    }
}
