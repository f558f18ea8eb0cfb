//! The motor controller's loops: operation control, profile position, velocity ramp, current,
//! zero return and CSP, as the manual describes them (spec §4.3, §8).

/// Speed of the zero-return mode (run_mode 4). The manuals only say "slowly"; an assumption.
pub const ZERO_MODE_SPEED_RAD_S: f64 = 1.0;

/// The last operation-control command (type 1), in physical units.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct OpCommand {
    /// Target angle (rad).
    pub angle_rad: f64,
    /// Target speed (rad/s).
    pub speed_rad_s: f64,
    /// Stiffness (N·m/rad).
    pub kp: f64,
    /// Damping (N·m·s/rad).
    pub kd: f64,
    /// Feed-forward torque (N·m).
    pub torque_nm: f64,
}

/// A trapezoidal profile generator for PP mode: the reference moves toward the target with
/// the profile speed, accelerating with `acc` and braking with `dcc`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Profile {
    /// Reference angle (rad).
    pub angle_rad: f64,
    /// Reference speed (rad/s).
    pub speed_rad_s: f64,
    /// Target angle (rad).
    pub target_rad: f64,
}

impl Profile {
    /// A profile resting at `angle_rad`.
    pub fn at_rest(angle_rad: f64) -> Self {
        Self {
            angle_rad,
            speed_rad_s: 0.0,
            target_rad: angle_rad,
        }
    }

    /// Advance by `dt_s`.
    pub fn step(&mut self, vel_max: f64, acc: f64, dcc: f64, dt_s: f64) {
        let acc = acc.max(1e-6);
        let dcc = dcc.max(1e-6);
        let distance = self.target_rad - self.angle_rad;
        let direction = distance.signum();
        // The fastest speed from which the target can still be reached with `dcc`.
        let braking_speed = (2.0 * dcc * distance.abs()).sqrt();
        let desired = direction * vel_max.max(0.0).min(braking_speed);
        let v = self.speed_rad_s;
        // Speeding up (same sign, larger magnitude) uses acc; anything else is braking.
        let rate = if desired * v >= 0.0 && desired.abs() > v.abs() {
            acc
        } else {
            dcc
        };
        let dv = (desired - v).clamp(-rate * dt_s, rate * dt_s);
        self.speed_rad_s = v + dv;
        self.angle_rad += self.speed_rad_s * dt_s;
        let remaining = self.target_rad - self.angle_rad;
        if remaining.abs() < 1e-6
            || (remaining * distance < 0.0 && self.speed_rad_s.abs() < dcc * dt_s * 2.0)
        {
            self.angle_rad = self.target_rad;
            self.speed_rad_s = 0.0;
        }
    }
}

/// A speed PI loop producing an iq command (A). `ki` is per millisecond of error, the
/// firmware's 1 kHz convention, scaled to the substep.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SpeedLoop {
    /// Integral term (A).
    pub integral_a: f64,
}

impl SpeedLoop {
    /// One update: error → iq, limited to ±`limit_a` with anti-windup.
    pub fn update(&mut self, error_rad_s: f64, kp: f64, ki: f64, limit_a: f64, dt_s: f64) -> f64 {
        let limit = limit_a.abs();
        self.integral_a = (self.integral_a + ki * error_rad_s * dt_s * 1000.0).clamp(-limit, limit);
        (kp * error_rad_s + self.integral_a).clamp(-limit, limit)
    }
}

/// The motor's torque–speed line (spec §6.3): peak torque at standstill falling linearly to
/// zero at the no-load speed, as back-EMF eats the supply voltage.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpeedEnvelope {
    /// Peak output torque (N·m).
    pub peak_torque_nm: f64,
    /// No-load output speed at the present supply voltage (rad/s).
    pub no_load_speed_rad_s: f64,
    /// Inertia the motor drives (kg·m²).
    pub inertia_kg_m2: f64,
    /// Integration step (s).
    pub dt_s: f64,
}

