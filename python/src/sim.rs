//! The emulators under Python control, in-process and in real time, started the way
//! `armhil sim <device>` starts them: the Realman controller on TCP/UDP, the Piper and the
//! RobStride actuators on a SocketCAN interface or behind a socketcand server (CAN over TCP,
//! for hosts without kernel CAN). Each is a context manager; faults use the emulator's own
//! names (`comm_loss`, `reply_delay`, `over_temperature`, …).

use std::collections::BTreeMap;
use std::net::{IpAddr, SocketAddr};
use std::sync::{Arc, Mutex};

use bus::socketcand::SocketcandServer;
use bus::virtual_bus::{FaultId, VirtualBus};
use bus::CanBus;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use sim::piper::{FaultKind, NtcBoard, PiperConfig, PiperFault, PiperHandle};
use sim::realman::model::ArmModel;
use sim::realman::{
    ControllerConfig, EmulatorConfig, RealmanEmulator as RealmanSpawner, RealmanFault,
    RealmanFaultKind, RealmanHandle, Transport,
};
use sim::robstride::{Fault, Model, MotorConfig, RobstrideBus, RobstrideConfig, RobstrideHandle};

use crate::{block_on, sim_runtime};

fn value_err(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(e.to_string())
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// Fault keyword arguments, checked against what the fault takes.
struct FaultArgs<'a, 'py> {
    name: &'a str,
    kwargs: Option<&'a Bound<'py, PyDict>>,
    used: Vec<&'static str>,
}

impl<'py> FaultArgs<'_, 'py> {
    fn get<T: for<'a> FromPyObject<'a, 'py>>(&mut self, key: &'static str) -> PyResult<Option<T>> {
        self.used.push(key);
        match self.kwargs.map(|k| k.get_item(key)).transpose()?.flatten() {
            None => Ok(None),
            Some(v) => v.extract::<T>().map(Some).map_err(|_| {
                value_err(format!(
                    "fault {:?}: {key} = {v} has the wrong type",
                    self.name
                ))
            }),
        }
    }

    fn need<T: for<'a> FromPyObject<'a, 'py>>(&mut self, key: &'static str) -> PyResult<T> {
        self.get(key)?
            .ok_or_else(|| value_err(format!("fault {:?} needs {key}=…", self.name)))
    }

    /// Refuses keywords the fault does not take (a typo must not pass silently).
    fn finish(self) -> PyResult<()> {
        if let Some(k) = self.kwargs {
            for key in k.keys() {
                let key: String = key.extract()?;
                if !self.used.contains(&key.as_str()) {
                    return Err(value_err(format!(
                        "fault {:?} takes no argument {key:?} (it takes: {})",
                        self.name,
                        self.used.join(", ")
                    )));
                }
            }
        }
        Ok(())
    }
}

fn fault_args<'a, 'py>(
    name: &'a str,
    kwargs: Option<&'a Bound<'py, PyDict>>,
) -> FaultArgs<'a, 'py> {
    FaultArgs {
        name,
        kwargs,
        used: Vec::new(),
    }
}

fn deg(rad: &[f64]) -> Vec<f64> {
    rad.iter().map(|r| r.to_degrees()).collect()
}

/// Returns false so an exception inside `with` propagates.
fn exit_false() -> bool {
    false
}

// ---------------------------------------------------------------------------------------
// Realman

/// A Realman arm controller emulator on TCP (commands) and UDP (realtime push).
#[pyclass(module = "armhil.sim", frozen)]
pub struct RealmanEmulator {
    handle: Mutex<Option<RealmanHandle>>,
    addr: SocketAddr,
}

impl RealmanEmulator {
    fn with<R>(&self, f: impl FnOnce(&RealmanHandle) -> R) -> PyResult<R> {
        lock(&self.handle)
            .as_ref()
            .map(f)
            .ok_or_else(|| PyRuntimeError::new_err("the Realman emulator is stopped"))
    }
}

