//! `sticky_lips._native`: the native half of the Python package `sticky_lips` (python/).
//! It loads and checks problems, runs them with the GIL released, builds faces and reads run
//! directories into NumPy arrays; the package's Python half (`python/sticky_lips/`) turns
//! these into the documented classes (`Scenario`, `Run`, ...). Nothing here is public API:
//! the stubs are `python/sticky_lips/_native.pyi`.

mod drive;
mod errors;
mod frames;
mod values;

use errors::IntoPy;
use pyo3::exceptions::{PyKeyboardInterrupt, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::{Path, PathBuf};
use sticky_lips::app;
use sticky_lips::control::CancelToken;
use sticky_lips::driver::{self, Backend, RunOptions};
use sticky_lips::io::scenario::{self, DtChoice};
use sticky_lips::tled::precompute::Discretisation;
use sticky_lips::tled::stability;
use sticky_lips::Precision;

/// A problem ready to run: a scenario or a NiftySim model, read and checked.
#[pyclass(module = "sticky_lips._native", frozen)]
struct Problem {
    problem: sticky_lips::Problem,
    /// The scenario's `[output] dir`, where it names one.
    default_output: Option<PathBuf>,
}

fn problem(p: sticky_lips::Problem, default_output: Option<PathBuf>) -> Problem {
    Problem {
        problem: p,
        default_output,
    }
}

/// The problem in the file `path`, read as its extension says (`.toml` or `.xml`).
#[pyfunction]
#[pyo3(signature = (path, niftysim_compat = false))]
fn load(py: Python<'_>, path: PathBuf, niftysim_compat: bool) -> PyResult<Problem> {
    let input = app::input::Input {
        path,
        niftysim_compat,
    };
    let (p, out) = py.detach(|| app::input::load(&input)).py_err(py)?;
    Ok(problem(p, out))
}

/// The scenario `text`, taken to be the file `path` (errors name it; relative paths in the
/// text are read from its directory).
#[pyfunction]
fn parse(py: Python<'_>, text: &str, path: PathBuf) -> PyResult<Problem> {
    let s = py.detach(|| scenario::parse(text, &path)).py_err(py)?;
    Ok(problem(s.problem, s.default_output))
}

/// A scenario file's text.
#[pyfunction]
fn read_text(py: Python<'_>, path: PathBuf) -> PyResult<String> {
    scenario::read_text(&path).py_err(py)
}

/// `text` (the file `file`) with the dotted keys of `overrides` set to the TOML values of
/// the Python values.
#[pyfunction]
fn with_overrides(
    py: Python<'_>,
    text: &str,
    file: &str,
    overrides: Vec<(String, Bound<'_, PyAny>)>,
) -> PyResult<String> {
    let values = overrides
        .iter()
        .map(|(k, v)| Ok((k.as_str(), values::toml_value(k, v)?)))
        .collect::<PyResult<Vec<_>>>()?;
    scenario::with_overrides(text, file, &values).py_err(py)
}

/// A time step: seconds (a positive number) or "auto".
fn dt_choice(dt: &Bound<'_, PyAny>) -> PyResult<DtChoice> {
    if let Ok(s) = dt.extract::<String>() {
        return s.parse().map_err(PyValueError::new_err);
    }
    match dt.extract::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(DtChoice::Seconds(x)),
        _ => Err(PyValueError::new_err(format!(
            "dt = {dt}: give \"auto\" or a time step in seconds (a positive number)"
        ))),
    }
}

/// `text` at the time step `dt`, the frames' interval and eq. 11's decay kept in seconds.
#[pyfunction]
fn with_dt(py: Python<'_>, text: &str, file: &str, dt: &Bound<'_, PyAny>) -> PyResult<String> {
    scenario::with_dt(text, file, dt_choice(dt)?).py_err(py)
}

/// The default job's scenario text (what `sticky-lips run` runs with no input), to be saved
/// as `path`; at `dt` where given, else "auto".
#[pyfunction]
#[pyo3(signature = (path, dt = None))]
fn quick_face_text(
    py: Python<'_>,
    path: PathBuf,
    dt: Option<&Bound<'_, PyAny>>,
) -> PyResult<String> {
    let dt = dt.map(dt_choice).transpose()?;
    py.detach(|| app::input::default_job_text(&path, dt))
        .py_err(py)
}

fn precision_of(name: &str) -> PyResult<Precision> {
    match name {
        "f64" => Ok(Precision::F64),
        "f32" => Ok(Precision::F32),
        _ => Err(PyValueError::new_err(format!(
            "precision = {name:?}: give \"f64\" or \"f32\""
        ))),
    }
}

fn backend_of(name: &str) -> PyResult<Backend> {
    match name {
        "cpu" => Ok(Backend::Cpu),
        "gpu" => Ok(Backend::Gpu),
        "auto" => Ok(Backend::Auto),
        _ => Err(PyValueError::new_err(format!(
            "backend = {name:?}: give \"cpu\", \"gpu\" or \"auto\""
        ))),
    }
}

#[pymethods]
impl Problem {
    /// The input's name, as errors and the run's summary give it.
    #[getter]
    fn source(&self) -> &str {
        &self.problem.source
    }

    /// The scenario's `[output] dir` (relative to the scenario's directory), if any.
    #[getter]
    fn default_output(&self) -> Option<PathBuf> {
        self.default_output.clone()
    }

    /// Mesh statistics, the time settings and the stability limits, as a dict.
    fn check<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let p = &self.problem;
        let (st, r, saliva) = py.detach(|| {
            let d = Discretisation::new(p);
            let r = stability::analyse(p, &d);
            (p.mesh.stats(), r, d.saliva.elements.len())
        });
        let d = PyDict::new(py);
        d.set_item("source", &p.source)?;
        d.set_item("nodes", st.nodes)?;
        d.set_item("elements", st.elements)?;
        d.set_item("saliva_elements", saliva)?;
        d.set_item("materials", p.materials.len())?;
        d.set_item("bounding_box_min", st.bounding_box_min.to_vec())?;
        d.set_item("bounding_box_max", st.bounding_box_max.to_vec())?;
        d.set_item("total_volume", st.total_volume)?;
        d.set_item("min_element_volume", st.min_element_volume)?;
        d.set_item("max_element_volume", st.max_element_volume)?;
        d.set_item("worst_jacobian_ratio", st.worst_jacobian_ratio)?;
        d.set_item("dt", p.time.dt)?;
        d.set_item("steps", p.num_steps())?;
        d.set_item("total_time", p.time.total_time)?;
        d.set_item("output_every", p.time.output_every)?;
        d.set_item("subcycles", p.numerics.subcycles)?;
        d.set_item("critical_time_step", r.critical_time_step)?;
        d.set_item("tissue_critical_time_step", r.tissue_critical_time_step)?;
        d.set_item("element_estimate", r.element_estimate)?;
        d.set_item("limiting_element", r.limiting_element)?;
        d.set_item("lanczos_iterations", r.iterations)?;
        Ok(d)
    }

    /// Runs the problem into `out` (see `Scenario.run`). Returns nothing: the run is its
    /// directory. A Python exception raised while it runs (by `progress`, or Ctrl-C's
    /// `KeyboardInterrupt`) stops it between two steps and is raised once the frames and
    /// the summary marked interrupted are written (a `KeyboardInterrupt` as
    /// `RunInterrupted`, naming `out`).
    #[pyo3(signature = (out, precision = "f64", backend = "cpu", threads = None, force_dt = false, progress = None))]
    // one argument per keyword of the Python signature
    #[allow(clippy::too_many_arguments)]
    fn run(
        &self,
        py: Python<'_>,
        out: PathBuf,
        precision: &str,
        backend: &str,
        threads: Option<usize>,
        force_dt: bool,
        progress: Option<Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        let threads = match threads {
            Some(0) => return Err(PyValueError::new_err("threads = 0: give at least 1")),
            Some(n) => n,
            None => std::thread::available_parallelism().map_or(1, |n| n.get()),
        };
        let cancel = CancelToken::new();
        let mut opts = RunOptions::new(&out, precision_of(precision)?, threads);
        opts.backend = backend_of(backend)?;
        opts.force_dt = force_dt;
        opts.cancel = cancel.clone();
        let p = &self.problem;
        let outcome = drive::drive(py, &cancel, progress.as_ref(), move |on_progress| {
            opts.progress = Some(on_progress);
            driver::run(p, &opts)
        });
        finish(py, &out, outcome.result.map(|_| ()), outcome.raised)
    }
}

