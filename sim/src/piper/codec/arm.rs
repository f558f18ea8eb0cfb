//! Arm → host frames: what the master controller sends (spec §4, §6, §7).

use bus::CanFrame;

use super::frame;
use crate::piper::ids;

/// Radians → wire m° (0.001°), rounded.
pub fn rad_to_mdeg(rad: f64) -> i32 {
    sat_i32((rad.to_degrees() * 1000.0).round())
}

/// Wire m° → radians.
pub fn mdeg_to_rad(mdeg: i32) -> f64 {
    (f64::from(mdeg) / 1000.0).to_radians()
}

/// Saturating float → i32 (NaN → 0), so a runaway simulation never wraps on the wire.
pub fn sat_i32(x: f64) -> i32 {
    if x.is_nan() {
        0
    } else {
        x.clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32
    }
}

/// Saturating float → i16 (NaN → 0).
pub fn sat_i16(x: f64) -> i16 {
    if x.is_nan() {
        0
    } else {
        x.clamp(f64::from(i16::MIN), f64::from(i16::MAX)) as i16
    }
}

/// Saturating float → u16 (NaN → 0).
pub fn sat_u16(x: f64) -> u16 {
    if x.is_nan() {
        0
    } else {
        x.clamp(0.0, f64::from(u16::MAX)) as u16
    }
}

/// 0x2A1 arm status, raw bytes as the firmware fills them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ArmStatusFrame {
    /// Byte 0: control mode.
    pub ctrl_mode: u8,
    /// Byte 1: arm status code.
    pub arm_status: u8,
    /// Byte 2: active MOVE mode code.
    pub mode_feed: u8,
    /// Byte 3: teach status.
    pub teach_status: u8,
    /// Byte 4: 0 reached, 1 moving.
    pub motion_status: u8,
    /// Byte 5: offline trajectory point.
    pub trajectory_num: u8,
    /// Byte 6: bit n = joint n+1 angle limit exceeded.
    pub limit_bits: u8,
    /// Byte 7: bit n = joint n+1 communication error.
    pub comm_bits: u8,
}

impl ArmStatusFrame {
    /// Encode on `id` (0x2A1 plus the feedback offset).
    pub fn encode(&self, id: u16) -> CanFrame {
        frame(
            id,
            &[
                self.ctrl_mode,
                self.arm_status,
                self.mode_feed,
                self.teach_status,
                self.motion_status,
                self.trajectory_num,
                self.limit_bits,
                self.comm_bits,
            ],
        )
    }
}

/// Two int32 BE fields (0x2A2–0x2A7 and the 0x15x command layouts).
pub fn encode_pair(id: u16, first: i32, second: i32) -> CanFrame {
    let mut d = [0u8; 8];
    d[..4].copy_from_slice(&first.to_be_bytes());
    d[4..].copy_from_slice(&second.to_be_bytes());
    frame(id, &d)
}

/// 0x2A8 gripper feedback.
pub fn encode_gripper(id: u16, stroke_um: i32, torque_mnm: i16, status: u8) -> CanFrame {
    let mut d = [0u8; 8];
    d[..4].copy_from_slice(&stroke_um.to_be_bytes());
    d[4..6].copy_from_slice(&torque_mnm.to_be_bytes());
    d[6] = status;
    frame(id, &d)
}

/// 0x251–0x256 high-speed driver feedback for 0-based `joint`.
pub fn encode_high_speed(
    joint: usize,
    speed_mrad_s: i16,
    current_ma: i16,
    position_mrad: i32,
) -> CanFrame {
    let mut d = [0u8; 8];
    d[..2].copy_from_slice(&speed_mrad_s.to_be_bytes());
    d[2..4].copy_from_slice(&current_ma.to_be_bytes());
    d[4..].copy_from_slice(&position_mrad.to_be_bytes());
    frame(ids::HIGH_SPEED_FIRST + joint as u16, &d)
}

/// 0x261–0x266 low-speed driver feedback for 0-based `joint`.
pub fn encode_low_speed(
    joint: usize,
    voltage_dv: u16,
    driver_temp_c: i16,
    motor_temp_c: i8,
    status: u8,
    bus_current_ma: u16,
) -> CanFrame {
    let mut d = [0u8; 8];
    d[..2].copy_from_slice(&voltage_dv.to_be_bytes());
    d[2..4].copy_from_slice(&driver_temp_c.to_be_bytes());
    d[4] = motor_temp_c.to_be_bytes()[0];
    d[5] = status;
    d[6..].copy_from_slice(&bus_current_ma.to_be_bytes());
    frame(ids::LOW_SPEED_FIRST + joint as u16, &d)
}

/// 0x473 joint limit / max speed reply for 0-based `joint`.
pub fn encode_joint_limits(
    joint: usize,
    max_angle_ddeg: i16,
    min_angle_ddeg: i16,
    max_speed_crad_s: u16,
) -> CanFrame {
    let mut d = [0u8; 8];
    d[0] = joint as u8 + 1;
    d[1..3].copy_from_slice(&max_angle_ddeg.to_be_bytes());
    d[3..5].copy_from_slice(&min_angle_ddeg.to_be_bytes());
    d[5..7].copy_from_slice(&max_speed_crad_s.to_be_bytes());
    frame(ids::JOINT_LIMIT_REPLY, &d)
}

/// 0x47C joint max acceleration reply for 0-based `joint`.
pub fn encode_joint_acc(joint: usize, max_acc_crad_s2: u16) -> CanFrame {
    let mut d = [0u8; 8];
    d[0] = joint as u8 + 1;
    d[1..3].copy_from_slice(&max_acc_crad_s2.to_be_bytes());
    frame(ids::JOINT_ACC_REPLY, &d)
}

