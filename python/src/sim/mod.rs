//! The emulators under Python control, in-process and in real time, started the way
//! `armhil sim <device>` starts them: the Realman controller on TCP/UDP, the Piper, the
//! RobStride actuators and the Damiao motors on a SocketCAN interface or behind a socketcand
//! server (CAN over TCP, for hosts without kernel CAN), and a whole robot from its robot file
//! with every bus at once. Each is a context manager; faults use the emulator's own names
//! (`comm_loss`, `reply_delay`, `over_temperature`, …).

mod can_place;
mod damiao;
mod emulated;
mod piper;
mod realman;
mod robot;
mod robstride;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use std::sync::Mutex;

use damiao::DamiaoEmulator;
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

pub(super) fn deg(rad: &[f64]) -> Vec<f64> {
    rad.iter().map(|r| r.to_degrees()).collect()
}

/// Adds the emulator classes and constructors (`_armhil.sim_realman`, …).
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<RealmanEmulator>()?;
    m.add_class::<PiperEmulator>()?;
    m.add_class::<RobstrideEmulator>()?;
    m.add_class::<DamiaoEmulator>()?;
    m.add_class::<RobotEmulator>()?;
    let py = m.py();
    m.add("sim_realman", wrap_pyfunction!(realman::realman, py)?)?;
    m.add("sim_piper", wrap_pyfunction!(piper::piper, py)?)?;
    m.add("sim_robstride", wrap_pyfunction!(robstride::robstride, py)?)?;
    m.add("sim_damiao", wrap_pyfunction!(damiao::damiao, py)?)?;
    m.add("sim_robot", wrap_pyfunction!(robot::robot, py)?)?;
    Ok(())
}
