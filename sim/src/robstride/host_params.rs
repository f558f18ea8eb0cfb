//! The host-tool tables (protocol note §7.2): the 0x20xx configuration block and the 0x30xx
//! observation block, per model, as type 17 (and MIT command 14) serve them.
//!
//! The layouts differ between models: layout A (RS00, RS01, RS02, RS05, EL05) puts CAN_ID at
//! 0x200a and CAN_TIMEOUT at 0x200c, layout B (RS03, RS04, RS06) at 0x2009 and 0x200b; the tails
//! from 0x201a are model specific; RS04's observation block is shifted by one from 0x3010 (an
//! extra filtered speed command). Only rows whose value the emulator models are listed: a row
//! whose meaning the note leaves opaque (echoPara, status2.., ADC offsets, timeUse) is absent and
//! reads with the failure flag, as unknown indices do.
//!
//! Every row is read-only except those that mirror a 0x70xx control parameter (cur_kp, loc_kp,
//! limit_spd, CAN_TIMEOUT, zero_sta, damper, add_offset, …): a type-18 write to such a row
//! writes the 0x70xx parameter, with its range and clamping. Settings the private protocol
//! changes with a command of its own (CAN_ID type 7, CAN_MASTER, baud type 23, protocol_1 type
//! 25, MechOffset type 6) are refused over type 18. The firmware's internal units for the
//! 0x2011.. copies are not documented; the rows show the 0x70xx values in their own units.

use crate::robstride::model::Model;
use crate::robstride::params::index;

/// Wire type of a host-table value (bytes 4..7 of the type-17 reply, little-endian).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HostType {
    /// One byte at `data[4]`.
    U8,
    /// u16 at `data[4..6]`.
    U16,
    /// i16 at `data[4..6]` (temperatures ×10, turn count).
    I16,
    /// u32 at `data[4..8]`.
    U32,
    /// IEEE-754 f32 at `data[4..8]`.
    F32,
}

/// A value of the running motor a row shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Live {
    /// CAN ID in use.
    CanId,
    /// Host ID replies go to.
    CanMaster,
    /// Baud code for the next power-on (1 = 1 Mbit/s … 4 = 125 kbit/s).
    BaudCode,
    /// Protocol for the next power-on (0 private, 1 CANopen, 2 MIT).
    Protocol,
    /// Mechanical zero as an encoder offset, wrapped into [−π, π) (rad).
    MechOffset,
    /// Multi-turn load angle after the zero (rad).
    MechPos,
    /// Load speed (rad/s).
    MechVel,
    /// Angle within one turn, [0, 2π) (rad).
    ModPos,
    /// Whole turns of the load angle (floor(angle / 2π)).
    Rotation,
    /// Torque the motor produces (N·m).
    TorqueFdb,
    /// q-axis current (A).
    Iq,
    /// d-axis current (A): the drive commands 0.
    Id,
    /// Position command in use (rad): loc_ref in PP/CSP, the MIT/operation-control angle
    /// otherwise.
    CmdLocRef,
    /// Speed reference of the speed loop (rad/s).
    CmdSpdRef,
    /// Torque command after limits (N·m).
    CmdTorque,
    /// Operation-control / MIT position setpoint (rad).
    CmdPos,
    /// Operation-control / MIT speed setpoint (rad/s).
    CmdVel,
    /// Supply voltage (V).
    Vbus,
    /// Supply voltage (mV).
    VbusMv,
    /// MCU temperature ×10 (the ambient: the emulator models no MCU heating).
    McuTemp10,
    /// Winding (NTC) temperature ×10.
    MotorTemp10,
    /// Board temperature ×10 (the ambient).
    BoardTemp10,
    /// Latched fault word (§9.1).
    FaultSta,
    /// Warning word.
    WarnSta,
}

/// Where a row's value comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Source {
    /// A 0x70xx control parameter: reads show it, type-18 writes change it.
    Mirror(u16),
    /// A value of the running motor (read-only).
    Live(Live),
    /// A fixed value (read-only).
    Const(f64),
}

/// One row of a host table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HostParam {
    /// Index (0x20xx or 0x30xx).
    pub index: u16,
    /// Name in the host tool's table.
    pub name: &'static str,
    /// Wire type.
    pub ty: HostType,
    /// What it shows.
    pub source: Source,
}

impl HostParam {
    /// Whether a type-18 write may change it (only mirrors of 0x70xx parameters).
    pub fn writable(&self) -> bool {
        matches!(self.source, Source::Mirror(_))
    }
}

const fn row(index: u16, name: &'static str, ty: HostType, source: Source) -> HostParam {
    HostParam {
        index,
        name,
        ty,
        source,
    }
}

use HostType::{F32, I16, U16, U32, U8};
use Source::{Const, Live as L, Mirror as M};

