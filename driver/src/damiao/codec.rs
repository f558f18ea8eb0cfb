//! The driver's own codec for Damiao joint motors (docs/protocols/damiao.md §2–§6): 11-bit
//! identifiers, the MIT command's bit packing, the f32 mode commands, the register frames on
//! 0x7FF and the feedback frame. Written independently of the emulator's; both are checked
//! against `fixtures/damiao/`.
//!
//! Every function takes any input without panicking: values are clamped (NaN encodes as the
//! bottom of its range), identifiers that do not fit 11 bits are a [`bus::FrameError`], and
//! frames that are not what they claim decode to `None`.

use std::fmt;

use bus::CanFrame;

use crate::damiao::model::Ranges;
use crate::damiao::register::RegisterValue;

/// Identifiers of the command frames (the MIT command and the special commands use ESC_ID
/// itself).
pub mod id {
    /// Position-velocity command: `POS_VEL + ESC_ID`.
    pub const POS_VEL: u16 = 0x100;
    /// Velocity command: `VELOCITY + ESC_ID`.
    pub const VELOCITY: u16 = 0x200;
    /// Force-position command: `FORCE_POS + ESC_ID`.
    pub const FORCE_POS: u16 = 0x300;
    /// Register read/write/save and refresh requests, for every motor.
    pub const REGISTER: u16 = 0x7FF;
}

/// The last byte of the special commands (`FF FF FF FF FF FF FF code`).
pub mod special {
    /// Enable.
    pub const ENABLE: u8 = 0xFC;
    /// Disable.
    pub const DISABLE: u8 = 0xFD;
    /// Take the present position as zero.
    pub const SET_ZERO: u8 = 0xFE;
    /// Clear a latched error.
    pub const CLEAR_ERROR: u8 = 0xFB;
}

/// The operation byte (D2) of the frames on [`id::REGISTER`] and of register replies.
pub mod op {
    /// Read a register; answered with the value.
    pub const READ: u8 = 0x33;
    /// Write a register; answered with an echo of the value stored.
    pub const WRITE: u8 = 0x55;
    /// Save every register to flash; not answered.
    pub const SAVE: u8 = 0xAA;
    /// Ask for a feedback frame.
    pub const REFRESH: u8 = 0xCC;
}

/// Top of the MIT kp range (kp maps over 0..=500 for every model).
pub const KP_MAX: f32 = 500.0;
/// Top of the MIT kd range (kd maps over 0..=5 for every model).
pub const KD_MAX: f32 = 5.0;
/// Top of the force-position speed limit (rad/s): the wire carries rad/s × 100 up to 10000.
pub const FORCE_POS_SPEED_MAX: f32 = 100.0;
/// Top of the force-position current limit (per unit of the board's maximum current): the
/// wire carries it × 10000 up to 10000.
pub const FORCE_POS_CURRENT_MAX: f32 = 1.0;

/// The motor's control modes (register CTRL_MODE).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ControlMode {
    /// 1: MIT commands on ESC_ID.
    Mit,
    /// 2: position-velocity commands on 0x100 + ESC_ID.
    PosVel,
    /// 3: velocity commands on 0x200 + ESC_ID.
    Velocity,
    /// 4: force-position commands on 0x300 + ESC_ID.
    ForcePos,
}

impl ControlMode {
    /// The CTRL_MODE value.
    pub fn code(self) -> u32 {
        match self {
            Self::Mit => 1,
            Self::PosVel => 2,
            Self::Velocity => 3,
            Self::ForcePos => 4,
        }
    }

    /// The mode of a CTRL_MODE value, if it names one.
    pub fn from_code(code: u32) -> Option<Self> {
        match code {
            1 => Some(Self::Mit),
            2 => Some(Self::PosVel),
            3 => Some(Self::Velocity),
            4 => Some(Self::ForcePos),
            _ => None,
        }
    }
}

impl fmt::Display for ControlMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Mit => "MIT",
            Self::PosVel => "position-velocity",
            Self::Velocity => "velocity",
            Self::ForcePos => "force-position",
        })
    }
}

/// The state nibble of a feedback frame (D0 bits 7..4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MotorState {
    /// 0x0: disabled.
    Disabled,
    /// 0x1: enabled.
    Enabled,
    /// 0x8: over-voltage.
    OverVoltage,
    /// 0x9: under-voltage.
    UnderVoltage,
    /// 0xA: over-current.
    OverCurrent,
    /// 0xB: MOS (driver stage) over-temperature.
    MosOverTemperature,
    /// 0xC: rotor (coil) over-temperature.
    RotorOverTemperature,
    /// 0xD: communication lost (the CAN timeout expired).
    CommunicationLost,
    /// 0xE: overload.
    Overload,
    /// Any other nibble (undocumented); treated as an error.
    Unknown(u8),
}

