//! The arm's physical plant: the rapier world of `urdf/rm65b.urdf` (or `rm75b.urdf`) stepped at 1 kHz, one
//! position controller per joint driving it with torque, joint brakes, and the motor currents,
//! temperatures and bus voltage the controller reports.
//!
//! The joint controller is a PD loop on the reference the controller's planner streams
//! ([`ArmPlant::set_target`]) in computed-torque form: each joint asks for the acceleration
//! `ω²·(q_ref − q) + 2ζω·(q̇_ref − q̇)`, the mass matrix turns those into torques (so every joint
//! has the same bandwidth whatever the pose and the joints do not excite each other), plus
//! gravity and viscous feed-forward. Each motor's torque is clamped to the joint's effort
//! limit (60, 60, 30, 10, 10, 10 N·m on the RM65-B, from the URDF).
//!
//! A joint that is disabled, or any joint while the brakes are engaged, is held by its brake
//! where it was when the brake closed; the motor then produces no torque (zero current). The
//! brake is a stiff lock that carries the joint's load up to its holding torque, so a large
//! enough external torque can still slip it.
//!
//! Not documented by the vendor and chosen by us (the controller only reports these values):
//! the torque constants [`TORQUE_CONSTANT_NM_PER_A`], the winding resistances and thermal
//! constants, the brake's stiffness and holding torque, and the 48 V bus with its source
//! resistance.

use nalgebra::{DMatrix, DVector};

use crate::physics::{PhysicsError, RapierWorld, WorldConfig};

use super::model::ArmModel;

/// The RM65-B URDF (authored by the project, see `urdf/README.md`).
pub const RM65B_URDF: &str = include_str!("../../../urdf/rm65b.urdf");
/// The RM75-B URDF (authored by the project, see `urdf/README.md`).
pub const RM75B_URDF: &str = include_str!("../../../urdf/rm75b.urdf");

/// Output torque per phase ampere, N·m/A, per joint (J1..J6; J7 of an RM75 uses the last).
/// **Assumed**: chosen so that the effort limit takes about 12 A on J1–J2 (60 N·m),
/// 8 A on J3 (30 N·m) and 5 A on J4–J6 (10 N·m).
pub const TORQUE_CONSTANT_NM_PER_A: [f64; 7] = [5.0, 5.0, 3.75, 2.0, 2.0, 2.0, 2.0];
/// Winding resistance, Ω (assumed; only the heating rate depends on it).
const WINDING_RESISTANCE_OHM: [f64; 7] = [0.3, 0.3, 0.45, 0.8, 0.8, 0.8, 0.8];
/// Thermal resistance winding → ambient, K/W (assumed).
const THERMAL_RESISTANCE_K_PER_W: f64 = 2.5;
/// Thermal time constant of a joint, s (assumed).
const THERMAL_TIME_CONSTANT_S: f64 = 300.0;
/// Ambient and power-on temperature, °C.
pub const AMBIENT_C: f64 = 25.0;
/// Nominal bus voltage, V (the controller's 48 V DC supply).
pub const BUS_VOLTAGE_V: f64 = 48.0;
/// Source resistance of the supply, Ω (assumed): the bus sags by this × total current.
const BUS_RESISTANCE_OHM: f64 = 0.02;
/// Position-loop bandwidth, rad/s: J1–J3, then the wrist.
const LOOP_BANDWIDTH_RAD_S: [f64; 2] = [60.0, 80.0];
/// Damping ratio of the position loop.
const LOOP_DAMPING_RATIO: f64 = 0.9;
/// Largest reference acceleration used as feed-forward, rad/s² (above the joints' 3 × speed
/// limits of the planner).
const MAX_FEED_FORWARD_ACC_RAD_S2: f64 = 20.0;
/// Bandwidth of the brake's spring, rad/s (a stiff hold).
const BRAKE_BANDWIDTH_RAD_S: f64 = 150.0;
/// Brake holding torque = this × the joint's effort limit (assumed).
const BRAKE_HOLD_PER_EFFORT: f64 = 1.5;
/// Speed under which a joint counts as still, rad/s.
const REST_SPEED_RAD_S: f64 = 1e-5;
/// Distance from where its loop or its brake holds it under which a still joint counts as
/// settled, rad: a fiftieth of the 0.001° the controller reports.
const REST_ERROR_RAD: f64 = 3e-7;

