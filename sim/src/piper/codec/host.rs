//! Host → arm frames: decoding what the master controller receives (spec §5, §6).

use bus::{CanFrame, CanId};

use super::mit::{self, MitCheckError, MitCommand};
use super::{be_i16, be_i32, be_u16, DecodeError};
use crate::piper::flash::rules as flash_rules;
use crate::piper::ids;
use crate::piper::profile::FirmwareProfile;

/// 0x7FFF in a 16-bit set field means "leave unchanged" (fw ≥ V1.5-2).
pub const UNCHANGED_U16: u16 = 0x7FFF;
/// The magic byte that confirms an action in 0x159/0x475/0x477.
pub const CONFIRM: u8 = 0xAE;
/// 0x151 byte 3 value that selects MIT.
pub const MIT_FLAG: u8 = 0xAD;

/// Control mode (0x151 byte 0, 0x2A1 byte 0).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
#[repr(u8)]
pub enum CtrlMode {
    /// Standby.
    Standby = 0x00,
    /// CAN command mode.
    Can = 0x01,
    /// Drag teach (physical button only).
    Teach = 0x02,
    /// Ethernet.
    Ethernet = 0x03,
    /// Wi-Fi.
    Wifi = 0x04,
    /// Remote controller.
    Remote = 0x05,
    /// Linkage-teach input (leader arm).
    LinkageTeach = 0x06,
    /// Offline trajectory.
    Offline = 0x07,
}

impl TryFrom<u8> for CtrlMode {
    type Error = u8;
    fn try_from(v: u8) -> Result<Self, u8> {
        Ok(match v {
            0x00 => Self::Standby,
            0x01 => Self::Can,
            0x02 => Self::Teach,
            0x03 => Self::Ethernet,
            0x04 => Self::Wifi,
            0x05 => Self::Remote,
            0x06 => Self::LinkageTeach,
            0x07 => Self::Offline,
            other => return Err(other),
        })
    }
}

/// MOVE mode; its wire code for MIT depends on the firmware.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum MoveMode {
    /// Point-to-point to a Cartesian pose (firmware IK, joint-space motion).
    P,
    /// Joint-space move.
    J,
    /// Straight line in Cartesian space.
    L,
    /// Circular arc through three poses.
    C,
    /// MIT per-joint pass-through.
    Mit,
    /// Continuous position-velocity.
    Cpv,
}

impl MoveMode {
    /// The wire code under `profile`.
    pub fn code(self, profile: FirmwareProfile) -> u8 {
        match self {
            Self::P => 0x00,
            Self::J => 0x01,
            Self::L => 0x02,
            Self::C => 0x03,
            Self::Mit => profile.mit_mode_code(),
            Self::Cpv => 0x05,
        }
    }

    /// Decode under `profile`; `None` for a code this firmware does not know.
    pub fn from_code(code: u8, profile: FirmwareProfile) -> Option<Self> {
        match code {
            0x00 => Some(Self::P),
            0x01 => Some(Self::J),
            0x02 => Some(Self::L),
            0x03 => Some(Self::C),
            0x05 => Some(Self::Cpv),
            c if c == profile.mit_mode_code() => Some(Self::Mit),
            _ => None,
        }
    }
}

/// 0x150 byte 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum QuickStop {
    /// No action.
    None,
    /// Quick stop: joints go to damping mode.
    Stop,
    /// Resume / reset: clear errors, motors off, back to standby.
    Reset,
}

/// 0x150: motion control 1.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MotionCtrl1 {
    /// Quick stop / reset.
    pub quick_stop: QuickStop,
    /// Offline-trajectory command (0–8).
    pub trajectory: u8,
    /// Drag-teach command (0–7).
    pub drag_teach: u8,
    /// Trajectory point index.
    pub point_index: u8,
    /// Trajectory package name index.
    pub name_index: u16,
    /// Trajectory package CRC.
    pub crc16: u16,
}

/// 0x151: motion control 2 (mode control).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ModeCtrl {
    /// Requested control mode.
    pub ctrl_mode: CtrlMode,
    /// Requested MOVE mode; `None` for 0xFF (leave unchanged).
    pub move_mode: Option<MoveMode>,
    /// Speed percentage 0–100.
    pub speed_pct: u8,
    /// True for MIT (0xAD) in byte 3; `None` for 0xFF (ignore).
    pub mit: Option<bool>,
    /// Offline trajectory dwell, s (255 = trajectory end).
    pub dwell_s: u8,
    /// Installation position 0–3 (0 = no change).
    pub install_position: u8,
}

/// Which two end-pose fields a 0x152–0x154 frame carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PosePart {
    /// X, Y in µm (0x152).
    XY,
    /// Z in µm, RX in m° (0x153).
    ZRx,
    /// RY, RZ in m° (0x154).
    RyRz,
}