impl MotorState {
    /// The state of a nibble (only the low four bits of `code` count).
    pub fn from_code(code: u8) -> Self {
        match code & 0x0F {
            0x0 => Self::Disabled,
            0x1 => Self::Enabled,
            0x8 => Self::OverVoltage,
            0x9 => Self::UnderVoltage,
            0xA => Self::OverCurrent,
            0xB => Self::MosOverTemperature,
            0xC => Self::RotorOverTemperature,
            0xD => Self::CommunicationLost,
            0xE => Self::Overload,
            other => Self::Unknown(other),
        }
    }

    /// The nibble.
    pub fn code(self) -> u8 {
        match self {
            Self::Disabled => 0x0,
            Self::Enabled => 0x1,
            Self::OverVoltage => 0x8,
            Self::UnderVoltage => 0x9,
            Self::OverCurrent => 0xA,
            Self::MosOverTemperature => 0xB,
            Self::RotorOverTemperature => 0xC,
            Self::CommunicationLost => 0xD,
            Self::Overload => 0xE,
            Self::Unknown(code) => code & 0x0F,
        }
    }

    /// True for every state but disabled and enabled: a latched error (cleared with
    /// [`special::CLEAR_ERROR`]) or an undocumented nibble.
    pub fn is_error(self) -> bool {
        !matches!(self, Self::Disabled | Self::Enabled)
    }

    /// The state's name (`over_voltage`), as the fixtures write it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Disabled => "disabled",
            Self::Enabled => "enabled",
            Self::OverVoltage => "over_voltage",
            Self::UnderVoltage => "under_voltage",
            Self::OverCurrent => "over_current",
            Self::MosOverTemperature => "mos_over_temperature",
            Self::RotorOverTemperature => "rotor_over_temperature",
            Self::CommunicationLost => "communication_lost",
            Self::Overload => "overload",
            Self::Unknown(_) => "unknown",
        }
    }
}

impl fmt::Display for MotorState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} (state {:#x})", self.name(), self.code())
    }
}

/// An MIT command's five values.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MitCommand {
    /// Position target (rad), over ±PMAX.
    pub p_des_rad: f32,
    /// Velocity target (rad/s), over ±VMAX.
    pub v_des_rad_s: f32,
    /// Position gain, over 0..=500.
    pub kp: f32,
    /// Velocity gain, over 0..=5.
    pub kd: f32,
    /// Torque feed-forward (N·m), over ±TMAX.
    pub t_ff_nm: f32,
}

/// A force-position command's values.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ForcePosCommand {
    /// Position target (rad).
    pub p_des_rad: f32,
    /// Speed limit (rad/s), 0..=100 in 0.01 rad/s steps.
    pub v_limit_rad_s: f32,
    /// Current limit, per unit of the board's maximum current, 0..=1 in 1e-4 steps.
    pub i_limit: f32,
}

/// How many bytes the velocity command carries: the firmware takes both.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum VelocityLen {
    /// DLC 4: the f32 alone.
    Four,
    /// DLC 8: the f32 and four zero bytes (the driver's default).
    #[default]
    Eight,
}

/// A feedback frame, decoded.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Feedback {
    /// The low nibble of the motor's ESC_ID (D0 bits 3..0).
    pub motor: u8,
    /// The state nibble (D0 bits 7..4).
    pub state: MotorState,
    /// Position (rad), 16 bits over ±PMAX.
    pub position_rad: f32,
    /// Velocity (rad/s), 12 bits over ±VMAX.
    pub velocity_rad_s: f32,
    /// Torque (N·m), 12 bits over ±TMAX.
    pub torque_nm: f32,
    /// MOS (driver stage) temperature (°C).
    pub mos_temp_c: u8,
    /// Rotor (coil) temperature (°C).
    pub rotor_temp_c: u8,
}

/// A register reply (on MST_ID), decoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RegisterReply {
    /// The ESC_ID echoed in D0..D1.
    pub esc_id: u16,
    /// [`op::READ`] or [`op::WRITE`].
    pub op: u8,
    /// The register's ID.
    pub rid: u8,
    /// The value bytes D4..D7 (read them with [`RegisterValue::from_bytes`]).
    pub value: [u8; 4],
}

