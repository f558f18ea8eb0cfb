//! The joint an actuator drives inside a robot's physics world, as the actuator's [`Plant`].
//!
//! The firmware's control loops run at 10 kHz (ten 100 µs substeps per 1 ms tick); stepping a
//! 20-joint world with contacts at 10 kHz would cost more than real time. So the two are
//! co-simulated: during a tick each actuator integrates *its own joint* locally — the joint's
//! effective inertia (the world's mass-matrix diagonal plus the rotor), the torque the motor
//! applies, and the load the rest of the robot put on the joint during the previous world step
//! (gravity, the other joints' coupling, contacts, limits) — while recording the mean torque
//! it applied. The world then steps 1 ms with every joint's mean torque, and each joint's
//! local state is reset to what the world computed ([`JointLink::sync_from_world`]). The
//! control loops keep their 10 kHz behaviour; the world decides where the robot really is.
//!
//! Shaft and joint frames: the shaft angle θ = direction · (q − zero offset), where q is the
//! URDF joint position; the joint torque is direction · shaft torque.

use std::sync::{Arc, Mutex, MutexGuard};

use crate::robstride::Plant;

/// What the robot's world and one actuator share about the joint between them.
#[derive(Debug, Clone, PartialEq)]
pub struct JointState {
    /// Shaft angle (rad).
    pub shaft_angle_rad: f64,
    /// Shaft speed (rad/s).
    pub shaft_speed_rad_s: f64,
    /// Effective inertia about the joint: mass-matrix diagonal plus rotor (kg·m²).
    pub inertia_kg_m2: f64,
    /// The load the rest of the robot puts on the shaft, measured over the last world step
    /// (N·m, shaft frame).
    pub load_nm: f64,
    /// An external torque on the shaft (the harness's hand), N·m.
    pub external_nm: f64,
    /// ∫ motor torque dt since the last world step (N·m·s, shaft frame).
    torque_impulse_nm_s: f64,
    /// Time integrated since the last world step (s).
    integrated_s: f64,
}

/// Largest load the measured estimate may carry, as a multiple of the motor's peak torque: a
/// joint hitting its hard stop gets an impulse whose one-step "load" is meaningless for the
/// next prediction, and the world corrects the state at every step anyway.
const MAX_LOAD_PER_PEAK: f64 = 4.0;

/// Share of a new load measurement taken per world step (a first-order filter with a time
/// constant of about 10 steps = 10 ms).
const LOAD_FILTER_GAIN: f64 = 0.1;

/// The robot's side of a joint: where the world reads the motor's torque and writes back the
/// joint's state.
#[derive(Debug, Clone)]
pub struct JointLink {
    state: Arc<Mutex<JointState>>,
    direction: f64,
    zero_offset_rad: f64,
    max_load_nm: f64,
}

/// The actuator's side of a joint (its [`Plant`]).
#[derive(Debug)]
pub struct JointPlant {
    state: Arc<Mutex<JointState>>,
}

/// A joint link and the plant for the actuator driving it.
///
/// `direction` is +1 or −1 (anything negative counts as −1); `joint_q` the joint's start
/// position; `peak_torque_nm` the motor's peak torque (bounds the measured load).
pub fn joint_pair(
    direction: f64,
    zero_offset_rad: f64,
    joint_q: f64,
    inertia_kg_m2: f64,
    peak_torque_nm: f64,
) -> (JointLink, JointPlant) {
    let direction = if direction < 0.0 { -1.0 } else { 1.0 };
    let state = Arc::new(Mutex::new(JointState {
        shaft_angle_rad: direction * (joint_q - zero_offset_rad),
        shaft_speed_rad_s: 0.0,
        inertia_kg_m2: inertia_kg_m2.max(1e-6),
        load_nm: 0.0,
        external_nm: 0.0,
        torque_impulse_nm_s: 0.0,
        integrated_s: 0.0,
    }));
    (
        JointLink {
            state: Arc::clone(&state),
            direction,
            zero_offset_rad,
            max_load_nm: MAX_LOAD_PER_PEAK * peak_torque_nm.abs().max(1.0),
        },
        JointPlant { state },
    )
}

/// The state behind the lock. A panic while it was held (it holds plain numbers, nothing a
/// panic could leave half-written in a harmful way) does not poison the robot.
fn lock(state: &Mutex<JointState>) -> MutexGuard<'_, JointState> {
    state
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

impl JointLink {
    /// The joint torque to apply over the coming world step (N·m, joint frame): the motor's
    /// mean torque since the last step plus the external torque. Resets the integral.
    pub fn take_joint_torque_nm(&self) -> f64 {
        let mut s = lock(&self.state);
        let mean = if s.integrated_s > 0.0 {
            s.torque_impulse_nm_s / s.integrated_s
        } else {
            0.0
        };
        s.torque_impulse_nm_s = 0.0;
        s.integrated_s = 0.0;
        self.direction * (mean + s.external_nm)
    }

