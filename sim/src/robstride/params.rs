//! The control parameter table 0x70xx (spec §7.1): types, ranges, access, defaults.

use std::collections::BTreeMap;

use crate::robstride::model::{Model, Ranges};

/// Parameter indices the emulator's control code reads.
pub mod index {
    /// run_mode (u8).
    pub const RUN_MODE: u16 = 0x7005;
    /// iq_ref (A).
    pub const IQ_REF: u16 = 0x7006;
    /// spd_ref (rad/s).
    pub const SPD_REF: u16 = 0x700A;
    /// limit_torque (N·m).
    pub const LIMIT_TORQUE: u16 = 0x700B;
    /// cur_kp.
    pub const CUR_KP: u16 = 0x7010;
    /// cur_ki.
    pub const CUR_KI: u16 = 0x7011;
    /// cur_filt_gain.
    pub const CUR_FILT_GAIN: u16 = 0x7014;
    /// loc_ref (rad).
    pub const LOC_REF: u16 = 0x7016;
    /// limit_spd (rad/s), CSP speed limit.
    pub const LIMIT_SPD: u16 = 0x7017;
    /// limit_cur (A).
    pub const LIMIT_CUR: u16 = 0x7018;
    /// mechPos (rad), read-only.
    pub const MECH_POS: u16 = 0x7019;
    /// iqf (A), read-only.
    pub const IQF: u16 = 0x701A;
    /// mechVel (rad/s), read-only.
    pub const MECH_VEL: u16 = 0x701B;
    /// VBUS (V), read-only.
    pub const VBUS: u16 = 0x701C;
    /// loc_kp.
    pub const LOC_KP: u16 = 0x701E;
    /// spd_kp.
    pub const SPD_KP: u16 = 0x701F;
    /// spd_ki.
    pub const SPD_KI: u16 = 0x7020;
    /// spd_filt_gain.
    pub const SPD_FILT_GAIN: u16 = 0x7021;
    /// acc_rad (rad/s²), velocity-mode acceleration.
    pub const ACC_RAD: u16 = 0x7022;
    /// vel_max (rad/s), PP profile speed.
    pub const VEL_MAX: u16 = 0x7024;
    /// acc_set (rad/s²), PP acceleration.
    pub const ACC_SET: u16 = 0x7025;
    /// EPScan_time (u16), active-report period.
    pub const EPSCAN_TIME: u16 = 0x7026;
    /// canTimeout (u32, 50 µs ticks).
    pub const CAN_TIMEOUT: u16 = 0x7028;
    /// zero_sta (u8).
    pub const ZERO_STA: u16 = 0x7029;
    /// damper (u8).
    pub const DAMPER: u16 = 0x702A;
    /// add_offset (rad).
    pub const ADD_OFFSET: u16 = 0x702B;
    /// alveolous_open (u8).
    pub const ALVEOLOUS_OPEN: u16 = 0x702C;
    /// iq_test (u8).
    pub const IQ_TEST: u16 = 0x702D;
    /// dcc_set (rad/s²), PP deceleration.
    pub const DCC_SET: u16 = 0x702E;
}

/// How a parameter's value is laid out in bytes 4..7 of types 17/18.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParamType {
    /// One byte at `data[4]`.
    U8,
    /// Little-endian u16 at data[4..6].
    U16,
    /// Little-endian u32 at data[4..8].
    U32,
    /// IEEE-754 f32, little-endian, at data[4..8].
    F32,
}

/// Whether the host may write a parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Access {
    /// Read and write.
    ReadWrite,
    /// Read only: writes are refused.
    ReadOnly,
}

/// One row of the parameter table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamSpec {
    /// Index (0x70xx).
    pub index: u16,
    /// Manual name.
    pub name: &'static str,
    /// Wire type.
    pub ty: ParamType,
    /// Access.
    pub access: Access,
    /// Smallest accepted value (writes are clamped into range).
    pub min: f64,
    /// Largest accepted value.
    pub max: f64,
    /// Power-on default.
    pub default: f64,
    /// Stored by a save (type 22); setpoints are not.
    pub saved: bool,
}

