//! Damiao motor models: the MIT mapping ranges each model's registers 21–23 hold (protocol
//! note §9.1), and the plant facts the emulator drives its shaft with (§9.2 where a source
//! gives them, documented estimates otherwise).
//!
//! Every figure that is an estimate says so in [`ModelSpec::provenance`]: the note's §9.2
//! sources only the DM4310, DM4340 and DM8009 peak torque and speed (OpenArm URDF, a
//! third-party spec page) and the J-series gear ratios (the naming rule); the rotor inertia
//! of no model is published.

use serde::{Deserialize, Serialize};

/// A Damiao motor model, named as the OpenArm and damiao-motor model tables write it.
///
/// `#[allow(non_camel_case_types)]`: the variants are the printed names (`DM4310-48V` becomes
/// `DM4310_48V`), so a reader finds the model they hold in their hand.
#[allow(non_camel_case_types)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum Model {
    /// DM3507 (35 mm frame).
    #[serde(rename = "DM3507")]
    DM3507,
    /// DM-J4310-2EC, 24 V: the OpenArm's wrist and gripper motor (J5–J8).
    #[serde(rename = "DM4310")]
    DM4310,
    /// DM-J4310-2EC on a 48 V supply (wider speed range).
    #[serde(rename = "DM4310-48V")]
    DM4310_48V,
    /// DM-J4340-2EC, 24 V: the OpenArm's J3/J4 motor.
    #[serde(rename = "DM4340")]
    DM4340,
    /// DM-J4340-2EC on a 48 V supply.
    #[serde(rename = "DM4340-48V")]
    DM4340_48V,
    /// DM-J6006.
    #[serde(rename = "DM6006")]
    DM6006,
    /// DM-J8006.
    #[serde(rename = "DM8006")]
    DM8006,
    /// DM-J8009-2EC: the OpenArm's J1/J2 motor.
    #[serde(rename = "DM8009")]
    DM8009,
    /// DM-J10010L (rated 24 V, supports 24–48 V).
    #[serde(rename = "DM10010L")]
    DM10010L,
    /// DM-J10010.
    #[serde(rename = "DM10010")]
    DM10010,
    /// DM-H3510.
    #[serde(rename = "H3510")]
    H3510,
    /// DM-G6215.
    #[serde(rename = "G6215")]
    G6215,
    /// DM-H6220.
    #[serde(rename = "H6220")]
    H6220,
}

/// The MIT mapping ranges of a model: what registers 21–23 (PMAX, VMAX, TMAX) hold at power-on.
/// Command and feedback fields span `[-max, max]`; kp and kd span [`KP_MAX`] and [`KD_MAX`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MitRanges {
    /// PMAX: position range (rad).
    pub p_max_rad: f32,
    /// VMAX: velocity range (rad/s).
    pub v_max_rad_s: f32,
    /// TMAX: torque range (N·m). A mapping range, not necessarily what the motor can produce
    /// (the DM8009 maps ±54 N·m but peaks at 40).
    pub t_max_nm: f32,
}

/// Largest MIT kp (N·m/rad), every model (note §9.1).
pub const KP_MAX: f32 = 500.0;
/// Largest MIT kd (N·m·s/rad), every model (note §9.1).
pub const KD_MAX: f32 = 5.0;

/// What the emulator's plant and registers need to know about a model.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ModelSpec {
    /// The MIT mapping ranges (registers 21–23 at power-on).
    pub ranges: MitRanges,
    /// Peak output torque (N·m): the motor's torque is clamped here whatever TMAX says.
    pub peak_torque_nm: f64,
    /// Rated (continuous) output torque (N·m).
    pub rated_torque_nm: f64,
    /// Gear ratio (register 20, `Gr`).
    pub gear_ratio: f64,
    /// Output speed at which the available torque falls to zero (rad/s): the end of the
    /// torque–speed line, and MAX_SPD's default.
    pub max_speed_rad_s: f64,
    /// Rotor inertia reflected to the output (kg·m²): rotor inertia × gear². Always an
    /// estimate (register 12 `Inertia` has no public value).
    pub rotor_inertia_kg_m2: f64,
    /// Nominal supply voltage (V).
    pub nominal_voltage_v: f64,
    /// Board current at full scale (A, register 59 `Imax`): the base of the force-position
    /// command's per-unit current limit. An estimate.
    pub max_current_a: f64,
    /// Which figures come from a source and which are estimates, in words.
    pub provenance: &'static str,
}

