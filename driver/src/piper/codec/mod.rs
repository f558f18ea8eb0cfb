//! The Piper wire codec, written from the protocol specification: pure functions that turn
//! typed commands into [`CanFrame`]s and received frames into typed [`Message`]s.
//!
//! Scaled integers stay here: every field carries its wire unit in its name (`_mdeg`, `_um`,
//! `_mrad_s` …). The client API never shows them: `si` converts to and from the SI types of
//! the public API, and decides the "unchanged" codes and per-firmware MIT codes. This module
//! is public for tools and byte-level tests; applications use [`super::Piper`].
//!
//! Where a comment says where a fact comes from: DOC is AgileX's CAN protocol document, SDK
//! the vendor's Python SDK (piper_sdk), AGX AgileX's newer Python SDK (pyAgxArm), PC the
//! third-party piper_control library.

mod command;
mod config;
mod feedback;
mod firmware;
mod mit;
pub(crate) mod si;
mod types;

pub use command::*;
pub use config::*;
pub use feedback::*;
pub use firmware::*;
pub use mit::*;
pub use si::{mdeg_to_rad, rad_to_mdeg};
pub use types::*;

use bus::{CanFrame, CanId};

/// CAN identifiers of the Piper protocol (11-bit).
pub mod ids {
    /// LED control.
    pub const LED: u16 = 0x121;
    /// Motion control 1: e-stop, trajectory, drag teach.
    pub const MOTION_CTRL_1: u16 = 0x150;
    /// Motion control 2: mode control.
    pub const MODE_CTRL: u16 = 0x151;
    /// End-pose target X, Y.
    pub const END_POSE_CMD_1: u16 = 0x152;
    /// End-pose target Z, RX.
    pub const END_POSE_CMD_2: u16 = 0x153;
    /// End-pose target RY, RZ.
    pub const END_POSE_CMD_3: u16 = 0x154;
    /// Joint target J1, J2.
    pub const JOINT_CMD_12: u16 = 0x155;
    /// Joint target J3, J4.
    pub const JOINT_CMD_34: u16 = 0x156;
    /// Joint target J5, J6.
    pub const JOINT_CMD_56: u16 = 0x157;
    /// MOVE C point index.
    pub const MOVE_C_POINT: u16 = 0x158;
    /// Gripper control.
    pub const GRIPPER_CMD: u16 = 0x159;
    /// MIT command of joint 1 (joint n = id − 0x159).
    pub const MIT_J1: u16 = 0x15A;
    /// MIT command of joint 6.
    pub const MIT_J6: u16 = 0x15F;
    /// CPV parameter frame of motor 1 (motor n = id − 0x180, 7 = gripper).
    pub const CPV_1: u16 = 0x181;
    /// CPV parameter frame of motor 7 (gripper).
    pub const CPV_7: u16 = 0x187;
    /// Leader-arm home request.
    pub const LEADER_HOME: u16 = 0x191;
    /// Joint driver high-speed feedback, joint 1 (joint n = id − 0x250).
    pub const HIGH_SPEED_1: u16 = 0x251;
    /// Joint driver high-speed feedback, joint 6.
    pub const HIGH_SPEED_6: u16 = 0x256;
    /// Joint driver low-speed feedback, joint 1 (joint n = id − 0x260).
    pub const LOW_SPEED_1: u16 = 0x261;
    /// Joint driver low-speed feedback, joint 6.
    pub const LOW_SPEED_6: u16 = 0x266;
    /// Arm status.
    pub const ARM_STATUS: u16 = 0x2A1;
    /// End pose X, Y.
    pub const END_POSE_1: u16 = 0x2A2;
    /// End pose Z, RX.
    pub const END_POSE_2: u16 = 0x2A3;
    /// End pose RY, RZ.
    pub const END_POSE_3: u16 = 0x2A4;
    /// Joint angles J1, J2.
    pub const JOINTS_12: u16 = 0x2A5;
    /// Joint angles J3, J4.
    pub const JOINTS_34: u16 = 0x2A6;
    /// Joint angles J5, J6.
    pub const JOINTS_56: u16 = 0x2A7;
    /// Gripper feedback.
    pub const GRIPPER: u16 = 0x2A8;
    /// Firmware-upgrade bus mode.
    pub const UPGRADE_MODE: u16 = 0x422;
    /// Leader/follower configuration.
    pub const LEADER_FOLLOWER: u16 = 0x470;
    /// Motor enable / disable.
    pub const MOTOR_ENABLE: u16 = 0x471;
    /// Query joint limits (→ 0x473) or max acceleration (→ 0x47C).
    pub const QUERY_JOINT: u16 = 0x472;
    /// Joint limits / max speed reply.
    pub const JOINT_LIMITS: u16 = 0x473;
    /// Set joint limits / max speed.
    pub const SET_JOINT_LIMITS: u16 = 0x474;
    /// Joint configuration (zero, max acc, clear error).
    pub const JOINT_CONFIG: u16 = 0x475;
    /// Set-command acknowledgement.
    pub const ACK: u16 = 0x476;
    /// Parameter query and settings.
    pub const PARAM: u16 = 0x477;
    /// End-effector vel/acc reply.
    pub const END_PARAMS: u16 = 0x478;
    /// Set end-effector vel/acc.
    pub const SET_END_PARAMS: u16 = 0x479;
    /// Set collision-protection levels.
    pub const SET_COLLISION: u16 = 0x47A;
    /// Collision-protection levels reply.
    pub const COLLISION: u16 = 0x47B;
    /// Joint max acceleration reply.
    pub const JOINT_MAX_ACC: u16 = 0x47C;
    /// Set gripper / teach-pendant parameters.
    pub const SET_GRIPPER_TEACH: u16 = 0x47D;
    /// Gripper / teach-pendant parameters reply.
    pub const GRIPPER_TEACH: u16 = 0x47E;
    /// Per-joint end velocity/acceleration, joint 1 (joint n = id − 0x480).
    pub const END_VEL_ACC_1: u16 = 0x481;
    /// Per-joint end velocity/acceleration, joint 6.
    pub const END_VEL_ACC_6: u16 = 0x486;
    /// Set joint assistance levels.
    pub const SET_ASSIST: u16 = 0x487;
    /// Joint assistance levels reply.
    pub const ASSIST: u16 = 0x488;
    /// Firmware version query and reply.
    pub const FIRMWARE: u16 = 0x4AF;
}

