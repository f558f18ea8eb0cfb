//! Property tests across the two independent codecs (the driver's and the emulator's, each
//! written from docs/protocols/*.md), and of what the emulators put on the wire:
//!
//! - driver encode → emulator decode (host commands) and emulator encode → driver decode
//!   (feedback and replies) agree on every field, across full value ranges;
//! - whatever the commands, the Piper and RobStride emulators emit only frames the driver
//!   decodes, with scaled values that saturate at the ends of their wire range (as the
//!   firmware does) and never wrap.

use std::time::Duration;

use bus::CanFrame;
use driver::piper::codec as dp;
use driver::robstride::codec as drs;
use proptest::prelude::*;
use sim::piper::codec::{arm, host};
use sim::piper::{Firmware, FirmwareProfile, PiperConfig};
use sim::robstride::{Actuator, Model, MotorConfig};

fn profile(index: usize) -> FirmwareProfile {
    FirmwareProfile::ALL[index % FirmwareProfile::ALL.len()]
}

/// The driver's MIT packing for a firmware profile (S-V1.8-8 switched to 12-bit torque).
fn packing(profile: FirmwareProfile) -> dp::MitPacking {
    if profile == FirmwareProfile::V1_8_8 {
        dp::MitPacking::Torque12
    } else {
        dp::MitPacking::Torque8Crc
    }
}

