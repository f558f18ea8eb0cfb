//! Configuration and query frames: 0x422, 0x470–0x47E, 0x487/0x488.

use bus::CanFrame;

use super::{
    be_i16, be_u16, frame, ids, joint_index, payload, AckedCommand, DecodeError, IdOffset,
    LinkageConfig, Payload,
};

/// Marker byte (0xAE) that arms an action in 0x475 and 0x477.
pub const APPLY: u8 = 0xAE;

/// 0x470 leader/follower configuration.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct LeaderFollowerConfig {
    /// Linkage setting.
    pub linkage: LinkageConfig,
    /// Feedback id offset (0x2Ax → 0x2Bx / 0x2Cx).
    pub feedback_offset: IdOffset,
    /// Control id offset this arm listens on (0x15x → 0x16x / 0x17x).
    pub ctrl_offset: IdOffset,
    /// Id offset a leader emits on.
    pub target_offset: IdOffset,
}

impl LeaderFollowerConfig {
    /// Encode as 0x470.
    pub fn encode(&self) -> CanFrame {
        frame(
            ids::LEADER_FOLLOWER,
            &[
                self.linkage.into(),
                self.feedback_offset.into(),
                self.ctrl_offset.into(),
                self.target_offset.into(),
                0,
                0,
                0,
                0,
            ],
        )
    }
}

/// Which motors 0x471 addresses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum MotorSelect {
    /// One joint, 1–6.
    Joint(u8),
    /// All joints (7; the gripper follows per DOC/PC).
    All,
    /// 0xFF: all including the gripper (SDK message class reading, spec §14 #6).
    AllWithGripper,
}

impl MotorSelect {
    /// The wire byte.
    pub fn raw(self) -> u8 {
        match self {
            Self::Joint(joint) => joint,
            Self::All => 7,
            Self::AllWithGripper => 0xFF,
        }
    }

    /// The joints this selection confirms through the 0x26x enable bits.
    pub fn joints(self) -> super::JointMask {
        match self {
            Self::Joint(joint @ 1..=6) => super::JointMask(1 << (joint - 1)),
            Self::Joint(_) => super::JointMask(0),
            Self::All | Self::AllWithGripper => super::JointMask::ALL,
        }
    }
}

/// Encode 0x471 motor enable (`enable = true`, flag 0x02) or disable (flag 0x01).
pub fn encode_motor_enable(motor: MotorSelect, enable: bool) -> CanFrame {
    let flag = if enable { 0x02 } else { 0x01 };
    frame(ids::MOTOR_ENABLE, &[motor.raw(), flag, 0, 0, 0, 0, 0, 0])
}

/// What 0x472 asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum JointQuery {
    /// Angle limits and max speed (reply 0x473).
    Limits,
    /// Max acceleration (reply 0x47C).
    MaxAcc,
}

/// Encode a 0x472 query for `joint` (1–6).
pub fn encode_joint_query(joint: u8, query: JointQuery) -> CanFrame {
    let kind = match query {
        JointQuery::Limits => 0x01,
        JointQuery::MaxAcc => 0x02,
    };
    frame(ids::QUERY_JOINT, &[joint, kind, 0, 0, 0, 0, 0, 0])
}

/// Joint angle limits and max speed (0x473 reply, 0x474 set). 0x7FFF in a set field means
/// "unchanged".
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct JointLimits {
    /// Joint 1–6.
    pub joint: u8,
    /// Upper angle limit, 0.1°.
    pub max_angle_ddeg: i16,
    /// Lower angle limit, 0.1°.
    pub min_angle_ddeg: i16,
    /// Max joint speed, 0.01 rad/s (official unit; spec §14 #1).
    pub max_speed_crad_s: u16,
}

impl JointLimits {
    /// Decode a 0x473 reply.
    pub fn decode(frame: &CanFrame) -> Result<Self, DecodeError> {
        let d = payload(ids::JOINT_LIMITS, frame, 7)?;
        Ok(Self {
            joint: joint_index(ids::JOINT_LIMITS, "joint", d[0])?,
            max_angle_ddeg: be_i16(d, 1),
            min_angle_ddeg: be_i16(d, 3),
            max_speed_crad_s: be_u16(d, 5),
        })
    }

    /// Encode as a 0x474 set command.
    pub fn encode_set(&self) -> CanFrame {
        let mut data = [0u8; 8];
        data[0] = self.joint;
        data[1..3].copy_from_slice(&self.max_angle_ddeg.to_be_bytes());
        data[3..5].copy_from_slice(&self.min_angle_ddeg.to_be_bytes());
        data[5..7].copy_from_slice(&self.max_speed_crad_s.to_be_bytes());
        frame(ids::SET_JOINT_LIMITS, &data)
    }
}

