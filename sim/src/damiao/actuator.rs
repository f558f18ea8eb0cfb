//! Damiao's entry in the actuator registry ([`crate::actuator::KINDS`]): its [`KIND`] (model
//! names, CAN ids, bus rates, fault table and labels) and what a robot asks of a Damiao
//! motor's settings ([`ActuatorSetup`] on [`MotorConfig`]).

use super::faults::{self, Thresholds};
use super::{DamiaoMotor, Model, MotorConfig};
use crate::actuator::{
    ActuatorConfig, ActuatorFirmware, ActuatorKind, ActuatorModel, ActuatorSetup, PowerOn,
    ShaftPlant,
};
use crate::fault_args::FaultArgs;
use crate::robstride::state_file::StateFile;

/// Damiao's joint motors (MIT, position-velocity, velocity and force-position on 11-bit
/// identifiers): the OpenArm's.
pub static KIND: ActuatorKind = ActuatorKind {
    name: super::KIND,
    model_names: || Model::ALL.iter().map(|m| m.name()).collect(),
    // The force-position command goes to 0x300 + id, which must stay below the register
    // identifier 0x7FF.
    ids: (1, 0x4FE),
    bitrates_bps: &[1_000_000, 500_000, 250_000, 200_000, 125_000],
    fd: true,
    configure: |model, can_id| {
        let model = Model::from_name(model)?;
        let esc_id = u16::try_from(can_id).unwrap_or(u16::MAX);
        Some(ActuatorConfig::new(MotorConfig::new(esc_id, model)))
    },
    faults: |model| faults::table(&limits(model)),
    fault_label: |model, name, args, clearing| {
        let limits = limits(model);
        let fault = faults::Fault::named(name)?;
        if clearing {
            fault.build_to_clear(args, &limits)?;
            Ok(fault.name().to_owned())
        } else {
            fault.build(args, &limits)?;
            Ok(shown_with_values(fault.name(), args))
        }
    },
};

/// A `model`'s fault thresholds at power-on (a DM4310's for a name it does not know).
fn limits(model: &str) -> Thresholds {
    Thresholds::power_on(Model::from_name(model).unwrap_or(Model::DM4310))
}

/// `name` followed by its values as given (`over_voltage voltage_v=60`).
fn shown_with_values(name: &str, args: &FaultArgs) -> String {
    let mut shown = name.to_owned();
    for (arg, value) in args.iter() {
        shown.push_str(&format!(" {arg}={value}"));
    }
    shown
}

/// A Damiao motor a robot carries (its `load` and rig fields are unused: the robot is the
/// load). It keeps its flash image in the state file by bus and configured id.
impl ActuatorSetup for MotorConfig {
    fn kind(&self) -> &'static ActuatorKind {
        &KIND
    }

    fn can_id(&self) -> u32 {
        u32::from(self.esc_id)
    }

    fn model(&self) -> ActuatorModel {
        let spec = self.model.spec();
        ActuatorModel {
            kind: KIND.name,
            name: self.model.name(),
            peak_torque_nm: spec.peak_torque_nm,
            rotor_inertia_kg_m2: spec.rotor_inertia_kg_m2,
        }
    }

    fn power_on_id(&self, bus: &str, kept: &StateFile) -> u32 {
        kept_config(self, bus, kept).map_or(u32::from(self.esc_id), |c| u32::from(c.esc_id))
    }

    fn power_on(&self, plant: Box<dyn ShaftPlant>, how: &PowerOn<'_>) -> Box<dyn ActuatorFirmware> {
        let config = kept_config(self, how.bus, how.kept).unwrap_or_else(|| self.clone());
        Box::new(DamiaoMotor::with_plant(config, plant))
    }

    fn keep(&self, bus: &str, firmware: &dyn ActuatorFirmware, state: &mut StateFile) {
        state
            .actuators
            .insert(state_key(self, bus), firmware.persisted());
    }
}

impl From<MotorConfig> for ActuatorConfig {
    fn from(config: MotorConfig) -> Self {
        ActuatorConfig::new(config)
    }
}

/// The key of a motor in a robot's state file: its bus and configured id (ids repeat across
/// buses, as on the OpenArm's two arms).
fn state_key(m: &MotorConfig, bus: &str) -> String {
    format!("{}:{bus}:{}", KIND.name, m.esc_id)
}

/// A motor's settings from the flash image the state file kept, when it has one that reads
/// (an unreadable one is ignored: the motor starts from its defaults).
fn kept_config(m: &MotorConfig, bus: &str, kept: &StateFile) -> Option<MotorConfig> {
    let image = kept.actuators.get(&state_key(m, bus))?;
    MotorConfig::from_persisted(m.model, image).ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::actuator::configure;

    #[test]
    fn a_damiao_model_is_damiaos_with_its_own_ids_faults_and_key() {
        let config = configure("DM4310", 8).expect("DM4310 is Damiao's");
        assert_eq!((config.kind().name, config.can_id()), ("damiao", 8));
        assert!(config
            .downcast_ref::<crate::robstride::MotorConfig>()
            .is_none());
        assert!(
            configure("DM4310", 0x4FF).is_err(),
            "0x300 + id must stay below 0x7FF"
        );
        assert!(
            KIND.has_fault("DM4310", "over_voltage") && !KIND.has_fault("DM4310", "gate_driver")
        );
        // Ids repeat across buses (the OpenArm's two arms): kept apart by bus.
        let m = config
            .downcast_ref::<MotorConfig>()
            .expect("a Damiao config");
        assert_ne!(state_key(m, "can0"), state_key(m, "can1"));
    }

    #[test]
    fn it_lists_the_rates_its_firmware_runs_at() {
        assert!(KIND.bitrates_bps.contains(&1_000_000) && KIND.bitrates_bps.contains(&200_000));
    }
}
