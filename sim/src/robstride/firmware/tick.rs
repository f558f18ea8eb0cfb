//! Time: physics, control loops, thermal and overload models, watchdog, active reporting.

use bus::CanFrame;

use super::{canopen, mit, Actuator, ModeState, ReportType};
use crate::robstride::codec::CommType;
use crate::robstride::control::{SpeedEnvelope, ZERO_MODE_SPEED_RAD_S};
use crate::robstride::faults::{Fault, WARNING_OVER_TEMP};
use crate::robstride::params::index;

impl Actuator {
    /// Advance 1 ms: control loops and plant (10 substeps), thermal and overload models, the
    /// CAN watchdog and active reporting. Returns frames the motor sends on its own.
    pub fn tick(&mut self) -> Vec<CanFrame> {
        let mut out = Vec::new();
        if self.calibration_left_ms > 0 {
            self.calibration_left_ms -= 1;
            if self.calibration_left_ms == 0 {
                self.encoder_uncalibrated = false;
                self.fault_word &= !Fault::EncoderNotCalibrated.word_bit();
                self.mode = ModeState::Reset;
            }
        }
        let dt = 1e-3 / f64::from(self.substeps);
        for _ in 0..self.substeps {
            let torque = self.control(dt);
            self.plant.step(torque, dt);
        }
        self.update_thermal(1e-3);
        self.update_overload(1e-3);
        self.watchdog(1e-3);
        out.extend(self.check_conditions());
        if self.active_report && self.listening {
            self.report_elapsed_ms += 1;
            let n = self.params.get(index::EPSCAN_TIME).max(1.0);
            let period_ms = (10.0 + 5.0 * (n - 1.0)) as u32;
            if self.report_elapsed_ms >= period_ms {
                self.report_elapsed_ms = 0;
                let comm = match self.config.report_type {
                    ReportType::Type24 => CommType::ActiveReport,
                    ReportType::Type2 => CommType::Status,
                };
                if self.protocol == mit::PROTOCOL_MIT {
                    // MIT command 13: reports are Response 1 frames.
                    out.extend(self.mit_status());
                } else {
                    out.extend(self.status_frame(comm));
                }
            }
        }
        if self.listening && self.protocol == canopen::PROTOCOL_CANOPEN {
            out.extend(self.canopen_tick());
        }
        out
    }

    /// The torque–speed line at the present supply voltage (no-load speed ∝ voltage).
    fn envelope(&self, dt: f64) -> SpeedEnvelope {
        let volts = self.bus_voltage_v.max(0.0) / self.spec.nominal_voltage_v;
        SpeedEnvelope {
            peak_torque_nm: self.spec.peak_torque_nm,
            no_load_speed_rad_s: self.spec.no_load_speed_rad_s * volts,
            inertia_kg_m2: self.plant.inertia_kg_m2(),
            dt_s: dt,
        }
    }

    fn control(&mut self, dt: f64) -> f64 {
        if self.mode != ModeState::Run || self.fault_word != 0 {
            self.iq_a = 0.0;
            self.torque_nm = 0.0;
            // De-energised, the drive shorts the windings against back-driving unless the
            // model has 0x702A `damper` and it is set to 1. That torque is passive: the
            // reported torque and current stay those the drive commands (0). The manual has a
            // changed `damper` take effect after save and power cycle; we apply it at once.
            let damper_off = self.spec.has_damper_param && self.params.get(index::DAMPER) >= 0.5;
            if damper_off {
                return 0.0;
            }
            return self
                .envelope(dt)
                .short_circuit_brake(self.plant.velocity_rad_s());
        }
        let kt = self.spec.torque_constant_nm_per_a;
        let angle = self.angle_rad();
        let speed = self.plant.velocity_rad_s();
        let inertia = self.plant.inertia_kg_m2();
        // Gains above what an explicit step at `dt` can hold stable for this inertia would
        // make the simulation explode where the real loop (with its own filters) does not.
        let kd_cap = 0.5 * inertia / dt;
        let kp_cap = 0.25 * inertia / (dt * dt);
        let speed_kp = self.params.get(index::SPD_KP).min(kd_cap / kt);
        let speed_ki = self.params.get(index::SPD_KI);
        let limit_cur = self.params.get(index::LIMIT_CUR);
        let loc_kp = self.params.get(index::LOC_KP);
        let torque_cmd = match self.run_mode() {
            0 => {
                let op = self.op;
                let torque = op.kp.min(kp_cap) * (op.angle_rad - angle)
                    + op.kd.min(kd_cap) * (op.speed_rad_s - speed)
                    + op.torque_nm;
                self.iq_a = torque / kt;
                torque
            }
            1 => {
                let vel_max = self.params.get(index::VEL_MAX);
                let acc = self.params.get(index::ACC_SET);
                let dcc = self.params.get(index::DCC_SET);
                self.profile.step(vel_max, acc, dcc, dt);
                let target = self.profile.speed_rad_s + loc_kp * (self.profile.angle_rad - angle);
                let iq = self
                    .speed_loop
                    .update(target - speed, speed_kp, speed_ki, limit_cur, dt);
                self.iq_a = iq;
                iq * kt
            }
            2 => {
                let reference = self.params.get(index::SPD_REF);
                let acc = self.params.get(index::ACC_RAD).max(0.0) * dt;
                self.speed_ramp_rad_s += (reference - self.speed_ramp_rad_s).clamp(-acc, acc);
                let error = self.speed_ramp_rad_s - speed;
                let iq = self
                    .speed_loop
                    .update(error, speed_kp, speed_ki, limit_cur, dt);
                self.iq_a = iq;
                iq * kt
            }
            3 => {
                let limit = f64::from(self.ranges.current_a);
                self.iq_a = self.params.get(index::IQ_REF).clamp(-limit, limit);
                self.iq_a * kt
            }
            4 => {
                let target = (loc_kp * -angle).clamp(-ZERO_MODE_SPEED_RAD_S, ZERO_MODE_SPEED_RAD_S);
                let iq = self
                    .speed_loop
                    .update(target - speed, speed_kp, speed_ki, limit_cur, dt);
                self.iq_a = iq;
                iq * kt
            }
            _ => {
                let limit_spd = self.params.get(index::LIMIT_SPD);
                let loc_ref = self.params.get(index::LOC_REF);
                let target = (loc_kp * (loc_ref - angle)).clamp(-limit_spd, limit_spd);
                let iq = self
                    .speed_loop
                    .update(target - speed, speed_kp, speed_ki, limit_cur, dt);
                self.iq_a = iq;
                iq * kt
            }
        };
        let limit = self
            .params
            .get(index::LIMIT_TORQUE)
            .min(f64::from(self.ranges.torque_nm));
        let torque = torque_cmd.clamp(-limit, limit);
        self.torque_nm = self.envelope(dt).limit(torque, speed);
        if self.torque_nm != torque_cmd {
            self.iq_a = self.torque_nm / kt;
        }
        self.torque_nm
    }

