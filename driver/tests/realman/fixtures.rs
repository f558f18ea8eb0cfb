//! Every vector in fixtures/realman: the driver's encoder produces the request bytes and its
//! decoders read the replies to the SI values the notes state.

use std::f64::consts::PI;

use driver::realman::codec::decode::{self as d, Body};
use driver::realman::codec::request::{
    self as rq, CartesianTarget, DhRow, MoveOpts, PushCustom, PushSettings,
};
use driver::realman::codec::types::*;
use driver::realman::codec::{
    decode_message, decode_push, Expect, Frame, JointSpeedUnit, Message, Request, Splitter,
};
use testkit::transcript::{load_dir, realman_fixtures_dir, Channel, Vector};

const FILES: [&str; 9] = [
    "errors",
    "gripper_hand",
    "handshake",
    "io",
    "motion",
    "params",
    "peripherals",
    "push",
    "state",
];

fn rad(deg: &[f64]) -> Vec<f64> {
    deg.iter().map(|d| d.to_radians()).collect()
}

fn pose(x: f64, y: f64, z: f64, rx: f64, ry: f64, rz: f64) -> Pose {
    Pose {
        position_m: [x, y, z],
        euler_rad: [rx, ry, rz],
    }
}

fn opts(v: u8, r: u8, connect: Connect) -> MoveOpts {
    MoveOpts {
        speed_percent: v,
        blend_percent: r,
        connect,
    }
}

const Q1: [f64; 6] = [10.0, 20.0, 30.0, 40.0, 50.0, 60.0];
const Q1_POSE: (f64, f64, f64, f64, f64, f64) = (-0.35566, -0.13471, 0.61081, 1.607, 0.008, -0.881);

fn q1_pose_z(z: f64) -> Pose {
    let p = Q1_POSE;
    pose(p.0, p.1, z, p.3, p.4, p.5)
}

fn rm65_dh(d6: f64) -> Vec<DhRow> {
    let row = |alpha: f64, a: f64, d: f64, off: f64| DhRow {
        alpha_rad: alpha.to_radians(),
        a_m: a,
        d_m: d,
        offset_rad: off.to_radians(),
    };
    vec![
        row(0.0, 0.0, 0.2405, 0.0),
        row(90.0, 0.0, 0.0, 90.0),
        row(0.0, 0.256, 0.0, 90.0),
        row(90.0, 0.0, 0.21, 0.0),
        row(-90.0, 0.0, 0.0, 0.0),
        row(90.0, 0.0, d6, 0.0),
    ]
}

