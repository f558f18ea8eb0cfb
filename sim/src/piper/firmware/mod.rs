//! The master controller's behaviour as a synchronous state machine: frames in, a 1 ms
//! [`Firmware::tick`] that runs the joint drivers and the physics, frames out.
//!
//! Being synchronous keeps it deterministic and directly testable; the async emulator in
//! [`super::emulator`] only feeds it frames and time.

mod commands;
mod feedback;
mod protections;
#[cfg(test)]
mod tests;

use std::path::PathBuf;

use bus::CanFrame;
use nalgebra::Isometry3;

use super::codec::host::{CtrlMode, MoveMode};
use super::codec::mit::MitCommand;
use super::config::{PiperConfig, PiperError};
use super::flash::{Flash, FlashError, LinkageRole};
use super::kin;
use super::motor::{DriveLaw, JointMotor};
use super::profile::FirmwareProfile;
use super::state::{ArmStatusSnapshot, PiperSimState};
use super::trajectory::{JointMove, PathMove};
use crate::physics::{KineticFriction, ObstacleId, ObstacleShape, RapierWorld, WorldConfig};
use crate::state_file::InvalidField;

pub use protections::FaultState;

/// Physics and control period, s (1 kHz).
pub const STEP_S: f64 = 0.001;
/// From the last bit of a host's query on the wire to the first bit of the answer. No
/// published figure: an estimate for a controller that decodes the frame in its receive
/// interrupt and answers from the state of its latest 1 ms step (documented in
/// docs/timing.md as an estimate).
pub const TURNAROUND: std::time::Duration = std::time::Duration::from_micros(200);
/// Ticks between two 200 Hz feedback groups.
const HIGH_RATE_DIVIDER: u64 = 5;
/// Ticks between two 40 Hz feedback groups.
const LOW_RATE_DIVIDER: u64 = 25;
/// Position tolerance for "target reached" (0x2A1 byte 4), rad (0.1°).
const REACHED_TOL_RAD: f64 = 0.001_745;
/// Velocity tolerance for "target reached", rad/s.
const REACHED_VEL_RAD_S: f64 = 0.05;
/// Finger force per N·m of gripper torque command, N/(N·m): maps the SDK's 0–5 N·m onto the
/// URDF finger effort of 10 N.
pub const GRIPPER_FORCE_N_PER_NM: f64 = 2.0;
/// Gripper position loop: stiffness N/m and damping N·s/m per finger.
const GRIPPER_KP: f64 = 1000.0;
const GRIPPER_KD: f64 = 8.0;

/// The motion the firmware is executing.
#[derive(Debug, Clone)]
pub(crate) enum Motion {
    Joint(JointMove),
    Path(PathMove),
}

impl Motion {
    fn step(&mut self, dt: f64) -> ([f64; 6], [f64; 6]) {
        match self {
            Self::Joint(m) => m.step(dt),
            Self::Path(p) => p.step(dt),
        }
    }
    fn done(&self) -> bool {
        match self {
            Self::Joint(m) => m.done(),
            Self::Path(p) => p.done(),
        }
    }
    fn target(&self) -> [f64; 6] {
        match self {
            Self::Joint(m) => m.target(),
            Self::Path(p) => p.target(),
        }
    }
}

/// The host command a motion was planned from. A command that repeats it (SDK clients
/// re-send mode + target every few milliseconds) leaves the running profile alone instead of
/// replanning it from rest.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum TargetKey {
    /// MOVE P or MOVE L to a wire pose (0x152–0x154).
    Pose(MoveMode, [i32; 6]),
    /// MOVE C through three wire poses.
    Arc([[i32; 6]; 3]),
}

/// Gripper state.
#[derive(Debug, Clone, Default)]
pub(crate) struct Gripper {
    pub enabled: bool,
    pub target_stroke_m: f64,
    pub effort_nm: f64,
    pub force_n: f64,
}

/// Leader-arm runtime state.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) enum LeaderHoming {
    #[default]
    Drag,
    /// Moving home; `with_follower` keeps emitting joint targets so the follower follows.
    Homing { with_follower: bool },
}