impl SpeedEnvelope {
    /// `torque_nm` limited to what the motor can produce at `speed_rad_s`.
    ///
    /// Torque that drives the shaft faster (same sign as the speed) is capped at
    /// `peak·(1 − |ω|/ω₀)`, and at what one step may add without overshooting ω₀ (the line is
    /// a stiff damping term, `peak/ω₀` N·m·s/rad, too stiff for an explicit step on a light
    /// rotor). Braking torque is limited by the peak torque only.
    pub fn limit(&self, torque_nm: f64, speed_rad_s: f64) -> f64 {
        let w0 = self.no_load_speed_rad_s;
        if !w0.is_finite() || w0 <= 0.0 || torque_nm * speed_rad_s <= 0.0 {
            return torque_nm;
        }
        let headroom = (w0 - speed_rad_s.abs()).max(0.0);
        let available = (self.peak_torque_nm * headroom / w0)
            .min(self.inertia_kg_m2 * headroom / self.dt_s.max(1e-9));
        torque_nm.clamp(-available, available)
    }

    /// Torque of the de-energised motor's anti-back-drive damping (windings shorted, spec
    /// §7.1 `damper`): the torque–speed line's slope `peak/ω₀` against the motion, never more
    /// than what stops the shaft within one step.
    pub fn short_circuit_brake(&self, speed_rad_s: f64) -> f64 {
        let w0 = self.no_load_speed_rad_s;
        if !w0.is_finite() || w0 <= 0.0 {
            return 0.0;
        }
        let damping = self.peak_torque_nm / w0;
        let magnitude = (damping * speed_rad_s.abs())
            .min(self.inertia_kg_m2 * speed_rad_s.abs() / self.dt_s.max(1e-9));
        -magnitude * speed_rad_s.signum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn profile_reaches_the_target_with_the_profile_speed() {
        let mut profile = Profile::at_rest(0.0);
        profile.target_rad = 10.0;
        let dt = 1e-3;
        let mut peak: f64 = 0.0;
        let mut steps = 0;
        while (profile.angle_rad - 10.0).abs() > 1e-9 || profile.speed_rad_s != 0.0 {
            profile.step(2.0, 4.0, 1.0, dt);
            peak = peak.max(profile.speed_rad_s);
            steps += 1;
            assert!(steps < 100_000, "profile never settles");
        }
        assert!((peak - 2.0).abs() < 1e-9);
        // acc phase 0.5 s, dcc phase 2 s, cruise (10 − 0.5 − 2)/2 = 3.75 s: 6.25 s in all.
        let seconds = f64::from(steps) * dt;
        assert!((seconds - 6.25).abs() < 0.08, "{seconds}");
    }

    #[test]
    fn speed_loop_saturates_and_does_not_wind_up() {
        let mut pi = SpeedLoop::default();
        for _ in 0..10_000 {
            assert!(pi.update(100.0, 6.0, 0.02, 5.0, 1e-3).abs() <= 5.0);
        }
        assert!(pi.integral_a <= 5.0);
    }

    #[test]
    fn envelope_caps_driving_torque_and_leaves_braking_alone() {
        let env = SpeedEnvelope {
            peak_torque_nm: 60.0,
            no_load_speed_rad_s: 20.0,
            inertia_kg_m2: 1.0,
            dt_s: 1e-4,
        };
        assert_eq!(env.limit(60.0, 0.0), 60.0);
        assert!((env.limit(60.0, 10.0) - 30.0).abs() < 1e-12);
        assert!((env.limit(-60.0, -15.0) + 15.0).abs() < 1e-12);
        assert_eq!(env.limit(60.0, 25.0), 0.0);
        assert_eq!(env.limit(-60.0, 10.0), -60.0);
        let brake = env.short_circuit_brake(10.0);
        assert!((brake + 30.0).abs() < 1e-12, "{brake}");
        assert_eq!(env.short_circuit_brake(0.0), 0.0);
        // A light rotor: the brake never reverses the speed within one step.
        let light = SpeedEnvelope {
            inertia_kg_m2: 1e-4,
            ..env
        };
        let tau = light.short_circuit_brake(10.0);
        assert!(10.0 + tau * 1e-4 / 1e-4 >= -1e-9, "{tau}");
    }
}
