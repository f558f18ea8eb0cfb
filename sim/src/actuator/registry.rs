//! The actuator kinds a robot joint can be driven by, the model names each answers to, and
//! the settings of one actuator a robot carries. A robot file's `model:` is looked up here
//! ([`configure`]); adding a kind is a variant of [`ActuatorConfig`] and a line in [`KINDS`].

use super::{ActuatorFirmware, ShaftPlant};
use crate::damiao::faults::{self as damiao_faults, Thresholds};
use crate::damiao::{DamiaoMotor, Model as DamiaoModel, MotorConfig as DamiaoConfig};
use crate::fault_args::{FaultArgError, FaultArgs};
use crate::fault_desk::FaultInfo;
use crate::robstride::state_file::{uid_key, StateFile};
use crate::robstride::Fault as RobstrideFault;
use crate::robstride::{Actuator, Model as RobstrideModel, MotorConfig as RobstrideConfig};
use crate::yaml_words::suggestion;

/// Facts about one actuator model a robot needs before its firmware runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ActuatorModel {
    /// The kind's name (`robstride`).
    pub kind: &'static str,
    /// Its name as robot files write it (`RS03`, `DM4310`).
    pub name: &'static str,
    /// Peak torque (N·m): a robot file warns when below its joint's URDF effort.
    pub peak_torque_nm: f64,
    /// Rotor inertia reflected to the output (kg·m²): the joint's armature.
    pub rotor_inertia_kg_m2: f64,
}

/// An actuator kind: its name, its models, the CAN identifiers a robot file may give it.
#[derive(Debug)]
pub struct ActuatorKind {
    /// The kind's name (`robstride`).
    pub name: &'static str,
    /// Every model it answers to, as robot files write them.
    pub model_names: fn() -> Vec<&'static str>,
    /// The identifiers a robot file may give (both ends included).
    pub ids: (u32, u32),
    /// The settings of a `model` (a name [`Self::model_names`] lists, any case) on `can_id`;
    /// `None` when the kind has no such model.
    pub configure: fn(model: &str, can_id: u32) -> Option<ActuatorConfig>,
    /// The bit rates (bit/s) its actuators run a bus at.
    pub bitrates_bps: &'static [u32],
    /// Whether its CAN controllers take CAN FD frames (a classic one on an FD bus destroys
    /// every FD frame with an error frame).
    pub fd: bool,
    /// The fault table of a `model` actuator at power-on (what its firmware's
    /// [`super::ActuatorFirmware::fault_table`] says), for a front end to offer before a
    /// robot runs.
    pub faults: fn(model: &str) -> Vec<FaultInfo>,
    /// The fault `name` with `args` (its values only) checked as a `model` actuator's firmware
    /// at power-on takes it, and how a front end shows it applied (`encoder_glitch 100
    /// counts`); `clearing`: its values may be left out (clearing removes the cause whatever
    /// its size).
    pub fault_label: fn(
        model: &str,
        name: &str,
        args: &FaultArgs,
        clearing: bool,
    ) -> Result<String, FaultArgError>,
}

impl ActuatorKind {
    /// Whether a `model` actuator's table has a fault `name`.
    pub fn has_fault(&self, model: &str, name: &str) -> bool {
        (self.faults)(model).iter().any(|f| f.name == name)
    }
}

/// The kind named `name`.
pub fn kind_named(name: &str) -> Option<&'static ActuatorKind> {
    KINDS.iter().copied().find(|k| k.name == name)
}

/// Every actuator kind, in the order a model name is looked up.
pub static KINDS: &[&ActuatorKind] = &[&ROBSTRIDE, &DAMIAO];