/// The request each vector's name stands for, built from SI arguments.
fn request_for(name: &str) -> Option<Request> {
    let start = Connect::Start;
    let queue = Connect::Queue;
    Some(match name {
        "get_arm_software_info" => rq::get_arm_software_info(),
        n if n.starts_with("get_arm_current_trajectory") => rq::get_arm_current_trajectory(),
        n if n.starts_with("get_realtime_push") => rq::get_realtime_push(),
        "get_current_work_frame" => rq::get_current_work_frame(),
        "get_current_tool_frame" => rq::get_current_tool_frame(),
        n if n.starts_with("get_install_pose") => rq::get_install_pose(),
        "get_joint_min_pos" => rq::get_joint_min_pos(),
        n if n.starts_with("get_joint_max_pos") => rq::get_joint_max_pos(),
        "get_joint_max_acc" => rq::get_joint_max_acc(),
        "get_joint_max_speed" => rq::get_joint_max_speed(),
        n if n.starts_with("get_DH_data") => rq::get_dh_data(),
        n if n.starts_with("get_arm_power_state") => rq::get_arm_power_state(),
        "get_joint_err_flag" => rq::get_joint_err_flag(),
        n if n.starts_with("get_current_arm_state") => rq::get_current_arm_state(),
        "get_joint_degree" => rq::get_joint_degree(),
        "get_arm_all_state" => rq::get_arm_all_state(),
        "get_controller_state" => rq::get_controller_state(),
        "get_current_joint_temperature" => rq::get_current_joint_temperature(),
        "get_current_joint_current" => rq::get_current_joint_current(),
        "get_current_joint_voltage" => rq::get_current_joint_voltage(),
        n if n.starts_with("get_arm_max_line_speed") => rq::get_arm_max_line_speed(),
        n if n.starts_with("get_arm_max_line_acc") => rq::get_arm_max_line_acc(),
        n if n.starts_with("get_arm_max_angular_speed") => rq::get_arm_max_angular_speed(),
        "get_arm_max_angular_acc" => rq::get_arm_max_angular_acc(),
        n if n.starts_with("get_collision_stage") => rq::get_collision_stage(),
        "get_self_collision_enable" => rq::get_self_collision_enable(),
        "get_gripper_state" => rq::get_gripper_state(),
        // Motion.
        "movej_blocking" => rq::movej(&rad(&Q1), MoveOpts::speed(20)).ok()?,
        "movel_blocking" => rq::movel(&q1_pose_z(0.56081), MoveOpts::speed(20)).ok()?,
        "movej_p_blocking" => rq::movej_p(&q1_pose_z(0.61081), MoveOpts::speed(20)).ok()?,
        "movec_blocking" | "movec_pretty_request" => {
            let via = pose(-0.35566, -0.10471, 0.59081, 1.607, 0.008, -0.881);
            let to = if name == "movec_blocking" {
                q1_pose_z(0.57081)
            } else {
                q1_pose_z(0.61081)
            };
            rq::movec(&via, &to, 0, MoveOpts::speed(20)).ok()?
        }
        "movej_queue_first" => rq::movej(
            &rad(&[0.0, 20.0, 30.0, 40.0, 50.0, 60.0]),
            opts(20, 10, queue),
        )
        .ok()?,
        "movej_queue_last" => rq::movej(&rad(&Q1), opts(20, 0, start)).ok()?,
        "moves_point_1" => rq::moves(&q1_pose_z(0.59081), opts(20, 0, queue)).ok()?,
        "moves_point_2" => rq::moves(
            &pose(-0.34566, -0.12471, 0.58081, 1.607, 0.008, -0.881),
            opts(20, 0, queue),
        )
        .ok()?,
        "moves_point_3" => rq::moves(
            &pose(-0.33566, -0.13471, 0.57081, 1.607, 0.008, -0.881),
            opts(20, 0, start),
        )
        .ok()?,
        "set_joint_step" => rq::set_joint_step(6, 5f64.to_radians(), 10).ok()?,
        "set_pos_step" => rq::set_pos_step(Axis::Z, -0.01, 10).ok()?,
        "set_ort_step" => rq::set_ort_step(Axis::Z, 0.05, 10).ok()?,
        "set_joint_teach" => rq::set_joint_teach(1, Direction::Positive, 10).ok()?,
        "set_pos_teach" => rq::set_pos_teach(Axis::Z, Direction::Negative, 10).ok()?,
        "set_ort_teach" => rq::set_ort_teach(Axis::Z, Direction::Positive, 10).ok()?,
        n if n.starts_with("set_stop_teach") => rq::set_stop_teach(),
        "movej_canfd" => rq::movej_canfd(
            &rad(&[10.1, 20.0, 30.0, 40.0, 50.0, 60.0]),
            false,
            Smoothing::Raw,
        )
        .ok()?,
        "movep_canfd" => rq::movep_canfd(
            &CartesianTarget::Euler(q1_pose_z(0.61181)),
            false,
            Smoothing::Raw,
        )
        .ok()?,
        "movep_canfd_quat" => {
            let q = QuatPose {
                position_m: [-0.35566, -0.13471, 0.61181],
                quaternion_wxyz: [0.62662, 0.652401, -0.304221, -0.298614],
            };
            rq::movep_canfd(&CartesianTarget::Quat(q), true, Smoothing::Raw).ok()?
        }
        "movej_follow" => rq::movej_follow(&rad(&[10.2, 20.0, 30.0, 40.0, 50.0, 60.0])).ok()?,
        "movep_follow" => rq::movep_follow(&CartesianTarget::Euler(q1_pose_z(0.61281))).ok()?,
        n if n.starts_with("set_arm_pause") => rq::set_arm_pause(),
        "set_arm_continue" => rq::set_arm_continue(),
        "set_delete_current_trajectory" => rq::set_delete_current_trajectory(),
        "set_arm_delete_trajectory" => rq::set_arm_delete_trajectory(),
        "set_arm_slow_stop" => rq::set_arm_slow_stop(),
        "set_arm_stop" => rq::set_arm_stop(),
        // Motion parameters.
        "set_arm_max_line_speed" => rq::set_arm_max_line_speed(0.5).ok()?,
        "set_arm_max_line_acc" => rq::set_arm_max_line_acc(2.0).ok()?,
        "set_arm_max_angular_speed" => rq::set_arm_max_angular_speed(0.2).ok()?,
        "set_arm_max_angular_acc" => rq::set_arm_max_angular_acc(4.0).ok()?,
        "set_arm_init" => rq::set_arm_init(),
        "set_collision_stage" => rq::set_collision_stage(1).ok()?,
        "set_self_collision_enable" => rq::set_self_collision_enable(true),
        "set_DH_data" => rq::set_dh_data(&rm65_dh(0.1441)).ok()?,
        "set_DH_data_default" => rq::set_dh_data_default(),
        "set_joint_zero_offset" => {
            rq::set_joint_zero_offset(&rad(&[1.0, -2.0, 3.0, -4.0, 5.0, -6.0])).ok()?
        }
        "set_joint_zero_offset_restore" => rq::set_joint_zero_offset(&[0.0; 6]).ok()?,
        // State and joint configuration.
        "set_arm_power_off" => rq::set_arm_power(false),
        "set_arm_power_on" => rq::set_arm_power(true),
        "set_joint_en_state_off" => rq::set_joint_en_state(6, false).ok()?,
        "set_joint_en_state_on" => rq::set_joint_en_state(6, true).ok()?,
        "set_joint_max_pos" | "set_joint_max_pos_while_enabled" => {
            rq::set_joint_max_pos(6, 350f64.to_radians()).ok()?
        }
        "set_joint_min_pos" => rq::set_joint_min_pos(6, (-350f64).to_radians()).ok()?,
        "set_joint_max_speed" => rq::set_joint_max_speed(6, 180f64.to_radians()).ok()?,
        "set_joint_max_acc" => rq::set_joint_max_acc(6, 90.0 * 2.0 * PI / 60.0).ok()?,
        "clear_system_err" => rq::clear_system_err(),
        "set_joint_clear_err" => rq::set_joint_clear_err(3).ok()?,
        "set_install_pose" => rq::set_install_pose([0.0, 90f64.to_radians(), 0.0]).ok()?,
        "set_install_pose_restore" => rq::set_install_pose([0.0; 3]).ok()?,
        // Gripper and hand.
        "set_gripper_route" => rq::set_gripper_route(0, 1000).ok()?,
        "set_gripper_position_blocking" => rq::set_gripper_position(500, true).ok()?,
        "set_gripper_pick_blocking" => rq::set_gripper_pick(500, 200, true).ok()?,
        "set_gripper_pick_on" => rq::set_gripper_pick_on(500, 200, false).ok()?,
        "set_gripper_release_blocking" => rq::set_gripper_release(500, true).ok()?,
        "set_gripper_position_nonblocking" => rq::set_gripper_position(800, false).ok()?,
        "set_hand_posture_blocking" => rq::set_hand_posture(1, true).ok()?,
        "set_hand_seq_blocking" => rq::set_hand_seq(2, true).ok()?,
        "set_hand_angle" => rq::set_hand_angle(
            [
                Some(1000),
                Some(1000),
                Some(1000),
                Some(1000),
                Some(500),
                None,
            ],
            false,
        )
        .ok()?,
        "set_hand_speed" => rq::set_hand_speed(500).ok()?,
        "read_holding_registers" | "read_holding_registers_no_modbus" => {
            rq::read_holding_registers(0, 1, 100).ok()?
        }
        "read_holding_registers_signed" => rq::read_holding_registers(0, 1, 101).ok()?,
        "set_modbus_mode" => rq::set_modbus_mode(0, 115_200, 2).ok()?,
        "close_modbus_mode" => rq::close_modbus_mode(0).ok()?,
        "write_registers" => rq::write_registers(0, 1, 100, &[0x1234, 0xABCD]).ok()?,
        "write_registers_after_close" => rq::write_registers(0, 1, 100, &[1]).ok()?,
        "set_rm_plus_mode" => rq::set_rm_plus_mode(256_000).ok()?,
        // IO ports, supplies, version, end-effector identity (io.jsonl).
        "get_arm_software_version" => rq::get_arm_software_version(),
        n if n.starts_with("get_IO_state") => rq::get_io_state(1).ok()?,
        n if n.starts_with("set_DO_state") => rq::set_do_state(1, true).ok()?,
        "set_IO_mode_output" => rq::set_io_mode(1, 1).ok()?,
        "set_AO_state" => rq::set_ao_state(2, 5.0).ok()?,
        "get_IO_output" => rq::get_io_output(),
        "get_IO_input" => rq::get_io_input(),
        "set_voltage" => rq::set_voltage(2).ok()?,
        "get_voltage" => rq::get_voltage(),
        "set_tool_voltage" => rq::set_tool_voltage(1).ok()?,
        "get_tool_voltage" => rq::get_tool_voltage(),
        n if n.starts_with("set_tool_DO_state") => rq::set_tool_do_state(2, true).ok()?,
        "set_tool_IO_mode" => rq::set_tool_io_mode(2, true).ok()?,
        "get_tool_IO_state" => rq::get_tool_io_state(),
        n if n.starts_with("get_rm_plus_base_info") => rq::get_rm_plus_base_info(),
        "set_rm_plus_mode_on" => rq::set_rm_plus_mode(115_200).ok()?,
        "hand_follow_pos" => rq::set_hand_follow_pos([100, 200, 300, 400, 500, 600], true),
        "get_rm_plus_mode" => rq::get_rm_plus_mode(),
        "hand_follow_angle" => rq::set_hand_follow_angle([100, 200, 300, 400, 500, 600], true),
        "set_hand_force" => rq::set_hand_force(500).ok()?,
        // Push.
        "set_realtime_push" => rq::set_realtime_push(&PushSettings {
            period_ms: 10,
            enable: true,
            port: 8090,
            ip: [127, 0, 0, 1].into(),
            force_coordinate: None,
            custom: PushCustom {
                joint_speed: Some(true),
                arm_current_status: Some(true),
                ..Default::default()
            },
        })
        .ok()?,
        // Refusals: the driver encodes these; the controller says false.
        "movej_beyond_joint_limit" => {
            rq::movej(&rad(&[0.0, 0.0, 0.0, 0.0, 0.0, 365.0]), MoveOpts::speed(20)).ok()?
        }
        "movel_unreachable" => {
            rq::movel(&pose(2.0, 0.0, 0.5, 0.0, 0.0, 0.0), MoveOpts::speed(20)).ok()?
        }
        "movej_p_unreachable" => {
            rq::movej_p(&pose(0.0, 0.0, 1.5, 0.0, 0.0, 0.0), MoveOpts::speed(20)).ok()?
        }
        "set_arm_max_line_speed_zero" => {
            // The encoder refuses 0 m/s locally, so the raw request is never sent by armhil.
            assert!(rq::set_arm_max_line_speed(0.0).is_err());
            return None;
        }
        "set_collision_stage_out_of_range" => {
            assert!(rq::set_collision_stage(9).is_err());
            return None;
        }
        "set_gripper_position_refused" => {
            assert!(rq::set_gripper_position(1001, true).is_err());
            return None;
        }
        "movej_motion_failed" => {
            rq::movej(&rad(&[0.0, 0.0, 90.0, 0.0, 0.0, 0.0]), MoveOpts::speed(20)).ok()?
        }
        _ => return None,
    })
}

