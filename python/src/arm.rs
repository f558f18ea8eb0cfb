//! `ArmFactory`, `ArmFactoryParam` and `ArmInterface`: the vendor-neutral Arm API over
//! `driver::arm`. Methods return an `AbcErrorCode` (or `(AbcErrorCode, value)`) exactly as the
//! API documents; the message of the last failure is kept in `ArmInterface.last_error`.

use std::collections::BTreeMap;
use std::net::{IpAddr, Ipv4Addr};
use std::sync::{Arc, Mutex};

use driver::arm::{
    self as darm, AbcErrorCode, ArmError, ArmResult, IkMode, MoveOptions, TrajectoryMode,
};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyString};

use crate::types::{ArmRealtimeState, GripperState, PeripheralReadWriteParams, Pose};
use crate::{block_on, code_object, driver_runtime, runtime_error};

/// Why the last `ArmFactory` call returned `None`.
static FACTORY_ERROR: Mutex<String> = Mutex::new(String::new());

fn set_factory_error(e: &ArmError) {
    *FACTORY_ERROR.lock().unwrap_or_else(|p| p.into_inner()) = e.to_string();
}

/// A dictionary's values as strings: `str` as is, `bool` as `true`/`false`, `int` in
/// decimal; anything else is a `RuntimeError` naming the key.
fn string_map(params: &Bound<'_, PyDict>) -> PyResult<BTreeMap<String, String>> {
    let mut map = BTreeMap::new();
    for (k, v) in params.iter() {
        let key: String = k
            .extract()
            .map_err(|_| runtime_error(format!("parameter key {k} is not a string")))?;
        let value = if let Ok(s) = v.cast::<PyString>() {
            s.to_string()
        } else if let Ok(b) = v.cast::<PyBool>() {
            b.is_true().to_string()
        } else if let Ok(n) = v.extract::<i64>() {
            n.to_string()
        } else {
            return Err(runtime_error(format!(
                "parameter {key:?}: {v} is not a string"
            )));
        };
        map.insert(key, value);
    }
    Ok(map)
}

/// The parameters that create an arm. `ArmFactoryParam(dict)` validates the dictionary
/// (a missing or malformed key is a `RuntimeError`); every attribute is read-write.
#[pyclass(module = "armhil")]
#[derive(Debug, Clone)]
pub struct ArmFactoryParam {
    inner: darm::ArmFactoryParam,
}

fn bad_value(key: &str, e: impl std::fmt::Display) -> PyErr {
    runtime_error(format!("ArmFactoryParam.{key}: {e}"))
}

fn port_of(key: &str, v: i64) -> PyResult<u16> {
    u16::try_from(v).map_err(|_| bad_value(key, format!("{v} is outside 0..=65535")))
}

#[pymethods]
impl ArmFactoryParam {
    /// `ArmFactoryParam()` (a Realman arm at 127.0.0.1:8080) or `ArmFactoryParam(dict)`.
    #[new]
    #[pyo3(signature = (arg0=None))]
    fn py_new(arg0: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let inner = match arg0 {
            None => darm::ArmFactoryParam::realman(
                "arm",
                IpAddr::V4(Ipv4Addr::LOCALHOST),
                8080,
                Ipv4Addr::LOCALHOST,
            ),
            Some(d) => darm::ArmFactoryParam::from_map(&string_map(d)?)
                .map_err(|e| runtime_error(format!("ArmFactoryParam: {e}")))?,
        };
        Ok(Self { inner })
    }