/// Motor-side rotor inertia by frame size (kg·m²), estimates: a thin rotor of the frame's
/// size, steel and magnets. Reflected to the output by the gear ratio squared.
const ROTOR_35MM_KG_M2: f64 = 4.0e-6;
const ROTOR_43MM_KG_M2: f64 = 1.2e-5;
const ROTOR_60MM_KG_M2: f64 = 4.0e-5;
const ROTOR_80MM_KG_M2: f64 = 1.0e-4;
const ROTOR_100MM_KG_M2: f64 = 2.5e-4;

/// Where no source gives the peak torque, it is estimated as this share of TMAX: the sourced
/// models give 7/10 (DM4310), 27/28 (DM4340) and 40/54 (DM8009); the lowest is kept.
const PEAK_SHARE_OF_TMAX: f64 = 0.7;
/// Where no source gives the speed, it is estimated as this share of VMAX: the sourced models
/// give 0.70 (DM4310), 0.54 (DM4340) and 0.37 (DM8009).
const SPEED_SHARE_OF_VMAX: f64 = 0.5;
/// Where no source gives the rated torque, it is estimated as this share of the peak (DM4340:
/// 9 of 27).
const RATED_SHARE_OF_PEAK: f64 = 1.0 / 3.0;

const RPM_TO_RAD_S: f64 = std::f64::consts::TAU / 60.0;

impl Model {
    /// Every model, in the note's §9.1 order.
    pub const ALL: [Model; 13] = [
        Model::DM3507,
        Model::DM4310,
        Model::DM4310_48V,
        Model::DM4340,
        Model::DM4340_48V,
        Model::DM6006,
        Model::DM8006,
        Model::DM8009,
        Model::DM10010L,
        Model::DM10010,
        Model::H3510,
        Model::G6215,
        Model::H6220,
    ];

