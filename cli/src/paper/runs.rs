//! The runs behind the figures: Table 1 once (`paper/scenarios/table1.toml`, compiled in),
//! each run a short list of overrides on it, and the run itself through the library's
//! driver. A run's outputs go to `OUT/runs/NAME/` (frames, `measures.json`,
//! `summary.json`, and `scenario.toml`: the scenario it used, for `sticky-lips run`).

use super::PaperOptions;
use std::path::PathBuf;
use std::time::Instant;
use sticky_lips::driver::{self, RunOptions, RunSummary};
use sticky_lips::error::{Error, Result};
use sticky_lips::measures::{RunMeasures, ZipFront, ZIP_THRESHOLD};
pub use sticky_lips::paper::{all, sweep_grid, sweep_name, Choice, Model, Spec};
use sticky_lips::run_dir::RunDir;
use sticky_lips::Problem;

/// The face model the face runs are made of (the shipped MakeHuman face at the runs'
/// resolution), for what a run does not carry: blend-shape targets.
pub fn face_model(opts: &PaperOptions) -> Result<sticky_lips::mesh::face::FaceModel> {
    let src = sticky_lips::mesh::face::makehuman()?;
    let params = sticky_lips::mesh::face::FaceParams {
        resolution: if opts.quick { 0.25 } else { 1.0 },
        ..Default::default()
    };
    sticky_lips::mesh::face::build(&src, &params, "assets/makehuman")
}

/// A finished run: its problem, outputs and measures.
pub struct Run {
    pub name: String,
    pub what: String,
    pub problem: Problem,
    pub dir: PathBuf,
    pub measures: RunMeasures,
    pub summary: RunSummary,
    pub zip: ZipFront,
    /// Wall time of the run (s), or of the reused run.
    pub wall: f64,
}

/// Runs `s` (or reuses its complete outputs with `--reuse`).
pub fn run(opts: &PaperOptions, s: &Spec) -> Result<Run> {
    let label = opts.out.join("runs").join(&s.name).join("scenario.toml");
    let (text, problem) = sticky_lips::paper::scenario_of(opts.model, opts.quick, s, &label)?;
    // another step where asked (`--dt`): the frames' interval and the decay in physical time
    let (text, problem) = match opts.dt {
        None => (text, problem),
        Some(dt) => {
            let name = label.display().to_string();
            let t = sticky_lips::io::scenario::with_dt(&text, &name, dt)?;
            let p = sticky_lips::io::scenario::parse(&t, &label)?.problem;
            (t, p)
        }
    };
    let dir = opts.out.join("runs").join(&s.name);
    eprintln!(
        "paper: {} ({}; {} hexahedra, {} steps)",
        s.name,
        s.what,
        problem.mesh.elements.len(),
        problem.num_steps()
    );
    let t0 = Instant::now();
    let run_dir = RunDir::new(&dir);
    let previous: Option<RunSummary> = run_dir.summary().ok();
    let same_scenario = std::fs::read_to_string(dir.join("scenario.toml")).is_ok_and(|t| t == text);
    let complete = same_scenario
        && previous.as_ref().is_some_and(|v| {
            v.steps == problem.num_steps()
                && v.num_elements == problem.mesh.elements.len()
                && run_dir.has_measures()
        });
    let reused = opts.reuse && complete;
    let summary = if reused {
        eprintln!(
            "paper: {}: reusing the complete run in {}",
            s.name,
            dir.display()
        );
        previous.expect("complete")
    } else {
        std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
        let path = dir.join("scenario.toml");
        sticky_lips::io::atomic::write_atomic(&path, text.as_bytes())
            .map_err(|e| Error::io(&path, e))?;
        driver::run(
            &problem,
            &RunOptions {
                out: dir.clone(),
                precision: opts.precision,
                backend: opts.backend,
                threads: opts.threads,
                force_dt: false,
                cancel: crate::progress::cancel_token(),
                progress: opts.progress.callback(),
                checkpoint_every: None,
                restart: false,
                // the figures read the frames; caches of each run are `sticky-lips export`'s
                export: false,
            },
        )?
    };
    let wall = if reused {
        summary.wall_time
    } else {
        t0.elapsed().as_secs_f64()
    };
    let measures: RunMeasures = run_dir.measures()?;
    let zip = ZipFront::new(&measures, ZIP_THRESHOLD);
    Ok(Run {
        name: s.name.clone(),
        what: s.what.clone(),
        problem,
        dir,
        measures,
        summary,
        zip,
        wall,
    })
}

impl Run {
    pub fn times(&self) -> Vec<f64> {
        self.measures.frames.iter().map(|f| f.time).collect()
    }

    /// Index of the output frame closest to time `t`.
    pub fn frame_at(&self, t: f64) -> usize {
        let ts = self.times();
        (0..ts.len())
            .min_by(|&a, &b| (ts[a] - t).abs().total_cmp(&(ts[b] - t).abs()))
            .unwrap_or(0)
    }

    pub fn last(&self) -> usize {
        self.measures.frames.len().saturating_sub(1)
    }

    /// Node displacements at output frame `frame` (m).
    pub fn displacement(&self, frame: usize) -> Result<Vec<[f64; 3]>> {
        RunDir::new(&self.dir).displacement(frame)
    }

    /// A saliva cell field at output frame `frame` (one value per element).
    pub fn cell_field(&self, frame: usize, name: &str) -> Result<Vec<f64>> {
        RunDir::new(&self.dir).cell_field(frame, name)
    }

    /// Which elements are broken saliva elements at output frame `frame`.
    pub fn broken(&self, frame: usize) -> Result<Vec<bool>> {
        if self.problem.physics.saliva.is_empty() {
            return Ok(Vec::new());
        }
        Ok(self
            .cell_field(frame, "saliva_broken")?
            .iter()
            .map(|b| *b > 0.5)
            .collect())
    }

    /// `(time, value)` of a per-frame measure.
    pub fn series(
        &self,
        f: &dyn Fn(&sticky_lips::measures::FrameMeasures) -> f64,
    ) -> Vec<(f64, f64)> {
        self.measures
            .frames
            .iter()
            .map(|m| (m.time, f(m)))
            .collect()
    }

    /// The jaw angle of the run (rad); for a keyed jaw (run `plosive`) its largest key.
    pub fn angle(&self) -> f64 {
        self.problem
            .bc
            .rotations
            .first()
            .map(|r| match &r.curve.shape {
                sticky_lips::boundary::LoadShape::Keyed(k) => {
                    r.angle * k.keys().iter().fold(0.0f64, |a, k| a.max(k.1))
                }
                _ => r.angle,
            })
            .unwrap_or(0.0)
    }

    pub fn k_glue(&self) -> f64 {
        self.problem
            .physics
            .saliva
            .first()
            .map(|s| s.params.k_glue)
            .unwrap_or(0.0)
    }
}
