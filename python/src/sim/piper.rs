//! The Piper firmware emulator under Python control.

use std::collections::BTreeMap;
use std::future::Future;
use std::net::SocketAddr;
use std::pin::Pin;
use std::sync::{Arc, Mutex};

use bus::virtual_bus::FaultId;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sim::fault_desk::{FaultAction, FaultDesk, Faults};
use sim::piper::{PiperConfig, PiperHandle, PiperMonitor};

use super::can_place::{open_place, CanPlace};
use super::emulated::{apply, builder_args, emulator_methods, Emulated, Running, Stop};
use super::{deg, lock, value_err};
use crate::{block_on, sim_runtime};

/// A Piper firmware emulator on a SocketCAN interface or behind a socketcand server.
#[pyclass(module = "armhil.sim", frozen)]
pub struct PiperEmulator {
    running: Running<(PiperHandle, CanPlace)>,
    faults: FaultDesk<PiperMonitor>,
    silenced: Mutex<Option<FaultId>>,
    params: BTreeMap<&'static str, String>,
    addr: Option<SocketAddr>,
}

impl Stop for PiperHandle {
    fn stop(self) -> Pin<Box<dyn Future<Output = ()> + Send>> {
        Box::pin(self.shutdown())
    }
}

impl Emulated for PiperEmulator {
    type Parts = (PiperHandle, CanPlace);
    const NAME: &'static str = "Piper";

    fn desk(&self) -> &dyn Faults {
        &self.faults
    }

    fn parts(&self) -> &Running<Self::Parts> {
        &self.running
    }
}

emulator_methods!(PiperEmulator);

#[pymethods]
impl PiperEmulator {
    /// Host of the socketcand server (`None` on a SocketCAN interface).
    #[getter]
    fn host(&self) -> Option<String> {
        self.addr.map(|a| a.ip().to_string())
    }

    /// Port of the socketcand server (`None` on a SocketCAN interface).
    #[getter]
    fn port(&self) -> Option<u16> {
        self.addr.map(|a| a.port())
    }

