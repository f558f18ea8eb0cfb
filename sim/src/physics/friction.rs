//! Static and kinetic dry friction of a joint (Karnopp's stick band).
//!
//! rapier has one dry-friction value per multibody degree of freedom: a constraint that holds
//! the joint still while the net torque on it stays below the value and opposes the motion
//! with exactly that torque once it slides. A real geared joint needs more torque to start
//! (breakaway, static friction) than it loses while sliding (kinetic, Coulomb friction).
//! [`KineticFriction`] switches the constraint's value between the two by the joint's speed
//! at the start of each step (Karnopp's model): a joint whose speed has stayed inside the
//! stick band (|v| ≤ [`KineticFriction::stick_speed`]) for [`STICK_STEPS`] consecutive steps
//! is stuck and sees its breakaway value; otherwise it slides and sees the kinetic one.
//!
//! Why two steps and not one: a joint that reverses (an overshoot) crosses zero speed within
//! one step, and the sample after the crossing can land inside the band by chance; a joint
//! that friction has really stopped stays inside it. Judged on one sample, a reversing joint
//! would now and then be caught by the breakaway value at the far end of its swing, where the
//! spring of a PD law cannot pull it back (kp 10 stuck 0.084 rad past a 17° target).
//!
//! A joint without a kinetic figure keeps its URDF friction at every speed (the world is
//! unchanged for it).

/// Consecutive steps inside the stick band after which a joint counts as stuck.
pub const STICK_STEPS: u32 = 2;

/// The sliding part of a joint's dry friction and the speed below which it sticks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KineticFriction {
    /// Friction while sliding (N·m, or N for a prismatic joint); at most the breakaway value.
    pub kinetic: f64,
    /// Speed at or below which the joint counts as stuck and sees the breakaway value
    /// (rad/s or m/s).
    pub stick_speed: f64,
}

impl KineticFriction {
    /// A kinetic figure for a joint whose breakaway friction is `breakaway`: `kinetic` is
    /// clamped into `[0, breakaway]` and a non-finite or negative value (or stick speed)
    /// counts as 0, so the split can only lower the friction a sliding joint sees.
    pub fn new(breakaway: f64, kinetic: f64, stick_speed: f64) -> Self {
        let finite_non_negative = |x: f64| if x.is_finite() { x.max(0.0) } else { 0.0 };
        Self {
            kinetic: finite_non_negative(kinetic).min(finite_non_negative(breakaway)),
            stick_speed: finite_non_negative(stick_speed),
        }
    }

    /// Whether `speed` lies inside the stick band.
    pub fn within_band(&self, speed: f64) -> bool {
        speed.abs() <= self.stick_speed
    }

    /// The friction a joint with breakaway friction `breakaway` sees after `still_steps`
    /// consecutive steps inside the stick band.
    pub fn in_effect(&self, breakaway: f64, still_steps: u32) -> f64 {
        if still_steps >= STICK_STEPS {
            breakaway
        } else {
            self.kinetic
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sticks_after_two_steps_inside_the_band_and_slides_otherwise() {
        let f = KineticFriction::new(1.0, 0.3, 0.01);
        assert!(f.within_band(0.0) && f.within_band(-0.01));
        assert!(!f.within_band(0.0101) && !f.within_band(-2.0));
        assert_eq!(f.in_effect(1.0, 0), 0.3);
        assert_eq!(f.in_effect(1.0, 1), 0.3);
        assert_eq!(f.in_effect(1.0, 2), 1.0);
        assert_eq!(f.in_effect(1.0, u32::MAX), 1.0);
    }

    #[test]
    fn the_kinetic_value_never_exceeds_the_breakaway_one_and_bad_input_is_zero() {
        assert_eq!(KineticFriction::new(1.0, 5.0, 0.01).kinetic, 1.0);
        assert_eq!(KineticFriction::new(1.0, f64::NAN, 0.01).kinetic, 0.0);
        assert_eq!(KineticFriction::new(1.0, -1.0, 0.01).kinetic, 0.0);
        assert_eq!(
            KineticFriction::new(1.0, 0.3, f64::INFINITY).stick_speed,
            0.0
        );
    }
}