/// A frame on a motor's MST_ID, decoded.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Reply {
    /// A feedback frame.
    Feedback(Feedback),
    /// A register reply.
    Register(RegisterReply),
}

/// `2^bits - 1` as a real (`bits` at most 16).
fn top(bits: u32) -> f64 {
    f64::from((1u32 << bits.min(16)) - 1)
}

/// Real → unsigned `bits`-bit integer over [min, max]: clamp, then
/// `trunc((x - min)·(2^bits - 1)/(max - min))`. NaN, and any empty or non-finite range, give 0.
pub fn to_uint(value: f32, min: f32, max: f32, bits: u32) -> u16 {
    let (lo, hi) = (f64::from(min), f64::from(max));
    if value.is_nan() || !lo.is_finite() || !hi.is_finite() || hi <= lo {
        return 0;
    }
    let x = f64::from(value);
    let clamped = if x < lo {
        lo
    } else if x > hi {
        hi
    } else {
        x
    };
    // The float-to-int cast truncates and saturates: the result fits `bits` after the clamp.
    ((clamped - lo) * top(bits) / (hi - lo)) as u16
}

/// Unsigned `bits`-bit integer → real over [min, max]: `u·(max - min)/(2^bits - 1) + min`.
pub fn from_uint(raw: u16, min: f32, max: f32, bits: u32) -> f32 {
    let (lo, hi) = (f64::from(min), f64::from(max));
    (f64::from(raw) * (hi - lo) / top(bits) + lo) as f32
}

/// `base + esc_id` as a standard identifier (an error past 0x7FF).
fn command_id(base: u16, esc_id: u16) -> Result<bus::CanId, bus::FrameError> {
    bus::CanId::standard(base.saturating_add(esc_id))
}

/// A special command: `FF FF FF FF FF FF FF code` on ESC_ID (codes in [`mod@special`]).
pub fn special(esc_id: u16, code: u8) -> Result<CanFrame, bus::FrameError> {
    let mut data = [0xFF; 8];
    data[7] = code;
    CanFrame::new(command_id(0, esc_id)?, &data)
}

/// The MIT command on ESC_ID: p 16 bits, then v, kp, kd and t_ff 12 bits each, big-endian bit
/// packing, each value clamped to its range and truncated.
pub fn mit(esc_id: u16, cmd: &MitCommand, r: &Ranges) -> Result<CanFrame, bus::FrameError> {
    let p = to_uint(cmd.p_des_rad, -r.pmax, r.pmax, 16);
    let v = to_uint(cmd.v_des_rad_s, -r.vmax, r.vmax, 12);
    let kp = to_uint(cmd.kp, 0.0, KP_MAX, 12);
    let kd = to_uint(cmd.kd, 0.0, KD_MAX, 12);
    let t = to_uint(cmd.t_ff_nm, -r.tmax, r.tmax, 12);
    let [p_hi, p_lo] = p.to_be_bytes();
    let data = [
        p_hi,
        p_lo,
        (v >> 4) as u8,
        (((v & 0x0F) << 4) | (kp >> 8)) as u8,
        (kp & 0xFF) as u8,
        (kd >> 4) as u8,
        (((kd & 0x0F) << 4) | (t >> 8)) as u8,
        (t & 0xFF) as u8,
    ];
    CanFrame::new(command_id(0, esc_id)?, &data)
}

/// The position-velocity command on 0x100 + ESC_ID: p_des and the speed limit, f32
/// little-endian.
pub fn pos_vel(esc_id: u16, p_des_rad: f32, v_des_rad_s: f32) -> Result<CanFrame, bus::FrameError> {
    let mut data = [0u8; 8];
    data[..4].copy_from_slice(&p_des_rad.to_le_bytes());
    data[4..].copy_from_slice(&v_des_rad_s.to_le_bytes());
    CanFrame::new(command_id(id::POS_VEL, esc_id)?, &data)
}

/// The velocity command on 0x200 + ESC_ID: v_des f32 little-endian, DLC 4 or 8.
pub fn velocity(
    esc_id: u16,
    v_des_rad_s: f32,
    len: VelocityLen,
) -> Result<CanFrame, bus::FrameError> {
    let mut data = [0u8; 8];
    data[..4].copy_from_slice(&v_des_rad_s.to_le_bytes());
    let n = match len {
        VelocityLen::Four => 4,
        VelocityLen::Eight => 8,
    };
    CanFrame::new(command_id(id::VELOCITY, esc_id)?, &data[..n])
}

