//! The actuator kinds a robot joint can be driven by, the model names each answers to, and
//! the settings of one actuator a robot carries. A robot file's `model:` is looked up here
//! ([`configure`]). Each kind keeps its entry in its own folder (`sim/src/<kind>/actuator.rs`:
//! its [`ActuatorKind`] and its settings' [`ActuatorSetup`]); adding one is a line in
//! [`KINDS`].

use std::any::Any;
use std::fmt::Debug;
use std::sync::Arc;

use super::{ActuatorFirmware, ShaftPlant};
use crate::fault_args::{FaultArgError, FaultArgs};
use crate::fault_desk::FaultInfo;
use crate::robstride::state_file::StateFile;
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

/// Every actuator kind, in the order a model name is looked up: one registration line each.
pub static KINDS: &[&ActuatorKind] = &[
    &crate::robstride::actuator::KIND,
    &crate::damiao::actuator::KIND,
];

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

/// The firmware settings of one actuator a robot carries, as its kind holds them: what a
/// robot asks of an actuator of any kind before and after its firmware runs. Each kind
/// implements it on its own settings (`sim/src/<kind>/actuator.rs`); a robot holds them as an
/// [`ActuatorConfig`].
pub trait ActuatorSetup: AnySetup + Debug + Send + Sync {
    /// Its kind.
    fn kind(&self) -> &'static ActuatorKind;

    /// The CAN identifier at first power-on (a state file may hold a newer one).
    fn can_id(&self) -> u32;

    /// The model's facts.
    fn model(&self) -> ActuatorModel;

    /// The CAN identifier it answers on at power-on on bus `bus`, after what the state file
    /// kept.
    fn power_on_id(&self, bus: &str, kept: &StateFile) -> u32;

    /// Its firmware, powered on driving `plant`.
    fn power_on(&self, plant: Box<dyn ShaftPlant>, how: &PowerOn<'_>) -> Box<dyn ActuatorFirmware>;

    /// Keeps what `firmware` (this actuator's, on bus `bus`) asked to save in `state`.
    fn keep(&self, bus: &str, firmware: &dyn ActuatorFirmware, state: &mut StateFile);
}

/// What every [`ActuatorSetup`] has by being a settings type with an equality (implemented
/// for them all): its concrete type, for the few places that need a kind's own settings, and
/// an equality with another kind's.
pub trait AnySetup {
    /// Itself, to downcast to its kind's settings.
    fn as_any(&self) -> &dyn Any;
    /// Whether `other` is settings of the same type, equal to these.
    fn same_as(&self, other: &dyn Any) -> bool;
}

impl<T: Any + PartialEq> AnySetup for T {
    fn as_any(&self) -> &dyn Any {
        self
    }

    fn same_as(&self, other: &dyn Any) -> bool {
        other.downcast_ref::<T>() == Some(self)
    }
}

/// The firmware settings of one actuator a robot carries, of any kind of [`KINDS`] (its
/// `load` and rig fields, where it has them, are unused: the robot is the load). Equal when
/// they are one kind's settings and equal.
#[derive(Debug, Clone)]
pub struct ActuatorConfig(Arc<dyn ActuatorSetup>);

impl ActuatorConfig {
    /// A kind's settings, held for a robot.
    pub fn new(setup: impl ActuatorSetup + 'static) -> Self {
        Self(Arc::new(setup))
    }

    /// The settings, as any kind's.
    pub fn setup(&self) -> &dyn ActuatorSetup {
        &*self.0
    }

    /// The settings as the kind whose settings are a `T` holds them, when they are.
    pub fn downcast_ref<T: ActuatorSetup + 'static>(&self) -> Option<&T> {
        self.setup().as_any().downcast_ref::<T>()
    }

    /// Its kind.
    pub fn kind(&self) -> &'static ActuatorKind {
        self.0.kind()
    }

    /// The CAN identifier at first power-on (a state file may hold a newer one).
    pub fn can_id(&self) -> u32 {
        self.0.can_id()
    }

    /// The model's facts.
    pub fn model(&self) -> ActuatorModel {
        self.0.model()
    }

    /// The CAN identifier it answers on at power-on on bus `bus`, after what the state file
    /// kept.
    pub fn power_on_id(&self, bus: &str, kept: &StateFile) -> u32 {
        self.0.power_on_id(bus, kept)
    }

    /// Its firmware, powered on driving `plant`.
    pub fn power_on(
        &self,
        plant: Box<dyn ShaftPlant>,
        how: &PowerOn<'_>,
    ) -> Box<dyn ActuatorFirmware> {
        self.0.power_on(plant, how)
    }

    /// Keeps what `firmware` (this actuator's, on bus `bus`) asked to save in `state`.
    pub fn keep(&self, bus: &str, firmware: &dyn ActuatorFirmware, state: &mut StateFile) {
        self.0.keep(bus, firmware, state);
    }
}

impl PartialEq for ActuatorConfig {
    fn eq(&self, other: &Self) -> bool {
        self.setup().same_as(other.setup().as_any())
    }
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
    fn configs_are_equal_when_one_kinds_settings_are() {
        let rs03 = configure("RS03", 5).unwrap();
        assert_eq!(rs03, configure("RS03", 5).unwrap());
        assert_eq!(rs03, rs03.clone());
        assert_ne!(rs03, configure("RS03", 6).unwrap());
        assert_ne!(rs03, configure("RS02", 5).unwrap());
        // Another kind's settings on the same id are not equal, whatever they hold.
        assert_ne!(rs03, configure("DM4310", 5).unwrap());
        assert!(rs03
            .downcast_ref::<crate::robstride::MotorConfig>()
            .is_some());
        assert!(rs03.downcast_ref::<crate::damiao::MotorConfig>().is_none());
    }
}
