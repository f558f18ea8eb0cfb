//! Actuator models and their per-model numbers (scaling ranges, electrical and thermal facts).
//!
//! Ranges follow the RobStride manuals (spec §6.1). The official SDK's different table is
//! available as [`RangeTable::Sdk`] because real clients copied it; the spec says the manual
//! is right on hardware, so [`RangeTable::Manual`] is the default.

use serde::{Deserialize, Serialize};

/// A RobStride actuator model; its name is the variant's, as printed on the actuator.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    PartialOrd,
    Ord,
    Hash,
    Serialize,
    Deserialize,
    strum::EnumString,
    strum::IntoStaticStr,
)]
#[strum(ascii_case_insensitive)]
pub enum Model {
    /// RS00: 14 N·m peak.
    RS00,
    /// RS01: 17 N·m peak, 36 V.
    RS01,
    /// RS02: 17 N·m peak.
    RS02,
    /// RS03: 60 N·m peak.
    RS03,
    /// RS04: 120 N·m peak.
    RS04,
    /// RS05: 5.5 N·m peak.
    RS05,
    /// RS06: 36 N·m peak.
    RS06,
    /// EL05 ("EduLite05"): 6 N·m peak, shares the protocol.
    EL05,
}

impl Model {
    /// Every model, in order.
    pub const ALL: [Model; 8] = [
        Model::RS00,
        Model::RS01,
        Model::RS02,
        Model::RS03,
        Model::RS04,
        Model::RS05,
        Model::RS06,
        Model::EL05,
    ];

    /// Parse a model name such as `RS03` or `rs03` (CLI and configs).
    pub fn from_name(name: &str) -> Option<Self> {
        name.trim().parse().ok()
    }

    /// The model called `name`, or the message every file reader shows for a name it does not
    /// know: "unknown RobStride model `X`; expected one of: RS00, …".
    pub fn named(name: &str) -> Result<Self, String> {
        Self::from_name(name).ok_or_else(|| {
            let known: Vec<&str> = Self::ALL.iter().map(|m| m.name()).collect();
            format!(
                "unknown RobStride model `{name}`; expected one of: {}",
                known.join(", ")
            )
        })
    }

    /// The model's name as printed on the actuator.
    pub fn name(self) -> &'static str {
        self.into()
    }

    /// The scaling ranges of operation-control commands and status frames.
    pub fn ranges(self, table: RangeTable) -> Ranges {
        // (angle, speed, torque, kp max, kd max, current) — spec §6.1.
        let (speed, torque, kp, kd, current) = match (self, table) {
            (Model::RS00, RangeTable::Manual) => (33.0, 14.0, 500.0, 5.0, 16.0),
            (Model::RS00, RangeTable::Sdk) => (50.0, 17.0, 500.0, 5.0, 16.0),
            (Model::RS01 | Model::RS02, _) => (44.0, 17.0, 500.0, 5.0, 23.0),
            (Model::RS03, RangeTable::Manual) => (20.0, 60.0, 5000.0, 100.0, 43.0),
            (Model::RS03, RangeTable::Sdk) => (50.0, 60.0, 5000.0, 100.0, 43.0),
            (Model::RS04, _) => (15.0, 120.0, 5000.0, 100.0, 90.0),
            (Model::RS05, RangeTable::Manual) => (50.0, 5.5, 500.0, 5.0, 11.0),
            (Model::RS05, RangeTable::Sdk) => (33.0, 17.0, 500.0, 5.0, 11.0),
            (Model::RS06, RangeTable::Manual) => (50.0, 36.0, 5000.0, 100.0, 57.0),
            (Model::RS06, RangeTable::Sdk) => (20.0, 60.0, 5000.0, 100.0, 57.0),
            (Model::EL05, _) => (50.0, 6.0, 500.0, 5.0, 11.0),
        };
        Ranges {
            angle_rad: ANGLE_RANGE_RAD,
            speed_rad_s: speed,
            torque_nm: torque,
            kp_max: kp,
            kd_max: kd,
            current_a: current,
        }
    }

    /// Electrical, thermal and firmware facts of the model (spec §6.3, §9.1).
    pub fn spec(self) -> ModelSpec {
        // (Kt N·m/A, rated A, peak A, max V, OT fault °C, OT warning °C, firmware)
        let (kt, rated, peak, max_v, fault_c, warn_c, fw) = match self {
            Model::RS00 => (1.48, 4.7, 15.5, 60.0, 145.0, 135.0, [0, 0, 3, 27]),
            Model::RS01 => (1.22, 7.0, 23.0, 50.0, 103.0, 93.0, [0, 1, 3, 14]),
            Model::RS02 => (1.22, 7.0, 23.0, 60.0, 135.0, 135.0, [0, 2, 3, 32]),
            Model::RS03 => (2.36, 13.0, 43.0, 60.0, 145.0, 135.0, [0, 3, 1, 41]),
            Model::RS04 => (2.1, 27.0, 90.0, 60.0, 145.0, 145.0, [0, 4, 1, 29]),
            Model::RS05 => (0.94, 2.4, 11.0, 60.0, 135.0, 135.0, [0, 5, 0, 13]),
            Model::RS06 => (1.09, 14.3, 57.0, 60.0, 145.0, 145.0, [0, 6, 0, 11]),
            Model::EL05 => (0.94, 2.6, 11.0, 60.0, 135.0, 135.0, [1, 0, 5, 4]),
        };
        // (peak torque N·m, no-load output speed rpm) — spec §6.3.
        let (peak_torque_nm, no_load_rpm) = match self {
            Model::RS00 => (14.0, 315.0),
            Model::RS01 => (17.0, 315.0),
            Model::RS02 => (17.0, 410.0),
            Model::RS03 => (60.0, 200.0),
            Model::RS04 => (120.0, 200.0),
            Model::RS05 => (5.5, 480.0),
            Model::RS06 => (36.0, 480.0),
            Model::EL05 => (6.0, 430.0),
        };
        ModelSpec {
            peak_torque_nm,
            no_load_speed_rad_s: no_load_rpm * std::f64::consts::TAU / 60.0,
            torque_constant_nm_per_a: kt,
            rated_current_a: rated,
            peak_current_a: peak,
            under_voltage_v: 12.0,
            over_voltage_v: max_v,
            nominal_voltage_v: if self == Model::RS01 { 36.0 } else { 48.0 },
            over_temp_fault_c: fault_c,
            over_temp_warning_c: warn_c,
            firmware_version: fw,
            // The rotor's inertia reflected through the gearbox is not published; a small value
            // keeps a free-spinning motor from being a massless (infinitely fast) body.
            rotor_inertia_kg_m2: 2.0e-4 * kt,
            has_damper_param: !matches!(self, Model::RS01 | Model::RS05 | Model::EL05),
            has_add_offset_param: self != Model::RS01,
        }
    }

    /// Default position-loop gain `loc_kp` (spec §7.1; RS04 follows the CN manual).
    pub fn default_loc_kp(self) -> f32 {
        match self {
            Model::RS03 => 60.0,
            Model::RS04 => 80.0,
            _ => 40.0,
        }
    }

    /// Default velocity-mode acceleration `acc_rad` (spec §7.1; RS04 follows the CN manual).
    pub fn default_acc_rad(self) -> f32 {
        if self == Model::RS04 {
            10.0
        } else {
            20.0
        }
    }
}