/// Vectors the driver never sends as such (it validates locally, or there is no encoder).
const NOT_ENCODED: [&str; 10] = [
    "set_IO_mode_bad_port",
    "set_AO_state_over_range",
    "set_tool_voltage_bad",
    "set_arm_max_line_speed_zero",
    "set_modbus_mode_bad_baud",
    "set_collision_stage_out_of_range",
    "set_gripper_position_refused",
    "unknown_command",
    "malformed_json",
    "udp_boot_idle",
];

/// Encodable vectors the controller answers with `false`.
const REFUSED: [&str; 7] = [
    "set_DO_state_input_port",
    "set_tool_DO_state_input_port",
    "movej_beyond_joint_limit",
    "movel_unreachable",
    "movej_p_unreachable",
    "set_joint_max_pos_while_enabled",
    "write_registers_after_close",
];

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

fn assert_all_close(got: &[f64], want: &[f64], tol: f64, what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: length");
    for (g, w) in got.iter().zip(want) {
        assert!(close(*g, *w, tol), "{what}: got {got:?}, want {want:?}");
    }
}

fn body_of(v: &Vector, i: usize) -> Body {
    match decode_message(v.replies[i].trim_end()) {
        Ok(Message::Reply { body, .. }) => body,
        other => panic!("{}: reply {i} is not a reply: {other:?}", v.name),
    }
}