/// The emulated master controller plus the physics it drives.
pub struct Firmware {
    pub(crate) profile: FirmwareProfile,
    pub(crate) world: RapierWorld,
    arm_idx: [usize; 6],
    finger_idx: [usize; 2],
    finger_sign: [f64; 2],
    /// URDF viscous damping per arm joint, N·m·s/rad: the drivers feed it forward.
    viscous: [f64; 6],
    /// Effective inertia of each arm joint at boot, kg·m² (tunes the loops, feeds forward
    /// the reference acceleration).
    inertia: [f64; 6],
    ref_acc: [f64; 6],
    pub(crate) motors: [JointMotor; 6],
    pub(crate) flash: Flash,
    state_file: Option<PathBuf>,
    flash_dirty: bool,
    /// The state file could not be written: the emulator must stop (see
    /// [`Firmware::take_save_error`]) rather than run on with changes that will be lost.
    save_error: Option<FlashError>,
    pub(crate) ticks: u64,
    pub(crate) config: PiperConfig,

    pub(crate) ctrl_mode: CtrlMode,
    pub(crate) move_mode: MoveMode,
    pub(crate) mit_flag: bool,
    pub(crate) speed_pct: u8,
    pub(crate) teach_status: u8,
    pub(crate) trajectory_num: u8,
    /// Latched status from a rejected command (0x02 no solution, 0x03 singular, 0x04 limit).
    pub(crate) command_status: Option<u8>,
    pub(crate) target_limit_bits: u8,
    pub(crate) enabled: [bool; 6],
    pub(crate) estop: bool,
    pub(crate) leader_active: bool,
    pub(crate) leader_homing: LeaderHoming,
    pub(crate) silent: bool,
    pub(crate) periodic_48x: bool,
    /// MIT was entered on a firmware that cannot leave it without a reset (< S-V1.8-6).
    pub(crate) mit_sticky: bool,

    pub(crate) motion: Option<Motion>,
    /// The pose command the current (or last completed) motion came from; cleared whenever a
    /// motion is aborted or replaced.
    pub(crate) target_key: Option<TargetKey>,
    /// Physical reference (rad, v) held when no motion runs.
    pub(crate) hold_ref: [f64; 6],
    pub(crate) ref_vel: [f64; 6],
    pub(crate) settling: bool,
    pub(crate) joint_cmd_mdeg: [i32; 6],
    pub(crate) joint_cmd_dirty: bool,
    pub(crate) pose_cmd: [i32; 6],
    pub(crate) pose_parts: u8,
    pub(crate) pose_dirty: bool,
    pub(crate) move_c_points: [Option<[i32; 6]>; 3],
    pub(crate) mit_cmd: [Option<MitCommand>; 6],
    pub(crate) gripper: Gripper,
    pub(crate) cpv_params: std::collections::BTreeMap<(u8, [u8; 2]), i32>,
    pub(crate) trajectory_name_index: u16,
    pub(crate) trajectory_crc: u16,

    pub(crate) faults: FaultState,
    pub(crate) collision_residual: [f64; 6],
    /// Ticks left before a just-enabled joint's collision protection judges its residual
    /// (see `protections::ENABLE_COLLISION_BLANK_MS`).
    pub(crate) collision_blank_ticks: [u32; 6],
    pub(crate) q: Vec<f64>,
    pub(crate) v: Vec<f64>,
    pub(crate) torques: Vec<f64>,
    pub(crate) prev_link_pose: Option<[Isometry3<f64>; 6]>,
    pub(crate) prev_link_vel: [[f64; 2]; 6],
    pub(crate) out: Vec<CanFrame>,
    /// While catching up missed steps: the newest periodic frame of each ID, sent once at the
    /// end instead of one per missed period.
    coalesced: Option<Vec<CanFrame>>,
    /// Replies the master sends after a processing delay: (tick due, frame).
    pub(crate) delayed: Vec<(u64, CanFrame)>,
}