    /// Vendor: `realman` or `piper`.
    #[getter]
    fn arm_type(&self) -> &'static str {
        self.inner.arm_type.name()
    }
    #[setter]
    fn set_arm_type(&mut self, v: &str) -> PyResult<()> {
        self.inner.arm_type = v.parse().map_err(|e| bad_value("arm_type", e))?;
        Ok(())
    }
    /// Instance name.
    #[getter]
    fn arm_name(&self) -> String {
        self.inner.arm_name.clone()
    }
    #[setter]
    fn set_arm_name(&mut self, v: String) {
        self.inner.arm_name = v;
    }
    /// Controller IP (Realman).
    #[getter]
    fn ip(&self) -> String {
        self.inner.ip.to_string()
    }
    #[setter]
    fn set_ip(&mut self, v: &str) -> PyResult<()> {
        self.inner.ip = v.trim().parse().map_err(|e| bad_value("ip", e))?;
        Ok(())
    }
    /// Controller TCP port (Realman).
    #[getter]
    fn port(&self) -> u16 {
        self.inner.port
    }
    #[setter]
    fn set_port(&mut self, v: i64) -> PyResult<()> {
        self.inner.port = port_of("port", v)?;
        Ok(())
    }
    /// Local IP the realtime state is pushed to (Realman).
    #[getter]
    fn udp_ip(&self) -> String {
        self.inner.udp_ip.to_string()
    }
    #[setter]
    fn set_udp_ip(&mut self, v: &str) -> PyResult<()> {
        self.inner.udp_ip = v.trim().parse().map_err(|e| bad_value("udp_ip", e))?;
        Ok(())
    }
    /// Local UDP port of the push (Realman; 0 = any free port).
    #[getter]
    fn udp_port(&self) -> u16 {
        self.inner.udp_port
    }
    #[setter]
    fn set_udp_port(&mut self, v: i64) -> PyResult<()> {
        self.inner.udp_port = port_of("udp_port", v)?;
        Ok(())
    }
    /// Push period in units of 5 ms (Realman, 1–20000).
    #[getter]
    fn udp_cycle(&self) -> u32 {
        self.inner.udp_cycle
    }
    #[setter]
    fn set_udp_cycle(&mut self, v: i64) -> PyResult<()> {
        if !(1..=20_000).contains(&v) {
            return Err(bad_value("udp_cycle", format!("{v} is outside 1..=20000")));
        }
        self.inner.udp_cycle = v as u32;
        Ok(())
    }
    /// Whether the gripper is read for the realtime state.
    #[getter]
    fn enable_gripper(&self) -> bool {
        self.inner.enable_gripper
    }
    #[setter]
    fn set_enable_gripper(&mut self, v: bool) {
        self.inner.enable_gripper = v;
    }
    /// SocketCAN interface (Piper), or the bus name on the socketcand server.
    #[getter]
    fn can_interface(&self) -> String {
        self.inner.can_interface.clone()
    }
    #[setter]
    fn set_can_interface(&mut self, v: String) {
        self.inner.can_interface = v;
    }
    /// `HOST:PORT` of a socketcand server (Piper), or `None` for SocketCAN.
    #[getter]
    fn socketcand(&self) -> Option<String> {
        self.inner.socketcand.clone()
    }
    #[setter]
    fn set_socketcand(&mut self, v: Option<String>) {
        self.inner.socketcand = v;
    }

    fn __repr__(&self) -> String {
        format!(
            "ArmFactoryParam(arm_type={:?}, arm_name={:?})",
            self.inner.arm_type.name(),
            self.inner.arm_name
        )
    }
}

/// Creates arms. All methods are static.
#[pyclass(module = "armhil")]
pub struct ArmFactory;