/// Why a plant cannot be built.
#[derive(Debug, thiserror::Error)]
pub enum PlantError {
    /// The model has no URDF (only the RM65 and RM75 families have one).
    #[error("no URDF for {model} ({dof} joints)")]
    NoUrdf {
        /// Model name.
        model: String,
        /// Its joint count.
        dof: usize,
    },
    /// The physics world refused the URDF or the initial joints.
    #[error(transparent)]
    Physics(#[from] PhysicsError),
}

/// The simulated arm: rapier world, joint controllers, brakes, electrical and thermal state.
pub struct ArmPlant {
    world: RapierWorld,
    dof: usize,
    q: Vec<f64>,
    v: Vec<f64>,
    q_ref: Vec<f64>,
    v_ref: Vec<f64>,
    /// Reference acceleration, rad/s², from successive reference speeds.
    a_ref: Vec<f64>,
    enabled: Vec<bool>,
    brakes_engaged: bool,
    /// Where each joint's brake closed (None while released).
    brake_hold: Vec<Option<f64>>,
    motor_torque_nm: Vec<f64>,
    temperature_c: Vec<f64>,
    effort_nm: Vec<f64>,
    damping: Vec<f64>,
    lower: Vec<f64>,
    upper: Vec<f64>,
    /// Steps taken since the plant was built (stepped or at rest).
    steps: u64,
    /// Every joint settled where its loop or brake holds it, nothing commanded to move: the
    /// world stands still and is not stepped (as a physics engine lets a body at rest sleep)
    /// until a command, a brake or a disturbance changes something.
    resting: bool,
}

impl std::fmt::Debug for ArmPlant {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ArmPlant")
            .field("q", &self.q)
            .field("enabled", &self.enabled)
            .field("brakes_engaged", &self.brakes_engaged)
            .finish()
    }
}

/// The URDF of a model, by joint count (RM65 family: 6, RM75 family: 7).
pub fn urdf_for(model: &ArmModel) -> Option<&'static str> {
    // The -6F variants move the flange 28.5 mm out and add 0.248 kg there; the plant keeps
    // the -B URDF (the flange pose comes from the MDH model, not from the plant).
    match model.dof {
        6 => Some(RM65B_URDF),
        7 => Some(RM75B_URDF),
        _ => None,
    }
}

impl ArmPlant {
    /// A plant of `model` at rest at `initial_rad` (one angle per joint, within the limits),
    /// all joints enabled, brakes released, holding that pose.
    pub fn new(model: &ArmModel, initial_rad: &[f64]) -> Result<Self, PlantError> {
        let urdf = urdf_for(model).ok_or_else(|| PlantError::NoUrdf {
            model: model.name.clone(),
            dof: model.dof,
        })?;
        let mut world = RapierWorld::from_urdf_str(urdf, WorldConfig::default())?;
        world.set_joint_positions(initial_rad)?;
        let joints = world.joints();
        let dof = joints.len();
        let effort_nm = joints.iter().map(|j| j.effort_limit).collect();
        let damping = joints.iter().map(|j| j.damping).collect();
        let lower = joints.iter().map(|j| j.lower).collect();
        let upper = joints.iter().map(|j| j.upper).collect();
        Ok(Self {
            world,
            dof,
            q: initial_rad.to_vec(),
            v: vec![0.0; dof],
            q_ref: initial_rad.to_vec(),
            v_ref: vec![0.0; dof],
            a_ref: vec![0.0; dof],
            enabled: vec![true; dof],
            brakes_engaged: false,
            brake_hold: vec![None; dof],
            motor_torque_nm: vec![0.0; dof],
            temperature_c: vec![AMBIENT_C; dof],
            effort_nm,
            damping,
            lower,
            upper,
            steps: 0,
            resting: false,
        })
    }