fn load_world(config: &PiperConfig) -> Result<RapierWorld, PiperError> {
    let world_config = WorldConfig::default();
    let mut world = match &config.urdf_path {
        Some(path) => RapierWorld::from_urdf_file(path, world_config)?,
        None => RapierWorld::from_urdf_str(super::config::BUNDLED_URDF, world_config)?,
    };
    // URDF cannot carry the motors' rotor inertia: add it to joint1..joint6 here.
    for (j, armature) in super::motor::ARMATURE_KG_M2.iter().enumerate() {
        if let Some(i) = world.joint_index(&format!("joint{}", j + 1)) {
            world.set_armature(i, *armature);
        }
    }
    // The URDF friction is the joints' breakaway value; a sliding joint loses less.
    for (j, kinetic) in super::motor::KINETIC_FRICTION_NM.iter().enumerate() {
        if let Some(i) = world.joint_index(&format!("joint{}", j + 1)) {
            world.set_kinetic_friction(
                i,
                Some(KineticFriction {
                    kinetic: *kinetic,
                    stick_speed: super::motor::STICK_SPEED_RAD_S,
                }),
            );
        }
    }
    Ok(world)
}

/// Effective inertia of each arm joint at `q0`, kg·m²: the joint's diagonal entry of the
/// model's mass matrix, links plus armature (the inertia its motor drives when the other
/// joints hold still). Computed, not probed: a small test torque would not overcome the
/// joints' dry friction.
fn estimate_inertias(
    world: &RapierWorld,
    q0: &[f64],
    arm_idx: &[usize; 6],
) -> Result<[f64; 6], PiperError> {
    /// Floor for a degenerate model, kg·m².
    const MIN_INERTIA: f64 = 1e-4;
    let diagonal = world.model().mass_matrix_diagonal(q0)?;
    Ok(std::array::from_fn(|j| {
        diagonal
            .get(arm_idx[j])
            .copied()
            .filter(|i| i.is_finite())
            .unwrap_or(MIN_INERTIA)
            .max(MIN_INERTIA)
    }))
}

/// The six arm joints' and the two fingers' indices in the URDF world.
fn find_joints(world: &RapierWorld) -> Result<([usize; 6], [usize; 2]), PiperError> {
    let find = |name: &str| {
        world
            .joint_index(name)
            .ok_or_else(|| PiperError::MissingJoint {
                name: name.to_string(),
            })
    };
    Ok((
        [
            find("joint1")?,
            find("joint2")?,
            find("joint3")?,
            find("joint4")?,
            find("joint5")?,
            find("joint6")?,
        ],
        [find("joint7")?, find("joint8")?],
    ))
}

/// The flash at power-on: a state file that exists wins; a new one starts from
/// `config.flash` (or defaults). Either is checked with the commands' rules (a value no
/// command could store, min above max, would otherwise panic the core at the first move), and
/// its zero offsets against the URDF.
fn boot_flash(
    config: &PiperConfig,
    world: &RapierWorld,
    arm_idx: [usize; 6],
    finger_idx: [usize; 2],
    finger_sign: [f64; 2],
) -> Result<Flash, PiperError> {
    let from_file = config.state_file.as_ref().filter(|path| path.exists());
    let flash = match from_file {
        Some(path) => Flash::load(path)?,
        None => {
            let flash = config.flash.clone().unwrap_or_default();
            flash.validate().map_err(PiperError::InvalidFlash)?;
            flash
        }
    };
    // A zero offset is the joint's physical angle when it was zeroed (0x475), so it lies
    // within the URDF's range; the gripper's, within the fingers' travel.
    let zero_fields = arm_idx.iter().enumerate().map(|(j, &i)| {
        let lim = &world.joints()[i];
        (
            format!("flash.zero_offset_rad[{j}]"),
            flash.zero_offset_rad[j],
            lim.lower,
            lim.upper,
        )
    });
    let travel: [(f64, f64); 2] = std::array::from_fn(|k| {
        let lim = &world.joints()[finger_idx[k]];
        let (a, b) = (finger_sign[k] * lim.lower, finger_sign[k] * lim.upper);
        (a.min(b), a.max(b))
    });
    let gripper_field = (
        "flash.gripper_zero_offset_m".to_owned(),
        flash.gripper_zero_offset_m,
        travel[0].0 + travel[1].0,
        travel[0].1 + travel[1].1,
    );
    for (field, value, lower, upper) in zero_fields.chain(std::iter::once(gripper_field)) {
        if !(lower - 1e-9..=upper + 1e-9).contains(&value) {
            let invalid = InvalidField::new(
                field,
                format!("{value} is outside the URDF's range [{lower}, {upper}]"),
            );
            return Err(match from_file {
                Some(path) => PiperError::Flash(FlashError::invalid(path, invalid)),
                None => PiperError::InvalidFlash(invalid),
            });
        }
    }
    Ok(flash)
}