fn emu_decode(frame: &CanFrame, profile: FirmwareProfile) -> host::HostCommand {
    host::decode(frame, 0, profile).unwrap_or_else(|e| panic!("emulator refused {frame}: {e}"))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn driver_piper_commands_read_the_same_in_the_emulator(
        angles: [i32; 6], pose: [i32; 6], stroke_um: i32, effort_mnm: u16, flags in 0u8..8,
        p in 0usize..4,
    ) {
        let profile = profile(p);
        let joints = dp::JointTargets { angles_mdeg: angles }.encode();
        for (k, f) in joints.iter().enumerate() {
            prop_assert_eq!(emu_decode(f, profile), host::HostCommand::Joint {
                pair: k, first_mdeg: angles[2 * k], second_mdeg: angles[2 * k + 1],
            });
        }
        let target = dp::EndPoseTarget {
            x_um: pose[0], y_um: pose[1], z_um: pose[2],
            rx_mdeg: pose[3], ry_mdeg: pose[4], rz_mdeg: pose[5],
        };
        let parts = [host::PosePart::XY, host::PosePart::ZRx, host::PosePart::RyRz];
        for (k, f) in target.encode().iter().enumerate() {
            prop_assert_eq!(emu_decode(f, profile), host::HostCommand::EndPose {
                part: parts[k], first: pose[2 * k], second: pose[2 * k + 1],
            });
        }
        let g = dp::GripperCtrl {
            stroke_um, effort_mnm,
            enable: flags & 1 != 0, clear_error: flags & 2 != 0, set_zero: flags & 4 != 0,
        };
        prop_assert_eq!(emu_decode(&g.encode(), profile), host::HostCommand::Gripper(host::GripperCtrl {
            stroke_um, effort_mnm,
            enable: g.enable, clear_error: g.clear_error, set_zero: g.set_zero,
        }));
    }

    #[test]
    fn driver_mit_frames_read_the_same_in_the_emulator(
        joint in 1u8..=6, p: u16, v in 0u16..0x1000, kp in 0u16..0x1000, kd in 0u16..0x1000,
        t in 0u16..0x1000, prof in 0usize..4,
    ) {
        let profile = profile(prof);
        let packing = packing(profile);
        let t = if packing == dp::MitPacking::Torque12 { t } else { t & 0xFF };
        let raw = dp::MitRaw { p, v, kp, kd, t };
        let si = raw.to_si(packing);
        let host::HostCommand::Mit { joint: j, cmd } = emu_decode(&raw.encode(joint, packing), profile) else {
            panic!("not an MIT command");
        };
        prop_assert_eq!(j, usize::from(joint - 1));
        for (a, b) in [(cmd.p_des_rad, si.p_rad), (cmd.v_des_rad_s, si.v_rad_s), (cmd.kp, si.kp),
                       (cmd.kd, si.kd), (cmd.t_ff_nm, si.t_nm)] {
            prop_assert!((a - b).abs() < 1e-9, "{cmd:?} vs {si:?}");
        }
    }

    #[test]
    fn emulator_piper_feedback_reads_the_same_in_the_driver(
        a: i32, b: i32, pair in 0u16..3, speed: i16, current: i16, joint in 0usize..6,
        status: [u8; 8], u16s: [u16; 4], torque: i16,
    ) {
        let decode = |f: CanFrame| dp::decode(&f).unwrap().unwrap();
        prop_assert_eq!(decode(arm::encode_pair(0x2A5 + pair, a, b)), dp::Message::Joints(dp::JointPair {
            first_joint: 2 * pair as u8 + 1, a_mdeg: a, b_mdeg: b,
        }));
        prop_assert_eq!(decode(arm::encode_high_speed(joint, speed, current, a)),
            dp::Message::HighSpeed(dp::HighSpeedFeedback {
                joint: joint as u8 + 1, speed_mrad_s: speed, current_ma: current, position_mrad: a,
            }));
        prop_assert_eq!(decode(arm::encode_low_speed(joint, u16s[0], torque, status[0] as i8, status[1], u16s[1])),
            dp::Message::LowSpeed(dp::LowSpeedFeedback {
                joint: joint as u8 + 1, bus_voltage_dv: u16s[0], driver_temp_c: torque,
                motor_temp_c: status[0] as i8, status: dp::DriverStatus(status[1]), bus_current_ma: u16s[1],
            }));
        prop_assert_eq!(decode(arm::encode_gripper(0x2A8, a, torque, status[2])),
            dp::Message::Gripper(dp::GripperFeedback {
                stroke_um: a, torque_mnm: torque, status: dp::GripperStatus(status[2]),
            }));
        let s = arm::ArmStatusFrame {
            ctrl_mode: status[0], arm_status: status[1], mode_feed: status[2], teach_status: status[3],
            motion_status: status[4], trajectory_num: status[5], limit_bits: status[6], comm_bits: status[7],
        };
        let dp::Message::ArmStatus(d) = decode(s.encode(0x2A1)) else { panic!("not a status") };
        let again = d.encode();
        prop_assert_eq!(again.data(), &status[..]);
        prop_assert_eq!(decode(arm::encode_joint_limits(joint, torque, speed, u16s[2])),
            dp::Message::JointLimits(dp::JointLimits {
                joint: joint as u8 + 1, max_angle_ddeg: torque, min_angle_ddeg: speed, max_speed_crad_s: u16s[2],
            }));
        prop_assert_eq!(decode(arm::encode_joint_acc(joint, u16s[3])),
            dp::Message::JointMaxAcc(dp::JointMaxAcc { joint: joint as u8 + 1, max_acc_crad_s2: u16s[3] }));
        prop_assert_eq!(decode(arm::encode_four_u16(0x478, u16s)),
            dp::Message::EndParams(dp::EndParams {
                lin_vel_mm_s: u16s[0], ang_vel_mrad_s: u16s[1], lin_acc_mm_s2: u16s[2], ang_acc_mrad_s2: u16s[3],
            }));
        let six = [status[0], status[1], status[2], status[3], status[4], status[5]];
        prop_assert_eq!(decode(arm::encode_six_u8(0x47B, six)),
            dp::Message::Collision(dp::CollisionLevels { levels: six }));
        prop_assert_eq!(decode(arm::encode_cpv_reply(joint as u8 + 1, [status[6], status[7]], a)),
            dp::Message::Cpv(dp::CpvFrame {
                motor: joint as u8 + 1, mode: dp::CpvMode::Answer, param: [status[6], status[7]], value: a,
            }));
    }

    #[test]
    fn emulator_robstride_status_reads_the_same_in_the_driver(
        model in 0usize..8, x in prop::num::f32::ANY, temp in -40.0f32..200.0, motor: u8, host: u8,
    ) {
        let model = Model::ALL[model];
        let r = model.ranges(sim::robstride::RangeTable::Manual);
        let data = sim::robstride::codec::status_payload(x, x, x, temp, &r);
        let frame = sim::robstride::codec::frame(
            sim::robstride::codec::CommType::Status, u16::from(motor) | 0x8000, host, data,
        ).unwrap();
        let ranges = robstride_driver_ranges(model);
        let Some(drs::Incoming::Feedback(f)) = drs::decode(&frame, host, Duration::ZERO, |_| Some(ranges)) else {
            // The version reply shares type 2 (payload 00 C4 56 …): only a NaN-free value can collide.
            prop_assert!(data[..3] == [0x00, 0xC4, 0x56]);
            return Ok(());
        };
        prop_assert_eq!(f.motor_id, motor);
        prop_assert_eq!(f.mode, drs::MotorMode::Run);
        for (got, max) in [(f.angle_rad, r.angle_rad), (f.speed_rad_s, r.speed_rad_s), (f.torque_nm, r.torque_nm)] {
            let want = if x.is_nan() { -max } else { x.clamp(-max, max) };
            prop_assert!((got - want).abs() <= 2.0 * max / 65535.0 * 1.01 + max * 1e-6,
                "{x} over ±{max} read as {got}");
        }
        prop_assert!((f.temperature_c - temp.max(0.0)).abs() <= 0.051);
    }
}