#[pymethods]
impl ArmFactory {
    /// `create_arm(vendor_type, name, params)` or `create_arm(param)`: an unconnected arm,
    /// or `None` when the parameters are wrong (`ArmFactory.last_error()` says why).
    #[staticmethod]
    #[pyo3(signature = (vendor_type, name=None, params=None))]
    fn create_arm(
        vendor_type: &Bound<'_, PyAny>,
        name: Option<String>,
        params: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Option<ArmInterface>> {
        if let Ok(param) = vendor_type.cast::<ArmFactoryParam>() {
            let p = param.borrow().inner.clone();
            return Ok(Some(ArmInterface::new(darm::create_arm(p))));
        }
        let vendor: String = vendor_type.extract()?;
        let name = name.ok_or_else(|| {
            pyo3::exceptions::PyTypeError::new_err(
                "create_arm(vendor_type, name, params) needs a name",
            )
        })?;
        let map = match params {
            Some(d) => string_map(d)?,
            None => BTreeMap::new(),
        };
        match darm::create_arm_from_map(&vendor, &name, &map) {
            Ok(arm) => Ok(Some(ArmInterface::new(arm))),
            Err(e) => {
                set_factory_error(&e);
                Ok(None)
            }
        }
    }

    /// An unconnected arm from a JSON configuration file, or `None` when the file is
    /// unreadable or wrong (`ArmFactory.last_error()` says why).
    #[staticmethod]
    fn create_arm_from_config(config_path: std::path::PathBuf) -> Option<ArmInterface> {
        match darm::create_arm_from_config(&config_path) {
            Ok(arm) => Some(ArmInterface::new(arm)),
            Err(e) => {
                set_factory_error(&e);
                None
            }
        }
    }

    /// Why the last factory call returned `None` (empty when none failed).
    #[staticmethod]
    fn last_error() -> String {
        FACTORY_ERROR
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .clone()
    }
}

/// One robot arm, whatever its vendor.
#[pyclass(module = "armhil", frozen)]
pub struct ArmInterface {
    arm: Arc<dyn darm::ArmInterface>,
    last_error: Mutex<String>,
}

/// An integer argument that must fit `T`: otherwise `PARAM_OUT_OF_RANGE`.
fn fit<T: TryFrom<i64>>(field: &str, v: i64, range: &str) -> ArmResult<T> {
    T::try_from(v).map_err(|_| ArmError::out_of_range(field, v, range))
}

/// A 0/1 flag argument.
fn flag(field: &str, v: i64) -> ArmResult<bool> {
    match v {
        0 => Ok(false),
        1 => Ok(true),
        _ => Err(ArmError::out_of_range(field, v, "0 or 1")),
    }
}

fn move_options(v: i64, r: i64, trajectory_connect: i64, block: i64) -> ArmResult<MoveOptions> {
    Ok(MoveOptions {
        speed_percent: fit("v", v, "1..=100")?,
        blend_radius: fit("r", r, "0..=100")?,
        trajectory_connect: flag("trajectory_connect", trajectory_connect)?,
        block: flag("block", block)?,
    })
}

fn six(field: &str, v: &[i64]) -> ArmResult<[i32; 6]> {
    if v.len() != 6 {
        return Err(ArmError::new(
            AbcErrorCode::InvalidArgument,
            format!("{field} needs 6 values, got {}", v.len()),
        ));
    }
    let mut out = [0i32; 6];
    for (o, x) in out.iter_mut().zip(v) {
        *o = fit(field, *x, "a 32-bit integer")?;
    }
    Ok(out)
}

impl ArmInterface {
    fn new(arm: Arc<dyn darm::ArmInterface>) -> Self {
        Self {
            arm,
            last_error: Mutex::new(String::new()),
        }
    }

    /// The code of `r`, remembering the message of a failure.
    fn code<T>(&self, py: Python<'_>, r: &ArmResult<T>) -> Py<PyAny> {
        match r {
            Ok(_) => code_object(py, AbcErrorCode::Success),
            Err(e) => {
                *self.last_error.lock().unwrap_or_else(|p| p.into_inner()) = e.to_string();
                code_object(py, e.code)
            }
        }
    }

    /// Runs an async driver call with the GIL released; returns its code.
    fn run<F>(&self, py: Python<'_>, fut: F) -> Py<PyAny>
    where
        F: std::future::Future<Output = ArmResult<()>> + Send,
    {
        let r = block_on(py, driver_runtime(), fut);
        self.code(py, &r)
    }
}

#[pymethods]
impl ArmInterface {
    /// The arm's instance name.
    #[getter]
    fn name(&self) -> String {
        self.arm.name().to_string()
    }

    /// The message of the last failed call (empty when none failed).
    #[getter]
    fn last_error(&self) -> String {
        self.last_error
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .clone()
    }

