//! The driver's own codec for the RobStride MIT protocol variant (protocol note §12): 11-bit
//! identifiers, bits 10..8 the frame kind and bits 7..0 the motor ID. Written independently of
//! the emulator's; both are checked against `fixtures/robstride/mit.log`.

use bus::CanFrame;

use crate::robstride::codec::{MotorMode, OpControl};
use crate::robstride::model::Ranges;
use crate::robstride::params::ParamValue;

/// Frame kinds (identifier bits 10..8).
pub mod kind {
    /// Fixed-pattern commands and the MIT setpoint.
    pub const COMMAND: u16 = 0;
    /// Position-mode setpoint (command 10).
    pub const POSITION: u16 = 1;
    /// Velocity-mode setpoint (command 11).
    pub const VELOCITY: u16 = 2;
    /// Parameter read (command 14).
    pub const READ: u16 = 3;
    /// Parameter write (command 15).
    pub const WRITE: u16 = 4;
}

/// Marker bytes (byte 7) of the fixed-pattern commands; byte 6 is F_CMD.
pub mod marker {
    /// Enable (F_CMD 0xFF) or set run mode (F_CMD 0/1/2).
    pub const ENABLE_OR_MODE: u8 = 0xFC;
    /// Stop (F_CMD 0xFF) or protocol switch (F_CMD 0/1/2).
    pub const STOP_OR_PROTOCOL: u8 = 0xFD;
    /// Set mechanical zero.
    pub const ZERO: u8 = 0xFE;
    /// Clear fault (F_CMD 0xFF) or query the fault word (any other F_CMD).
    pub const FAULT: u8 = 0xFB;
    /// Set the motor's CAN ID (F_CMD = new ID).
    pub const CAN_ID: u8 = 0xFA;
    /// Set the host ID (F_CMD = host).
    pub const HOST_ID: u8 = 0x01;
    /// Save.
    pub const SAVE: u8 = 0xF8;
    /// Active reporting off/on (F_CMD 0/1).
    pub const REPORT: u8 = 0xF9;
}

/// F_CMD value meaning "no argument" (enable, stop, zero, clear, save).
pub const NO_ARG: u8 = 0xFF;

/// The 11-bit identifier of a frame to `motor`.
pub fn mit_id(frame_kind: u16, motor: u8) -> u16 {
    ((frame_kind & 0x7) << 8) | u16::from(motor)
}

/// A fixed-pattern command: `FF FF FF FF FF FF F_CMD marker`.
pub fn command(motor: u8, f_cmd: u8, marker: u8) -> Result<CanFrame, bus::FrameError> {
    CanFrame::standard(
        mit_id(kind::COMMAND, motor),
        &[0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, f_cmd, marker],
    )
}

/// Float → unsigned `bits`-bit integer over [min, max] (clamp, scale, truncate).
pub fn to_uint(value: f32, min: f32, max: f32, bits: u32) -> u16 {
    if value.is_nan() {
        return 0;
    }
    let top = ((1u32 << bits) - 1) as f32;
    ((value.clamp(min, max) - min) / (max - min) * top) as u16
}

/// Unsigned `bits`-bit integer → float over [min, max].
pub fn from_uint(raw: u16, min: f32, max: f32, bits: u32) -> f32 {
    let top = ((1u32 << bits) - 1) as f32;
    min + f32::from(raw) / top * (max - min)
}

/// Command 3: the MIT setpoint (16-bit angle, 12-bit speed, Kp, Kd and torque).
pub fn setpoint(motor: u8, cmd: &OpControl, r: &Ranges) -> Result<CanFrame, bus::FrameError> {
    let a = to_uint(cmd.angle_rad, -r.angle_rad, r.angle_rad, 16);
    let v = to_uint(cmd.speed_rad_s, -r.speed_rad_s, r.speed_rad_s, 12);
    let kp = to_uint(cmd.kp, 0.0, r.kp_max, 12);
    let kd = to_uint(cmd.kd, 0.0, r.kd_max, 12);
    let t = to_uint(cmd.torque_nm, -r.torque_nm, r.torque_nm, 12);
    let [a_hi, a_lo] = a.to_be_bytes();
    let data = [
        a_hi,
        a_lo,
        (v >> 4) as u8,
        (((v & 0x0F) << 4) | (kp >> 8)) as u8,
        (kp & 0xFF) as u8,
        (kd >> 4) as u8,
        (((kd & 0x0F) << 4) | (t >> 8)) as u8,
        (t & 0xFF) as u8,
    ];
    CanFrame::standard(mit_id(kind::COMMAND, motor), &data)
}