    /// The model's name as robot files and the model tables write it (`DM4310-48V`).
    pub fn name(self) -> &'static str {
        match self {
            Model::DM3507 => "DM3507",
            Model::DM4310 => "DM4310",
            Model::DM4310_48V => "DM4310-48V",
            Model::DM4340 => "DM4340",
            Model::DM4340_48V => "DM4340-48V",
            Model::DM6006 => "DM6006",
            Model::DM8006 => "DM8006",
            Model::DM8009 => "DM8009",
            Model::DM10010L => "DM10010L",
            Model::DM10010 => "DM10010",
            Model::H3510 => "H3510",
            Model::G6215 => "G6215",
            Model::H6220 => "H6220",
        }
    }

    /// The model a word names, in any case: the table name (`DM4310`, `dm4310-48v`), the
    /// vendor's part number (`DM-J4310-2EC`, `DM-J10010L-2EC`), or the H/G series with the
    /// vendor prefix (`DM-H3510`, `DMH3510`).
    pub fn from_name(word: &str) -> Option<Model> {
        let mut key = word.trim().to_ascii_uppercase();
        // The part number: "DM-J" + frame/gear digits + "-2EC" (the encoder suffix).
        if let Some(rest) = key.strip_prefix("DM-J") {
            key = format!("DM{rest}");
        }
        key = key.replace("-2EC", "");
        for prefix in ["DM-", "DM"] {
            if let Some(rest) = key.strip_prefix(prefix) {
                if rest.starts_with('H') || rest.starts_with('G') {
                    key = rest.to_owned();
                    break;
                }
            }
        }
        Model::ALL.into_iter().find(|m| m.name() == key)
    }

    /// The model `word` names ([`Model::from_name`]), or the message a file reader shows:
    /// "unknown Damiao model `X`; expected one of: DM3507, DM4310, …".
    pub fn named(word: &str) -> Result<Model, String> {
        Model::from_name(word).ok_or_else(|| {
            let known: Vec<&str> = Model::ALL.iter().map(|m| m.name()).collect();
            format!(
                "unknown Damiao model {}; expected one of: {} (or a part number such as DM-J4310-2EC)",
                crate::fault_args::shown_word(word),
                known.join(", ")
            )
        })
    }

    /// The MIT mapping ranges at power-on (note §9.1, openarm_can HEAD and damiao-motor).
    pub fn ranges(self) -> MitRanges {
        let (p, v, t) = match self {
            // damiao-motor writes PMAX 12.566 (4π) for the DM3507, openarm_can 12.5 (§14); the
            // emulator serves 12.5 like every other model, and a host reads register 21.
            Model::DM3507 => (12.5, 50.0, 5.0),
            Model::DM4310 => (12.5, 30.0, 10.0),
            Model::DM4310_48V => (12.5, 50.0, 10.0),
            // VMAX 10 per openarm_can HEAD ("fix DM 4340 table value") and damiao-motor; older
            // openarm_can, LeRobot 0.4.4 and pydamiao say 8 (§14). A host that assumes 8
            // mis-scales velocity by 25 %: it should read register 22.
            Model::DM4340 | Model::DM4340_48V => (12.5, 10.0, 28.0),
            Model::DM6006 => (12.5, 45.0, 20.0),
            Model::DM8006 => (12.5, 45.0, 40.0),
            Model::DM8009 => (12.5, 45.0, 54.0),
            Model::DM10010L => (12.5, 25.0, 200.0),
            Model::DM10010 => (12.5, 20.0, 200.0),
            Model::H3510 => (12.5, 280.0, 1.0),
            Model::G6215 | Model::H6220 => (12.5, 45.0, 10.0),
        };
        MitRanges {
            p_max_rad: p,
            v_max_rad_s: v,
            t_max_nm: t,
        }
    }

    /// Plant and board facts ([`ModelSpec`]); see [`ModelSpec::provenance`] for each model.
    pub fn spec(self) -> ModelSpec {
        let ranges = self.ranges();
        let peak_estimate = PEAK_SHARE_OF_TMAX * f64::from(ranges.t_max_nm);
        let speed_estimate = SPEED_SHARE_OF_VMAX * f64::from(ranges.v_max_rad_s);
        // (peak N·m, rated N·m, gear, speed rad/s, frame rotor, supply V, Imax A, provenance)
        let (peak, rated, gear, speed, rotor, volts, imax, provenance) = match self {
            Model::DM3507 => (
                peak_estimate,
                None,
                7.0,
                speed_estimate,
                ROTOR_35MM_KG_M2,
                24.0,
                6.0,
                "estimated: peak 0.7×TMAX, speed 0.5×VMAX, gear 7 by the J-series naming rule \
                 (not verified for this model), inertia, Imax",
            ),
            Model::DM4310 => (
                7.0,
                None,
                10.0,
                200.0 * RPM_TO_RAD_S,
                ROTOR_43MM_KG_M2,
                24.0,
                10.0,
                "peak 7 N·m and 200 rpm: OpenArm URDF J5–J7; gear 10: naming rule; \
                 estimated: rated, inertia, Imax",
            ),
            Model::DM4310_48V => (
                7.0,
                None,
                10.0,
                speed_estimate,
                ROTOR_43MM_KG_M2,
                48.0,
                10.0,
                "peak as the 24 V DM4310 (same motor); gear 10: naming rule; \
                 estimated: speed 0.5×VMAX, rated, inertia, Imax",
            ),
            Model::DM4340 => (
                27.0,
                Some(9.0),
                40.0,
                52.0 * RPM_TO_RAD_S,
                ROTOR_43MM_KG_M2,
                24.0,
                10.0,
                "rated 9 / peak 27 N·m, 52 rpm at 24 V: sharingwin spec page and OpenArm URDF \
                 J3/J4; gear 40: naming rule; estimated: inertia, Imax",
            ),
            Model::DM4340_48V => (
                27.0,
                Some(9.0),
                40.0,
                // 10.47 rad/s, just past VMAX 10: feedback saturates at full speed.
                100.0 * RPM_TO_RAD_S,
                ROTOR_43MM_KG_M2,
                48.0,
                10.0,
                "rated 9 / peak 27 N·m, 100 rpm at 48 V: sharingwin spec page; gear 40: naming \
                 rule; estimated: inertia, Imax",
            ),
            Model::DM6006 => (
                peak_estimate,
                None,
                6.0,
                speed_estimate,
                ROTOR_60MM_KG_M2,
                24.0,
                20.0,
                "gear 6: naming rule; estimated: peak 0.7×TMAX, speed 0.5×VMAX, rated, \
                 inertia, Imax",
            ),
            Model::DM8006 => (
                peak_estimate,
                None,
                6.0,
                speed_estimate,
                ROTOR_80MM_KG_M2,
                24.0,
                40.0,
                "gear 6: naming rule; estimated: peak 0.7×TMAX, speed 0.5×VMAX, rated, \
                 inertia, Imax",
            ),
            Model::DM8009 => (
                40.0,
                None,
                9.0,
                160.0 * RPM_TO_RAD_S,
                ROTOR_80MM_KG_M2,
                24.0,
                40.0,
                "peak 40 N·m and 160 rpm: OpenArm URDF J1/J2 (TMAX 54 is only the mapping); \
                 gear 9: naming rule; estimated: rated, inertia, Imax",
            ),
            Model::DM10010L => (
                peak_estimate,
                None,
                10.0,
                speed_estimate,
                ROTOR_100MM_KG_M2,
                24.0,
                40.0,
                "gear 10 and 24 V rating: vendor wiki; estimated: peak 0.7×TMAX, speed \
                 0.5×VMAX, rated, inertia, Imax",
            ),
            Model::DM10010 => (
                peak_estimate,
                None,
                10.0,
                speed_estimate,
                ROTOR_100MM_KG_M2,
                48.0,
                40.0,
                "gear 10: naming rule; estimated: peak 0.7×TMAX, speed 0.5×VMAX, supply 48 V, \
                 rated, inertia, Imax",
            ),
            Model::H3510 => (
                peak_estimate,
                None,
                10.0,
                speed_estimate,
                ROTOR_35MM_KG_M2,
                24.0,
                6.0,
                "estimated: everything (gear 10 by the J-series naming rule, not verified)",
            ),
            Model::G6215 => (
                peak_estimate,
                None,
                15.0,
                speed_estimate,
                ROTOR_60MM_KG_M2,
                24.0,
                20.0,
                "estimated: everything (gear 15 by the J-series naming rule, not verified)",
            ),
            Model::H6220 => (
                peak_estimate,
                None,
                20.0,
                speed_estimate,
                ROTOR_60MM_KG_M2,
                24.0,
                20.0,
                "estimated: everything (gear 20 by the J-series naming rule, not verified)",
            ),
        };
        ModelSpec {
            ranges,
            peak_torque_nm: peak,
            rated_torque_nm: rated.unwrap_or(RATED_SHARE_OF_PEAK * peak),
            gear_ratio: gear,
            max_speed_rad_s: speed,
            rotor_inertia_kg_m2: rotor * gear * gear,
            nominal_voltage_v: volts,
            max_current_a: imax,
            provenance,
        }
    }
}

