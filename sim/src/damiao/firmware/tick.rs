//! Time: error causes, the CAN timeout, the mode's control law and the plant.

use bus::CanFrame;

use super::{control, ControlMode, DamiaoMotor};
use crate::damiao::faults::{Fault, Thresholds};
use crate::damiao::registers::rid;

/// One tick of emulated time (µs).
const TICK_US: u64 = 1_000;
/// TIMEOUT register units (µs).
const TIMEOUT_UNIT_US: u64 = 50;

impl DamiaoMotor {
    /// Advance 1 ms: latch errors whose cause is present, run the CAN timeout, then the
    /// control law and the plant (10 substeps on the built-in rig). A Damiao motor sends
    /// nothing unasked, so this returns no frames.
    pub fn tick(&mut self) -> Vec<CanFrame> {
        self.latch_present_causes();
        self.watchdog(TICK_US);
        let dt = 1e-3 / f64::from(self.substeps);
        for _ in 0..self.substeps {
            let torque = self.control(dt);
            self.torque_nm = torque;
            self.plant.step(torque, dt);
        }
        Vec::new()
    }

    /// Run the control loops `substeps` times per tick (at least once): a robot's world steps
    /// once per tick for all its joints.
    pub fn set_control_substeps(&mut self, substeps: u32) {
        self.substeps = substeps.max(1);
    }

    /// The thresholds the registers hold now.
    pub fn thresholds(&self) -> Thresholds {
        Thresholds {
            over_voltage_v: self.registers.number(rid::OV_VALUE),
            under_voltage_v: self.registers.number(rid::UV_VALUE),
            over_temperature_c: self.registers.number(rid::OT_VALUE),
        }
    }

    /// Whether `fault`'s cause is present now.
    pub(super) fn cause_present(&self, fault: Fault) -> bool {
        let limits = self.thresholds();
        let c = &self.causes;
        match fault {
            Fault::OverVoltage => c.bus_voltage_v >= limits.over_voltage_v,
            Fault::UnderVoltage => c.bus_voltage_v <= limits.under_voltage_v,
            Fault::OverCurrent => c.over_current,
            Fault::MosOverTemperature => c.mos_temp_c >= limits.over_temperature_c,
            Fault::CoilOverTemperature => c.coil_temp_c >= limits.over_temperature_c,
            // The timeout is an event: once latched, nothing keeps it present.
            Fault::CommLost => false,
            Fault::Overload => c.overload,
        }
    }

    fn latch_present_causes(&mut self) {
        for fault in Fault::ALL {
            if !self.latched.contains(fault) && self.cause_present(fault) {
                self.latch(fault);
            }
        }
    }

    /// Latch `fault`: the motor stops (disabled, no torque) until the host clears it.
    pub(super) fn latch(&mut self, fault: Fault) {
        if !self.latched.contains(fault) {
            tracing::debug!(
                esc_id = self.esc_id(),
                fault = fault.name(),
                "damiao: error latched"
            );
        }
        self.latched.insert(fault);
        self.enabled = false;
        self.torque_nm = 0.0;
        self.hold();
    }

    /// `FB`: clear the latched errors whose cause is gone.
    pub(super) fn clear_errors(&mut self) {
        for fault in self.latched.iter() {
            if !self.cause_present(fault) {
                self.latched.remove(fault);
            }
        }
    }

    /// The CAN timeout: enabled, TIMEOUT non-zero and no frame for TIMEOUT × 50 µs → latch D.
    fn watchdog(&mut self, elapsed_us: u64) {
        self.quiet_us = self.quiet_us.saturating_add(elapsed_us);
        // A u32 register: exact in f64 and in u64.
        let timeout_us =
            (self.registers.number(rid::TIMEOUT) as u64).saturating_mul(TIMEOUT_UNIT_US);
        if self.enabled && timeout_us > 0 && self.quiet_us >= timeout_us {
            self.latch(Fault::CommLost);
        }
    }

    /// The torque the mode's law asks for over one substep `dt_s`, within what the motor gives.
    fn control(&mut self, dt_s: f64) -> f64 {
        if !self.enabled || !self.latched.is_empty() {
            return 0.0;
        }
        let (p, v) = (self.angle_rad(), self.speed_rad_s());
        let inertia = self.plant.inertia_kg_m2();
        let peak = self.spec.peak_torque_nm;
        let acc = self.registers.number(rid::ACC);
        let dec = self.registers.number(rid::DEC);
        let max_speed = self.registers.number(rid::MAX_SPD).abs();
        let torque = match self.control_mode() {
            ControlMode::Mit => {
                let c = self.targets.mit;
                let (kp_cap, kd_cap) = control::mit_gain_caps(inertia, dt_s);
                let law = c.kp_nm_per_rad.min(kp_cap) * (c.p_des_rad - p)
                    + c.kd_nm_s_per_rad.min(kd_cap) * (c.v_des_rad_s - v)
                    + c.t_ff_nm;
                // TMAX bounds the MIT law as well as the peak (a host may lower it).
                let limit = peak.min(self.registers.number(rid::TMAX).abs());
                law.clamp(-limit, limit)
            }
            ControlMode::PosVel => {
                let speed_limit = self.targets.speed_limit_rad_s.min(max_speed);
                self.track_position(speed_limit, (acc, dec), (p, v), inertia, peak, dt_s)
            }
            ControlMode::Velocity => {
                let target = self.targets.velocity_rad_s.clamp(-max_speed, max_speed);
                let before = self.speed_ramp_rad_s;
                self.speed_ramp_rad_s = control::ramp(before, target, acc, dec, dt_s);
                let accel = (self.speed_ramp_rad_s - before) / dt_s;
                self.speed_loop
                    .torque((self.speed_ramp_rad_s, accel), v, inertia, peak, dt_s)
            }
            ControlMode::PosForce => {
                // The current limit is per-unit of Imax, which drives the peak torque.
                let limit = peak * self.targets.current_fraction.clamp(0.0, 1.0);
                let speed_limit = self.targets.speed_limit_rad_s.min(max_speed);
                self.track_position(speed_limit, (acc, dec), (p, v), inertia, limit, dt_s)
            }
        };
        control::envelope(torque, v, peak, self.spec.max_speed_rad_s)
    }

    /// The position modes: the profile toward the target, the position loop after it.
    fn track_position(
        &mut self,
        speed_limit: f64,
        (acc, dec): (f64, f64),
        measured: (f64, f64),
        inertia: f64,
        limit_nm: f64,
        dt_s: f64,
    ) -> f64 {
        let accel = self
            .profile
            .step(self.targets.position_rad, speed_limit, acc, dec, dt_s);
        let reference = (self.profile.position_rad, self.profile.speed_rad_s, accel);
        self.position_loop
            .torque(reference, measured, inertia, limit_nm, dt_s)
            .clamp(-limit_nm.max(0.0), limit_nm.max(0.0))
    }
}
