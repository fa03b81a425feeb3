//! Runs a problem to an output directory: stability check, time stepping, frames,
//! progress, summary. Used by the CLI (`sticky-lips run`, `equilibrium`) and by tests.

use crate::error::Result;
use crate::io::output::{FrameWriter, SalivaFrame};
use crate::problem::Problem;
use crate::real::{Precision, Real};
use crate::static_solve::{solve_equilibrium, StaticOptions};
use crate::tled::stability::{analyse, check_time_step, StabilityReport};
use crate::tled::Simulation;
use std::path::PathBuf;
use std::time::Instant;

/// How a run reports progress.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Progress {
    /// A progress bar on the terminal (steps per second, ETA).
    Bar,
    /// A plain line every 10 % (for logs and pipes).
    Plain,
    Quiet,
}

#[derive(Clone, Debug)]
pub struct RunOptions {
    pub out: PathBuf,
    pub precision: Precision,
    /// Worker threads (the result is bit-identical for any count).
    pub threads: usize,
    /// Run even if the time step exceeds the critical one.
    pub force_dt: bool,
    pub progress: Progress,
}

#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct EnergySeries {
    pub time: Vec<f64>,
    pub kinetic: Vec<f64>,
    pub strain: Vec<f64>,
}

/// `summary.json`.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RunSummary {
    pub input: String,
    pub kind: &'static str,
    pub steps: usize,
    pub simulated_time: f64,
    pub dt: f64,
    pub wall_time: f64,
    /// Wall time of the stepping loop alone (s), without output and precompute.
    pub stepping_time: f64,
    pub element_updates_per_second: f64,
    pub precision: &'static str,
    pub threads: usize,
    pub num_nodes: usize,
    pub num_elements: usize,
    pub variant: String,
    pub niftysim_timing: bool,
    pub critical_time_step: f64,
    pub stability: Option<StabilityReport>,
    pub frames: usize,
    pub energy: EnergySeries,
    /// Number of saliva elements, and how many are broken at each frame (same times as `energy`).
    pub saliva_elements: usize,
    pub broken_saliva: Vec<usize>,
    pub newton_iterations: Option<usize>,
    pub residual_norm: Option<f64>,
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.max(1))
        .build()
        .expect("thread pool")
}

/// Explicit dynamic run.
pub fn run(problem: &Problem, opts: &RunOptions) -> Result<RunSummary> {
    pool(opts.threads).install(|| match opts.precision {
        Precision::F64 => run_typed::<f64>(problem, opts),
        Precision::F32 => run_typed::<f32>(problem, opts),
    })
}

fn run_typed<T: Real>(problem: &Problem, opts: &RunOptions) -> Result<RunSummary> {
    let t0 = Instant::now();
    let mut sim = Simulation::<T>::new(problem)?;
    let report = analyse(problem, &sim.disc);
    check_time_step(problem, &report, opts.force_dt)?;
    let mut writer = FrameWriter::new(
        &opts.out,
        &problem.mesh.nodes,
        &problem.mesh.elements,
        &problem.element_material,
    )?;
    let mut energy = EnergySeries::default();
    let mut broken = Vec::new();
    let has_saliva = !sim.disc.saliva.elements.is_empty();
    let mut measures = problem
        .physics
        .lip_columns
        .clone()
        .map(|c| crate::measures::RunMeasures::new(c, crate::measures::OPEN_THRESHOLD));
    let mut record = |sim: &Simulation<T>, writer: &mut FrameWriter| -> Result<()> {
        let u = sim.displacement_f64();
        if let Some(m) = measures.as_mut() {
            m.push(
                sim.time(),
                &problem.mesh.nodes,
                &u,
                sim.saliva().broken_count(),
            );
        }
        let e = sim.energies();
        energy.time.push(sim.time());
        energy.kinetic.push(e.kinetic);
        energy.strain.push(e.strain);
        let saliva = has_saliva.then(|| {
            let s = sim.saliva();
            broken.push(s.broken_count());
            SalivaFrame {
                moisture: s.moisture.clone(),
                z: s.z.clone(),
                q: s.q.clone(),
                broken: s.broken.clone(),
                broken_at: s.broken_at.clone(),
            }
        });
        writer.frame(sim.time(), &u, &sim.disc, saliva)
    };
    record(&sim, &mut writer)?;
    let n = sim.num_steps();
    let bar = progress_bar(opts.progress, n as u64);
    let every = problem.time.output_every;
    let mut stepping = 0.0;
    let mut next_plain = n / 10;
    while !sim.is_finished() {
        let ts = Instant::now();
        let chunk = every - sim.step_index() % every;
        for _ in 0..chunk.min(n - sim.step_index()) {
            sim.step()?;
        }
        stepping += ts.elapsed().as_secs_f64();
        record(&sim, &mut writer)?;
        if let Some(b) = &bar {
            b.set_position(sim.step_index() as u64);
        } else if opts.progress == Progress::Plain && sim.step_index() >= next_plain {
            eprintln!("step {}/{} (t = {:.4e} s)", sim.step_index(), n, sim.time());
            next_plain += (n / 10).max(1);
        }
    }
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    let summary = RunSummary {
        input: problem.source.clone(),
        kind: "dynamic",
        steps: sim.step_index(),
        simulated_time: sim.time(),
        dt: problem.time.dt,
        wall_time: t0.elapsed().as_secs_f64(),
        stepping_time: stepping,
        element_updates_per_second: (sim.step_index() * sim.num_elements()) as f64
            / stepping.max(1e-12),
        precision: T::NAME,
        threads: rayon::current_num_threads(),
        num_nodes: problem.mesh.nodes.len(),
        num_elements: problem.mesh.elements.len(),
        variant: format!("{:?}", problem.numerics.variant),
        niftysim_timing: problem.numerics.niftysim_timing,
        critical_time_step: report.critical_time_step,
        stability: Some(report),
        frames: writer.frames_written(),
        saliva_elements: sim.disc.saliva.elements.len(),
        broken_saliva: broken,
        energy,
        newton_iterations: None,
        residual_norm: None,
    };
    if let Some(m) = &measures {
        write_measures(&opts.out, m)?;
    }
    writer.finish(&sim.disc, &summary)?;
    Ok(summary)
}