/// A real scaled by `scale` and clamped to 0..=10000, rounded to the nearest step (NaN: 0).
fn force_pos_raw(value: f32, scale: f64) -> u16 {
    if value.is_nan() {
        return 0;
    }
    (f64::from(value) * scale).round().clamp(0.0, 10_000.0) as u16
}

/// The force-position command on 0x300 + ESC_ID: p_des f32 LE, the speed limit u16 LE in
/// 0.01 rad/s, the current limit u16 LE in 1e-4 per unit, both clamped to 0..=10000.
pub fn force_position(esc_id: u16, cmd: &ForcePosCommand) -> Result<CanFrame, bus::FrameError> {
    let mut data = [0u8; 8];
    data[..4].copy_from_slice(&cmd.p_des_rad.to_le_bytes());
    data[4..6].copy_from_slice(&force_pos_raw(cmd.v_limit_rad_s, 100.0).to_le_bytes());
    data[6..].copy_from_slice(&force_pos_raw(cmd.i_limit, 10_000.0).to_le_bytes());
    CanFrame::new(command_id(id::FORCE_POS, esc_id)?, &data)
}

/// A frame on [`id::REGISTER`]: ESC_ID low and high byte, `operation`, `rid`, four value
/// bytes.
pub fn register_frame(
    esc_id: u16,
    operation: u8,
    rid: u8,
    value: [u8; 4],
) -> Result<CanFrame, bus::FrameError> {
    let [lo, hi] = esc_id.to_le_bytes();
    let data = [
        lo, hi, operation, rid, value[0], value[1], value[2], value[3],
    ];
    CanFrame::standard(id::REGISTER, &data)
}

/// Read register `rid` (value bytes zero).
pub fn read_register(esc_id: u16, rid: u8) -> Result<CanFrame, bus::FrameError> {
    register_frame(esc_id, op::READ, rid, [0; 4])
}

/// Write `value` to register `rid`.
pub fn write_register(
    esc_id: u16,
    rid: u8,
    value: RegisterValue,
) -> Result<CanFrame, bus::FrameError> {
    register_frame(esc_id, op::WRITE, rid, value.to_bytes())
}

/// Save every register to flash (the RID byte, which the firmware ignores, is 0).
pub fn save(esc_id: u16) -> Result<CanFrame, bus::FrameError> {
    register_frame(esc_id, op::SAVE, 0, [0; 4])
}

/// Ask for a feedback frame.
pub fn refresh(esc_id: u16) -> Result<CanFrame, bus::FrameError> {
    register_frame(esc_id, op::REFRESH, 0, [0; 4])
}

/// Decode a feedback payload (DLC 8; anything else is `None`) with the motor's ranges.
pub fn decode_feedback(data: &[u8], r: &Ranges) -> Option<Feedback> {
    let d: &[u8; 8] = data.try_into().ok()?;
    let pos = u16::from_be_bytes([d[1], d[2]]);
    let vel = (u16::from(d[3]) << 4) | u16::from(d[4] >> 4);
    let torque = (u16::from(d[4] & 0x0F) << 8) | u16::from(d[5]);
    Some(Feedback {
        motor: d[0] & 0x0F,
        state: MotorState::from_code(d[0] >> 4),
        position_rad: from_uint(pos, -r.pmax, r.pmax, 16),
        velocity_rad_s: from_uint(vel, -r.vmax, r.vmax, 12),
        torque_nm: from_uint(torque, -r.tmax, r.tmax, 12),
        mos_temp_c: d[6],
        rotor_temp_c: d[7],
    })
}

/// Decode a frame received on the MST_ID of the motor whose ESC_ID is `esc_id`.
///
/// A frame whose D0..D1 are ESC_ID and whose D2 is [`op::READ`] or [`op::WRITE`] is a register
/// reply; any other is a feedback frame, which must carry ESC_ID's low nibble in D0. Returns
/// `None` for extended frames, a DLC other than 8, and a feedback frame of another motor.
///
/// The two kinds share the identifier. A feedback frame looks like a register reply only when
/// its D0 (state and nibble) equals ESC_ID's low byte, its D1 (the position's high byte) ESC_ID's
/// high byte and its D2 (the velocity's high byte) is 0x33 or 0x55: for ESC_IDs below 16, a
/// disabled motor within 0.4 % of the span above -PMAX moving at one of 32 of the 4096
/// velocity codes. Such a frame is read as a register reply.
pub fn decode_reply(frame: &CanFrame, esc_id: u16, r: &Ranges) -> Option<Reply> {
    if frame.is_extended() {
        return None;
    }
    let d: &[u8; 8] = frame.data().try_into().ok()?;
    let [lo, hi] = esc_id.to_le_bytes();
    if d[0] == lo && d[1] == hi && (d[2] == op::READ || d[2] == op::WRITE) {
        return Some(Reply::Register(RegisterReply {
            esc_id,
            op: d[2],
            rid: d[3],
            value: [d[4], d[5], d[6], d[7]],
        }));
    }
    if d[0] & 0x0F != (esc_id & 0x0F) as u8 {
        return None;
    }
    decode_feedback(d, r).map(Reply::Feedback)
}