    /// The methods this arm's vendor implements (the others return NOT_IMPLEMENTED).
    fn capabilities(&self) -> Vec<&'static str> {
        self.arm.capabilities().iter().map(|m| m.name()).collect()
    }

    /// Opens the link to the arm.
    fn connect(&self, py: Python<'_>) -> Py<PyAny> {
        self.run(py, self.arm.connect())
    }

    /// Closes the link (motion is not stopped).
    fn disconnect(&self, py: Python<'_>) {
        block_on(py, driver_runtime(), self.arm.disconnect());
    }

    /// Planned joint move to `joints` (degrees).
    #[pyo3(signature = (joints, v, r=0, trajectory_connect=0, block=1))]
    fn move_joint_position(
        &self,
        py: Python<'_>,
        joints: Vec<f64>,
        v: i64,
        r: i64,
        trajectory_connect: i64,
        block: i64,
    ) -> Py<PyAny> {
        let arm = &self.arm;
        self.run(py, async move {
            let o = move_options(v, r, trajectory_connect, block)?;
            arm.move_joint_position(&joints, o).await
        })
    }

    /// Straight-line Cartesian move to `pose`.
    #[pyo3(signature = (pose, v, r=0, trajectory_connect=0, block=1))]
    fn move_cartesian_linear(
        &self,
        py: Python<'_>,
        pose: Pose,
        v: i64,
        r: i64,
        trajectory_connect: i64,
        block: i64,
    ) -> Py<PyAny> {
        let arm = &self.arm;
        self.run(py, async move {
            let o = move_options(v, r, trajectory_connect, block)?;
            arm.move_cartesian_linear(&pose.inner, o).await
        })
    }

    /// Joint-space move to `pose`.
    #[pyo3(signature = (pose, v, r=0, trajectory_connect=0, block=1))]
    fn move_joint_pose(
        &self,
        py: Python<'_>,
        pose: Pose,
        v: i64,
        r: i64,
        trajectory_connect: i64,
        block: i64,
    ) -> Py<PyAny> {
        let arm = &self.arm;
        self.run(py, async move {
            let o = move_options(v, r, trajectory_connect, block)?;
            arm.move_joint_pose(&pose.inner, o).await
        })
    }

    /// Joint passthrough (no planning).
    #[pyo3(signature = (joints, follow, trajectory_mode=0, radio=0))]
    fn move_joint_position_canfd(
        &self,
        py: Python<'_>,
        joints: Vec<f64>,
        follow: bool,
        trajectory_mode: i64,
        radio: i64,
    ) -> Py<PyAny> {
        let arm = &self.arm;
        self.run(py, async move {
            let mode = trajectory_mode_of(trajectory_mode, radio)?;
            arm.move_joint_position_canfd(&joints, follow, mode).await
        })
    }

    /// Cartesian passthrough (no planning).
    #[pyo3(signature = (pose, follow, trajectory_mode=0, radio=0))]
    fn move_cartesian_pose_canfd(
        &self,
        py: Python<'_>,
        pose: Pose,
        follow: bool,
        trajectory_mode: i64,
        radio: i64,
    ) -> Py<PyAny> {
        let arm = &self.arm;
        self.run(py, async move {
            let mode = trajectory_mode_of(trajectory_mode, radio)?;
            arm.move_cartesian_pose_canfd(&pose.inner, follow, mode)
                .await
        })
    }

    /// Joint-space following of `joints` (degrees).
    fn move_joint_follow(&self, py: Python<'_>, joints: Vec<f64>) -> Py<PyAny> {
        let arm = &self.arm;
        self.run(py, async move { arm.move_joint_follow(&joints).await })
    }

    /// Cartesian following of `pose`.
    fn move_pose_follow(&self, py: Python<'_>, pose: Pose) -> Py<PyAny> {
        let arm = &self.arm;
        self.run(py, async move { arm.move_pose_follow(&pose.inner).await })
    }