fn realman_fault(name: &str, kwargs: Option<&Bound<'_, PyDict>>) -> PyResult<RealmanFault> {
    let mut a = fault_args(name, kwargs);
    let fault = match RealmanFaultKind::from_name(name) {
        Some(RealmanFaultKind::ConnectionDrop) => RealmanFault::ConnectionDrop {
            peer_ip: match a.get::<String>("peer_ip")? {
                Some(ip) => Some(ip.parse::<IpAddr>().map_err(value_err)?),
                None => None,
            },
        },
        Some(RealmanFaultKind::ReplyDelay) => RealmanFault::ReplyDelay {
            delay_ms: a.need("delay_ms")?,
        },
        Some(RealmanFaultKind::MalformedReply) => RealmanFault::MalformedReply {
            count: a.get("count")?.unwrap_or(1),
        },
        Some(RealmanFaultKind::UdpLoss) => RealmanFault::UdpLoss {
            permille: a.need("permille")?,
        },
        Some(RealmanFaultKind::UdpReorder) => RealmanFault::UdpReorder,
        Some(RealmanFaultKind::JointError) => RealmanFault::JointError {
            joint: a.need("joint")?,
            code: a.get("code")?.unwrap_or(0x0008),
        },
        Some(RealmanFaultKind::PowerLoss) => RealmanFault::PowerLoss,
        Some(RealmanFaultKind::Collision) => RealmanFault::Collision,
        Some(RealmanFaultKind::EStop) => RealmanFault::EStop,
        Some(RealmanFaultKind::GripperFault) => RealmanFault::GripperFault {
            bits: a.get("bits")?.unwrap_or(1),
        },
        None => {
            let known: Vec<_> = RealmanFaultKind::ALL.iter().map(|k| k.name()).collect();
            return Err(value_err(format!(
                "unknown Realman fault {name:?} (known: {})",
                known.join(", ")
            )));
        }
    };
    a.finish()?;
    // The emulator's table bounds every value (a reply delay of years is a typo).
    fault.check().map_err(value_err)?;
    Ok(fault)
}

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
    /// malformed_reply(count=1), udp_loss(permille), udp_reorder, joint_error(joint,
    /// code=8), power_loss, collision, estop, gripper_fault(bits=1).
    #[pyo3(signature = (name, **kwargs))]
    fn inject(&self, name: &str, kwargs: Option<&Bound<'_, PyDict>>) -> PyResult<()> {
        let fault = realman_fault(name, kwargs)?;
        self.with(|h| h.inject(fault))?.map_err(value_err)
    }

    /// Removes a fault by name.
    fn clear(&self, name: &str) -> PyResult<()> {
        let kind = RealmanFaultKind::from_name(name)
            .ok_or_else(|| value_err(format!("unknown Realman fault {name:?}")))?;
        self.with(|h| h.clear(kind))
    }

    /// Measured joint angles, degrees.
    fn joints_deg(&self) -> PyResult<Vec<f64>> {
        self.with(|h| deg(&h.snapshot().joints_rad))
    }

    /// The simulation's ground truth: time, joints, pose, power, errors, status.
    fn state<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = self.with(|h| h.snapshot())?;
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
        self.with(|h| h.connections())
    }

    /// Whether it is serving.
    #[getter]
    fn running(&self) -> bool {
        lock(&self.handle).is_some()
    }

    /// Stops serving and closes every connection (idempotent).
    fn stop(&self, py: Python<'_>) {
        let handle = lock(&self.handle).take();
        if let Some(h) = handle {
            block_on(py, sim_runtime(), h.shutdown());
        }
    }

    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    #[pyo3(signature = (*_args))]
    fn __exit__(&self, py: Python<'_>, _args: &Bound<'_, PyTuple>) -> bool {
        self.stop(py);
        exit_false()
    }

    fn __repr__(&self) -> String {
        format!("RealmanEmulator(tcp://{})", self.addr)
    }
}

/// Starts a Realman emulator (`port=0`: a free port).
#[pyfunction]
#[pyo3(signature = (port=0, host="127.0.0.1", model="RM65-B", firmware="V1.7.0", initial_joints_deg=None, gripper=true))]
fn realman(
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
        handle: Mutex::new(Some(handle)),
        addr,
    })
}

// ---------------------------------------------------------------------------------------
// CAN emulators: where they sit

