//! The emulator's own codec for the Damiao 11-bit protocol (protocol note §2–§6): MIT bit
//! packing, the feedback frame, the little-endian f32 command frames, the special commands
//! and the register frames on 0x7FF.
//!
//! Wire integers stay in here: the firmware sees radians, rad/s, N·m and °C. Nothing here
//! panics on any input: every parser takes a slice of any length and says `None` when the
//! frame is too short for its layout.

use bus::CanFrame;

use crate::damiao::model::{MitRanges, KD_MAX, KP_MAX};

/// The identifier every register request (read, write, save, refresh) is sent to.
pub const REGISTER_ID: u16 = 0x7FF;
/// Position-velocity commands go to this plus ESC_ID.
pub const POS_VEL_BASE: u16 = 0x100;
/// Velocity commands go to this plus ESC_ID.
pub const VELOCITY_BASE: u16 = 0x200;
/// Force-position commands go to this plus ESC_ID.
pub const POS_FORCE_BASE: u16 = 0x300;

/// `x` as an unsigned `bits`-bit integer over `[min, max]`, the note's §3.1 rule: clamp, then
/// `trunc((x − min)·(2^bits − 1)/(max − min))`. NaN, or an empty range, gives 0.
pub fn float_to_uint(x: f64, min: f64, max: f64, bits: u32) -> u16 {
    let top = f64::from((1u32 << bits.min(16)) - 1);
    if x.is_nan() || max <= min || !(max - min).is_finite() {
        return 0;
    }
    // The clamp keeps the product within 0..=top, so the truncating cast is exact.
    ((x.clamp(min, max) - min) * top / (max - min)) as u16
}

/// An unsigned `bits`-bit integer over `[min, max]` back to a float: `u·(max − min)/(2^bits −
/// 1) + min` (note §3.1).
pub fn uint_to_float(u: u16, min: f64, max: f64, bits: u32) -> f64 {
    let top = f64::from((1u32 << bits.min(16)) - 1);
    f64::from(u) * (max - min) / top + min
}

/// One MIT command (note §3.1): the setpoint of `τ = kp·(p_des − p) + kd·(v_des − v) + t_ff`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MitCommand {
    /// Position setpoint (rad).
    pub p_des_rad: f64,
    /// Velocity setpoint (rad/s).
    pub v_des_rad_s: f64,
    /// Stiffness (N·m/rad), 0..=500.
    pub kp_nm_per_rad: f64,
    /// Damping (N·m·s/rad), 0..=5.
    pub kd_nm_s_per_rad: f64,
    /// Feed-forward torque (N·m).
    pub t_ff_nm: f64,
}

impl MitCommand {
    /// Unpack an 8-byte MIT payload (big-endian bit packing) with the motor's ranges.
    pub fn unpack(d: &[u8; 8], ranges: &MitRanges) -> Self {
        let (p, v, t) = symmetric(ranges);
        let p_raw = u16::from_be_bytes([d[0], d[1]]);
        let v_raw = (u16::from(d[2]) << 4) | u16::from(d[3] >> 4);
        let kp_raw = (u16::from(d[3] & 0x0F) << 8) | u16::from(d[4]);
        let kd_raw = (u16::from(d[5]) << 4) | u16::from(d[6] >> 4);
        let t_raw = (u16::from(d[6] & 0x0F) << 8) | u16::from(d[7]);
        Self {
            p_des_rad: uint_to_float(p_raw, -p, p, 16),
            v_des_rad_s: uint_to_float(v_raw, -v, v, 12),
            kp_nm_per_rad: uint_to_float(kp_raw, 0.0, f64::from(KP_MAX), 12),
            kd_nm_s_per_rad: uint_to_float(kd_raw, 0.0, f64::from(KD_MAX), 12),
            t_ff_nm: uint_to_float(t_raw, -t, t, 12),
        }
    }