/// "Leave unchanged" value of 16-bit fields in set commands (fw >= V1.5-2).
pub const UNCHANGED_U16: u16 = 0x7FFF;

/// Why a received frame could not be decoded.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DecodeError {
    /// The frame is shorter than its layout.
    #[error("frame {id:#05x}: {got} data bytes, layout needs {needed}")]
    BadDlc {
        /// CAN id.
        id: u16,
        /// Bytes the layout uses.
        needed: usize,
        /// Bytes received.
        got: usize,
    },
    /// An index field (joint, motor) is outside its range.
    #[error("frame {id:#05x}: {field} = {value} is out of range")]
    OutOfRange {
        /// CAN id.
        id: u16,
        /// Field name.
        field: &'static str,
        /// Received value.
        value: u8,
    },
    /// The MIT check nibble does not match the payload.
    #[error("frame {id:#05x}: check nibble {got:#x}, expected {expected:#x}")]
    BadCrc {
        /// CAN id.
        id: u16,
        /// Nibble computed from the payload.
        expected: u8,
        /// Nibble received.
        got: u8,
    },
    /// A 29-bit identifier (the Piper uses 11-bit ids only).
    #[error("extended frame {id:#010x} is not a Piper frame")]
    Extended {
        /// The extended id.
        id: u32,
    },
}

/// Build a standard frame from an id and payload of at most eight bytes.
pub(crate) fn frame(id: u16, data: &[u8]) -> CanFrame {
    match CanFrame::new(CanId::Standard(id), data) {
        Ok(frame) => frame,
        // Every caller passes a literal layout of at most 8 bytes and an id below 0x800.
        Err(_) => unreachable!("Piper layouts are at most 8 bytes"),
    }
}

/// The payload, checked to hold at least `needed` bytes.
pub(crate) fn payload(id: u16, frame: &CanFrame, needed: usize) -> Result<&[u8], DecodeError> {
    let data = frame.data();
    if data.len() < needed {
        return Err(DecodeError::BadDlc {
            id,
            needed,
            got: data.len(),
        });
    }
    Ok(data)
}

pub(crate) fn be_i32(data: &[u8], at: usize) -> i32 {
    i32::from_be_bytes([data[at], data[at + 1], data[at + 2], data[at + 3]])
}

pub(crate) fn be_i16(data: &[u8], at: usize) -> i16 {
    i16::from_be_bytes([data[at], data[at + 1]])
}

pub(crate) fn be_u16(data: &[u8], at: usize) -> u16 {
    u16::from_be_bytes([data[at], data[at + 1]])
}

/// Where `frame` sits in the id block `first..=last`: its id and its 0-based offset. The
/// per-message decoders are public and may be handed any frame, so an id outside the block is
/// an error (before, the offset arithmetic underflowed: a panic in debug builds, found by the
/// piper_driver_decode fuzz target).
pub(crate) fn block_offset(
    frame: &CanFrame,
    first: u16,
    last: u16,
    field: &'static str,
) -> Result<(u16, u8), DecodeError> {
    let id = match frame.id() {
        CanId::Standard(id) => id,
        CanId::Extended(id) => return Err(DecodeError::Extended { id }),
    };
    match id.checked_sub(first) {
        Some(offset) if id <= last => Ok((id, offset as u8)),
        _ => Err(DecodeError::OutOfRange {
            id,
            field,
            // The number the id would stand for, as far as it fits.
            value: u8::try_from(id.wrapping_sub(first).wrapping_add(1)).unwrap_or(u8::MAX),
        }),
    }
}

/// Check a 1–6 joint index.
pub(crate) fn joint_index(id: u16, field: &'static str, value: u8) -> Result<u8, DecodeError> {
    if (1..=6).contains(&value) {
        Ok(value)
    } else {
        Err(DecodeError::OutOfRange { id, field, value })
    }
}

