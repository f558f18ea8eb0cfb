//! The driver's own codec for the RobStride private protocol (spec §2–§5, §9), written
//! independently of the emulator's.

use std::time::Duration;

use bus::CanFrame;

use crate::robstride::model::Ranges;

/// Communication type numbers (bits 28..24).
pub mod comm {
    /// Get device ID.
    pub const GET_ID: u8 = 0;
    /// Operation-control command.
    pub const OP_CONTROL: u8 = 1;
    /// Status reply.
    pub const STATUS: u8 = 2;
    /// Enable.
    pub const ENABLE: u8 = 3;
    /// Stop / clear / version.
    pub const STOP: u8 = 4;
    /// Set mechanical zero.
    pub const SET_ZERO: u8 = 6;
    /// Set CAN ID.
    pub const SET_CAN_ID: u8 = 7;
    /// Read parameter.
    pub const READ_PARAM: u8 = 17;
    /// Write parameter.
    pub const WRITE_PARAM: u8 = 18;
    /// Fault feedback.
    pub const FAULT: u8 = 21;
    /// Save.
    pub const SAVE: u8 = 22;
    /// Baud rate.
    pub const BAUD: u8 = 23;
    /// Active reporting.
    pub const ACTIVE_REPORT: u8 = 24;
    /// Protocol switch.
    pub const PROTOCOL: u8 = 25;
}

/// Compose a 29-bit identifier.
pub fn ext_id(comm_type: u8, data2: u16, dst: u8) -> u32 {
    (u32::from(comm_type & 0x1F) << 24) | (u32::from(data2) << 8) | u32::from(dst)
}

/// A request frame (`data2` = bits 23..8: usually the host ID in the low byte).
pub fn request(
    comm_type: u8,
    data2: u16,
    motor: u8,
    data: [u8; 8],
) -> Result<CanFrame, bus::FrameError> {
    CanFrame::extended(ext_id(comm_type, data2, motor), &data)
}

/// Float → u16 over [min, max] (manual formula: clamp, scale, truncate).
pub fn to_u16(value: f32, min: f32, max: f32) -> u16 {
    if value.is_nan() {
        return 0;
    }
    let x = value.clamp(min, max);
    ((x - min) / (max - min) * 65535.0) as u16
}

/// u16 → float over [min, max].
pub fn from_u16(raw: u16, min: f32, max: f32) -> f32 {
    min + f32::from(raw) / 65535.0 * (max - min)
}

/// Mode state of a status frame (bits 23..22).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MotorMode {
    /// Torque off.
    Reset,
    /// Calibrating.
    Calibration,
    /// Running.
    Run,
    /// Brake (undocumented value 3).
    Brake,
}

/// Fault bits of a status frame (bits 21..16).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StatusFaults(pub u8);

impl StatusFaults {
    /// Any fault bit set.
    pub fn any(self) -> bool {
        self.0 & 0x3F != 0
    }
    /// Bit 16: under-voltage.
    pub fn under_voltage(self) -> bool {
        self.0 & 0x01 != 0
    }
    /// Bit 17: over-current (phase current or driver).
    pub fn over_current(self) -> bool {
        self.0 & 0x02 != 0
    }
    /// Bit 18: over-temperature.
    pub fn over_temperature(self) -> bool {
        self.0 & 0x04 != 0
    }
    /// Bit 19: magnetic encoder fault.
    pub fn encoder(self) -> bool {
        self.0 & 0x08 != 0
    }
    /// Bit 20: stall / overload.
    pub fn stall_overload(self) -> bool {
        self.0 & 0x10 != 0
    }
    /// Bit 21: not calibrated.
    pub fn uncalibrated(self) -> bool {
        self.0 & 0x20 != 0
    }
}

/// Where a status frame came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FeedbackKind {
    /// A type-2 frame (reply, or active report of old firmware).
    Reply,
    /// A type-24 active report.
    ActiveReport,
}

/// A decoded status frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Feedback {
    /// Motor CAN ID.
    pub motor_id: u8,
    /// Mode state.
    pub mode: MotorMode,
    /// Fault bits.
    pub faults: StatusFaults,
    /// Angle (rad, wraps within ±4π).
    pub angle_rad: f32,
    /// Speed (rad/s).
    pub speed_rad_s: f32,
    /// Torque (N·m).
    pub torque_nm: f32,
    /// Temperature (°C).
    pub temperature_c: f32,
    /// Type 2 or 24.
    pub kind: FeedbackKind,
    /// Receive timestamp.
    pub timestamp: Duration,
}

/// A decoded type-21 frame (spec §9.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FaultReport {
    /// Fault word (bytes 0..3, LE).
    pub fault_word: u32,
    /// Warning word (bytes 4..7, LE).
    pub warning_word: u32,
}