    /// Calls `callback(ArmRealtimeState)` for every realtime state (on a driver thread, with
    /// the GIL taken). `None` removes the callback. An exception in the callback is reported
    /// as unraisable and the stream goes on.
    fn realtime_arm_state_call_back(&self, callback: Option<Bound<'_, PyAny>>) -> PyResult<()> {
        let Some(callback) = callback else {
            self.arm.realtime_hub().clear_callback();
            return Ok(());
        };
        if !callback.is_callable() {
            return Err(pyo3::exceptions::PyTypeError::new_err(
                "realtime_arm_state_call_back needs a callable",
            ));
        }
        let cb: Py<PyAny> = callback.unbind();
        let _guard = driver_runtime().enter();
        self.arm
            .realtime_arm_state_call_back(Box::new(move |state| deliver(&cb, &state)))
            .map_err(|e| runtime_error(e.to_string()))
    }

    /// Decelerates and stops on the path.
    fn set_arm_slow_stop(&self, py: Python<'_>) -> Py<PyAny> {
        self.run(py, self.arm.set_arm_slow_stop())
    }

    /// Stops at once (not resumable).
    fn set_arm_stop(&self, py: Python<'_>) -> Py<PyAny> {
        self.run(py, self.arm.set_arm_stop())
    }

    /// Pauses the trajectory (resumable).
    fn set_arm_pause(&self, py: Python<'_>) -> Py<PyAny> {
        self.run(py, self.arm.set_arm_pause())
    }

    /// Resumes a paused trajectory.
    fn set_arm_continue(&self, py: Python<'_>) -> Py<PyAny> {
        self.run(py, self.arm.set_arm_continue())
    }

    /// End-effector protocol mode (0 off, or a baud rate).
    fn set_plus_mode(&self, py: Python<'_>, mode: i64) -> Py<PyAny> {
        let arm = &self.arm;
        self.run(py, async move {
            arm.set_plus_mode(fit("mode", mode, "0, 9600, 115200, 256000, 460800")?)
                .await
        })
    }

    /// Opens the gripper fully.
    fn set_gripper_release(
        &self,
        py: Python<'_>,
        speed: i64,
        block: &Bound<'_, PyAny>,
        timeout: i64,
    ) -> PyResult<Py<PyAny>> {
        let block = block.is_truthy()?;
        let arm = &self.arm;
        Ok(self.run(py, async move {
            arm.set_gripper_release(
                fit("speed", speed, "1..=1000")?,
                block,
                fit("timeout", timeout, "0..")?,
            )
            .await
        }))
    }

    /// Closes the gripper under force control.
    fn set_gripper_pick(
        &self,
        py: Python<'_>,
        speed: i64,
        force: i64,
        block: &Bound<'_, PyAny>,
        timeout: i64,
    ) -> PyResult<Py<PyAny>> {
        let block = block.is_truthy()?;
        let arm = &self.arm;
        Ok(self.run(py, async move {
            arm.set_gripper_pick(
                fit("speed", speed, "1..=1000")?,
                fit("force", force, "50..=1000")?,
                block,
                fit("timeout", timeout, "0..")?,
            )
            .await
        }))
    }

    /// Closes the gripper and keeps gripping.
    fn set_gripper_pick_on(
        &self,
        py: Python<'_>,
        speed: i64,
        force: i64,
        block: &Bound<'_, PyAny>,
        timeout: i64,
    ) -> PyResult<Py<PyAny>> {
        let block = block.is_truthy()?;
        let arm = &self.arm;
        Ok(self.run(py, async move {
            arm.set_gripper_pick_on(
                fit("speed", speed, "1..=1000")?,
                fit("force", force, "50..=1000")?,
                block,
                fit("timeout", timeout, "0..")?,
            )
            .await
        }))
    }

