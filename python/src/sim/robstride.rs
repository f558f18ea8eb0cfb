//! RobStride actuators under Python control.

use std::collections::BTreeMap;
use std::future::Future;
use std::net::SocketAddr;
use std::pin::Pin;
use std::sync::Arc;

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sim::fault_args::{FaultArgValue, FaultArgs};
use sim::fault_desk::{FaultAction, FaultDesk, Faults};
use sim::robstride::{
    Model, MotorConfig, RobstrideBus, RobstrideConfig, RobstrideHandle, RobstrideMonitor,
};

use super::can_place::{open_place, CanPlace};
use super::emulated::{apply, emulator_methods, Emulated, Running, Stop};
use super::value_err;
use crate::{block_on, sim_runtime};

/// RobStride actuators on a SocketCAN interface or behind a socketcand server.
#[pyclass(module = "armhil.sim", frozen)]
pub struct RobstrideEmulator {
    running: Running<(RobstrideHandle, CanPlace)>,
    faults: FaultDesk<RobstrideMonitor>,
    params: BTreeMap<&'static str, String>,
    addr: Option<SocketAddr>,
}

/// The arguments of a fault on motor `can_id` (checked by the emulator's builder: every i64
/// a CAN ID could be is exact in f64 up to 2^53; beyond, it is refused anyway).
fn on_motor(can_id: i64) -> FaultArgs {
    FaultArgs::new().with("motor", FaultArgValue::Number(can_id as f64))
}

impl Stop for RobstrideHandle {
    fn stop(self) -> Pin<Box<dyn Future<Output = ()> + Send>> {
        Box::pin(self.shutdown())
    }
}

impl Emulated for RobstrideEmulator {
    type Parts = (RobstrideHandle, CanPlace);
    const NAME: &'static str = "RobStride";

    fn desk(&self) -> &dyn Faults {
        &self.faults
    }

    fn parts(&self) -> &Running<Self::Parts> {
        &self.running
    }
}

emulator_methods!(RobstrideEmulator);

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
    fn inject(&self, py: Python<'_>, name: &str, can_id: i64) -> PyResult<()> {
        apply(self, py, FaultAction::Inject, name, &on_motor(can_id))
    }

    /// Removes a fault's cause on motor `can_id`.
    fn clear(&self, py: Python<'_>, name: &str, can_id: i64) -> PyResult<()> {
        apply(self, py, FaultAction::Clear, name, &on_motor(can_id))
    }

    /// One dictionary per motor: CAN ID, model, mode, angle, speed, torque, temperature,
    /// voltage, fault word.
    fn state<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        let motors = self
            .ask(py, self.faults.target().snapshot())?
            .map_err(value_err)?;
        motors
            .iter()
            .map(|m| {
                let d = PyDict::new(py);
                d.set_item("can_id", m.can_id)?;
                d.set_item("model", m.model.name())?;
                d.set_item("mode", m.mode.name())?;
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
}

/// Starts RobStride actuators (`motors`: `"ID:MODEL"` strings, default one RS03 on ID 127)
/// on SocketCAN `iface` or (default) behind a socketcand server on `socketcand`.
#[pyfunction]
#[pyo3(signature = (motors=None, iface=None, socketcand="127.0.0.1:0"))]
pub(super) fn robstride(
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
        faults: FaultDesk::new(handle.monitor()),
        params: place.params(),
        addr: place.socketcand_addr(),
        running: Running::new((handle, place)),
    })
}