    /// Pack as a host would (for tests and tools; the firmware only unpacks).
    pub fn pack(&self, ranges: &MitRanges) -> [u8; 8] {
        let (p, v, t) = symmetric(ranges);
        let p_raw = float_to_uint(self.p_des_rad, -p, p, 16);
        let v_raw = float_to_uint(self.v_des_rad_s, -v, v, 12);
        let kp_raw = float_to_uint(self.kp_nm_per_rad, 0.0, f64::from(KP_MAX), 12);
        let kd_raw = float_to_uint(self.kd_nm_s_per_rad, 0.0, f64::from(KD_MAX), 12);
        let t_raw = float_to_uint(self.t_ff_nm, -t, t, 12);
        let [p_hi, p_lo] = p_raw.to_be_bytes();
        [
            p_hi,
            p_lo,
            (v_raw >> 4) as u8,
            (((v_raw & 0x0F) << 4) | (kp_raw >> 8)) as u8,
            (kp_raw & 0xFF) as u8,
            (kd_raw >> 4) as u8,
            (((kd_raw & 0x0F) << 4) | (t_raw >> 8)) as u8,
            (t_raw & 0xFF) as u8,
        ]
    }
}

/// The ranges as f64, each at least a tiny positive span (a zero PMAX would divide by zero;
/// the register write path refuses it, this is the last guard).
fn symmetric(ranges: &MitRanges) -> (f64, f64, f64) {
    let span = |x: f32| {
        let x = f64::from(x);
        if x.is_finite() && x > 0.0 {
            x
        } else {
            f64::MIN_POSITIVE
        }
    };
    (
        span(ranges.p_max_rad),
        span(ranges.v_max_rad_s),
        span(ranges.t_max_nm),
    )
}

/// The special commands on ESC_ID (note §4): `FF FF FF FF FF FF FF xx`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Special {
    /// `FC`: enable.
    Enable,
    /// `FD`: disable.
    Disable,
    /// `FE`: the present position becomes zero.
    SetZero,
    /// `FB`: clear latched errors.
    ClearError,
}

impl Special {
    /// Every special command.
    pub const ALL: [Special; 4] = [
        Special::Enable,
        Special::Disable,
        Special::SetZero,
        Special::ClearError,
    ];

    /// The marker byte (D7).
    pub fn marker(self) -> u8 {
        match self {
            Special::Enable => 0xFC,
            Special::Disable => 0xFD,
            Special::SetZero => 0xFE,
            Special::ClearError => 0xFB,
        }
    }

    /// The special command an 8-byte payload on ESC_ID is, if D0..D6 are all 0xFF and D7 a
    /// known marker; anything else on ESC_ID is an MIT setpoint.
    pub fn parse(data: &[u8]) -> Option<Special> {
        let (head, marker) = match data {
            [head @ .., marker] if data.len() == 8 => (head, *marker),
            _ => return None,
        };
        if head.iter().any(|&b| b != 0xFF) {
            return None;
        }
        Special::ALL.into_iter().find(|s| s.marker() == marker)
    }

    /// The payload a host sends.
    pub fn payload(self) -> [u8; 8] {
        let mut data = [0xFF; 8];
        data[7] = self.marker();
        data
    }
}

/// The feedback frame (note §5), as the firmware sends it on MST_ID.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Feedback {
    /// The state/error nibble (`D0[7:4]`): 0 disabled, 1 enabled, 8..=0xE an error.
    pub state: u8,
    /// The low nibble of ESC_ID (`D0[3:0]`).
    pub id_nibble: u8,
    /// Position (rad), over ±PMAX.
    pub position_rad: f64,
    /// Velocity (rad/s), over ±VMAX.
    pub velocity_rad_s: f64,
    /// Torque (N·m), over ±TMAX.
    pub torque_nm: f64,
    /// MOS (driver board) temperature (°C, D6).
    pub mos_temp_c: u8,
    /// Rotor (coil) temperature (°C, D7).
    pub rotor_temp_c: u8,
}

impl Feedback {
    /// The 8 payload bytes, packed over the motor's ranges (values beyond a range saturate).
    pub fn pack(&self, ranges: &MitRanges) -> [u8; 8] {
        let (p, v, t) = symmetric(ranges);
        let pos = float_to_uint(self.position_rad, -p, p, 16);
        let vel = float_to_uint(self.velocity_rad_s, -v, v, 12);
        let tor = float_to_uint(self.torque_nm, -t, t, 12);
        let [p_hi, p_lo] = pos.to_be_bytes();
        [
            ((self.state & 0x0F) << 4) | (self.id_nibble & 0x0F),
            p_hi,
            p_lo,
            (vel >> 4) as u8,
            (((vel & 0x0F) << 4) | (tor >> 8)) as u8,
            (tor & 0xFF) as u8,
            self.mos_temp_c,
            self.rotor_temp_c,
        ]
    }

