//! The actuator contract ([`ActuatorFirmware`]): how a robot's runner drives a Damiao motor.

use std::time::Duration;

use bus::CanFrame;

use super::{DamiaoMotor, KIND, TURNAROUND};
use crate::actuator::{ActuatorFirmware, ActuatorSnapshot, Detail};
use crate::damiao::faults::{self, Fault};
use crate::fault_args::{FaultArgError, FaultArgs};
use crate::fault_desk::FaultInfo;

/// Largest external push the side door takes, as a multiple of the model's peak torque: ten
/// times what the motor can answer still stalls it; more is not a disturbance a test means.
pub const EXTERNAL_TORQUE_PEAK_MULTIPLE: f64 = 10.0;

impl ActuatorFirmware for DamiaoMotor {
    fn kind(&self) -> &'static str {
        KIND
    }

    fn can_id(&self) -> u32 {
        u32::from(self.esc_id())
    }

    fn handle_frame(&mut self, frame: &CanFrame) -> Vec<CanFrame> {
        DamiaoMotor::handle_frame(self, frame)
    }

    /// The OpenArm runs its Damiao buses as CAN FD (1 Mbit/s nominal, 5 Mbit/s data) with the
    /// classic payloads inside FD frames: the motors take both.
    fn speaks_fd(&self) -> bool {
        true
    }

    fn tick(&mut self) -> Vec<CanFrame> {
        DamiaoMotor::tick(self)
    }

    fn is_running(&self) -> bool {
        self.enabled
    }

    /// A Damiao motor never sends unasked, but while enabled its loops move the joint and its
    /// CAN timeout may fire: only a disabled motor lets the clock rest.
    fn sends_nothing_on_its_own(&self) -> bool {
        !self.enabled
    }

    fn turnaround(&self) -> Duration {
        TURNAROUND
    }

    fn set_control_substeps(&mut self, substeps: u32) {
        DamiaoMotor::set_control_substeps(self, substeps);
    }

    fn snapshot(&self) -> ActuatorSnapshot {
        ActuatorSnapshot {
            kind: KIND,
            model: self.config.model.name(),
            can_id: u32::from(self.esc_id()),
            enabled: self.enabled,
            mode: self.control_mode().name().to_owned(),
            angle_rad: self.angle_rad(),
            speed_rad_s: self.speed_rad_s(),
            torque_nm: self.torque_nm,
            temperature_c: self.causes.coil_temp_c,
            faults: self.latched.iter().map(|f| f.name().to_owned()).collect(),
            details: vec![
                ("state", Detail::Int(i64::from(self.state_nibble()))),
                ("mst_id", Detail::Int(i64::from(self.mst_id()))),
                (
                    "ctrl_mode",
                    Detail::Int(i64::from(self.control_mode().register_value())),
                ),
                ("mos_temperature_c", Detail::Real(self.causes.mos_temp_c)),
                ("bus_voltage_v", Detail::Real(self.causes.bus_voltage_v)),
            ],
        }
    }

    fn set_temperature(&mut self, celsius: f64) {
        self.set_coil_temperature(celsius);
    }

    fn set_external_torque(&mut self, torque_nm: f64) {
        self.push(torque_nm);
    }

    fn max_external_torque_nm(&self) -> f64 {
        EXTERNAL_TORQUE_PEAK_MULTIPLE * self.spec.peak_torque_nm
    }

    fn fault_table(&self) -> Vec<FaultInfo> {
        faults::table(&self.thresholds())
    }

    fn inject(&mut self, name: &str, args: &FaultArgs) -> Result<Vec<CanFrame>, FaultArgError> {
        let injection = Fault::named(name)?.build(args, &self.thresholds())?;
        self.inject_fault(injection);
        Ok(Vec::new())
    }

    fn clear(&mut self, name: &str, args: &FaultArgs) -> Result<(), FaultArgError> {
        let fault = Fault::named(name)?.build_to_clear(args, &self.thresholds())?;
        self.remove_cause(fault);
        Ok(())
    }

    fn take_persist_request(&mut self) -> bool {
        DamiaoMotor::take_persist_request(self)
    }

    fn persisted(&self) -> serde_json::Value {
        // A map of names to finite numbers and one finite angle: serialization cannot fail;
        // `Null` would only stand for a bug, never a panic.
        serde_json::to_value(&self.flash).unwrap_or(serde_json::Value::Null)
    }
}
