//! The register table of the note's §6.2 (RID, name, f32/u32, RO/RW, range where the note
//! gives one) and one motor's register values ([`RegisterFile`]).
//!
//! Writes ([`RegisterFile::write`]) are checked against the table: a read-only register, a
//! value outside the row's range, or a non-finite f32 is refused and the stored value stays
//! (the firmware then echoes it, so a host that compares the echo with what it sent sees the
//! refusal). Refusing rather than clamping keeps a mistyped value (ESC_ID 0x800, CTRL_MODE 7)
//! from silently turning into a different valid one.
//!
//! Defaults: the MIT ranges (21–23) follow §9.1, the ids the configuration, `Gr` the model's
//! gear; every other default is an emulator estimate (the note gives no values), chosen to be
//! inside the row's range and plausible for the model.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::damiao::model::{MitRanges, Model};
use crate::state_file::InvalidField;

/// A register's wire type (D4..D7 little-endian).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum RegType {
    /// IEEE-754 single, little-endian.
    F32,
    /// Unsigned 32-bit, little-endian.
    U32,
}

/// Whether a host may write a register.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Access {
    /// Read-only: a write is echoed with the unchanged value.
    ReadOnly,
    /// Read-write.
    ReadWrite,
}

/// A register's valid range; each end open or closed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bounds {
    /// Lower end.
    pub min: f64,
    /// Whether `min` itself is valid.
    pub min_inclusive: bool,
    /// Upper end.
    pub max: f64,
    /// Whether `max` itself is valid.
    pub max_inclusive: bool,
}

impl Bounds {
    const fn closed(min: f64, max: f64) -> Self {
        Self {
            min,
            min_inclusive: true,
            max,
            max_inclusive: true,
        }
    }

    const fn open(min: f64, max: f64) -> Self {
        Self {
            min,
            min_inclusive: false,
            max,
            max_inclusive: false,
        }
    }

    const fn closed_open(min: f64, max: f64) -> Self {
        Self {
            min,
            min_inclusive: true,
            max,
            max_inclusive: false,
        }
    }

    const fn open_closed(min: f64, max: f64) -> Self {
        Self {
            min,
            min_inclusive: false,
            max,
            max_inclusive: true,
        }
    }

    /// Whether `x` is within.
    pub fn contains(&self, x: f64) -> bool {
        let above = if self.min_inclusive {
            x >= self.min
        } else {
            x > self.min
        };
        let below = if self.max_inclusive {
            x <= self.max
        } else {
            x < self.max
        };
        above && below
    }
}

impl std::fmt::Display for Bounds {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let open = if self.min_inclusive { '[' } else { '(' };
        let close = if self.max_inclusive { ']' } else { ')' };
        write!(f, "{open}{}, {}{close}", self.min, self.max)
    }
}

/// One row of the table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RegisterSpec {
    /// Register id (D3).
    pub rid: u8,
    /// Name as the note's table writes it (56 is `m_off_motor` here: the note calls it
    /// `m_off` like 54).
    pub name: &'static str,
    /// Wire type.
    pub ty: RegType,
    /// RO or RW.
    pub access: Access,
    /// Valid range: the note's where it gives one; PMAX/VMAX/TMAX must be positive (the
    /// emulator's own guard: a zero range cannot scale). `None`: any finite value.
    pub bounds: Option<Bounds>,
    /// What it holds.
    pub meaning: &'static str,
}