/// 0x475 joint configuration.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct JointConfig {
    /// Joint 1–6, or 7 = all.
    pub joint: u8,
    /// Set the current position as zero.
    pub set_zero: bool,
    /// Apply `max_acc_crad_s2`.
    pub apply_acc: bool,
    /// Max joint acceleration, 0.01 rad/s² (0x7FFF = invalid).
    pub max_acc_crad_s2: u16,
    /// Clear the joint error code.
    pub clear_error: bool,
}

impl JointConfig {
    /// Encode as 0x475.
    pub fn encode(&self) -> CanFrame {
        let flag = |on: bool| if on { APPLY } else { 0 };
        let [a0, a1] = self.max_acc_crad_s2.to_be_bytes();
        frame(
            ids::JOINT_CONFIG,
            &[
                self.joint,
                flag(self.set_zero),
                flag(self.apply_acc),
                a0,
                a1,
                flag(self.clear_error),
                0,
                0,
            ],
        )
    }
}

/// 0x476 set-command acknowledgement.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct Ack {
    /// The acknowledged command.
    pub cmd: AckedCommand,
    /// Zero-set result (0x475 set-zero only): true = success.
    pub zero_ok: bool,
    /// Trajectory point index acknowledged.
    pub traj_index: u8,
    /// Trajectory package status: 0xAE OK, 0xEE CRC failure.
    pub pkg_status: u8,
    /// NameIndex (also the trajectory-index reply of 0x477 query 0x03).
    pub name_index: u16,
    /// CRC-16.
    pub crc16: u16,
}

impl Ack {
    /// Decode a 0x476 frame.
    pub fn decode(frame: &CanFrame) -> Result<Self, DecodeError> {
        let d = payload(ids::ACK, frame, 8)?;
        Ok(Self {
            cmd: d[0].into(),
            zero_ok: d[1] == 0x01,
            traj_index: d[2],
            pkg_status: d[3],
            name_index: be_u16(d, 4),
            crc16: be_u16(d, 6),
        })
    }
}

/// 0x477 byte 0: which parameter block to query.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum ParamQuery {
    /// End vel/acc (reply 0x478).
    EndParams,
    /// Collision levels (reply 0x47B).
    Collision,
    /// Current trajectory index (reply 0x476).
    TrajectoryIndex,
    /// Gripper / teach-pendant params (reply 0x47E).
    GripperTeach,
}

/// 0x477 byte 1: reset to defaults.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum ParamReset {
    /// End vel/acc params to defaults.
    EndParams,
    /// All joint limits, max speeds and accelerations to defaults.
    JointParams,
}

/// 0x477 parameter query and settings. Each field left `None` sends its no-op value.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct ParamCommand {
    /// Query (byte 0).
    pub query: Option<ParamQuery>,
    /// Reset to defaults (byte 1).
    pub reset: Option<ParamReset>,
    /// Periodic 0x481–0x486 feedback on/off (byte 2; 0x01 = on, 0x02 = off, majority reading
    /// of spec §14 #7).
    pub feedback_48x: Option<bool>,
    /// End payload to apply (bytes 3–4).
    pub payload: Option<Payload>,
}

impl ParamCommand {
    /// Encode as 0x477.
    pub fn encode(&self) -> CanFrame {
        let query = match self.query {
            None => 0,
            Some(ParamQuery::EndParams) => 1,
            Some(ParamQuery::Collision) => 2,
            Some(ParamQuery::TrajectoryIndex) => 3,
            Some(ParamQuery::GripperTeach) => 4,
        };
        let reset = match self.reset {
            None => 0,
            Some(ParamReset::EndParams) => 1,
            Some(ParamReset::JointParams) => 2,
        };
        let feedback = match self.feedback_48x {
            None => 0,
            Some(true) => 1,
            Some(false) => 2,
        };
        let (apply, payload) = match self.payload {
            None => (0, Payload::NoChange.into()),
            Some(payload) => (APPLY, payload.into()),
        };
        frame(
            ids::PARAM,
            &[query, reset, feedback, apply, payload, 0, 0, 0],
        )
    }

    /// True when the arm acknowledges this command on 0x476 (any setting byte present).
    pub fn expects_ack(&self) -> bool {
        self.reset.is_some() || self.feedback_48x.is_some() || self.payload.is_some()
    }
}

/// End-effector max velocity / acceleration (0x478 reply, 0x479 set; 0x7FFF = unchanged).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct EndParams {
    /// Max linear velocity, 0.001 m/s.
    pub lin_vel_mm_s: u16,
    /// Max angular velocity, 0.001 rad/s.
    pub ang_vel_mrad_s: u16,
    /// Max linear acceleration, 0.001 m/s².
    pub lin_acc_mm_s2: u16,
    /// Max angular acceleration, 0.001 rad/s².
    pub ang_acc_mrad_s2: u16,
}

