//! Damiao (DM) joint motors under Python control.

use std::collections::BTreeMap;
use std::future::Future;
use std::net::SocketAddr;
use std::pin::Pin;
use std::sync::Arc;

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sim::actuator::Detail;
use sim::damiao::{
    DamiaoBus, DamiaoConfig, DamiaoError, DamiaoHandle, DamiaoMonitor, Model, MotorConfig, MAX_ID,
};
use sim::fault_desk::{FaultAction, FaultDesk, Faults};

use super::can_place::{open_place, CanPlace};
use super::emulated::{apply, builder_args, emulator_methods, Emulated, Running, Stop};
use super::value_err;
use crate::{block_on, sim_runtime};

/// Highest ESC_ID a motor may have: its force-position command goes to 0x300 + ESC_ID, which
/// must stay below the register identifier 0x7FF (as `armhil sim damiao` and robot files).
const MAX_ESC_ID: u16 = 0x4FE;
/// The identifier of register requests and refreshes, which every motor listens on.
const REGISTER_ID: u16 = 0x7FF;
/// The command identifiers of a motor besides ESC_ID itself: position-velocity, velocity and
/// force-position (docs/protocols/damiao.md §2).
const COMMAND_OFFSETS: [u16; 4] = [0, 0x100, 0x200, 0x300];

/// Damiao motors on a SocketCAN interface or behind a socketcand server.
#[pyclass(module = "armhil.sim", frozen)]
pub struct DamiaoEmulator {
    running: Running<(DamiaoHandle, CanPlace)>,
    faults: FaultDesk<DamiaoMonitor>,
    params: BTreeMap<&'static str, String>,
    addr: Option<SocketAddr>,
}

impl Stop for DamiaoHandle {
    fn stop(self) -> Pin<Box<dyn Future<Output = ()> + Send>> {
        Box::pin(self.shutdown())
    }
}

impl Emulated for DamiaoEmulator {
    type Parts = (DamiaoHandle, CanPlace);
    const NAME: &'static str = "Damiao";

    fn desk(&self) -> &dyn Faults {
        &self.faults
    }

    fn parts(&self) -> &Running<Self::Parts> {
        &self.running
    }
}

emulator_methods!(DamiaoEmulator);

#[pymethods]
impl DamiaoEmulator {
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

    /// Injects fault `name` of the Damiao fault table (`faults()` lists it, with each
    /// argument's range), its arguments by keyword: `motor=` (the ESC_ID) and the fault's own
    /// values — over_voltage(voltage_v), under_voltage(voltage_v), over_current,
    /// mos_over_temperature(temperature_c), coil_over_temperature(temperature_c), comm_lost,
    /// overload. The error latches (the feedback's state nibble) and the motor stops. The
    /// emulator's fault builder checks them (scenario files' ranges and messages):
    /// `ValueError` when it refuses them.
    #[pyo3(signature = (name, **kwargs))]
    fn inject(
        &self,
        py: Python<'_>,
        name: &str,
        kwargs: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<()> {
        let args = builder_args(kwargs)?;
        apply(self, py, FaultAction::Inject, name, &args)
    }

    /// Removes a fault's cause on a motor: `motor=` (a fault's values may be left out). The
    /// error stays latched until the host clears it (`FF…FB`), as on the motor.
    #[pyo3(signature = (name, **kwargs))]
    fn clear(
        &self,
        py: Python<'_>,
        name: &str,
        kwargs: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<()> {
        let args = builder_args(kwargs)?;
        apply(self, py, FaultAction::Clear, name, &args)
    }

    /// One dictionary per motor, in configuration order: `can_id` (its ESC_ID now), `mst_id`
    /// (feedback id), `model`, `enabled`, `mode`, `ctrl_mode` (register 10), `state` (the
    /// feedback's state nibble), `angle_rad`, `speed_rad_s`, `torque_nm`, `temperature_c`
    /// (coil), `mos_temperature_c`, `bus_voltage_v`, `faults` (latched, by name).
    fn state<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        let motors = self
            .ask(py, self.faults.target().snapshot())?
            .map_err(value_err)?;
        motors
            .iter()
            .map(|m| {
                let d = PyDict::new(py);
                d.set_item("can_id", m.can_id)?;
                d.set_item("model", m.model)?;
                d.set_item("enabled", m.enabled)?;
                d.set_item("mode", &m.mode)?;
                d.set_item("angle_rad", m.angle_rad)?;
                d.set_item("speed_rad_s", m.speed_rad_s)?;
                d.set_item("torque_nm", m.torque_nm)?;
                d.set_item("temperature_c", m.temperature_c)?;
                d.set_item("faults", m.faults.clone())?;
                // What only Damiao motors have (state, mst_id, ctrl_mode, …), by name.
                for (name, value) in &m.details {
                    match value {
                        Detail::Int(v) => d.set_item(*name, v)?,
                        Detail::Real(v) => d.set_item(*name, v)?,
                        Detail::Word(v) => d.set_item(*name, v)?,
                    }
                }
                Ok(d)
            })
            .collect()
    }
}

/// An identifier as written: decimal or `0x` hexadecimal, within `min..=max`.
fn parse_id(text: &str, what: &str, min: u16, max: u16) -> Result<u16, String> {
    let t = text.trim();
    let parsed = match t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        Some(hex) => u16::from_str_radix(hex, 16),
        None => t.parse::<u16>(),
    };
    match parsed {
        Ok(id) if (min..=max).contains(&id) => Ok(id),
        _ => Err(format!(
            "{what} {t:?}: expected a number in {min}..={max} (0x{min:X}..=0x{max:X})"
        )),
    }
}