/// Register ids the firmware reads by name.
pub mod rid {
    /// Under-voltage threshold (V).
    pub const UV_VALUE: u8 = 0;
    /// Torque constant.
    pub const KT_VALUE: u8 = 1;
    /// Over-temperature threshold (°C).
    pub const OT_VALUE: u8 = 2;
    /// Over-current threshold (per-unit).
    pub const OC_VALUE: u8 = 3;
    /// Acceleration (rad/s², > 0).
    pub const ACC: u8 = 4;
    /// Deceleration (rad/s², < 0).
    pub const DEC: u8 = 5;
    /// Maximum speed (rad/s).
    pub const MAX_SPD: u8 = 6;
    /// Feedback id.
    pub const MST_ID: u8 = 7;
    /// Command id.
    pub const ESC_ID: u8 = 8;
    /// CAN timeout (50 µs units, 0 = off).
    pub const TIMEOUT: u8 = 9;
    /// Control mode (1 MIT, 2 pos-vel, 3 velocity, 4 force-pos).
    pub const CTRL_MODE: u8 = 10;
    /// Rotor inertia (motor side).
    pub const INERTIA: u8 = 12;
    /// Serial number.
    pub const SN: u8 = 15;
    /// Gear ratio.
    pub const GR: u8 = 20;
    /// MIT position range (rad).
    pub const PMAX: u8 = 21;
    /// MIT velocity range (rad/s).
    pub const VMAX: u8 = 22;
    /// MIT torque range (N·m).
    pub const TMAX: u8 = 23;
    /// Over-voltage threshold (V).
    pub const OV_VALUE: u8 = 29;
    /// CAN bit-rate code.
    pub const CAN_BR: u8 = 35;
    /// Board full-scale current (A).
    pub const IMAX: u8 = 59;
    /// Supply voltage (V), live.
    pub const VBUS: u8 = 60;
    /// Board (MOS) temperature (°C), live.
    pub const TPCB: u8 = 61;
    /// Motor (coil) temperature (°C), live.
    pub const TMTR: u8 = 62;
    /// Motor-side position (rad), live.
    pub const P_M: u8 = 80;
    /// Output position (rad), live.
    pub const XOUT: u8 = 81;
}

/// Registers whose value is the motor's present state, not a stored number: the firmware
/// answers their reads from its state (the table's value is only the power-on one).
pub const LIVE: [u8; 5] = [rid::VBUS, rid::TPCB, rid::TMTR, rid::P_M, rid::XOUT];

const INF: f64 = f64::INFINITY;

macro_rules! row {
    ($rid:expr, $name:expr, $ty:ident, $access:ident, $bounds:expr, $meaning:expr) => {
        RegisterSpec {
            rid: $rid,
            name: $name,
            ty: RegType::$ty,
            access: Access::$access,
            bounds: $bounds,
            meaning: $meaning,
        }
    };
}

