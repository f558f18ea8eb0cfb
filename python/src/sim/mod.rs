//! The emulators under Python control, in-process and in real time, started the way
//! `armhil sim <device>` starts them: the Realman controller on TCP/UDP, the Piper and the
//! RobStride actuators on a SocketCAN interface or behind a socketcand server (CAN over TCP,
//! for hosts without kernel CAN). Each is a context manager; faults use the emulator's own
//! names (`comm_loss`, `reply_delay`, `over_temperature`, …).

mod can_place;
mod piper;
mod realman;
mod robstride;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::sync::Mutex;

use piper::PiperEmulator;
use realman::RealmanEmulator;
use robstride::RobstrideEmulator;

pub(super) fn value_err(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(e.to_string())
}

pub(super) fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// Fault keyword arguments, checked against what the fault takes.
pub(super) struct FaultArgs<'a, 'py> {
    name: &'a str,
    kwargs: Option<&'a Bound<'py, PyDict>>,
    used: Vec<&'static str>,
}

impl<'py> FaultArgs<'_, 'py> {
    pub(super) fn get<T: for<'a> FromPyObject<'a, 'py>>(
        &mut self,
        key: &'static str,
    ) -> PyResult<Option<T>> {
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

    pub(super) fn need<T: for<'a> FromPyObject<'a, 'py>>(
        &mut self,
        key: &'static str,
    ) -> PyResult<T> {
        self.get(key)?
            .ok_or_else(|| value_err(format!("fault {:?} needs {key}=…", self.name)))
    }

    /// Refuses keywords the fault does not take (a typo must not pass silently).
    pub(super) fn finish(self) -> PyResult<()> {
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

pub(super) fn fault_args<'a, 'py>(
    name: &'a str,
    kwargs: Option<&'a Bound<'py, PyDict>>,
) -> FaultArgs<'a, 'py> {
    FaultArgs {
        name,
        kwargs,
        used: Vec::new(),
    }
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
    let py = m.py();
    m.add("sim_realman", wrap_pyfunction!(realman::realman, py)?)?;
    m.add("sim_piper", wrap_pyfunction!(piper::piper, py)?)?;
    m.add("sim_robstride", wrap_pyfunction!(robstride::robstride, py)?)?;
    Ok(())
}
