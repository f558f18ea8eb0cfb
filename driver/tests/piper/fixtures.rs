//! The driver's codec against the shared byte-level fixtures in `fixtures/piper/*.log`, read
//! with `testkit::fixtures` (format: docs/fixtures.md).
//!
//! Every vector comment in a file must be checked by one of these tests (each test fails on a
//! vector name it does not know), so adding a vector without a check fails loudly.

use driver::piper::codec::*;
use testkit::fixtures;

/// A fixture vector with the panicking accessors these checks use (a missing or unreadable
/// field is a test failure naming file and line).
#[derive(Debug)]
struct Vector {
    /// 1-based line of the annotation.
    line: usize,
    inner: fixtures::Vector,
}

impl std::ops::Deref for Vector {
    type Target = fixtures::Vector;
    fn deref(&self) -> &fixtures::Vector {
        &self.inner
    }
}

impl Vector {
    fn get(&self, key: &str) -> &str {
        self.inner.text(key).unwrap_or_else(|e| panic!("{e}"))
    }

    fn int(&self, key: &str) -> i64 {
        self.inner.int(key).unwrap_or_else(|e| panic!("{e}"))
    }

    fn i32(&self, key: &str) -> i32 {
        self.int(key) as i32
    }

    fn u8(&self, key: &str) -> u8 {
        self.int(key) as u8
    }

    fn u16(&self, key: &str) -> u16 {
        self.int(key) as u16
    }

    fn f64(&self, key: &str) -> f64 {
        self.inner.float(key).unwrap_or_else(|e| panic!("{e}"))
    }

    fn expect(&self) -> &str {
        self.inner.expect().unwrap_or("ok")
    }

    fn bytes(&self) -> &[u8] {
        self.frame.data()
    }
}

/// Every Piper fixture file and the test that checks it: a file missing from the folder, or a
/// file nobody checks, fails [`every_fixture_file_is_checked`].
const TOPICS: [&str; 8] = [
    "config",
    "cpv",
    "emu_exchanges",
    "feedback",
    "firmware",
    "malformed",
    "mit",
    "motion",
];

/// The vectors of `fixtures/piper/<topic>.log`; a missing file or a malformed line fails.
fn load(topic: &str) -> Vec<Vector> {
    let path = fixtures::repo_path("piper").join(format!("{topic}.log"));
    fixtures::read_file(&path)
        .unwrap_or_else(|e| panic!("{e}"))
        .into_iter()
        .map(|inner| Vector {
            line: inner.at.line,
            inner,
        })
        .collect()
}