/// The bus a CAN emulator answers on.
struct CanPlace {
    node: Arc<dyn CanBus>,
    /// The virtual bus behind the socketcand server (`None` on SocketCAN).
    virtual_bus: Option<VirtualBus>,
    server: Option<SocketcandServer>,
    iface: Option<String>,
}

/// A socketcand server on `addr` with a real-time virtual bus, as `armhil sim --socketcand`.
async fn socketcand_place(addr: &str, node_name: &str) -> Result<CanPlace, String> {
    let (bus, server) = SocketcandServer::bind_realtime_bus(addr)
        .await
        .map_err(|e| format!("cannot serve socketcand on {addr}: {e}"))?;
    Ok(CanPlace {
        node: Arc::new(bus.attach(node_name)),
        virtual_bus: Some(bus),
        server: Some(server),
        iface: None,
    })
}

#[cfg(target_os = "linux")]
fn iface_place(iface: &str) -> Result<CanPlace, String> {
    let socket = bus::socketcan_bus::SocketCanBus::open(iface)
        .map_err(|e| format!("cannot open SocketCAN interface {iface}: {e}"))?;
    Ok(CanPlace {
        node: Arc::new(socket),
        virtual_bus: None,
        server: None,
        iface: Some(iface.to_string()),
    })
}

#[cfg(not(target_os = "linux"))]
fn iface_place(iface: &str) -> Result<CanPlace, String> {
    Err(format!(
        "SocketCAN interface {iface}: SocketCAN is Linux only"
    ))
}

/// `iface` when given, else a socketcand server on `socketcand` (a bare port = loopback).
fn open_place(
    py: Python<'_>,
    iface: Option<&str>,
    socketcand: &str,
    node: &str,
) -> PyResult<CanPlace> {
    let r = match iface {
        Some(i) => iface_place(i),
        None => {
            let addr = match socketcand.parse::<u16>() {
                Ok(port) => format!("127.0.0.1:{port}"),
                Err(_) => socketcand.to_string(),
            };
            let node = node.to_string();
            block_on(py, sim_runtime(), async move {
                socketcand_place(&addr, &node).await
            })
        }
    };
    r.map_err(PyRuntimeError::new_err)
}

impl CanPlace {
    fn socketcand_addr(&self) -> Option<SocketAddr> {
        self.server.as_ref().map(SocketcandServer::local_addr)
    }

    /// Closes the node and the server.
    async fn close(self) {
        self.node.close().await;
        if let Some(s) = self.server {
            s.shutdown().await;
        }
    }

    /// The `params` a driver uses to reach this bus.
    fn params(&self) -> BTreeMap<&'static str, String> {
        match (self.socketcand_addr(), &self.iface) {
            (Some(a), _) => BTreeMap::from([
                ("socketcand", a.to_string()),
                ("can_interface", "can0".to_string()),
            ]),
            (None, Some(i)) => BTreeMap::from([("can_interface", i.clone())]),
            (None, None) => BTreeMap::new(),
        }
    }
}

// ---------------------------------------------------------------------------------------
// Piper

/// A Piper firmware emulator on a SocketCAN interface or behind a socketcand server.
#[pyclass(module = "armhil.sim", frozen)]
pub struct PiperEmulator {
    running: Mutex<Option<(PiperHandle, CanPlace)>>,
    silenced: Mutex<Option<FaultId>>,
    params: BTreeMap<&'static str, String>,
    addr: Option<SocketAddr>,
}

impl PiperEmulator {
    fn with<R>(&self, f: impl FnOnce(&PiperHandle, &CanPlace) -> R) -> PyResult<R> {
        lock(&self.running)
            .as_ref()
            .map(|(h, p)| f(h, p))
            .ok_or_else(|| PyRuntimeError::new_err("the Piper emulator is stopped"))
    }
}