/// The angle range P of every model in the current manuals (±4π, printed as 12.57).
pub const ANGLE_RANGE_RAD: f32 = 4.0 * std::f32::consts::PI;

/// Which scaling table to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum RangeTable {
    /// The RobStride user manuals (hardware agrees): the default.
    #[default]
    Manual,
    /// The official Python SDK / ROS sample table (differs for RS00, RS03, RS05, RS06).
    Sdk,
}

/// Scaling ranges of the private protocol's 16-bit fields (symmetric ±, or 0..max for gains).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Ranges {
    /// Angle range P (rad): fields span −P..+P.
    pub angle_rad: f32,
    /// Speed range V (rad/s).
    pub speed_rad_s: f32,
    /// Torque range T (N·m).
    pub torque_nm: f32,
    /// Largest operation-control Kp (N·m/rad).
    pub kp_max: f32,
    /// Largest operation-control Kd (N·m·s/rad).
    pub kd_max: f32,
    /// Current range (A) of iq_ref and limit_cur.
    pub current_a: f32,
}

/// Electrical, thermal and firmware facts of a model.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ModelSpec {
    /// Torque constant (N·m per A of iq), manual §1.
    pub torque_constant_nm_per_a: f64,
    /// Rated phase current (A).
    pub rated_current_a: f64,
    /// Peak phase current (A).
    pub peak_current_a: f64,
    /// Under-voltage fault threshold (V).
    pub under_voltage_v: f64,
    /// Over-voltage fault threshold (V).
    pub over_voltage_v: f64,
    /// Nominal supply voltage (V).
    pub nominal_voltage_v: f64,
    /// Over-temperature fault threshold (°C).
    pub over_temp_fault_c: f64,
    /// Over-temperature warning threshold (°C).
    pub over_temp_warning_c: f64,
    /// Firmware version reported by the version read (one byte per dotted field).
    pub firmware_version: [u8; 4],
    /// Rotor inertia reflected to the output (kg·m²), an assumption (not published).
    pub rotor_inertia_kg_m2: f64,
    /// Peak output torque (N·m), the stall end of the torque–speed line.
    pub peak_torque_nm: f64,
    /// No-load output speed at the nominal supply voltage (rad/s): where the torque–speed
    /// line reaches zero torque.
    pub no_load_speed_rad_s: f64,
    /// Whether parameter 0x702A `damper` exists on this model.
    pub has_damper_param: bool,
    /// Whether parameter 0x702B `add_offset` exists on this model.
    pub has_add_offset_param: bool,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_model_is_found_by_its_name_in_any_case() {
        for model in Model::ALL {
            let name = model.name();
            assert_eq!(name, format!("{model:?}"));
            assert_eq!(Model::from_name(name), Some(model));
            assert_eq!(
                Model::from_name(&format!(" {} ", name.to_lowercase())),
                Some(model)
            );
        }
        assert_eq!(Model::from_name("RS07"), None);
    }
}
