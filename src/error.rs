//! One error type for the library. Every input error names its file and the line or
//! the field; a run that goes wrong names the step, time and element.

use std::fmt;
use std::path::PathBuf;

/// Where in an input something is wrong.
#[derive(Debug, Clone, PartialEq)]
pub enum Location {
    None,
    Line(usize),
    Field(String),
    LineField(usize, String),
}

#[derive(Debug)]
pub enum Error {
    /// Malformed or inconsistent input.
    Input {
        file: String,
        location: Location,
        message: String,
    },
    /// Reading or writing a file failed.
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// The requested time step exceeds the critical one.
    UnstableTimeStep {
        dt: f64,
        critical: f64,
        element: usize,
        element_estimate: f64,
    },
    /// A subcycled run's large step is above the tissue's critical step.
    UnstableLargeStep {
        dt: f64,
        critical: f64,
        subcycles: usize,
    },
    /// The explicit run diverged.
    Diverged {
        step: usize,
        time: f64,
        element: Option<usize>,
        node: Option<usize>,
        reason: String,
    },
    /// The run was stopped by SIGINT or SIGTERM between two steps; the frames written before
    /// are complete and `summary.json` says where it stopped.
    Interrupted { step: usize, time: f64 },
    /// A command other than a run's stepping (`face`, `export`, `sweep`, `paper`) was stopped
    /// by SIGINT or SIGTERM: what it had done, and that it left no partial file.
    Cancelled(String),
    /// The static solver did not converge.
    NotConverged(String),
    /// The GPU backend is unavailable or failed (no adapter, missing feature, shader or
    /// device error, a model too large for the adapter's limits).
    Gpu(String),
}

pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    pub fn input(file: impl Into<String>, location: Location, message: impl Into<String>) -> Self {
        Error::Input {
            file: file.into(),
            location,
            message: message.into(),
        }
    }
    pub fn field(
        file: impl Into<String>,
        field: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        Error::Input {
            file: file.into(),
            location: Location::Field(field.into()),
            message: message.into(),
        }
    }
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Input { file, location, message } => match location {
                Location::None => write!(f, "{file}: {message}"),
                Location::Line(l) => write!(f, "{file}:{l}: {message}"),
                Location::Field(k) => write!(f, "{file}: field `{k}`: {message}"),
                Location::LineField(l, k) => write!(f, "{file}:{l}: field `{k}`: {message}"),
            },
            Error::Io { path, source } => write!(f, "{}: {source}", path.display()),
            Error::UnstableTimeStep { dt, critical, element, element_estimate } => write!(
                f,
                "time step {dt:.4e} s exceeds the critical time step {critical:.4e} s (2/omega_max of M^-1 K); \
                 the limiting element is {element} (its own estimate {element_estimate:.4e} s). \
                 Use a time step of at most {critical:.4e} s, or force the run (`--force-dt` on \
                 the command line, `force_dt=True` from Python)"
            ),
            Error::UnstableLargeStep { dt, critical, subcycles } => write!(
                f,
                "the large step {dt:.4e} s of a run with {subcycles} substeps exceeds the \
                 critical time step of the tissue {critical:.4e} s (the model without the \
                 saliva's stiffness); use a step of at most {critical:.4e} s, or force the run \
                 (`--force-dt` on the command line, `force_dt=True` from Python)"
            ),
            Error::Diverged { step, time, element, node, reason } => {
                write!(f, "run diverged at step {step} (t = {time:.6e} s)")?;
                if let Some(e) = element {
                    write!(f, ", element {e}")?;
                }
                if let Some(n) = node {
                    write!(f, ", node {n}")?;
                }
                write!(f, ": {reason}")?;
                if *step <= 2 {
                    write!(
                        f,
                        " (at the first steps: what the run started from or was given is out of \
                         range, not the stepping: check the keyed controls' values (jaw angle in \
                         radians, activations in [0, 1]), the prescribed displacements, the rig's \
                         hinge, and for a restart the checkpoint)"
                    )?;
                }
                Ok(())
            }
            Error::Interrupted { step, time } => write!(
                f,
                "interrupted at step {step} (t = {time:.6e} s): the frames written so far are complete and listed in frames.pvd; summary.json is marked interrupted"
            ),
            Error::Cancelled(m) => write!(f, "interrupted: {m}"),
            Error::NotConverged(m) => write!(f, "static solver did not converge: {m}"),
            Error::Gpu(m) => write!(f, "GPU backend: {m}"),
        }
    }
}

impl std::error::Error for Error {}
