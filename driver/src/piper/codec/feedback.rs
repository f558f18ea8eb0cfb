//! Periodic arm feedback: 0x2A1–0x2A8, 0x251–0x256, 0x261–0x266, 0x481–0x486.

use bus::CanFrame;

use super::{
    be_i16, be_i32, be_u16, block_offset, ids, payload, ArmStatusCode, CtrlMode, DecodeError,
    DriverStatus, GripperStatus, JointMask, MotionStatus, MoveMode, TeachStatus,
};

/// 0x2A1 arm status.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct ArmStatus {
    /// Control mode.
    pub ctrl_mode: CtrlMode,
    /// Arm status code.
    pub arm_status: ArmStatusCode,
    /// Active MOVE mode.
    pub mode_feed: MoveMode,
    /// Drag-teach status.
    pub teach_status: TeachStatus,
    /// Target reached or moving.
    pub motion_status: MotionStatus,
    /// Current offline-trajectory point.
    pub trajectory_num: u8,
    /// Joints whose angle limit is exceeded (byte 6).
    pub angle_limit_exceeded: JointMask,
    /// Joints with a communication error (byte 7).
    pub comm_error: JointMask,
}

impl ArmStatus {
    /// Decode a 0x2A1 frame.
    pub fn decode(frame: &CanFrame) -> Result<Self, DecodeError> {
        let d = payload(ids::ARM_STATUS, frame, 8)?;
        Ok(Self {
            ctrl_mode: d[0].into(),
            arm_status: d[1].into(),
            mode_feed: d[2].into(),
            teach_status: d[3].into(),
            motion_status: d[4].into(),
            trajectory_num: d[5],
            angle_limit_exceeded: JointMask(d[6]),
            comm_error: JointMask(d[7]),
        })
    }

    /// Encode as the arm would (used by tests and tools).
    pub fn encode(&self) -> CanFrame {
        super::frame(
            ids::ARM_STATUS,
            &[
                self.ctrl_mode.into(),
                self.arm_status.into(),
                self.mode_feed.into(),
                self.teach_status.into(),
                self.motion_status.into(),
                self.trajectory_num,
                self.angle_limit_exceeded.0,
                self.comm_error.0,
            ],
        )
    }
}

/// One frame of the end pose (0x2A2–0x2A4, same layout as the 0x152–0x154 targets).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum EndPosePart {
    /// X and Y, 0.001 mm.
    Xy {
        /// X in µm.
        x_um: i32,
        /// Y in µm.
        y_um: i32,
    },
    /// Z (0.001 mm) and RX (0.001°).
    ZRx {
        /// Z in µm.
        z_um: i32,
        /// RX in millidegrees.
        rx_mdeg: i32,
    },
    /// RY and RZ, 0.001°.
    RyRz {
        /// RY in millidegrees.
        ry_mdeg: i32,
        /// RZ in millidegrees.
        rz_mdeg: i32,
    },
}

impl EndPosePart {
    /// Decode a 0x2A2–0x2A4 frame (or a 0x152–0x154 command: the layout is the same).
    pub fn decode(frame: &CanFrame) -> Result<Self, DecodeError> {
        let id = frame.raw_id() as u16;
        let d = payload(id, frame, 8)?;
        let (a, b) = (be_i32(d, 0), be_i32(d, 4));
        Ok(match id {
            ids::END_POSE_1 | ids::END_POSE_CMD_1 => Self::Xy { x_um: a, y_um: b },
            ids::END_POSE_2 | ids::END_POSE_CMD_2 => Self::ZRx {
                z_um: a,
                rx_mdeg: b,
            },
            _ => Self::RyRz {
                ry_mdeg: a,
                rz_mdeg: b,
            },
        })
    }
}

/// Two joint angles of one frame (0x2A5–0x2A7 feedback or 0x155–0x157 targets).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct JointPair {
    /// The first joint of the pair: 1, 3 or 5.
    pub first_joint: u8,
    /// Angle of `first_joint`, millidegrees.
    pub a_mdeg: i32,
    /// Angle of `first_joint + 1`, millidegrees.
    pub b_mdeg: i32,
}

impl JointPair {
    fn decode_at(frame: &CanFrame, base: u16) -> Result<Self, DecodeError> {
        // base, base+1, base+2 carry joints 1-2, 3-4, 5-6.
        let (id, pair) = block_offset(frame, base, base + 2, "joint pair")?;
        let d = payload(id, frame, 8)?;
        let first_joint = pair * 2 + 1;
        Ok(Self {
            first_joint,
            a_mdeg: be_i32(d, 0),
            b_mdeg: be_i32(d, 4),
        })
    }

    /// Decode a 0x2A5–0x2A7 feedback frame (another id is refused).
    pub fn decode_feedback(frame: &CanFrame) -> Result<Self, DecodeError> {
        Self::decode_at(frame, ids::JOINTS_12)
    }

    /// Decode a 0x155–0x157 target frame (a leader arm’s emission or a host command; another
    /// id is refused).
    pub fn decode_command(frame: &CanFrame) -> Result<Self, DecodeError> {
        Self::decode_at(frame, ids::JOINT_CMD_12)
    }
}

/// 0x2A8 gripper feedback.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct GripperFeedback {
    /// Jaw opening, µm (0 = closed).
    pub stroke_um: i32,
    /// Torque, 0.001 N·m.
    pub torque_mnm: i16,
    /// Status bits.
    pub status: GripperStatus,
}