/// `ESC_ID:MODEL[:FEEDBACK_ID]`; the feedback id defaults to ESC_ID + 0x10 (the OpenArm's).
fn parse_motor(spec: &str) -> Result<MotorConfig, String> {
    let fail = |why: String| format!("motor {spec:?}: {why}");
    let parts: Vec<&str> = spec.split(':').collect();
    let (esc, model, mst) = match parts.as_slice() {
        [esc, model] => (esc, model, None),
        [esc, model, mst] => (esc, model, Some(mst)),
        _ => {
            return Err(fail(
                "expected ID:MODEL or ID:MODEL:FEEDBACK_ID, e.g. 1:DM4310 or 0x01:DM4310:0x11"
                    .to_string(),
            ))
        }
    };
    let esc_id = parse_id(esc, "ESC_ID", 1, MAX_ESC_ID).map_err(fail)?;
    let model = Model::named(model).map_err(fail)?;
    let mut config = MotorConfig::new(esc_id, model);
    if let Some(mst) = mst {
        config.mst_id = parse_id(mst, "feedback id", 0, MAX_ID).map_err(fail)?;
    }
    Ok(config)
}

/// Refuses a feedback id a motor listens on: the register identifier, or another motor's
/// command identifier (that motor would read each reply as a command).
fn check_feedback_ids(specs: &[String], motors: &[MotorConfig]) -> Result<(), String> {
    for (spec, m) in specs.iter().zip(motors) {
        if m.mst_id == REGISTER_ID {
            return Err(format!(
                "motor {spec:?}: its feedback id 0x7FF is the register identifier every motor listens on"
            ));
        }
        for other in motors {
            if let Some(offset) = COMMAND_OFFSETS
                .iter()
                .find(|&&o| other.esc_id + o == m.mst_id)
            {
                return Err(format!(
                    "motor {spec:?}: it would answer on 0x{:03X}, a command identifier of the motor on ESC_ID {} (ESC_ID + 0x{offset:X}); give it another feedback id (ID:MODEL:FEEDBACK_ID)",
                    m.mst_id, other.esc_id
                ));
            }
        }
    }
    Ok(())
}

/// Starts Damiao motors (`motors`: `"ESC_ID:MODEL"` or `"ESC_ID:MODEL:FEEDBACK_ID"` strings,
/// default one DM4310 on ESC_ID 1 answering on 0x11) on SocketCAN `iface` or (default) behind
/// a socketcand server on `socketcand`.
#[pyfunction]
#[pyo3(signature = (motors=None, iface=None, socketcand="127.0.0.1:0"))]
pub(super) fn damiao(
    py: Python<'_>,
    motors: Option<Vec<String>>,
    iface: Option<&str>,
    socketcand: &str,
) -> PyResult<DamiaoEmulator> {
    let specs = motors.unwrap_or_else(|| vec!["1:DM4310".to_string()]);
    let configs = specs
        .iter()
        .map(|s| parse_motor(s))
        .collect::<Result<Vec<_>, _>>()
        .map_err(value_err)?;
    check_feedback_ids(&specs, &configs).map_err(value_err)?;
    let config = DamiaoConfig::new(configs);
    let place = open_place(py, iface, socketcand, "damiao", true)?;
    let node = Arc::clone(&place.node);
    let handle = block_on(
        py,
        sim_runtime(),
        async move { DamiaoBus::spawn(config, node) },
    );
    let handle = match handle {
        Ok(handle) => handle,
        Err(e) => {
            block_on(py, sim_runtime(), place.close());
            return Err(match e {
                DamiaoError::DuplicateEscId { .. } | DamiaoError::InvalidMotor { .. } => {
                    value_err(e)
                }
                e => PyRuntimeError::new_err(format!("cannot start the Damiao emulator: {e}")),
            });
        }
    };
    Ok(DamiaoEmulator {
        faults: FaultDesk::new(handle.monitor()),
        params: place.params(),
        addr: place.socketcand_addr(),
        running: Running::new((handle, place)),
    })
}
