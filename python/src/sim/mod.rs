//! The emulators under Python control, in-process and in real time, started the way
//! `armhil sim <device>` starts them: the Realman controller on TCP/UDP, the Piper and the
//! RobStride actuators on a SocketCAN interface or behind a socketcand server (CAN over TCP,
//! for hosts without kernel CAN), and a whole robot from its robot file with every bus at
//! once. Each is a context manager; faults use the emulator's own names (`comm_loss`,
//! `reply_delay`, `over_temperature`, …).

mod can_place;
mod piper;
mod realman;
mod robot;
mod robstride;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};
use sim::fault_args::{FaultArgValue, FaultArgs};
use std::sync::Mutex;

use piper::PiperEmulator;
use realman::RealmanEmulator;
use robot::RobotEmulator;
use robstride::RobstrideEmulator;

pub(super) fn value_err(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(e.to_string())
}

pub(super) fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// Python's keyword arguments as an emulator's fault builder reads them
/// (`sim::fault_args`): `str` is a word, anything else a number (`int`, `float`), or shown by
/// its `str()` if it is not one (the builder then refuses it by name).
pub(super) fn builder_args(kwargs: Option<&Bound<'_, PyDict>>) -> PyResult<FaultArgs> {
    let mut args = FaultArgs::new();
    for (key, value) in kwargs.into_iter().flat_map(|k| k.iter()) {
        let key: String = key.extract()?;
        let value = if value.is_instance_of::<PyString>() {
            FaultArgValue::Text(value.extract()?)
        } else if let Ok(x) = value.extract::<f64>() {
            FaultArgValue::Number(x)
        } else {
            FaultArgValue::Text(value.str()?.to_string())
        };
        args.push(key, value);
    }
    Ok(args)
}

pub(super) fn deg(rad: &[f64]) -> Vec<f64> {
    rad.iter().map(|r| r.to_degrees()).collect()
}

/// Returns false so an exception inside `with` propagates.
pub(super) fn exit_false() -> bool {
    false
}

/// Adds the emulator classes and constructors (`_armhil.sim_realman`, …).
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<RealmanEmulator>()?;
    m.add_class::<PiperEmulator>()?;
    m.add_class::<RobstrideEmulator>()?;
    m.add_class::<RobotEmulator>()?;
    let py = m.py();
    m.add("sim_realman", wrap_pyfunction!(realman::realman, py)?)?;
    m.add("sim_piper", wrap_pyfunction!(piper::piper, py)?)?;
    m.add("sim_robstride", wrap_pyfunction!(robstride::robstride, py)?)?;
    m.add("sim_robot", wrap_pyfunction!(robot::robot, py)?)?;
    Ok(())
}