fn robstride_driver_ranges(model: Model) -> driver::robstride::Ranges {
    driver::robstride::Model::parse(&format!("{model:?}"))
        .unwrap()
        .ranges(driver::robstride::RangeTable::Manual)
}

/// One step of a random Piper command sequence.
#[derive(Debug, Clone)]
enum PiperOp {
    Joints([i32; 6]),
    Mit { joint: u8, raw: [u16; 5] },
    Gripper { stroke_um: i32, effort_mnm: u16 },
    Mode { mit: bool, speed_pct: u8 },
    Ticks(u32),
}

fn piper_op() -> impl Strategy<Value = PiperOp> {
    prop_oneof![
        any::<[i32; 6]>().prop_map(PiperOp::Joints),
        (1u8..=6, any::<[u16; 5]>()).prop_map(|(joint, raw)| PiperOp::Mit { joint, raw }),
        (any::<i32>(), any::<u16>()).prop_map(|(stroke_um, effort_mnm)| PiperOp::Gripper {
            stroke_um,
            effort_mnm
        }),
        (any::<bool>(), 0u8..=100).prop_map(|(mit, speed_pct)| PiperOp::Mode { mit, speed_pct }),
        (1u32..120).prop_map(PiperOp::Ticks),
    ]
}

fn piper_frames(op: &PiperOp, profile: FirmwareProfile) -> Vec<CanFrame> {
    match *op {
        PiperOp::Joints(a) => dp::JointTargets { angles_mdeg: a }.encode().to_vec(),
        PiperOp::Mit { joint, raw } => {
            let [p, v, kp, kd, t] = raw;
            vec![dp::MitRaw {
                p,
                v: v & 0xFFF,
                kp: kp & 0xFFF,
                kd: kd & 0xFFF,
                t: t & 0xFFF,
            }
            .encode(joint, packing(profile))]
        }
        PiperOp::Gripper {
            stroke_um,
            effort_mnm,
        } => vec![dp::GripperCtrl {
            stroke_um,
            effort_mnm,
            enable: true,
            clear_error: false,
            set_zero: false,
        }
        .encode()],
        PiperOp::Mode { mit, speed_pct } => vec![host::encode_mode_ctrl(
            0x151,
            &host::ModeCtrl {
                ctrl_mode: host::CtrlMode::Can,
                move_mode: Some(if mit {
                    host::MoveMode::Mit
                } else {
                    host::MoveMode::J
                }),
                speed_pct,
                mit: Some(mit),
                dwell_s: 0,
                install_position: 0,
            },
            profile,
        )],
        PiperOp::Ticks(_) => Vec::new(),
    }
}