/// 0x2000..0x2008, every model (rows the note gives a meaning for).
const CONFIG_HEAD: &[HostParam] = &[
    row(0x2004, "echoFreHz", U32, Const(500.0)),
    row(0x2005, "MechOffset", F32, L(Live::MechOffset)),
    row(0x2008, "I_FW_MAX", F32, Const(0.0)),
];

/// Layout A (RS00, RS01, RS02, RS05, EL05): 0x2009..0x200c.
const LAYOUT_A_IDS: &[HostParam] = &[
    row(0x2009, "motor_baud", U8, L(Live::BaudCode)),
    row(0x200a, "CAN_ID", U8, L(Live::CanId)),
    row(0x200b, "CAN_MASTER", U8, L(Live::CanMaster)),
    row(0x200c, "CAN_TIMEOUT", U32, M(index::CAN_TIMEOUT)),
];

/// Layout B (RS03, RS04, RS06): 0x2009..0x200b.
const LAYOUT_B_IDS: &[HostParam] = &[
    row(0x2009, "CAN_ID", U8, L(Live::CanId)),
    row(0x200a, "CAN_MASTER", U8, L(Live::CanMaster)),
    row(0x200b, "CAN_TIMEOUT", U32, M(index::CAN_TIMEOUT)),
];

/// 0x2011..0x2019, every model: copies of control parameters.
const CONFIG_LOOPS: &[HostParam] = &[
    row(0x2011, "cur_filt_gain", F32, M(index::CUR_FILT_GAIN)),
    row(0x2012, "cur_kp", F32, M(index::CUR_KP)),
    row(0x2013, "cur_ki", F32, M(index::CUR_KI)),
    row(0x2014, "spd_kp", F32, M(index::SPD_KP)),
    row(0x2015, "spd_ki", F32, M(index::SPD_KI)),
    row(0x2016, "loc_kp", F32, M(index::LOC_KP)),
    row(0x2017, "spd_filt_gain", F32, M(index::SPD_FILT_GAIN)),
    row(0x2018, "limit_spd", F32, M(index::LIMIT_SPD)),
    row(0x2019, "limit_cur", F32, M(index::LIMIT_CUR)),
];

const RS00_TAIL: &[HostParam] = &[
    row(0x201e, "spd_step_value", F32, M(index::ACC_RAD)),
    row(0x201f, "vel_max", F32, M(index::VEL_MAX)),
    row(0x2020, "acc_set", F32, M(index::ACC_SET)),
    row(0x2021, "zero_sta", U8, M(index::ZERO_STA)),
    row(0x2022, "protocol_1", U8, L(Live::Protocol)),
    row(0x2023, "damper", U8, M(index::DAMPER)),
    row(0x2024, "add_offset", F32, M(index::ADD_OFFSET)),
];

const RS02_TAIL: &[HostParam] = &[
    row(0x201e, "zero_sta", U8, M(index::ZERO_STA)),
    row(0x201f, "protocol_1", U8, L(Live::Protocol)),
];

const RS03_TAIL: &[HostParam] = &[
    row(0x201e, "fault4", F32, M(index::ACC_RAD)),
    row(0x201f, "fault5", F32, M(index::VEL_MAX)),
    row(0x2020, "fault6", F32, M(index::ACC_SET)),
    row(0x2022, "baud", U8, L(Live::BaudCode)),
    row(0x2023, "zero_sta", U8, M(index::ZERO_STA)),
    row(0x2025, "protocol_1", U8, L(Live::Protocol)),
    row(0x2026, "damper", U8, M(index::DAMPER)),
    row(0x2027, "add_offset", F32, M(index::ADD_OFFSET)),
];

const RS04_TAIL: &[HostParam] = &[
    row(0x201a, "spd_step_value", F32, M(index::ACC_RAD)),
    row(0x201b, "vel_max", F32, M(index::VEL_MAX)),
    row(0x201c, "acc_set", F32, M(index::ACC_SET)),
    row(0x2024, "baud", U8, L(Live::BaudCode)),
    row(0x2025, "zero_sta", U8, M(index::ZERO_STA)),
    row(0x2027, "protocol_1", U8, L(Live::Protocol)),
    row(0x2028, "damper", U8, M(index::DAMPER)),
    row(0x2029, "add_offset", F32, M(index::ADD_OFFSET)),
];

/// 0x3005..0x300f, every model (0x3007 only on layout-A models, where it is the supply in mV;
/// layout B has the second encoder there).
const OBSERVE_HEAD: &[HostParam] = &[
    row(0x3005, "mcuTemp", I16, L(Live::McuTemp10)),
    row(0x3006, "motorTemp", I16, L(Live::MotorTemp10)),
    row(0x300c, "VBUS", F32, L(Live::Vbus)),
    row(0x300d, "cmdId", F32, L(Live::Id)),
    row(0x300e, "cmdIq", F32, L(Live::Iq)),
    row(0x300f, "cmdlocref", F32, L(Live::CmdLocRef)),
];