impl GripperFeedback {
    /// Decode a 0x2A8 frame.
    pub fn decode(frame: &CanFrame) -> Result<Self, DecodeError> {
        let d = payload(ids::GRIPPER, frame, 7)?;
        Ok(Self {
            stroke_um: be_i32(d, 0),
            torque_mnm: be_i16(d, 4),
            status: GripperStatus(d[6]),
        })
    }
}

/// 0x251–0x256 joint driver high-speed feedback.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct HighSpeedFeedback {
    /// Joint 1–6.
    pub joint: u8,
    /// Motor speed, 0.001 rad/s.
    pub speed_mrad_s: i16,
    /// Motor current, 0.001 A (signed).
    pub current_ma: i16,
    /// Motor position, 0.001 rad (unit per AGX; see the spec §4.5).
    pub position_mrad: i32,
}

impl HighSpeedFeedback {
    /// Decode a 0x251–0x256 frame (another id is refused).
    pub fn decode(frame: &CanFrame) -> Result<Self, DecodeError> {
        let (id, offset) = block_offset(frame, ids::HIGH_SPEED_1, ids::HIGH_SPEED_6, "joint")?;
        let d = payload(id, frame, 8)?;
        Ok(Self {
            joint: offset + 1,
            speed_mrad_s: be_i16(d, 0),
            current_ma: be_i16(d, 2),
            position_mrad: be_i32(d, 4),
        })
    }

    /// The SDK's effort estimate in 0.001 N·m: current × 1.18125 (J1–3) or × 0.95844 (J4–6).
    pub fn effort_mnm(&self) -> f64 {
        let k = if self.joint <= 3 { 1.18125 } else { 0.95844 };
        f64::from(self.current_ma) * k
    }
}

/// 0x261–0x266 joint driver low-speed feedback.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct LowSpeedFeedback {
    /// Joint 1–6.
    pub joint: u8,
    /// Bus voltage, 0.1 V.
    pub bus_voltage_dv: u16,
    /// Driver temperature, °C.
    pub driver_temp_c: i16,
    /// Motor temperature, °C.
    pub motor_temp_c: i8,
    /// Driver status bits.
    pub status: DriverStatus,
    /// Bus current, 0.001 A.
    pub bus_current_ma: u16,
}

impl LowSpeedFeedback {
    /// Decode a 0x261–0x266 frame (another id is refused).
    pub fn decode(frame: &CanFrame) -> Result<Self, DecodeError> {
        let (id, offset) = block_offset(frame, ids::LOW_SPEED_1, ids::LOW_SPEED_6, "joint")?;
        let d = payload(id, frame, 8)?;
        Ok(Self {
            joint: offset + 1,
            bus_voltage_dv: be_u16(d, 0),
            driver_temp_c: be_i16(d, 2),
            motor_temp_c: i8::from_be_bytes([d[4]]),
            status: DriverStatus(d[5]),
            bus_current_ma: be_u16(d, 6),
        })
    }
}

/// 0x481–0x486 per-joint end velocity / acceleration.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct EndVelAccFeedback {
    /// Joint 1–6.
    pub joint: u8,
    /// Linear velocity, 0.001 m/s.
    pub lin_vel_mm_s: u16,
    /// Angular velocity, 0.001 rad/s.
    pub ang_vel_mrad_s: u16,
    /// Linear acceleration, 0.001 m/s².
    pub lin_acc_mm_s2: u16,
    /// Angular acceleration, 0.001 rad/s².
    pub ang_acc_mrad_s2: u16,
}

impl EndVelAccFeedback {
    /// Decode a 0x481–0x486 frame (another id is refused).
    pub fn decode(frame: &CanFrame) -> Result<Self, DecodeError> {
        let (id, offset) = block_offset(frame, ids::END_VEL_ACC_1, ids::END_VEL_ACC_6, "joint")?;
        let d = payload(id, frame, 8)?;
        Ok(Self {
            joint: offset + 1,
            lin_vel_mm_s: be_u16(d, 0),
            ang_vel_mrad_s: be_u16(d, 2),
            lin_acc_mm_s2: be_u16(d, 4),
            ang_acc_mrad_s2: be_u16(d, 6),
        })
    }
}

#[cfg(test)]
mod block_tests {
    use super::*;

    #[test]
    fn per_joint_decoders_refuse_ids_outside_their_block() {
        let data = [0x11; 8];
        for id in [
            0x000, 0x150, 0x250, 0x257, 0x260, 0x267, 0x2A4, 0x2A8, 0x480, 0x487, 0x7FF,
        ] {
            let frame = CanFrame::standard(id, &data).unwrap();
            assert!(
                matches!(
                    HighSpeedFeedback::decode(&frame),
                    Err(DecodeError::OutOfRange { field: "joint", .. })
                ),
                "{id:#x}"
            );
            assert!(LowSpeedFeedback::decode(&frame).is_err(), "{id:#x}");
            assert!(EndVelAccFeedback::decode(&frame).is_err(), "{id:#x}");
            assert!(JointPair::decode_feedback(&frame).is_err(), "{id:#x}");
        }
        let j3 = CanFrame::standard(0x263, &data).unwrap();
        assert_eq!(LowSpeedFeedback::decode(&j3).unwrap().joint, 3);
        let j56 = CanFrame::standard(0x2A7, &data).unwrap();
        assert_eq!(JointPair::decode_feedback(&j56).unwrap().first_joint, 5);
        let extended = CanFrame::extended(0x481, &data).unwrap();
        assert_eq!(
            EndVelAccFeedback::decode(&extended),
            Err(DecodeError::Extended { id: 0x481 })
        );
    }
}
