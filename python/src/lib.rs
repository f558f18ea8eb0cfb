//! `armhil._armhil`: the Python extension behind the `armhil` package.
//!
//! - [`arm`]: the vendor-neutral Arm API (`ArmFactory`, `ArmFactoryParam`, `ArmInterface`)
//!   wrapping `driver::arm`; every method returns an `AbcErrorCode` (or a tuple with one).
//! - [`types`]: the API's data classes (`Pose`, `ArmRealtimeState`, …).
//! - [`sim`]: the Realman, Piper and RobStride emulators running in-process in real time.
//!
//! Blocking calls release the GIL and run the async driver on a module-wide tokio runtime;
//! the emulators run on a second one, so a busy physics step never delays a driver reply.

// PyO3's macros (`#[pymodule]`, `#[pyclass]`, `#[pymethods]`) expand to `unsafe` FFI glue;
// this crate itself writes no unsafe code.
#![allow(unsafe_code)]

use std::future::Future;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

use driver::arm::AbcErrorCode;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

pub mod arm;
pub mod sim;
pub mod types;

/// Set at interpreter exit: realtime callbacks stop calling into Python.
static SHUTTING_DOWN: AtomicBool = AtomicBool::new(false);

/// Driver threads inside (or about to enter) Python. A thread that holds the GIL when the
/// interpreter finalizes aborts the process, so exit waits for them.
static IN_PYTHON: AtomicUsize = AtomicUsize::new(0);

/// Runs `f` with the GIL from a driver thread, unless the interpreter is exiting.
pub(crate) fn with_python(f: impl FnOnce(Python<'_>)) {
    // Counted before the flag is read: `_shutdown` sets the flag, then waits for the count,
    // so every thread either sees the flag or is waited for.
    IN_PYTHON.fetch_add(1, Ordering::SeqCst);
    if !SHUTTING_DOWN.load(Ordering::SeqCst) {
        Python::attach(f);
    }
    IN_PYTHON.fetch_sub(1, Ordering::SeqCst);
}

fn build_runtime(name: &str) -> tokio::runtime::Runtime {
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .thread_name(name)
        .enable_all()
        .build()
        // Without threads or timers nothing in this module can work; say so plainly.
        .unwrap_or_else(|e| panic!("armhil: cannot start the tokio runtime: {e}"))
}

/// The runtime the arm drivers run on.
pub(crate) fn driver_runtime() -> &'static tokio::runtime::Runtime {
    static RT: OnceLock<tokio::runtime::Runtime> = OnceLock::new();
    RT.get_or_init(|| build_runtime("armhil-driver"))
}

/// The runtime the emulators run on: what `armhil sim` starts
/// (`sim::pacer::real_time_runtime`), one punctual worker: two kept waking each other, and
/// an emulator's work fits one core with room to spare.
pub(crate) fn sim_runtime() -> &'static tokio::runtime::Runtime {
    static RT: OnceLock<tokio::runtime::Runtime> = OnceLock::new();
    RT.get_or_init(|| {
        ::sim::pacer::real_time_runtime_builder()
            .thread_name("armhil-sim")
            .build()
            .unwrap_or_else(|e| panic!("armhil: cannot start the emulators' runtime: {e}"))
    })
}

/// Runs `fut` to completion on `rt` with the GIL released. Inside a runtime thread (a
/// realtime callback calling the arm) `block_on` is not allowed, and simply blocking the
/// worker could starve the very tasks `fut` waits for (a worker's next-task slot is never
/// stolen): the worker hands its queue over first (`block_in_place`).
pub(crate) fn block_on<F>(py: Python<'_>, rt: &'static tokio::runtime::Runtime, fut: F) -> F::Output
where
    F: Future + Send,
    F::Output: Send,
{
    use tokio::runtime::{Handle, RuntimeFlavor};
    py.detach(|| match Handle::try_current().map(|h| h.runtime_flavor()) {
        Err(_) => rt.block_on(fut),
        Ok(RuntimeFlavor::MultiThread) => tokio::task::block_in_place(|| rt.block_on(fut)),
        // Not one of ours (ours are multi-thread): wait on a helper thread.
        Ok(_) => std::thread::scope(|s| {
            s.spawn(|| rt.block_on(fut))
                .join()
                .unwrap_or_else(|p| std::panic::resume_unwind(p))
        }),
    })
}

/// The `AbcErrorCode` IntEnum members, in `AbcErrorCode::ALL` order.
static CODES: OnceLock<Vec<Py<PyAny>>> = OnceLock::new();

/// The Python `AbcErrorCode` member for `code`.
pub(crate) fn code_object(py: Python<'_>, code: AbcErrorCode) -> Py<PyAny> {
    let i = AbcErrorCode::ALL
        .iter()
        .position(|c| *c == code)
        .unwrap_or(0);
    match CODES.get() {
        Some(members) => members[i].clone_ref(py),
        // Only before module init, which cannot happen from Python.
        None => code
            .value()
            .into_pyobject(py)
            .map_or_else(|_| py.None(), |v| v.into_any().unbind()),
    }
}

/// Builds `AbcErrorCode` as an `enum.IntEnum` from the driver's table (one source of truth).
fn make_codes(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    let members = PyList::empty(py);
    for code in AbcErrorCode::ALL {
        members.append((code.name(), code.value()))?;
    }
    let kwargs = PyDict::new(py);
    kwargs.set_item("module", "armhil")?;
    let cls = py
        .import("enum")?
        .getattr("IntEnum")?
        .call(("AbcErrorCode", members), Some(&kwargs))?;
    cls.setattr(
        "__doc__",
        "Result codes of the Arm API: SUCCESS (0) or a negative error code.",
    )?;
    let objects = AbcErrorCode::ALL
        .iter()
        .map(|c| cls.call1((c.value(),)).map(Bound::unbind))
        .collect::<PyResult<Vec<_>>>()?;
    let _ = CODES.set(objects);
    m.add("AbcErrorCode", cls)?;
    Ok(())
}

/// Called at interpreter exit: realtime callbacks stop entering Python, and those already
/// in it finish (the GIL is released meanwhile) before finalization starts.
#[pyfunction]
fn _shutdown(py: Python<'_>) {
    SHUTTING_DOWN.store(true, Ordering::SeqCst);
    py.detach(|| {
        // A callback stuck in user code must not hang the exit forever.
        let end = Instant::now() + Duration::from_secs(5);
        while IN_PYTHON.load(Ordering::SeqCst) > 0 && Instant::now() < end {
            std::thread::sleep(Duration::from_millis(1));
        }
    });
}

/// Converts a message into the `RuntimeError` the API raises for bad parameters.
pub(crate) fn runtime_error(message: impl Into<String>) -> PyErr {
    PyRuntimeError::new_err(message.into())
}

/// The extension module.
#[pymodule]
fn _armhil(m: &Bound<'_, PyModule>) -> PyResult<()> {
    make_codes(m)?;
    types::register(m)?;
    arm::register(m)?;
    sim::register(m)?;
    let shutdown = wrap_pyfunction!(_shutdown, m)?;
    m.py()
        .import("atexit")?
        .call_method1("register", (shutdown.clone(),))?;
    m.add_function(shutdown)?;
    Ok(())
}