/// Every URDF joint's position at power-on: the configured joint angles (through the flash's
/// zero offsets, refused outside the URDF's range) and each finger at half the opening.
fn initial_positions(
    config: &PiperConfig,
    world: &RapierWorld,
    flash: &Flash,
    arm_idx: [usize; 6],
    finger_idx: [usize; 2],
    finger_sign: [f64; 2],
) -> Result<Vec<f64>, PiperError> {
    let mut q0 = vec![0.0; world.joints().len()];
    for (j, &i) in arm_idx.iter().enumerate() {
        let lim = &world.joints()[i];
        let phys = config.initial_joints_rad[j] + flash.zero_offset_rad[j];
        if !phys.is_finite() || phys < lim.lower - 1e-9 || phys > lim.upper + 1e-9 {
            return Err(PiperError::InitialJointOutOfRange {
                joint: j + 1,
                value_rad: config.initial_joints_rad[j],
                lower_rad: lim.lower,
                upper_rad: lim.upper,
            });
        }
        q0[i] = phys.clamp(lim.lower, lim.upper);
    }
    // Each finger takes half of the initial opening (clamped to its travel).
    let half_stroke_m = 0.5 * config.initial_gripper_stroke_m.max(0.0);
    for (k, &i) in finger_idx.iter().enumerate() {
        let lim = &world.joints()[i];
        q0[i] = (finger_sign[k] * half_stroke_m).clamp(lim.lower, lim.upper);
    }
    Ok(q0)
}

impl Firmware {
    /// Boot the firmware: load the URDF, the flash (state file) and place the arm.
    pub fn new(config: PiperConfig) -> Result<Self, PiperError> {
        let mut world = load_world(&config)?;
        let (arm_idx, finger_idx) = find_joints(&world)?;
        // A finger opens towards whichever side of zero its range lies on.
        let finger_sign = finger_idx.map(|i| {
            let j = &world.joints()[i];
            if j.upper > 0.0 {
                1.0
            } else if j.lower < 0.0 {
                -1.0
            } else {
                1.0
            }
        });
        let flash = boot_flash(&config, &world, arm_idx, finger_idx, finger_sign)?;
        let q0 = initial_positions(&config, &world, &flash, arm_idx, finger_idx, finger_sign)?;
        world.set_joint_positions(&q0)?;
        let viscous = std::array::from_fn(|j| world.joints()[arm_idx[j]].damping);
        let inertia = estimate_inertias(&world, &q0, &arm_idx)?;
        let motors = std::array::from_fn(|j| {
            JointMotor::new(j, world.joints()[arm_idx[j]].effort_limit, inertia[j])
        });
        let leader_active = flash.linkage_role == LinkageRole::Leader;
        let hold_ref = std::array::from_fn(|j| q0[arm_idx[j]]);
        let n = q0.len();
        let v0 = vec![0.0; n];
        Ok(Self {
            profile: config.firmware,
            world,
            arm_idx,
            finger_idx,
            finger_sign,
            viscous,
            inertia,
            ref_acc: [0.0; 6],
            motors,
            flash,
            state_file: config.state_file.clone(),
            flash_dirty: false,
            save_error: None,
            ticks: 0,
            ctrl_mode: if leader_active {
                CtrlMode::LinkageTeach
            } else {
                CtrlMode::Standby
            },
            move_mode: MoveMode::P,
            mit_flag: false,
            speed_pct: 0,
            teach_status: 0,
            trajectory_num: 0,
            command_status: None,
            target_limit_bits: 0,
            enabled: [false; 6],
            estop: false,
            leader_active,
            leader_homing: LeaderHoming::Drag,
            silent: false,
            periodic_48x: false,
            mit_sticky: false,
            motion: None,
            target_key: None,
            hold_ref,
            ref_vel: [0.0; 6],
            settling: false,
            joint_cmd_mdeg: [0; 6],
            joint_cmd_dirty: false,
            pose_cmd: [0; 6],
            pose_parts: 0,
            pose_dirty: false,
            move_c_points: [None; 3],
            mit_cmd: [None; 6],
            gripper: Gripper {
                effort_nm: 1.0,
                target_stroke_m: config.initial_gripper_stroke_m.max(0.0),
                ..Gripper::default()
            },
            cpv_params: Default::default(),
            trajectory_name_index: 0,
            trajectory_crc: 0,
            faults: FaultState::new(config.bus_voltage_v),
            collision_residual: [0.0; 6],
            collision_blank_ticks: [0; 6],
            q: q0,
            v: v0,
            torques: vec![0.0; n],
            prev_link_pose: None,
            prev_link_vel: [[0.0; 2]; 6],
            out: Vec::with_capacity(32),
            coalesced: None,
            delayed: Vec::new(),
            config,
        })
    }