/// 0x158 byte 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MoveCPoint {
    /// Start point.
    Start,
    /// Middle point.
    Middle,
    /// End point.
    End,
}

/// 0x159: gripper control.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GripperCtrl {
    /// Target stroke, µm.
    pub stroke_um: i32,
    /// Torque limit, mN·m.
    pub effort_mnm: u16,
    /// Enable the gripper motor.
    pub enable: bool,
    /// Clear the gripper's error.
    pub clear_error: bool,
    /// Set the current position as zero.
    pub set_zero: bool,
}

/// Motor selection in 0x471.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MotorSelect {
    /// One joint, 0-based.
    Joint(usize),
    /// 7: all joints and the gripper (spec §14 #6).
    AllWithGripper,
    /// 0xFF: all joints and the gripper.
    All,
}

/// 0x470 byte 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinkageRole {
    /// No change.
    NoOp,
    /// 0xFA: become the teach-input (leader) arm.
    Leader,
    /// 0xFC: become the motion-output (follower) arm.
    Follower,
}

/// 0x470: leader/follower configuration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LinkageConfig {
    /// Role change.
    pub role: LinkageRole,
    /// Feedback ID offset: 0x00, 0x10 or 0x20.
    pub feedback_offset: u8,
    /// Control ID offset: 0x00, 0x10 or 0x20.
    pub control_offset: u8,
    /// Offset a leader emits on: 0x00, 0x10 or 0x20.
    pub target_offset: u8,
}

/// 0x477: parameter query and settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ParamQuery {
    /// Byte 0: 0 none, 1 → 0x478, 2 → 0x47B, 3 → trajectory index, 4 → 0x47E.
    pub query: u8,
    /// Byte 1: 0 none, 1 end vel/acc defaults, 2 joint limits/speed/acc defaults.
    pub reset: u8,
    /// Byte 2: 0 no-op, 1 / 2 periodic 0x48X on / off (order configurable, spec §14 #7).
    pub periodic_48x: u8,
    /// Byte 3 == 0xAE: apply the end payload in byte 4.
    pub payload: Option<u8>,
}

/// 0x479: end-effector limits (0.001 m/s, 0.001 rad/s, 0.001 m/s², 0.001 rad/s²).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EndVelAcc {
    /// Max linear velocity, mm/s; `None` = unchanged.
    pub linear_vel_mm_s: Option<u16>,
    /// Max angular velocity, mrad/s.
    pub angular_vel_mrad_s: Option<u16>,
    /// Max linear acceleration, mm/s².
    pub linear_acc_mm_s2: Option<u16>,
    /// Max angular acceleration, mrad/s².
    pub angular_acc_mrad_s2: Option<u16>,
}

