//! MIT frame packing (0x15A–0x15F, spec §5.7): fixed-point fields with firmware-dependent
//! torque width.

use crate::piper::profile::MitPacking;

/// Range of the position setpoint, rad.
pub const P_RANGE_RAD: (f64, f64) = (-12.5, 12.5);
/// Range of the velocity setpoint, rad/s.
pub const V_RANGE_RAD_S: (f64, f64) = (-45.0, 45.0);
/// Range of the stiffness, N·m/rad.
pub const KP_RANGE: (f64, f64) = (0.0, 500.0);
/// Range of the damping, N·m·s/rad.
pub const KD_RANGE: (f64, f64) = (-5.0, 5.0);
/// Range of the 8-bit feed-forward torque, N·m.
pub const T8_RANGE_NM: (f64, f64) = (-8.0, 8.0);
/// Range of the 12-bit feed-forward torque, N·m.
pub const T12_RANGE_NM: (f64, f64) = (-16.0, 16.0);

/// One decoded MIT command, as the frame states it (before firmware sign/torque quirks).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MitCommand {
    /// Position setpoint, rad.
    pub p_des_rad: f64,
    /// Velocity setpoint, rad/s.
    pub v_des_rad_s: f64,
    /// Stiffness, N·m/rad.
    pub kp: f64,
    /// Damping, N·m·s/rad.
    pub kd: f64,
    /// Feed-forward torque, N·m.
    pub t_ff_nm: f64,
}

/// The quantised fields of an MIT frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MitRaw {
    /// 16-bit position.
    pub p: u16,
    /// 12-bit velocity.
    pub v: u16,
    /// 12-bit stiffness.
    pub kp: u16,
    /// 12-bit damping.
    pub kd: u16,
    /// 8- or 12-bit torque.
    pub t: u16,
}

/// The MIT frame failed its check nibble.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("MIT check nibble {got:#x} does not match {expected:#x}")]
pub struct MitCheckError {
    /// Nibble computed from bytes 0–6.
    pub expected: u8,
    /// Nibble found in byte 7.
    pub got: u8,
}

fn dequantise(u: u16, bits: u32, (min, max): (f64, f64)) -> f64 {
    f64::from(u) * (max - min) / f64::from((1u32 << bits) - 1) + min
}

/// Quantise like the SDKs do (truncation), clamping to the field's range first.
pub fn quantise(x: f64, bits: u32, (min, max): (f64, f64)) -> u16 {
    let top = f64::from((1u32 << bits) - 1);
    let scaled = ((x.clamp(min, max) - min) * top / (max - min)).trunc();
    // In range by the clamp above; u16 holds up to 16 bits.
    scaled.clamp(0.0, top) as u16
}

/// Split an MIT payload into its quantised fields; checks the nibble where the packing has one.
pub fn unpack(data: &[u8; 8], packing: MitPacking) -> Result<MitRaw, MitCheckError> {
    let p = u16::from_be_bytes([data[0], data[1]]);
    let v = (u16::from(data[2]) << 4) | u16::from(data[3] >> 4);
    let kp = (u16::from(data[3] & 0x0F) << 8) | u16::from(data[4]);
    let kd = (u16::from(data[5]) << 4) | u16::from(data[6] >> 4);
    let t = match packing {
        MitPacking::Torque8WithCheck => {
            let expected = data[..7].iter().fold(0u8, |acc, b| acc ^ b) & 0x0F;
            let got = data[7] & 0x0F;
            if expected != got {
                return Err(MitCheckError { expected, got });
            }
            (u16::from(data[6] & 0x0F) << 4) | u16::from(data[7] >> 4)
        }
        MitPacking::Torque12 => (u16::from(data[6] & 0x0F) << 8) | u16::from(data[7]),
    };
    Ok(MitRaw { p, v, kp, kd, t })
}

