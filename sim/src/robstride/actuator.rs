//! RobStride's entry in the actuator registry ([`crate::actuator::KINDS`]): its [`KIND`] (model
//! names, CAN ids, bus rates, fault table and labels) and what a robot asks of a RobStride
//! actuator's settings ([`ActuatorSetup`] on [`MotorConfig`]).

use super::state_file::{uid_key, StateFile};
use super::{Actuator, Fault, Model, MotorConfig};
use crate::actuator::{
    ActuatorConfig, ActuatorFirmware, ActuatorKind, ActuatorModel, ActuatorSetup, PowerOn,
    ShaftPlant,
};

/// RobStride's quasi-direct-drive actuators (private protocol, MIT and CANopen variants).
pub static KIND: ActuatorKind = ActuatorKind {
    name: super::ACTUATOR_KIND,
    model_names: || Model::ALL.iter().map(|m| m.name()).collect(),
    ids: (1, 0x7F),
    configure: |model, can_id| {
        let model = Model::from_name(model)?;
        let can_id = u8::try_from(can_id).unwrap_or(u8::MAX);
        Some(ActuatorConfig::new(MotorConfig::new(can_id, model)))
    },
    bitrates_bps: &[1_000_000, 500_000, 250_000, 125_000],
    fd: false,
    faults: |_| super::faults::actuator_fault_table(),
    fault_label: |_, name, args, clearing| {
        let fault = Fault::named(name)?;
        let names: Vec<&str> = fault.values().iter().map(|p| p.name).collect();
        args.only(name, &names)?;
        Ok(if clearing {
            fault.name().to_owned()
        } else {
            fault.with_values(args)?.label()
        })
    },
};

/// A RobStride actuator a robot carries (its `load` and rig fields are unused: the robot is
/// the load). Its state file entry is keyed by its UID, on whatever bus.
impl ActuatorSetup for MotorConfig {
    fn kind(&self) -> &'static ActuatorKind {
        &KIND
    }

    fn can_id(&self) -> u32 {
        u32::from(self.can_id)
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

    fn power_on_id(&self, _bus: &str, kept: &StateFile) -> u32 {
        u32::from(kept.power_on_id(self))
    }

    fn power_on(&self, plant: Box<dyn ShaftPlant>, how: &PowerOn<'_>) -> Box<dyn ActuatorFirmware> {
        let saved = how.kept.motors.get(&uid_key(self.effective_uid()));
        let mut actuator = Actuator::with_plant(self.clone(), saved, how.bitrate_bps, plant);
        if saved.is_none() {
            actuator.set_master_id(how.host_id);
        }
        Box::new(actuator)
    }

    fn keep(&self, _bus: &str, firmware: &dyn ActuatorFirmware, state: &mut StateFile) {
        if let Ok(saved) = serde_json::from_value(firmware.persisted()) {
            state.motors.insert(uid_key(self.effective_uid()), saved);
        }
    }
}

impl From<MotorConfig> for ActuatorConfig {
    fn from(config: MotorConfig) -> Self {
        ActuatorConfig::new(config)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::actuator::configure;
    use crate::fault_args::{FaultArgValue, FaultArgs};

    #[test]
    fn it_lists_the_rates_its_firmware_runs_at() {
        let mut rates: Vec<u32> = (1..=4).filter_map(super::super::baud_code_bps).collect();
        rates.sort_unstable();
        let mut listed = KIND.bitrates_bps.to_vec();
        listed.sort_unstable();
        assert_eq!(listed, rates);
    }

    #[test]
    fn a_robstride_model_is_robstrides_settings() {
        let config = configure("RS03", 5).expect("RS03 is RobStride's");
        let motor = config.downcast_ref::<MotorConfig>().expect("RobStride's");
        assert_eq!((motor.can_id, motor.model), (5, Model::RS03));
        assert_eq!(
            config,
            ActuatorConfig::from(MotorConfig::new(5, Model::RS03))
        );
    }

    #[test]
    fn its_fault_labels_check_values_as_its_firmware_does() {
        let glitch = FaultArgs::new().with("counts", FaultArgValue::Number(100.0));
        assert_eq!(
            (KIND.fault_label)("RS03", "encoder_glitch", &glitch, false).as_deref(),
            Ok("encoder_glitch 100 counts")
        );
        let huge = FaultArgs::new().with("counts", FaultArgValue::Number(1e6));
        assert!((KIND.fault_label)("RS03", "encoder_glitch", &huge, false).is_err());
        // Clearing takes the fault whatever its size.
        assert!((KIND.fault_label)("RS03", "encoder_glitch", &FaultArgs::new(), true).is_ok());
        assert!((KIND.fault_label)("RS03", "melt", &FaultArgs::new(), false).is_err());
        assert!(KIND.has_fault("RS03", "gate_driver") && !KIND.has_fault("RS03", "melt"));
    }
}
