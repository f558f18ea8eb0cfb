//! The Arm API's data classes with the API's attribute names and units: joints in degrees,
//! joint speeds in RPM, currents in mA, gripper values 0–1000, force in 0.001 N, a pose in
//! metres and Z-Y-X Euler radians.

use std::time::UNIX_EPOCH;

use driver::arm;
use pyo3::prelude::*;

/// A flange pose: position in metres, orientation as Z-Y-X Euler angles in radians.
#[pyclass(module = "armhil", from_py_object)]
#[derive(Debug, Clone, Copy, Default)]
pub struct Pose {
    /// The driver's pose.
    pub inner: arm::Pose,
}

fn three(name: &str, v: Option<Vec<f64>>) -> PyResult<[f64; 3]> {
    match v {
        None => Ok([0.0; 3]),
        Some(v) => v.as_slice().try_into().map_err(|_| {
            pyo3::exceptions::PyValueError::new_err(format!(
                "{name} needs 3 values, got {}",
                v.len()
            ))
        }),
    }
}

#[pymethods]
impl Pose {
    /// `Pose(position=[x, y, z], euler=[rx, ry, rz])` in metres and radians.
    #[new]
    #[pyo3(signature = (position=None, euler=None))]
    fn py_new(position: Option<Vec<f64>>, euler: Option<Vec<f64>>) -> PyResult<Self> {
        Ok(Self {
            inner: arm::Pose::new(three("position", position)?, three("euler", euler)?),
        })
    }

    /// `[x, y, z]`, metres.
    #[getter]
    fn position(&self) -> [f64; 3] {
        self.inner.position_m
    }

    #[setter]
    fn set_position(&mut self, v: Vec<f64>) -> PyResult<()> {
        self.inner.position_m = three("position", Some(v))?;
        Ok(())
    }

    /// `[rx, ry, rz]`, radians (R = Rz·Ry·Rx).
    #[getter]
    fn euler(&self) -> [f64; 3] {
        self.inner.euler_rad
    }

    #[setter]
    fn set_euler(&mut self, v: Vec<f64>) -> PyResult<()> {
        self.inner.euler_rad = three("euler", Some(v))?;
        Ok(())
    }

    fn __repr__(&self) -> String {
        let [x, y, z] = self.inner.position_m;
        let [rx, ry, rz] = self.inner.euler_rad;
        format!("Pose(position=[{x:.6}, {y:.6}, {z:.6}], euler=[{rx:.6}, {ry:.6}, {rz:.6}])")
    }
}

/// Per-joint state (one entry per joint).
#[pyclass(module = "armhil", get_all, set_all, from_py_object)]
#[derive(Debug, Clone, Default)]
pub struct JointState {
    /// Joint angles, degrees.
    pub joint_position: Vec<f64>,
    /// Joint speeds, RPM.
    pub joint_speed: Vec<f64>,
    /// Joint currents, mA.
    pub joint_current: Vec<f64>,
    /// Joint temperatures, °C.
    pub joint_temperature: Vec<f64>,
    /// Joint voltages, V.
    pub joint_voltage: Vec<f64>,
    /// Joint error codes.
    pub joint_err_code: Vec<u32>,
    /// Joint enable flags.
    pub joint_en_flag: Vec<bool>,
}

#[pymethods]
impl JointState {
    /// An empty state.
    #[new]
    fn py_new() -> Self {
        Self::default()
    }

    fn __repr__(&self) -> String {
        format!("JointState(joint_position={:?})", self.joint_position)
    }
}

impl From<&arm::JointState> for JointState {
    fn from(s: &arm::JointState) -> Self {
        Self {
            joint_position: s.joint_position.clone(),
            joint_speed: s.joint_speed.clone(),
            joint_current: s.joint_current.clone(),
            joint_temperature: s.joint_temperature.clone(),
            joint_voltage: s.joint_voltage.clone(),
            joint_err_code: s.joint_err_code.clone(),
            joint_en_flag: s.joint_en_flag.clone(),
        }
    }
}

/// Force sensor data, 0.001 N / 0.001 N·m.
#[pyclass(module = "armhil", get_all, set_all, from_py_object)]
#[derive(Debug, Clone, Default)]
pub struct ArmForceSensor {
    /// Raw sensor data.
    pub force: Vec<f64>,
    /// External force in the chosen frame.
    pub zero_force: Vec<f64>,
    /// Frame of `zero_force`: 0 sensor, 1 work, 2 tool.
    pub coordinate: i32,
}

#[pymethods]
impl ArmForceSensor {
    /// An empty reading.
    #[new]
    fn py_new() -> Self {
        Self::default()
    }
}

