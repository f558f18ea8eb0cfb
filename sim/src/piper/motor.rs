//! Emulated joint motor controllers: the torque each joint driver actually produces, its
//! current, and a first-order thermal model.
//!
//! Torque constants come from the SDK's effort conversion (spec §4.5): effort (mN·m) =
//! current (mA) × 1.18125 on J1–J3 and × 0.95844 on J4–J6, i.e. k_t = 1.18125 N·m/A and
//! 0.95844 N·m/A. The emulator reports current = τ / k_t, so the SDK's effort equals the torque
//! the emulated motor produced (spec §14 #10: the disputed ×4 / ÷4 correction is not applied).
//! Torque limits are the URDF effort limits (32 N·m J1–J3, 8 N·m J4–J6, spec §9.2 (AGX)).

/// Torque constant per joint, N·m/A (spec §4.5).
pub const TORQUE_CONSTANT_NM_PER_A: [f64; 6] =
    [1.18125, 1.18125, 1.18125, 0.95844, 0.95844, 0.95844];

/// Reflected rotor inertia (armature) of each joint's geared motor, kg·m²: gear ratio² × rotor
/// inertia. AgileX publishes neither the ratios nor the rotor inertias; 0.1 kg·m² is the
/// armature MuJoCo Menagerie's Piper model gives every joint (spec §13.3, `urdf/README.md`).
/// It keeps the wrist, whose links alone weigh in at ~4e-4 kg·m², from being a near-massless
/// body that a host's MIT damping gain drives past the step's stability limit.
pub const ARMATURE_KG_M2: [f64; 6] = [0.1; 6];

/// Kinetic (sliding) dry friction of each joint, N·m: what a joint that is already moving
/// loses. The URDF's `<dynamics friction>` (1.0 N·m on J1–J3, 0.25 N·m on J4–J6) is the
/// breakaway value a joint at rest must overcome. No kinetic figure for the Piper is
/// published: 0.1 N·m is MuJoCo Menagerie's `frictionloss` for every joint of this arm (a
/// sliding friction, the model's only one), and it agrees with what field reports bound: a
/// J1 under the community controller's kp 5 settles within 0.05 rad only if kinetic friction
/// plus the 0.125 N·m the zero code of the 8-bit MIT torque field executes on J1–J3 (up to
/// S-V1.8-2) stays under 5 × 0.05 = 0.25 N·m. See `urdf/README.md`, "Dynamics".
pub const KINETIC_FRICTION_NM: [f64; 6] = [0.1; 6];

/// A joint whose speed stays at or below this for two steps is stuck and sees its breakaway
/// friction, rad/s: the resolution of the 0x251–0x256 speed field (0.001 rad/s), so a stuck
/// joint is one the arm reports as not moving. A joint that friction has stopped sits far
/// below it (rapier leaves ~1e-6 rad/s); any commanded motion (≥ 0.03 rad/s at the
/// planner's 1 %) is far above it.
pub const STICK_SPEED_RAD_S: f64 = 0.0001;

/// No-load speed of every joint motor (at the joint), rad/s: the motor cannot drive the joint
/// faster whatever it is commanded. AgileX publish no motor speed; this is an assumption:
/// above the 3 rad/s planner limit (docs/protocols/piper.md §9.2) with room for MIT moves and
/// falls, and inside the ±32.767 rad/s the 0x251–0x256 speed field can carry (§4.5).
pub const NO_LOAD_SPEED_RAD_S: f64 = 10.0;
/// Speed above which the driving torque tapers linearly to zero at [`NO_LOAD_SPEED_RAD_S`]
/// (a torque–speed line's knee), rad/s. Braking torque is never reduced.
pub const TORQUE_KNEE_SPEED_RAD_S: f64 = 8.0;

/// Position-loop bandwidth of the MOVE-mode drivers, rad/s: J1–J3, then J4–J6.
pub const LOOP_BANDWIDTH_RAD_S: [f64; 6] = [100.0, 100.0, 100.0, 150.0, 150.0, 150.0];
/// Damping ratio of the MOVE-mode position loop.
pub const LOOP_DAMPING_RATIO: f64 = 0.7;
/// Damping of the quick-stop "damping mode" (0x150 = 0x01), N·m·s/rad: the arm sinks slowly.
/// An assumption (AgileX publish no figure), sized so that the wrist holding the gripper
/// (≈ 0.47 N·m of gravity on J5) sinks at ≈ 15°/s and J2/J3 no faster than they did while a
/// sliding joint still lost its full breakaway friction.
pub const ESTOP_DAMPING: [f64; 6] = [6.0, 7.0, 5.0, 1.1, 1.1, 0.2];

