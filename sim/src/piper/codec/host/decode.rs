//! Decoding host frames into [`HostCommand`]s: the control block (0x121, 0x150–0x191, 0x422)
//! and the configuration block (0x470–0x4AF).

use bus::{CanFrame, CanId};

use super::*;
use crate::piper::codec::mit::{self, MitCheckError};
use crate::piper::codec::{be_i16, be_i32, be_u16, DecodeError};
use crate::piper::flash::rules as flash_rules;
use crate::piper::ids;
use crate::piper::profile::FirmwareProfile;

fn need(frame: &CanFrame, id: u16, len: usize) -> Result<(), DecodeError> {
    if frame.len() == len {
        Ok(())
    } else {
        Err(DecodeError::WrongDlc {
            id,
            dlc: frame.len(),
            expected: len,
        })
    }
}

fn invalid(id: u16, field: &'static str, value: u32) -> DecodeError {
    DecodeError::InvalidValue { id, field, value }
}

fn opt16(v: u16) -> Option<u16> {
    (v != UNCHANGED_U16).then_some(v)
}

fn opt_i16(v: i16) -> Option<i16> {
    (v as u16 != UNCHANGED_U16).then_some(v)
}

/// Decode a host frame. `control_offset` (0x00/0x10/0x20) is where the motion block 0x150–0x15F
/// currently lives (0x470 byte 2); a motion frame on another offset is [`DecodeError::UnknownId`].
pub fn decode(
    frame: &CanFrame,
    control_offset: u16,
    profile: FirmwareProfile,
) -> Result<HostCommand, DecodeError> {
    let CanId::Standard(raw_id) = frame.id() else {
        return Err(DecodeError::Extended { id: frame.raw_id() });
    };
    let mut d = [0u8; 8];
    d[..frame.len()].copy_from_slice(frame.data());
    let motion_base = ids::MOTION_CTRL_1 + control_offset;
    let id = if (motion_base..=motion_base + 0x0F).contains(&raw_id) {
        raw_id - control_offset
    } else if (ids::MOTION_CTRL_1..=ids::MIT_LAST + 0x20).contains(&raw_id) {
        return Err(DecodeError::UnknownId { id: raw_id });
    } else {
        raw_id
    };
    if id < ids::LINKAGE_CONFIG {
        control_command(frame, id, &d, profile)
    } else {
        config_command(frame, id, &d)
    }
}