    /// The firmware profile.
    pub fn profile(&self) -> FirmwareProfile {
        self.profile
    }

    /// Simulated time since boot, s.
    pub fn time_s(&self) -> f64 {
        self.ticks as f64 * STEP_S
    }

    /// Run `steps` ticks that are already late (a real-time process woke up behind its clock):
    /// the physics runs every missed step, but each periodic feedback frame is sent once, with
    /// the newest values, instead of a backlog burst of one per missed period. Replies and
    /// other event frames are kept in order.
    pub fn catch_up(&mut self, steps: u32) {
        self.coalesced = Some(Vec::new());
        for _ in 0..steps {
            self.tick();
        }
        if let Some(held) = self.coalesced.take() {
            self.out.extend(held);
        }
    }

    /// Take the frames produced since the last call, in send order.
    pub fn take_output(&mut self) -> Vec<CanFrame> {
        std::mem::take(&mut self.out)
    }

    /// Move the produced frames into `dst` (keeps this buffer's allocation).
    pub fn drain_output_into(&mut self, dst: &mut Vec<CanFrame>) {
        dst.append(&mut self.out);
    }

    /// Physical joint position (rad) of arm joint `j`.
    pub(crate) fn q_phys(&self, j: usize) -> f64 {
        self.q[self.arm_idx[j]]
    }

    /// Physical joint velocity (rad/s) of arm joint `j`.
    pub(crate) fn v_phys(&self, j: usize) -> f64 {
        self.v[self.arm_idx[j]]
    }

    /// Reported joint angle (rad): physical minus the flash zero offset.
    pub(crate) fn q_reported(&self, j: usize) -> f64 {
        self.q_phys(j) - self.flash.zero_offset_rad[j]
    }

    pub(crate) fn reported_joints(&self) -> [f64; 6] {
        std::array::from_fn(|j| self.q_reported(j))
    }

    pub(crate) fn physical_joints(&self) -> [f64; 6] {
        std::array::from_fn(|j| self.q_phys(j))
    }

    /// Gripper opening (m) as the physics has it, before the zero offset.
    pub(crate) fn gripper_stroke_phys_m(&self) -> f64 {
        self.finger_sign[0] * self.q[self.finger_idx[0]]
            + self.finger_sign[1] * self.q[self.finger_idx[1]]
    }

    /// Why the state file could not be written, once (the caller stops the emulator).
    pub(crate) fn take_save_error(&mut self) -> Option<FlashError> {
        self.save_error.take()
    }