    /// Moves the gripper to an aperture 1–1000.
    fn set_gripper_position(
        &self,
        py: Python<'_>,
        position: i64,
        block: &Bound<'_, PyAny>,
        timeout: i64,
    ) -> PyResult<Py<PyAny>> {
        let block = block.is_truthy()?;
        let arm = &self.arm;
        Ok(self.run(py, async move {
            arm.set_gripper_position(
                fit("position", position, "1..=1000")?,
                block,
                fit("timeout", timeout, "0..")?,
            )
            .await
        }))
    }

    /// `(code, GripperState)`.
    fn get_gripper_state(&self, py: Python<'_>) -> PyResult<(Py<PyAny>, GripperState)> {
        let r = block_on(py, driver_runtime(), self.arm.get_gripper_state());
        let code = self.code(py, &r);
        Ok((code, r.as_ref().map(GripperState::from).unwrap_or_default()))
    }

    /// Dexterous hand: pre-stored gesture 1–40.
    fn set_hand_posture(
        &self,
        py: Python<'_>,
        posture_num: i64,
        block: &Bound<'_, PyAny>,
        timeout: i64,
    ) -> PyResult<Py<PyAny>> {
        let block = block.is_truthy()?;
        let arm = &self.arm;
        Ok(self.run(py, async move {
            arm.set_hand_posture(
                fit("posture_num", posture_num, "1..=40")?,
                block,
                fit("timeout", timeout, "0..")?,
            )
            .await
        }))
    }

    /// Dexterous hand: six finger angles (0–1000, -1 = keep).
    fn set_hand_angle(&self, py: Python<'_>, hand_angle: Vec<i64>) -> Py<PyAny> {
        let arm = &self.arm;
        self.run(py, async move {
            arm.set_hand_angle(six("hand_angle", &hand_angle)?).await
        })
    }

    /// Dexterous hand: angle following; `block` = wait in ms (0 = non-blocking).
    fn set_hand_follow_angle(&self, py: Python<'_>, hand_angle: Vec<i64>, block: i64) -> Py<PyAny> {
        let arm = &self.arm;
        self.run(py, async move {
            arm.set_hand_follow_angle(six("hand_angle", &hand_angle)?, fit("block", block, "0..")?)
                .await
        })
    }

    /// Dexterous hand: position following; `block` = wait in ms (0 = non-blocking).
    fn set_hand_follow_pos(&self, py: Python<'_>, hand_pos: Vec<i64>, block: i64) -> Py<PyAny> {
        let arm = &self.arm;
        self.run(py, async move {
            arm.set_hand_follow_pos(six("hand_pos", &hand_pos)?, fit("block", block, "0..")?)
                .await
        })
    }

    /// Dexterous hand finger speed 1–1000.
    fn set_hand_speed(&self, py: Python<'_>, speed: i64) -> Py<PyAny> {
        let arm = &self.arm;
        self.run(py, async move {
            arm.set_hand_speed(fit("speed", speed, "1..=1000")?).await
        })
    }

    /// Dexterous hand finger force 1–1000.
    fn set_hand_force(&self, py: Python<'_>, hand_force: i64) -> Py<PyAny> {
        let arm = &self.arm;
        self.run(py, async move {
            arm.set_hand_force(fit("hand_force", hand_force, "1..=1000")?)
                .await
        })
    }

    /// `(code, joint angles in degrees)`.
    fn get_joint_degree(&self, py: Python<'_>) -> (Py<PyAny>, Vec<f64>) {
        let r = block_on(py, driver_runtime(), self.arm.get_joint_degree());
        (self.code(py, &r), r.unwrap_or_default())
    }

    /// `(code, Pose)` of the flange for `joints` (degrees).
    fn forward_kinematics(&self, py: Python<'_>, joints: Vec<f64>) -> (Py<PyAny>, Pose) {
        let r = block_on(py, driver_runtime(), self.arm.forward_kinematics(&joints));
        let code = self.code(py, &r);
        (
            code,
            Pose {
                inner: r.unwrap_or_default(),
            },
        )
    }