/// `measures.json`, `gap.csv` (lip gap profiles) and `series.csv` (open fraction, broken
/// saliva elements, asymmetry over time), written atomically.
pub fn write_measures(dir: &std::path::Path, m: &crate::measures::RunMeasures) -> Result<()> {
    use crate::io::atomic::write_atomic;
    let w = |name: &str, bytes: &[u8]| {
        let p = dir.join(name);
        write_atomic(&p, bytes).map_err(|e| crate::error::Error::io(&p, e))
    };
    w(
        "measures.json",
        &serde_json::to_vec_pretty(m).expect("measures serialise"),
    )?;
    w("gap.csv", m.gap_csv().as_bytes())?;
    w("series.csv", m.series_csv().as_bytes())
}

fn progress_bar(p: Progress, n: u64) -> Option<indicatif::ProgressBar> {
    if p != Progress::Bar {
        return None;
    }
    let b = indicatif::ProgressBar::new(n);
    b.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} steps  {per_sec}  ETA {eta}")
            .expect("progress template"),
    );
    Some(b)
}

/// Static equilibrium at the end-of-run loads, written like a run with one frame.
pub fn equilibrium(
    problem: &Problem,
    opts: &RunOptions,
    static_opts: &StaticOptions,
) -> Result<RunSummary> {
    pool(opts.threads).install(|| {
        let t0 = Instant::now();
        let res = solve_equilibrium(problem, static_opts)?;
        let disc = crate::tled::precompute::Discretisation::new(problem);
        let mut writer = FrameWriter::new(
            &opts.out,
            &problem.mesh.nodes,
            &problem.mesh.elements,
            &problem.element_material,
        )?;
        writer.frame(problem.time.total_time, &res.u, &disc, None)?;
        let strain = crate::tled::solver::strain_energy(&disc, &res.u);
        let report = analyse(problem, &disc);
        let summary = RunSummary {
            input: problem.source.clone(),
            kind: "static",
            steps: res.newton_iterations,
            simulated_time: problem.time.total_time,
            dt: problem.time.dt,
            wall_time: t0.elapsed().as_secs_f64(),
            stepping_time: 0.0,
            element_updates_per_second: 0.0,
            precision: "f64",
            threads: rayon::current_num_threads(),
            num_nodes: problem.mesh.nodes.len(),
            num_elements: problem.mesh.elements.len(),
            variant: format!("{:?}", problem.numerics.variant),
            niftysim_timing: problem.numerics.niftysim_timing,
            critical_time_step: report.critical_time_step,
            stability: Some(report),
            frames: 1,
            energy: EnergySeries {
                time: vec![problem.time.total_time],
                kinetic: vec![0.0],
                strain: vec![strain],
            },
            saliva_elements: 0,
            broken_saliva: Vec::new(),
            newton_iterations: Some(res.newton_iterations),
            residual_norm: Some(res.residual_norm),
        };
        writer.finish(&disc, &summary)?;
        Ok(summary)
    })
}
