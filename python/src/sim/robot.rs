//! A whole robot under Python control: its robot file, one physics world, every bus served
//! at once — as channels of one socketcand server (default), or each on the SocketCAN
//! interface of its name.

use std::collections::BTreeMap;
use std::future::Future;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::pin::Pin;
use std::sync::Arc;

use bus::socketcand::SocketcandServer;
use bus::CanBus;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sim::actuator::Detail;
use sim::fault_args::{FaultArgValue, FaultArgs};
use sim::fault_desk::{FaultAction, FaultDesk, Faults};
use sim::robot::faults::{BUS_LOST, EXTERNAL_TORQUE, GANTRY_RELEASE};
use sim::robot::file::{load_robot_file, RobotFileError};
use sim::robot::{
    Gantry, RobotEmulator as Emulator, RobotError, RobotHandle, RobotMonitor, RobotSnapshot,
};

use super::emulated::{apply, builder_args_after, emulator_methods, Emulated, Running, Stop};
use super::value_err;
use crate::{block_on, sim_runtime};

/// What serves the robot's buses.
pub(super) struct Served {
    nodes: Vec<Arc<dyn CanBus>>,
    server: Option<SocketcandServer>,
}

impl Served {
    async fn close(self) {
        for node in self.nodes {
            node.close().await;
        }
        if let Some(server) = self.server {
            server.shutdown().await;
        }
    }
}

/// A whole robot from its robot file (`armhil sim robot FILE` in this process).
#[pyclass(module = "armhil.sim", frozen)]
pub struct RobotEmulator {
    running: Running<(RobotHandle, Served)>,
    faults: FaultDesk<RobotMonitor>,
    name: String,
    buses: Vec<String>,
    /// Per actuated joint: its bus and CAN id.
    joints: Vec<(String, String, u32)>,
    addr: Option<SocketAddr>,
}

fn robot_err(e: RobotError) -> PyErr {
    match e {
        RobotError::Stopped => PyRuntimeError::new_err(e.to_string()),
        other => value_err(other),
    }
}

impl Stop for RobotHandle {
    fn stop(self) -> Pin<Box<dyn Future<Output = ()> + Send>> {
        Box::pin(self.shutdown())
    }
}

impl Stop for Served {
    fn stop(self) -> Pin<Box<dyn Future<Output = ()> + Send>> {
        Box::pin(self.close())
    }
}

impl Emulated for RobotEmulator {
    type Parts = (RobotHandle, Served);
    const NAME: &'static str = "robot";

    fn desk(&self) -> &dyn Faults {
        &self.faults
    }

    fn parts(&self) -> &Running<Self::Parts> {
        &self.running
    }
}

emulator_methods!(RobotEmulator);

/// A robot fault's arguments: one word (`joint`, `bus`).
fn word(name: &str, value: String) -> FaultArgs {
    FaultArgs::new().with(name, FaultArgValue::Text(value))
}

fn snapshot_dict<'py>(py: Python<'py>, s: &RobotSnapshot) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("time_s", s.time_s)?;
    d.set_item("base_position_m", s.base_position_m.to_vec())?;
    d.set_item("lost_buses", s.lost_buses.clone())?;
    d.set_item("gantry_holds", s.gantry_holds)?;
    let joints = PyDict::new(py);
    for j in &s.joints {
        let m = &j.actuator;
        let jd = PyDict::new(py);
        jd.set_item("bus", &j.bus)?;
        jd.set_item("kind", m.kind)?;
        jd.set_item("can_id", m.can_id)?;
        jd.set_item("model", m.model)?;
        jd.set_item("position_rad", j.position_rad)?;
        jd.set_item("velocity_rad_s", j.velocity_rad_s)?;
        jd.set_item("enabled", m.enabled)?;
        jd.set_item("mode", &m.mode)?;
        jd.set_item("angle_rad", m.angle_rad)?;
        jd.set_item("speed_rad_s", m.speed_rad_s)?;
        jd.set_item("torque_nm", m.torque_nm)?;
        jd.set_item("temperature_c", m.temperature_c)?;
        jd.set_item("faults", m.faults.clone())?;
        // What only this kind has (RobStride: run_mode, fault_word …), under its own names.
        for (name, value) in &m.details {
            match value {
                Detail::Int(v) => jd.set_item(*name, v)?,
                Detail::Real(v) => jd.set_item(*name, v)?,
                Detail::Word(v) => jd.set_item(*name, v)?,
            }
        }
        joints.set_item(&j.joint, jd)?;
    }
    d.set_item("joints", joints)?;
    Ok(d)
}