/// 0x3010.. on every model but RS04 (RS04 adds `cmdspdreff` and moves the rest up by one).
const OBSERVE_TAIL: &[HostParam] = &[
    row(0x3010, "cmdspdref", F32, L(Live::CmdSpdRef)),
    row(0x3011, "cmdTorque", F32, L(Live::CmdTorque)),
    row(0x3012, "cmdPos", F32, L(Live::CmdPos)),
    row(0x3013, "cmdVel", F32, L(Live::CmdVel)),
    row(0x3014, "rotation", I16, L(Live::Rotation)),
    row(0x3015, "modPos", F32, L(Live::ModPos)),
    row(0x3016, "mechPos", F32, L(Live::MechPos)),
    row(0x3017, "mechVel", F32, L(Live::MechVel)),
    row(0x301e, "iqf", F32, L(Live::Iq)),
    row(0x301f, "boardTemp", I16, L(Live::BoardTemp10)),
    row(0x3020, "iq", F32, L(Live::Iq)),
    row(0x3021, "id", F32, L(Live::Id)),
    row(0x3022, "faultSta", U32, L(Live::FaultSta)),
    row(0x3023, "warnSta", U32, L(Live::WarnSta)),
];

/// Whether a model uses configuration layout A (CyberGear-derived).
pub fn layout_a(model: Model) -> bool {
    matches!(
        model,
        Model::RS00 | Model::RS01 | Model::RS02 | Model::RS05 | Model::EL05
    )
}

/// The index of `torque_fdb` on a model (0x302D on RS06, 0x302C elsewhere).
pub fn torque_fdb_index(model: Model) -> u16 {
    if model == Model::RS06 {
        0x302D
    } else {
        0x302C
    }
}

/// Every row of a model's host tables, sorted by index.
pub fn table(model: Model) -> Vec<HostParam> {
    let spec = model.spec();
    let mut rows: Vec<HostParam> = CONFIG_HEAD.to_vec();
    rows.extend_from_slice(if layout_a(model) {
        LAYOUT_A_IDS
    } else {
        LAYOUT_B_IDS
    });
    rows.extend_from_slice(CONFIG_LOOPS);
    rows.extend_from_slice(match model {
        Model::RS00 => RS00_TAIL,
        Model::RS02 => RS02_TAIL,
        Model::RS03 => RS03_TAIL,
        Model::RS04 => RS04_TAIL,
        // The note gives no tail for RS01, RS05, RS06 and EL05.
        Model::RS01 | Model::RS05 | Model::RS06 | Model::EL05 => &[],
    });
    rows.extend_from_slice(OBSERVE_HEAD);
    if layout_a(model) {
        rows.push(row(0x3007, "vBus", U16, L(Live::VbusMv)));
    }
    if model == Model::RS04 {
        rows.push(OBSERVE_TAIL[0]);
        rows.push(row(0x3011, "cmdspdreff", F32, L(Live::CmdSpdRef)));
        rows.extend(OBSERVE_TAIL[1..].iter().map(|r| HostParam {
            index: r.index + 1,
            ..*r
        }));
    } else {
        rows.extend_from_slice(OBSERVE_TAIL);
    }
    rows.push(row(
        torque_fdb_index(model),
        "torque_fdb",
        F32,
        L(Live::TorqueFdb),
    ));
    // Rows mirroring a parameter the model lacks (damper, add_offset) are absent too.
    rows.retain(|r| match r.source {
        Source::Mirror(index::DAMPER) => spec.has_damper_param,
        Source::Mirror(index::ADD_OFFSET) => spec.has_add_offset_param,
        _ => true,
    });
    rows.sort_by_key(|r| r.index);
    rows
}

/// The row of `index` on `model`, if the emulator serves it.
pub fn lookup(model: Model, index: u16) -> Option<HostParam> {
    if !(0x2000..0x3100).contains(&index) {
        return None;
    }
    table(model).into_iter().find(|r| r.index == index)
}

/// Encode a value into bytes 4..7 (little-endian; integers rounded and saturated, NaN → 0).
pub fn encode(ty: HostType, value: f64) -> [u8; 4] {
    let value = if value.is_nan() { 0.0 } else { value };
    let mut out = [0u8; 4];
    match ty {
        HostType::U8 => out[0] = value.round().clamp(0.0, 255.0) as u8,
        HostType::U16 => {
            out[..2].copy_from_slice(&(value.round().clamp(0.0, 65535.0) as u16).to_le_bytes())
        }
        HostType::I16 => out[..2].copy_from_slice(
            &(value
                .round()
                .clamp(f64::from(i16::MIN), f64::from(i16::MAX)) as i16)
                .to_le_bytes(),
        ),
        HostType::U32 => out
            .copy_from_slice(&(value.round().clamp(0.0, f64::from(u32::MAX)) as u32).to_le_bytes()),
        HostType::F32 => out.copy_from_slice(
            &(value.clamp(f64::from(f32::MIN), f64::from(f32::MAX)) as f32).to_le_bytes(),
        ),
    }
    out
}

