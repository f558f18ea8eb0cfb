//! MIT per-joint command frames 0x15A–0x15F and their two firmware packings.

use bus::CanFrame;

use super::{block_offset, frame, ids, payload, DecodeError};

/// How the MIT frame packs its torque (firmware dependent, spec §5.7).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum MitPacking {
    /// Firmware up to S-V1.8-7: 8-bit torque in ±8 N·m plus an XOR check nibble.
    Torque8Crc,
    /// Firmware S-V1.8-8 and later: 12-bit torque in ±16 N·m, no check nibble.
    Torque12,
}

impl MitPacking {
    /// Torque range (N·m) of this packing.
    pub fn torque_range_nm(self) -> (f64, f64) {
        match self {
            Self::Torque8Crc => (-8.0, 8.0),
            Self::Torque12 => (-16.0, 16.0),
        }
    }

    fn torque_bits(self) -> u32 {
        match self {
            Self::Torque8Crc => 8,
            Self::Torque12 => 12,
        }
    }
}

/// Position range of p_des, rad.
pub const MIT_P_RANGE_RAD: (f64, f64) = (-12.5, 12.5);
/// Velocity range of v_des, rad/s.
pub const MIT_V_RANGE_RAD_S: (f64, f64) = (-45.0, 45.0);
/// Range of kp.
pub const MIT_KP_RANGE: (f64, f64) = (0.0, 500.0);
/// Range of kd.
pub const MIT_KD_RANGE: (f64, f64) = (-5.0, 5.0);

/// An MIT command in SI units.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct MitCommand {
    /// Desired position, rad.
    pub p_rad: f64,
    /// Desired velocity, rad/s.
    pub v_rad_s: f64,
    /// Position gain.
    pub kp: f64,
    /// Velocity gain.
    pub kd: f64,
    /// Feed-forward torque, N·m.
    pub t_nm: f64,
}

/// The quantised fields of an MIT frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct MitRaw {
    /// p_des, 16 bit.
    pub p: u16,
    /// v_des, 12 bit.
    pub v: u16,
    /// kp, 12 bit.
    pub kp: u16,
    /// kd, 12 bit.
    pub kd: u16,
    /// t_ff, 8 or 12 bit.
    pub t: u16,
}

/// Quantise by truncation as every implementation does, saturating at the range ends.
fn quantise(x: f64, (lo, hi): (f64, f64), bits: u32) -> u16 {
    let max = f64::from((1u32 << bits) - 1);
    let scaled = (x - lo) * max / (hi - lo);
    // `as` saturates (NaN → 0); the clamp keeps values at the top of the field.
    scaled.clamp(0.0, max) as u16
}

fn dequantise(u: u16, (lo, hi): (f64, f64), bits: u32) -> f64 {
    let max = f64::from((1u32 << bits) - 1);
    f64::from(u) * (hi - lo) / max + lo
}

impl MitCommand {
    /// Quantise for `packing`.
    pub fn quantise(&self, packing: MitPacking) -> MitRaw {
        MitRaw {
            p: quantise(self.p_rad, MIT_P_RANGE_RAD, 16),
            v: quantise(self.v_rad_s, MIT_V_RANGE_RAD_S, 12),
            kp: quantise(self.kp, MIT_KP_RANGE, 12),
            kd: quantise(self.kd, MIT_KD_RANGE, 12),
            t: quantise(self.t_nm, packing.torque_range_nm(), packing.torque_bits()),
        }
    }
}

/// XOR of bytes 0–6, low nibble.
pub fn mit_check_nibble(bytes: &[u8]) -> u8 {
    bytes.iter().take(7).fold(0u8, |acc, b| acc ^ b) & 0x0F
}

impl MitRaw {
    /// Back to SI units.
    pub fn to_si(&self, packing: MitPacking) -> MitCommand {
        MitCommand {
            p_rad: dequantise(self.p, MIT_P_RANGE_RAD, 16),
            v_rad_s: dequantise(self.v, MIT_V_RANGE_RAD_S, 12),
            kp: dequantise(self.kp, MIT_KP_RANGE, 12),
            kd: dequantise(self.kd, MIT_KD_RANGE, 12),
            t_nm: dequantise(self.t, packing.torque_range_nm(), packing.torque_bits()),
        }
    }

