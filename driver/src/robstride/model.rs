//! Per-model scaling ranges the driver encodes commands with and decodes feedback with.
//!
//! The manual table (spec §6.1) is the default; the official SDK's table is selectable because
//! some firmware/clients use it.

/// A RobStride actuator model; its name is the variant's (`RS03`, any case).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, strum::EnumString)]
#[strum(ascii_case_insensitive)]
pub enum Model {
    /// RS00 (14 N·m).
    RS00,
    /// RS01 (17 N·m).
    RS01,
    /// RS02 (17 N·m).
    RS02,
    /// RS03 (60 N·m).
    RS03,
    /// RS04 (120 N·m).
    RS04,
    /// RS05 (5.5 N·m).
    RS05,
    /// RS06 (36 N·m).
    RS06,
    /// EL05 (6 N·m).
    EL05,
}

/// Which published range table to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RangeTable {
    /// RobStride user manuals (default; hardware agrees).
    #[default]
    Manual,
    /// Official Python SDK / ROS sample.
    Sdk,
}

/// Symmetric scaling ranges (±) and gain maxima of one model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ranges {
    /// Angle P (rad).
    pub angle_rad: f32,
    /// Speed V (rad/s).
    pub speed_rad_s: f32,
    /// Torque T (N·m).
    pub torque_nm: f32,
    /// Kp maximum.
    pub kp_max: f32,
    /// Kd maximum.
    pub kd_max: f32,
    /// Current range (A) for iq_ref and limit_cur.
    pub current_a: f32,
}

impl Model {
    /// Parse `RS03` / `rs03` / `EL05`.
    pub fn parse(name: &str) -> Option<Self> {
        name.trim().parse().ok()
    }

    /// The model's ranges in `table`.
    pub fn ranges(self, table: RangeTable) -> Ranges {
        let manual = matches!(table, RangeTable::Manual);
        // (V, T, Kp max, Kd max, current)
        let (v, t, kp, kd, i) = match self {
            Self::RS00 if manual => (33.0, 14.0, 500.0, 5.0, 16.0),
            Self::RS00 => (50.0, 17.0, 500.0, 5.0, 16.0),
            Self::RS01 | Self::RS02 => (44.0, 17.0, 500.0, 5.0, 23.0),
            Self::RS03 if manual => (20.0, 60.0, 5000.0, 100.0, 43.0),
            Self::RS03 => (50.0, 60.0, 5000.0, 100.0, 43.0),
            Self::RS04 => (15.0, 120.0, 5000.0, 100.0, 90.0),
            Self::RS05 if manual => (50.0, 5.5, 500.0, 5.0, 11.0),
            Self::RS05 => (33.0, 17.0, 500.0, 5.0, 11.0),
            Self::RS06 if manual => (50.0, 36.0, 5000.0, 100.0, 57.0),
            Self::RS06 => (20.0, 60.0, 5000.0, 100.0, 57.0),
            Self::EL05 => (50.0, 6.0, 500.0, 5.0, 11.0),
        };
        Ranges {
            angle_rad: 4.0 * std::f32::consts::PI,
            speed_rad_s: v,
            torque_nm: t,
            kp_max: kp,
            kd_max: kd,
            current_a: i,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn models_parse_by_name_in_any_case() {
        assert_eq!(Model::parse("RS03"), Some(Model::RS03));
        assert_eq!(Model::parse(" el05 "), Some(Model::EL05));
        assert_eq!(Model::parse("rs00"), Some(Model::RS00));
        assert_eq!(Model::parse("RS07"), None);
    }
}