    /// Decode a feedback payload as a host would (tests, tools).
    pub fn unpack(d: &[u8; 8], ranges: &MitRanges) -> Self {
        let (p, v, t) = symmetric(ranges);
        let pos = u16::from_be_bytes([d[1], d[2]]);
        let vel = (u16::from(d[3]) << 4) | u16::from(d[4] >> 4);
        let tor = (u16::from(d[4] & 0x0F) << 8) | u16::from(d[5]);
        Self {
            state: d[0] >> 4,
            id_nibble: d[0] & 0x0F,
            position_rad: uint_to_float(pos, -p, p, 16),
            velocity_rad_s: uint_to_float(vel, -v, v, 12),
            torque_nm: uint_to_float(tor, -t, t, 12),
            mos_temp_c: d[6],
            rotor_temp_c: d[7],
        }
    }
}

/// A temperature as the feedback's byte: whole °C, saturating at 0 and 255.
pub fn temperature_byte(celsius: f64) -> u8 {
    if celsius.is_nan() {
        return 0;
    }
    // Clamped into 0..=255 first: the cast is exact.
    celsius.round().clamp(0.0, 255.0) as u8
}

/// The little-endian f32 at `offset`, if the payload reaches that far.
pub fn f32_le(data: &[u8], offset: usize) -> Option<f32> {
    let bytes = data.get(offset..offset.checked_add(4)?)?;
    Some(f32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]))
}

/// The little-endian u16 at `offset`, if the payload reaches that far.
fn u16_le(data: &[u8], offset: usize) -> Option<u16> {
    let bytes = data.get(offset..offset.checked_add(2)?)?;
    Some(u16::from_le_bytes([bytes[0], bytes[1]]))
}

/// A position-velocity command (note §3.2, 0x100 + ESC_ID, DLC 8).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PosVelCommand {
    /// Target position (rad).
    pub p_des_rad: f32,
    /// Speed limit on the way (rad/s; its magnitude is used).
    pub v_des_rad_s: f32,
}

impl PosVelCommand {
    /// Decode; `None` if shorter than 8 bytes.
    pub fn parse(data: &[u8]) -> Option<Self> {
        Some(Self {
            p_des_rad: f32_le(data, 0)?,
            v_des_rad_s: f32_le(data, 4)?,
        })
    }

    /// The payload a host sends.
    pub fn payload(&self) -> [u8; 8] {
        let mut data = [0u8; 8];
        data[..4].copy_from_slice(&self.p_des_rad.to_le_bytes());
        data[4..].copy_from_slice(&self.v_des_rad_s.to_le_bytes());
        data
    }
}

/// A velocity command (note §3.3, 0x200 + ESC_ID): `v_des` in D0..D3; DLC 4 (openarm_can) or 8
/// (damiao-motor, zero padded) alike.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VelocityCommand {
    /// Target velocity (rad/s).
    pub v_des_rad_s: f32,
}

impl VelocityCommand {
    /// Decode; `None` if shorter than 4 bytes.
    pub fn parse(data: &[u8]) -> Option<Self> {
        Some(Self {
            v_des_rad_s: f32_le(data, 0)?,
        })
    }
}

/// Largest raw speed and current of a force-position command (note §3.4: 0…10000).
pub const POS_FORCE_RAW_MAX: u16 = 10_000;

/// A force-position command (note §3.4, 0x300 + ESC_ID, DLC 8).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PosForceCommand {
    /// Target position (rad).
    pub p_des_rad: f32,
    /// Speed limit (rad/s): the wire's u16 / 100, raw values past 10000 taken as 10000.
    pub v_des_rad_s: f64,
    /// Current limit as a fraction of the board's Imax (0..=1): the wire's u16 / 10000, raw
    /// values past 10000 taken as 10000.
    pub current_fraction: f64,
}

impl PosForceCommand {
    /// Decode; `None` if shorter than 8 bytes.
    pub fn parse(data: &[u8]) -> Option<Self> {
        let v_raw = u16_le(data, 4)?.min(POS_FORCE_RAW_MAX);
        let i_raw = u16_le(data, 6)?.min(POS_FORCE_RAW_MAX);
        Some(Self {
            p_des_rad: f32_le(data, 0)?,
            v_des_rad_s: f64::from(v_raw) / 100.0,
            current_fraction: f64::from(i_raw) / f64::from(POS_FORCE_RAW_MAX),
        })
    }