/// Everything the master controller understands from the host.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum HostCommand {
    /// 0x121 LED control (accepted, no visible effect).
    Led {
        /// Byte 0 == 1: apply.
        apply: bool,
        /// Joint 1–6.
        joint: u8,
    },
    /// 0x150.
    MotionCtrl1(MotionCtrl1),
    /// 0x151.
    ModeCtrl(ModeCtrl),
    /// 0x152–0x154: two end-pose fields (µm or m°).
    EndPose {
        /// Which fields.
        part: PosePart,
        /// First field.
        first: i32,
        /// Second field.
        second: i32,
    },
    /// 0x155–0x157: two joint targets in m°.
    Joint {
        /// 0 for J1/J2, 1 for J3/J4, 2 for J5/J6.
        pair: usize,
        /// First joint, m°.
        first_mdeg: i32,
        /// Second joint, m°.
        second_mdeg: i32,
    },
    /// 0x158.
    MoveCPoint(MoveCPoint),
    /// 0x159.
    Gripper(GripperCtrl),
    /// 0x15A–0x15F.
    Mit {
        /// 0-based joint.
        joint: usize,
        /// Decoded command (before firmware quirks).
        cmd: MitCommand,
    },
    /// 0x181–0x187.
    Cpv {
        /// Motor 1–7.
        motor: u8,
        /// Mode byte: b'w' write, b'r' read (others kept raw).
        mode: u8,
        /// Two-character parameter name.
        param: [u8; 2],
        /// Value (int32 BE), zero when the frame is shorter.
        value: i32,
    },
    /// 0x191.
    LeaderHome {
        /// Bytes 0–2.
        bytes: [u8; 3],
    },
    /// 0x422: 0 normal, 1/2 upgrade (bus silent).
    UpgradeMode(u8),
    /// 0x470.
    Linkage(LinkageConfig),
    /// 0x471.
    MotorEnable {
        /// Which motor(s).
        motor: MotorSelect,
        /// True to enable, false to disable.
        enable: bool,
    },
    /// 0x472: byte 1 == 1 → 0x473, 2 → 0x47C.
    JointQuery {
        /// 0-based joint.
        joint: usize,
        /// True for max acceleration (0x47C), false for limits (0x473).
        acceleration: bool,
    },
    /// 0x474.
    SetJointLimits {
        /// 0-based joint.
        joint: usize,
        /// Max angle, 0.1°.
        max_angle_ddeg: Option<i16>,
        /// Min angle, 0.1°.
        min_angle_ddeg: Option<i16>,
        /// Max speed, 0.01 rad/s.
        max_speed_crad_s: Option<u16>,
    },
    /// 0x475.
    JointConfig {
        /// 0-based joint, or `None` for 7 (all).
        joint: Option<usize>,
        /// Set current position as zero.
        set_zero: bool,
        /// New max acceleration, 0.01 rad/s².
        max_acc_crad_s2: Option<u16>,
        /// Clear the joint's error code.
        clear_error: bool,
    },
    /// 0x477.
    ParamQuery(ParamQuery),
    /// 0x479.
    SetEndVelAcc(EndVelAcc),
    /// 0x47A: per-joint level 0–8, `None` = unchanged.
    SetCollision([Option<u8>; 6]),
    /// 0x47D.
    SetGripperTeach {
        /// Teach-pendant travel coefficient, % (100–200).
        travel_pct: u8,
        /// Max gripper stroke, mm.
        max_stroke_mm: u8,
        /// Teach-pendant friction 1–10.
        friction: u8,
    },
    /// 0x487 (accepted and stored).
    SetAssist([u8; 6]),
    /// 0x4AF query.
    FirmwareQuery,
}

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
                name_index: be_u16(&d, 4),
                crc16: be_u16(&d, 6),
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
                first: be_i32(&d, 0),
                second: be_i32(&d, 4),
            })
        }
        ids::JOINT_12 | ids::JOINT_34 | ids::JOINT_56 => {
            need(frame, id, 8)?;
            Ok(HostCommand::Joint {
                pair: usize::from(id - ids::JOINT_12),
                first_mdeg: be_i32(&d, 0),
                second_mdeg: be_i32(&d, 4),
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
                stroke_um: be_i32(&d, 0),
                effort_mnm: be_u16(&d, 4),
                enable: d[6] & 1 != 0,
                clear_error: d[6] & 2 != 0,
                set_zero: d[7] == CONFIRM,
            }))
        }
        ids::MIT_FIRST..=ids::MIT_LAST => {
            need(frame, id, 8)?;
            let packing = profile.mit_packing();
            let raw =
                mit::unpack(&d, packing).map_err(|e: MitCheckError| DecodeError::BadCheck {
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
                value: be_i32(&d, 3),
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
                max_angle_ddeg: opt_i16(be_i16(&d, 1)),
                min_angle_ddeg: opt_i16(be_i16(&d, 3)),
                max_speed_crad_s: opt16(be_u16(&d, 5)),
            })
        }
        ids::JOINT_CONFIG => {
            need(frame, id, 8)?;
            let joint = match d[0] {
                7 => None,
                n => Some(joint_index(id, n)?),
            };
            let acc = be_u16(&d, 3);
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
                linear_vel_mm_s: opt16(be_u16(&d, 0)),
                angular_vel_mrad_s: opt16(be_u16(&d, 2)),
                linear_acc_mm_s2: opt16(be_u16(&d, 4)),
                angular_acc_mrad_s2: opt16(be_u16(&d, 6)),
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

/// Encode a 0x151 frame (what a leader arm emits; also used by tests).
pub fn encode_mode_ctrl(id: u16, m: &ModeCtrl, profile: FirmwareProfile) -> CanFrame {
    let d = [
        m.ctrl_mode as u8,
        m.move_mode.map_or(0xFF, |mm| mm.code(profile)),
        m.speed_pct,
        match m.mit {
            Some(true) => MIT_FLAG,
            Some(false) => 0,
            None => 0xFF,
        },
        m.dwell_s,
        m.install_position,
        0,
        0,
    ];
    super::frame(id, &d)
}

/// Encode a 0x159 frame.
pub fn encode_gripper(id: u16, g: &GripperCtrl) -> CanFrame {
    let mut d = [0u8; 8];
    d[..4].copy_from_slice(&g.stroke_um.to_be_bytes());
    d[4..6].copy_from_slice(&g.effort_mnm.to_be_bytes());
    d[6] = u8::from(g.enable) | (u8::from(g.clear_error) << 1);
    d[7] = if g.set_zero { CONFIRM } else { 0 };
    super::frame(id, &d)
}
