//! The library's [`Error`] as a Python exception of `sticky_lips.errors` (the classes are
//! written in Python, with their attributes documented there):
//!
//! | `sticky_lips::Error`                      | Python                                        |
//! |-------------------------------------------|-----------------------------------------------|
//! | `Input { file, location, message }`       | `InputError(ValueError)`: file, line, field    |
//! | `Io { path, source }`                     | `OSError` (its errno's subclass): filename     |
//! | `UnstableTimeStep`, `UnstableLargeStep`   | `UnstableTimeStepError(SimulationError)`       |
//! | `Diverged { step, time, element, node }`  | `DivergedError(SimulationError)`               |
//! | `NotConverged`                            | `SimulationError(RuntimeError)`                |
//! | `Gpu`                                     | `GpuError(RuntimeError)`                       |
//! | `Interrupted { step, time }`              | `RunInterrupted(KeyboardInterrupt)` ([`interrupted`]) |
//! | `Cancelled`                               | `KeyboardInterrupt`                            |

use pyo3::exceptions::{PyKeyboardInterrupt, PyOSError, PyRuntimeError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use pyo3::BoundObject;
use std::path::Path;
use sticky_lips::error::Location;
use sticky_lips::Error;

/// An instance of `sticky_lips.errors.<class>(message, **attributes)` as a `PyErr`.
fn raise(py: Python<'_>, class: &str, message: String, attributes: &[(&str, Py<PyAny>)]) -> PyErr {
    let build = || -> PyResult<PyErr> {
        let kwargs = PyDict::new(py);
        for (k, v) in attributes {
            kwargs.set_item(k, v)?;
        }
        let cls = py.import("sticky_lips.errors")?.getattr(class)?;
        Ok(PyErr::from_value(
            cls.call((message.clone(),), Some(&kwargs))?,
        ))
    };
    // the classes live in the package's Python part: without it (the native module imported
    // on its own) the message still arrives, as a RuntimeError
    build().unwrap_or_else(|_| PyRuntimeError::new_err(message))
}

fn obj<'py, T: IntoPyObject<'py>>(py: Python<'py>, v: T) -> Py<PyAny> {
    v.into_pyobject(py)
        .map(|b| b.into_any().unbind())
        .unwrap_or_else(|_| py.None())
}

/// The Python exception for `e`.
pub fn to_py(py: Python<'_>, e: Error) -> PyErr {
    let message = e.to_string();
    match e {
        Error::Input {
            file,
            location,
            message: m,
        } => {
            let (line, field) = match location {
                Location::None => (None, None),
                Location::Line(l) => (Some(l), None),
                Location::Field(f) => (None, Some(f)),
                Location::LineField(l, f) => (Some(l), Some(f)),
            };
            raise(
                py,
                "InputError",
                message,
                &[
                    ("file", obj(py, file)),
                    ("line", obj(py, line)),
                    ("field", obj(py, field)),
                    ("message", obj(py, m)),
                ],
            )
        }
        Error::Io { path, source } => os_error(&path, &source),
        Error::UnstableTimeStep {
            dt,
            critical,
            element,
            ..
        } => raise(
            py,
            "UnstableTimeStepError",
            message,
            &[
                ("dt", obj(py, dt)),
                ("critical_time_step", obj(py, critical)),
                ("element", obj(py, element)),
                ("subcycles", obj(py, 1usize)),
            ],
        ),
        Error::UnstableLargeStep {
            dt,
            critical,
            subcycles,
        } => raise(
            py,
            "UnstableTimeStepError",
            message,
            &[
                ("dt", obj(py, dt)),
                ("critical_time_step", obj(py, critical)),
                ("element", py.None()),
                ("subcycles", obj(py, subcycles)),
            ],
        ),
        Error::Diverged {
            step,
            time,
            element,
            node,
            ..
        } => raise(
            py,
            "DivergedError",
            message,
            &[
                ("step", obj(py, step)),
                ("time", obj(py, time)),
                ("element", obj(py, element)),
                ("node", obj(py, node)),
            ],
        ),
        Error::NotConverged(_) => raise(py, "SimulationError", message, &[]),
        Error::Gpu(_) => raise(py, "GpuError", message, &[]),
        // a run stopped by its token: `interrupted` makes the exception that names the
        // directory; reaching this arm means the caller had no directory to name
        Error::Interrupted { step, time } => raise(
            py,
            "RunInterrupted",
            message,
            &[
                ("out", py.None()),
                ("step", obj(py, step)),
                ("time", obj(py, time)),
            ],
        ),
        Error::Cancelled(_) => PyKeyboardInterrupt::new_err(message),
    }
}

/// `OSError(errno, strerror, filename)`: Python picks the subclass of the errno
/// (`FileNotFoundError`, `PermissionError`, ...).
fn os_error(path: &Path, source: &std::io::Error) -> PyErr {
    let filename = path.display().to_string();
    match source.raw_os_error() {
        Some(errno) => {
            // Python adds the errno itself: "[Errno 2] No such file or directory: 'x'"
            let text = source.to_string();
            let strerror = text
                .strip_suffix(&format!(" (os error {errno})"))
                .unwrap_or(&text)
                .to_string();
            PyOSError::new_err((errno, strerror, filename))
        }
        None => PyOSError::new_err(format!("{filename}: {source}")),
    }
}

/// `RunInterrupted` for a run stopped at `step`, `time`, its partial output in `out`.
pub fn interrupted(py: Python<'_>, out: &Path, step: usize, time: f64) -> PyErr {
    let message = Error::Interrupted { step, time }.to_string();
    raise(
        py,
        "RunInterrupted",
        format!("{}: {message}", out.display()),
        &[
            ("out", obj(py, out.display().to_string())),
            ("step", obj(py, step)),
            ("time", obj(py, time)),
        ],
    )
}

/// Converts a library result.
pub trait IntoPy<T> {
    fn py_err(self, py: Python<'_>) -> PyResult<T>;
}

impl<T> IntoPy<T> for sticky_lips::Result<T> {
    fn py_err(self, py: Python<'_>) -> PyResult<T> {
        self.map_err(|e| to_py(py, e))
    }
}