/// A frame of the control block (LED, motion, MIT, CPV, leader homing, upgrade mode).
fn control_command(
    frame: &CanFrame,
    id: u16,
    d: &[u8; 8],
    profile: FirmwareProfile,
) -> Result<HostCommand, DecodeError> {
    match id {
        ids::LED => {
            need(frame, id, 8)?;
            Ok(HostCommand::Led {
                apply: d[0] == 1,
                joint: d[1],
            })
        }
        ids::MOTION_CTRL_1 => {
            need(frame, id, 8)?;
            let quick_stop = match d[0] {
                0 => QuickStop::None,
                1 => QuickStop::Stop,
                2 => QuickStop::Reset,
                v => return Err(invalid(id, "quick_stop", v.into())),
            };
            if d[1] > 8 {
                return Err(invalid(id, "trajectory", d[1].into()));
            }
            if d[2] > 7 {
                return Err(invalid(id, "drag_teach", d[2].into()));
            }
            Ok(HostCommand::MotionCtrl1(MotionCtrl1 {
                quick_stop,
                trajectory: d[1],
                drag_teach: d[2],
                point_index: d[3],
                name_index: be_u16(d, 4),
                crc16: be_u16(d, 6),
            }))
        }
        ids::MODE_CTRL => {
            need(frame, id, 8)?;
            let ctrl_mode =
                CtrlMode::try_from(d[0]).map_err(|v| invalid(id, "ctrl_mode", v.into()))?;
            let move_mode = match d[1] {
                0xFF => None,
                code => Some(
                    MoveMode::from_code(code, profile)
                        .ok_or_else(|| invalid(id, "move_mode", code.into()))?,
                ),
            };
            // The speed byte is ignored in MIT mode, so only reject it when it would be used.
            if d[2] > 100 && d[3] != MIT_FLAG {
                return Err(invalid(id, "speed_pct", d[2].into()));
            }
            let mit = match d[3] {
                0x00 => Some(false),
                MIT_FLAG => Some(true),
                0xFF => None,
                v => return Err(invalid(id, "mit_mode", v.into())),
            };
            // 0 leaves the installation position unchanged.
            if d[5] != 0 && !flash_rules::INSTALL_POSITIONS.contains(&d[5]) {
                return Err(invalid(id, "install_position", d[5].into()));
            }
            Ok(HostCommand::ModeCtrl(ModeCtrl {
                ctrl_mode,
                move_mode,
                speed_pct: d[2].min(100),
                mit,
                dwell_s: d[4],
                install_position: d[5],
            }))
        }
        ids::END_POSE_XY | ids::END_POSE_ZRX | ids::END_POSE_RYRZ => {
            need(frame, id, 8)?;
            let part = match id {
                ids::END_POSE_XY => PosePart::XY,
                ids::END_POSE_ZRX => PosePart::ZRx,
                _ => PosePart::RyRz,
            };
            Ok(HostCommand::EndPose {
                part,
                first: be_i32(d, 0),
                second: be_i32(d, 4),
            })
        }
        ids::JOINT_12 | ids::JOINT_34 | ids::JOINT_56 => {
            need(frame, id, 8)?;
            Ok(HostCommand::Joint {
                pair: usize::from(id - ids::JOINT_12),
                first_mdeg: be_i32(d, 0),
                second_mdeg: be_i32(d, 4),
            })
        }
        ids::MOVE_C_POINT => {
            need(frame, id, 8)?;
            let point = match d[0] {
                1 => MoveCPoint::Start,
                2 => MoveCPoint::Middle,
                3 => MoveCPoint::End,
                v => return Err(invalid(id, "point", v.into())),
            };
            Ok(HostCommand::MoveCPoint(point))
        }
        ids::GRIPPER_CTRL => {
            need(frame, id, 8)?;
            if d[6] > 3 {
                return Err(invalid(id, "gripper_code", d[6].into()));
            }
            if d[7] != 0 && d[7] != CONFIRM {
                return Err(invalid(id, "set_zero", d[7].into()));
            }
            Ok(HostCommand::Gripper(GripperCtrl {
                stroke_um: be_i32(d, 0),
                effort_mnm: be_u16(d, 4),
                enable: d[6] & 1 != 0,
                clear_error: d[6] & 2 != 0,
                set_zero: d[7] == CONFIRM,
            }))
        }
        ids::MIT_FIRST..=ids::MIT_LAST => {
            need(frame, id, 8)?;
            let packing = profile.mit_packing();
            let raw =
                mit::unpack(d, packing).map_err(|e: MitCheckError| DecodeError::BadCheck {
                    id,
                    expected: e.expected,
                    got: e.got,
                })?;
            Ok(HostCommand::Mit {
                joint: usize::from(id - ids::MIT_FIRST),
                cmd: raw.to_command(packing),
            })
        }
        ids::CPV_FIRST..=ids::CPV_LAST => {
            // One SDK demo sends CPV frames with DLC 7; the value is then 4 bytes at 3..7.
            if frame.len() < 7 {
                return Err(DecodeError::WrongDlc {
                    id,
                    dlc: frame.len(),
                    expected: 8,
                });
            }
            Ok(HostCommand::Cpv {
                motor: (id - 0x180) as u8,
                mode: d[0],
                param: [d[1], d[2]],
                value: be_i32(d, 3),
            })
        }
        ids::LEADER_HOME => {
            need(frame, id, 8)?;
            Ok(HostCommand::LeaderHome {
                bytes: [d[0], d[1], d[2]],
            })
        }
        ids::UPGRADE_MODE => {
            if frame.is_empty() {
                return Err(DecodeError::WrongDlc {
                    id,
                    dlc: 0,
                    expected: 1,
                });
            }
            if d[0] > 2 {
                return Err(invalid(id, "upgrade_mode", d[0].into()));
            }
            Ok(HostCommand::UpgradeMode(d[0]))
        }
        other => Err(DecodeError::UnknownId { id: other }),
    }
}

