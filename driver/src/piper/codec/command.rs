//! Motion-control commands (host → arm): 0x121, 0x150–0x159, 0x181–0x187, 0x191.

use bus::CanFrame;

use super::{
    be_i32, be_u16, block_offset, frame, ids, payload, CtrlMode, DecodeError, EmergencyStop,
    InstallPosition, MitMode, MoveCPoint, MoveMode, TeachStatus, TrackCommand,
};

/// 0x150 motion control 1: quick stop / resume, offline trajectory, drag teach.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct MotionCtrl1 {
    /// Quick e-stop field.
    pub estop: EmergencyStop,
    /// Offline-trajectory command.
    pub track: TrackCommand,
    /// Drag-teach command.
    pub drag_teach: TeachStatus,
    /// Trajectory point index (transfer only).
    pub traj_index: u8,
    /// Trajectory package name index (transfer only).
    pub name_index: u16,
    /// Trajectory package CRC-16 (transfer only).
    pub crc16: u16,
}

impl MotionCtrl1 {
    /// Only the e-stop field set (what the SDK sends for stop / resume).
    pub fn estop(estop: EmergencyStop) -> Self {
        Self {
            estop,
            track: TrackCommand::Off,
            drag_teach: TeachStatus::Off,
            traj_index: 0,
            name_index: 0,
            crc16: 0,
        }
    }

    /// Encode as 0x150.
    pub fn encode(&self) -> CanFrame {
        let [n0, n1] = self.name_index.to_be_bytes();
        let [c0, c1] = self.crc16.to_be_bytes();
        frame(
            ids::MOTION_CTRL_1,
            &[
                self.estop.into(),
                self.track.into(),
                self.drag_teach.into(),
                self.traj_index,
                n0,
                n1,
                c0,
                c1,
            ],
        )
    }
}

/// 0x151 mode control (also emitted by a leader arm).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct ModeCtrl {
    /// Control mode.
    pub ctrl_mode: CtrlMode,
    /// MOVE mode.
    pub move_mode: MoveMode,
    /// Speed percentage 0–100.
    pub speed_pct: u8,
    /// MIT flag.
    pub mit_mode: MitMode,
    /// Offline-trajectory dwell, s (255 = trajectory end).
    pub dwell_s: u8,
    /// Installation position.
    pub install_pos: InstallPosition,
}

impl ModeCtrl {
    /// Encode as 0x151.
    pub fn encode(&self) -> CanFrame {
        frame(
            ids::MODE_CTRL,
            &[
                self.ctrl_mode.into(),
                self.move_mode.into(),
                self.speed_pct,
                self.mit_mode.into(),
                self.dwell_s,
                self.install_pos.into(),
                0,
                0,
            ],
        )
    }

    /// Decode a 0x151 frame.
    pub fn decode(frame: &CanFrame) -> Result<Self, DecodeError> {
        let d = payload(ids::MODE_CTRL, frame, 6)?;
        Ok(Self {
            ctrl_mode: d[0].into(),
            move_mode: d[1].into(),
            speed_pct: d[2],
            mit_mode: d[3].into(),
            dwell_s: d[4],
            install_pos: d[5].into(),
        })
    }
}

/// End-pose target (0x152–0x154): flange position in µm and ZYX Euler angles in millidegrees.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct EndPoseTarget {
    /// X, µm.
    pub x_um: i32,
    /// Y, µm.
    pub y_um: i32,
    /// Z, µm.
    pub z_um: i32,
    /// RX, millidegrees.
    pub rx_mdeg: i32,
    /// RY, millidegrees.
    pub ry_mdeg: i32,
    /// RZ, millidegrees.
    pub rz_mdeg: i32,
}

fn pair(id: u16, a: i32, b: i32) -> CanFrame {
    let mut data = [0u8; 8];
    data[..4].copy_from_slice(&a.to_be_bytes());
    data[4..].copy_from_slice(&b.to_be_bytes());
    frame(id, &data)
}

impl EndPoseTarget {
    /// The three frames 0x152, 0x153, 0x154 in the order the SDK sends them.
    pub fn encode(&self) -> [CanFrame; 3] {
        [
            pair(ids::END_POSE_CMD_1, self.x_um, self.y_um),
            pair(ids::END_POSE_CMD_2, self.z_um, self.rx_mdeg),
            pair(ids::END_POSE_CMD_3, self.ry_mdeg, self.rz_mdeg),
        ]
    }
}

/// Joint targets J1–J6 in millidegrees (0x155–0x157).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct JointTargets {
    /// Angles of joints 1–6, millidegrees.
    pub angles_mdeg: [i32; 6],
}

impl JointTargets {
    /// The three frames 0x155, 0x156, 0x157.
    pub fn encode(&self) -> [CanFrame; 3] {
        let a = self.angles_mdeg;
        [
            pair(ids::JOINT_CMD_12, a[0], a[1]),
            pair(ids::JOINT_CMD_34, a[2], a[3]),
            pair(ids::JOINT_CMD_56, a[4], a[5]),
        ]
    }
}

/// Encode a 0x158 MOVE C point index.
pub fn encode_move_c_point(point: MoveCPoint) -> CanFrame {
    frame(ids::MOVE_C_POINT, &[point.into(), 0, 0, 0, 0, 0, 0, 0])
}

/// Set-zero marker of 0x159 byte 7.
pub const GRIPPER_SET_ZERO: u8 = 0xAE;

/// 0x159 gripper control (also emitted by a leader arm).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct GripperCtrl {
    /// Target stroke, µm.
    pub stroke_um: i32,
    /// Torque limit, 0.001 N·m.
    pub effort_mnm: u16,
    /// Enable the gripper driver (byte 6 bit 0).
    pub enable: bool,
    /// Clear the gripper error (byte 6 bit 1).
    pub clear_error: bool,
    /// Set the current position as zero (byte 7 = 0xAE).
    pub set_zero: bool,
}

