//! The motor's registers (docs/protocols/damiao.md §6): RID, name, wire type and access.

use std::fmt;

/// How a register's four value bytes read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum RegisterKind {
    /// Unsigned 32-bit integer, little-endian.
    U32,
    /// IEEE-754 single, little-endian.
    F32,
}

impl RegisterKind {
    /// The wire type of any RID: u32 for 7–10, 13–16 and 35–36, f32 for every other.
    pub fn of_rid(rid: u8) -> Self {
        match rid {
            7..=10 | 13..=16 | 35..=36 => Self::U32,
            _ => Self::F32,
        }
    }
}

impl fmt::Display for RegisterKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::U32 => "u32",
            Self::F32 => "f32",
        })
    }
}

/// A register value as the wire carries it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RegisterValue {
    /// An integer register's value.
    U32(u32),
    /// A real register's value.
    F32(f32),
}

impl RegisterValue {
    /// The value's wire type.
    pub fn kind(self) -> RegisterKind {
        match self {
            Self::U32(_) => RegisterKind::U32,
            Self::F32(_) => RegisterKind::F32,
        }
    }

    /// The four value bytes (D4..D7), little-endian.
    pub fn to_bytes(self) -> [u8; 4] {
        match self {
            Self::U32(v) => v.to_le_bytes(),
            Self::F32(v) => v.to_le_bytes(),
        }
    }

    /// The value of four bytes read as `kind`.
    pub fn from_bytes(kind: RegisterKind, bytes: [u8; 4]) -> Self {
        match kind {
            RegisterKind::U32 => Self::U32(u32::from_le_bytes(bytes)),
            RegisterKind::F32 => Self::F32(f32::from_le_bytes(bytes)),
        }
    }

    /// The value as a real (integers convert exactly up to 2^53).
    pub fn as_f64(self) -> f64 {
        match self {
            Self::U32(v) => f64::from(v),
            Self::F32(v) => f64::from(v),
        }
    }
}