    /// The payload a host sends (values rounded to the wire's steps, saturating).
    pub fn payload(&self) -> [u8; 8] {
        let raw = |x: f64, scale: f64| {
            // Clamped into 0..=10000 first: the cast is exact.
            (x * scale).round().clamp(0.0, f64::from(POS_FORCE_RAW_MAX)) as u16
        };
        let mut data = [0u8; 8];
        data[..4].copy_from_slice(&self.p_des_rad.to_le_bytes());
        data[4..6].copy_from_slice(&raw(self.v_des_rad_s, 100.0).to_le_bytes());
        data[6..].copy_from_slice(&raw(self.current_fraction, 10_000.0).to_le_bytes());
        data
    }
}

/// The command byte (D2) of a register frame (note §6.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RegisterCmd {
    /// 0x33: read a register.
    Read,
    /// 0x55: write a register.
    Write,
    /// 0xAA: save every register to flash.
    Save,
    /// 0xCC: refresh (answered with a feedback frame).
    Refresh,
}

impl RegisterCmd {
    /// The command byte.
    pub fn byte(self) -> u8 {
        match self {
            RegisterCmd::Read => 0x33,
            RegisterCmd::Write => 0x55,
            RegisterCmd::Save => 0xAA,
            RegisterCmd::Refresh => 0xCC,
        }
    }

    /// The command a byte names, if any.
    pub fn from_byte(byte: u8) -> Option<Self> {
        [
            RegisterCmd::Read,
            RegisterCmd::Write,
            RegisterCmd::Save,
            RegisterCmd::Refresh,
        ]
        .into_iter()
        .find(|c| c.byte() == byte)
    }
}

/// A register request on 0x7FF: `ESC_ID lo, ESC_ID hi, cmd, RID, value (4 bytes)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RegisterRequest {
    /// The motor addressed (D0..D1, little-endian).
    pub esc_id: u16,
    /// What to do.
    pub cmd: RegisterCmd,
    /// The register (D3); `None` when the frame stops before it (save and refresh need none).
    pub rid: Option<u8>,
    /// D4..D7, if the frame carries them.
    pub value: Option<[u8; 4]>,
}

impl RegisterRequest {
    /// Decode a 0x7FF payload; `None` if it is shorter than the three bytes every request
    /// needs (the motor and the command) or the command byte is unknown.
    pub fn parse(data: &[u8]) -> Option<Self> {
        let esc_id = u16_le(data, 0)?;
        let cmd = RegisterCmd::from_byte(*data.get(2)?)?;
        let value = data.get(4..8).map(|v| [v[0], v[1], v[2], v[3]]);
        Some(Self {
            esc_id,
            cmd,
            rid: data.get(3).copied(),
            value,
        })
    }

    /// The 8-byte payload a host sends (`rid` 0 and a zero value where absent).
    pub fn payload(&self) -> [u8; 8] {
        register_payload(
            self.esc_id,
            self.cmd.byte(),
            self.rid.unwrap_or(0),
            self.value.unwrap_or([0; 4]),
        )
    }
}

/// A register frame's payload: `ESC_ID lo, hi, cmd, RID, value` (requests and the replies to
/// 0x33 and 0x55 share it).
pub fn register_payload(esc_id: u16, cmd: u8, rid: u8, value: [u8; 4]) -> [u8; 8] {
    let [lo, hi] = esc_id.to_le_bytes();
    [lo, hi, cmd, rid, value[0], value[1], value[2], value[3]]
}