/// RobStride's quasi-direct-drive actuators (private protocol, MIT and CANopen variants).
pub static ROBSTRIDE: ActuatorKind = ActuatorKind {
    name: crate::robstride::ACTUATOR_KIND,
    model_names: || RobstrideModel::ALL.iter().map(|m| m.name()).collect(),
    ids: (1, 0x7F),
    configure: |model, can_id| {
        let model = RobstrideModel::from_name(model)?;
        let can_id = u8::try_from(can_id).unwrap_or(u8::MAX);
        Some(ActuatorConfig::Robstride(RobstrideConfig::new(
            can_id, model,
        )))
    },
    bitrates_bps: &[1_000_000, 500_000, 250_000, 125_000],
    fd: false,
    faults: |_| crate::robstride::faults::actuator_fault_table(),
    fault_label: |_, name, args, clearing| {
        let fault = RobstrideFault::named(name)?;
        let names: Vec<&str> = fault.values().iter().map(|p| p.name).collect();
        args.only(name, &names)?;
        Ok(if clearing {
            fault.name().to_owned()
        } else {
            fault.with_values(args)?.label()
        })
    },
};

/// Damiao's joint motors (MIT, position-velocity, velocity and force-position on 11-bit
/// identifiers): the OpenArm's.
pub static DAMIAO: ActuatorKind = ActuatorKind {
    name: crate::damiao::KIND,
    model_names: || DamiaoModel::ALL.iter().map(|m| m.name()).collect(),
    // The force-position command goes to 0x300 + id, which must stay below the register
    // identifier 0x7FF.
    ids: (1, 0x4FE),
    bitrates_bps: &[1_000_000, 500_000, 250_000, 200_000, 125_000],
    fd: true,
    configure: |model, can_id| {
        let model = DamiaoModel::from_name(model)?;
        let esc_id = u16::try_from(can_id).unwrap_or(u16::MAX);
        Some(ActuatorConfig::Damiao(DamiaoConfig::new(esc_id, model)))
    },
    faults: |model| damiao_faults::table(&damiao_limits(model)),
    fault_label: |model, name, args, clearing| {
        let limits = damiao_limits(model);
        let fault = damiao_faults::Fault::named(name)?;
        if clearing {
            fault.build_to_clear(args, &limits)?;
            Ok(fault.name().to_owned())
        } else {
            fault.build(args, &limits)?;
            Ok(shown_with_values(fault.name(), args))
        }
    },
};

/// A Damiao `model`'s fault thresholds at power-on (a DM4310's for a name it does not know).
fn damiao_limits(model: &str) -> Thresholds {
    Thresholds::power_on(DamiaoModel::from_name(model).unwrap_or(DamiaoModel::DM4310))
}

/// `name` followed by its values as given (`over_voltage voltage_v=60`).
fn shown_with_values(name: &str, args: &FaultArgs) -> String {
    let mut shown = name.to_owned();
    for (arg, value) in args.iter() {
        shown.push_str(&format!(" {arg}={value}"));
    }
    shown
}

/// Why a robot file's actuator has no settings.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConfigureError {
    /// No kind makes a model of this name.
    #[error("no actuator model `{model}` (known: {}){suggestion}", known.join(", "))]
    UnknownModel {
        /// The name given.
        model: String,
        /// Every model of every kind.
        known: Vec<&'static str>,
        /// `; did you mean …?` with the nearest name, or nothing.
        suggestion: String,
    },
    /// The model's kind takes no such identifier.
    #[error("a {kind} actuator's id must be {low}..={high}, got {can_id}")]
    IdOutOfRange {
        /// The kind.
        kind: &'static str,
        /// The identifier given.
        can_id: u32,
        /// The lowest it takes.
        low: u32,
        /// The highest.
        high: u32,
    },
}

/// The settings of `model` on `can_id`, from whichever kind makes it.
pub fn configure(model: &str, can_id: u32) -> Result<ActuatorConfig, ConfigureError> {
    for kind in KINDS {
        if let Some(config) = (kind.configure)(model, can_id) {
            let (low, high) = kind.ids;
            if !(low..=high).contains(&can_id) {
                return Err(ConfigureError::IdOutOfRange {
                    kind: kind.name,
                    can_id,
                    low,
                    high,
                });
            }
            return Ok(config);
        }
    }
    let known: Vec<&str> = KINDS.iter().flat_map(|k| (k.model_names)()).collect();
    Err(ConfigureError::UnknownModel {
        model: model.to_owned(),
        suggestion: suggestion(model, &known),
        known,
    })
}