/// A job's result and the Python exception that cancelled it, as one result: the exception
/// wins (a `KeyboardInterrupt` that stopped a run becomes `RunInterrupted` naming `out`).
fn finish(
    py: Python<'_>,
    out: &Path,
    result: sticky_lips::Result<()>,
    raised: Option<PyErr>,
) -> PyResult<()> {
    match (raised, result) {
        (None, r) => r.py_err(py),
        (Some(e), Err(sticky_lips::Error::Interrupted { step, time }))
            if e.is_instance_of::<PyKeyboardInterrupt>(py) =>
        {
            let stopped = errors::interrupted(py, out, step, time);
            stopped.set_cause(py, Some(e));
            Err(stopped)
        }
        (Some(e), _) => Err(e),
    }
}

/// Builds the model of a head (`sticky-lips face`): writes `out/scenario.toml` and the
/// model's files; returns the detected unit, the notes and the wall time.
#[pyfunction]
#[pyo3(signature = (input, out, rig = None, units = "auto", up = "auto", forward = "auto", params = None, resolution = 1.0))]
// one argument per keyword of the Python signature (`sticky-lips face`'s options)
#[allow(clippy::too_many_arguments)]
fn face<'py>(
    py: Python<'py>,
    input: PathBuf,
    out: PathBuf,
    rig: Option<PathBuf>,
    units: &str,
    up: &str,
    forward: &str,
    params: Option<PathBuf>,
    resolution: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let job = app::face::FaceJob {
        input: &input,
        rig: rig.as_deref(),
        units,
        up,
        forward,
        params: params.as_deref(),
        resolution,
        out: &out,
    };
    let cancel = CancelToken::new();
    let token = cancel.clone();
    let outcome = drive::drive(py, &cancel, None, move |_| app::face::face(&job, &token));
    let report = match (outcome.raised, outcome.result) {
        (None, r) => r.py_err(py)?,
        (Some(e), _) => return Err(e),
    };
    let d = PyDict::new(py);
    d.set_item("detected_unit", report.detected_unit)?;
    d.set_item("notes", report.notes)?;
    d.set_item("seconds", report.seconds)?;
    Ok(d)
}

