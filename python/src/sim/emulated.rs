//! What every Python emulator shares: its faults through the emulator's own desk
//! (`sim::fault_desk`: the builder, table and messages of scenario files and the web view),
//! and being a context manager whose running parts stop once ([`Running`]).
//! [`emulator_methods!`] adds the shared Python methods (`faults`, `active_faults`, `running`,
//! `stop`, `with`) to a class implementing [`Emulated`].

use std::future::Future;
use std::pin::Pin;
use std::sync::Mutex;

use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sim::fault_args::{FaultArgValue, FaultArgs};
use sim::fault_desk::{FaultAction, FaultInfo, Faults};

use super::lock;
use crate::{block_on, sim_runtime};

/// A part of a running emulator that stops: its handle, or what serves it.
pub(super) trait Stop: Send + 'static {
    /// Shut it down.
    fn stop(self) -> Pin<Box<dyn Future<Output = ()> + Send>>;
}

/// An emulator's handle and what serves it: the emulator stops first, then its server.
impl<H: Stop, S: Stop> Stop for (H, S) {
    fn stop(self) -> Pin<Box<dyn Future<Output = ()> + Send>> {
        let (handle, served) = self;
        Box::pin(async move {
            handle.stop().await;
            served.stop().await;
        })
    }
}

/// What an emulator class holds while it runs; `stop` takes it, once.
pub(super) struct Running<T>(Mutex<Option<T>>);

impl<T: Stop> Running<T> {
    /// Running with `parts`.
    pub(super) fn new(parts: T) -> Self {
        Self(Mutex::new(Some(parts)))
    }

    /// `f` on the parts while running; `None` once stopped.
    pub(super) fn with<R>(&self, f: impl FnOnce(&T) -> R) -> Option<R> {
        lock(&self.0).as_ref().map(f)
    }

    fn is_running(&self) -> bool {
        lock(&self.0).is_some()
    }

    fn stop(&self, py: Python<'_>) {
        let parts = lock(&self.0).take();
        if let Some(parts) = parts {
            block_on(py, sim_runtime(), parts.stop());
        }
    }
}

/// A Python emulator class: a running emulator with a fault desk, stopped once.
pub(super) trait Emulated: Sized {
    /// Its handle and what serves it.
    type Parts: Stop;

    /// The emulator's name in messages (`the Piper emulator is stopped`).
    const NAME: &'static str;

    /// Its fault desk.
    fn desk(&self) -> &dyn Faults;

    /// Its running parts.
    fn parts(&self) -> &Running<Self::Parts>;

    /// `f` on the running parts, or `RuntimeError: the <kind> emulator is stopped`.
    fn with_parts<R>(&self, f: impl FnOnce(&Self::Parts) -> R) -> PyResult<R> {
        self.parts().with(f).ok_or_else(stopped::<Self>)
    }

    /// `request` (a call on the emulator's monitor) run to its end while the emulator runs.
    fn ask<F>(&self, py: Python<'_>, request: F) -> PyResult<F::Output>
    where
        F: Future + Send,
        F::Output: Send,
    {
        self.with_parts(|_| ())?;
        Ok(block_on(py, sim_runtime(), request))
    }

    /// Whether it is still running.
    fn is_running(&self) -> bool {
        self.parts().is_running()
    }

    /// Stop it and close what serves it (idempotent).
    fn shut_down(&self, py: Python<'_>) {
        self.parts().stop(py);
    }
}

/// Build the fault `name` from `args` and apply or clear it: a fault the builder refuses, or
/// the running emulator does (no motor has that CAN ID now), raises `ValueError` with its
/// message; a stopped emulator raises `RuntimeError`.
pub(super) fn apply<E: Emulated>(
    emulator: &E,
    py: Python<'_>,
    action: FaultAction,
    name: &str,
    args: &FaultArgs,
) -> PyResult<()> {
    if !emulator.is_running() {
        return Err(stopped::<E>());
    }
    block_on(py, sim_runtime(), emulator.desk().apply(action, name, args))
        .map(|_| ())
        .map_err(|e| PyValueError::new_err(e.to_string()))
}

/// `RuntimeError: the <kind> emulator is stopped`.
pub(super) fn stopped<E: Emulated>() -> PyErr {
    PyRuntimeError::new_err(format!("the {} emulator is stopped", E::NAME))
}

/// Python's keyword arguments as an emulator's fault builder reads them
/// (`sim::fault_args`), every emulator's `inject(name, **kwargs)` and `clear(name, **kwargs)`:
/// each keyword is a parameter name of the fault table (`faults()`), and the builder refuses
/// any other by name.
pub(super) fn builder_args(kwargs: Option<&Bound<'_, PyDict>>) -> PyResult<FaultArgs> {
    builder_args_after(None, kwargs)
}

/// [`builder_args`] after one argument given by position, under its table name (`("joint",
/// value)`: the robot's `inject(name, joint)`; `("motor", value)`: RobStride's old `can_id`).
/// The caller makes sure `kwargs` does not name it too.
pub(super) fn builder_args_after(
    positional: Option<(&str, &Bound<'_, PyAny>)>,
    kwargs: Option<&Bound<'_, PyDict>>,
) -> PyResult<FaultArgs> {
    let mut args = FaultArgs::new();
    if let Some((name, value)) = positional {
        args.push(name, builder_value(value)?);
    }
    for (key, value) in kwargs.into_iter().flat_map(|k| k.iter()) {
        let key: String = key.extract()?;
        args.push(key, builder_value(&value)?);
    }
    Ok(args)
}

/// One Python value as the builder reads it: `str` is a word, anything else a number (`int`,
/// `float`), or shown by its `str()` if it is not one (the builder then refuses it by name).
fn builder_value(value: &Bound<'_, PyAny>) -> PyResult<FaultArgValue> {
    Ok(if value.is_instance_of::<pyo3::types::PyString>() {
        FaultArgValue::Text(value.extract()?)
    } else if let Ok(x) = value.extract::<f64>() {
        FaultArgValue::Number(x)
    } else {
        FaultArgValue::Text(value.str()?.to_string())
    })
}

/// One argument as a Python value.
fn arg_value<'py>(py: Python<'py>, value: &FaultArgValue) -> PyResult<Bound<'py, PyAny>> {
    match value {
        FaultArgValue::Number(x) => Ok(x.into_pyobject(py)?.into_any()),
        FaultArgValue::Text(t) => Ok(t.into_pyobject(py)?.into_any()),
    }
}