/// Winding resistance used by the thermal model, Ω (phase-to-phase order of magnitude of small
/// BLDC joint motors; only the heating rate depends on it).
const WINDING_RESISTANCE_OHM: [f64; 6] = [0.15, 0.15, 0.15, 0.3, 0.3, 0.3];
/// Thermal resistance winding → ambient, K/W.
const THERMAL_RESISTANCE_K_PER_W: f64 = 4.0;
/// Thermal time constant of the winding, s.
const THERMAL_TIME_CONSTANT_S: f64 = 120.0;
/// Ambient temperature, °C (the real capture in spec §4.6 idles at 25 °C).
pub const AMBIENT_C: f64 = 25.0;
/// Motor over-temperature threshold, °C (driver status bit 1).
pub const MOTOR_OVER_TEMP_C: f64 = 90.0;
/// Driver over-temperature threshold, °C (driver status bit 3).
pub const DRIVER_OVER_TEMP_C: f64 = 80.0;
/// A fault clears once the temperature is this far below its threshold.
pub const TEMP_HYSTERESIS_C: f64 = 10.0;

/// What a joint driver is doing this step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DriveLaw {
    /// De-energised: no torque.
    Off,
    /// Damping mode: τ = −b·v.
    Damping,
    /// Follow a reference: τ = kp·(q_ref − q) + kd·(v_ref − v) + τ_ff.
    Track {
        /// Reference position, rad.
        q_ref: f64,
        /// Reference velocity, rad/s.
        v_ref: f64,
        /// Feed-forward torque (gravity, viscous, inertial), N·m.
        tau_ff: f64,
    },
    /// MIT law with the host's gains: τ = kp·(p − q) + kd·(v − q̇) + τ_ff.
    Mit {
        /// Position setpoint, rad.
        p_rad: f64,
        /// Velocity setpoint, rad/s.
        v_rad_s: f64,
        /// Stiffness, N·m/rad.
        kp: f64,
        /// Damping, N·m·s/rad.
        kd: f64,
        /// Feed-forward torque as executed, N·m.
        tau_ff: f64,
    },
    /// Gravity compensation only (teach / leader arm): the arm is compliant.
    Compliant {
        /// Gravity torque, N·m.
        tau_ff: f64,
    },
}

/// One joint's driver: torque limit, last torque, temperatures.
#[derive(Debug, Clone)]
pub struct JointMotor {
    joint: usize,
    kp: f64,
    kd: f64,
    torque_limit_nm: f64,
    torque_nm: f64,
    motor_temp_c: f64,
    driver_temp_c: f64,
}

impl JointMotor {
    /// A cold motor for 0-based `joint` with the given torque limit, its MOVE-mode loop tuned
    /// to the joint's effective inertia `inertia_kg_m2` (kp = I·ω², kd = 2ζ·I·ω).
    pub fn new(joint: usize, torque_limit_nm: f64, inertia_kg_m2: f64) -> Self {
        let w = LOOP_BANDWIDTH_RAD_S[joint.min(5)];
        Self {
            joint,
            kp: inertia_kg_m2 * w * w,
            kd: 2.0 * LOOP_DAMPING_RATIO * inertia_kg_m2 * w,
            torque_limit_nm,
            torque_nm: 0.0,
            motor_temp_c: AMBIENT_C,
            driver_temp_c: AMBIENT_C,
        }
    }

    /// Torque for this step under `law` at state (`q`, `v`), clamped to the motor's limit.
    pub fn command(&mut self, law: DriveLaw, q: f64, v: f64) -> f64 {
        let j = self.joint;
        let raw = match law {
            DriveLaw::Off => 0.0,
            DriveLaw::Damping => -ESTOP_DAMPING[j] * v,
            DriveLaw::Track {
                q_ref,
                v_ref,
                tau_ff,
            } => self.kp * (q_ref - q) + self.kd * (v_ref - v) + tau_ff,
            DriveLaw::Mit {
                p_rad,
                v_rad_s,
                kp,
                kd,
                tau_ff,
            } => kp * (p_rad - q) + kd * (v_rad_s - v) + tau_ff,
            DriveLaw::Compliant { tau_ff } => tau_ff,
        };
        let raw = if raw.is_finite() { raw } else { 0.0 };
        let torque = raw.clamp(-self.torque_limit_nm, self.torque_limit_nm);
        self.torque_nm = torque * speed_derating(torque, v);
        self.torque_nm
    }

    /// Feedback part of the MOVE-mode law (what the loop adds on top of its feed-forward),
    /// N·m: the disturbance the collision protection watches.
    pub fn residual_nm(&self, q_ref: f64, v_ref: f64, q: f64, v: f64) -> f64 {
        self.kp * (q_ref - q) + self.kd * (v_ref - v)
    }

    /// MOVE-mode stiffness (N·m/rad) and damping (N·m·s/rad).
    pub fn gains(&self) -> (f64, f64) {
        (self.kp, self.kd)
    }

    /// The torque produced in the last step, N·m.
    pub fn torque_nm(&self) -> f64 {
        self.torque_nm
    }

    /// Phase current for the last torque, A.
    pub fn current_a(&self) -> f64 {
        self.torque_nm / TORQUE_CONSTANT_NM_PER_A[self.joint]
    }

    /// Torque limit, N·m.
    pub fn torque_limit_nm(&self) -> f64 {
        self.torque_limit_nm
    }