/// Commands 10/11: two little-endian f32 values under `frame_kind`.
pub fn f32_pair(frame_kind: u16, motor: u8, a: f32, b: f32) -> Result<CanFrame, bus::FrameError> {
    let mut data = [0u8; 8];
    data[..4].copy_from_slice(&a.to_le_bytes());
    data[4..].copy_from_slice(&b.to_le_bytes());
    CanFrame::standard(mit_id(frame_kind, motor), &data)
}

/// Command 14: read `index`.
pub fn read_param(motor: u8, index: u16) -> Result<CanFrame, bus::FrameError> {
    let [lo, hi] = index.to_le_bytes();
    CanFrame::standard(mit_id(kind::READ, motor), &[lo, hi, 0, 0, 0, 0, 0, 0])
}

/// Command 15: write `value` to `index`.
pub fn write_param(motor: u8, index: u16, value: ParamValue) -> Result<CanFrame, bus::FrameError> {
    let [lo, hi] = index.to_le_bytes();
    let v = value.to_bytes();
    CanFrame::standard(
        mit_id(kind::WRITE, motor),
        &[lo, hi, 0, 0, v[0], v[1], v[2], v[3]],
    )
}

/// Response 1, decoded (CN manual layout).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MitStatus {
    /// Motor ID (byte 0).
    pub motor_id: u8,
    /// Mode state (byte 6 bits 7..6).
    pub mode: MotorMode,
    /// A fault is latched (byte 6 bit 5).
    pub fault: bool,
    /// A warning is active (byte 6 bit 4).
    pub warning: bool,
    /// Angle (rad), periodic within ±P.
    pub angle_rad: f32,
    /// Speed (rad/s), 12-bit resolution.
    pub speed_rad_s: f32,
    /// Torque (N·m), 12-bit resolution.
    pub torque_nm: f32,
    /// Temperature (°C), 0.1 °C steps.
    pub temperature_c: f32,
}

/// A frame of the MIT variant, decoded.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MitIncoming {
    /// Response 1 (to the host ID).
    Status(MitStatus),
    /// The fault-status reply (to the host ID): the fault word.
    FaultWord {
        /// Motor ID.
        motor_id: u8,
        /// Fault word (bytes 1..4, little-endian).
        word: u32,
    },
    /// Response 2 (from the motor's ID): the MCU UID.
    Uid {
        /// Motor ID.
        motor_id: u8,
        /// MCU UID.
        uid: [u8; 8],
    },
    /// Reply to command 14 (read) or 15 (write): the value at `index`.
    Param {
        /// Motor ID.
        motor_id: u8,
        /// True for a write's reply.
        write: bool,
        /// Index echo.
        index: u16,
        /// Bytes 4..7.
        value: [u8; 4],
    },
}

impl MitIncoming {
    /// The motor the frame is from.
    pub fn motor_id(&self) -> u8 {
        match self {
            Self::Status(status) => status.motor_id,
            Self::FaultWord { motor_id, .. }
            | Self::Uid { motor_id, .. }
            | Self::Param { motor_id, .. } => *motor_id,
        }
    }
}