/// A frame of the configuration block (linkage, enabling, limits, parameters, identity).
fn config_command(frame: &CanFrame, id: u16, d: &[u8; 8]) -> Result<HostCommand, DecodeError> {
    match id {
        ids::LINKAGE_CONFIG => {
            need(frame, id, 8)?;
            let role = match d[0] {
                0x00 => LinkageRole::NoOp,
                0xFA => LinkageRole::Leader,
                0xFC => LinkageRole::Follower,
                v => return Err(invalid(id, "linkage", v.into())),
            };
            for (field, v) in [
                ("feedback_offset", d[1]),
                ("control_offset", d[2]),
                ("target_offset", d[3]),
            ] {
                if !flash_rules::is_id_offset(v) {
                    return Err(invalid(id, field, v.into()));
                }
            }
            Ok(HostCommand::Linkage(LinkageConfig {
                role,
                feedback_offset: d[1],
                control_offset: d[2],
                target_offset: d[3],
            }))
        }
        ids::MOTOR_ENABLE => {
            need(frame, id, 8)?;
            let motor = match d[0] {
                1..=6 => MotorSelect::Joint(usize::from(d[0] - 1)),
                7 => MotorSelect::AllWithGripper,
                0xFF => MotorSelect::All,
                v => return Err(invalid(id, "motor", v.into())),
            };
            let enable = match d[1] {
                1 => false,
                2 => true,
                v => return Err(invalid(id, "enable_flag", v.into())),
            };
            Ok(HostCommand::MotorEnable { motor, enable })
        }
        ids::JOINT_QUERY => {
            need(frame, id, 8)?;
            let joint = joint_index(id, d[0])?;
            let acceleration = match d[1] {
                1 => false,
                2 => true,
                v => return Err(invalid(id, "query", v.into())),
            };
            Ok(HostCommand::JointQuery {
                joint,
                acceleration,
            })
        }
        ids::SET_JOINT_LIMITS => {
            need(frame, id, 8)?;
            Ok(HostCommand::SetJointLimits {
                joint: joint_index(id, d[0])?,
                max_angle_ddeg: opt_i16(be_i16(d, 1)),
                min_angle_ddeg: opt_i16(be_i16(d, 3)),
                max_speed_crad_s: opt16(be_u16(d, 5)),
            })
        }
        ids::JOINT_CONFIG => {
            need(frame, id, 8)?;
            let joint = match d[0] {
                7 => None,
                n => Some(joint_index(id, n)?),
            };
            let acc = be_u16(d, 3);
            Ok(HostCommand::JointConfig {
                joint,
                set_zero: d[1] == CONFIRM,
                max_acc_crad_s2: (d[2] == CONFIRM && acc != UNCHANGED_U16).then_some(acc),
                clear_error: d[5] == CONFIRM,
            })
        }
        ids::PARAM_QUERY => {
            need(frame, id, 8)?;
            if d[0] > 4 {
                return Err(invalid(id, "query", d[0].into()));
            }
            if d[1] > 2 {
                return Err(invalid(id, "reset", d[1].into()));
            }
            if d[2] > 2 {
                return Err(invalid(id, "periodic_48x", d[2].into()));
            }
            let payload = if d[3] == CONFIRM && flash_rules::PAYLOADS.contains(&d[4]) {
                Some(d[4])
            } else {
                None
            };
            Ok(HostCommand::ParamQuery(ParamQuery {
                query: d[0],
                reset: d[1],
                periodic_48x: d[2],
                payload,
            }))
        }
        ids::SET_END_VEL_ACC => {
            need(frame, id, 8)?;
            Ok(HostCommand::SetEndVelAcc(EndVelAcc {
                linear_vel_mm_s: opt16(be_u16(d, 0)),
                angular_vel_mrad_s: opt16(be_u16(d, 2)),
                linear_acc_mm_s2: opt16(be_u16(d, 4)),
                angular_acc_mrad_s2: opt16(be_u16(d, 6)),
            }))
        }
        ids::SET_COLLISION => {
            need(frame, id, 8)?;
            let mut levels = [None; 6];
            for (slot, &v) in levels.iter_mut().zip(&d[..6]) {
                *slot = match v {
                    0xFF => None,
                    v if flash_rules::COLLISION_LEVELS.contains(&v) => Some(v),
                    v => return Err(invalid(id, "collision_level", v.into())),
                };
            }
            Ok(HostCommand::SetCollision(levels))
        }
        ids::SET_GRIPPER_TEACH => {
            need(frame, id, 8)?;
            Ok(HostCommand::SetGripperTeach {
                travel_pct: d[0],
                max_stroke_mm: d[1],
                friction: d[2],
            })
        }
        ids::SET_ASSIST => {
            need(frame, id, 8)?;
            let mut levels = [0u8; 6];
            levels.copy_from_slice(&d[..6]);
            Ok(HostCommand::SetAssist(levels))
        }
        ids::FIRMWARE => {
            // pyAgxArm sends the query as a 1-byte payload; the SDK sends 8 bytes.
            if frame.is_empty() || d[0] != 1 {
                return Err(invalid(id, "firmware_query", d[0].into()));
            }
            Ok(HostCommand::FirmwareQuery)
        }
        other => Err(DecodeError::UnknownId { id: other }),
    }
}

fn joint_index(id: u16, n: u8) -> Result<usize, DecodeError> {
    if (1..=6).contains(&n) {
        Ok(usize::from(n - 1))
    } else {
        Err(invalid(id, "joint", n.into()))
    }
}