    /// Advance the thermal model by `dt_s` with the current I²R loss.
    pub fn heat(&mut self, dt_s: f64) {
        let i = self.current_a();
        let loss_w = i * i * WINDING_RESISTANCE_OHM[self.joint];
        let steady_motor = AMBIENT_C + loss_w * THERMAL_RESISTANCE_K_PER_W;
        self.motor_temp_c += (steady_motor - self.motor_temp_c) * dt_s / THERMAL_TIME_CONSTANT_S;
        // The driver sees the same loss through its MOSFETs, at half the rise.
        let steady_driver = AMBIENT_C + 0.5 * loss_w * THERMAL_RESISTANCE_K_PER_W;
        self.driver_temp_c += (steady_driver - self.driver_temp_c) * dt_s / THERMAL_TIME_CONSTANT_S;
    }

    /// Motor winding temperature, °C.
    pub fn motor_temp_c(&self) -> f64 {
        self.motor_temp_c
    }

    /// Driver temperature, °C.
    pub fn driver_temp_c(&self) -> f64 {
        self.driver_temp_c
    }

    /// Force the temperatures (fault injection).
    pub fn set_temps(&mut self, motor_c: Option<f64>, driver_c: Option<f64>) {
        if let Some(t) = motor_c {
            self.motor_temp_c = t;
        }
        if let Some(t) = driver_c {
            self.driver_temp_c = t;
        }
    }
}

/// Fraction of `torque` the motor can still produce at joint speed `v`: 1 when braking or
/// below the knee, falling linearly to 0 at the no-load speed.
fn speed_derating(torque: f64, v: f64) -> f64 {
    if torque * v <= 0.0 || !v.is_finite() {
        return 1.0;
    }
    ((NO_LOAD_SPEED_RAD_S - v.abs()) / (NO_LOAD_SPEED_RAD_S - TORQUE_KNEE_SPEED_RAD_S))
        .clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn strong_mit() -> DriveLaw {
        DriveLaw::Mit {
            p_rad: 0.0,
            v_rad_s: 45.0,
            kp: 0.0,
            kd: 5.0,
            tau_ff: 8.0,
        }
    }

    #[test]
    fn driving_torque_tapers_to_zero_at_the_no_load_speed() {
        let mut m = JointMotor::new(5, 8.0, 0.1);
        assert_eq!(m.command(strong_mit(), 0.0, 5.0), 8.0);
        let half = m.command(strong_mit(), 0.0, 9.0);
        assert!((half - 4.0).abs() < 1e-9, "{half}");
        assert_eq!(m.command(strong_mit(), 0.0, NO_LOAD_SPEED_RAD_S), 0.0);
        // Braking is never reduced.
        assert_eq!(
            m.command(DriveLaw::Damping, 0.0, 20.0),
            -ESTOP_DAMPING[5] * 20.0
        );
    }

    #[test]
    fn a_strong_mit_command_cannot_spin_a_joint_past_the_no_load_speed() {
        // Joint 6 with its armature alone, driven flat out for 2 s.
        let inertia = ARMATURE_KG_M2[5];
        let mut m = JointMotor::new(5, 8.0, inertia);
        let (mut q, mut v) = (0.0, 0.0);
        let mut peak: f64 = 0.0;
        for _ in 0..2000 {
            let torque = m.command(strong_mit(), q, v);
            v += torque / inertia * 1e-3;
            q += v * 1e-3;
            peak = peak.max(v.abs());
        }
        assert!(peak <= NO_LOAD_SPEED_RAD_S + 0.1, "peak {peak} rad/s");
        assert!(peak > TORQUE_KNEE_SPEED_RAD_S, "peak {peak} rad/s");
    }

    #[test]
    fn torque_is_clamped_and_current_follows() {
        let mut m = JointMotor::new(0, 32.0, 0.1);
        let t = m.command(
            DriveLaw::Mit {
                p_rad: 1.0,
                v_rad_s: 0.0,
                kp: 500.0,
                kd: 0.0,
                tau_ff: 0.0,
            },
            0.0,
            0.0,
        );
        assert_eq!(t, 32.0);
        assert!((m.current_a() - 32.0 / 1.18125).abs() < 1e-12);
        let mut w = JointMotor::new(4, 8.0, 0.01);
        assert_eq!(
            w.command(DriveLaw::Compliant { tau_ff: -20.0 }, 0.0, 0.0),
            -8.0
        );
        assert_eq!(w.command(DriveLaw::Off, 0.0, 5.0), 0.0);
    }

    #[test]
    fn heats_under_load_and_cools_at_rest() {
        let mut m = JointMotor::new(1, 32.0, 0.1);
        m.command(DriveLaw::Compliant { tau_ff: 20.0 }, 0.0, 0.0);
        for _ in 0..60_000 {
            m.heat(0.001);
        }
        let hot = m.motor_temp_c();
        assert!(hot > AMBIENT_C + 50.0, "{hot}");
        m.command(DriveLaw::Off, 0.0, 0.0);
        for _ in 0..60_000 {
            m.heat(0.001);
        }
        assert!(m.motor_temp_c() < hot - 20.0);
    }
}