fn piper_fault(
    name: &str,
    kwargs: Option<&Bound<'_, PyDict>>,
    clearing: bool,
) -> PyResult<PiperFault> {
    let kind = FaultKind::from_name(name).ok_or_else(|| {
        let known: Vec<_> = FaultKind::ALL.iter().map(|k| k.name()).collect();
        value_err(format!(
            "unknown Piper fault {name:?} (known: {})",
            known.join(", ")
        ))
    })?;
    let mut a = fault_args(name, kwargs);
    // Clearing ignores the values (a temperature, a torque) but needs the site (the joint).
    let value = |a: &mut FaultArgs<'_, '_>, key: &'static str, default: f64| -> PyResult<f64> {
        Ok(a.get(key)?.unwrap_or(default))
    };
    let fault = match kind {
        FaultKind::CommLoss => PiperFault::CommLoss {
            joint: a.need("joint")?,
        },
        FaultKind::MotorOverTemp => PiperFault::MotorOverTemp {
            joint: a.need("joint")?,
            temp_c: value(&mut a, "temp_c", 90.0)?,
        },
        FaultKind::DriverOverTemp => PiperFault::DriverOverTemp {
            joint: a.need("joint")?,
            temp_c: value(&mut a, "temp_c", 90.0)?,
        },
        FaultKind::OverCurrent => PiperFault::OverCurrent {
            joint: a.need("joint")?,
        },
        FaultKind::UnderVoltage => PiperFault::UnderVoltage {
            voltage_v: value(&mut a, "voltage_v", 18.0)?,
        },
        FaultKind::DriverError => PiperFault::DriverError {
            joint: a.need("joint")?,
        },
        FaultKind::Stall => PiperFault::Stall {
            joint: a.need("joint")?,
        },
        FaultKind::ExternalTorque => PiperFault::ExternalTorque {
            joint: a.need("joint")?,
            torque_nm: if clearing {
                a.get("torque_nm")?.unwrap_or(0.0)
            } else {
                a.need("torque_nm")?
            },
        },
        FaultKind::Collision => PiperFault::Collision {
            joint: a.need("joint")?,
        },
        FaultKind::Estop => PiperFault::Estop,
        FaultKind::NtcOverTemp => PiperFault::NtcOverTemp {
            board: match a.get::<String>("board")?.as_deref() {
                None | Some("main") => NtcBoard::Main,
                Some("brake_resistor") => NtcBoard::BrakeResistor,
                Some(other) => {
                    return Err(value_err(format!(
                        "board must be main or brake_resistor, got {other:?}"
                    )))
                }
            },
        },
        FaultKind::GripperSensorFault => PiperFault::GripperSensorFault,
        FaultKind::TeachButton => PiperFault::TeachButton,
    };
    a.finish()?;
    Ok(fault)
}

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
    #[pyo3(signature = (name, **kwargs))]
    fn inject(&self, name: &str, kwargs: Option<&Bound<'_, PyDict>>) -> PyResult<()> {
        let fault = piper_fault(name, kwargs, false)?;
        self.with(|h, _| h.inject(fault))?.map_err(value_err)
    }

    /// Removes a fault's cause (joint faults need `joint=`).
    #[pyo3(signature = (name, **kwargs))]
    fn clear(&self, name: &str, kwargs: Option<&Bound<'_, PyDict>>) -> PyResult<()> {
        let fault = piper_fault(name, kwargs, true)?;
        self.with(|h, _| h.clear(fault))?.map_err(value_err)
    }

    /// Drops every frame the emulator sends (the virtual bus's `silence_node`): the link
    /// reads as lost. Socketcand only.
    fn silence(&self) -> PyResult<()> {
        let id = self.with(|_, p| {
            p.virtual_bus
                .as_ref()
                .map(|b| b.faults().silence_node("piper"))
        })?;
        let id =
            id.ok_or_else(|| PyRuntimeError::new_err("silence needs the socketcand emulator"))?;
        if let Some(old) = lock(&self.silenced).replace(id) {
            self.with(|_, p| p.virtual_bus.as_ref().map(|b| b.faults().remove(old)))?;
        }
        Ok(())
    }

    /// Ends `silence`.
    fn unsilence(&self) -> PyResult<()> {
        if let Some(id) = lock(&self.silenced).take() {
            self.with(|_, p| p.virtual_bus.as_ref().map(|b| b.faults().remove(id)))?;
        }
        Ok(())
    }

    /// Reported joint angles, degrees.
    fn joints_deg(&self) -> PyResult<Vec<f64>> {
        self.with(|h, _| deg(&h.snapshot().reported_joints_rad))
    }

    /// The simulation's ground truth: time, joints, flange pose, gripper, status bytes.
    fn state<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = self.with(|h, _| h.snapshot())?;
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

    /// Whether it is running.
    #[getter]
    fn running(&self) -> bool {
        lock(&self.running).is_some()
    }

    /// Stops the emulator and its server (idempotent).
    fn stop(&self, py: Python<'_>) {
        let running = lock(&self.running).take();
        if let Some((h, place)) = running {
            block_on(py, sim_runtime(), async move {
                h.shutdown().await;
                place.close().await;
            });
        }
    }

    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    #[pyo3(signature = (*_args))]
    fn __exit__(&self, py: Python<'_>, _args: &Bound<'_, PyTuple>) -> bool {
        self.stop(py);
        exit_false()
    }

    fn __repr__(&self) -> String {
        format!("PiperEmulator({:?})", self.params)
    }
}