/// Typed checks of data replies: SI values the notes state.
fn check_data(v: &Vector, b: &Body) {
    let lims = [178.0, 130.0, 135.0, 178.0, 128.0, 360.0];
    let n = v.name.as_str();
    match n {
        "get_arm_software_info" => {
            let s = d::software_info(b).unwrap();
            assert_eq!(
                (s.product_version.as_str(), s.model, s.dof, s.generation),
                ("RM65-B", Some("RM65"), 6, 3)
            );
        }
        "get_arm_current_trajectory"
        | "get_arm_current_trajectory_at_rest"
        | "get_arm_current_trajectory_moving" => {
            let t = d::current_trajectory(b).unwrap();
            let kind = if n.ends_with("moving") {
                TrajectoryKind::MoveJ
            } else {
                TrajectoryKind::None
            };
            assert_eq!(t.kind, kind);
            let want = if n == "get_arm_current_trajectory" {
                vec![0.0; 6]
            } else {
                rad(&Q1)
            };
            assert_all_close(&t.joints_rad, &want, 1e-9, n);
        }
        "get_realtime_push" | "get_realtime_push_after_set" => {
            let c = d::push_config(b).unwrap();
            let after = n.ends_with("after_set");
            assert_eq!(c.period_ms, if after { 10 } else { 5 });
            assert_eq!(c.port, if after { 8090 } else { 8089 });
            assert!(c.enable);
            assert_eq!(c.force_coordinate, -1);
            assert_eq!(c.custom.get("joint_speed"), Some(&after));
        }
        "get_current_work_frame" => {
            let f = d::work_frame(b).unwrap();
            assert_eq!((f.name.as_str(), f.pose), ("Base", Pose::default()));
        }
        "get_current_tool_frame" => {
            let f = d::tool_frame(b).unwrap();
            assert_eq!(
                (f.name.as_str(), f.pose, f.payload_kg, f.com_m),
                ("Arm_Tip", Pose::default(), 0.0, [0.0; 3])
            );
        }
        "get_install_pose" | "get_install_pose_after_set" => {
            let p = d::install_pose(b).unwrap();
            let pitch = if n.ends_with("after_set") {
                PI / 2.0
            } else {
                0.0
            };
            assert_all_close(&p, &[0.0, pitch, 0.0], 1e-12, n);
        }
        "get_joint_min_pos" => {
            let want: Vec<f64> = lims.iter().map(|l: &f64| -l.to_radians()).collect();
            assert_all_close(&d::joint_limits(b, "min_pos").unwrap(), &want, 1e-12, n);
        }
        "get_joint_max_pos" | "get_joint_max_pos_after_set" => {
            let mut want = rad(&lims);
            if n.ends_with("after_set") {
                want[5] = 350f64.to_radians();
            }
            assert_all_close(&d::joint_limits(b, "max_pos").unwrap(), &want, 1e-12, n);
        }
        "get_joint_max_speed" => {
            let want = rad(&[180.0, 180.0, 225.0, 225.0, 225.0, 225.0]);
            assert_all_close(&d::joint_rates(b, "joint_speed").unwrap(), &want, 1e-9, n);
        }
        "get_joint_max_acc" => {
            let want = vec![100.0 * 2.0 * PI / 60.0; 6];
            assert_all_close(&d::joint_rates(b, "joint_acc").unwrap(), &want, 1e-9, n);
        }
        "get_DH_data" | "get_DH_data_after_set" | "get_DH_data_after_default" => {
            let d6 = if n.ends_with("after_set") {
                0.1441
            } else {
                0.144
            };
            let got = d::dh_table(b).unwrap();
            for (g, w) in got.iter().zip(rm65_dh(d6)) {
                assert_all_close(
                    &[g.alpha_rad, g.a_m, g.d_m, g.offset_rad],
                    &[w.alpha_rad, w.a_m, w.d_m, w.offset_rad],
                    1e-12,
                    n,
                );
            }
            assert_eq!(got.len(), 6);
        }
        "get_arm_power_state" | "get_arm_power_state_off" => {
            assert_eq!(d::power_state(b).unwrap(), !n.ends_with("off"));
        }
        "get_joint_err_flag" => {
            let f = d::joint_flags(b).unwrap();
            assert!(f.errors.iter().all(|e| !e.any()) && f.brake_engaged == vec![false; 6]);
        }
        n if n.starts_with("get_current_arm_state") => check_arm_state(n, b),
        "get_joint_degree" => {
            let want = if v.origin_motion() {
                rad(&Q1)
            } else {
                vec![0.0; 6]
            };
            assert_all_close(&d::joints_rad(b, "joint").unwrap(), &want, 1e-9, n);
        }
        "get_arm_all_state" => {
            let s = d::all_state(b).unwrap();
            assert_all_close(&s.temperatures_c, &[30.0; 6], 1e-9, n);
            assert_all_close(&s.currents_a, &[0.1; 6], 1e-9, n);
            assert_all_close(&s.voltages_v, &[24.0; 6], 1e-9, n);
            assert!(s.enabled.iter().all(|e| *e) && s.errors.is_empty());
        }
        "get_controller_state" => {
            let c = d::controller_state(b).unwrap();
            assert_eq!(
                (c.voltage_v, c.current_a, c.temperature_c, c.error),
                (24.0, 1.5, 42.0, None)
            );
        }
        "get_current_joint_temperature" => assert_all_close(
            &d::joint_measure(b, "joint_temperature").unwrap(),
            &[30.0; 6],
            1e-9,
            n,
        ),
        "get_current_joint_current" => assert_all_close(
            &d::joint_measure(b, "joint_current").unwrap(),
            &[0.1; 6],
            1e-9,
            n,
        ),
        "get_current_joint_voltage" => assert_all_close(
            &d::joint_measure(b, "joint_voltage").unwrap(),
            &[24.0; 6],
            1e-9,
            n,
        ),
        "get_arm_max_line_speed" | "get_arm_max_line_speed_after_init" => {
            assert_eq!(d::milli_scalar(b, "arm_line_speed").unwrap(), 0.25)
        }
        "get_arm_max_line_speed_after_set" => {
            assert_eq!(d::milli_scalar(b, "arm_line_speed").unwrap(), 0.5)
        }
        "get_arm_max_line_acc" | "get_arm_max_line_acc_after_init" => {
            assert_eq!(d::milli_scalar(b, "arm_line_acc").unwrap(), 1.6)
        }
        "get_arm_max_angular_speed" => {
            assert_eq!(d::milli_scalar(b, "arm_angular_speed").unwrap(), 0.6)
        }
        "get_arm_max_angular_speed_after_set" => {
            assert_eq!(d::milli_scalar(b, "arm_angular_speed").unwrap(), 0.2)
        }
        "get_arm_max_angular_acc" => {
            assert_eq!(d::milli_scalar(b, "arm_angular_acc").unwrap(), 4.0)
        }
        "get_collision_stage" => assert_eq!(d::collision_stage(b).unwrap(), 0),
        "get_collision_stage_after_set" => assert_eq!(d::collision_stage(b).unwrap(), 1),
        "get_self_collision_enable" => assert!(d::self_collision(b).unwrap()),
        "get_gripper_state" => {
            let g = d::gripper_state(b).unwrap();
            assert!(g.enabled && g.online && g.error == 0);
            assert_eq!(
                (g.mode, g.position, g.temperature_c),
                (d::GripperMode::OpenIdle, 1000, 30)
            );
        }
        "read_holding_registers" => assert_eq!(b["data"].as_i64().unwrap(), 0x1234),
        "read_holding_registers_signed" => {
            assert_eq!(b["data"].as_i64().unwrap(), i64::from(0xABCDu16 as i16))
        }
        "read_holding_registers_no_modbus" => {
            assert_eq!(b.get("read_state").and_then(|v| v.as_bool()), Some(false))
        }
        "get_rm_plus_mode" => assert_eq!(b["mode"].as_i64().unwrap(), 256_000),
        "get_arm_software_version" => {
            let v = driver::realman::codec::io::software_version(b).unwrap();
            assert_eq!(v.plan_version, 0x6B0170);
            assert_eq!(
                driver::realman::SoftwareVersion::version_text(v.ctrl_version),
                "V1.7.0"
            );
            assert_eq!(v.kernel_versions, [0x0203, 0x0203]);
            assert_eq!(v.product_version, "RM65-B");
        }
        n if n.starts_with("get_IO_state") => {
            let s = driver::realman::codec::io::io_port_state(b).unwrap();
            let out = n.ends_with("output_high");
            assert_eq!((s.io_num, s.mode, s.high), (1, u8::from(out), out), "{n}");
        }
        "get_IO_output" => {
            let l = driver::realman::codec::io::io_levels(b, "DO", "AO").unwrap();
            assert_eq!(l.digital, [true, false, false, false]);
            assert_all_close(&l.analog_v, &[0.0, 5.0, 0.0, 0.0], 1e-9, n);
        }
        "get_IO_input" => {
            let l = driver::realman::codec::io::io_levels(b, "DI", "AI").unwrap();
            assert_eq!(l.digital, [false; 4]);
            assert_all_close(&l.analog_v, &[0.0; 4], 1e-9, n);
        }
        "get_voltage" => assert_eq!(driver::realman::codec::io::voltage_type(b).unwrap(), 2),
        "get_tool_voltage" => assert_eq!(driver::realman::codec::io::voltage_type(b).unwrap(), 1),
        "get_tool_IO_state" => {
            let t = driver::realman::codec::io::tool_io_state(b).unwrap();
            assert_eq!(t.output, [false, true]);
            assert_eq!(t.high, [false, true]);
        }
        "get_rm_plus_base_info_off" => {
            assert_eq!(driver::realman::codec::io::plus_base_info(b).unwrap(), None)
        }
        "get_rm_plus_base_info" => {
            let i = driver::realman::codec::io::plus_base_info(b)
                .unwrap()
                .unwrap();
            assert_eq!((i.device_type, i.dof), (2, 6), "a five-finger hand");
            assert_eq!(i.pos_up, [1000; 6]);
        }
        other => panic!("no data check for vector {other}"),
    }
}

