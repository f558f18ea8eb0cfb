//! One emulated Damiao motor: its frames (`frames`), its loops and watchdog (`tick`,
//! `control`), the bench's side door (`side_door`) and the actuator contract (`contract`).
//!
//! [`DamiaoMotor`] is pure and synchronous (frames in, frames out, [`DamiaoMotor::tick`] per
//! millisecond) so it can be tested without a bus; [`crate::damiao::DamiaoBus`] runs several
//! on one.

use std::time::Duration;

use bus::CanFrame;

use crate::actuator::ShaftPlant;
use crate::damiao::codec::{self, Feedback, MitCommand};
use crate::damiao::faults::ErrorSet;
use crate::damiao::model::ModelSpec;
use crate::damiao::registers::{rid, RegisterFile};
use crate::robstride::rig::RigPlant;

mod config;
mod contract;
mod control;
mod frames;
mod side_door;
mod tick;

pub use config::{MotorConfig, PersistedMotor, MAX_ID, OPENARM_MST_OFFSET};
pub use contract::EXTERNAL_TORQUE_PEAK_MULTIPLE;

/// The kind's name in the actuator registry and snapshots.
pub const KIND: &str = "damiao";

/// From a command's last bit to the reply's first: the firmware's turnaround. No source gives
/// one; 200 µs keeps a feedback frame (≈130 µs on a 1 Mbit/s wire) inside openarm_can's
/// 500 µs wait for the first reply (note §13), as hosts see on hardware.
pub const TURNAROUND: Duration = Duration::from_micros(200);

/// Control-loop substeps per 1 ms tick on the built-in rig (10 kHz, as a motor's loops run
/// faster than its host's 1 kHz).
const SUBSTEPS: u32 = 10;

/// The control mode register 10 (`CTRL_MODE`) selects.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ControlMode {
    /// 1: MIT (impedance) commands on ESC_ID.
    Mit,
    /// 2: position-velocity commands on 0x100 + ESC_ID.
    PosVel,
    /// 3: velocity commands on 0x200 + ESC_ID.
    Velocity,
    /// 4: force-position commands on 0x300 + ESC_ID.
    PosForce,
}

impl ControlMode {
    /// Every mode, in register order.
    pub const ALL: [ControlMode; 4] = [
        ControlMode::Mit,
        ControlMode::PosVel,
        ControlMode::Velocity,
        ControlMode::PosForce,
    ];

    /// The mode a `CTRL_MODE` value selects (1..=4).
    pub fn from_register(value: f64) -> Option<Self> {
        ControlMode::ALL
            .into_iter()
            .find(|mode| f64::from(mode.register_value()) == value)
    }

    /// Its `CTRL_MODE` value.
    pub fn register_value(self) -> u32 {
        match self {
            ControlMode::Mit => 1,
            ControlMode::PosVel => 2,
            ControlMode::Velocity => 3,
            ControlMode::PosForce => 4,
        }
    }

    /// Its name in snapshots: `mit`, `pos_vel`, `velocity`, `pos_force`.
    pub fn name(self) -> &'static str {
        match self {
            ControlMode::Mit => "mit",
            ControlMode::PosVel => "pos_vel",
            ControlMode::Velocity => "velocity",
            ControlMode::PosForce => "pos_force",
        }
    }

    /// The identifier offset its commands come on (added to ESC_ID).
    pub fn id_offset(self) -> u16 {
        match self {
            ControlMode::Mit => 0,
            ControlMode::PosVel => codec::POS_VEL_BASE,
            ControlMode::Velocity => codec::VELOCITY_BASE,
            ControlMode::PosForce => codec::POS_FORCE_BASE,
        }
    }
}

/// What the host last asked of each mode.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Targets {
    /// MIT setpoint (zero gains and torque until the first command after enabling).
    mit: MitCommand,
    /// Pos-vel and force-position target (rad, after the zero).
    position_rad: f64,
    /// Pos-vel and force-position speed limit (rad/s).
    speed_limit_rad_s: f64,
    /// Force-position current limit (fraction of Imax).
    current_fraction: f64,
    /// Velocity-mode target (rad/s).
    velocity_rad_s: f64,
}

/// What makes an error's cause present (the supply, temperatures, events).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Causes {
    bus_voltage_v: f64,
    mos_temp_c: f64,
    coil_temp_c: f64,
    over_current: bool,
    overload: bool,
}

/// One emulated Damiao motor.
pub struct DamiaoMotor {
    config: MotorConfig,
    spec: ModelSpec,
    registers: RegisterFile,
    /// What the last save (0xAA) and zero (FE) wrote: what `persisted` returns.
    flash: PersistedMotor,
    plant: Box<dyn ShaftPlant>,
    substeps: u32,
    enabled: bool,
    latched: ErrorSet,
    causes: Causes,
    zero_offset_rad: f64,
    targets: Targets,
    profile: control::Profile,
    position_loop: control::PositionLoop,
    speed_loop: control::SpeedLoop,
    /// Velocity mode's ramped speed reference (rad/s).
    speed_ramp_rad_s: f64,
    /// Torque the motor applies now (N·m).
    torque_nm: f64,
    /// Time since the last frame addressed to the motor (µs), for the CAN timeout.
    quiet_us: u64,
    persist_requested: bool,
}