    pub(crate) fn mark_flash_dirty(&mut self) {
        self.flash_dirty = true;
    }

    /// Flange pose at the reported joints under this firmware's DH.
    pub(crate) fn flange_pose(&self) -> Isometry3<f64> {
        kin::flange(&self.reported_joints(), self.profile)
    }

    /// Limits (rad) of every joint in the reported frame.
    pub(crate) fn limits(&self) -> [(f64, f64); 6] {
        std::array::from_fn(|j| self.flash.limits_rad(j))
    }

    /// Per-joint speed and acceleration limits scaled by the speed percentage.
    pub(crate) fn motion_limits(&self) -> ([f64; 6], [f64; 6]) {
        // Speed % scales the velocity limit only; 0 % is treated as 1 % so a move still ends.
        let pct = f64::from(self.speed_pct.clamp(1, 100)) / 100.0;
        (
            std::array::from_fn(|j| self.flash.max_speed_rad_s(j) * pct),
            std::array::from_fn(|j| self.flash.max_acc_rad_s2(j)),
        )
    }

    /// Current reference state to start a new motion from (physical frame).
    pub(crate) fn reference_state(&self) -> ([f64; 6], [f64; 6]) {
        (self.hold_ref, self.ref_vel)
    }

    /// Stop any motion and hold where the arm is now.
    pub(crate) fn hold_here(&mut self) {
        self.motion = None;
        self.target_key = None;
        self.settling = false;
        self.hold_ref = self.physical_joints();
        self.ref_vel = [0.0; 6];
        self.mit_cmd = [None; 6];
    }

    /// Whether MIT pass-through is active.
    pub(crate) fn mit_active(&self) -> bool {
        self.move_mode == MoveMode::Mit && self.mit_flag
    }

    /// Whether the arm follows host motion commands at all.
    pub(crate) fn accepts_motion(&self) -> bool {
        self.ctrl_mode == CtrlMode::Can
            && !self.estop
            && !self.leader_active
            && !self.silent
            && self.faults.blocks_motion().is_none()
    }

    /// One 1 ms step: pending commands, trajectory, joint drivers, physics, feedback.
    pub fn tick(&mut self) {
        self.apply_pending_targets();
        self.q = self.world.joint_positions();
        self.v = self.world.joint_velocities();
        self.advance_reference();
        let gravity = self
            .world
            .gravity_torques(&self.q)
            .unwrap_or_else(|_| vec![0.0; self.q.len()]);
        let mut torques = vec![0.0; self.q.len()];
        let laws = self.drive_laws(&gravity);
        for j in 0..6 {
            let (q, v) = (self.q_phys(j), self.v_phys(j));
            torques[self.arm_idx[j]] = self.motors[j].command(laws[j], q, v);
            if let DriveLaw::Track { q_ref, v_ref, .. } = laws[j] {
                let residual = self.motors[j].residual_nm(q_ref, v_ref, q, v);
                // 10 ms low-pass so a single-step spike does not trip the protection.
                self.collision_residual[j] += (residual - self.collision_residual[j]) * 0.1;
            } else {
                self.collision_residual[j] = 0.0;
            }
        }
        self.gripper_torques(&gravity, &mut torques);
        self.world.step(&torques);
        self.torques = torques;
        self.ticks += 1;
        for m in &mut self.motors {
            m.heat(STEP_S);
        }
        self.q = self.world.joint_positions();
        self.v = self.world.joint_velocities();
        for blank in &mut self.collision_blank_ticks {
            *blank = blank.saturating_sub(1);
        }
        self.check_protections();
        self.update_settling();
        let periodic_from = self.out.len();
        if !self.silent {
            if self.leader_active {
                if self.ticks.is_multiple_of(HIGH_RATE_DIVIDER) {
                    self.emit_leader();
                }
            } else {
                if self.ticks.is_multiple_of(HIGH_RATE_DIVIDER) {
                    self.emit_high_rate();
                }
                if self.ticks.is_multiple_of(LOW_RATE_DIVIDER) {
                    self.emit_low_rate();
                }
            }
        }
        if let Some(held) = &mut self.coalesced {
            let fresh: Vec<CanFrame> = self.out.drain(periodic_from..).collect();
            held.retain(|old| fresh.iter().all(|f| f.raw_id() != old.raw_id()));
            held.extend(fresh);
        }
        if !self.delayed.is_empty() {
            let now = self.ticks;
            let (due, later): (Vec<_>, Vec<_>) =
                self.delayed.drain(..).partition(|(t, _)| *t <= now);
            self.delayed = later;
            self.out.extend(due.into_iter().map(|(_, f)| f));
        }
        if self.flash_dirty {
            self.flash_dirty = false;
            if let Some(path) = &self.state_file {
                if let Err(e) = self.flash.save(path) {
                    tracing::error!(error = %e, "could not write the Piper state file");
                    self.save_error.get_or_insert(e);
                }
            }
        }
    }

