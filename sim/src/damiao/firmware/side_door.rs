//! The bench's side door: faults, supply, temperatures, a push on the shaft, and the flash.

use super::{DamiaoMotor, PersistedMotor};
use crate::damiao::faults::{Fault, Injection};

impl DamiaoMotor {
    /// Apply an injected fault: set its cause (supply, temperature, event) and latch it at
    /// once, so the motor stops before its next tick. Nothing is sent: a Damiao motor reports
    /// errors only in the feedback a host asks for.
    pub fn inject_fault(&mut self, injection: Injection) {
        let limits = self.thresholds();
        let c = &mut self.causes;
        match injection.fault {
            Fault::OverVoltage => {
                c.bus_voltage_v = injection.value.unwrap_or(limits.over_voltage_v + 2.0);
            }
            Fault::UnderVoltage => {
                c.bus_voltage_v = injection.value.unwrap_or(limits.under_voltage_v - 2.0);
            }
            Fault::MosOverTemperature => {
                c.mos_temp_c = injection.value.unwrap_or(limits.over_temperature_c + 5.0);
            }
            Fault::CoilOverTemperature => {
                c.coil_temp_c = injection.value.unwrap_or(limits.over_temperature_c + 5.0);
            }
            Fault::OverCurrent => c.over_current = true,
            Fault::Overload => c.overload = true,
            Fault::CommLost => {}
        }
        self.latch(injection.fault);
    }

    /// Remove `fault`'s cause (nominal supply, ambient temperature, event over). The latch
    /// stays until the host's `FB`.
    pub fn remove_cause(&mut self, fault: Fault) {
        let ambient = self.config.ambient_c;
        let c = &mut self.causes;
        match fault {
            Fault::OverVoltage | Fault::UnderVoltage => {
                c.bus_voltage_v = self.spec.nominal_voltage_v;
            }
            Fault::MosOverTemperature => c.mos_temp_c = ambient,
            Fault::CoilOverTemperature => c.coil_temp_c = ambient,
            Fault::OverCurrent => c.over_current = false,
            Fault::Overload => c.overload = false,
            Fault::CommLost => {}
        }
    }

    /// Set the supply voltage (V); an error latches at the next tick if it is past a
    /// threshold. Non-finite values are ignored.
    pub fn set_bus_voltage(&mut self, volts: f64) {
        if volts.is_finite() {
            self.causes.bus_voltage_v = volts;
        }
    }

    /// Set the driver board (MOS) temperature (°C). Non-finite values are ignored.
    pub fn set_mos_temperature(&mut self, celsius: f64) {
        if celsius.is_finite() {
            self.causes.mos_temp_c = celsius;
        }
    }

    /// Set the coil (winding) temperature (°C). Non-finite values are ignored.
    pub fn set_coil_temperature(&mut self, celsius: f64) {
        if celsius.is_finite() {
            self.causes.coil_temp_c = celsius;
        }
    }

    /// The supply voltage (V).
    pub fn bus_voltage_v(&self) -> f64 {
        self.causes.bus_voltage_v
    }

    /// The coil temperature (°C).
    pub fn coil_temperature_c(&self) -> f64 {
        self.causes.coil_temp_c
    }

    /// The board (MOS) temperature (°C).
    pub fn mos_temperature_c(&self) -> f64 {
        self.causes.mos_temp_c
    }

    /// Push the shaft with an external torque (N·m) until changed.
    pub fn push(&mut self, torque_nm: f64) {
        self.plant.set_external_torque_nm(torque_nm);
    }

    /// True once after a save (0xAA) or a zero (FE): the caller keeps [`DamiaoMotor::flash`].
    pub fn take_persist_request(&mut self) -> bool {
        std::mem::take(&mut self.persist_requested)
    }

    /// What the motor keeps across power cycles now (the last save and zero).
    pub fn flash(&self) -> &PersistedMotor {
        &self.flash
    }
}