/// Every register, by RID (note §6.2). One row per line: (RID, name, type, access, range,
/// meaning).
#[rustfmt::skip]
pub static TABLE: &[RegisterSpec] = &[
    row!(0, "UV_Value", F32, ReadWrite, Some(Bounds::open(10.0, INF)), "under-voltage threshold (V)"),
    row!(1, "KT_Value", F32, ReadWrite, None, "torque constant"),
    row!(2, "OT_Value", F32, ReadWrite, Some(Bounds::closed_open(80.0, 200.0)), "over-temperature threshold (°C)"),
    row!(3, "OC_Value", F32, ReadWrite, Some(Bounds::open_closed(0.0, 1.0)), "over-current threshold (per-unit)"),
    row!(4, "ACC", F32, ReadWrite, Some(Bounds::open(0.0, INF)), "acceleration (rad/s²)"),
    row!(5, "DEC", F32, ReadWrite, Some(Bounds::open(-INF, 0.0)), "deceleration (rad/s², negative)"),
    row!(6, "MAX_SPD", F32, ReadWrite, None, "maximum speed (rad/s)"),
    row!(7, "MST_ID", U32, ReadWrite, Some(Bounds::closed(0.0, 2047.0)), "feedback id"),
    row!(8, "ESC_ID", U32, ReadWrite, Some(Bounds::closed(0.0, 2047.0)), "command id"),
    row!(9, "TIMEOUT", U32, ReadWrite, None, "CAN timeout (50 µs units, 0 = off)"),
    row!(10, "CTRL_MODE", U32, ReadWrite, Some(Bounds::closed(1.0, 4.0)), "1 MIT, 2 pos-vel, 3 velocity, 4 force-pos"),
    row!(11, "Damp", F32, ReadOnly, None, "viscous damping"),
    row!(12, "Inertia", F32, ReadOnly, None, "rotor inertia (kg·m², motor side)"),
    row!(13, "hw_ver", U32, ReadOnly, None, "hardware version"),
    row!(14, "sw_ver", U32, ReadOnly, None, "software version"),
    row!(15, "SN", U32, ReadOnly, None, "serial number"),
    row!(16, "NPP", U32, ReadOnly, None, "pole pairs"),
    row!(17, "Rs", F32, ReadOnly, None, "phase resistance (Ω)"),
    row!(18, "LS", F32, ReadOnly, None, "phase inductance (H)"),
    row!(19, "Flux", F32, ReadOnly, None, "flux linkage (Wb)"),
    row!(20, "Gr", F32, ReadOnly, None, "gear ratio"),
    row!(21, "PMAX", F32, ReadWrite, Some(Bounds::open(0.0, INF)), "MIT position range (rad)"),
    row!(22, "VMAX", F32, ReadWrite, Some(Bounds::open(0.0, INF)), "MIT velocity range (rad/s)"),
    row!(23, "TMAX", F32, ReadWrite, Some(Bounds::open(0.0, INF)), "MIT torque range (N·m)"),
    row!(24, "I_BW", F32, ReadWrite, Some(Bounds::closed(100.0, 10_000.0)), "current-loop bandwidth"),
    row!(25, "KP_ASR", F32, ReadWrite, None, "speed-loop kp"),
    row!(26, "KI_ASR", F32, ReadWrite, None, "speed-loop ki"),
    row!(27, "KP_APR", F32, ReadWrite, None, "position-loop kp"),
    row!(28, "KI_APR", F32, ReadWrite, None, "position-loop ki"),
    row!(29, "OV_Value", F32, ReadWrite, None, "over-voltage threshold (V)"),
    row!(30, "GREF", F32, ReadWrite, Some(Bounds::open_closed(0.0, 1.0)), "gear torque efficiency"),
    row!(31, "Deta", F32, ReadWrite, Some(Bounds::closed(1.0, 30.0)), "speed-loop damping"),
    row!(32, "V_BW", F32, ReadWrite, Some(Bounds::open(0.0, 500.0)), "speed-loop filter bandwidth"),
    row!(33, "IQ_c1", F32, ReadWrite, None, "current-loop enhancement"),
    row!(34, "VL_c1", F32, ReadWrite, None, "speed-loop enhancement"),
    row!(35, "can_br", U32, ReadWrite, Some(Bounds::closed(0.0, 4.0)), "bit-rate code (0 125k … 4 1M)"),
    row!(36, "sub_ver", U32, ReadOnly, None, "sub-version"),
    row!(50, "u_off", F32, ReadOnly, None, "calibration: u offset"),
    row!(51, "v_off", F32, ReadOnly, None, "calibration: v offset"),
    row!(52, "k1", F32, ReadOnly, None, "calibration: k1"),
    row!(53, "k2", F32, ReadOnly, None, "calibration: k2"),
    row!(54, "m_off", F32, ReadOnly, None, "calibration: angle offset"),
    row!(55, "dir", F32, ReadOnly, None, "calibration: direction"),
    row!(56, "m_off_motor", F32, ReadOnly, None, "angle offset, motor side"),
    row!(59, "Imax", F32, ReadOnly, None, "board full-scale current (A)"),
    row!(60, "VBus", F32, ReadOnly, None, "supply voltage (V), live"),
    row!(61, "Tpcb", F32, ReadOnly, None, "board (MOS) temperature (°C), live"),
    row!(62, "Tmtr", F32, ReadOnly, None, "motor (coil) temperature (°C), live"),
    row!(63, "Iu_off", F32, ReadOnly, None, "phase u current offset"),
    row!(64, "Iv_off", F32, ReadOnly, None, "phase v current offset"),
    row!(65, "Iw_off", F32, ReadOnly, None, "phase w current offset"),
    row!(80, "p_m", F32, ReadOnly, None, "motor-side position (rad), live"),
    row!(81, "xout", F32, ReadOnly, None, "output position (rad), live"),
];

/// The row of `rid`, if the table has one.
pub fn spec(rid: u8) -> Option<&'static RegisterSpec> {
    TABLE.iter().find(|row| row.rid == rid)
}

/// The row called `name` (exact, as [`RegisterSpec::name`]).
pub fn spec_named(name: &str) -> Option<&'static RegisterSpec> {
    TABLE.iter().find(|row| row.name == name)
}

