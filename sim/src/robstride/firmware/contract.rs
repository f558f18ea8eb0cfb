//! A RobStride actuator as the actuator contract sees it: what a robot's runner drives a joint
//! through ([`ActuatorFirmware`]), whatever the kind.

use std::time::Duration;

use bus::CanFrame;

use super::{Actuator, TURNAROUND};
use crate::actuator::{ActuatorFirmware, ActuatorSnapshot, Detail};
use crate::fault_args::{FaultArgError, FaultArgs};
use crate::fault_desk::FaultInfo;
use crate::robstride::faults::{actuator_fault_table, max_external_torque_nm, Fault};

/// The kind's name in the actuator registry.
pub const KIND: &str = "robstride";

impl ActuatorFirmware for Actuator {
    fn kind(&self) -> &'static str {
        KIND
    }

    fn can_id(&self) -> u32 {
        u32::from(Actuator::can_id(self))
    }

    fn handle_frame(&mut self, frame: &CanFrame) -> Vec<CanFrame> {
        Actuator::handle_frame(self, frame)
    }

    fn tick(&mut self) -> Vec<CanFrame> {
        Actuator::tick(self)
    }

    fn is_running(&self) -> bool {
        Actuator::is_running(self)
    }

    fn sends_nothing_on_its_own(&self) -> bool {
        Actuator::sends_nothing_on_its_own(self)
    }

    fn turnaround(&self) -> Duration {
        TURNAROUND
    }

    fn set_control_substeps(&mut self, substeps: u32) {
        Actuator::set_control_substeps(self, substeps);
    }

    fn snapshot(&self) -> ActuatorSnapshot {
        let m = Actuator::snapshot(self);
        ActuatorSnapshot {
            kind: KIND,
            model: m.model.name(),
            can_id: u32::from(m.can_id),
            enabled: Actuator::is_running(self),
            mode: m.mode.name().to_owned(),
            angle_rad: m.angle_rad,
            speed_rad_s: m.speed_rad_s,
            torque_nm: m.torque_nm,
            temperature_c: m.temperature_c,
            faults: Fault::set_in(m.fault_word)
                .into_iter()
                .map(|f| f.name().to_owned())
                .collect(),
            details: vec![
                ("run_mode", Detail::Int(i64::from(m.run_mode))),
                ("fault_word", Detail::Int(i64::from(m.fault_word))),
                ("warning_word", Detail::Int(i64::from(m.warning_word))),
                ("iq_a", Detail::Real(m.iq_a)),
                ("bus_voltage_v", Detail::Real(m.bus_voltage_v)),
                ("protocol", Detail::Int(i64::from(m.protocol))),
            ],
        }
    }

    fn set_temperature(&mut self, celsius: f64) {
        Actuator::set_temperature(self, celsius);
    }

    fn set_external_torque(&mut self, torque_nm: f64) {
        Actuator::set_external_torque(self, torque_nm);
    }

    fn max_external_torque_nm(&self) -> f64 {
        max_external_torque_nm(self.config().model)
    }

    fn fault_table(&self) -> Vec<FaultInfo> {
        actuator_fault_table()
    }

    fn inject(&mut self, name: &str, args: &FaultArgs) -> Result<Vec<CanFrame>, FaultArgError> {
        let fault = Fault::named(name)?.with_values(args)?;
        Ok(Actuator::inject(self, fault).into_iter().collect())
    }

    fn clear(&mut self, name: &str, _args: &FaultArgs) -> Result<(), FaultArgError> {
        // A cause is removed whatever values it was injected with (a glitch of any size).
        Actuator::remove_cause(self, Fault::named(name)?);
        Ok(())
    }

    fn take_persist_request(&mut self) -> bool {
        Actuator::take_persist_request(self)
    }

    fn persisted(&self) -> serde_json::Value {
        // A plain struct of numbers and maps: it always has a JSON form.
        serde_json::to_value(Actuator::persisted(self)).unwrap_or(serde_json::Value::Null)
    }
}