    /// The reference the joint controllers follow: positions (rad) and speeds (rad/s), one per
    /// joint. Positions are clamped into the joint range. A vector of the wrong length or with
    /// a non-finite value is ignored (the previous reference stays), with a warning.
    pub fn set_target(&mut self, positions_rad: &[f64], speeds_rad_s: &[f64]) {
        let ok = |v: &[f64]| v.len() == self.dof && v.iter().all(|x| x.is_finite());
        if !ok(positions_rad) || !ok(speeds_rad_s) {
            tracing::warn!(
                positions = positions_rad.len(),
                speeds = speeds_rad_s.len(),
                "plant target ignored: needs {} finite values each",
                self.dof
            );
            return;
        }
        let dt = self.world.config().step_s;
        let mut changed = false;
        for j in 0..self.dof {
            let q_ref = positions_rad[j].clamp(self.lower[j], self.upper[j]);
            changed |= q_ref != self.q_ref[j] || speeds_rad_s[j] != self.v_ref[j];
            self.q_ref[j] = q_ref;
            // Streamed once per step: the change of speed is the reference acceleration (an
            // inertial feed-forward); capped so that a jump in the stream cannot kick the arm.
            self.a_ref[j] = ((speeds_rad_s[j] - self.v_ref[j]) / dt)
                .clamp(-MAX_FEED_FORWARD_ACC_RAD_S2, MAX_FEED_FORWARD_ACC_RAD_S2);
            self.v_ref[j] = speeds_rad_s[j];
        }
        // A host streaming the pose the arm already holds leaves it at rest.
        if changed {
            self.resting = false;
        }
    }

    /// Enables or disables one joint (0-based; out-of-range indices are ignored). A disabled
    /// joint's motor is off and its brake holds it. Enabling a joint makes it hold where it is.
    pub fn set_enabled(&mut self, joint: usize, enabled: bool) {
        let Some(slot) = self.enabled.get_mut(joint) else {
            return;
        };
        if enabled && !*slot {
            self.q_ref[joint] = self.q[joint];
            self.v_ref[joint] = 0.0;
            self.a_ref[joint] = 0.0;
        }
        if *slot != enabled {
            self.resting = false;
        }
        *slot = enabled;
    }

    /// Engages (`true`) or releases (`false`) the brakes of all joints. While engaged the
    /// motors are off. On release each enabled joint holds where it is.
    pub fn set_brakes(&mut self, engaged: bool) {
        if self.brakes_engaged && !engaged {
            self.q_ref.clone_from(&self.q);
            self.v_ref.fill(0.0);
            self.a_ref.fill(0.0);
        }
        if self.brakes_engaged != engaged {
            self.resting = false;
        }
        self.brakes_engaged = engaged;
    }

    /// Whether joint `joint` is held by its brake now.
    pub fn is_braked(&self, joint: usize) -> bool {
        self.brakes_engaged || !self.enabled.get(joint).copied().unwrap_or(false)
    }

    /// Advances the plant by one 1 ms step.
    pub fn step(&mut self) {
        self.steps += 1;
        if self.resting {
            // Held still: the same torques hold it, and only the windings' heat moves.
            self.heat(self.world.config().step_s);
            return;
        }
        let model = self.world.model();
        let gravity = model
            .gravity_torques(&self.q, self.world.config().gravity_m_s2)
            .unwrap_or_else(|_| vec![0.0; self.dof]);
        let mass = model
            .mass_matrix(&self.q)
            .unwrap_or_else(|_| DMatrix::zeros(self.dof, self.dof));
        // Each joint asks for the acceleration of a critically damped second-order loop on
        // its reference (a released joint) or on the place its brake closed (a braked one).
        let mut acc = DVector::zeros(self.dof);
        for j in 0..self.dof {
            let (q, v) = (self.q[j], self.v[j]);
            acc[j] = if self.is_braked(j) {
                let hold = *self.brake_hold[j].get_or_insert(q);
                let w = BRAKE_BANDWIDTH_RAD_S;
                w * w * (hold - q) - 2.0 * LOOP_DAMPING_RATIO * w * v
            } else {
                self.brake_hold[j] = None;
                let w = LOOP_BANDWIDTH_RAD_S[usize::from(j >= 3)];
                self.a_ref[j]
                    + w * w * (self.q_ref[j] - q)
                    + 2.0 * LOOP_DAMPING_RATIO * w * (self.v_ref[j] - v)
            };
        }
        // Weighting by the mass matrix decouples the joints: with gains from the diagonal
        // alone, the parallel axes J2, J3, J5 form a light coupled mode that a 1 kHz loop
        // drives unstable.
        let tau = &mass * acc;
        let mut applied = vec![0.0; self.dof];
        for j in 0..self.dof {
            let load = tau[j] + gravity[j];
            let load = if load.is_finite() { load } else { 0.0 };
            if self.is_braked(j) {
                // A friction brake: holds whatever the joint needs up to its holding torque.
                let limit = BRAKE_HOLD_PER_EFFORT * self.effort_nm[j];
                applied[j] = load.clamp(-limit, limit);
                self.motor_torque_nm[j] = 0.0;
            } else {
                // Feed-forward of the joint's own viscous damping at the reference speed.
                let limit = self.effort_nm[j];
                self.motor_torque_nm[j] =
                    (load + self.damping[j] * self.v_ref[j]).clamp(-limit, limit);
                applied[j] = self.motor_torque_nm[j];
            }
        }
        self.world.step(&applied);
        // The acceleration feed-forward belongs to the step it was streamed for.
        self.a_ref.fill(0.0);
        self.q = self.world.joint_positions();
        self.v = self.world.joint_velocities();
        self.heat(self.world.config().step_s);
        self.resting = self.settled();
    }