    fn advance_reference(&mut self) {
        self.ref_acc = [0.0; 6];
        if let Some(motion) = &mut self.motion {
            let (q, v) = motion.step(STEP_S);
            self.ref_acc = std::array::from_fn(|j| (v[j] - self.ref_vel[j]) / STEP_S);
            self.hold_ref = q;
            self.ref_vel = v;
            if motion.done() {
                self.hold_ref = motion.target();
                self.ref_vel = [0.0; 6];
                self.motion = None;
            }
        }
        if self.leader_active {
            if let LeaderHoming::Homing { .. } = self.leader_homing {
                if self.motion.is_none() && self.settled() {
                    self.leader_homing = LeaderHoming::Drag;
                }
            }
        }
    }

    fn drive_laws(&self, gravity: &[f64]) -> [DriveLaw; 6] {
        std::array::from_fn(|j| {
            let g = gravity[self.arm_idx[j]];
            if self.faults.joint_unpowered(j) {
                return DriveLaw::Off;
            }
            if self.estop {
                return DriveLaw::Damping;
            }
            let leader_drag = self.leader_active && self.leader_homing == LeaderHoming::Drag;
            if self.ctrl_mode == CtrlMode::Teach || leader_drag {
                return DriveLaw::Compliant { tau_ff: g };
            }
            if !self.enabled[j] && !self.leader_active {
                return DriveLaw::Off;
            }
            if self.mit_active() && self.ctrl_mode == CtrlMode::Can {
                if let Some(cmd) = self.mit_cmd[j] {
                    let sign = if self.profile.mit_sign_flipped(j) {
                        -1.0
                    } else {
                        1.0
                    };
                    return DriveLaw::Mit {
                        p_rad: sign * cmd.p_des_rad + self.flash.zero_offset_rad[j],
                        v_rad_s: sign * cmd.v_des_rad_s,
                        kp: cmd.kp,
                        kd: cmd.kd,
                        tau_ff: sign * cmd.t_ff_nm * self.profile.mit_torque_factor(j),
                    };
                }
            }
            DriveLaw::Track {
                q_ref: self.hold_ref[j],
                v_ref: self.ref_vel[j],
                tau_ff: g + self.viscous[j] * self.ref_vel[j] + self.inertia[j] * self.ref_acc[j],
            }
        })
    }

    fn gripper_torques(&mut self, gravity: &[f64], torques: &mut [f64]) {
        let max_force = self.gripper.effort_nm.clamp(0.0, 5.0) * GRIPPER_FORCE_N_PER_NM;
        let stroke = self.gripper_stroke_phys_m();
        let powered = self.gripper.enabled && !self.faults.gripper_sensor_fault && !self.estop;
        let force = if powered {
            let half_err = 0.5 * (self.gripper.target_stroke_m - stroke);
            let vel = 0.5
                * (self.finger_sign[0] * self.v[self.finger_idx[0]]
                    + self.finger_sign[1] * self.v[self.finger_idx[1]]);
            (GRIPPER_KP * half_err - GRIPPER_KD * vel).clamp(-max_force, max_force)
        } else {
            0.0
        };
        self.gripper.force_n = force;
        for k in 0..2 {
            let i = self.finger_idx[k];
            torques[i] = self.finger_sign[k] * force + if powered { gravity[i] } else { 0.0 };
        }
    }

