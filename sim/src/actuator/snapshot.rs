//! An actuator's state in the words every front end shows, whatever its kind.

/// One actuator's state: what the web view's strip, a scenario's trace and Python's robot
/// show for a joint, the same fields for every kind.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ActuatorSnapshot {
    /// The kind (`robstride`, `damiao`).
    pub kind: &'static str,
    /// The model's name as robot files write it (`RS03`, `DM4310`).
    pub model: &'static str,
    /// The CAN identifier it is addressed by now.
    pub can_id: u32,
    /// Whether it is enabled (its loops drive the joint).
    pub enabled: bool,
    /// Its control mode in the kind's words (`mit`, `position`, `velocity` …).
    pub mode: String,
    /// Shaft angle as the actuator reports it (rad, after its zero, not wrapped).
    pub angle_rad: f64,
    /// Shaft speed (rad/s).
    pub speed_rad_s: f64,
    /// Torque it produces (N·m).
    pub torque_nm: f64,
    /// Winding temperature (°C).
    pub temperature_c: f64,
    /// Faults latched now, by the names of the kind's fault table (empty when healthy).
    pub faults: Vec<String>,
    /// What only this kind has (RobStride's `run_mode` and fault word, Damiao's state
    /// nibble), by name, for the front ends that show everything.
    pub details: Vec<(&'static str, Detail)>,
}

/// One kind-specific value of an [`ActuatorSnapshot`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(untagged)]
pub enum Detail {
    /// A whole number (a mode code, a fault word).
    Int(i64),
    /// A measurement.
    Real(f64),
    /// A word.
    Word(&'static str),
}