    /// Whether every joint is still where its loop (or its brake) holds it and nothing asks it
    /// to move: the next step would leave the arm where it is (to well under what the
    /// controller reports), so it need not be computed.
    fn settled(&self) -> bool {
        if self.v_ref.iter().chain(&self.a_ref).any(|x| *x != 0.0) {
            return false;
        }
        (0..self.dof).all(|j| {
            let held_at = match self.brake_hold[j] {
                Some(hold) if self.is_braked(j) => hold,
                _ => self.q_ref[j],
            };
            self.v[j].abs() < REST_SPEED_RAD_S && (held_at - self.q[j]).abs() < REST_ERROR_RAD
        })
    }

    /// First-order thermal model: each joint tends to ambient + R_th · I²R.
    fn heat(&mut self, dt_s: f64) {
        for j in 0..self.dof {
            let i = self.motor_torque_nm[j] / TORQUE_CONSTANT_NM_PER_A[j.min(6)];
            let loss_w = i * i * WINDING_RESISTANCE_OHM[j.min(6)];
            let steady = AMBIENT_C + loss_w * THERMAL_RESISTANCE_K_PER_W;
            self.temperature_c[j] +=
                (steady - self.temperature_c[j]) * dt_s / THERMAL_TIME_CONSTANT_S;
        }
    }

    /// Joint positions, rad.
    pub fn positions_rad(&self) -> Vec<f64> {
        self.q.clone()
    }

    /// Joint speeds, rad/s.
    pub fn speeds_rad_s(&self) -> Vec<f64> {
        self.v.clone()
    }

    /// Motor torques produced in the last step, N·m (0 for a braked joint).
    pub fn torques_nm(&self) -> Vec<f64> {
        self.motor_torque_nm.clone()
    }

    /// Motor currents, mA: torque / k_t ([`TORQUE_CONSTANT_NM_PER_A`]).
    pub fn currents_ma(&self) -> Vec<f64> {
        self.motor_torque_nm
            .iter()
            .enumerate()
            .map(|(j, t)| t / TORQUE_CONSTANT_NM_PER_A[j.min(6)] * 1000.0)
            .collect()
    }

    /// Joint temperatures, °C.
    pub fn temperatures_c(&self) -> Vec<f64> {
        self.temperature_c.clone()
    }

    /// Supply voltage at each joint, V: the 48 V bus less the sag of the total current.
    pub fn voltages_v(&self) -> Vec<f64> {
        let total_a: f64 = self.currents_ma().iter().map(|i| i.abs() / 1000.0).sum();
        vec![BUS_VOLTAGE_V - BUS_RESISTANCE_OHM * total_a; self.dof]
    }

    /// Forces joint temperatures (fault injection); entries beyond the joint count are ignored,
    /// non-finite ones too.
    pub fn set_temperatures_c(&mut self, temps_c: &[f64]) {
        for (slot, t) in self.temperature_c.iter_mut().zip(temps_c) {
            if t.is_finite() {
                *slot = *t;
            }
        }
    }

    /// Simulated time since the plant was built, s.
    pub fn time_s(&self) -> f64 {
        self.steps as f64 * self.world.config().step_s
    }

    /// The physics world (link poses, contacts, the URDF model).
    pub fn world(&self) -> &RapierWorld {
        &self.world
    }

    /// The physics world, to add obstacles or disturbance torques (collision faults).
    pub fn world_mut(&mut self) -> &mut RapierWorld {
        // An obstacle or a push may move a resting arm.
        self.resting = false;
        &mut self.world
    }
}