impl FaultReport {
    /// Bit 0: over-temperature fault.
    pub fn over_temperature(self) -> bool {
        self.fault_word & 1 != 0
    }
    /// Bit 1: gate-driver fault.
    pub fn gate_driver(self) -> bool {
        self.fault_word & (1 << 1) != 0
    }
    /// Bit 2: under-voltage.
    pub fn under_voltage(self) -> bool {
        self.fault_word & (1 << 2) != 0
    }
    /// Bit 3: over-voltage.
    pub fn over_voltage(self) -> bool {
        self.fault_word & (1 << 3) != 0
    }
    /// Bits 16, 4, 5: phase A, B, C over-current.
    pub fn phase_over_current(self) -> [bool; 3] {
        [
            self.fault_word & (1 << 16) != 0,
            self.fault_word & (1 << 4) != 0,
            self.fault_word & (1 << 5) != 0,
        ]
    }
    /// Bit 7: encoder not calibrated.
    pub fn uncalibrated(self) -> bool {
        self.fault_word & (1 << 7) != 0
    }
    /// Bit 14: stall / I²t overload.
    pub fn stall_overload(self) -> bool {
        self.fault_word & (1 << 14) != 0
    }
    /// Warning bit 0: over-temperature warning.
    pub fn over_temperature_warning(self) -> bool {
        self.warning_word & 1 != 0
    }
}

/// A frame the driver understands, addressed to our host (or type 0 to 0xFE).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Incoming {
    /// Type 0: a motor announced its UID (ping, set-ID, baud and protocol replies).
    DeviceId {
        /// Motor ID.
        motor_id: u8,
        /// MCU UID.
        uid: [u8; 8],
    },
    /// Type 2 / 24 status.
    Feedback(Feedback),
    /// Type 2 version reply (`00 C4 56 …`).
    Version {
        /// Motor ID.
        motor_id: u8,
        /// Version bytes, most significant first.
        version: [u8; 4],
    },
    /// Type 17 reply.
    Param {
        /// Motor ID.
        motor_id: u8,
        /// True when bits 23..16 = 0.
        ok: bool,
        /// Index echo.
        index: u16,
        /// Bytes 4..7.
        value: [u8; 4],
    },
    /// Type 21.
    Fault {
        /// Motor ID.
        motor_id: u8,
        /// The words.
        report: FaultReport,
    },
}

impl Incoming {
    /// The motor the frame comes from.
    pub fn motor_id(&self) -> u8 {
        match self {
            Self::DeviceId { motor_id, .. }
            | Self::Version { motor_id, .. }
            | Self::Param { motor_id, .. }
            | Self::Fault { motor_id, .. } => *motor_id,
            Self::Feedback(feedback) => feedback.motor_id,
        }
    }
}

/// Decode a motor frame for host `host_id`, or `None` for anything else (other hosts' traffic,
/// requests, standard frames, short frames). `ranges_of` gives the ranges of a motor ID.
pub fn decode(
    frame: &CanFrame,
    host_id: u8,
    timestamp: Duration,
    ranges_of: impl Fn(u8) -> Option<Ranges>,
) -> Option<Incoming> {
    if !frame.is_extended() || frame.len() != 8 {
        return None;
    }
    let id = frame.raw_id();
    let comm_type = ((id >> 24) & 0x1F) as u8;
    let high = ((id >> 16) & 0xFF) as u8;
    let motor_id = ((id >> 8) & 0xFF) as u8;
    let dst = (id & 0xFF) as u8;
    let d = frame.data();
    match comm_type {
        comm::GET_ID if dst == 0xFE && high == 0 => {
            let mut uid = [0u8; 8];
            uid.copy_from_slice(d);
            Some(Incoming::DeviceId { motor_id, uid })
        }
        comm::STATUS | comm::ACTIVE_REPORT if dst == host_id => {
            if comm_type == comm::STATUS && d[..3] == [0x00, 0xC4, 0x56] {
                return Some(Incoming::Version {
                    motor_id,
                    version: [d[3], d[4], d[5], d[6]],
                });
            }
            let r = ranges_of(motor_id)?;
            let be = |i: usize| u16::from_be_bytes([d[i], d[i + 1]]);
            Some(Incoming::Feedback(Feedback {
                motor_id,
                mode: match high >> 6 {
                    0 => MotorMode::Reset,
                    1 => MotorMode::Calibration,
                    2 => MotorMode::Run,
                    _ => MotorMode::Brake,
                },
                faults: StatusFaults(high & 0x3F),
                angle_rad: from_u16(be(0), -r.angle_rad, r.angle_rad),
                speed_rad_s: from_u16(be(2), -r.speed_rad_s, r.speed_rad_s),
                torque_nm: from_u16(be(4), -r.torque_nm, r.torque_nm),
                temperature_c: f32::from(be(6)) / 10.0,
                kind: if comm_type == comm::STATUS {
                    FeedbackKind::Reply
                } else {
                    FeedbackKind::ActiveReport
                },
                timestamp,
            }))
        }
        comm::READ_PARAM if dst == host_id => Some(Incoming::Param {
            motor_id,
            ok: high == 0,
            index: u16::from_le_bytes([d[0], d[1]]),
            value: [d[4], d[5], d[6], d[7]],
        }),
        comm::FAULT if dst == host_id => Some(Incoming::Fault {
            motor_id,
            report: FaultReport {
                fault_word: u32::from_le_bytes([d[0], d[1], d[2], d[3]]),
                warning_word: u32::from_le_bytes([d[4], d[5], d[6], d[7]]),
            },
        }),
        _ => None,
    }
}