macro_rules! registers {
    ($($(#[$doc:meta])* $variant:ident = $rid:literal, $name:literal, $rw:literal;)*) => {
        /// A named register of the Damiao firmware.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum Register {
            $($(#[$doc])* $variant,)*
        }

        impl Register {
            /// Every named register, by RID.
            pub const ALL: &'static [Register] = &[$(Self::$variant,)*];

            /// The register's ID (D3 of a register frame).
            pub fn rid(self) -> u8 {
                match self { $(Self::$variant => $rid,)* }
            }

            /// The firmware's name (`CTRL_MODE`, `KT_Value`).
            pub fn name(self) -> &'static str {
                match self { $(Self::$variant => $name,)* }
            }

            /// True when the host may write the register.
            pub fn writable(self) -> bool {
                match self { $(Self::$variant => $rw,)* }
            }
        }
    };
}

registers! {
    /// Under-voltage threshold (V).
    UvValue = 0, "UV_Value", true;
    /// Torque constant.
    KtValue = 1, "KT_Value", true;
    /// Over-temperature threshold (°C).
    OtValue = 2, "OT_Value", true;
    /// Over-current threshold (per unit).
    OcValue = 3, "OC_Value", true;
    /// Acceleration of the position-velocity mode (> 0).
    Acc = 4, "ACC", true;
    /// Deceleration of the position-velocity mode (< 0).
    Dec = 5, "DEC", true;
    /// Maximum speed.
    MaxSpd = 6, "MAX_SPD", true;
    /// Feedback identifier (u32).
    MstId = 7, "MST_ID", true;
    /// Command identifier (u32).
    EscId = 8, "ESC_ID", true;
    /// CAN timeout in 50 µs units, 0 = off (u32).
    Timeout = 9, "TIMEOUT", true;
    /// Control mode: 1 MIT, 2 position-velocity, 3 velocity, 4 force-position (u32).
    CtrlMode = 10, "CTRL_MODE", true;
    /// Motor viscous damping.
    Damp = 11, "Damp", false;
    /// Motor inertia.
    Inertia = 12, "Inertia", false;
    /// Hardware version (u32).
    HwVer = 13, "hw_ver", false;
    /// Software version (u32).
    SwVer = 14, "sw_ver", false;
    /// Serial number (u32).
    Sn = 15, "SN", false;
    /// Pole pairs (u32).
    Npp = 16, "NPP", false;
    /// Phase resistance.
    Rs = 17, "Rs", false;
    /// Phase inductance.
    Ls = 18, "LS", false;
    /// Flux linkage.
    Flux = 19, "Flux", false;
    /// Gear ratio.
    Gr = 20, "Gr", false;
    /// MIT position range PMAX (rad).
    Pmax = 21, "PMAX", true;
    /// MIT velocity range VMAX (rad/s).
    Vmax = 22, "VMAX", true;
    /// MIT torque range TMAX (N·m).
    Tmax = 23, "TMAX", true;
    /// Current-loop bandwidth.
    IBw = 24, "I_BW", true;
    /// Speed-loop proportional gain.
    KpAsr = 25, "KP_ASR", true;
    /// Speed-loop integral gain.
    KiAsr = 26, "KI_ASR", true;
    /// Position-loop proportional gain.
    KpApr = 27, "KP_APR", true;
    /// Position-loop integral gain.
    KiApr = 28, "KI_APR", true;
    /// Over-voltage threshold (V).
    OvValue = 29, "OV_Value", true;
    /// Gear torque efficiency.
    Gref = 30, "GREF", true;
    /// Speed-loop damping.
    Deta = 31, "Deta", true;
    /// Speed-loop filter bandwidth.
    VBw = 32, "V_BW", true;
    /// Current-loop enhancement.
    IqC1 = 33, "IQ_c1", true;
    /// Speed-loop enhancement.
    VlC1 = 34, "VL_c1", true;
    /// CAN bit-rate code: 0 125k, 1 200k, 2 250k, 3 500k, 4 1M (u32).
    CanBr = 35, "can_br", true;
    /// Sub-version (u32).
    SubVer = 36, "sub_ver", false;
    /// Calibration: u offset.
    UOff = 50, "u_off", false;
    /// Calibration: v offset.
    VOff = 51, "v_off", false;
    /// Calibration: k1.
    K1 = 52, "k1", false;
    /// Calibration: k2.
    K2 = 53, "k2", false;
    /// Calibration: angle offset.
    MOff = 54, "m_off", false;
    /// Calibration: direction.
    Dir = 55, "dir", false;
    /// Board: current limit Imax.
    Imax = 59, "Imax", false;
    /// Board: bus voltage.
    VBus = 60, "VBus", false;
    /// Board: PCB temperature.
    Tpcb = 61, "Tpcb", false;
    /// Board: motor temperature.
    Tmtr = 62, "Tmtr", false;
    /// Board: phase u current offset.
    IuOff = 63, "Iu_off", false;
    /// Board: phase v current offset.
    IvOff = 64, "Iv_off", false;
    /// Board: phase w current offset.
    IwOff = 65, "Iw_off", false;
    /// Motor-side position.
    PM = 80, "p_m", false;
    /// Output position.
    Xout = 81, "xout", false;
}

impl Register {
    /// The register with this RID, if it has a name here.
    pub fn from_rid(rid: u8) -> Option<Self> {
        Self::ALL.iter().copied().find(|r| r.rid() == rid)
    }

    /// The register's wire type.
    pub fn kind(self) -> RegisterKind {
        RegisterKind::of_rid(self.rid())
    }
}

impl fmt::Display for Register {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} (RID {})", self.name(), self.rid())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rids_are_unique_and_round_trip() {
        for (i, r) in Register::ALL.iter().enumerate() {
            assert_eq!(Register::from_rid(r.rid()), Some(*r));
            assert!(Register::ALL[..i].iter().all(|o| o.rid() != r.rid()));
        }
        assert_eq!(Register::from_rid(37), None);
        assert_eq!(Register::CtrlMode.kind(), RegisterKind::U32);
        assert_eq!(Register::KtValue.kind(), RegisterKind::F32);
        assert_eq!(Register::CanBr.kind(), RegisterKind::U32);
        assert!(!Register::Gr.writable() && Register::Pmax.writable());
    }
}
