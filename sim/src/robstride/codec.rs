//! The emulator's codec for the private 29-bit protocol (spec §2–§5).
//!
//! Wire integers stay in here: the rest of the emulator sees radians, N·m and °C.

use bus::CanFrame;

/// Communication types the emulator understands (bits 28..24 of the identifier).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CommType {
    /// 0: get device ID.
    GetId,
    /// 1: operation-control command.
    OpControl,
    /// 2: status frame (also an undocumented host poll).
    Status,
    /// 3: enable.
    Enable,
    /// 4: stop / clear fault / version read.
    Stop,
    /// 5: encoder calibration (undocumented).
    Calibrate,
    /// 6: set mechanical zero.
    SetZero,
    /// 7: set CAN ID.
    SetCanId,
    /// 17: read parameter.
    ReadParam,
    /// 18: write parameter.
    WriteParam,
    /// 21: fault feedback.
    Fault,
    /// 22: save parameters.
    Save,
    /// 23: baud rate (after power cycle).
    Baud,
    /// 24: active reporting on/off, and the active-report frame.
    ActiveReport,
    /// 25: protocol switch (after power cycle).
    Protocol,
    /// Any other type: ignored, as older firmware does.
    Unknown(u8),
}

impl CommType {
    /// Decode the 5-bit type field.
    pub fn from_bits(bits: u8) -> Self {
        match bits {
            0 => Self::GetId,
            1 => Self::OpControl,
            2 => Self::Status,
            3 => Self::Enable,
            4 => Self::Stop,
            5 => Self::Calibrate,
            6 => Self::SetZero,
            7 => Self::SetCanId,
            17 => Self::ReadParam,
            18 => Self::WriteParam,
            21 => Self::Fault,
            22 => Self::Save,
            23 => Self::Baud,
            24 => Self::ActiveReport,
            25 => Self::Protocol,
            other => Self::Unknown(other),
        }
    }

    /// The 5-bit type field.
    pub fn bits(self) -> u8 {
        match self {
            Self::GetId => 0,
            Self::OpControl => 1,
            Self::Status => 2,
            Self::Enable => 3,
            Self::Stop => 4,
            Self::Calibrate => 5,
            Self::SetZero => 6,
            Self::SetCanId => 7,
            Self::ReadParam => 17,
            Self::WriteParam => 18,
            Self::Fault => 21,
            Self::Save => 22,
            Self::Baud => 23,
            Self::ActiveReport => 24,
            Self::Protocol => 25,
            Self::Unknown(bits) => bits & 0x1F,
        }
    }
}

/// A decoded private-protocol identifier.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ExtId {
    /// Communication type.
    pub comm: CommType,
    /// Data area 2 (bits 23..8).
    pub data2: u16,
    /// Destination (bits 7..0).
    pub dst: u8,
}

impl ExtId {
    /// Split a 29-bit identifier into its fields.
    pub fn parse(raw: u32) -> Self {
        Self {
            comm: CommType::from_bits(((raw >> 24) & 0x1F) as u8),
            data2: ((raw >> 8) & 0xFFFF) as u16,
            dst: (raw & 0xFF) as u8,
        }
    }

    /// The 29-bit identifier.
    pub fn raw(self) -> u32 {
        (u32::from(self.comm.bits()) << 24) | (u32::from(self.data2) << 8) | u32::from(self.dst)
    }

    /// Bits 15..8 (host ID in requests, motor ID in replies).
    pub fn low_data2(self) -> u8 {
        (self.data2 & 0xFF) as u8
    }

    /// Bits 23..16 (new ID for type 7, status bits in replies).
    pub fn high_data2(self) -> u8 {
        (self.data2 >> 8) as u8
    }
}

/// Build an extended frame (`None` only if the identifier could not fit 29 bits, which the
/// field widths rule out; callers `extend` their reply list with it so no panic path exists).
pub fn frame(comm: CommType, data2: u16, dst: u8, data: [u8; 8]) -> Option<CanFrame> {
    let id = ExtId { comm, data2, dst }.raw();
    CanFrame::extended(id, &data).ok()
}

/// Float → u16 over [min, max] as the manual's reference code does (clamp, truncate).
pub fn float_to_u16(value: f32, min: f32, max: f32) -> u16 {
    let span = max - min;
    if !value.is_finite() || span <= 0.0 {
        return if value.is_nan() || span <= 0.0 {
            0
        } else if value > 0.0 {
            u16::MAX
        } else {
            0
        };
    }
    let clamped = value.clamp(min, max);
    ((clamped - min) * 65535.0 / span) as u16
}

/// u16 → float over [min, max].
pub fn u16_to_float(raw: u16, min: f32, max: f32) -> f32 {
    f32::from(raw) * (max - min) / 65535.0 + min
}

/// Big-endian u16 at `offset` of an 8-byte payload.
pub fn be_u16(data: &[u8; 8], offset: usize) -> u16 {
    u16::from_be_bytes([data[offset], data[offset + 1]])
}

/// A received payload as exactly 8 bytes (short frames padded with zeros).
pub fn payload8(frame: &CanFrame) -> [u8; 8] {
    let mut out = [0u8; 8];
    let data = frame.data();
    out[..data.len()].copy_from_slice(data);
    out
}

/// The magic prefix of types 22–25 (bytes 0..5 = 01 02 03 04 05 06).
pub fn has_magic_prefix(data: &[u8; 8]) -> bool {
    data[..6] == [1, 2, 3, 4, 5, 6]
}

/// Encode a status payload (type 2 / 24): angle, speed, torque (BE u16) and temp ×10.
pub fn status_payload(
    angle_rad: f32,
    speed_rad_s: f32,
    torque_nm: f32,
    temp_c: f32,
    ranges: &crate::robstride::model::Ranges,
) -> [u8; 8] {
    let angle = float_to_u16(angle_rad, -ranges.angle_rad, ranges.angle_rad);
    let speed = float_to_u16(speed_rad_s, -ranges.speed_rad_s, ranges.speed_rad_s);
    let torque = float_to_u16(torque_nm, -ranges.torque_nm, ranges.torque_nm);
    let temp = (temp_c * 10.0).round().clamp(0.0, 65535.0) as u16;
    let mut out = [0u8; 8];
    out[0..2].copy_from_slice(&angle.to_be_bytes());
    out[2..4].copy_from_slice(&speed.to_be_bytes());
    out[4..6].copy_from_slice(&torque.to_be_bytes());
    out[6..8].copy_from_slice(&temp.to_be_bytes());
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scaling_matches_the_manual_formula() {
        assert_eq!(float_to_u16(0.0, -60.0, 60.0), 32767);
        assert_eq!(float_to_u16(60.0, -60.0, 60.0), 65535);
        assert_eq!(float_to_u16(-99.0, -60.0, 60.0), 0);
        assert_eq!(float_to_u16(f32::NAN, -60.0, 60.0), 0);
        assert_eq!(float_to_u16(20.0, 0.0, 5000.0), 0x0106);
        assert!((u16_to_float(0x7FFF, -60.0, 60.0)).abs() < 0.002);
    }

    #[test]
    fn identifier_round_trips() {
        let id = ExtId::parse(0x0701_FD7F);
        assert_eq!(id.comm, CommType::SetCanId);
        assert_eq!(id.high_data2(), 0x01);
        assert_eq!(id.low_data2(), 0xFD);
        assert_eq!(id.dst, 0x7F);
        assert_eq!(id.raw(), 0x0701_FD7F);
        assert_eq!(ExtId::parse(0x1F00_0000).comm, CommType::Unknown(31));
    }
}
