//! The emulator's control loops: a motion profile for the position modes, a position loop, a
//! speed loop and the motor's torque–speed line.
//!
//! The note gives the modes' behaviour, not the firmware's loops (registers 25–28 hold gains
//! of undocumented units), so the loops here are the emulator's own: their gains come from the
//! inertia the plant reports, placing the closed-loop poles at fixed bandwidths. That keeps a
//! step response the same shape whatever the load, and stable at the 1 kHz a robot's world
//! steps at as well as at the built-in rig's 10 kHz.

/// Position-loop bandwidth (rad/s): three poles at 15 Hz.
const POSITION_BANDWIDTH_RAD_S: f64 = std::f64::consts::TAU * 15.0;
/// Speed-loop bandwidth (rad/s): two poles at 20 Hz.
const SPEED_BANDWIDTH_RAD_S: f64 = std::f64::consts::TAU * 20.0;
/// Largest bandwidth × step an explicit step holds well damped.
const MAX_BANDWIDTH_STEPS: f64 = 0.2;
/// No-load speed as a multiple of the model's maximum speed: the torque–speed line reaches
/// zero torque a little past the speed the model is rated to reach under load.
const NO_LOAD_SPEED_MULTIPLE: f64 = 1.2;

/// A trapezoidal motion profile: the reference the position loop follows toward a target.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(super) struct Profile {
    /// Reference position (rad).
    pub position_rad: f64,
    /// Reference speed (rad/s).
    pub speed_rad_s: f64,
}

impl Profile {
    /// At rest at `position_rad`.
    pub fn at_rest(position_rad: f64) -> Self {
        Self {
            position_rad,
            speed_rad_s: 0.0,
        }
    }

    /// Advance `dt_s` toward `target_rad` with |speed| ≤ `max_speed`, speeding up at `acc` and
    /// slowing at `dec` (magnitudes, rad/s²); returns the reference acceleration (rad/s²).
    pub fn step(&mut self, target_rad: f64, max_speed: f64, acc: f64, dec: f64, dt_s: f64) -> f64 {
        let (acc, dec) = (acc.abs().max(1e-6), dec.abs().max(1e-6));
        let max_speed = if max_speed.is_finite() {
            max_speed.abs()
        } else {
            0.0
        };
        let to_go = target_rad - self.position_rad;
        // The fastest speed from which it can still stop at the target.
        let braking = (2.0 * dec * to_go.abs()).sqrt();
        let wanted = if to_go == 0.0 {
            0.0
        } else {
            to_go.signum() * max_speed.min(braking)
        };
        let speed = self.speed_rad_s;
        let speeding_up = wanted * speed >= 0.0 && wanted.abs() > speed.abs();
        let rate = if speeding_up { acc } else { dec };
        let new_speed = speed + (wanted - speed).clamp(-rate * dt_s, rate * dt_s);
        let new_position = self.position_rad + 0.5 * (speed + new_speed) * dt_s;
        // Arrived: the step would reach or cross the target at the crawl the braking curve
        // ends in (about 2·dec·dt): land on it. A faster crossing (a target moved in front of
        // a fast reference) overshoots and comes back instead of stopping at once.
        let crawl = 4.0 * dec * dt_s;
        if to_go != 0.0 && (target_rad - new_position) * to_go <= 0.0 && new_speed.abs() <= crawl {
            *self = Self::at_rest(target_rad);
            return 0.0;
        }
        self.position_rad = new_position;
        self.speed_rad_s = new_speed;
        (new_speed - speed) / dt_s
    }
}

/// The bandwidth a loop may use at step `dt_s`.
fn bandwidth(wanted: f64, dt_s: f64) -> f64 {
    wanted.min(MAX_BANDWIDTH_STEPS / dt_s.max(1e-9))
}

/// A position loop with integral action: three closed-loop poles at the position bandwidth
/// for the plant's inertia, plus the profile's acceleration as feed-forward.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(super) struct PositionLoop {
    integral_nm: f64,
}

impl PositionLoop {
    /// The torque toward the reference `(position, speed, acceleration)` from the measured
    /// `(position, speed)`, within ±`limit_nm` (the integral too, so it cannot wind up).
    #[allow(clippy::too_many_arguments)]
    pub fn torque(
        &mut self,
        reference: (f64, f64, f64),
        measured: (f64, f64),
        inertia_kg_m2: f64,
        limit_nm: f64,
        dt_s: f64,
    ) -> f64 {
        let (p_ref, v_ref, a_ref) = reference;
        let (p, v) = measured;
        let j = inertia_kg_m2.max(1e-9);
        let w = bandwidth(POSITION_BANDWIDTH_RAD_S, dt_s);
        let error = p_ref - p;
        let limit = limit_nm.max(0.0);
        self.integral_nm = (self.integral_nm + j * w * w * w * error * dt_s).clamp(-limit, limit);
        j * a_ref + 3.0 * j * w * w * error + 3.0 * j * w * (v_ref - v) + self.integral_nm
    }
}

/// A speed loop (PI): two closed-loop poles at the speed bandwidth for the plant's inertia.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(super) struct SpeedLoop {
    integral_nm: f64,
}