/// A register value of its row's type.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RegValue {
    /// An f32 register's value.
    F32(f32),
    /// A u32 register's value.
    U32(u32),
}

impl RegValue {
    /// D4..D7.
    pub fn to_le_bytes(self) -> [u8; 4] {
        match self {
            RegValue::F32(x) => x.to_le_bytes(),
            RegValue::U32(x) => x.to_le_bytes(),
        }
    }

    /// The value of type `ty` in D4..D7.
    pub fn from_le_bytes(ty: RegType, bytes: [u8; 4]) -> Self {
        match ty {
            RegType::F32 => RegValue::F32(f32::from_le_bytes(bytes)),
            RegType::U32 => RegValue::U32(u32::from_le_bytes(bytes)),
        }
    }

    /// As a number (u32 values are exact in f64).
    pub fn as_f64(self) -> f64 {
        match self {
            RegValue::F32(x) => f64::from(x),
            RegValue::U32(x) => f64::from(x),
        }
    }

    /// `x` as a value of type `ty`, if it is one: finite, and for u32 whole and in range.
    pub fn from_f64(ty: RegType, x: f64) -> Option<Self> {
        match ty {
            // An f32 register keeps f32 precision; a value beyond f32's range is no value.
            RegType::F32 => {
                let narrow = x as f32;
                narrow.is_finite().then_some(RegValue::F32(narrow))
            }
            RegType::U32 => {
                (x.is_finite() && x.fract() == 0.0 && (0.0..=f64::from(u32::MAX)).contains(&x))
                    // Whole and within u32: the cast is exact.
                    .then_some(RegValue::U32(x as u32))
            }
        }
    }
}

/// What a write did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum WriteOutcome {
    /// Stored; the value now held.
    Stored(RegValue),
    /// Refused (read-only, out of range, not finite); the value still held.
    Refused(RegValue),
    /// No such register.
    Unknown,
}

/// One motor's register values.
#[derive(Debug, Clone, PartialEq)]
pub struct RegisterFile {
    values: BTreeMap<u8, RegValue>,
}

/// Power-on defaults besides the ids and MIT ranges, all estimates (see the module doc).
struct Estimates;

impl Estimates {
    const OT_C: f32 = 120.0;
    const OC_PER_UNIT: f32 = 0.98;
    const ACC_RAD_S2: f32 = 30.0;
    const DEC_RAD_S2: f32 = -30.0;
    const POLE_PAIRS: u32 = 14;
    const HW_VER: u32 = 1;
    const SW_VER: u32 = 0x1000;
    const I_BW: f32 = 1000.0;
    const DETA: f32 = 4.0;
    const V_BW: f32 = 100.0;
}