/// The fault table as Python dictionaries: `name`, `description`, `params` (each `name`,
/// `description`, `required`, `default`, `min`, `max`, `words`).
pub(super) fn table<'py>(
    py: Python<'py>,
    table: &[FaultInfo],
) -> PyResult<Vec<Bound<'py, PyDict>>> {
    table
        .iter()
        .map(|fault| {
            let params = fault
                .params
                .iter()
                .map(|p| {
                    let d = PyDict::new(py);
                    d.set_item("name", p.name)?;
                    d.set_item("description", &p.description)?;
                    d.set_item("required", p.required)?;
                    let default = p.default.as_ref().map(|v| arg_value(py, v)).transpose()?;
                    d.set_item("default", default)?;
                    d.set_item("min", p.min)?;
                    d.set_item("max", p.max)?;
                    d.set_item("words", p.words.clone())?;
                    Ok(d)
                })
                .collect::<PyResult<Vec<_>>>()?;
            let d = PyDict::new(py);
            d.set_item("name", fault.name)?;
            d.set_item("description", &fault.description)?;
            d.set_item("params", params)?;
            Ok(d)
        })
        .collect()
}

/// The Python methods every emulator class has, for a class implementing [`Emulated`]: a
/// second `#[pymethods]` block (pyo3's `multiple-pymethods`), so they are written once.
macro_rules! emulator_methods {
    ($class:ty) => {
        #[pyo3::pymethods]
        impl $class {
            /// Every fault this emulator takes: a list of dictionaries with `name`,
            /// `description` and `params` (each `name`, `description`, `required`,
            /// `default`, `min`, `max`, `words`), as scenario files and the web view name them.
            fn faults<'py>(
                &self,
                py: pyo3::Python<'py>,
            ) -> pyo3::PyResult<Vec<pyo3::Bound<'py, pyo3::types::PyDict>>> {
                $crate::sim::emulated::table(
                    py,
                    &$crate::sim::emulated::Emulated::desk(self).table(),
                )
            }

            /// The faults injected from Python and not cleared, as labels (`stall joint 2`).
            #[getter]
            fn active_faults(&self) -> Vec<String> {
                $crate::sim::emulated::Emulated::desk(self).active()
            }

            /// Whether it is running.
            #[getter]
            fn running(&self) -> bool {
                $crate::sim::emulated::Emulated::is_running(self)
            }

            /// Stops the emulator and what serves it (idempotent).
            fn stop(&self, py: pyo3::Python<'_>) {
                $crate::sim::emulated::Emulated::shut_down(self, py)
            }

            fn __enter__(slf: pyo3::Py<Self>) -> pyo3::Py<Self> {
                slf
            }

            /// Stops it; returns false so an exception inside `with` propagates.
            #[pyo3(signature = (*_args))]
            fn __exit__(
                &self,
                py: pyo3::Python<'_>,
                _args: &pyo3::Bound<'_, pyo3::types::PyTuple>,
            ) -> bool {
                $crate::sim::emulated::Emulated::shut_down(self, py);
                false
            }
        }
    };
}

pub(super) use emulator_methods;
