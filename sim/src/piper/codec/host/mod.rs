//! Host → arm frames: the commands the master controller receives (spec §5, §6), decoded in
//! `decode`, and the encoders tests and leader arms use.

use bus::CanFrame;

use super::mit::MitCommand;
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

mod decode;

pub use self::decode::decode;

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