/// `wire` is `x` (already scaled to wire units) rounded and saturated into `lo..=hi`.
fn saturated(wire: i64, x: f64, lo: i64, hi: i64) -> bool {
    let want = x.round().clamp(lo as f64, hi as f64) as i64;
    wire.abs_diff(want) <= 1
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]

    /// Random joint, MIT, gripper and mode commands with time passing: every frame the Piper
    /// emulator sends decodes in the driver, and the high-speed feedback (speed, current,
    /// position) is the simulated value saturated into its wire field.
    #[test]
    fn piper_emulator_output_stays_in_range(p in 0usize..4, ops in prop::collection::vec(piper_op(), 1..16)) {
        let profile = profile(p);
        let mut fw = Firmware::new(PiperConfig { firmware: profile, ..PiperConfig::default() }).unwrap();
        fw.handle_frame(&dp::encode_motor_enable(dp::MotorSelect::All, true));
        for op in &ops {
            for f in piper_frames(op, profile) {
                fw.handle_frame(&f);
            }
            let ticks = if let PiperOp::Ticks(n) = op { *n } else { 1 };
            for _ in 0..ticks {
                fw.tick();
                let state = fw.snapshot();
                for frame in fw.take_output() {
                    let message = dp::decode(&frame).unwrap_or_else(|e| panic!("{frame}: {e}"));
                    if let Some(dp::Message::HighSpeed(h)) = message {
                        let j = usize::from(h.joint - 1);
                        let (i16_lo, i16_hi) = (i64::from(i16::MIN), i64::from(i16::MAX));
                        prop_assert!(saturated(h.speed_mrad_s.into(), state.joint_velocities_rad_s[j] * 1e3, i16_lo, i16_hi),
                            "J{} speed {} vs {}", j + 1, h.speed_mrad_s, state.joint_velocities_rad_s[j]);
                        prop_assert!(saturated(h.current_ma.into(), state.motor_currents_a[j] * 1e3, i16_lo, i16_hi),
                            "J{} current {} vs {}", j + 1, h.current_ma, state.motor_currents_a[j]);
                        prop_assert!(saturated(h.position_mrad.into(), state.reported_joints_rad[j] * 1e3,
                            i64::from(i32::MIN), i64::from(i32::MAX)));
                    }
                }
            }
        }
    }
}

/// One step of a random RobStride command sequence.
#[derive(Debug, Clone)]
enum RsOp {
    /// Write a float parameter (spd_ref, loc_ref, iq_ref, limit_spd, limit_cur) with any value.
    Write {
        index: u16,
        value: f32,
    },
    RunMode(u8),
    OpControl([u16; 5]),
    Ticks(u32),
}

fn rs_op() -> impl Strategy<Value = RsOp> {
    let index = prop::sample::select(vec![0x700A_u16, 0x7016, 0x7006, 0x7017, 0x7018]);
    prop_oneof![
        (index, prop::num::f32::ANY).prop_map(|(index, value)| RsOp::Write { index, value }),
        (0u8..6).prop_map(RsOp::RunMode),
        any::<[u16; 5]>().prop_map(RsOp::OpControl),
        (1u32..400).prop_map(RsOp::Ticks),
    ]
}

const HOST: u8 = 0xFD;
const MOTOR: u8 = 0x7F;