impl std::fmt::Display for Model {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_model_is_found_by_its_name_in_any_case() {
        for model in Model::ALL {
            assert_eq!(Model::from_name(model.name()), Some(model));
            let lower = format!(" {} ", model.name().to_lowercase());
            assert_eq!(Model::from_name(&lower), Some(model), "{lower}");
            // Serde writes the same name.
            let json = serde_json::to_string(&model).unwrap();
            assert_eq!(json, format!("\"{}\"", model.name()));
        }
    }

    #[test]
    fn part_numbers_name_their_model() {
        for (word, model) in [
            ("DM-J4310-2EC", Model::DM4310),
            ("dm-j4340-2ec", Model::DM4340),
            ("DM-J10010L-2EC", Model::DM10010L),
            ("DM-J8009-2EC", Model::DM8009),
            ("DM-H3510", Model::H3510),
            ("DMG6215", Model::G6215),
            ("DM-J4310-2EC-48V", Model::DM4310_48V),
        ] {
            assert_eq!(Model::from_name(word), Some(model), "{word}");
        }
        assert_eq!(Model::from_name("DM4311"), None);
        assert_eq!(Model::from_name("RS03"), None);
    }

    #[test]
    fn an_unknown_name_lists_the_valid_ones() {
        let error = Model::named("DM9999").unwrap_err();
        assert!(error.contains("`DM9999`"), "{error}");
        for model in Model::ALL {
            assert!(error.contains(model.name()), "{error}");
        }
    }

    #[test]
    fn ranges_follow_the_note_and_specs_are_physical() {
        let r = Model::DM4340.ranges();
        assert_eq!((r.p_max_rad, r.v_max_rad_s, r.t_max_nm), (12.5, 10.0, 28.0));
        assert_eq!(Model::DM3507.ranges().p_max_rad, 12.5);
        assert_eq!(Model::DM8009.spec().peak_torque_nm, 40.0);
        assert!((Model::DM4310.spec().max_speed_rad_s - 20.944).abs() < 1e-3);
        for model in Model::ALL {
            let s = model.spec();
            assert!(s.peak_torque_nm > 0.0 && s.peak_torque_nm <= f64::from(s.ranges.t_max_nm));
            // The DM4340-48V's sourced 100 rpm (10.47 rad/s) is just past its VMAX of 10.
            let v_max = f64::from(s.ranges.v_max_rad_s);
            assert!(s.max_speed_rad_s > 0.0 && s.max_speed_rad_s <= 1.05 * v_max);
            assert!(s.rotor_inertia_kg_m2 > 0.0 && s.rated_torque_nm < s.peak_torque_nm);
            assert!(!s.provenance.is_empty());
        }
    }
}