    /// `(code, joint angles in degrees)` reaching `pose`, starting from `ref_joints`.
    #[pyo3(signature = (pose, ref_joints, mode=0))]
    fn inverse_kinematics(
        &self,
        py: Python<'_>,
        pose: Pose,
        ref_joints: Vec<f64>,
        mode: i64,
    ) -> (Py<PyAny>, Vec<f64>) {
        let arm = &self.arm;
        let r = block_on(py, driver_runtime(), async move {
            let mode = match mode {
                0 => IkMode::SingleStep,
                1 => IkMode::IterativeSearch,
                other => return Err(ArmError::out_of_range("mode", other, "0 or 1")),
            };
            arm.inverse_kinematics(&pose.inner, &ref_joints, mode).await
        });
        (self.code(py, &r), r.unwrap_or_default())
    }

    /// Modbus RTU mode on `port` at `baudrate`, reply timeout in 100 ms units.
    fn set_modbus_mode(&self, py: Python<'_>, port: i64, baudrate: i64, timeout: i64) -> Py<PyAny> {
        let arm = &self.arm;
        self.run(py, async move {
            arm.set_modbus_mode(
                fit("port", port, "0..=2")?,
                fit("baudrate", baudrate, "9600, 115200, 460800")?,
                fit("timeout", timeout, "0..")?,
            )
            .await
        })
    }

    /// Ends Modbus RTU mode on `port`.
    fn close_modbus_mode(&self, py: Python<'_>, port: i64) -> Py<PyAny> {
        let arm = &self.arm;
        self.run(py, async move {
            arm.close_modbus_mode(fit("port", port, "0..=2")?).await
        })
    }

    /// Writes `values` (0–65535 each) to consecutive registers.
    fn write_registers(
        &self,
        py: Python<'_>,
        params: PeripheralReadWriteParams,
        values: Vec<i64>,
    ) -> Py<PyAny> {
        let arm = &self.arm;
        self.run(py, async move {
            let p = darm::PeripheralReadWriteParams {
                port: fit("port", params.port, "0..=3")?,
                address: fit("address", params.address, "0..=65535")?,
                device: fit("device", params.device, "0..=255")?,
                num: fit("num", params.num, "0..=65535")?,
            };
            let words = values
                .iter()
                .map(|v| fit("values", *v, "0..=65535"))
                .collect::<ArmResult<Vec<u16>>>()?;
            arm.write_registers(&p, &words).await
        })
    }

    /// `(code, (joint error codes, brake engaged flags as 1/0))`.
    fn get_error_flag(&self, py: Python<'_>) -> (Py<PyAny>, (Vec<u32>, Vec<u8>)) {
        let r = block_on(py, driver_runtime(), self.arm.get_error_flag());
        let code = self.code(py, &r);
        let flags = r.unwrap_or_default();
        let brakes = flags.brake_engaged.iter().map(|b| u8::from(*b)).collect();
        (code, (flags.joint_errors, brakes))
    }

    fn __repr__(&self) -> String {
        format!(
            "ArmInterface(name={:?}, vendor={:?})",
            self.arm.name(),
            self.arm.vendor().name()
        )
    }
}

fn trajectory_mode_of(mode: i64, radio: i64) -> ArmResult<TrajectoryMode> {
    TrajectoryMode::from_api(
        fit("trajectory_mode", mode, "0, 1, 2")?,
        fit("radio", radio, "0..=1000")?,
    )
}

/// Hands one realtime state to the Python callback (GIL taken on this driver thread).
fn deliver(cb: &Py<PyAny>, state: &darm::ArmRealtimeState) {
    crate::with_python(|py| {
        let r = ArmRealtimeState::from_driver(py, state)
            .and_then(|s| Py::new(py, s))
            .and_then(|s| cb.call1(py, (s,)));
        if let Err(e) = r {
            e.write_unraisable(py, Some(cb.bind(py)));
        }
    });
}

/// Adds the API classes to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<ArmFactoryParam>()?;
    m.add_class::<ArmFactory>()?;
    m.add_class::<ArmInterface>()?;
    Ok(())
}