impl SpeedLoop {
    /// The torque toward `speed_ref` (with `accel_ref` as feed-forward) from `speed`, within
    /// ±`limit_nm`.
    pub fn torque(
        &mut self,
        (speed_ref, accel_ref): (f64, f64),
        speed: f64,
        inertia_kg_m2: f64,
        limit_nm: f64,
        dt_s: f64,
    ) -> f64 {
        let j = inertia_kg_m2.max(1e-9);
        let w = bandwidth(SPEED_BANDWIDTH_RAD_S, dt_s);
        let error = speed_ref - speed;
        let limit = limit_nm.max(0.0);
        self.integral_nm = (self.integral_nm + j * w * w * error * dt_s).clamp(-limit, limit);
        j * accel_ref + 2.0 * j * w * error + self.integral_nm
    }
}

/// A speed reference ramped toward its target at ACC (speeding up) and DEC (slowing down).
pub(super) fn ramp(speed: f64, target: f64, acc: f64, dec: f64, dt_s: f64) -> f64 {
    let speeding_up = target * speed >= 0.0 && target.abs() > speed.abs();
    // `max` drops a NaN: a rate that is not a number holds the reference still.
    let rate = (if speeding_up { acc.abs() } else { dec.abs() } * dt_s).max(0.0);
    speed + (target - speed).clamp(-rate, rate)
}

/// Largest MIT gains an explicit step at `dt_s` holds stable for `inertia` (kp, kd): the real
/// loop has its own filters; the emulator's must not explode where the motor does not.
pub(super) fn mit_gain_caps(inertia_kg_m2: f64, dt_s: f64) -> (f64, f64) {
    let j = inertia_kg_m2.max(1e-9);
    (0.25 * j / (dt_s * dt_s), 0.5 * j / dt_s)
}

/// `torque_nm` within what the motor gives at `speed_rad_s`: ±`peak_nm`, and, driving the way
/// it turns, a line from the peak at standstill to zero at the no-load speed (braking keeps
/// the peak). Non-finite torque gives zero.
pub(super) fn envelope(
    torque_nm: f64,
    speed_rad_s: f64,
    peak_nm: f64,
    max_speed_rad_s: f64,
) -> f64 {
    if !torque_nm.is_finite() {
        return 0.0;
    }
    let peak = peak_nm.max(0.0);
    let torque = torque_nm.clamp(-peak, peak);
    if torque * speed_rad_s <= 0.0 {
        return torque;
    }
    let no_load = (NO_LOAD_SPEED_MULTIPLE * max_speed_rad_s).max(1e-6);
    let available = peak * (1.0 - speed_rad_s.abs() / no_load).max(0.0);
    torque.clamp(-available, available)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_profile_reaches_its_target_within_the_speed_limit() {
        let mut profile = Profile::at_rest(0.0);
        let mut top = 0.0f64;
        let mut steps = 0;
        while profile != Profile::at_rest(2.0) && steps < 100_000 {
            profile.step(2.0, 3.0, 10.0, 5.0, 1e-4);
            top = top.max(profile.speed_rad_s.abs());
            steps += 1;
        }
        assert_eq!(profile, Profile::at_rest(2.0));
        assert!(top <= 3.0 && top > 2.9, "{top}");
        // Speeding up at 10 to 3 rad/s takes 0.3 s, slowing at 5 takes 0.6 s; 2 rad total.
        let expected = 0.3 + 0.6 + (2.0 - 0.45 - 0.9) / 3.0;
        assert!((f64::from(steps) * 1e-4 - expected).abs() < 0.02, "{steps}");
    }

    #[test]
    fn the_profile_turns_around_when_the_target_moves_behind_it() {
        let mut profile = Profile {
            position_rad: 0.0,
            speed_rad_s: 2.0,
        };
        for _ in 0..50_000 {
            profile.step(-1.0, 2.0, 10.0, 10.0, 1e-4);
        }
        assert_eq!(profile, Profile::at_rest(-1.0));
    }

    #[test]
    fn the_envelope_limits_driving_torque_with_speed_only() {
        assert_eq!(envelope(50.0, 0.0, 7.0, 10.0), 7.0);
        assert_eq!(envelope(5.0, 12.0, 7.0, 10.0), 0.0);
        assert!((envelope(7.0, 6.0, 7.0, 10.0) - 3.5).abs() < 1e-9);
        assert_eq!(
            envelope(-7.0, 6.0, 7.0, 10.0),
            -7.0,
            "braking keeps the peak"
        );
        assert_eq!(envelope(f64::NAN, 0.0, 7.0, 10.0), 0.0);
    }

    #[test]
    fn the_ramp_speeds_up_at_acc_and_slows_at_dec() {
        assert!((ramp(0.0, 5.0, 10.0, 20.0, 0.1) - 1.0).abs() < 1e-12);
        assert!((ramp(5.0, 0.0, 10.0, 20.0, 0.1) - 3.0).abs() < 1e-12);
        assert_eq!(ramp(4.9, 5.0, 10.0, 20.0, 0.1), 5.0);
    }
}
