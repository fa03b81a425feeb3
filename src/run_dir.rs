//! A run's output directory, owned in one place: the names of its files, the summary
//! ([`RunSummary`], `summary.json`), the measures (`measures.json`, `gap.csv`, `series.csv`),
//! and a typed reader ([`RunDir`]) of all of it, frames included, for a finished or an
//! interrupted run. The frames themselves (`frames.pvd`, `frame_NNNNNN.vtu`, `final.vtu`) are
//! written by [`crate::io::output::FrameWriter`], the checkpoint by [`crate::io::checkpoint`].
//!
//! Every reader of a run directory (the CLI's `run --restart`, `export`, `sweep` and
//! `paper --reuse`, the preview, the Python package's `open_run`) goes through [`RunDir`].

use crate::error::{Error, Location, Result};
use crate::io::output::EnergySeries;
use crate::measures::RunMeasures;
use std::path::{Path, PathBuf};

pub use crate::io::output::{frame_file, FINAL, PVD, SUMMARY};

/// `measures.json`: the lip measures per frame ([`RunMeasures`]).
pub const MEASURES: &str = "measures.json";
/// The lip gap profiles per frame (CSV).
pub const GAP_CSV: &str = "gap.csv";
/// The open fraction, broken saliva count and asymmetry per frame (CSV).
pub const SERIES_CSV: &str = "series.csv";

fn one() -> usize {
    1
}
fn is_one(k: &usize) -> bool {
    *k == 1
}

/// `summary.json`: what a run did (read back by `paper --reuse`).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct RunSummary {
    pub input: String,
    pub kind: String,
    pub steps: usize,
    pub simulated_time: f64,
    pub dt: f64,
    /// Substeps of the saliva layer per step (`tled::subcycle`); written when more than 1.
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub subcycles: usize,
    pub wall_time: f64,
    /// Wall time of the stepping loop alone (s), without output and precompute.
    pub stepping_time: f64,
    pub element_updates_per_second: f64,
    pub precision: String,
    /// `cpu`, or `gpu: <adapter>`.
    pub backend: String,
    pub threads: usize,
    pub num_nodes: usize,
    pub num_elements: usize,
    pub variant: String,
    pub niftysim_timing: bool,
    pub critical_time_step: f64,
    pub stability: Option<crate::tled::stability::StabilityReport>,
    pub frames: usize,
    pub energy: EnergySeries,
    /// Number of saliva elements, and how many are broken at each frame (same times as `energy`).
    pub saliva_elements: usize,
    pub broken_saliva: Vec<usize>,
    pub newton_iterations: Option<usize>,
    pub residual_norm: Option<f64>,
    /// Where a run stopped by SIGINT or SIGTERM stopped (absent for a run that finished).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub interrupted: Option<Interruption>,
    /// The checkpoint step a restarted run continued from (absent for a run from the start);
    /// `wall_time` is then the restarted process's, `stepping_time` all the stepping's.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub restarted_from: Option<usize>,
    /// The shapes of a blend (`PATH.vtu=WEIGHT`; `kind` is `blend`), absent for a run.
    #[serde(skip_serializing_if = "Vec::is_empty", default)]
    pub shapes: Vec<String>,
    /// The point caches and USD written after the frames ([`crate::export`]).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub export: Option<crate::export::ExportSummary>,
}

impl RunSummary {
    /// The summary of a one-frame result at rest (a static solution, a blend): no steps, the
    /// frame's strain energy at `time`, CPU and f64, `wall_time` as given.
    pub fn one_frame(
        problem: &crate::Problem,
        kind: &str,
        time: f64,
        report: crate::tled::stability::StabilityReport,
        strain: f64,
        wall_time: f64,
    ) -> RunSummary {
        RunSummary {
            input: problem.source.clone(),
            kind: kind.into(),
            steps: 0,
            simulated_time: time,
            dt: problem.time.dt,
            subcycles: 1,
            wall_time,
            stepping_time: 0.0,
            element_updates_per_second: 0.0,
            precision: "f64".into(),
            backend: "cpu".into(),
            threads: rayon::current_num_threads(),
            num_nodes: problem.mesh.nodes.len(),
            num_elements: problem.mesh.elements.len(),
            variant: format!("{:?}", problem.numerics.variant),
            niftysim_timing: problem.numerics.niftysim_timing,
            critical_time_step: report.critical_time_step,
            stability: Some(report),
            frames: 1,
            energy: EnergySeries {
                time: vec![time],
                kinetic: vec![0.0],
                strain: vec![strain],
            },
            saliva_elements: 0,
            broken_saliva: Vec::new(),
            newton_iterations: None,
            residual_norm: None,
            interrupted: None,
            restarted_from: None,
            shapes: Vec::new(),
            export: None,
        }
    }
}