impl std::fmt::Debug for DamiaoMotor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DamiaoMotor")
            .field("esc_id", &self.esc_id())
            .field("model", &self.config.model)
            .field("enabled", &self.enabled)
            .field("latched", &self.latched)
            .finish_non_exhaustive()
    }
}

impl DamiaoMotor {
    /// Power on a motor driving the rig its configuration describes.
    pub fn new(config: MotorConfig) -> Self {
        let spec = config.model.spec();
        let plant = Box::new(RigPlant::new(
            config.load,
            spec.rotor_inertia_kg_m2,
            config.friction_nm_s_per_rad,
            config.start_angle_rad,
        ));
        Self::with_plant(config, plant)
    }

    /// Power on a motor driving `plant` (a joint of a robot's world) instead of its rig.
    pub fn with_plant(config: MotorConfig, plant: Box<dyn ShaftPlant>) -> Self {
        let spec = config.model.spec();
        let registers = config.power_on_registers();
        let zero_offset_rad = config
            .flash
            .as_ref()
            .map(|f| f.zero_offset_rad)
            .filter(|z| z.is_finite())
            .unwrap_or(0.0);
        let flash = PersistedMotor {
            registers: registers.saved(),
            zero_offset_rad,
        };
        let ambient = if config.ambient_c.is_finite() {
            config.ambient_c
        } else {
            25.0
        };
        let mut motor = Self {
            causes: Causes {
                bus_voltage_v: spec.nominal_voltage_v,
                mos_temp_c: ambient,
                coil_temp_c: ambient,
                over_current: false,
                overload: false,
            },
            config,
            spec,
            registers,
            flash,
            plant,
            substeps: SUBSTEPS,
            enabled: false,
            latched: ErrorSet::default(),
            zero_offset_rad,
            targets: Targets::default(),
            profile: control::Profile::default(),
            position_loop: control::PositionLoop::default(),
            speed_loop: control::SpeedLoop::default(),
            speed_ramp_rad_s: 0.0,
            torque_nm: 0.0,
            quiet_us: 0,
            persist_requested: false,
        };
        motor.hold();
        motor
    }

    /// The configuration it was built from.
    pub fn config(&self) -> &MotorConfig {
        &self.config
    }

    /// Its command id now (register 8; a host may have moved it).
    pub fn esc_id(&self) -> u16 {
        self.id_register(rid::ESC_ID)
    }

    /// Its feedback id now (register 7).
    pub fn mst_id(&self) -> u16 {
        self.id_register(rid::MST_ID)
    }

    fn id_register(&self, rid: u8) -> u16 {
        // The table bounds both ids to 0..=0x7FF: the cast is exact.
        self.registers.number(rid).clamp(0.0, f64::from(MAX_ID)) as u16
    }

    /// The control mode now (register 10).
    pub fn control_mode(&self) -> ControlMode {
        ControlMode::from_register(self.registers.number(rid::CTRL_MODE))
            .unwrap_or(ControlMode::Mit)
    }

    /// The register values now (RAM, not flash).
    pub fn registers(&self) -> &RegisterFile {
        &self.registers
    }

    /// Whether the motor is enabled (its loops drive the shaft).
    pub fn is_enabled(&self) -> bool {
        self.enabled
    }

    /// The errors latched now.
    pub fn latched(&self) -> ErrorSet {
        self.latched
    }

    /// The state nibble its feedback carries: the lowest latched error, else 1 enabled / 0
    /// disabled.
    pub fn state_nibble(&self) -> u8 {
        self.latched
            .state_nibble()
            .unwrap_or(u8::from(self.enabled))
    }

    /// Shaft angle as the motor reports it (rad, after its zero).
    pub fn angle_rad(&self) -> f64 {
        self.plant.position_rad() - self.zero_offset_rad
    }

    /// Shaft speed (rad/s).
    pub fn speed_rad_s(&self) -> f64 {
        self.plant.velocity_rad_s()
    }

    /// Torque it applies now (N·m).
    pub fn torque_nm(&self) -> f64 {
        self.torque_nm
    }

    /// The feedback frame (note §5) on MST_ID, from the present state.
    pub fn feedback(&self) -> Option<CanFrame> {
        let feedback = Feedback {
            state: self.state_nibble(),
            id_nibble: (self.esc_id() & 0x0F) as u8,
            position_rad: self.angle_rad(),
            velocity_rad_s: self.speed_rad_s(),
            torque_nm: self.torque_nm,
            mos_temp_c: codec::temperature_byte(self.causes.mos_temp_c),
            rotor_temp_c: codec::temperature_byte(self.causes.coil_temp_c),
        };
        codec::standard_frame(self.mst_id(), &feedback.pack(&self.registers.ranges()))
    }

    /// Targets and loops set to hold the present state: position modes hold the present
    /// angle, velocity mode 0 rad/s, MIT zero gains and torque until the host's first
    /// setpoint (enabling never makes the joint jump toward a stale target).
    fn hold(&mut self) {
        let angle = self.angle_rad();
        self.targets = Targets {
            mit: MitCommand::default(),
            position_rad: angle,
            speed_limit_rad_s: 0.0,
            current_fraction: 1.0,
            velocity_rad_s: 0.0,
        };
        self.profile = control::Profile::at_rest(angle);
        self.position_loop = control::PositionLoop::default();
        self.speed_loop = control::SpeedLoop::default();
        self.speed_ramp_rad_s = self.speed_rad_s();
    }
}
