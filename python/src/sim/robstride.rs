//! RobStride actuators under Python control.

use std::collections::BTreeMap;
use std::future::Future;
use std::net::SocketAddr;
use std::pin::Pin;
use std::sync::Arc;

use pyo3::exceptions::{PyDeprecationWarning, PyRuntimeError, PyTypeError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sim::fault_args::FaultArgs;
use sim::fault_desk::{FaultAction, FaultDesk, Faults};
use sim::robstride::faults::MOTOR;
use sim::robstride::{
    Model, MotorConfig, RobstrideBus, RobstrideConfig, RobstrideHandle, RobstrideMonitor,
};

use super::can_place::{open_place, CanPlace};
use super::emulated::{
    apply, builder_args, builder_args_after, emulator_methods, Emulated, Running, Stop,
};
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

/// The builder's arguments of `inject` and `clear`: `kwargs`, after `can_id` if given (the
/// old spelling of `motor=`, kept for one release with a `DeprecationWarning`; `TypeError`
/// when `motor=` is given too).
fn motor_args(
    py: Python<'_>,
    can_id: Option<&Bound<'_, PyAny>>,
    kwargs: Option<&Bound<'_, PyDict>>,
) -> PyResult<FaultArgs> {
    let Some(can_id) = can_id else {
        return builder_args(kwargs);
    };
    if let Some(kwargs) = kwargs {
        if kwargs.contains(MOTOR.name)? {
            return Err(PyTypeError::new_err(
                "`can_id` is the old spelling of `motor=`: give the motor once, as `motor=`",
            ));
        }
    }
    PyErr::warn(
        py,
        &py.get_type::<PyDeprecationWarning>(),
        c"RobStride inject/clear: `can_id` is the old spelling of `motor=` and goes in the next release; write inject(name, motor=ID)",
        1,
    )?;
    builder_args_after(Some((MOTOR.name, can_id)), kwargs)
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

    /// Injects fault `name` of the RobStride fault table (`faults()` lists it, with each
    /// argument's range), its arguments by keyword: `motor=` (the CAN ID) and the fault's own
    /// values — over_temperature, under_voltage, over_voltage, phase_a_over_current,
    /// phase_b_over_current, phase_c_over_current, encoder_not_calibrated, stall_overload,
    /// gate_driver (`motor=` alone); encoder_glitch(motor, counts). The emulator's fault
    /// builder checks them (scenario files' ranges and messages): `ValueError` when it refuses
    /// them. `can_id`, by position, is the old spelling of `motor=` (deprecated).
    #[pyo3(signature = (name, can_id=None, **kwargs))]
    fn inject(
        &self,
        py: Python<'_>,
        name: &str,
        can_id: Option<&Bound<'_, PyAny>>,
        kwargs: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<()> {
        let args = motor_args(py, can_id, kwargs)?;
        apply(self, py, FaultAction::Inject, name, &args)
    }

    /// Removes a fault's cause on a motor: `motor=` (a fault's values may be left out).
    /// `can_id`, by position, is the old spelling of `motor=` (deprecated).
    #[pyo3(signature = (name, can_id=None, **kwargs))]
    fn clear(
        &self,
        py: Python<'_>,
        name: &str,
        can_id: Option<&Bound<'_, PyAny>>,
        kwargs: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<()> {
        let args = motor_args(py, can_id, kwargs)?;
        apply(self, py, FaultAction::Clear, name, &args)
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
    let place = open_place(py, iface, socketcand, "robstride", false)?;
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