/// Starts a Piper emulator on SocketCAN `iface`, or (default) behind a socketcand server on
/// `socketcand` (`HOST:PORT`, port 0 = a free port).
#[pyfunction]
#[pyo3(signature = (iface=None, socketcand="127.0.0.1:0", firmware="S-V1.8-2", initial_joints_deg=None))]
fn piper(
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
    let place = open_place(py, iface, socketcand, "piper")?;
    let node = Arc::clone(&place.node);
    let handle = block_on(py, sim_runtime(), async move {
        sim::piper::PiperEmulator::spawn(node, config)
    })
    .map_err(|e| PyRuntimeError::new_err(format!("cannot start the Piper emulator: {e}")))?;
    Ok(PiperEmulator {
        params: place.params(),
        addr: place.socketcand_addr(),
        running: Mutex::new(Some((handle, place))),
        silenced: Mutex::new(None),
    })
}

// ---------------------------------------------------------------------------------------
// RobStride

/// RobStride actuators on a SocketCAN interface or behind a socketcand server.
#[pyclass(module = "armhil.sim", frozen)]
pub struct RobstrideEmulator {
    running: Mutex<Option<(RobstrideHandle, CanPlace)>>,
    params: BTreeMap<&'static str, String>,
    addr: Option<SocketAddr>,
}

fn robstride_fault(name: &str) -> PyResult<Fault> {
    Fault::from_name(name).ok_or_else(|| {
        let known: Vec<_> = Fault::ALL.iter().map(|f| f.name()).collect();
        value_err(format!(
            "unknown RobStride fault {name:?} (known: {})",
            known.join(", ")
        ))
    })
}

impl RobstrideEmulator {
    /// Runs a request on the emulator task (it answers through a channel).
    fn request<F, R>(&self, py: Python<'_>, f: F) -> PyResult<R>
    where
        F: for<'a> FnOnce(
            &'a RobstrideHandle,
        ) -> std::pin::Pin<
            Box<
                dyn std::future::Future<Output = Result<R, sim::robstride::RobstrideError>>
                    + Send
                    + 'a,
            >,
        >,
        R: Send,
    {
        let guard = lock(&self.running);
        let (h, _) = guard
            .as_ref()
            .ok_or_else(|| PyRuntimeError::new_err("the RobStride emulator is stopped"))?;
        block_on(py, sim_runtime(), f(h)).map_err(value_err)
    }
}

#[pymethods]
impl RobstrideEmulator {
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