impl RegisterFile {
    /// A model's power-on values with the given ids and serial number.
    pub fn defaults(model: Model, esc_id: u16, mst_id: u16, serial: u32) -> Self {
        let spec = model.spec();
        let MitRanges {
            p_max_rad,
            v_max_rad_s,
            t_max_nm,
        } = spec.ranges;
        let gear = spec.gear_ratio as f32;
        let volts = spec.nominal_voltage_v as f32;
        // A motor-side torque constant that makes Imax through the gear the peak torque.
        let kt = (spec.peak_torque_nm / (spec.gear_ratio * spec.max_current_a)) as f32;
        let rotor_motor_side =
            (spec.rotor_inertia_kg_m2 / (spec.gear_ratio * spec.gear_ratio)) as f32;
        let mut values = BTreeMap::new();
        for row in TABLE {
            let f = |x: f32| RegValue::F32(x);
            let u = |x: u32| RegValue::U32(x);
            let value = match row.rid {
                // Half the nominal supply: inside the note's "> 10 V" for both 24 and 48 V.
                rid::UV_VALUE => f(volts * 0.5),
                rid::KT_VALUE => f(kt),
                rid::OT_VALUE => f(Estimates::OT_C),
                rid::OC_VALUE => f(Estimates::OC_PER_UNIT),
                rid::ACC => f(Estimates::ACC_RAD_S2),
                rid::DEC => f(Estimates::DEC_RAD_S2),
                rid::MAX_SPD => f(spec.max_speed_rad_s as f32),
                rid::MST_ID => u(u32::from(mst_id)),
                rid::ESC_ID => u(u32::from(esc_id)),
                rid::TIMEOUT => u(0),
                rid::CTRL_MODE => u(1),
                rid::INERTIA => f(rotor_motor_side),
                13 => u(Estimates::HW_VER),
                14 => u(Estimates::SW_VER),
                rid::SN => u(serial),
                16 => u(Estimates::POLE_PAIRS),
                17 => f(0.5),
                18 => f(2.0e-4),
                19 => f(0.005),
                rid::GR => f(gear),
                rid::PMAX => f(p_max_rad),
                rid::VMAX => f(v_max_rad_s),
                rid::TMAX => f(t_max_nm),
                24 => f(Estimates::I_BW),
                // Loop gains: stored and served; the emulator's loops take their gains from
                // the plant's inertia instead (their units are not documented).
                25 => f(0.002),
                26 => f(0.002),
                27 => f(30.0),
                28 => f(0.0),
                // 1.35 × nominal: room for regenerative braking on a 24/48 V supply.
                rid::OV_VALUE => f(volts * 1.35),
                30 => f(1.0),
                31 => f(Estimates::DETA),
                32 => f(Estimates::V_BW),
                52 | 53 | 55 => f(1.0),
                rid::CAN_BR => u(4),
                rid::IMAX => f(spec.max_current_a as f32),
                rid::VBUS => f(volts),
                rid::TPCB | rid::TMTR => f(25.0),
                _ => match row.ty {
                    RegType::F32 => f(0.0),
                    RegType::U32 => u(0),
                },
            };
            values.insert(row.rid, value);
        }
        Self { values }
    }

    /// The value held for `rid`, if the register exists.
    pub fn get(&self, rid: u8) -> Option<RegValue> {
        self.values.get(&rid).copied()
    }

    /// The value of `rid` as a number (0 for a register that does not exist).
    pub fn number(&self, rid: u8) -> f64 {
        self.get(rid).map_or(0.0, RegValue::as_f64)
    }

    /// The MIT ranges in force (registers 21–23).
    pub fn ranges(&self) -> MitRanges {
        let f = |rid| self.number(rid) as f32;
        MitRanges {
            p_max_rad: f(rid::PMAX),
            v_max_rad_s: f(rid::VMAX),
            t_max_nm: f(rid::TMAX),
        }
    }

    /// A host's 0x55 write of `bytes` to `rid` (see the module doc for what is refused).
    pub fn write(&mut self, rid: u8, bytes: [u8; 4]) -> WriteOutcome {
        let (Some(row), Some(held)) = (spec(rid), self.get(rid)) else {
            return WriteOutcome::Unknown;
        };
        let value = RegValue::from_le_bytes(row.ty, bytes);
        if !accepts(row, value) {
            return WriteOutcome::Refused(held);
        }
        self.values.insert(rid, value);
        WriteOutcome::Stored(value)
    }

    /// The read-write registers by name: what a save (0xAA) keeps in flash.
    pub fn saved(&self) -> BTreeMap<String, f64> {
        TABLE
            .iter()
            .filter(|row| row.access == Access::ReadWrite)
            .filter_map(|row| Some((row.name.to_owned(), self.get(row.rid)?.as_f64())))
            .collect()
    }

    /// Apply values saved in flash ([`RegisterFile::saved`]), each checked as a write would
    /// be: an unknown name, a read-only register or a value a write would refuse is an error
    /// naming `prefix.<name>`.
    pub fn apply_saved(
        &mut self,
        saved: &BTreeMap<String, f64>,
        prefix: &str,
    ) -> Result<(), InvalidField> {
        for (name, &x) in saved {
            let field = || format!("{prefix}.{name}");
            let Some(row) = spec_named(name) else {
                return Err(InvalidField::new(field(), "no register of that name"));
            };
            if row.access != Access::ReadWrite {
                return Err(InvalidField::new(field(), "read-only register"));
            }
            let value = RegValue::from_f64(row.ty, x)
                .filter(|v| accepts(row, *v))
                .ok_or_else(|| InvalidField::new(field(), refusal(row, x)))?;
            self.values.insert(row.rid, value);
        }
        Ok(())
    }
}