#[pymethods]
impl RobotEmulator {
    /// The robot's name (its file's `robot:`).
    #[getter]
    fn name(&self) -> String {
        self.name.clone()
    }

    /// Its buses' names, in file order (the socketcand channels, or the interfaces).
    #[getter]
    fn buses(&self) -> Vec<String> {
        self.buses.clone()
    }

    /// Per actuated joint: `{"bus": ..., "can_id": ...}`.
    #[getter]
    fn actuators(&self) -> BTreeMap<String, (String, u32)> {
        self.joints
            .iter()
            .map(|(j, b, id)| (j.clone(), (b.clone(), *id)))
            .collect()
    }

    /// Host of the socketcand server (`None` on SocketCAN interfaces).
    #[getter]
    fn host(&self) -> Option<String> {
        self.addr.map(|a| a.ip().to_string())
    }

    /// Port of the socketcand server (`None` on SocketCAN interfaces).
    #[getter]
    fn port(&self) -> Option<u16> {
        self.addr.map(|a| a.port())
    }

    /// Injects fault `name` of the robot's fault table (`faults()` lists it, with each
    /// argument), its arguments by keyword: RobStride's faults on the actuator of `joint=` —
    /// over_temperature, under_voltage, over_voltage, phase_a_over_current,
    /// phase_b_over_current, phase_c_over_current, encoder_not_calibrated, stall_overload,
    /// gate_driver; encoder_glitch(joint, counts) — and external_torque(joint, torque_nm),
    /// bus_lost(bus), gantry_release. `joint` may come by position. The emulator's fault
    /// builder checks them: `ValueError` when it refuses them.
    #[pyo3(signature = (name, joint=None, **kwargs))]
    fn inject(
        &self,
        py: Python<'_>,
        name: &str,
        joint: Option<&Bound<'_, PyAny>>,
        kwargs: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<()> {
        let args = builder_args_after(joint.map(|j| ("joint", j)), kwargs)?;
        apply(self, py, FaultAction::Inject, name, &args)
    }

    /// Removes a fault's cause: on the actuator of `joint=` (a fault's values may be left
    /// out), or `bus_lost` with `bus=`.
    #[pyo3(signature = (name, joint=None, **kwargs))]
    fn clear(
        &self,
        py: Python<'_>,
        name: &str,
        joint: Option<&Bound<'_, PyAny>>,
        kwargs: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<()> {
        let args = builder_args_after(joint.map(|j| ("joint", j)), kwargs)?;
        apply(self, py, FaultAction::Clear, name, &args)
    }

    /// Sets the winding temperature of `joint`'s actuator (°C); its thermal model goes on
    /// from there.
    fn set_temperature(&self, py: Python<'_>, joint: String, celsius: f64) -> PyResult<()> {
        let robot = self.faults.target();
        self.ask(py, robot.set_temperature(&joint, celsius))?
            .map_err(robot_err)
    }

    /// Pushes on `joint` with a torque from outside (N·m, up to ten times its actuator's
    /// peak torque; 0 stops pushing): the fault `external_torque`.
    fn set_external_torque(&self, py: Python<'_>, joint: String, torque_nm: f64) -> PyResult<()> {
        let args = word("joint", joint);
        if torque_nm == 0.0 {
            apply(self, py, FaultAction::Clear, EXTERNAL_TORQUE, &args)
        } else {
            let args = args.with("torque_nm", FaultArgValue::Number(torque_nm));
            apply(self, py, FaultAction::Inject, EXTERNAL_TORQUE, &args)
        }
    }

    /// Cuts bus `bus` off (`lost=True`: no frame reaches or leaves its actuators) or
    /// reconnects it: the fault `bus_lost`.
    #[pyo3(signature = (bus, lost=true))]
    fn bus_lost(&self, py: Python<'_>, bus: String, lost: bool) -> PyResult<()> {
        let action = if lost {
            FaultAction::Inject
        } else {
            FaultAction::Clear
        };
        apply(self, py, action, BUS_LOST, &word("bus", bus))
    }

    /// The gantry lets go of the base (the fault `gantry_release`, an event): from then on
    /// the robot stands on its actuators or falls. Nothing happens when nothing holds it.
    fn release_gantry(&self, py: Python<'_>) -> PyResult<()> {
        apply(
            self,
            py,
            FaultAction::Inject,
            GANTRY_RELEASE,
            &FaultArgs::new(),
        )
    }

    /// The robot's state: `time_s`, `base_position_m`, `lost_buses`, `gantry_holds` and
    /// `joints` (by URDF
    /// joint name: bus, CAN id, model, world position and speed, the actuator's mode, shaft
    /// angle, torque, temperature, fault word).
    fn state<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let snapshot = self
            .ask(py, self.faults.target().snapshot())?
            .map_err(robot_err)?;
        snapshot_dict(py, &snapshot)
    }
}

/// Each bus by its name and whether it is a CAN FD bus (the robot file gives it a data rate).
async fn serve_buses(
    buses: &[(String, bool)],
    interfaces: bool,
    socketcand: &str,
) -> Result<Served, String> {
    if interfaces {
        // The bus crate's errors name the interface and say what to do. A CAN FD bus gets
        // CAN FD sockets, as `armhil sim robot` gives it.
        let nodes = buses
            .iter()
            .map(|(iface, fd)| bus::open_socketcan_for(iface, *fd).map_err(|e| e.to_string()))
            .collect::<Result<Vec<_>, _>>()?;
        return Ok(Served {
            nodes,
            server: None,
        });
    }
    let names: Vec<String> = buses.iter().map(|(name, _)| name.clone()).collect();
    let (buses, server) = SocketcandServer::bind_realtime_channels(socketcand, &names)
        .await
        .map_err(|e| format!("cannot serve socketcand on {socketcand}: {e}"))?;
    let nodes = buses
        .iter()
        .map(|b| Arc::new(b.attach("robot")) as Arc<dyn CanBus>)
        .collect();
    Ok(Served {
        nodes,
        server: Some(server),
    })
}

/// Starts the robot of robot file `file`: its buses as channels of a socketcand server on
/// `socketcand` (default, port 0 = a free port), or with `interfaces=True` each on the
/// SocketCAN interface of its name.
#[pyfunction]
#[pyo3(signature = (file, socketcand="127.0.0.1:0", interfaces=false, state_file=None, gantry=None))]
pub(super) fn robot(
    py: Python<'_>,
    file: PathBuf,
    socketcand: &str,
    interfaces: bool,
    state_file: Option<PathBuf>,
    gantry: Option<&str>,
) -> PyResult<RobotEmulator> {
    let loaded = load_robot_file(&file).map_err(|e| match e {
        RobotFileError::Read { .. } => PyErr::new::<pyo3::exceptions::PyOSError, _>(e.to_string()),
        RobotFileError::Invalid(_) => value_err(e),
    })?;
    // As `armhil sim robot`: the caller's, else the file's, else on the stand until enabled.
    let requested = gantry
        .map(|word| Gantry::parse(word).map_err(|e| PyValueError::new_err(format!("gantry {e}"))))
        .transpose()?;
    let gantry = loaded.serving_gantry(requested);
    let mut config = loaded.config;
    config.state_file = state_file;
    config.gantry = gantry;
    let names: Vec<String> = config.buses.iter().map(|b| b.name.clone()).collect();
    let joints = config
        .actuators
        .iter()
        .map(|a| (a.joint.clone(), names[a.bus].clone(), a.actuator.can_id()))
        .collect();
    let name = config.name.clone();
    let socketcand = socketcand.to_owned();
    let buses: Vec<(String, bool)> = config
        .buses
        .iter()
        .map(|b| (b.name.clone(), b.data_bitrate_bps.is_some()))
        .collect();
    let (handle, served, addr) = block_on(py, sim_runtime(), async move {
        let served = serve_buses(&buses, interfaces, &socketcand).await?;
        let addr = served.server.as_ref().map(SocketcandServer::local_addr);
        match Emulator::spawn(config, served.nodes.clone()) {
            Ok(handle) => Ok((handle, served, addr)),
            Err(e) => {
                served.close().await;
                Err(format!("cannot start the robot: {e}"))
            }
        }
    })
    .map_err(PyRuntimeError::new_err)?;
    Ok(RobotEmulator {
        faults: FaultDesk::new(handle.monitor()),
        running: Running::new((handle, served)),
        name,
        buses: names,
        joints,
        addr,
    })
}