    /// Where a client finds the bus (`socketcand` and `can_interface`, or `can_interface`).
    #[getter]
    fn params(&self) -> BTreeMap<&'static str, String> {
        self.params.clone()
    }

    /// Injects a fault on motor `can_id`: over_temperature, under_voltage, over_voltage,
    /// phase_a/b/c_over_current, encoder_not_calibrated, stall_overload, gate_driver.
    fn inject(&self, py: Python<'_>, name: &str, can_id: u8) -> PyResult<()> {
        let fault = robstride_fault(name)?;
        self.request(py, move |h| Box::pin(h.inject(can_id, fault)))
    }

    /// Removes a fault's cause on motor `can_id`.
    fn clear(&self, py: Python<'_>, name: &str, can_id: u8) -> PyResult<()> {
        let fault = robstride_fault(name)?;
        self.request(py, move |h| Box::pin(h.clear(can_id, fault)))
    }

    /// One dictionary per motor: CAN ID, model, mode, angle, speed, torque, temperature,
    /// voltage, fault word.
    fn state<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        let motors = self.request(py, |h| Box::pin(h.snapshot()))?;
        motors
            .iter()
            .map(|m| {
                let d = PyDict::new(py);
                d.set_item("can_id", m.can_id)?;
                d.set_item("model", m.model.name())?;
                d.set_item("mode", format!("{:?}", m.mode).to_lowercase())?;
                d.set_item("run_mode", m.run_mode)?;
                d.set_item("angle_rad", m.angle_rad)?;
                d.set_item("speed_rad_s", m.speed_rad_s)?;
                d.set_item("torque_nm", m.torque_nm)?;
                d.set_item("temperature_c", m.temperature_c)?;
                d.set_item("bus_voltage_v", m.bus_voltage_v)?;
                d.set_item("fault_word", m.fault_word)?;
                Ok(d)
            })
            .collect()
    }

    /// Whether it is running.
    #[getter]
    fn running(&self) -> bool {
        lock(&self.running).is_some()
    }

    /// Stops the emulator and its server (idempotent).
    fn stop(&self, py: Python<'_>) {
        let running = lock(&self.running).take();
        if let Some((h, place)) = running {
            block_on(py, sim_runtime(), async move {
                h.shutdown().await;
                place.close().await;
            });
        }
    }

    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    #[pyo3(signature = (*_args))]
    fn __exit__(&self, py: Python<'_>, _args: &Bound<'_, PyTuple>) -> bool {
        self.stop(py);
        exit_false()
    }
}

/// Starts RobStride actuators (`motors`: `"ID:MODEL"` strings, default one RS03 on ID 127)
/// on SocketCAN `iface` or (default) behind a socketcand server on `socketcand`.
#[pyfunction]
#[pyo3(signature = (motors=None, iface=None, socketcand="127.0.0.1:0"))]
fn robstride(
    py: Python<'_>,
    motors: Option<Vec<String>>,
    iface: Option<&str>,
    socketcand: &str,
) -> PyResult<RobstrideEmulator> {
    let specs = motors.unwrap_or_else(|| vec!["127:RS03".to_string()]);
    let motors = specs
        .iter()
        .map(|s| {
            let (id, model) = s.split_once(':').ok_or_else(|| {
                value_err(format!("motor {s:?}: expected ID:MODEL, e.g. 127:RS03"))
            })?;
            let id: u8 = id
                .trim()
                .parse()
                .map_err(|_| value_err(format!("motor {s:?}: bad CAN ID")))?;
            let model = Model::from_name(model).ok_or_else(|| {
                value_err(format!("motor {s:?}: unknown model (RS00..RS06, EL05)"))
            })?;
            Ok(MotorConfig::new(id, model))
        })
        .collect::<PyResult<Vec<_>>>()?;
    let config = RobstrideConfig::new(motors);
    let place = open_place(py, iface, socketcand, "robstride")?;
    let node = Arc::clone(&place.node);
    let handle = block_on(py, sim_runtime(), async move {
        RobstrideBus::spawn(node, config)
    })
    .map_err(|e| PyRuntimeError::new_err(format!("cannot start the RobStride emulator: {e}")))?;
    Ok(RobstrideEmulator {
        params: place.params(),
        addr: place.socketcand_addr(),
        running: Mutex::new(Some((handle, place))),
    })
}

/// Adds the emulator classes and constructors (`_armhil.sim_realman`, …).
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<RealmanEmulator>()?;
    m.add_class::<PiperEmulator>()?;
    m.add_class::<RobstrideEmulator>()?;
    let py = m.py();
    m.add("sim_realman", wrap_pyfunction!(realman, py)?)?;
    m.add("sim_piper", wrap_pyfunction!(piper, py)?)?;
    m.add("sim_robstride", wrap_pyfunction!(robstride, py)?)?;
    Ok(())
}