impl EndParams {
    /// Decode a 0x478 reply.
    pub fn decode(frame: &CanFrame) -> Result<Self, DecodeError> {
        let d = payload(ids::END_PARAMS, frame, 8)?;
        Ok(Self {
            lin_vel_mm_s: be_u16(d, 0),
            ang_vel_mrad_s: be_u16(d, 2),
            lin_acc_mm_s2: be_u16(d, 4),
            ang_acc_mrad_s2: be_u16(d, 6),
        })
    }

    /// Encode as a 0x479 set command.
    pub fn encode_set(&self) -> CanFrame {
        let mut data = [0u8; 8];
        for (i, v) in [
            self.lin_vel_mm_s,
            self.ang_vel_mrad_s,
            self.lin_acc_mm_s2,
            self.ang_acc_mrad_s2,
        ]
        .into_iter()
        .enumerate()
        {
            data[i * 2..i * 2 + 2].copy_from_slice(&v.to_be_bytes());
        }
        frame(ids::SET_END_PARAMS, &data)
    }
}

/// Collision-protection levels of joints 1–6 (0–8; 0xFF = unchanged in a set).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct CollisionLevels {
    /// Level per joint.
    pub levels: [u8; 6],
}

impl CollisionLevels {
    /// Decode a 0x47B reply.
    pub fn decode(frame: &CanFrame) -> Result<Self, DecodeError> {
        let d = payload(ids::COLLISION, frame, 6)?;
        Ok(Self {
            levels: [d[0], d[1], d[2], d[3], d[4], d[5]],
        })
    }

    /// Encode as a 0x47A set command.
    pub fn encode_set(&self) -> CanFrame {
        let l = self.levels;
        frame(
            ids::SET_COLLISION,
            &[l[0], l[1], l[2], l[3], l[4], l[5], 0, 0],
        )
    }
}

/// Joint assistance levels (AGX only; semantics undocumented).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct AssistLevels {
    /// Level per joint.
    pub levels: [u8; 6],
}

impl AssistLevels {
    /// Decode a 0x488 reply.
    pub fn decode(frame: &CanFrame) -> Result<Self, DecodeError> {
        let d = payload(ids::ASSIST, frame, 6)?;
        Ok(Self {
            levels: [d[0], d[1], d[2], d[3], d[4], d[5]],
        })
    }

    /// Encode as a 0x487 set command.
    pub fn encode_set(&self) -> CanFrame {
        let l = self.levels;
        frame(ids::SET_ASSIST, &[l[0], l[1], l[2], l[3], l[4], l[5], 0, 0])
    }
}

/// 0x47C joint max acceleration reply.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct JointMaxAcc {
    /// Joint 1–6.
    pub joint: u8,
    /// Max acceleration, 0.01 rad/s² (AGX unit; spec §14 #2).
    pub max_acc_crad_s2: u16,
}

impl JointMaxAcc {
    /// Decode a 0x47C reply.
    pub fn decode(frame: &CanFrame) -> Result<Self, DecodeError> {
        let d = payload(ids::JOINT_MAX_ACC, frame, 3)?;
        Ok(Self {
            joint: joint_index(ids::JOINT_MAX_ACC, "joint", d[0])?,
            max_acc_crad_s2: be_u16(d, 1),
        })
    }
}

/// Gripper / teach-pendant parameters (0x47D set, 0x47E reply; fw >= V1.5-2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct GripperTeachParams {
    /// Teach-pendant travel coefficient, 100–200 %.
    pub teach_coef_pct: u8,
    /// Max gripper stroke, mm (0 = unset, 70 small, 100 large gripper).
    pub max_stroke_mm: u8,
    /// Teach-pendant friction coefficient 1–10.
    pub friction: u8,
}

impl GripperTeachParams {
    /// Decode a 0x47E reply.
    pub fn decode(frame: &CanFrame) -> Result<Self, DecodeError> {
        let d = payload(ids::GRIPPER_TEACH, frame, 3)?;
        Ok(Self {
            teach_coef_pct: d[0],
            max_stroke_mm: d[1],
            friction: d[2],
        })
    }

    /// Encode as a 0x47D set command.
    pub fn encode_set(&self) -> CanFrame {
        frame(
            ids::SET_GRIPPER_TEACH,
            &[
                self.teach_coef_pct,
                self.max_stroke_mm,
                self.friction,
                0,
                0,
                0,
                0,
                0,
            ],
        )
    }
}

/// Encode 0x422 firmware-upgrade bus mode (DLC 1): 0 leave, 1 silent, 2 bridge.
pub fn encode_upgrade_mode(mode: u8) -> CanFrame {
    frame(ids::UPGRADE_MODE, &[mode])
}