/// 0x476 acknowledgement of a set command (`cmd_low` = low byte of the acknowledged id).
pub fn encode_ack(cmd_low: u8, zero_ok: bool, point_index: u8) -> CanFrame {
    frame(
        ids::SET_ACK,
        &[cmd_low, u8::from(zero_ok), point_index, 0, 0, 0, 0, 0],
    )
}

/// 0x476 answer to the trajectory-index query (0x477 byte 0 = 3): index in bytes 4–7.
pub fn encode_trajectory_index(name_index: u16, crc16: u16) -> CanFrame {
    let mut d = [0u8; 8];
    d[0] = 0x77;
    d[4..6].copy_from_slice(&name_index.to_be_bytes());
    d[6..8].copy_from_slice(&crc16.to_be_bytes());
    frame(ids::SET_ACK, &d)
}

/// Four uint16 fields (0x478 end limits, 0x481–0x486 end velocities).
pub fn encode_four_u16(id: u16, v: [u16; 4]) -> CanFrame {
    let mut d = [0u8; 8];
    for (i, x) in v.iter().enumerate() {
        d[2 * i..2 * i + 2].copy_from_slice(&x.to_be_bytes());
    }
    frame(id, &d)
}

/// Six u8 fields then two zero bytes (0x47B collision levels, 0x488 assistance).
pub fn encode_six_u8(id: u16, v: [u8; 6]) -> CanFrame {
    let mut d = [0u8; 8];
    d[..6].copy_from_slice(&v);
    frame(id, &d)
}

/// 0x47E gripper / teach-pendant parameters.
pub fn encode_gripper_teach(travel_pct: u8, max_stroke_mm: u8, friction: u8) -> CanFrame {
    frame(
        ids::GRIPPER_TEACH_REPLY,
        &[travel_pct, max_stroke_mm, friction, 0, 0, 0, 0, 0],
    )
}

/// CPV reply on motor `motor`'s id 0x180 + n: `'a'`, the parameter name, int32 BE value.
pub fn encode_cpv_reply(motor: u8, param: [u8; 2], value: i32) -> CanFrame {
    let mut d = [0u8; 8];
    d[0] = b'a';
    d[1..3].copy_from_slice(&param);
    d[3..7].copy_from_slice(&value.to_be_bytes());
    frame(0x180 + u16::from(motor), &d)
}

/// Static identity fields of the 0x4AF reply (spec §7).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FirmwareInfo<'a> {
    /// Hardware version, e.g. `H-V1.2-1` (offset 0).
    pub hardware: &'a str,
    /// Motor ratio and batch, e.g. `10` (offset 16).
    pub motor_ratio: &'a str,
    /// Node type, e.g. `ARM_MC` (offset 32).
    pub node_type: &'a str,
    /// Software version, e.g. `S-V1.8-2` (offset 60).
    pub software: &'a str,
    /// Production date YYMMDD (offset 68).
    pub production_date: &'a str,
    /// Node number (offset 76).
    pub node_number: &'a str,
}

/// The 11 consecutive 0x4AF frames (88 bytes, ASCII at fixed offsets, zero-padded).
pub fn encode_firmware(info: &FirmwareInfo<'_>) -> Vec<CanFrame> {
    let mut buf = [0u8; 88];
    for (offset, max_len, text) in [
        (0usize, 8usize, info.hardware),
        (16, 8, info.motor_ratio),
        (32, 16, info.node_type),
        (60, 8, info.software),
        (68, 8, info.production_date),
        (76, 8, info.node_number),
    ] {
        let bytes = text.as_bytes();
        let n = bytes.len().min(max_len);
        buf[offset..offset + n].copy_from_slice(&bytes[..n]);
    }
    buf.chunks(8).map(|c| frame(ids::FIRMWARE, c)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn high_speed_feedback_saturates_speeds_beyond_the_field() {
        for (speed_rad_s, wire) in [(40.0, i16::MAX), (-40.0, i16::MIN), (1.5, 1500)] {
            let f = encode_high_speed(5, sat_i16((speed_rad_s * 1000.0_f64).round()), 0, 0);
            assert_eq!(i16::from_be_bytes([f.data()[0], f.data()[1]]), wire);
        }
    }

    #[test]
    fn low_speed_matches_real_capture() {
        // (AGX) _HEX_261_LOW_SPD: 01 E0 00 19 19 40 00 00.
        let f = encode_low_speed(0, 480, 25, 25, 0x40, 0);
        assert_eq!(f.raw_id(), 0x261);
        assert_eq!(f.data(), &[0x01, 0xE0, 0x00, 0x19, 0x19, 0x40, 0x00, 0x00]);
    }

    #[test]
    fn firmware_reply_layout() {
        let frames = encode_firmware(&FirmwareInfo {
            hardware: "H-V1.2-1",
            motor_ratio: "10",
            node_type: "ARM_MC",
            software: "S-V1.8-2",
            production_date: "250925",
            node_number: "15",
        });
        assert_eq!(frames.len(), 11);
        let all: Vec<u8> = frames.iter().flat_map(|f| f.data().to_vec()).collect();
        assert_eq!(&all[0..8], b"H-V1.2-1");
        assert_eq!(&all[60..68], b"S-V1.8-2");
        assert_eq!(&all[68..74], b"250925");
        assert_eq!(all[74], 0);
    }

    #[test]
    fn angles_round_and_saturate() {
        assert_eq!(rad_to_mdeg(std::f64::consts::FRAC_PI_2), 90_000);
        assert_eq!(rad_to_mdeg(-1.0), -57_296);
        assert_eq!(sat_i32(f64::NAN), 0);
        assert_eq!(sat_i16(1e9), i16::MAX);
    }
}