/// The per-model parameter table.
pub fn table(model: Model, ranges: &Ranges) -> Vec<ParamSpec> {
    use Access::{ReadOnly, ReadWrite};
    use ParamType::{F32, U16, U32, U8};
    let current = f64::from(ranges.current_a);
    let speed = f64::from(ranges.speed_rad_s);
    let torque = f64::from(ranges.torque_nm);
    let spec = model.spec();
    // Gains and accelerations have no published upper bound; a wide one keeps NaN/∞ out.
    let big = 1.0e6;
    let row = |index, name, ty, access, min, max, default, saved| ParamSpec {
        index,
        name,
        ty,
        access,
        min,
        max,
        default,
        saved,
    };
    let mut rows = vec![
        row(
            index::RUN_MODE,
            "run_mode",
            U8,
            ReadWrite,
            0.0,
            5.0,
            0.0,
            false,
        ),
        row(
            index::IQ_REF,
            "iq_ref",
            F32,
            ReadWrite,
            -current,
            current,
            0.0,
            false,
        ),
        row(
            index::SPD_REF,
            "spd_ref",
            F32,
            ReadWrite,
            -speed,
            speed,
            0.0,
            false,
        ),
        row(
            index::LIMIT_TORQUE,
            "limit_torque",
            F32,
            ReadWrite,
            0.0,
            torque,
            torque,
            true,
        ),
        row(
            index::CUR_KP,
            "cur_kp",
            F32,
            ReadWrite,
            0.0,
            big,
            0.17,
            true,
        ),
        row(
            index::CUR_KI,
            "cur_ki",
            F32,
            ReadWrite,
            0.0,
            big,
            0.012,
            true,
        ),
        row(
            index::CUR_FILT_GAIN,
            "cur_filt_gain",
            F32,
            ReadWrite,
            0.0,
            1.0,
            0.1,
            true,
        ),
        row(
            index::LOC_REF,
            "loc_ref",
            F32,
            ReadWrite,
            -big,
            big,
            0.0,
            false,
        ),
        row(
            index::LIMIT_SPD,
            "limit_spd",
            F32,
            ReadWrite,
            0.0,
            speed,
            2.0,
            true,
        ),
        row(
            index::LIMIT_CUR,
            "limit_cur",
            F32,
            ReadWrite,
            0.0,
            current,
            current,
            true,
        ),
        row(
            index::MECH_POS,
            "mechPos",
            F32,
            ReadOnly,
            -big,
            big,
            0.0,
            false,
        ),
        row(
            index::IQF,
            "iqf",
            F32,
            ReadOnly,
            -current,
            current,
            0.0,
            false,
        ),
        row(
            index::MECH_VEL,
            "mechVel",
            F32,
            ReadOnly,
            -speed,
            speed,
            0.0,
            false,
        ),
        row(index::VBUS, "VBUS", F32, ReadOnly, 0.0, 100.0, 0.0, false),
        row(
            index::LOC_KP,
            "loc_kp",
            F32,
            ReadWrite,
            0.0,
            big,
            f64::from(model.default_loc_kp()),
            true,
        ),
        row(index::SPD_KP, "spd_kp", F32, ReadWrite, 0.0, big, 6.0, true),
        row(
            index::SPD_KI,
            "spd_ki",
            F32,
            ReadWrite,
            0.0,
            big,
            0.02,
            true,
        ),
        row(
            index::SPD_FILT_GAIN,
            "spd_filt_gain",
            F32,
            ReadWrite,
            0.0,
            1.0,
            0.1,
            true,
        ),
        row(
            index::ACC_RAD,
            "acc_rad",
            F32,
            ReadWrite,
            0.0,
            big,
            f64::from(model.default_acc_rad()),
            true,
        ),
        row(
            index::VEL_MAX,
            "vel_max",
            F32,
            ReadWrite,
            0.0,
            speed,
            10.0_f64.min(speed),
            true,
        ),
        row(
            index::ACC_SET,
            "acc_set",
            F32,
            ReadWrite,
            0.0,
            big,
            10.0,
            true,
        ),
        row(
            index::EPSCAN_TIME,
            "EPScan_time",
            U16,
            ReadWrite,
            1.0,
            65535.0,
            1.0,
            true,
        ),
        row(
            index::CAN_TIMEOUT,
            "canTimeout",
            U32,
            ReadWrite,
            0.0,
            100_000.0,
            0.0,
            true,
        ),
        row(
            index::ZERO_STA,
            "zero_sta",
            U8,
            ReadWrite,
            0.0,
            1.0,
            0.0,
            true,
        ),
        row(
            index::ALVEOLOUS_OPEN,
            "alveolous_open",
            U8,
            ReadWrite,
            0.0,
            1.0,
            0.0,
            true,
        ),
        row(
            index::IQ_TEST,
            "iq_test",
            U8,
            ReadWrite,
            0.0,
            1.0,
            0.0,
            true,
        ),
        row(
            index::DCC_SET,
            "dcc_set",
            F32,
            ReadWrite,
            0.0,
            big,
            10.0,
            true,
        ),
    ];
    if spec.has_damper_param {
        rows.push(row(
            index::DAMPER,
            "damper",
            U8,
            ReadWrite,
            0.0,
            1.0,
            0.0,
            true,
        ));
    }
    if spec.has_add_offset_param {
        rows.push(row(
            index::ADD_OFFSET,
            "add_offset",
            F32,
            ReadWrite,
            -7.0,
            7.0,
            0.0,
            true,
        ));
    }
    rows.sort_by_key(|row| row.index);
    rows
}

/// Encode a value into bytes 4..7 of a type-17 reply.
pub fn encode_value(ty: ParamType, value: f64) -> [u8; 4] {
    let mut out = [0u8; 4];
    match ty {
        ParamType::U8 => out[0] = value.round().clamp(0.0, 255.0) as u8,
        ParamType::U16 => {
            out[..2].copy_from_slice(&(value.round().clamp(0.0, 65535.0) as u16).to_le_bytes())
        }
        ParamType::U32 => out
            .copy_from_slice(&(value.round().clamp(0.0, f64::from(u32::MAX)) as u32).to_le_bytes()),
        ParamType::F32 => {
            // Never NaN or inf on the wire: NaN reads 0, out-of-range values saturate.
            let value = if value.is_nan() {
                0.0
            } else {
                value.clamp(f64::from(f32::MIN), f64::from(f32::MAX)) as f32
            };
            out.copy_from_slice(&value.to_le_bytes())
        }
    }
    out
}

