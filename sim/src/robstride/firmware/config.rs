//! How one actuator is configured: its model, rig, report type and thermal figures.

use serde::{Deserialize, Serialize};

use crate::robstride::model::{Model, RangeTable, Ranges};
use crate::robstride::rig::Load;

/// Which comm type active reports use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum ReportType {
    /// Type 24 (current firmware).
    #[default]
    Type24,
    /// Type 2 (firmware before RS00 0.0.3.3, RS03 0.3.1.3, …).
    Type2,
}

/// Configuration of one emulated actuator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MotorConfig {
    /// CAN ID at first power-on (1..=127); a state file may hold a newer one.
    pub can_id: u8,
    /// Model.
    pub model: Model,
    /// What the motor drives.
    pub load: Load,
    /// Which scaling table the firmware uses.
    pub range_table: RangeTable,
    /// Explicit ranges, overriding the table (a per-model setting).
    pub ranges: Option<Ranges>,
    /// MCU unique ID; derived from the model and first CAN ID when `None` (stable).
    pub uid: Option<[u8; 8]>,
    /// Viscous friction of the rig (N·m·s/rad).
    pub friction_nm_s_per_rad: f64,
    /// Shaft angle at start (rad, 0 = pendulum hanging down).
    pub start_angle_rad: f64,
    /// Comm type of active reports.
    pub report_type: ReportType,
    /// Ambient temperature (°C).
    pub ambient_c: f64,
    /// Winding thermal time constant (s).
    pub thermal_time_constant_s: f64,
    /// Steady-state winding temperature rise at rated current (°C).
    pub thermal_rise_at_rated_c: f64,
    /// canTimeout ticks per second (manual: 20000, i.e. 50 µs ticks).
    pub can_timeout_ticks_per_s: f64,
    /// How long peak current may flow before the I²t overload trips (s).
    pub overload_time_at_peak_s: f64,
    /// Which integrator moves the rig.
    pub plant: PlantKind,
}

/// Which integrator moves the rig.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum PlantKind {
    /// The one-joint rig integrated directly (fast; default).
    #[default]
    Analytic,
    /// The rig's URDF in the rapier3d physics world ([`crate::physics::RapierWorld`]).
    World,
}

impl MotorConfig {
    /// A motor with default rig (1 kg, 0.1 m disc) and manual ranges.
    pub fn new(can_id: u8, model: Model) -> Self {
        Self {
            can_id,
            model,
            load: Load::default(),
            range_table: RangeTable::Manual,
            ranges: None,
            uid: None,
            friction_nm_s_per_rad: 0.0,
            start_angle_rad: 0.0,
            report_type: ReportType::Type24,
            ambient_c: 25.0,
            thermal_time_constant_s: 60.0,
            thermal_rise_at_rated_c: 60.0,
            can_timeout_ticks_per_s: 20_000.0,
            overload_time_at_peak_s: 2.0,
            plant: PlantKind::Analytic,
        }
    }

    /// The same motor with another load.
    pub fn with_load(mut self, load: Load) -> Self {
        self.load = load;
        self
    }

    /// The UID this motor reports: the configured one, or one derived from model and first ID.
    pub fn effective_uid(&self) -> [u8; 8] {
        self.uid.unwrap_or_else(|| {
            // FNV-1a over (model, first id): stable across runs, distinct per motor.
            let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
            for byte in self.model.name().bytes().chain([self.can_id]) {
                hash ^= u64::from(byte);
                hash = hash.wrapping_mul(0x0000_0100_0000_01B3);
            }
            hash.to_le_bytes()
        })
    }
}