/// Gripper state.
#[pyclass(module = "armhil", get_all, set_all, from_py_object)]
#[derive(Debug, Clone, Default)]
pub struct GripperState {
    /// 0 offline, 1 online, -1 online but disabled.
    pub status: i32,
    /// Error bits.
    pub error: u32,
    /// Operating mode 1–6.
    pub mode: i32,
    /// Force, grams.
    pub current_force: i32,
    /// Temperature, °C.
    pub temperature: i32,
    /// Aperture 0 (closed) – 1000 (open).
    pub actpos: i32,
}

#[pymethods]
impl GripperState {
    /// An offline gripper.
    #[new]
    fn py_new() -> Self {
        Self::default()
    }

    fn __repr__(&self) -> String {
        format!(
            "GripperState(status={}, error={}, mode={}, current_force={}, temperature={}, actpos={})",
            self.status, self.error, self.mode, self.current_force, self.temperature, self.actpos
        )
    }
}

impl From<&arm::GripperState> for GripperState {
    fn from(g: &arm::GripperState) -> Self {
        Self {
            status: g.status,
            error: g.error,
            mode: g.mode,
            current_force: g.current_force,
            temperature: g.temperature,
            actpos: g.actpos,
        }
    }
}

/// Modbus register access parameters.
#[pyclass(module = "armhil", get_all, set_all, from_py_object)]
#[derive(Debug, Clone, Default)]
pub struct PeripheralReadWriteParams {
    /// 0 controller RS485, 1 end-effector RS485, 3 controller Modbus TCP.
    pub port: i64,
    /// Starting data address.
    pub address: i64,
    /// Peripheral device address.
    pub device: i64,
    /// Number of data items.
    pub num: i64,
}

#[pymethods]
impl PeripheralReadWriteParams {
    /// `PeripheralReadWriteParams(port=0, address=0, device=0, num=0)`.
    #[new]
    #[pyo3(signature = (port=0, address=0, device=0, num=0))]
    fn py_new(port: i64, address: i64, device: i64, num: i64) -> Self {
        Self {
            port,
            address,
            device,
            num,
        }
    }
}

/// The realtime state of an arm, as the realtime callback receives it.
#[pyclass(module = "armhil", get_all, set_all)]
#[derive(Debug)]
pub struct ArmRealtimeState {
    /// Arm name.
    pub name: String,
    /// Wall-clock time of reception, seconds since the Unix epoch.
    pub timestamp: f64,
    /// Joint states.
    pub joint_status: Py<JointState>,
    /// Force sensor.
    pub force_sensor: Py<ArmForceSensor>,
    /// `idle`, `moving`, `paused`, `stopped`, `error` or `unknown`.
    pub arm_current_status: String,
    /// Gripper state, `None` when the arm reports none.
    pub gripper_state: Option<Py<GripperState>>,
    /// Flange pose.
    pub ee_pose: Py<Pose>,
}

fn status_name(s: arm::ArmCurrentStatus) -> &'static str {
    match s {
        arm::ArmCurrentStatus::Unknown => "unknown",
        arm::ArmCurrentStatus::Idle => "idle",
        arm::ArmCurrentStatus::Moving => "moving",
        arm::ArmCurrentStatus::Paused => "paused",
        arm::ArmCurrentStatus::Stopped => "stopped",
        arm::ArmCurrentStatus::Error => "error",
    }
}

impl ArmRealtimeState {
    /// Converts a driver state (allocates the nested Python objects).
    pub fn from_driver(py: Python<'_>, s: &arm::ArmRealtimeState) -> PyResult<Self> {
        let timestamp = s
            .timestamp
            .duration_since(UNIX_EPOCH)
            .map_or(0.0, |d| d.as_secs_f64());
        let gripper_state = match &s.gripper_state {
            Some(g) => Some(Py::new(py, GripperState::from(g))?),
            None => None,
        };
        Ok(Self {
            name: s.name.clone(),
            timestamp,
            joint_status: Py::new(py, JointState::from(&s.joint_status))?,
            force_sensor: Py::new(
                py,
                ArmForceSensor {
                    force: s.force_sensor.force.clone(),
                    zero_force: s.force_sensor.zero_force.clone(),
                    coordinate: s.force_sensor.coordinate,
                },
            )?,
            arm_current_status: status_name(s.arm_current_status).to_string(),
            gripper_state,
            ee_pose: Py::new(py, Pose { inner: s.ee_pose })?,
        })
    }
}

#[pymethods]
impl ArmRealtimeState {
    fn __repr__(&self, py: Python<'_>) -> String {
        format!(
            "ArmRealtimeState(name={:?}, timestamp={:.3}, arm_current_status={:?}, joint_position={:?})",
            self.name,
            self.timestamp,
            self.arm_current_status,
            self.joint_status.borrow(py).joint_position
        )
    }
}

/// Adds the data classes to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Pose>()?;
    m.add_class::<JointState>()?;
    m.add_class::<ArmForceSensor>()?;
    m.add_class::<GripperState>()?;
    m.add_class::<PeripheralReadWriteParams>()?;
    m.add_class::<ArmRealtimeState>()?;
    Ok(())
}