/// Decode bytes 4..7 of a type-18 request; `None` for a non-finite float.
pub fn decode_value(ty: ParamType, bytes: [u8; 4]) -> Option<f64> {
    match ty {
        ParamType::U8 => Some(f64::from(bytes[0])),
        ParamType::U16 => Some(f64::from(u16::from_le_bytes([bytes[0], bytes[1]]))),
        ParamType::U32 => Some(f64::from(u32::from_le_bytes(bytes))),
        ParamType::F32 => {
            let value = f32::from_le_bytes(bytes);
            value.is_finite().then_some(f64::from(value))
        }
    }
}

/// Writable parameter values of one motor, keyed by index (BTreeMap: stable order on save).
#[derive(Debug, Clone, PartialEq)]
pub struct ParamStore {
    specs: Vec<ParamSpec>,
    values: BTreeMap<u16, f64>,
}

impl ParamStore {
    /// A store holding every default of the model's table.
    pub fn new(model: Model, ranges: &Ranges) -> Self {
        let specs = table(model, ranges);
        let values = specs
            .iter()
            .filter(|spec| spec.access == Access::ReadWrite)
            .map(|spec| (spec.index, spec.default))
            .collect();
        Self { specs, values }
    }

    /// The table row of an index.
    pub fn spec(&self, index: u16) -> Option<&ParamSpec> {
        self.specs.iter().find(|spec| spec.index == index)
    }

    /// A stored (writable) value; 0 for an unknown index.
    pub fn get(&self, index: u16) -> f64 {
        self.values.get(&index).copied().unwrap_or(0.0)
    }

    /// Set a writable value, clamped into its range (integers rounded). Returns the stored
    /// value, or `None` if the index is unknown or read-only.
    pub fn set(&mut self, index: u16, value: f64) -> Option<f64> {
        let spec = *self.spec(index)?;
        if spec.access == Access::ReadOnly || !value.is_finite() {
            return None;
        }
        let mut stored = value.clamp(spec.min, spec.max);
        if spec.ty != ParamType::F32 {
            stored = stored.round();
        }
        self.values.insert(index, stored);
        Some(stored)
    }

    /// The values a save (type 22) stores.
    pub fn saved_values(&self) -> BTreeMap<u16, f64> {
        self.specs
            .iter()
            .filter(|spec| spec.saved)
            .filter_map(|spec| self.values.get(&spec.index).map(|v| (spec.index, *v)))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robstride::model::RangeTable;

    fn store(model: Model) -> ParamStore {
        ParamStore::new(model, &model.ranges(RangeTable::Manual))
    }

    #[test]
    fn float_values_on_the_wire_are_always_finite() {
        let f = |value: f64| f32::from_le_bytes(encode_value(ParamType::F32, value));
        assert_eq!(f(f64::NAN), 0.0);
        assert_eq!(f(f64::INFINITY), f32::MAX);
        assert_eq!(f(-1e300), f32::MIN);
        assert_eq!(f(1.5), 1.5);
    }

    #[test]
    fn read_only_and_unknown_indices_refuse_writes() {
        let mut params = store(Model::RS03);
        assert_eq!(params.set(index::MECH_POS, 1.0), None);
        assert_eq!(params.set(0x7007, 1.0), None);
        assert_eq!(params.set(index::LIMIT_SPD, 3.0), Some(3.0));
    }

    #[test]
    fn writes_clamp_into_the_model_range() {
        let mut params = store(Model::RS03);
        assert_eq!(params.set(index::SPD_REF, 99.0), Some(20.0));
        assert_eq!(params.set(index::RUN_MODE, 9.0), Some(5.0));
        let mut params = store(Model::RS00);
        assert_eq!(params.set(index::IQ_REF, -99.0), Some(-16.0));
    }

    #[test]
    fn model_specific_rows_exist_only_where_documented() {
        assert!(store(Model::RS01).spec(index::DAMPER).is_none());
        assert!(store(Model::RS01).spec(index::ADD_OFFSET).is_none());
        assert!(store(Model::RS03).spec(index::DAMPER).is_some());
        assert_eq!(store(Model::RS03).get(index::LOC_KP), 60.0);
    }

    #[test]
    fn values_encode_little_endian_by_type() {
        assert_eq!(encode_value(ParamType::F32, 30.0), [0, 0, 0xF0, 0x41]);
        assert_eq!(encode_value(ParamType::U32, 20000.0), [0x20, 0x4E, 0, 0]);
        assert_eq!(encode_value(ParamType::U8, 5.0), [5, 0, 0, 0]);
        assert_eq!(decode_value(ParamType::F32, [0, 0, 0, 0x40]), Some(2.0));
        assert_eq!(decode_value(ParamType::F32, f32::NAN.to_le_bytes()), None);
    }
}