/// Operation-control command in physical units (spec §5.2).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct OpControl {
    /// Target angle (rad).
    pub angle_rad: f32,
    /// Target speed (rad/s).
    pub speed_rad_s: f32,
    /// Stiffness (N·m/rad).
    pub kp: f32,
    /// Damping (N·m·s/rad).
    pub kd: f32,
    /// Feed-forward torque (N·m).
    pub torque_nm: f32,
}

/// Encode a type-1 frame (values must already be in range).
pub fn op_control_frame(
    motor: u8,
    cmd: &OpControl,
    r: &Ranges,
) -> Result<CanFrame, bus::FrameError> {
    let torque = to_u16(cmd.torque_nm, -r.torque_nm, r.torque_nm);
    let mut data = [0u8; 8];
    data[0..2].copy_from_slice(&to_u16(cmd.angle_rad, -r.angle_rad, r.angle_rad).to_be_bytes());
    data[2..4]
        .copy_from_slice(&to_u16(cmd.speed_rad_s, -r.speed_rad_s, r.speed_rad_s).to_be_bytes());
    data[4..6].copy_from_slice(&to_u16(cmd.kp, 0.0, r.kp_max).to_be_bytes());
    data[6..8].copy_from_slice(&to_u16(cmd.kd, 0.0, r.kd_max).to_be_bytes());
    request(comm::OP_CONTROL, torque, motor, data)
}

/// Payload of types 23/24/25: magic bytes then the command byte.
pub fn magic_payload(f_cmd: u8) -> [u8; 8] {
    [1, 2, 3, 4, 5, 6, f_cmd, 0]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robstride::model::{Model, RangeTable};
    /// The host the replies under test go to.
    const HOST: u8 = crate::robstride::DEFAULT_HOST_ID;

    fn rs03() -> Ranges {
        Model::RS03.ranges(RangeTable::Manual)
    }

    #[test]
    fn scaling_endpoints_follow_the_manual() {
        assert_eq!(to_u16(-60.0, -60.0, 60.0), 0);
        assert_eq!(to_u16(60.0, -60.0, 60.0), 65535);
        assert_eq!(to_u16(1e9, -60.0, 60.0), 65535);
        assert_eq!(to_u16(f32::NAN, -60.0, 60.0), 0);
        assert!((from_u16(0x7FFF, -60.0, 60.0)).abs() < 0.001);
        assert_eq!(ext_id(comm::SET_CAN_ID, 0x01FD, 0x7F), 0x0701_FD7F);
    }

    #[test]
    fn decode_ignores_what_is_not_a_motor_reply_to_us() {
        let status = |id: u32| {
            CanFrame::extended(id, &[0x7F, 0xFF, 0x7F, 0xFF, 0x7F, 0xFF, 0, 250]).unwrap()
        };
        let ranges = |_| Some(rs03());
        // Another host's reply, a short frame and a standard frame decode to nothing.
        assert_eq!(
            decode(&status(0x0280_7FFC), HOST, Duration::ZERO, ranges),
            None
        );
        let short = CanFrame::extended(0x0280_7FFD, &[0; 4]).unwrap();
        assert_eq!(decode(&short, HOST, Duration::ZERO, ranges), None);
        let standard = CanFrame::standard(0x7F, &[0; 8]).unwrap();
        assert_eq!(decode(&standard, HOST, Duration::ZERO, ranges), None);
        // Unknown motor (no ranges): status frames cannot be scaled.
        assert_eq!(
            decode(&status(0x0280_7FFD), HOST, Duration::ZERO, |_| None),
            None
        );
        let Some(Incoming::Feedback(fb)) =
            decode(&status(0x1880_7FFD), HOST, Duration::ZERO, ranges)
        else {
            panic!("type 24 decodes");
        };
        assert_eq!(
            (fb.kind, fb.mode, fb.temperature_c),
            (FeedbackKind::ActiveReport, MotorMode::Run, 25.0)
        );
        let brake = decode(&status(0x02C0_7FFD), HOST, Duration::ZERO, ranges);
        assert!(matches!(
            brake,
            Some(Incoming::Feedback(Feedback {
                mode: MotorMode::Brake,
                ..
            }))
        ));
    }

    #[test]
    fn op_control_clamps_inside_the_codec_only_after_range_checks() {
        let frame = op_control_frame(
            1,
            &OpControl {
                torque_nm: 60.0,
                kp: 5000.0,
                ..OpControl::default()
            },
            &rs03(),
        )
        .unwrap();
        assert_eq!(frame.raw_id(), 0x01FF_FF01);
        assert_eq!(&frame.data()[4..6], &[0xFF, 0xFF]);
    }
}