#[cfg(test)]
mod tests {
    use super::*;

    const DM4310: Ranges = Ranges {
        pmax: 12.5,
        vmax: 30.0,
        tmax: 10.0,
    };

    #[test]
    fn zero_encodes_below_the_middle_and_ends_are_exact() {
        assert_eq!(to_uint(0.0, -12.5, 12.5, 16), 32767);
        assert_eq!(to_uint(12.5, -12.5, 12.5, 16), 65535);
        assert_eq!(to_uint(-12.5, -12.5, 12.5, 16), 0);
        assert_eq!(to_uint(f32::INFINITY, -30.0, 30.0, 12), 4095);
        assert_eq!(to_uint(f32::NEG_INFINITY, -30.0, 30.0, 12), 0);
        assert_eq!(to_uint(f32::NAN, -30.0, 30.0, 12), 0);
        // Empty or broken ranges do not panic.
        assert_eq!(to_uint(1.0, 5.0, 5.0, 12), 0);
        assert_eq!(to_uint(1.0, 5.0, -5.0, 12), 0);
        assert_eq!(to_uint(1.0, f32::NAN, 5.0, 12), 0);
        assert_eq!(from_uint(4095, -30.0, 30.0, 12), 30.0);
    }

    #[test]
    fn mit_fields_pack_across_nibbles() {
        let cmd = MitCommand {
            p_des_rad: 0.0,
            v_des_rad_s: 0.0,
            kp: 0.0,
            kd: 0.0,
            t_ff_nm: 0.0,
        };
        let frame = mit(0x01, &cmd, &DM4310).unwrap();
        assert_eq!(frame.raw_id(), 0x001);
        assert_eq!(
            frame.data(),
            &[0x7F, 0xFF, 0x7F, 0xF0, 0x00, 0x00, 0x07, 0xFF]
        );
        // Identifiers past 11 bits are errors, not panics.
        assert!(mit(0x800, &cmd, &DM4310).is_err());
        assert!(force_position(u16::MAX, &ForcePosCommand::default()).is_err());
    }

    #[test]
    fn replies_are_told_apart_and_other_motors_ignored() {
        let reg = CanFrame::standard(0x11, &[0x01, 0x00, 0x33, 0x0A, 1, 0, 0, 0]).unwrap();
        assert!(matches!(
            decode_reply(&reg, 0x01, &DM4310),
            Some(Reply::Register(RegisterReply {
                op: op::READ,
                rid: 10,
                ..
            }))
        ));
        // The same bytes are another motor's feedback for ESC_ID 0x02.
        assert_eq!(decode_reply(&reg, 0x02, &DM4310), None);
        let feedback =
            CanFrame::standard(0x11, &[0x11, 0x7F, 0xFF, 0x7F, 0xF7, 0xFF, 25, 24]).unwrap();
        let Some(Reply::Feedback(fb)) = decode_reply(&feedback, 0x01, &DM4310) else {
            panic!("feedback");
        };
        assert_eq!((fb.motor, fb.state), (1, MotorState::Enabled));
        // ESC_ID 0x21 has the same low nibble: routing by identifier decides.
        assert!(decode_reply(&feedback, 0x21, &DM4310).is_some());
        let short = CanFrame::standard(0x11, &[0x11, 0x7F]).unwrap();
        assert_eq!(decode_reply(&short, 0x01, &DM4310), None);
        let extended = CanFrame::extended(0x11, &[0x11; 8]).unwrap();
        assert_eq!(decode_reply(&extended, 0x01, &DM4310), None);
    }

    #[test]
    fn states_round_trip_through_their_nibble() {
        for code in 0..16u8 {
            let state = MotorState::from_code(code);
            assert_eq!(state.code(), code);
            assert_eq!(state.is_error(), code > 1);
        }
        assert_eq!(
            MotorState::OverVoltage.to_string(),
            "over_voltage (state 0x8)"
        );
    }
}