/// How a robot powers an actuator on.
pub struct PowerOn<'a> {
    /// The name of its bus.
    pub bus: &'a str,
    /// Bit rate of its bus (bit/s).
    pub bitrate_bps: u32,
    /// The host identifier replies go to at first power-on, where the kind has one.
    pub host_id: u8,
    /// What the robot's state file kept of earlier runs.
    pub kept: &'a StateFile,
}

/// The firmware settings of one actuator a robot carries: one variant per kind of [`KINDS`].
#[derive(Debug, Clone, PartialEq)]
pub enum ActuatorConfig {
    /// A RobStride actuator (its `load` and rig fields are unused: the robot is the load).
    Robstride(RobstrideConfig),
    /// A Damiao motor (its `load` and rig fields are unused: the robot is the load).
    Damiao(DamiaoConfig),
}

impl ActuatorConfig {
    /// Its kind.
    pub fn kind(&self) -> &'static ActuatorKind {
        match self {
            Self::Robstride(_) => &ROBSTRIDE,
            Self::Damiao(_) => &DAMIAO,
        }
    }

    /// The CAN identifier at first power-on (a state file may hold a newer one).
    pub fn can_id(&self) -> u32 {
        match self {
            Self::Robstride(m) => u32::from(m.can_id),
            Self::Damiao(m) => u32::from(m.esc_id),
        }
    }

    /// The model's facts.
    pub fn model(&self) -> ActuatorModel {
        match self {
            Self::Robstride(m) => {
                let spec = m.model.spec();
                ActuatorModel {
                    kind: ROBSTRIDE.name,
                    name: m.model.name(),
                    peak_torque_nm: spec.peak_torque_nm,
                    rotor_inertia_kg_m2: spec.rotor_inertia_kg_m2,
                }
            }
            Self::Damiao(m) => {
                let spec = m.model.spec();
                ActuatorModel {
                    kind: DAMIAO.name,
                    name: m.model.name(),
                    peak_torque_nm: spec.peak_torque_nm,
                    rotor_inertia_kg_m2: spec.rotor_inertia_kg_m2,
                }
            }
        }
    }

    /// The RobStride settings, when it is one.
    pub fn robstride(&self) -> Option<&RobstrideConfig> {
        match self {
            Self::Robstride(m) => Some(m),
            Self::Damiao(_) => None,
        }
    }

    /// The CAN identifier it answers on at power-on on bus `bus`, after what the state file
    /// kept.
    pub fn power_on_id(&self, bus: &str, kept: &StateFile) -> u32 {
        match self {
            Self::Robstride(m) => u32::from(kept.power_on_id(m)),
            Self::Damiao(m) => {
                kept_damiao(m, bus, kept).map_or(u32::from(m.esc_id), |c| u32::from(c.esc_id))
            }
        }
    }

    /// Its firmware, powered on driving `plant`.
    pub fn power_on(
        &self,
        plant: Box<dyn ShaftPlant>,
        how: &PowerOn<'_>,
    ) -> Box<dyn ActuatorFirmware> {
        match self {
            Self::Robstride(m) => {
                let saved = how.kept.motors.get(&uid_key(m.effective_uid()));
                let mut actuator = Actuator::with_plant(m.clone(), saved, how.bitrate_bps, plant);
                if saved.is_none() {
                    actuator.set_master_id(how.host_id);
                }
                Box::new(actuator)
            }
            Self::Damiao(m) => {
                let config = kept_damiao(m, how.bus, how.kept).unwrap_or_else(|| m.clone());
                Box::new(DamiaoMotor::with_plant(config, plant))
            }
        }
    }

    /// Keeps what `firmware` (this actuator's, on bus `bus`) asked to save in `state`.
    pub fn keep(&self, bus: &str, firmware: &dyn ActuatorFirmware, state: &mut StateFile) {
        match self {
            Self::Damiao(m) => {
                state
                    .actuators
                    .insert(damiao_key(m, bus), firmware.persisted());
            }
            Self::Robstride(m) => {
                if let Ok(saved) = serde_json::from_value(firmware.persisted()) {
                    state.motors.insert(uid_key(m.effective_uid()), saved);
                }
            }
        }
    }
}