/// Whether a write of `value` to `row` is taken.
fn accepts(row: &RegisterSpec, value: RegValue) -> bool {
    let x = value.as_f64();
    row.access == Access::ReadWrite && x.is_finite() && row.bounds.is_none_or(|b| b.contains(x))
}

/// Why `x` is refused for `row`, in words.
fn refusal(row: &RegisterSpec, x: f64) -> String {
    match (row.ty, row.bounds) {
        (RegType::U32, Some(b)) => format!("{x} is not a whole number within {b}"),
        (RegType::U32, None) => format!("{x} is not a u32"),
        (RegType::F32, Some(b)) => format!("{x} is not a finite number within {b}"),
        (RegType::F32, None) => format!("{x} is not a finite f32"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_has_unique_ids_and_names_and_the_note_s_types() {
        for (i, a) in TABLE.iter().enumerate() {
            for b in &TABLE[i + 1..] {
                assert_ne!(a.rid, b.rid);
                assert_ne!(a.name, b.name);
            }
        }
        // openarm_can decodes 7–10, 13–16 and 35–36 as u32, everything else f32.
        for row in TABLE {
            let u32_row = matches!(row.rid, 7..=10 | 13..=16 | 35..=36);
            assert_eq!(row.ty == RegType::U32, u32_row, "{}", row.name);
        }
    }

    #[test]
    fn every_default_is_a_value_a_write_would_take() {
        for model in Model::ALL {
            let file = RegisterFile::defaults(model, 3, 0x13, 77);
            for row in TABLE {
                let value = file.get(row.rid).unwrap();
                let typed = matches!(
                    (row.ty, value),
                    (RegType::F32, RegValue::F32(_)) | (RegType::U32, RegValue::U32(_))
                );
                assert!(typed, "{model} {}", row.name);
                if row.access == Access::ReadWrite {
                    assert!(accepts(row, value), "{model} {} = {value:?}", row.name);
                }
            }
            assert_eq!(file.ranges(), model.ranges());
        }
    }

    #[test]
    fn writes_are_refused_outside_the_row_and_to_read_only_rows() {
        let mut file = RegisterFile::defaults(Model::DM4310, 1, 0x11, 0);
        let stored = file.write(rid::CTRL_MODE, 2u32.to_le_bytes());
        assert_eq!(stored, WriteOutcome::Stored(RegValue::U32(2)));
        assert_eq!(
            file.write(rid::CTRL_MODE, 5u32.to_le_bytes()),
            WriteOutcome::Refused(RegValue::U32(2))
        );
        assert_eq!(
            file.write(rid::OT_VALUE, 200.0f32.to_le_bytes()),
            WriteOutcome::Refused(RegValue::F32(120.0)),
            "OT's upper end is open"
        );
        assert_eq!(
            file.write(rid::ACC, f32::NAN.to_le_bytes()),
            WriteOutcome::Refused(RegValue::F32(30.0))
        );
        let gear = file.get(rid::GR).unwrap();
        assert_eq!(
            file.write(rid::GR, 1.0f32.to_le_bytes()),
            WriteOutcome::Refused(gear)
        );
        assert_eq!(file.write(99, [0; 4]), WriteOutcome::Unknown);
    }

    #[test]
    fn saved_values_come_back_and_bad_ones_are_named() {
        let mut file = RegisterFile::defaults(Model::DM8009, 2, 0x12, 0);
        file.write(rid::TIMEOUT, 400u32.to_le_bytes());
        file.write(rid::ACC, 12.5f32.to_le_bytes());
        let saved = file.saved();
        let mut again = RegisterFile::defaults(Model::DM8009, 2, 0x12, 0);
        again.apply_saved(&saved, "flash").unwrap();
        assert_eq!(again, file);
        let bad = BTreeMap::from([("ESC_ID".to_owned(), 4096.0)]);
        let error = again.apply_saved(&bad, "flash").unwrap_err();
        assert_eq!(error.field, "flash.ESC_ID");
        let ro = BTreeMap::from([("Gr".to_owned(), 3.0)]);
        assert!(again.apply_saved(&ro, "flash").is_err());
    }
}