    /// Encode for joint 1–6 on 0x159 + joint. Fields wider than their bit count are masked.
    pub fn encode(&self, joint: u8, packing: MitPacking) -> CanFrame {
        let (p, v, kp, kd) = (self.p, self.v & 0xFFF, self.kp & 0xFFF, self.kd & 0xFFF);
        let mut d = [0u8; 8];
        d[0] = (p >> 8) as u8;
        d[1] = (p & 0xFF) as u8;
        d[2] = (v >> 4) as u8;
        d[3] = (((v & 0xF) << 4) | (kp >> 8)) as u8;
        d[4] = (kp & 0xFF) as u8;
        d[5] = (kd >> 4) as u8;
        match packing {
            MitPacking::Torque8Crc => {
                let t = self.t & 0xFF;
                d[6] = (((kd & 0xF) << 4) | (t >> 4)) as u8;
                d[7] = (((t & 0xF) << 4) as u8) | mit_check_nibble(&d);
            }
            MitPacking::Torque12 => {
                let t = self.t & 0xFFF;
                d[6] = (((kd & 0xF) << 4) | (t >> 8)) as u8;
                d[7] = (t & 0xFF) as u8;
            }
        }
        frame(0x159 + u16::from(joint), &d)
    }

    /// Decode a 0x15A–0x15F frame with the given packing (checks the nibble of
    /// [`MitPacking::Torque8Crc`]). Any other id is refused: an extended frame with
    /// [`DecodeError::Extended`], another 11-bit id with [`DecodeError::OutOfRange`] on the
    /// joint it would stand for.
    pub fn decode(frame: &CanFrame, packing: MitPacking) -> Result<(u8, Self), DecodeError> {
        let (id, offset) = block_offset(frame, ids::MIT_J1, ids::MIT_J6, "joint")?;
        let d = payload(id, frame, 8)?;
        let w = |b: u8| u16::from(b);
        let p = (w(d[0]) << 8) | w(d[1]);
        let v = (w(d[2]) << 4) | (w(d[3]) >> 4);
        let kp = ((w(d[3]) & 0xF) << 8) | w(d[4]);
        let kd = (w(d[5]) << 4) | (w(d[6]) >> 4);
        let t = match packing {
            MitPacking::Torque8Crc => {
                let expected = mit_check_nibble(d);
                let got = d[7] & 0x0F;
                if expected != got {
                    return Err(DecodeError::BadCrc { id, expected, got });
                }
                ((w(d[6]) & 0xF) << 4) | (w(d[7]) >> 4)
            }
            MitPacking::Torque12 => ((w(d[6]) & 0xF) << 8) | w(d[7]),
        };
        Ok((offset + 1, Self { p, v, kp, kd, t }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decode_refuses_frames_that_are_not_mit_commands() {
        let raw = MitRaw {
            p: 0x8000,
            v: 0x7FF,
            kp: 0x100,
            kd: 0x80,
            t: 0x7F,
        };
        for packing in [MitPacking::Torque8Crc, MitPacking::Torque12] {
            let good = raw.encode(3, packing);
            assert_eq!(MitRaw::decode(&good, packing), Ok((3, raw)));
            // Same payload on a neighbouring id or as an extended frame: not an MIT command.
            for id in [0x150, 0x159, 0x160, 0x2A5] {
                let other = CanFrame::standard(id, good.data()).unwrap();
                assert!(
                    matches!(
                        MitRaw::decode(&other, packing),
                        Err(DecodeError::OutOfRange { field: "joint", .. })
                    ),
                    "{other}"
                );
            }
            let extended = CanFrame::extended(0x15C, good.data()).unwrap();
            assert_eq!(
                MitRaw::decode(&extended, packing),
                Err(DecodeError::Extended { id: 0x15C })
            );
        }
    }
}