fn check_arm_state(n: &str, b: &Body) {
    let s = d::arm_snapshot(b).unwrap();
    if n == "get_current_arm_state_after_movej" {
        assert_all_close(&s.joints_rad, &rad(&Q1), 1e-9, n);
        assert_all_close(&s.pose.position_m, &[-0.35566, -0.13471, 0.61081], 1e-9, n);
        assert_all_close(&s.pose.euler_rad, &[1.607, 0.008, -0.881], 1e-9, n);
    } else {
        assert_all_close(&s.joints_rad, &[0.0; 6], 0.0, n);
        assert_all_close(&s.pose.position_m, &[0.0, 0.0, 0.8505], 1e-9, n);
        assert!(
            close(s.pose.euler_rad[2].abs(), PI, 1e-3),
            "{n}: rz {}",
            s.pose.euler_rad[2]
        );
    }
    let want = if n.ends_with("after_refusal") {
        vec![ControllerError::TargetBeyondJointLimit]
    } else {
        vec![]
    };
    assert_eq!(s.errors, want, "{n}");
}

trait Origin {
    fn origin_motion(&self) -> bool;
}

impl Origin for Vector {
    fn origin_motion(&self) -> bool {
        // Within motion.jsonl the arm is at q1 when joints are read.
        self.notes.contains("After movej_blocking")
    }
}

