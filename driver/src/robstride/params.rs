//! The 0x70xx parameters (spec §7.1) with their wire types.

/// Wire type of a parameter value (bytes 4..7 of types 17/18).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParamType {
    /// One byte.
    U8,
    /// Little-endian u16.
    U16,
    /// Little-endian u32.
    U32,
    /// Little-endian f32.
    F32,
}

/// A typed parameter value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ParamValue {
    /// u8 parameter.
    U8(u8),
    /// u16 parameter.
    U16(u16),
    /// u32 parameter.
    U32(u32),
    /// float parameter.
    F32(f32),
}

impl ParamValue {
    /// Bytes 4..7 of a type-18 request.
    pub fn to_bytes(self) -> [u8; 4] {
        match self {
            Self::U8(v) => [v, 0, 0, 0],
            Self::U16(v) => {
                let [a, b] = v.to_le_bytes();
                [a, b, 0, 0]
            }
            Self::U32(v) => v.to_le_bytes(),
            Self::F32(v) => v.to_le_bytes(),
        }
    }

    /// Decode bytes 4..7 of a type-17 reply.
    pub fn from_bytes(ty: ParamType, b: [u8; 4]) -> Self {
        match ty {
            ParamType::U8 => Self::U8(b[0]),
            ParamType::U16 => Self::U16(u16::from_le_bytes([b[0], b[1]])),
            ParamType::U32 => Self::U32(u32::from_le_bytes(b)),
            ParamType::F32 => Self::F32(f32::from_le_bytes(b)),
        }
    }

    /// The value as f64 (any type).
    pub fn as_f64(self) -> f64 {
        match self {
            Self::U8(v) => f64::from(v),
            Self::U16(v) => f64::from(v),
            Self::U32(v) => f64::from(v),
            Self::F32(v) => f64::from(v),
        }
    }

    /// The wire type.
    pub fn ty(self) -> ParamType {
        match self {
            Self::U8(_) => ParamType::U8,
            Self::U16(_) => ParamType::U16,
            Self::U32(_) => ParamType::U32,
            Self::F32(_) => ParamType::F32,
        }
    }
}

/// A control parameter. Its name is the manual's in snake case (`loc_ref`, `epscan_time`).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, strum::IntoStaticStr, strum::VariantArray,
)]
#[strum(serialize_all = "snake_case")]
pub enum Param {
    /// 0x7005 run_mode (u8).
    RunMode,
    /// 0x7006 iq_ref (A).
    IqRef,
    /// 0x700A spd_ref (rad/s).
    SpdRef,
    /// 0x700B limit_torque (N·m).
    LimitTorque,
    /// 0x7010 cur_kp.
    CurKp,
    /// 0x7011 cur_ki.
    CurKi,
    /// 0x7014 cur_filt_gain.
    CurFiltGain,
    /// 0x7016 loc_ref (rad).
    LocRef,
    /// 0x7017 limit_spd (rad/s).
    LimitSpd,
    /// 0x7018 limit_cur (A).
    LimitCur,
    /// 0x7019 mechPos (rad, read-only).
    MechPos,
    /// 0x701A iqf (A, read-only).
    Iqf,
    /// 0x701B mechVel (rad/s, read-only).
    MechVel,
    /// 0x701C VBUS (V, read-only).
    Vbus,
    /// 0x701E loc_kp.
    LocKp,
    /// 0x701F spd_kp.
    SpdKp,
    /// 0x7020 spd_ki.
    SpdKi,
    /// 0x7021 spd_filt_gain.
    SpdFiltGain,
    /// 0x7022 acc_rad (rad/s²).
    AccRad,
    /// 0x7024 vel_max (rad/s).
    VelMax,
    /// 0x7025 acc_set (rad/s²).
    AccSet,
    /// 0x7026 EPScan_time (u16).
    EpscanTime,
    /// 0x7028 canTimeout (u32).
    CanTimeout,
    /// 0x7029 zero_sta (u8).
    ZeroSta,
    /// 0x702A damper (u8).
    Damper,
    /// 0x702B add_offset (rad).
    AddOffset,
    /// 0x702C alveolous_open (u8).
    AlveolousOpen,
    /// 0x702D iq_test (u8).
    IqTest,
    /// 0x702E dcc_set (rad/s²).
    DccSet,
}

impl Param {
    /// The index and wire type.
    pub fn index_and_type(self) -> (u16, ParamType) {
        use ParamType::{F32, U16, U32, U8};
        match self {
            Self::RunMode => (0x7005, U8),
            Self::IqRef => (0x7006, F32),
            Self::SpdRef => (0x700A, F32),
            Self::LimitTorque => (0x700B, F32),
            Self::CurKp => (0x7010, F32),
            Self::CurKi => (0x7011, F32),
            Self::CurFiltGain => (0x7014, F32),
            Self::LocRef => (0x7016, F32),
            Self::LimitSpd => (0x7017, F32),
            Self::LimitCur => (0x7018, F32),
            Self::MechPos => (0x7019, F32),
            Self::Iqf => (0x701A, F32),
            Self::MechVel => (0x701B, F32),
            Self::Vbus => (0x701C, F32),
            Self::LocKp => (0x701E, F32),
            Self::SpdKp => (0x701F, F32),
            Self::SpdKi => (0x7020, F32),
            Self::SpdFiltGain => (0x7021, F32),
            Self::AccRad => (0x7022, F32),
            Self::VelMax => (0x7024, F32),
            Self::AccSet => (0x7025, F32),
            Self::EpscanTime => (0x7026, U16),
            Self::CanTimeout => (0x7028, U32),
            Self::ZeroSta => (0x7029, U8),
            Self::Damper => (0x702A, U8),
            Self::AddOffset => (0x702B, F32),
            Self::AlveolousOpen => (0x702C, U8),
            Self::IqTest => (0x702D, U8),
            Self::DccSet => (0x702E, F32),
        }
    }

    /// The index.
    pub fn index(self) -> u16 {
        self.index_and_type().0
    }

    /// The wire type.
    pub fn ty(self) -> ParamType {
        self.index_and_type().1
    }

    /// Every parameter, in index order.
    pub const ALL: &'static [Param] = <Param as strum::VariantArray>::VARIANTS;

    /// The manual's name in snake case (`run_mode`, `loc_ref`).
    pub fn name(self) -> &'static str {
        self.into()
    }

    /// The parameter at `index` (0x7005 …), if it is one of these.
    pub fn from_index(index: u16) -> Option<Self> {
        Self::ALL.iter().copied().find(|p| p.index() == index)
    }

    /// Read-only parameters (the motor refuses writes).
    pub fn is_read_only(self) -> bool {
        matches!(self, Self::MechPos | Self::Iqf | Self::MechVel | Self::Vbus)
    }
}

#[cfg(test)]
mod name_tests {
    use super::Param;

    #[test]
    fn names_and_indices_find_each_other() {
        assert_eq!(Param::ALL.len(), 29);
        assert_eq!(Param::LocRef.name(), "loc_ref");
        assert_eq!(Param::EpscanTime.name(), "epscan_time");
        assert_eq!(Param::from_index(0x7016), Some(Param::LocRef));
        assert_eq!(Param::from_index(0x7001), None);
        for p in Param::ALL {
            assert_eq!(Param::from_index(p.index()), Some(*p));
        }
    }
}