#[test]
fn every_fixture_file_is_checked() {
    let listed: Vec<String> = fixtures::list_dir(fixtures::repo_path("piper"))
        .unwrap_or_else(|e| panic!("{e}"))
        .iter()
        .filter_map(|p| p.file_stem().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    assert_eq!(listed, TOPICS);
}

fn unknown(v: &Vector) -> ! {
    panic!(
        "line {}: vector {} ({:03X}) has no check in this test",
        v.line,
        v.name,
        v.raw_id()
    )
}

fn decoded(v: &Vector) -> Message {
    match decode(&v.frame) {
        Ok(Some(message)) => message,
        other => panic!("line {}: {} decoded to {other:?}", v.line, v.name),
    }
}

fn joint_pair(v: &Vector, pair: JointPair) {
    let a = format!("j{}_mdeg", pair.first_joint);
    let b = format!("j{}_mdeg", pair.first_joint + 1);
    assert_eq!(pair.a_mdeg, v.i32(&a), "line {}", v.line);
    assert_eq!(pair.b_mdeg, v.i32(&b), "line {}", v.line);
}

#[test]
fn feedback_frames_decode_to_the_listed_fields() {
    let vectors = load("feedback");
    for v in &vectors {
        let line = v.line;
        match (v.name.as_str(), decoded(v)) {
            ("arm_status", Message::ArmStatus(s)) => {
                assert_eq!(u8::from(s.ctrl_mode), v.u8("ctrl_mode"), "line {line}");
                assert!(
                    s.ctrl_mode.is_known() && s.arm_status.is_known(),
                    "line {line}"
                );
                assert_eq!(u8::from(s.arm_status), v.u8("arm_status"), "line {line}");
                assert_eq!(u8::from(s.mode_feed), v.u8("mode_feed"), "line {line}");
                assert_eq!(
                    u8::from(s.teach_status),
                    v.u8("teach_status"),
                    "line {line}"
                );
                assert_eq!(
                    u8::from(s.motion_status),
                    v.u8("motion_status"),
                    "line {line}"
                );
                assert_eq!(s.trajectory_num, v.u8("trajectory_num"), "line {line}");
                assert_eq!(
                    s.angle_limit_exceeded.0,
                    v.u8("limit_err_mask"),
                    "line {line}"
                );
                assert_eq!(s.comm_error.0, v.u8("comm_err_mask"), "line {line}");
                assert_eq!(s.encode(), v.frame, "line {line}: re-encode");
            }
            ("end_pose_1", Message::EndPose(EndPosePart::Xy { x_um, y_um })) => {
                assert_eq!((x_um, y_um), (v.i32("x_um"), v.i32("y_um")), "line {line}");
            }
            ("end_pose_2", Message::EndPose(EndPosePart::ZRx { z_um, rx_mdeg })) => {
                assert_eq!(
                    (z_um, rx_mdeg),
                    (v.i32("z_um"), v.i32("rx_mdeg")),
                    "line {line}"
                );
            }
            ("end_pose_3", Message::EndPose(EndPosePart::RyRz { ry_mdeg, rz_mdeg })) => {
                assert_eq!(
                    (ry_mdeg, rz_mdeg),
                    (v.i32("ry_mdeg"), v.i32("rz_mdeg")),
                    "line {line}"
                );
            }
            ("joints_12" | "joints_34" | "joints_56", Message::Joints(pair)) => joint_pair(v, pair),
            ("gripper", Message::Gripper(g)) => {
                assert_eq!(g.stroke_um, v.i32("stroke_um"), "line {line}");
                assert_eq!(i64::from(g.torque_mnm), v.int("torque_mnm"), "line {line}");
                assert_eq!(g.status.0, v.u8("status"), "line {line}");
                let s = g.status;
                let bits = [
                    (s.under_voltage(), "under_voltage"),
                    (s.motor_over_temp(), "motor_over_temp"),
                    (s.over_current(), "over_current"),
                    (s.driver_over_temp(), "driver_over_temp"),
                    (s.sensor_fault(), "sensor_fault"),
                    (s.driver_error(), "driver_error"),
                    (s.enabled(), "enabled"),
                    (s.homed(), "homed"),
                ];
                for (bit, key) in bits {
                    assert_eq!(i64::from(bit), v.int(key), "line {line}: {key}");
                }
            }
            ("high_speed", Message::HighSpeed(h)) => {
                assert_eq!(h.joint, v.u8("joint"), "line {line}");
                assert_eq!(
                    i64::from(h.speed_mrad_s),
                    v.int("speed_mrad_s"),
                    "line {line}"
                );
                assert_eq!(i64::from(h.current_ma), v.int("current_ma"), "line {line}");
                assert_eq!(
                    i64::from(h.position_mrad),
                    v.int("position_mrad"),
                    "line {line}"
                );
            }
            ("low_speed", Message::LowSpeed(l)) => {
                assert_eq!(l.joint, v.u8("joint"), "line {line}");
                assert_eq!(l.bus_voltage_dv, v.u16("bus_voltage_dv"), "line {line}");
                assert_eq!(
                    i64::from(l.driver_temp_c),
                    v.int("driver_temp_c"),
                    "line {line}"
                );
                assert_eq!(
                    i64::from(l.motor_temp_c),
                    v.int("motor_temp_c"),
                    "line {line}"
                );
                assert_eq!(l.status.0, v.u8("status"), "line {line}");
                assert_eq!(l.bus_current_ma, v.u16("bus_current_ma"), "line {line}");
                let s = l.status;
                let bits = [
                    (s.under_voltage(), "under_voltage"),
                    (s.motor_over_temp(), "motor_over_temp"),
                    (s.over_current(), "over_current"),
                    (s.driver_over_temp(), "driver_over_temp"),
                    (s.collision(), "collision"),
                    (s.driver_error(), "driver_error"),
                    (s.enabled(), "enabled"),
                    (s.stall(), "stall"),
                ];
                for (bit, key) in bits {
                    assert_eq!(i64::from(bit), v.int(key), "line {line}: {key}");
                }
            }
            ("end_vel_acc", Message::EndVelAcc(e)) => {
                assert_eq!(e.joint, v.u8("joint"), "line {line}");
                assert_eq!(e.lin_vel_mm_s, v.u16("lin_vel_mm_s"), "line {line}");
                assert_eq!(e.ang_vel_mrad_s, v.u16("ang_vel_mrad_s"), "line {line}");
                assert_eq!(e.lin_acc_mm_s2, v.u16("lin_acc_mm_s2"), "line {line}");
                assert_eq!(e.ang_acc_mrad_s2, v.u16("ang_acc_mrad_s2"), "line {line}");
            }
            _ => unknown(v),
        }
    }
}

#[test]
fn motion_commands_encode_to_the_listed_bytes() {
    let vectors = load("motion");
    let mut i = 0;
    while i < vectors.len() {
        let v = &vectors[i];
        let line = v.line;
        match v.name.as_str() {
            "motion_ctrl_1" => {
                let cmd = MotionCtrl1 {
                    estop: v.u8("estop").into(),
                    track: v.u8("track").into(),
                    drag_teach: v.u8("drag_teach").into(),
                    traj_index: v.u8("traj_index"),
                    name_index: v.u16("name_index"),
                    crc16: v.u16("crc16"),
                };
                assert_eq!(cmd.encode(), v.frame, "line {line}");
            }
            "mode_ctrl" => {
                let cmd = ModeCtrl {
                    ctrl_mode: v.u8("ctrl_mode").into(),
                    move_mode: v.u8("move_mode").into(),
                    speed_pct: v.u8("speed_pct"),
                    mit_mode: v.u8("mit_mode").into(),
                    dwell_s: v.u8("dwell_s"),
                    install_pos: v.u8("install_pos").into(),
                };
                assert!(
                    cmd.move_mode.is_known() && cmd.mit_mode.is_known(),
                    "line {line}"
                );
                assert_eq!(cmd.encode(), v.frame, "line {line}");
                assert_eq!(
                    decoded(v),
                    Message::ModeEcho(cmd),
                    "line {line}: leader echo"
                );
            }
            "end_pose_cmd_1" => {
                // The three frames of one target follow each other.
                let target = EndPoseTarget {
                    x_um: v.i32("x_um"),
                    y_um: v.i32("y_um"),
                    z_um: vectors[i + 1].i32("z_um"),
                    rx_mdeg: vectors[i + 1].i32("rx_mdeg"),
                    ry_mdeg: vectors[i + 2].i32("ry_mdeg"),
                    rz_mdeg: vectors[i + 2].i32("rz_mdeg"),
                };
                assert_eq!(vectors[i + 1].name, "end_pose_cmd_2");
                assert_eq!(vectors[i + 2].name, "end_pose_cmd_3");
                let frames = target.encode();
                for (k, frame) in frames.iter().enumerate() {
                    assert_eq!(*frame, vectors[i + k].frame, "line {}", vectors[i + k].line);
                }
                i += 3;
                continue;
            }
            "joint_cmd_12" => {
                let mut angles_mdeg = [0; 6];
                for (k, slot) in angles_mdeg.iter_mut().enumerate() {
                    *slot = vectors[i + k / 2].i32(&format!("j{}_mdeg", k + 1));
                }
                let frames = JointTargets { angles_mdeg }.encode();
                for (k, frame) in frames.iter().enumerate() {
                    let fv = &vectors[i + k];
                    assert_eq!(*frame, fv.frame, "line {}", fv.line);
                    match decoded(fv) {
                        Message::JointCmdEcho(pair) => joint_pair(fv, pair),
                        other => panic!("line {}: {other:?}", fv.line),
                    }
                }
                i += 3;
                continue;
            }
            "move_c_point" => {
                assert_eq!(
                    encode_move_c_point(v.u8("point").into()),
                    v.frame,
                    "line {line}"
                );
            }
            "gripper_cmd" => {
                let cmd = GripperCtrl {
                    stroke_um: v.i32("stroke_um"),
                    effort_mnm: v.u16("effort_mnm"),
                    enable: v.int("enable") == 1,
                    clear_error: v.int("clear_error") == 1,
                    set_zero: v.u8("set_zero") == GRIPPER_SET_ZERO,
                };
                assert_eq!(
                    u8::from(cmd.enable) | u8::from(cmd.clear_error) << 1,
                    v.u8("code")
                );
                assert_eq!(cmd.encode(), v.frame, "line {line}");
                assert_eq!(
                    decoded(v),
                    Message::GripperCmdEcho(cmd),
                    "line {line}: leader echo"
                );
            }
            "leader_home" => {
                let action = match v.get("action") {
                    "restore" => LeaderHome::Restore,
                    "leader_home" => LeaderHome::LeaderHome,
                    "both_home" => LeaderHome::BothHome,
                    other => panic!("line {line}: action {other}"),
                };
                assert_eq!(action.encode(), v.frame, "line {line}");
            }
            "led" => {
                let cmd = LedCtrl {
                    enable: v.int("enable") == 1,
                    joint: v.u8("joint"),
                    led: v.u8("led"),
                    rgb: [v.u8("r"), v.u8("g"), v.u8("b")],
                    counter: v.u8("counter"),
                };
                assert_eq!(cmd.encode(), v.frame, "line {line}");
            }
            _ => unknown(v),
        }
        i += 1;
    }
}

fn packing(v: &Vector) -> MitPacking {
    match v.get("packing") {
        "t8_crc" => MitPacking::Torque8Crc,
        "t12" => MitPacking::Torque12,
        other => panic!("line {}: packing {other}", v.line),
    }
}

#[test]
fn mit_frames_match_both_packings() {
    for v in &load("mit") {
        assert_eq!(v.name, "mit_cmd", "line {}", v.line);
        let line = v.line;
        let packing = packing(v);
        let joint = v.u8("joint");
        let raw = MitRaw {
            p: v.u16("p_raw"),
            v: v.u16("v_raw"),
            kp: v.u16("kp_raw"),
            kd: v.u16("kd_raw"),
            t: v.u16("t_raw"),
        };
        if v.expect() == "bad_crc" {
            let result = MitRaw::decode(&v.frame, packing);
            assert!(
                matches!(result, Err(DecodeError::BadCrc { .. })),
                "line {line}: {result:?}"
            );
            continue;
        }
        assert_eq!(v.expect(), "ok", "line {line}");
        assert_eq!(raw.encode(joint, packing), v.frame, "line {line}: encode");
        assert_eq!(
            MitRaw::decode(&v.frame, packing),
            Ok((joint, raw)),
            "line {line}: decode"
        );
        if packing == MitPacking::Torque8Crc {
            assert_eq!(v.bytes()[7] & 0xF, v.u8("crc"), "line {line}: crc nibble");
        }
        if v.has("p_rad") {
            let si = MitCommand {
                p_rad: v.f64("p_rad"),
                v_rad_s: v.f64("v_rad_s"),
                kp: v.f64("kp"),
                kd: v.f64("kd"),
                t_nm: v.f64("t_nm"),
            };
            assert_eq!(si.quantise(packing), raw, "line {line}: quantise");
            // Decoding loses at most one LSB of each field.
            let back = raw.to_si(packing);
            let (lo, hi) = packing.torque_range_nm();
            let t_lsb = (hi - lo)
                / if packing == MitPacking::Torque12 {
                    4095.0
                } else {
                    255.0
                };
            assert!(
                (back.p_rad - si.p_rad).abs() <= 25.0 / 65535.0,
                "line {line}"
            );
            assert!(
                (back.v_rad_s - si.v_rad_s).abs() <= 90.0 / 4095.0,
                "line {line}"
            );
            assert!((back.kp - si.kp).abs() <= 500.0 / 4095.0, "line {line}");
            assert!((back.kd - si.kd).abs() <= 10.0 / 4095.0, "line {line}");
            assert!((back.t_nm - si.t_nm).abs() <= t_lsb, "line {line}");
        }
    }
}

#[test]
fn config_frames_encode_and_decode() {
    for v in &load("config") {
        if !check_config(v) {
            unknown(v);
        }
    }
}

/// Check one configuration vector; false for a name this check does not know.
fn check_config(v: &Vector) -> bool {
    {
        let line = v.line;
        match v.name.as_str() {
            "leader_follower" => {
                let cmd = LeaderFollowerConfig {
                    linkage: v.u8("linkage").into(),
                    feedback_offset: v.u8("feedback_offset").into(),
                    ctrl_offset: v.u8("ctrl_offset").into(),
                    target_offset: v.u8("target_offset").into(),
                };
                assert_eq!(cmd.encode(), v.frame, "line {line}");
            }
            "motor_enable" => {
                let motor = match v.u8("motor") {
                    7 => MotorSelect::All,
                    0xFF => MotorSelect::AllWithGripper,
                    joint => MotorSelect::Joint(joint),
                };
                assert_eq!(
                    encode_motor_enable(motor, v.int("enable") == 1),
                    v.frame,
                    "line {line}"
                );
                assert_eq!(v.bytes()[1], v.u8("flag"));
            }
            "query_joint" => {
                let query = if v.int("kind") == 1 {
                    JointQuery::Limits
                } else {
                    JointQuery::MaxAcc
                };
                assert_eq!(
                    encode_joint_query(v.u8("joint"), query),
                    v.frame,
                    "line {line}"
                );
            }
            "joint_limits" | "set_joint_limits" => {
                let limits = JointLimits {
                    joint: v.u8("joint"),
                    max_angle_ddeg: v.int("max_angle_ddeg") as i16,
                    min_angle_ddeg: v.int("min_angle_ddeg") as i16,
                    max_speed_crad_s: v.u16("max_speed_crad_s"),
                };
                if v.name == "joint_limits" {
                    assert_eq!(decoded(v), Message::JointLimits(limits), "line {line}");
                } else {
                    assert_eq!(limits.encode_set(), v.frame, "line {line}");
                }
            }
            "joint_config" => {
                let cmd = JointConfig {
                    joint: v.u8("joint"),
                    set_zero: v.u8("set_zero") == APPLY,
                    apply_acc: v.u8("apply_acc") == APPLY,
                    max_acc_crad_s2: v.u16("max_acc_crad_s2"),
                    clear_error: v.u8("clear_error") == APPLY,
                };
                assert_eq!(cmd.encode(), v.frame, "line {line}");
            }
            "ack" => {
                let ack = Ack {
                    cmd: v.u8("cmd").into(),
                    zero_ok: v.int("zero_ok") == 1,
                    traj_index: v.u8("traj_index"),
                    pkg_status: v.u8("pkg_status"),
                    name_index: v.u16("name_index"),
                    crc16: v.u16("crc16"),
                };
                assert!(ack.cmd.is_known(), "line {line}");
                assert_eq!(decoded(v), Message::Ack(ack), "line {line}");
            }
            "param" => {
                let query = match v.u8("query") {
                    0 => None,
                    1 => Some(ParamQuery::EndParams),
                    2 => Some(ParamQuery::Collision),
                    3 => Some(ParamQuery::TrajectoryIndex),
                    4 => Some(ParamQuery::GripperTeach),
                    other => panic!("line {line}: query {other}"),
                };
                let reset = match v.u8("reset") {
                    0 => None,
                    1 => Some(ParamReset::EndParams),
                    2 => Some(ParamReset::JointParams),
                    other => panic!("line {line}: reset {other}"),
                };
                let feedback_48x = match v.u8("feedback_48x") {
                    0 => None,
                    1 => Some(true),
                    2 => Some(false),
                    other => panic!("line {line}: feedback {other}"),
                };
                let payload = (v.u8("apply_payload") == APPLY).then(|| v.u8("payload").into());
                let cmd = ParamCommand {
                    query,
                    reset,
                    feedback_48x,
                    payload,
                };
                assert_eq!(cmd.encode(), v.frame, "line {line}");
            }
            "end_params" | "set_end_params" => {
                let p = EndParams {
                    lin_vel_mm_s: v.u16("lin_vel_mm_s"),
                    ang_vel_mrad_s: v.u16("ang_vel_mrad_s"),
                    lin_acc_mm_s2: v.u16("lin_acc_mm_s2"),
                    ang_acc_mrad_s2: v.u16("ang_acc_mrad_s2"),
                };
                if v.name == "end_params" {
                    assert_eq!(decoded(v), Message::EndParams(p), "line {line}");
                } else {
                    assert_eq!(p.encode_set(), v.frame, "line {line}");
                }
            }
            "set_collision" | "collision" | "set_assist" | "assist" => {
                let mut levels = [0u8; 6];
                for (k, level) in levels.iter_mut().enumerate() {
                    *level = v.u8(&format!("j{}", k + 1));
                }
                match v.name.as_str() {
                    "set_collision" => assert_eq!(
                        CollisionLevels { levels }.encode_set(),
                        v.frame,
                        "line {line}"
                    ),
                    "collision" => assert_eq!(
                        decoded(v),
                        Message::Collision(CollisionLevels { levels }),
                        "line {line}"
                    ),
                    "set_assist" => {
                        assert_eq!(AssistLevels { levels }.encode_set(), v.frame, "line {line}")
                    }
                    _ => assert_eq!(
                        decoded(v),
                        Message::Assist(AssistLevels { levels }),
                        "line {line}"
                    ),
                }
            }
            "joint_max_acc" => {
                let acc = JointMaxAcc {
                    joint: v.u8("joint"),
                    max_acc_crad_s2: v.u16("max_acc_crad_s2"),
                };
                assert_eq!(decoded(v), Message::JointMaxAcc(acc), "line {line}");
            }
            "set_gripper_teach" | "gripper_teach" => {
                let p = GripperTeachParams {
                    teach_coef_pct: v.u8("teach_coef_pct"),
                    max_stroke_mm: v.u8("max_stroke_mm"),
                    friction: v.u8("friction"),
                };
                if v.name == "gripper_teach" {
                    assert_eq!(decoded(v), Message::GripperTeach(p), "line {line}");
                } else {
                    assert_eq!(p.encode_set(), v.frame, "line {line}");
                }
            }
            "upgrade_mode" => {
                assert_eq!(encode_upgrade_mode(v.u8("mode")), v.frame, "line {line}");
            }
            _ => return false,
        }
    }
    true
}

#[test]
fn firmware_reply_is_reassembled_from_eleven_frames() {
    let mut assembler = FirmwareAssembler::new();
    let mut last: Option<FirmwareInfo> = None;
    let mut replies = 0;
    let mut parts_in_reply = 0;
    for v in &load("firmware") {
        let line = v.line;
        match v.name.as_str() {
            "firmware_query" => {
                assert_eq!(
                    decode(&v.frame),
                    Ok(None),
                    "line {line}: a query is not a reply part"
                );
                if v.bytes().len() == 8 {
                    assert_eq!(encode_firmware_query(), v.frame, "line {line}");
                }
            }
            "firmware_reply_part" => {
                let Message::FirmwarePart(part) = decoded(v) else {
                    panic!("line {line}")
                };
                parts_in_reply += 1;
                assert_eq!(v.int("part"), parts_in_reply, "line {line}");
                last = assembler.push(&part);
                if parts_in_reply < 11 {
                    assert!(last.is_none(), "line {line}: complete before part 11");
                }
            }
            "firmware_reply" => {
                let info = last
                    .take()
                    .unwrap_or_else(|| panic!("line {line}: reply incomplete"));
                assert_eq!(info.hardware, v.get("hardware"), "line {line}");
                assert_eq!(info.ratio, v.get("ratio"), "line {line}");
                assert_eq!(info.node_type, v.get("node_type"), "line {line}");
                assert_eq!(info.software, v.get("software"), "line {line}");
                assert_eq!(info.date, v.get("date"), "line {line}");
                assert_eq!(info.node, v.get("node"), "line {line}");
                let version = info
                    .version
                    .unwrap_or_else(|| panic!("line {line}: version"));
                let expected_packing = match v.get("mit_packing") {
                    "t12" => MitPacking::Torque12,
                    _ => MitPacking::Torque8Crc,
                };
                assert_eq!(version.mit_packing(), expected_packing, "line {line}");
                assert_eq!(
                    i64::from(version.uses_dh_offset()),
                    v.int("dh_offset"),
                    "line {line}"
                );
                replies += 1;
                parts_in_reply = 0;
            }
            _ => unknown(v),
        }
    }
    assert_eq!(replies, 3);
}

#[test]
fn cpv_frames_round_trip() {
    for v in &load("cpv") {
        assert_eq!(v.name, "cpv");
        let mode = v.get("mode").as_bytes()[0];
        let param = v.get("param").as_bytes();
        let cpv = CpvFrame {
            motor: v.u8("motor"),
            mode: mode.into(),
            param: [param[0], param[1]],
            value: v.i32("value"),
        };
        assert_eq!(CpvFrame::decode(&v.frame), Ok(cpv), "line {}", v.line);
        if v.bytes().len() == 8 {
            assert_eq!(cpv.encode(), v.frame, "line {}", v.line);
        }
        let expect_message = cpv.mode == CpvMode::Answer;
        assert_eq!(
            matches!(decode(&v.frame), Ok(Some(Message::Cpv(_)))),
            expect_message,
            "line {}",
            v.line
        );
    }
}

#[test]
fn malformed_frames_get_the_documented_handling() {
    for v in &load("malformed") {
        let line = v.line;
        match v.expect() {
            "bad_dlc" => {
                let result = if v.name == "mit_cmd" {
                    MitRaw::decode(&v.frame, MitPacking::Torque8Crc).map(|_| None)
                } else {
                    decode(&v.frame)
                };
                assert!(
                    matches!(result, Err(DecodeError::BadDlc { .. })),
                    "line {line}: {result:?}"
                );
            }
            "out_of_range" => {
                if v.name == "motor_enable" {
                    // Host-side frame: the driver never encodes it (MotorSelect::Joint is checked
                    // by the client); its decoder does not exist, so only check the byte.
                    assert_eq!(v.bytes()[0], v.u8("motor"));
                    continue;
                }
                let result = decode(&v.frame);
                assert!(
                    matches!(result, Err(DecodeError::OutOfRange { field: "joint", .. })),
                    "line {line}: {result:?}"
                );
            }
            "unknown_enum" => match (v.name.as_str(), decoded(v)) {
                ("arm_status", Message::ArmStatus(s)) => {
                    assert!(!s.ctrl_mode.is_known() && !s.arm_status.is_known());
                    assert!(!s.mode_feed.is_known() && !s.teach_status.is_known());
                    assert_eq!(
                        s.ctrl_mode,
                        CtrlMode::Unknown(v.u8("ctrl_mode")),
                        "line {line}"
                    );
                    assert_eq!(s.trajectory_num, v.u8("trajectory_num"), "line {line}");
                }
                ("mode_ctrl", Message::ModeEcho(m)) => {
                    assert_eq!(
                        m.move_mode,
                        MoveMode::Unknown(v.u8("move_mode")),
                        "line {line}"
                    );
                    assert_eq!(m.speed_pct, v.u8("speed_pct"), "line {line}");
                }
                ("ack", Message::Ack(a)) => {
                    assert_eq!(a.cmd, AckedCommand::Unknown(v.u8("cmd")), "line {line}");
                }
                _ => unknown(v),
            },
            "ignore" => assert_eq!(decode(&v.frame), Ok(None), "line {line}"),
            other => panic!("line {line}: expect={other} has no check"),
        }
    }
}

/// The emulator's own exchange vectors (`emu_exchanges.log`, same format): every one of them
/// must agree with the driver's codec too. A missing file, or a vector name or `expect=` this
/// test has no check for, fails.
#[test]
fn emulator_vectors_agree_with_the_driver_codec() {
    let vectors = load("emu_exchanges");
    let mut assembler = FirmwareAssembler::new();
    let mut last = None;
    let mut unknown = Vec::new();
    for v in &vectors {
        let line = v.line;
        match v.name.as_str() {
            _ if v.expect() != "ok" => {
                // Malformed host frames test the emulator's rejection. The driver never sends
                // them; seeing one on the bus it must not take it for arm feedback.
                assert!(
                    matches!(
                        v.expect(),
                        "bad_dlc" | "out_of_range" | "unknown_enum" | "ignore"
                    ),
                    "line {line}: expect={} has no check",
                    v.expect()
                );
                assert_eq!(decode(&v.frame), Ok(None), "line {line}: {}", v.expect());
            }
            "motion_ctrl_1" => {
                let cmd = MotionCtrl1 {
                    estop: v.u8("estop").into(),
                    track: v.u8("track").into(),
                    drag_teach: v.u8("drag_teach").into(),
                    traj_index: v.u8("traj_index"),
                    name_index: v.u16("name_index"),
                    crc16: v.u16("crc16"),
                };
                assert_eq!(cmd.encode(), v.frame, "line {line}");
            }
            "cpv" => {
                let param = v.get("param").as_bytes();
                let cpv = CpvFrame {
                    motor: v.u8("motor"),
                    mode: v.get("mode").as_bytes()[0].into(),
                    param: [param[0], param[1]],
                    value: v.i32("value"),
                };
                assert_eq!(CpvFrame::decode(&v.frame), Ok(cpv), "line {line}");
                assert_eq!(cpv.encode(), v.frame, "line {line}");
            }
            "firmware_query" => {
                assert_eq!(encode_firmware_query(), v.frame, "line {line}");
                assert_eq!(decode(&v.frame), Ok(None), "line {line}: not a reply part");
            }
            "firmware_reply_part" => {
                let Message::FirmwarePart(part) = decoded(v) else {
                    panic!("line {line}: not a firmware part")
                };
                last = assembler.push(&part);
            }
            "firmware_reply" => {
                let info: FirmwareInfo = last
                    .take()
                    .unwrap_or_else(|| panic!("line {line}: reply incomplete"));
                assert_eq!(info.hardware, v.get("hardware"), "line {line}");
                assert_eq!(info.software, v.get("software"), "line {line}");
                assert_eq!(info.date, v.get("date"), "line {line}");
            }
            _ if check_config(v) => {}
            _ => unknown.push(format!("line {line}: {}", v.name)),
        }
    }
    assert!(unknown.is_empty(), "vectors without a check: {unknown:#?}");
}