/// `summary.json` of the run in `dir`, as JSON text (read through the library's typed
/// reader: a malformed file is an `InputError` naming it and the line).
#[pyfunction]
fn read_summary(py: Python<'_>, dir: PathBuf) -> PyResult<String> {
    let s = sticky_lips::run_dir::RunDir::new(dir)
        .summary()
        .py_err(py)?;
    serde_json::to_string(&s).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// `measures.json` of the run in `dir` as JSON text, `None` where the run has none (a model
/// without lips).
#[pyfunction]
fn read_measures(py: Python<'_>, dir: PathBuf) -> PyResult<Option<String>> {
    let rd = sticky_lips::run_dir::RunDir::new(dir);
    if !rd.has_measures() {
        return Ok(None);
    }
    let m = rd.measures().py_err(py)?;
    serde_json::to_string(&m)
        .map(Some)
        .map_err(|e| PyValueError::new_err(e.to_string()))
}

#[pymodule]
mod _native {
    #[pymodule_export]
    use super::{
        face, load, parse, quick_face_text, read_measures, read_summary, read_text, with_dt,
        with_overrides, Problem,
    };

    #[pymodule_export]
    use super::frames::read_frames;

    /// The package's version (the crate's).
    #[pymodule_export]
    const VERSION: &str = env!("CARGO_PKG_VERSION");
}