/// The step and time at which a run was interrupted.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Interruption {
    pub step: usize,
    pub time: f64,
}

/// `measures.json`, `gap.csv` (lip gap profiles) and `series.csv` (open fraction, broken
/// saliva elements, asymmetry over time), written atomically.
pub fn write_measures(dir: &Path, m: &RunMeasures) -> Result<()> {
    use crate::io::atomic::write_atomic;
    let w = |name: &str, bytes: &[u8]| {
        let p = dir.join(name);
        write_atomic(&p, bytes).map_err(|e| Error::io(&p, e))
    };
    w(
        MEASURES,
        &serde_json::to_vec_pretty(m).expect("measures serialise"),
    )?;
    w(GAP_CSV, m.gap_csv().as_bytes())?;
    w(SERIES_CSV, m.series_csv().as_bytes())
}

/// A run directory to read: a finished run, or an interrupted one (its frames are complete).
#[derive(Clone, Debug)]
pub struct RunDir {
    pub dir: PathBuf,
}

impl RunDir {
    pub fn new(dir: impl Into<PathBuf>) -> Self {
        RunDir { dir: dir.into() }
    }

    pub fn path(&self, name: &str) -> PathBuf {
        self.dir.join(name)
    }

    fn json<T: serde::de::DeserializeOwned>(&self, name: &str) -> Result<T> {
        let path = self.path(name);
        let text = std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?;
        serde_json::from_str(&text).map_err(|e| {
            Error::input(
                path.display().to_string(),
                Location::Line(e.line()),
                e.to_string(),
            )
        })
    }

    /// `summary.json`; an error naming the file and line when it is missing or malformed.
    pub fn summary(&self) -> Result<RunSummary> {
        self.json(SUMMARY)
    }

    /// `measures.json` (runs of a model with lips only).
    pub fn measures(&self) -> Result<RunMeasures> {
        self.json(MEASURES)
    }

    /// Whether `measures.json` exists.
    pub fn has_measures(&self) -> bool {
        self.path(MEASURES).exists()
    }

    /// The complete frames: `(time, file name)` from `frames.pvd`, in order.
    pub fn frames(&self) -> Result<Vec<(f64, String)>> {
        crate::export::read_pvd(&self.dir)
    }

    /// The path of output frame `k`.
    pub fn frame_path(&self, k: usize) -> PathBuf {
        self.path(&frame_file(k))
    }

    /// Node displacements at output frame `k` (m).
    pub fn displacement(&self, k: usize) -> Result<Vec<[f64; 3]>> {
        let (v, _, _) = crate::io::vtu::read_point_data_f64(&self.frame_path(k), "displacement")?;
        Ok(v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
    }

    /// A cell array of output frame `k` (one value per element), e.g. `saliva_broken`.
    pub fn cell_field(&self, k: usize, name: &str) -> Result<Vec<f64>> {
        let (v, _, _) = crate::io::vtu::read_cell_data(&self.frame_path(k), name)?;
        Ok(v)
    }

    /// The input the run solved, from its summary's `input`: an error naming the summary and
    /// the field where it is missing or not found from here (`export --scenario` and
    /// `run --restart` then need it given).
    pub fn input(&self) -> Result<PathBuf> {
        let path = self.path(SUMMARY);
        let v: serde_json::Value = self.json(SUMMARY)?;
        let input = v
            .get("input")
            .and_then(|i| i.as_str())
            .map(PathBuf::from)
            .ok_or_else(|| {
                Error::field(
                    path.display().to_string(),
                    "input",
                    "missing: give the scenario with --scenario",
                )
            })?;
        if !input.exists() {
            return Err(Error::field(
                path.display().to_string(),
                "input",
                format!(
                    "names the scenario {}, which is not found from {}{}: give it with --scenario",
                    input.display(),
                    std::env::current_dir()
                        .map(|d| d.display().to_string())
                        .unwrap_or_else(|_| "here".into()),
                    if input.is_relative() {
                        " (a relative path is read from the directory the run was started in)"
                    } else {
                        ""
                    }
                ),
            ));
        }
        Ok(input)
    }

    /// The input of the run whose checkpoint is in this directory (`run --restart`).
    pub fn checkpoint_input(&self) -> Result<PathBuf> {
        let path = self.path(crate::io::checkpoint::FILE_NAME);
        let (header, _) = crate::io::checkpoint::read(&path)?;
        Ok(PathBuf::from(header.input))
    }
}