    /// After a world step of `dt_s` in which the joint got `applied_joint_nm` and its speed
    /// went from `joint_qd_before` to `joint_qd`: take the world's position and speed, set the
    /// effective inertia, and measure the load the rest of the robot put on the joint (what
    /// the world's acceleration needed beyond the applied torque; measured on the world's own
    /// speeds so the local integration's error does not feed back).
    pub fn sync_from_world(
        &self,
        joint_q: f64,
        joint_qd_before: f64,
        joint_qd: f64,
        inertia_kg_m2: f64,
        applied_joint_nm: f64,
        dt_s: f64,
    ) {
        let mut s = lock(&self.state);
        let speed_before = self.direction * joint_qd_before;
        let speed = self.direction * joint_qd;
        let inertia = inertia_kg_m2.max(1e-6);
        if dt_s > 0.0 && speed.is_finite() && joint_q.is_finite() {
            let needed = inertia * (speed - speed_before) / dt_s;
            let measured = (needed - self.direction * applied_joint_nm)
                .clamp(-self.max_load_nm, self.max_load_nm);
            // Low-pass: a load measured one step late and fed straight back makes the
            // controller and the world chatter at half the step rate; the loads that matter
            // (gravity, the other joints' motion) change far slower than 1 ms.
            s.load_nm += LOAD_FILTER_GAIN * (measured - s.load_nm);
            s.shaft_angle_rad = self.direction * (joint_q - self.zero_offset_rad);
            s.shaft_speed_rad_s = speed;
        }
        s.inertia_kg_m2 = inertia;
    }

    /// The shaft's state now.
    pub fn state(&self) -> JointState {
        lock(&self.state).clone()
    }
}

impl Plant for JointPlant {
    fn step(&mut self, torque_nm: f64, dt_s: f64) {
        let mut s = lock(&self.state);
        let torque = if torque_nm.is_finite() {
            torque_nm
        } else {
            0.0
        };
        let accel = (torque + s.load_nm + s.external_nm) / s.inertia_kg_m2;
        let speed = s.shaft_speed_rad_s + accel * dt_s;
        if speed.is_finite() {
            s.shaft_speed_rad_s = speed;
            s.shaft_angle_rad += speed * dt_s;
        }
        s.torque_impulse_nm_s += torque * dt_s;
        s.integrated_s += dt_s;
    }

    fn position_rad(&self) -> f64 {
        lock(&self.state).shaft_angle_rad
    }

    fn velocity_rad_s(&self) -> f64 {
        lock(&self.state).shaft_speed_rad_s
    }

    fn inertia_kg_m2(&self) -> f64 {
        lock(&self.state).inertia_kg_m2
    }

    fn set_external_torque_nm(&mut self, torque_nm: f64) {
        lock(&self.state).external_nm = if torque_nm.is_finite() {
            torque_nm
        } else {
            0.0
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_mean_torque_reaches_the_joint_in_its_direction() {
        let (link, mut plant) = joint_pair(-1.0, 0.5, 0.5, 0.1, 10.0);
        assert_eq!(
            plant.position_rad(),
            0.0,
            "q = zero offset is shaft angle 0"
        );
        for k in 0..10 {
            plant.step(if k < 5 { 2.0 } else { 4.0 }, 1e-4);
        }
        assert!((link.take_joint_torque_nm() + 3.0).abs() < 1e-12);
        assert_eq!(link.take_joint_torque_nm(), 0.0, "the integral was reset");
    }

    #[test]
    fn the_load_is_what_the_acceleration_needed_beyond_the_torque() {
        // Gravity pulls the joint with −5 N·m while the motor applied +2: the world's joint
        // sped down by 3 N·m / 0.1 kg·m² · 1 ms = −0.03 rad/s.
        let (link, plant) = joint_pair(1.0, 0.0, 0.0, 0.1, 10.0);
        for _ in 0..200 {
            link.sync_from_world(0.0, 0.0, -0.03, 0.1, 2.0, 1e-3);
        }
        let s = link.state();
        assert!((s.load_nm + 5.0).abs() < 1e-6, "{s:?}");
        assert_eq!(plant.velocity_rad_s(), -0.03);
    }

    #[test]
    fn a_hard_stop_impulse_does_not_become_a_huge_load() {
        let (link, _plant) = joint_pair(1.0, 0.0, 0.0, 0.1, 10.0);
        for _ in 0..200 {
            link.sync_from_world(0.0, 0.0, -50.0, 0.1, 0.0, 1e-3);
        }
        assert!((link.state().load_nm + 40.0).abs() < 1e-6);
    }
}
