//! Controller firmware releases the emulator can impersonate and where they differ on the wire
//! (docs/protocols/realman.md §6, §11).

use std::fmt;
use std::str::FromStr;

/// A controller firmware release.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FirmwareProfile {
    /// 3rd-generation controller ≥ V1.6.7: errors as an `err` array everywhere (what SDK ≥ 1.0.5
    /// expects).
    #[default]
    V1_7_0,
    /// Older 3rd-generation firmware (≤ V1.6.6): `arm_err` and `sys_err` integers instead of
    /// the `err` array in `get_current_arm_state`, `get_arm_all_state` and the UDP push.
    V1_6_5,
}

impl FirmwareProfile {
    /// Whether errors are reported as the `err` array (else `arm_err` + `sys_err`).
    pub fn err_array(self) -> bool {
        matches!(self, Self::V1_7_0)
    }

    /// Controller software version string reported by `get_arm_software_info`.
    pub fn ctrl_version(self) -> &'static str {
        match self {
            Self::V1_7_0 => "V1.7.0",
            Self::V1_6_5 => "V1.6.5",
        }
    }

    /// Planning-layer version string reported by `get_arm_software_info`.
    pub fn plan_version(self) -> &'static str {
        match self {
            Self::V1_7_0 => "V1.7.0",
            Self::V1_6_5 => "V1.6.5",
        }
    }
}

impl fmt::Display for FirmwareProfile {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.ctrl_version())
    }
}

/// The name given is not a known firmware release.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown Realman firmware {given:?} (known: V1.7.0, V1.6.5)")]
pub struct UnknownFirmware {
    /// The name given.
    pub given: String,
}

impl FromStr for FirmwareProfile {
    type Err = UnknownFirmware;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().trim_start_matches(['V', 'v']) {
            "1.7.0" | "1.7" => Ok(Self::V1_7_0),
            "1.6.5" | "1.6" => Ok(Self::V1_6_5),
            _ => Err(UnknownFirmware { given: s.into() }),
        }
    }
}
