//! The Realman controller emulator under Python control (TCP commands, UDP push).

use std::collections::BTreeMap;
use std::future::Future;
use std::net::{IpAddr, SocketAddr};
use std::pin::Pin;

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sim::fault_desk::{FaultAction, FaultDesk, Faults};
use sim::realman::model::ArmModel;
use sim::realman::{
    ControllerConfig, EmulatorConfig, RealmanEmulator as RealmanSpawner, RealmanHandle,
    RealmanMonitor, Transport,
};

use super::emulated::{apply, builder_args, emulator_methods, Emulated, Running, Stop};
use super::{deg, value_err};
use crate::{block_on, sim_runtime};

/// A Realman arm controller emulator on TCP (commands) and UDP (realtime push).
#[pyclass(module = "armhil.sim", frozen)]
pub struct RealmanEmulator {
    handle: Running<RealmanHandle>,
    faults: FaultDesk<RealmanMonitor>,
    addr: SocketAddr,
}

impl Stop for RealmanHandle {
    fn stop(self) -> Pin<Box<dyn Future<Output = ()> + Send>> {
        Box::pin(self.shutdown())
    }
}

impl Emulated for RealmanEmulator {
    type Parts = RealmanHandle;
    const NAME: &'static str = "Realman";

    fn desk(&self) -> &dyn Faults {
        &self.faults
    }

    fn parts(&self) -> &Running<Self::Parts> {
        &self.handle
    }
}

emulator_methods!(RealmanEmulator);

#[pymethods]
impl RealmanEmulator {
    /// Address the command server listens on.
    #[getter]
    fn host(&self) -> String {
        self.addr.ip().to_string()
    }

    /// TCP port of the command server.
    #[getter]
    fn port(&self) -> u16 {
        self.addr.port()
    }

    /// Always `"realman"`.
    #[getter]
    fn arm_type(&self) -> &'static str {
        "realman"
    }

    /// The `params` of `ArmFactory.create_arm("realman", name, params)` for this emulator
    /// (push to a free local UDP port every 5 ms).
    #[getter]
    fn params(&self) -> BTreeMap<&'static str, String> {
        BTreeMap::from([
            ("ip", self.addr.ip().to_string()),
            ("port", self.addr.port().to_string()),
            ("udp_ip", self.addr.ip().to_string()),
            ("udp_port", "0".to_string()),
            ("udp_cycle", "1".to_string()),
        ])
    }

    /// `params` plus `arm_type` and `arm_name`: an `ArmFactoryParam` dictionary or the
    /// content of a configuration file.
    #[pyo3(signature = (arm_name="arm"))]
    fn config(&self, arm_name: &str) -> BTreeMap<&'static str, String> {
        let mut m = self.params();
        m.insert("arm_type", "realman".into());
        m.insert("arm_name", arm_name.into());
        m.insert("enable_gripper", "false".into());
        m
    }

    /// Injects a fault by name: connection_drop(peer_ip=None), reply_delay(delay_ms),
    /// malformed_reply(count), udp_loss(permille), udp_reorder, joint_error(joint, code),
    /// power_loss, collision, estop, gripper_fault(bits). Every argument but `peer_ip` is
    /// required, as in scenario files; a value out of range raises `ValueError`.
    #[pyo3(signature = (name, **kwargs))]
    fn inject(
        &self,
        py: Python<'_>,
        name: &str,
        kwargs: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<()> {
        apply(self, py, FaultAction::Inject, name, &builder_args(kwargs)?)
    }

    /// Removes a fault by name (the controller clears a fault by kind: arguments, if given,
    /// are not needed).
    #[pyo3(signature = (name, **kwargs))]
    fn clear(
        &self,
        py: Python<'_>,
        name: &str,
        kwargs: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<()> {
        apply(self, py, FaultAction::Clear, name, &builder_args(kwargs)?)
    }

    /// Measured joint angles, degrees.
    fn joints_deg(&self) -> PyResult<Vec<f64>> {
        self.with_parts(|h| deg(&h.snapshot().joints_rad))
    }

    /// The simulation's ground truth: time, joints, pose, power, errors, status.
    fn state<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = self.with_parts(|h| h.snapshot())?;
        let d = PyDict::new(py);
        d.set_item("time_ms", s.time_ms)?;
        d.set_item("joints_deg", deg(&s.joints_rad))?;
        d.set_item("speeds_deg_s", deg(&s.speeds_rad_s))?;
        d.set_item("setpoint_deg", deg(&s.setpoint_rad))?;
        d.set_item("position_m", s.pose.position_m.to_vec())?;
        d.set_item("euler_rad", s.pose.euler_rad.to_vec())?;
        d.set_item("power_on", s.power_on)?;
        d.set_item("enabled", s.enabled)?;
        d.set_item("errors", s.errors)?;
        d.set_item("status", s.status)?;
        d.set_item("queued_moves", s.queued_moves)?;
        Ok(d)
    }

    /// Open client connections.
    fn connections(&self) -> PyResult<usize> {
        self.with_parts(|h| h.connections())
    }

    fn __repr__(&self) -> String {
        format!("RealmanEmulator(tcp://{})", self.addr)
    }
}

/// Starts a Realman emulator (`port=0`: a free port).
#[pyfunction]
#[pyo3(signature = (port=0, host="127.0.0.1", model="RM65-B", firmware="V1.7.0", initial_joints_deg=None, gripper=true))]
pub(super) fn realman(
    py: Python<'_>,
    port: u16,
    host: &str,
    model: &str,
    firmware: &str,
    initial_joints_deg: Option<Vec<f64>>,
    gripper: bool,
) -> PyResult<RealmanEmulator> {
    let ip: IpAddr = host.parse().map_err(value_err)?;
    let model = ArmModel::from_product(model)
        .ok_or_else(|| value_err(format!("unknown Realman model {model:?} (try RM65-B)")))?;
    let mut controller = ControllerConfig::new(model);
    controller.firmware = firmware.parse().map_err(value_err)?;
    controller.gripper = gripper;
    controller.initial_joints_rad =
        initial_joints_deg.map(|d| d.iter().map(|x| x.to_radians()).collect());
    let config = EmulatorConfig::new(controller);
    let addr = SocketAddr::new(ip, port);
    let handle = block_on(
        py,
        sim_runtime(),
        RealmanSpawner::spawn(config, Transport::Tcp(addr)),
    )
    .map_err(|e| PyRuntimeError::new_err(format!("cannot start the Realman emulator: {e}")))?;
    let addr = handle.local_addr().unwrap_or(addr);
    Ok(RealmanEmulator {
        faults: FaultDesk::new(handle.monitor()),
        handle: Running::new(handle),
        addr,
    })
}
