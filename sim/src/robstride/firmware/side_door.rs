//! The harness's side door: faults, supply, temperature, snapshot.

use bus::CanFrame;

use super::{Actuator, ModeState, MotorSnapshot};
use crate::robstride::faults::{Fault, Phase, ENCODER_COUNTS_PER_TURN, WARNING_OVER_TEMP};

impl Actuator {
    /// Inject a fault: set its physical cause (heat, supply) or latch a one-shot event.
    /// Returns the type-21 frame the motor sends.
    pub fn inject(&mut self, fault: Fault) -> Option<CanFrame> {
        let before = (self.fault_word, self.warning_word);
        match fault {
            Fault::OverTemperature => {
                self.temperature_c = self.spec.over_temp_fault_c + 5.0;
                self.warning_word |= WARNING_OVER_TEMP;
            }
            Fault::UnderVoltage => self.bus_voltage_v = self.spec.under_voltage_v - 2.0,
            Fault::OverVoltage => self.bus_voltage_v = self.spec.over_voltage_v + 2.0,
            Fault::EncoderNotCalibrated => {
                self.encoder_uncalibrated = true;
                self.mode = ModeState::Calibration;
            }
            Fault::PhaseOverCurrent(_) | Fault::StallOverload | Fault::GateDriver => {}
            Fault::EncoderGlitch { counts } => {
                self.encoder_glitch_rad =
                    f64::from(counts) * std::f64::consts::TAU / ENCODER_COUNTS_PER_TURN as f64;
            }
        }
        self.fault_word |= fault.word_bit();
        self.after_fault_change(before)
    }

    /// Remove a fault's cause (cool down, restore the supply, calibrate). The latched bit stays
    /// until the host sends stop + clear, as on hardware.
    pub fn remove_cause(&mut self, fault: Fault) {
        match fault {
            Fault::OverTemperature => self.temperature_c = self.config.ambient_c,
            Fault::UnderVoltage | Fault::OverVoltage => {
                self.bus_voltage_v = self.spec.nominal_voltage_v
            }
            Fault::EncoderNotCalibrated => {
                self.encoder_uncalibrated = false;
                if self.mode == ModeState::Calibration {
                    self.mode = ModeState::Reset;
                }
            }
            Fault::EncoderGlitch { .. } => self.encoder_glitch_rad = 0.0,
            Fault::PhaseOverCurrent(Phase::A | Phase::B | Phase::C)
            | Fault::StallOverload
            | Fault::GateDriver => {}
        }
    }

    /// Set the supply voltage (V); faults latch on the next tick if it is out of range.
    pub fn set_bus_voltage(&mut self, volts: f64) {
        if volts.is_finite() {
            self.bus_voltage_v = volts;
        }
    }

    /// Set the winding temperature (°C).
    pub fn set_temperature(&mut self, celsius: f64) {
        if celsius.is_finite() {
            self.temperature_c = celsius;
        }
    }

    /// Push the load with an external torque (N·m).
    pub fn set_external_torque(&mut self, torque_nm: f64) {
        self.plant.set_external_torque_nm(torque_nm);
    }

    /// Whether the motor's 1 ms steps send nothing of their own for now: not running (no loop
    /// can raise a fault from its current), no active report, not a CANopen node (its own
    /// heartbeat and PDOs), no calibration ending. Its steps may then run in batches as long
    /// as they are caught up before it answers ([`crate::can_runner::StepClock::rest`]).
    pub fn sends_nothing_on_its_own(&self) -> bool {
        self.mode != ModeState::Run
            && !(self.active_report && self.listening)
            && self.protocol != super::canopen::PROTOCOL_CANOPEN
            && self.calibration_left_ms == 0
    }

    /// Whether the motor is enabled (run mode): its loops drive the joint.
    pub fn is_running(&self) -> bool {
        self.mode == ModeState::Run
    }

    /// A view of the motor's state.
    pub fn snapshot(&self) -> MotorSnapshot {
        MotorSnapshot {
            can_id: self.can_id,
            model: self.config.model,
            mode: self.mode,
            run_mode: self.run_mode(),
            angle_rad: self.angle_rad(),
            speed_rad_s: self.plant.velocity_rad_s(),
            torque_nm: self.torque_nm,
            iq_a: self.iq_a,
            temperature_c: self.temperature_c,
            bus_voltage_v: self.bus_voltage_v,
            fault_word: self.fault_word,
            warning_word: self.warning_word,
            active_report: self.active_report,
            master_id: self.master_id,
            baud_code: self.baud_code,
            protocol: self.protocol,
            listening: self.listening,
        }
    }
}