    fn update_thermal(&mut self, dt: f64) {
        let ratio = self.iq_a / self.spec.rated_current_a;
        let target = self.config.ambient_c + self.config.thermal_rise_at_rated_c * ratio * ratio;
        let tau = self.config.thermal_time_constant_s.max(1e-3);
        self.temperature_c += (target - self.temperature_c) * (dt / tau).min(1.0);
    }

    fn update_overload(&mut self, dt: f64) {
        let rated2 = self.spec.rated_current_a.powi(2);
        self.overload_a2s = (self.overload_a2s + (self.iq_a.powi(2) - rated2) * dt).max(0.0);
    }

    fn watchdog(&mut self, dt: f64) {
        self.since_command_s += dt;
        let ticks = self.params.get(index::CAN_TIMEOUT);
        if ticks <= 0.0 || self.mode != ModeState::Run {
            return;
        }
        let window_s = ticks / self.config.can_timeout_ticks_per_s.max(1.0);
        if self.since_command_s > window_s {
            tracing::info!(
                motor = self.can_id,
                window_s,
                "robstride: CAN timeout, motor reset"
            );
            self.stop();
        }
    }

    /// Latch faults whose conditions hold, raise the warning, and send a type-21 frame on
    /// every change of the fault or warning word.
    fn check_conditions(&mut self) -> Option<CanFrame> {
        let before = (self.fault_word, self.warning_word);
        if self.temperature_c >= self.spec.over_temp_fault_c {
            self.fault_word |= Fault::OverTemperature.word_bit();
        }
        if self.temperature_c >= self.spec.over_temp_warning_c {
            self.warning_word |= WARNING_OVER_TEMP;
        } else if self.temperature_c < self.spec.over_temp_warning_c - 5.0 {
            self.warning_word &= !WARNING_OVER_TEMP;
        }
        if self.bus_voltage_v < self.spec.under_voltage_v {
            self.fault_word |= Fault::UnderVoltage.word_bit();
        }
        if self.bus_voltage_v > self.spec.over_voltage_v {
            self.fault_word |= Fault::OverVoltage.word_bit();
        }
        let budget = (self.spec.peak_current_a.powi(2) - self.spec.rated_current_a.powi(2))
            * self.config.overload_time_at_peak_s;
        if self.overload_a2s > budget {
            self.fault_word |= Fault::StallOverload.word_bit();
            self.overload_a2s = 0.0;
        }
        if self.encoder_uncalibrated {
            self.fault_word |= Fault::EncoderNotCalibrated.word_bit();
        }
        self.after_fault_change(before)
    }

    pub(super) fn after_fault_change(&mut self, before: (u32, u32)) -> Option<CanFrame> {
        if (self.fault_word, self.warning_word) == before {
            return None;
        }
        if self.fault_word & !before.0 != 0 {
            tracing::warn!(
                motor = self.can_id,
                fault_word = self.fault_word,
                "robstride: fault"
            );
            self.stop();
        }
        // Type 21 is a private-protocol frame; the MIT variant shows faults in its replies and
        // a CANopen node sends EMCY (see `canopen`).
        if self.listening && self.protocol == 0 {
            self.fault_frame()
        } else {
            None
        }
    }
}