fn expected_device(req: &Request) -> Device {
    match req.command {
        c if c.starts_with("set_gripper") => Device::Gripper,
        c if c.starts_with("set_hand") => Device::Hand,
        _ => Device::Arm,
    }
}

/// Checks request bytes and every reply of one vector; returns how many replies were decoded.
fn check_vector(file: &str, v: &Vector) -> usize {
    // Every reply (and the whole reply stream) must split into exactly one object each.
    let mut sp = Splitter::default();
    sp.push(v.replies.concat().as_bytes());
    let frames: Vec<Frame> = std::iter::from_fn(|| sp.next_frame()).collect();
    assert_eq!(frames.len(), v.replies.len(), "{file}/{}: splitter", v.name);
    assert!(
        frames.iter().all(|f| matches!(f, Frame::Object(_))),
        "{file}/{}",
        v.name
    );

    if v.channel == Channel::Udp {
        return check_udp(v);
    }
    match v.name.as_str() {
        "unknown_command" => {
            assert!(v.replies.is_empty());
            return 0;
        }
        "malformed_json" => {
            let mut sp = Splitter::default();
            sp.push(v.request.as_bytes());
            // An object broken by a CR LF is cut there as truncated, as the controller does,
            // so the next message is read cleanly.
            assert_eq!(
                sp.next_frame(),
                Some(Frame::Truncated(v.request.trim_end().to_string())),
                "an object broken by a line end is reported as truncated"
            );
            assert_eq!(sp.buffered(), 0);
            return 0;
        }
        _ => {}
    }
    let Some(req) = request_for(&v.name) else {
        assert!(
            NOT_ENCODED.contains(&v.name.as_str()),
            "{file}: unknown vector name {}",
            v.name
        );
        // Still decode the refusal the controller would send.
        let b = body_of(v, 0);
        assert!(!d::result_flag(&b, None).unwrap(), "{}", v.name);
        return 1;
    };
    if v.name == "movec_pretty_request" {
        let a: serde_json::Value = serde_json::from_str(&v.request).unwrap();
        let b: serde_json::Value = serde_json::from_str(&req.wire).unwrap();
        assert_eq!(a, b, "pretty movec equals the compact encoding");
        let mut sp = Splitter::default();
        sp.push(v.request.as_bytes());
        assert!(matches!(sp.next_frame(), Some(Frame::Object(_))));
    } else {
        assert_eq!(req.wire, v.request, "{file}/{}: request bytes", v.name);
    }
    check_replies(v, &req)
}