    fn settled(&self) -> bool {
        (0..6).all(|j| {
            (self.hold_ref[j] - self.q_phys(j)).abs() < REACHED_TOL_RAD
                && self.v_phys(j).abs() < REACHED_VEL_RAD_S
        })
    }

    fn update_settling(&mut self) {
        if self.motion.is_none() && self.settling && self.settled() {
            self.settling = false;
        }
    }

    /// 0x2A1 byte 4: 1 while a move runs or the arm has not yet settled on its target.
    pub(crate) fn motion_status(&self) -> u8 {
        u8::from(self.motion.is_some() || self.settling)
    }

    /// Start a motion (physical frame targets) and mark the arm as moving.
    pub(crate) fn start_motion(&mut self, motion: Motion) {
        self.motion = Some(motion);
        self.target_key = None;
        self.settling = true;
    }

    /// Drop the running motion where the reference is now (estop, teach button).
    pub(crate) fn abort_motion(&mut self) {
        self.motion = None;
        self.target_key = None;
        self.settling = false;
    }

    /// Add a static obstacle to the world.
    pub fn add_obstacle(&mut self, shape: ObstacleShape, position_m: [f64; 3]) -> ObstacleId {
        self.world.add_obstacle(shape, position_m)
    }

    /// Remove an obstacle.
    pub fn remove_obstacle(&mut self, id: ObstacleId) {
        self.world.remove_obstacle(id);
    }

    /// Byte 6 of 0x2A1: rejected-target bits plus joints currently beyond their limits.
    pub(crate) fn limit_bits(&self) -> u8 {
        let mut bits = self.target_limit_bits;
        for j in 0..6 {
            let (lo, hi) = self.flash.limits_rad(j);
            let q = self.q_reported(j);
            // Half a degree of slack: sitting on a limit is not exceeding it.
            let slack = 0.5f64.to_radians();
            if q < lo - slack || q > hi + slack {
                bits |= 1 << j;
            }
        }
        bits
    }

    /// The arm status code of 0x2A1 byte 1, most severe first.
    pub(crate) fn arm_status_code(&self) -> u8 {
        if self.estop {
            return 0x01;
        }
        if let Some(code) = self.faults.status_code() {
            return code;
        }
        self.command_status.unwrap_or(0x00)
    }

    /// Everything the harness may want to look at.
    pub fn snapshot(&self) -> PiperSimState {
        let status = ArmStatusSnapshot {
            ctrl_mode: self.ctrl_mode as u8,
            arm_status: self.arm_status_code(),
            mode_feed: self.move_mode.code(self.profile),
            motion_status: self.motion_status(),
            limit_bits: self.limit_bits(),
            comm_bits: self.faults.comm_bits(),
            enabled: std::array::from_fn(|j| self.joint_enabled_bit(j)),
            gripper_enabled: self.gripper.enabled,
            driver_status: std::array::from_fn(|j| self.driver_status_bits(j)),
        };
        PiperSimState {
            time_s: self.time_s(),
            joint_positions_rad: self.physical_joints(),
            reported_joints_rad: self.reported_joints(),
            joint_velocities_rad_s: std::array::from_fn(|j| self.v_phys(j)),
            joint_torques_nm: std::array::from_fn(|j| self.motors[j].torque_nm()),
            motor_currents_a: std::array::from_fn(|j| self.motors[j].current_a()),
            motor_temps_c: std::array::from_fn(|j| self.faults.motor_temp_c(j, &self.motors[j])),
            gripper_stroke_m: self.gripper_stroke_phys_m(),
            gripper_force_n: self.gripper.force_n,
            flange_pose: super::pose::WirePose::from_isometry(&self.flange_pose()),
            contacts: self.world.contacts().len(),
            status,
            flash: self.flash.clone(),
        }
    }
}