/// The key of a Damiao motor in a robot's state file: its bus and configured id (ids repeat
/// across buses, as on the OpenArm's two arms).
fn damiao_key(m: &DamiaoConfig, bus: &str) -> String {
    format!("{}:{bus}:{}", DAMIAO.name, m.esc_id)
}

/// A Damiao motor's settings from the flash image the state file kept, when it has one that
/// reads (an unreadable one is ignored: the motor starts from its defaults).
fn kept_damiao(m: &DamiaoConfig, bus: &str, kept: &StateFile) -> Option<DamiaoConfig> {
    let image = kept.actuators.get(&damiao_key(m, bus))?;
    DamiaoConfig::from_persisted(m.model, image).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_model_name_finds_its_kind_in_any_case() {
        let config = configure("rs03", 5).expect("RS03 is RobStride's");
        assert_eq!(config.kind().name, "robstride");
        assert_eq!(config.can_id(), 5);
        let model = config.model();
        assert_eq!((model.kind, model.name), ("robstride", "RS03"));
        assert!(model.peak_torque_nm > 10.0 && model.rotor_inertia_kg_m2 > 0.0);
    }

    #[test]
    fn an_unknown_model_lists_every_kinds_models_with_the_nearest() {
        let error = configure("RS3", 1).unwrap_err().to_string();
        assert!(
            error.starts_with("no actuator model `RS3` (known: RS00"),
            "{error}"
        );
        assert!(error.contains("did you mean"), "{error}");
    }

    #[test]
    fn each_kind_lists_the_rates_its_firmware_runs_at() {
        let mut robstride: Vec<u32> = (1..=4)
            .filter_map(crate::robstride::baud_code_bps)
            .collect();
        robstride.sort_unstable();
        let mut listed = ROBSTRIDE.bitrates_bps.to_vec();
        listed.sort_unstable();
        assert_eq!(listed, robstride);
        assert!(DAMIAO.bitrates_bps.contains(&1_000_000) && DAMIAO.bitrates_bps.contains(&200_000));
    }

    #[test]
    fn a_damiao_model_is_damiaos_with_its_own_ids_faults_and_key() {
        let config = configure("DM4310", 8).expect("DM4310 is Damiao's");
        assert_eq!((config.kind().name, config.can_id()), ("damiao", 8));
        assert!(config.robstride().is_none());
        assert!(
            configure("DM4310", 0x4FF).is_err(),
            "0x300 + id must stay below 0x7FF"
        );
        assert!(
            DAMIAO.has_fault("DM4310", "over_voltage")
                && !DAMIAO.has_fault("DM4310", "gate_driver")
        );
        // Ids repeat across buses (the OpenArm's two arms): kept apart by bus.
        let ActuatorConfig::Damiao(m) = &config else {
            panic!("a Damiao config");
        };
        assert_ne!(damiao_key(m, "can0"), damiao_key(m, "can1"));
    }

    #[test]
    fn an_id_is_checked_by_the_models_kind() {
        assert_eq!(
            configure("RS03", 128),
            Err(ConfigureError::IdOutOfRange {
                kind: "robstride",
                can_id: 128,
                low: 1,
                high: 0x7F
            })
        );
        assert!(configure("RS03", 0).is_err());
    }

    #[test]
    fn a_kinds_fault_labels_check_values_as_its_firmware_does() {
        let glitch =
            FaultArgs::new().with("counts", crate::fault_args::FaultArgValue::Number(100.0));
        assert_eq!(
            (ROBSTRIDE.fault_label)("RS03", "encoder_glitch", &glitch, false).as_deref(),
            Ok("encoder_glitch 100 counts")
        );
        let huge = FaultArgs::new().with("counts", crate::fault_args::FaultArgValue::Number(1e6));
        assert!((ROBSTRIDE.fault_label)("RS03", "encoder_glitch", &huge, false).is_err());
        // Clearing takes the fault whatever its size.
        assert!((ROBSTRIDE.fault_label)("RS03", "encoder_glitch", &FaultArgs::new(), true).is_ok());
        assert!((ROBSTRIDE.fault_label)("RS03", "melt", &FaultArgs::new(), false).is_err());
        assert!(ROBSTRIDE.has_fault("RS03", "gate_driver") && !ROBSTRIDE.has_fault("RS03", "melt"));
    }
}