/// Pack quantised fields into a payload (adds the check nibble for the 8-bit packing).
pub fn pack(raw: MitRaw, packing: MitPacking) -> [u8; 8] {
    let mut d = [0u8; 8];
    d[0..2].copy_from_slice(&raw.p.to_be_bytes());
    d[2] = (raw.v >> 4) as u8;
    d[3] = (((raw.v & 0x0F) as u8) << 4) | ((raw.kp >> 8) as u8 & 0x0F);
    d[4] = (raw.kp & 0xFF) as u8;
    d[5] = (raw.kd >> 4) as u8;
    match packing {
        MitPacking::Torque8WithCheck => {
            d[6] = (((raw.kd & 0x0F) as u8) << 4) | ((raw.t >> 4) as u8 & 0x0F);
            let check = d[..7].iter().fold(0u8, |acc, b| acc ^ b) & 0x0F;
            d[7] = (((raw.t & 0x0F) as u8) << 4) | check;
        }
        MitPacking::Torque12 => {
            d[6] = (((raw.kd & 0x0F) as u8) << 4) | ((raw.t >> 8) as u8 & 0x0F);
            d[7] = (raw.t & 0xFF) as u8;
        }
    }
    d
}

impl MitRaw {
    /// Physical values of the quantised fields.
    pub fn to_command(self, packing: MitPacking) -> MitCommand {
        let (t_bits, t_range) = match packing {
            MitPacking::Torque8WithCheck => (8, T8_RANGE_NM),
            MitPacking::Torque12 => (12, T12_RANGE_NM),
        };
        MitCommand {
            p_des_rad: dequantise(self.p, 16, P_RANGE_RAD),
            v_des_rad_s: dequantise(self.v, 12, V_RANGE_RAD_S),
            kp: dequantise(self.kp, 12, KP_RANGE),
            kd: dequantise(self.kd, 12, KD_RANGE),
            t_ff_nm: dequantise(self.t, t_bits, t_range),
        }
    }

    /// Quantise physical values (clamped to each field's range).
    pub fn from_command(cmd: &MitCommand, packing: MitPacking) -> Self {
        let (t_bits, t_range) = match packing {
            MitPacking::Torque8WithCheck => (8, T8_RANGE_NM),
            MitPacking::Torque12 => (12, T12_RANGE_NM),
        };
        Self {
            p: quantise(cmd.p_des_rad, 16, P_RANGE_RAD),
            v: quantise(cmd.v_des_rad_s, 12, V_RANGE_RAD_S),
            kp: quantise(cmd.kp, 12, KP_RANGE),
            kd: quantise(cmd.kd, 12, KD_RANGE),
            t: quantise(cmd.t_ff_nm, t_bits, t_range),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spec_vector_packs_and_unpacks() {
        // Spec §5.7: pos=12345, vel=123, kp=100, kd=50, t=20 → 30 39 07 B0 64 03 21 48.
        let raw = MitRaw {
            p: 12345,
            v: 123,
            kp: 100,
            kd: 50,
            t: 20,
        };
        let bytes = pack(raw, MitPacking::Torque8WithCheck);
        assert_eq!(bytes, [0x30, 0x39, 0x07, 0xB0, 0x64, 0x03, 0x21, 0x48]);
        assert_eq!(unpack(&bytes, MitPacking::Torque8WithCheck), Ok(raw));
    }

    #[test]
    fn bad_check_nibble_is_rejected() {
        let bytes = [0x30, 0x39, 0x07, 0xB0, 0x64, 0x03, 0x21, 0x47];
        assert_eq!(
            unpack(&bytes, MitPacking::Torque8WithCheck),
            Err(MitCheckError {
                expected: 8,
                got: 7
            })
        );
    }

    #[test]
    fn spec_quantisation_examples() {
        assert_eq!(quantise(0.0, 16, P_RANGE_RAD), 32767);
        assert_eq!(quantise(0.0, 12, V_RANGE_RAD_S), 2047);
        assert_eq!(quantise(10.0, 12, KP_RANGE), 81);
        assert_eq!(quantise(0.8, 12, KD_RANGE), 2375);
        assert_eq!(quantise(0.0, 8, T8_RANGE_NM), 127);
        assert_eq!(quantise(0.0, 12, T12_RANGE_NM), 2047);
    }

    #[test]
    fn twelve_bit_torque_round_trips() {
        let raw = MitRaw {
            p: 40000,
            v: 2047,
            kp: 81,
            kd: 2375,
            t: 0xABC,
        };
        let bytes = pack(raw, MitPacking::Torque12);
        assert_eq!(bytes[6] & 0x0F, 0x0A);
        assert_eq!(bytes[7], 0xBC);
        assert_eq!(unpack(&bytes, MitPacking::Torque12), Ok(raw));
        let cmd = raw.to_command(MitPacking::Torque12);
        assert!((cmd.t_ff_nm - (f64::from(0xABCu16) * 32.0 / 4095.0 - 16.0)).abs() < 1e-12);
    }
}