/// Decode bytes 4..7 of a write; `None` for a non-finite float.
pub fn decode(ty: HostType, bytes: [u8; 4]) -> Option<f64> {
    match ty {
        HostType::U8 => Some(f64::from(bytes[0])),
        HostType::U16 => Some(f64::from(u16::from_le_bytes([bytes[0], bytes[1]]))),
        HostType::I16 => Some(f64::from(i16::from_le_bytes([bytes[0], bytes[1]]))),
        HostType::U32 => Some(f64::from(u32::from_le_bytes(bytes))),
        HostType::F32 => {
            let value = f32::from_le_bytes(bytes);
            value.is_finite().then_some(f64::from(value))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn name_at(model: Model, index: u16) -> Option<&'static str> {
        lookup(model, index).map(|r| r.name)
    }

    #[test]
    fn the_sdk_indices_exist_on_every_model_but_shift_on_rs04() {
        for model in Model::ALL {
            assert_eq!(name_at(model, 0x2005), Some("MechOffset"), "{model:?}");
            if model == Model::RS04 {
                assert_eq!(name_at(model, 0x3016), Some("modPos"));
                assert_eq!(name_at(model, 0x3017), Some("mechPos"));
                assert_eq!(name_at(model, 0x3018), Some("mechVel"));
                assert_eq!(name_at(model, 0x3023), Some("faultSta"));
            } else {
                assert_eq!(name_at(model, 0x3016), Some("mechPos"), "{model:?}");
                assert_eq!(name_at(model, 0x3017), Some("mechVel"), "{model:?}");
                assert_eq!(name_at(model, 0x3022), Some("faultSta"), "{model:?}");
            }
        }
        assert_eq!(name_at(Model::RS03, 0x302C), Some("torque_fdb"));
        assert_eq!(name_at(Model::RS06, 0x302D), Some("torque_fdb"));
        assert_eq!(name_at(Model::RS06, 0x302C), None);
    }

    #[test]
    fn the_two_configuration_layouts() {
        assert_eq!(name_at(Model::RS00, 0x200a), Some("CAN_ID"));
        assert_eq!(name_at(Model::RS00, 0x200c), Some("CAN_TIMEOUT"));
        assert_eq!(name_at(Model::RS03, 0x2009), Some("CAN_ID"));
        assert_eq!(name_at(Model::RS03, 0x200b), Some("CAN_TIMEOUT"));
        assert_eq!(name_at(Model::RS03, 0x2025), Some("protocol_1"));
        assert_eq!(name_at(Model::RS00, 0x2022), Some("protocol_1"));
        assert_eq!(name_at(Model::RS04, 0x2027), Some("protocol_1"));
        // RS01 has neither damper nor add_offset, so no tail rows for them either.
        assert!(table(Model::RS01)
            .iter()
            .all(|r| !matches!(r.source, Source::Mirror(index::DAMPER))));
    }

    #[test]
    fn only_mirrors_are_writable_and_indices_are_unique() {
        for model in Model::ALL {
            let rows = table(model);
            for pair in rows.windows(2) {
                assert!(pair[0].index < pair[1].index, "{model:?} {pair:?}");
            }
            for r in &rows {
                let observation = r.index >= 0x3000;
                assert!(!(observation && r.writable()), "{model:?} {r:?}");
            }
        }
        assert!(lookup(Model::RS03, 0x200b).unwrap().writable());
        assert!(!lookup(Model::RS03, 0x2009).unwrap().writable());
        assert_eq!(lookup(Model::RS03, 0x1003), None);
        assert_eq!(lookup(Model::RS03, 0x7019), None);
    }

    #[test]
    fn values_encode_by_type() {
        assert_eq!(encode(HostType::I16, -251.0), (-251i16).to_le_bytes_4());
        assert_eq!(encode(HostType::F32, f64::NAN), [0; 4]);
        assert_eq!(encode(HostType::U32, 1.0), [1, 0, 0, 0]);
        assert_eq!(decode(HostType::I16, [0x05, 0xFF, 0, 0]), Some(-251.0));
    }

    trait Le4 {
        fn to_le_bytes_4(self) -> [u8; 4];
    }
    impl Le4 for i16 {
        fn to_le_bytes_4(self) -> [u8; 4] {
            let [a, b] = self.to_le_bytes();
            [a, b, 0, 0]
        }
    }
}