    /// Always `"piper"`.
    #[getter]
    fn arm_type(&self) -> &'static str {
        "piper"
    }

    /// The `params` of `ArmFactory.create_arm("piper", name, params)` for this emulator.
    #[getter]
    fn params(&self) -> BTreeMap<&'static str, String> {
        self.params.clone()
    }

    /// `params` plus `arm_type` and `arm_name`.
    #[pyo3(signature = (arm_name="arm"))]
    fn config(&self, arm_name: &str) -> BTreeMap<&'static str, String> {
        let mut m = self.params.clone();
        m.insert("arm_type", "piper".into());
        m.insert("arm_name", arm_name.into());
        m
    }

    /// Injects a fault by the Piper's names: comm_loss(joint), motor_over_temp(joint,
    /// temp_c=90), driver_over_temp(joint, temp_c=90), over_current(joint),
    /// under_voltage(voltage_v=18), driver_error(joint), stall(joint),
    /// external_torque(joint, torque_nm), collision(joint), estop,
    /// ntc_over_temp(board="main"), gripper_sensor_fault, teach_button.
    /// The emulator's fault builder checks the arguments (scenario files' defaults, ranges
    /// and messages): `ValueError` when it refuses them.
    #[pyo3(signature = (name, **kwargs))]
    fn inject(
        &self,
        py: Python<'_>,
        name: &str,
        kwargs: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<()> {
        apply(self, py, FaultAction::Inject, name, &builder_args(kwargs)?)
    }

    /// Removes a fault's cause (joint faults need `joint=`; values may be left out).
    #[pyo3(signature = (name, **kwargs))]
    fn clear(
        &self,
        py: Python<'_>,
        name: &str,
        kwargs: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<()> {
        apply(self, py, FaultAction::Clear, name, &builder_args(kwargs)?)
    }

    /// Drops every frame the emulator sends (the virtual bus's `silence_node`): the link
    /// reads as lost. Socketcand only.
    fn silence(&self) -> PyResult<()> {
        let id = self.with_parts(|(_, p)| {
            p.virtual_bus
                .as_ref()
                .map(|b| b.faults().silence_node("piper"))
        })?;
        let id =
            id.ok_or_else(|| PyRuntimeError::new_err("silence needs the socketcand emulator"))?;
        if let Some(old) = lock(&self.silenced).replace(id) {
            self.with_parts(|(_, p)| p.virtual_bus.as_ref().map(|b| b.faults().remove(old)))?;
        }
        Ok(())
    }

    /// Ends `silence`.
    fn unsilence(&self) -> PyResult<()> {
        if let Some(id) = lock(&self.silenced).take() {
            self.with_parts(|(_, p)| p.virtual_bus.as_ref().map(|b| b.faults().remove(id)))?;
        }
        Ok(())
    }

    /// Reported joint angles, degrees.
    fn joints_deg(&self) -> PyResult<Vec<f64>> {
        self.with_parts(|(h, _)| deg(&h.snapshot().reported_joints_rad))
    }

    /// The simulation's ground truth: time, joints, flange pose, gripper, status bytes.
    fn state<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = self.with_parts(|(h, _)| h.snapshot())?;
        let d = PyDict::new(py);
        d.set_item("time_s", s.time_s)?;
        d.set_item("joints_deg", deg(&s.reported_joints_rad))?;
        d.set_item("speeds_deg_s", deg(&s.joint_velocities_rad_s))?;
        d.set_item("torques_nm", s.joint_torques_nm.to_vec())?;
        d.set_item("motor_temps_c", s.motor_temps_c.to_vec())?;
        d.set_item("gripper_stroke_m", s.gripper_stroke_m)?;
        d.set_item("gripper_force_n", s.gripper_force_n)?;
        d.set_item("position_m", s.flange_pose.position_m.to_vec())?;
        d.set_item("euler_rad", s.flange_pose.euler_rad.to_vec())?;
        d.set_item("contacts", s.contacts)?;
        d.set_item("ctrl_mode", s.status.ctrl_mode)?;
        d.set_item("arm_status", s.status.arm_status)?;
        d.set_item("motion_status", s.status.motion_status)?;
        d.set_item("comm_bits", s.status.comm_bits)?;
        d.set_item("enabled", s.status.enabled.to_vec())?;
        Ok(d)
    }

    fn __repr__(&self) -> String {
        format!("PiperEmulator({:?})", self.params)
    }
}

/// Starts a Piper emulator on SocketCAN `iface`, or (default) behind a socketcand server on
/// `socketcand` (`HOST:PORT`, port 0 = a free port).
#[pyfunction]
#[pyo3(signature = (iface=None, socketcand="127.0.0.1:0", firmware="S-V1.8-2", initial_joints_deg=None))]
pub(super) fn piper(
    py: Python<'_>,
    iface: Option<&str>,
    socketcand: &str,
    firmware: &str,
    initial_joints_deg: Option<Vec<f64>>,
) -> PyResult<PiperEmulator> {
    let initial_joints_rad = match initial_joints_deg {
        None => [0.0; 6],
        Some(d) => {
            let arr: [f64; 6] = d.as_slice().try_into().map_err(|_| {
                value_err(format!(
                    "initial_joints_deg needs 6 values, got {}",
                    d.len()
                ))
            })?;
            arr.map(f64::to_radians)
        }
    };
    let config = PiperConfig {
        firmware: firmware.parse().map_err(value_err)?,
        initial_joints_rad,
        ..PiperConfig::default()
    };
    let place = open_place(py, iface, socketcand, "piper", false)?;
    let node = Arc::clone(&place.node);
    let handle = block_on(py, sim_runtime(), async move {
        sim::piper::PiperEmulator::spawn(node, config)
    })
    .map_err(|e| PyRuntimeError::new_err(format!("cannot start the Piper emulator: {e}")))?;
    Ok(PiperEmulator {
        faults: FaultDesk::new(handle.monitor()),
        params: place.params(),
        addr: place.socketcand_addr(),
        running: Running::new((handle, place)),
        silenced: Mutex::new(None),
    })
}