impl GripperCtrl {
    /// Encode as 0x159.
    pub fn encode(&self) -> CanFrame {
        let mut data = [0u8; 8];
        data[..4].copy_from_slice(&self.stroke_um.to_be_bytes());
        data[4..6].copy_from_slice(&self.effort_mnm.to_be_bytes());
        data[6] = u8::from(self.enable) | (u8::from(self.clear_error) << 1);
        data[7] = if self.set_zero { GRIPPER_SET_ZERO } else { 0 };
        frame(ids::GRIPPER_CMD, &data)
    }

    /// Decode a 0x159 frame.
    pub fn decode(frame: &CanFrame) -> Result<Self, DecodeError> {
        let d = payload(ids::GRIPPER_CMD, frame, 8)?;
        Ok(Self {
            stroke_um: be_i32(d, 0),
            effort_mnm: be_u16(d, 4),
            enable: d[6] & 1 != 0,
            clear_error: d[6] & 2 != 0,
            set_zero: d[7] == GRIPPER_SET_ZERO,
        })
    }
}

/// 0x191 leader-arm home request (fw >= V1.7-4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum LeaderHome {
    /// Restore leader/follower (drag) mode.
    Restore,
    /// The leader goes home.
    LeaderHome,
    /// Leader and follower go home together.
    BothHome,
}

impl LeaderHome {
    /// Encode as 0x191.
    pub fn encode(self) -> CanFrame {
        let (b1, b2) = match self {
            Self::Restore => (0, 0),
            Self::LeaderHome => (1, 1),
            Self::BothHome => (0, 1),
        };
        frame(ids::LEADER_HOME, &[1, b1, b2, 0, 0, 0, 0, 0])
    }
}

/// 0x121 LED control ((DOC) only; no SDK implements it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct LedCtrl {
    /// Apply (true) or ignore.
    pub enable: bool,
    /// Joint 1–6.
    pub joint: u8,
    /// LED index 0–254, 0xFF = all.
    pub led: u8,
    /// Red, green, blue.
    pub rgb: [u8; 3],
    /// Rolling counter.
    pub counter: u8,
}

impl LedCtrl {
    /// Encode as 0x121.
    pub fn encode(&self) -> CanFrame {
        let [r, g, b] = self.rgb;
        frame(
            ids::LED,
            &[
                u8::from(self.enable),
                self.joint,
                self.led,
                r,
                g,
                b,
                0,
                self.counter,
            ],
        )
    }
}

/// CPV frame mode (byte 0, ASCII).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum CpvMode {
    /// `'w'`: write.
    Write,
    /// `'r'`: read.
    Read,
    /// `'a'`: the arm's answer.
    Answer,
    /// Any other byte.
    Unknown(u8),
}

impl From<u8> for CpvMode {
    fn from(raw: u8) -> Self {
        match raw {
            b'w' => Self::Write,
            b'r' => Self::Read,
            b'a' => Self::Answer,
            other => Self::Unknown(other),
        }
    }
}

impl From<CpvMode> for u8 {
    fn from(mode: CpvMode) -> u8 {
        match mode {
            CpvMode::Write => b'w',
            CpvMode::Read => b'r',
            CpvMode::Answer => b'a',
            CpvMode::Unknown(raw) => raw,
        }
    }
}

/// 0x181–0x187 CPV parameter frame (request or answer; semantics mostly undocumented).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct CpvFrame {
    /// Motor 1–7 (7 = gripper).
    pub motor: u8,
    /// Read, write or answer.
    pub mode: CpvMode,
    /// Two ASCII characters naming the parameter (`po`, `sp`, `ac` …).
    pub param: [u8; 2],
    /// Value (int32 BE in bytes 3–6).
    pub value: i32,
}

impl CpvFrame {
    /// Encode on 0x180 + motor (8 bytes).
    pub fn encode(&self) -> CanFrame {
        let mut data = [0u8; 8];
        data[0] = self.mode.into();
        data[1..3].copy_from_slice(&self.param);
        data[3..7].copy_from_slice(&self.value.to_be_bytes());
        frame(0x180 + u16::from(self.motor), &data)
    }

    /// Decode a 0x181–0x187 frame (7 or 8 bytes); any other id is refused
    /// ([`DecodeError::Extended`], or [`DecodeError::OutOfRange`] on the motor).
    pub fn decode(frame: &CanFrame) -> Result<Self, DecodeError> {
        let (id, offset) = block_offset(frame, ids::CPV_1, ids::CPV_7, "motor")?;
        let d = payload(id, frame, 7)?;
        Ok(Self {
            motor: offset + 1,
            mode: d[0].into(),
            param: [d[1], d[2]],
            value: be_i32(d, 3),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cpv_decode_refuses_ids_outside_its_range_without_panicking() {
        let good = CpvFrame {
            motor: 2,
            mode: CpvMode::Answer,
            param: *b"kp",
            value: -5,
        };
        assert_eq!(CpvFrame::decode(&good.encode()), Ok(good));
        for id in [0x000, 0x17F, 0x180, 0x188, 0x7FF] {
            let frame = CanFrame::standard(id, good.encode().data()).unwrap();
            assert!(
                matches!(
                    CpvFrame::decode(&frame),
                    Err(DecodeError::OutOfRange { field: "motor", .. })
                ),
                "{frame}"
            );
        }
        let extended = CanFrame::extended(0x182, good.encode().data()).unwrap();
        assert_eq!(
            CpvFrame::decode(&extended),
            Err(DecodeError::Extended { id: 0x182 })
        );
    }
}