fn check_replies(v: &Vector, req: &Request) -> usize {
    let tag = match req.expect {
        Expect::Nothing => {
            assert!(v.replies.is_empty(), "{}: passthrough has no reply", v.name);
            return 0;
        }
        Expect::Flag { tag, .. } | Expect::Data { tag } => tag,
    };
    match decode_message(v.replies[0].trim_end()).unwrap() {
        Message::Reply { tag: t, body } => {
            assert!(t.is(tag), "{}: reply tag {t:?} is not {tag:?}", v.name);
            match req.expect {
                Expect::Flag { key, .. } => {
                    let flag = d::result_flag(&body, key).unwrap();
                    assert_eq!(
                        flag,
                        !REFUSED.contains(&v.name.as_str()),
                        "{}: result flag",
                        v.name
                    );
                }
                _ => check_data(v, &body),
            }
        }
        other => panic!("{}: first reply is {other:?}", v.name),
    }
    let device = expected_device(req);
    let events = &v.replies[1..];
    for (i, e) in events.iter().enumerate() {
        let Message::Arrival(a) = decode_message(e.trim_end()).unwrap() else {
            panic!("{}: reply {} is not an arrival event", v.name, i + 1);
        };
        assert_eq!(a.device, device, "{}", v.name);
        assert_eq!(a.ok, v.name != "movej_motion_failed", "{}", v.name);
        assert_eq!(
            a.more_follow,
            i + 1 < events.len(),
            "{}: only the last event ends the motion",
            v.name
        );
    }
    v.replies.len()
}

fn check_udp(v: &Vector) -> usize {
    assert!(v.request.is_empty());
    let s = decode_push(v.replies[0].as_bytes(), JointSpeedUnit::default()).unwrap();
    match v.name.as_str() {
        "udp_boot_idle" => {
            assert_all_close(&s.joints_rad, &[0.0; 6], 0.0, "joints");
            assert_all_close(&s.currents_a, &[0.1; 6], 1e-12, "currents");
            assert_all_close(&s.temperatures_c, &[30.0; 6], 1e-12, "temperatures");
            assert_all_close(&s.pose.position_m, &[0.0, 0.0, 0.8505], 1e-12, "position");
            assert_all_close(
                &s.quaternion_wxyz,
                &[0.0, 0.0, 0.0, 1.0],
                1e-12,
                "quaternion",
            );
            assert!(s.errors.is_empty() && s.status.is_none() && s.joint_speeds_rad_s.is_none());
            assert!(s.enabled.iter().all(|e| *e));
        }
        "udp_moving_legacy" => {
            assert_all_close(&s.joints_rad, &rad(&Q1), 1e-12, "joints");
            assert_all_close(
                &s.currents_a,
                &[1.2, 2.5, 1.8, 0.4, 0.3, 0.1],
                1e-12,
                "currents",
            );
            let speeds = s.joint_speeds_rad_s.clone().unwrap();
            assert_all_close(
                &speeds,
                &rad(&[10.0, 0.0, 0.0, 0.0, 0.0, -15.0]),
                1e-12,
                "speeds",
            );
            assert_eq!(s.status, Some(ArmStatus::MoveJ));
            assert!(s.joint_errors[5].contains(JointErrorFlags::OVER_TEMPERATURE));
            assert!(s.errors.is_empty());
            let q = s.quaternion_wxyz;
            assert!(
                close(q.iter().map(|c| c * c).sum::<f64>(), 1.0, 1e-5),
                "unit quaternion"
            );
        }
        other => panic!("unknown UDP vector {other}"),
    }
    1
}