/// A classic standard frame, or `None` for an identifier past 0x7FF (a register the host
/// wrote with a value the table refused could never get here; this is the last guard).
pub fn standard_frame(id: u16, data: &[u8]) -> Option<CanFrame> {
    CanFrame::standard(id, data).ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::damiao::model::Model;

    #[test]
    fn zero_encodes_below_the_midpoint_and_the_ends_are_exact() {
        // The note: 0 rad over ±12.5 encodes to 32767, not 32768.
        assert_eq!(float_to_uint(0.0, -12.5, 12.5, 16), 32767);
        assert_eq!(float_to_uint(12.5, -12.5, 12.5, 16), 65535);
        assert_eq!(float_to_uint(99.0, -12.5, 12.5, 16), 65535);
        assert_eq!(float_to_uint(-99.0, -12.5, 12.5, 16), 0);
        assert_eq!(float_to_uint(f64::NAN, -1.0, 1.0, 12), 0);
        assert_eq!(float_to_uint(1.0, 1.0, 1.0, 12), 0);
        assert!((uint_to_float(4095, -30.0, 30.0, 12) - 30.0).abs() < 1e-12);
        assert!((uint_to_float(0, 0.0, 500.0, 12)).abs() < 1e-12);
    }

    #[test]
    fn mit_pack_and_unpack_agree_within_one_step() {
        let ranges = Model::DM4310.ranges();
        let command = MitCommand {
            p_des_rad: 1.234,
            v_des_rad_s: -3.5,
            kp_nm_per_rad: 42.0,
            kd_nm_s_per_rad: 1.3,
            t_ff_nm: -2.25,
        };
        let back = MitCommand::unpack(&command.pack(&ranges), &ranges);
        assert!((back.p_des_rad - command.p_des_rad).abs() <= 25.0 / 65535.0);
        assert!((back.v_des_rad_s - command.v_des_rad_s).abs() <= 60.0 / 4095.0);
        assert!((back.kp_nm_per_rad - command.kp_nm_per_rad).abs() <= 500.0 / 4095.0);
        assert!((back.kd_nm_s_per_rad - command.kd_nm_s_per_rad).abs() <= 5.0 / 4095.0);
        assert!((back.t_ff_nm - command.t_ff_nm).abs() <= 20.0 / 4095.0);
    }

    #[test]
    fn feedback_puts_state_and_id_in_the_first_byte() {
        let ranges = Model::DM8009.ranges();
        let fb = Feedback {
            state: 0xD,
            id_nibble: 0x2,
            position_rad: -0.5,
            velocity_rad_s: 3.0,
            torque_nm: 10.0,
            mos_temp_c: 41,
            rotor_temp_c: 55,
        };
        let data = fb.pack(&ranges);
        assert_eq!(data[0], 0xD2);
        assert_eq!((data[6], data[7]), (41, 55));
        let back = Feedback::unpack(&data, &ranges);
        assert_eq!((back.state, back.id_nibble), (0xD, 0x2));
        assert!((back.torque_nm - 10.0).abs() <= 108.0 / 4095.0);
        assert!((back.position_rad + 0.5).abs() <= 25.0 / 65535.0);
    }

    #[test]
    fn specials_need_seven_ff_bytes_and_a_known_marker() {
        for special in Special::ALL {
            assert_eq!(Special::parse(&special.payload()), Some(special));
        }
        assert_eq!(Special::parse(&[0xFF; 8]), None);
        assert_eq!(
            Special::parse(&[0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFE, 0xFC]),
            None
        );
        assert_eq!(Special::parse(&[0xFF, 0xFC]), None);
        assert_eq!(Special::parse(&[]), None);
    }

    #[test]
    fn short_payloads_parse_to_none() {
        assert_eq!(PosVelCommand::parse(&[0; 7]), None);
        assert_eq!(VelocityCommand::parse(&[0; 3]), None);
        assert!(VelocityCommand::parse(&1.5f32.to_le_bytes()).is_some());
        assert_eq!(PosForceCommand::parse(&[0; 6]), None);
        assert_eq!(RegisterRequest::parse(&[1, 0]), None);
        assert_eq!(
            RegisterRequest::parse(&[1, 0, 0x12, 7]),
            None,
            "unknown cmd"
        );
        let read = RegisterRequest::parse(&[1, 0, 0x33, 10]).unwrap();
        assert_eq!((read.rid, read.value), (Some(10), None));
        assert_eq!(f32_le(&[0; 4], usize::MAX), None);
    }

    #[test]
    fn force_position_scales_and_saturates() {
        let mut data = [0u8; 8];
        data[..4].copy_from_slice(&0.5f32.to_le_bytes());
        data[4..6].copy_from_slice(&5000u16.to_le_bytes());
        data[6..].copy_from_slice(&60000u16.to_le_bytes());
        let command = PosForceCommand::parse(&data).unwrap();
        assert_eq!(command.v_des_rad_s, 50.0);
        assert_eq!(command.current_fraction, 1.0);
        assert_eq!(PosForceCommand::parse(&command.payload()), Some(command));
    }
}