/// Decode a standard frame of the MIT variant; `ranges_of` gives the scaling of the motor in
/// byte 0 of a Response 1 (`None`: not ours). Frames to or from other nodes give `None`.
///
/// Response 1 and the fault-status reply share the host's identifier; the fault-status reply is
/// recognised by bytes 5..7 being zero (a Response 1 has the temperature there, which is never
/// exactly 0.0 °C with zero torque low byte on a running bench).
pub fn decode(
    frame: &CanFrame,
    host_id: u8,
    ranges_of: impl Fn(u8) -> Option<Ranges>,
) -> Option<MitIncoming> {
    if frame.is_extended() || frame.len() != 8 {
        return None;
    }
    let id = frame.raw_id();
    let d = frame.data();
    let motor = (id & 0xFF) as u8;
    let frame_kind = (id >> 8) as u16;
    if id == u32::from(host_id) {
        let motor_id = d[0];
        if d[5..8] == [0, 0, 0] {
            let word = u32::from_le_bytes([d[1], d[2], d[3], d[4]]);
            return Some(MitIncoming::FaultWord { motor_id, word });
        }
        let r = ranges_of(motor_id)?;
        let angle = u16::from_be_bytes([d[1], d[2]]);
        let speed = (u16::from(d[3]) << 4) | u16::from(d[4] >> 4);
        let torque = (u16::from(d[4] & 0x0F) << 8) | u16::from(d[5]);
        let temp = (u16::from(d[6] & 0x0F) << 8) | u16::from(d[7]);
        return Some(MitIncoming::Status(MitStatus {
            motor_id,
            mode: match d[6] >> 6 {
                0 => MotorMode::Reset,
                1 => MotorMode::Calibration,
                2 => MotorMode::Run,
                _ => MotorMode::Brake,
            },
            fault: d[6] & 0x20 != 0,
            warning: d[6] & 0x10 != 0,
            angle_rad: from_uint(angle, -r.angle_rad, r.angle_rad, 16),
            speed_rad_s: from_uint(speed, -r.speed_rad_s, r.speed_rad_s, 12),
            torque_nm: from_uint(torque, -r.torque_nm, r.torque_nm, 12),
            temperature_c: f32::from(temp) / 10.0,
        }));
    }
    match frame_kind {
        kind::COMMAND if motor <= 0x7F => {
            let mut uid = [0u8; 8];
            uid.copy_from_slice(d);
            Some(MitIncoming::Uid {
                motor_id: motor,
                uid,
            })
        }
        kind::READ | kind::WRITE => Some(MitIncoming::Param {
            motor_id: motor,
            write: frame_kind == kind::WRITE,
            index: u16::from_le_bytes([d[0], d[1]]),
            value: [d[4], d[5], d[6], d[7]],
        }),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robstride::model::{Model, RangeTable};
    /// The host the replies under test go to.
    const HOST: u8 = crate::robstride::DEFAULT_HOST_ID;

    #[test]
    fn twelve_bit_fields_pack_across_nibbles() {
        let r = Model::RS03.ranges(RangeTable::Manual);
        let cmd = OpControl {
            angle_rad: 0.0,
            speed_rad_s: 0.0,
            kp: 20.0,
            kd: 1.0,
            torque_nm: 0.0,
        };
        let frame = setpoint(0x7F, &cmd, &r).unwrap();
        assert_eq!(frame.raw_id(), 0x07F);
        assert_eq!(
            frame.data(),
            &[0x7F, 0xFF, 0x7F, 0xF0, 0x10, 0x02, 0x87, 0xFF]
        );
    }

    #[test]
    fn response1_and_the_fault_reply_share_the_host_id() {
        let r = Model::RS03.ranges(RangeTable::Manual);
        let status =
            CanFrame::standard(0x0FD, &[0x7F, 0x7F, 0xFF, 0x7F, 0xF7, 0xFF, 0x80, 0xFA]).unwrap();
        let Some(MitIncoming::Status(s)) = decode(&status, HOST, |_| Some(r)) else {
            panic!("status");
        };
        assert_eq!(
            (s.mode, s.fault, s.temperature_c),
            (MotorMode::Run, false, 25.0)
        );
        assert!(s.angle_rad.abs() < 2e-4 && s.speed_rad_s.abs() < 0.01);
        let fault = CanFrame::standard(0x0FD, &[0x7F, 1, 0, 1, 0, 0, 0, 0]).unwrap();
        assert_eq!(
            decode(&fault, HOST, |_| Some(r)),
            Some(MitIncoming::FaultWord {
                motor_id: 0x7F,
                word: 0x0001_0001
            })
        );
        // A command frame has Response 2's shape: only the direction tells them apart (the
        // driver never receives its own frames).
        let enable = command(0x05, NO_ARG, marker::ENABLE_OR_MODE).unwrap();
        assert!(matches!(
            decode(&enable, HOST, |_| Some(r)),
            Some(MitIncoming::Uid { motor_id: 5, .. })
        ));
    }
}