fn rs_frames(op: &RsOp, ranges: &driver::robstride::Ranges) -> Vec<CanFrame> {
    let write = |index: u16, value: [u8; 4]| {
        let [i0, i1] = index.to_le_bytes();
        drs::request(
            drs::comm::WRITE_PARAM,
            u16::from(HOST),
            MOTOR,
            [i0, i1, 0, 0, value[0], value[1], value[2], value[3]],
        )
        .unwrap()
    };
    match *op {
        RsOp::Write { index, value } => vec![write(index, value.to_le_bytes())],
        // Switching mode needs the motor stopped: stop, write, enable (spec §6).
        RsOp::RunMode(mode) => vec![
            drs::request(drs::comm::STOP, u16::from(HOST), MOTOR, [0; 8]).unwrap(),
            write(0x7005, [mode, 0, 0, 0]),
            drs::request(drs::comm::ENABLE, u16::from(HOST), MOTOR, [0; 8]).unwrap(),
        ],
        RsOp::OpControl([a, v, kp, kd, t]) => {
            let f = |raw: u16, max: f32| drs::from_u16(raw, -max, max);
            let cmd = drs::OpControl {
                angle_rad: f(a, ranges.angle_rad),
                speed_rad_s: f(v, ranges.speed_rad_s),
                kp: drs::from_u16(kp, 0.0, ranges.kp_max),
                kd: drs::from_u16(kd, 0.0, ranges.kd_max),
                torque_nm: f(t, ranges.torque_nm),
            };
            vec![drs::op_control_frame(MOTOR, &cmd, ranges).unwrap()]
        }
        RsOp::Ticks(_) => Vec::new(),
    }
}

fn check_rs_status(
    frame: &CanFrame,
    m: &sim::robstride::MotorSnapshot,
    r: &driver::robstride::Ranges,
) -> Result<(), TestCaseError> {
    prop_assert!(frame.is_extended() && frame.len() == 8, "{frame}");
    let Some(drs::Incoming::Feedback(f)) = drs::decode(frame, HOST, Duration::ZERO, |_| Some(*r))
    else {
        return Ok(());
    };
    // Speed and torque on the wire are the simulated values clamped into ±range: a runaway
    // motor reads as the end of the range with its sign, never as a wrapped value. The angle
    // is periodic instead: the firmware wraps it into [−range, range) (docs/protocols/
    // robstride.md §3.3), so a shaft past −4π reads near +4π.
    let angle_max = f64::from(r.angle_rad);
    let wrapped_angle = (m.angle_rad + angle_max).rem_euclid(2.0 * angle_max) - angle_max;
    for (got, want, max) in [
        (f.angle_rad, wrapped_angle as f32, r.angle_rad),
        (
            f.speed_rad_s,
            (m.speed_rad_s as f32).clamp(-r.speed_rad_s, r.speed_rad_s),
            r.speed_rad_s,
        ),
        (
            f.torque_nm,
            (m.torque_nm as f32).clamp(-r.torque_nm, r.torque_nm),
            r.torque_nm,
        ),
    ] {
        prop_assert!(
            (got - want).abs() <= 3.0 * max / 65535.0 + max * 1e-5,
            "{frame}: wire {got}, expected {want} (range ±{max})"
        );
    }
    prop_assert!(f.temperature_c >= 0.0 && f.temperature_c.is_finite());
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Random parameter writes (any float, NaN and infinities included), mode switches,
    /// operation-control commands and time, with active reporting on: every status frame
    /// the motor sends carries its simulated angle, speed and torque saturated into the
    /// model's ranges.
    #[test]
    fn robstride_emulator_output_stays_in_range(model in 0usize..8, ops in prop::collection::vec(rs_op(), 1..16)) {
        let model = Model::ALL[model];
        let ranges = robstride_driver_ranges(model);
        let mut motor = Actuator::new(MotorConfig::new(MOTOR, model), None, 1_000_000);
        let setup = [
            drs::request(drs::comm::ENABLE, u16::from(HOST), MOTOR, [0; 8]).unwrap(),
            // Active reporting on (type 24, magic payload, command byte 1).
            drs::request(24, u16::from(HOST), MOTOR, drs::magic_payload(1)).unwrap(),
        ];
        for f in &setup {
            motor.handle_frame(f);
        }
        for op in &ops {
            for f in rs_frames(op, &ranges) {
                for reply in motor.handle_frame(&f) {
                    check_rs_status(&reply, &motor.snapshot(), &ranges)?;
                }
            }
            let ticks = if let RsOp::Ticks(n) = op { *n } else { 1 };
            for _ in 0..ticks {
                let out = motor.tick();
                let snap = motor.snapshot();
                for frame in &out {
                    check_rs_status(frame, &snap, &ranges)?;
                }
            }
        }
    }
}