/// Every message the driver understands on the bus (arm feedback, replies, and the control
/// frames a leader arm emits).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub enum Message {
    /// 0x2A1.
    ArmStatus(ArmStatus),
    /// 0x2A2–0x2A4.
    EndPose(EndPosePart),
    /// 0x2A5–0x2A7.
    Joints(JointPair),
    /// 0x2A8.
    Gripper(GripperFeedback),
    /// 0x251–0x256.
    HighSpeed(HighSpeedFeedback),
    /// 0x261–0x266.
    LowSpeed(LowSpeedFeedback),
    /// 0x481–0x486.
    EndVelAcc(EndVelAccFeedback),
    /// 0x473.
    JointLimits(JointLimits),
    /// 0x47C.
    JointMaxAcc(JointMaxAcc),
    /// 0x476.
    Ack(Ack),
    /// 0x478.
    EndParams(EndParams),
    /// 0x47B.
    Collision(CollisionLevels),
    /// 0x47E.
    GripperTeach(GripperTeachParams),
    /// 0x488.
    Assist(AssistLevels),
    /// 0x4AF reply part.
    FirmwarePart(FirmwarePart),
    /// 0x181–0x187 reply (`'a'`).
    Cpv(CpvFrame),
    /// 0x151 emitted by a leader arm.
    ModeEcho(ModeCtrl),
    /// 0x155–0x157 emitted by a leader arm.
    JointCmdEcho(JointPair),
    /// 0x159 emitted by a leader arm.
    GripperCmdEcho(GripperCtrl),
}

/// Decode one received frame. `Ok(None)` for ids the driver does not consume (host-only
/// commands from another client, firmware-upgrade internals, undocumented ids).
///
/// ```
/// use bus::CanFrame;
/// use driver::piper::codec::{decode, JointPair, Message};
/// // J1 = 90°, J2 = −90° in 0.001° (big-endian int32).
/// let frame = CanFrame::standard(0x2A5, &[0x00, 0x01, 0x5F, 0x90, 0xFF, 0xFE, 0xA0, 0x70]).unwrap();
/// let message = decode(&frame).unwrap();
/// assert_eq!(message, Some(Message::Joints(JointPair { first_joint: 1, a_mdeg: 90_000, b_mdeg: -90_000 })));
/// ```
pub fn decode(frame: &CanFrame) -> Result<Option<Message>, DecodeError> {
    let id = match frame.id() {
        CanId::Standard(id) => id,
        CanId::Extended(id) => return Err(DecodeError::Extended { id }),
    };
    let message = match id {
        ids::ARM_STATUS => Message::ArmStatus(ArmStatus::decode(frame)?),
        ids::END_POSE_1..=ids::END_POSE_3 => Message::EndPose(EndPosePart::decode(frame)?),
        ids::JOINTS_12..=ids::JOINTS_56 => Message::Joints(JointPair::decode_feedback(frame)?),
        ids::GRIPPER => Message::Gripper(GripperFeedback::decode(frame)?),
        ids::HIGH_SPEED_1..=ids::HIGH_SPEED_6 => {
            Message::HighSpeed(HighSpeedFeedback::decode(frame)?)
        }
        ids::LOW_SPEED_1..=ids::LOW_SPEED_6 => Message::LowSpeed(LowSpeedFeedback::decode(frame)?),
        ids::END_VEL_ACC_1..=ids::END_VEL_ACC_6 => {
            Message::EndVelAcc(EndVelAccFeedback::decode(frame)?)
        }
        ids::JOINT_LIMITS => Message::JointLimits(JointLimits::decode(frame)?),
        ids::JOINT_MAX_ACC => Message::JointMaxAcc(JointMaxAcc::decode(frame)?),
        ids::ACK => Message::Ack(Ack::decode(frame)?),
        ids::END_PARAMS => Message::EndParams(EndParams::decode(frame)?),
        ids::COLLISION => Message::Collision(CollisionLevels::decode(frame)?),
        ids::GRIPPER_TEACH => Message::GripperTeach(GripperTeachParams::decode(frame)?),
        ids::ASSIST => Message::Assist(AssistLevels::decode(frame)?),
        ids::FIRMWARE => match FirmwarePart::decode(frame) {
            Some(part) => Message::FirmwarePart(part),
            None => return Ok(None),
        },
        ids::CPV_1..=ids::CPV_7 => {
            let cpv = CpvFrame::decode(frame)?;
            if cpv.mode != CpvMode::Answer {
                return Ok(None);
            }
            Message::Cpv(cpv)
        }
        ids::MODE_CTRL => Message::ModeEcho(ModeCtrl::decode(frame)?),
        ids::JOINT_CMD_12..=ids::JOINT_CMD_56 => {
            Message::JointCmdEcho(JointPair::decode_command(frame)?)
        }
        ids::GRIPPER_CMD => Message::GripperCmdEcho(GripperCtrl::decode(frame)?),
        _ => return Ok(None),
    };
    Ok(Some(message))
}