#[test]
fn realman_every_fixture_vector_encodes_and_decodes() {
    let transcripts = load_dir(realman_fixtures_dir()).expect("fixtures load");
    let names: Vec<String> = transcripts
        .iter()
        .map(|t| {
            std::path::Path::new(&t.origin)
                .file_stem()
                .unwrap()
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    assert_eq!(names, FILES, "fixture files");
    let mut vectors = 0;
    let mut replies = 0;
    for (t, file) in transcripts.iter().zip(&names) {
        for v in &t.vectors {
            replies += check_vector(file, v);
            vectors += 1;
        }
    }
    assert!(vectors >= 130, "{vectors} vectors");
    println!("{vectors} vectors, {replies} replies checked");
}

#[test]
fn realman_handshake_file_starts_with_the_sdk_order() {
    let t = testkit::transcript::Transcript::load(realman_fixtures_dir().join("handshake.jsonl"))
        .unwrap();
    let got: Vec<&str> = t
        .vectors
        .iter()
        .take(11)
        .map(|v| v.request.as_str())
        .collect();
    let want: Vec<String> = rq::handshake_queries()
        .iter()
        .map(|r| r.wire.clone())
        .collect();
    assert_eq!(got, want);
}

#[test]
fn realman_legacy_and_current_error_forms_decode_alike() {
    let legacy = r#"{"state":"current_arm_state","arm_state":{"joint":[0,0,0,0,0,0],"pose":[0,0,0,0,0,0],"arm_err":4109,"sys_err":0}}"#;
    let current = r#"{"state":"current_arm_state","arm_state":{"joint":[0,0,0,0,0,0],"pose":[0,0,0,0,0,0],"err":[4109,20000]}}"#;
    let decode = |s: &str| match decode_message(s).unwrap() {
        Message::Reply { body, .. } => d::arm_snapshot(&body).unwrap().errors,
        other => panic!("{other:?}"),
    };
    assert_eq!(decode(legacy), vec![ControllerError::Collision]);
    assert_eq!(
        decode(current),
        vec![ControllerError::Collision, ControllerError::Unknown(20000)]
    );
}

#[test]
fn realman_decoders_survive_mangled_vectors() {
    // Every prefix and every single-byte corruption of every reply: no panic, and a corrupted
    // reply is either still a valid message or a typed error.
    let transcripts = load_dir(realman_fixtures_dir()).unwrap();
    let mut cases = 0usize;
    for t in &transcripts {
        for v in &t.vectors {
            for reply in &v.replies {
                let bytes = reply.as_bytes();
                for cut in 0..bytes.len() {
                    let mut sp = Splitter::new(256);
                    sp.push(&bytes[..cut]);
                    while let Some(f) = sp.next_frame() {
                        if let Frame::Object(text) = f {
                            let _ = decode_message(&text);
                        }
                    }
                    let _ = decode_push(&bytes[..cut], JointSpeedUnit::default());
                    cases += 1;
                }
                for (i, junk) in [b'}', b'"', b'x', b'\\', b'{']
                    .iter()
                    .cycle()
                    .take(bytes.len())
                    .enumerate()
                {
                    let mut mangled = bytes.to_vec();
                    mangled[i] = *junk;
                    let mut sp = Splitter::new(4096);
                    sp.push(&mangled);
                    while let Some(f) = sp.next_frame() {
                        if let Frame::Object(text) = f {
                            if let Ok(Message::Reply { body, .. }) = decode_message(&text) {
                                let _ = d::arm_snapshot(&body);
                                let _ = d::push_config(&body);
                                let _ = d::dh_table(&body);
                                let _ = d::all_state(&body);
                            }
                        }
                    }
                    let _ = decode_push(&mangled, JointSpeedUnit::default());
                    cases += 1;
                }
            }
        }
    }
    assert!(cases > 10_000, "{cases} cases");
}

#[test]
fn realman_cartesian_trajectory_reports_a_pose() {
    let text = r#"{"state":"arm_current_trajectory","type":"movel","data":[-355660,-134710,560810,1607,8,-881]}"#;
    let Message::Reply { body, .. } = decode_message(text).unwrap() else {
        panic!()
    };
    let t = d::current_trajectory(&body).unwrap();
    assert_eq!(t.kind, TrajectoryKind::MoveL);
    let p = t.pose.unwrap();
    assert!((p.position_m[2] - 0.56081).abs() < 1e-12 && (p.euler_rad[0] - 1.607).abs() < 1e-12);
    let odd = r#"{"state":"arm_current_trajectory","type":"re_trajectory","data":[0,0,0,0,0,0]}"#;
    let Message::Reply { body, .. } = decode_message(odd).unwrap() else {
        panic!()
    };
    assert_eq!(
        d::current_trajectory(&body).unwrap().kind,
        TrajectoryKind::Unknown("re_trajectory".into())
    );
}
