//! Runs a problem to an output directory: stability check, time stepping, frames,
//! progress, summary. Used by the CLI (`sticky-lips run`, `equilibrium`) and by tests.

use crate::control::{CancelToken, OnProgress, ProgressUpdate};
use crate::error::Result;
use crate::io::checkpoint::{self, RunHistory, SolverState};
pub use crate::io::output::EnergySeries;
use crate::io::output::{Frame, FrameWriter, SalivaFrame};
use crate::problem::Problem;
use crate::real::{Precision, Real};
pub use crate::run_dir::{Interruption, RunSummary};
#[cfg(feature = "equilibrium")]
use crate::static_solve::{solve_equilibrium, StaticOptions};
use crate::tled::solver::{volume_ratios, Energies};
use crate::tled::stability::{analyse, check_time_step};
use crate::tled::Simulation;
use std::path::PathBuf;
use std::time::Instant;

/// Where the explicit steps run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Backend {
    /// `tled::Simulation` (rayon).
    #[default]
    Cpu,
    /// `gpu::GpuSimulation` (wgpu); an error if there is no adapter or the crate was built
    /// without the `gpu` feature.
    Gpu,
    /// The GPU when an adapter exists (and has `SHADER_F64` for an f64 run), else the CPU.
    Auto,
}

impl Backend {
    /// The backend a run with `precision` will use: `Auto` resolved by looking for an adapter.
    pub fn resolve(self, precision: Precision) -> Backend {
        match self {
            Backend::Auto => {
                #[cfg(feature = "gpu")]
                {
                    if let Ok(ctx) = crate::gpu::GpuContext::new() {
                        if precision == Precision::F32 || ctx.has_f64 {
                            return Backend::Gpu;
                        }
                    }
                }
                let _ = precision;
                Backend::Cpu
            }
            b => b,
        }
    }
}

#[derive(Clone, Debug)]
pub struct RunOptions {
    pub out: PathBuf,
    pub precision: Precision,
    pub backend: Backend,
    /// Worker threads (the result is bit-identical for any count).
    pub threads: usize,
    /// Run even if the time step exceeds the critical one.
    pub force_dt: bool,
    /// Stops the run between two steps (the command line cancels it on SIGINT/SIGTERM).
    pub cancel: CancelToken,
    /// Called as the run goes ([`ProgressUpdate`]); `None`: nothing reported.
    pub progress: Option<OnProgress>,
    /// Write `checkpoint.bin` every this many steps (CPU backend; see `io::checkpoint`).
    pub checkpoint_every: Option<usize>,
    /// Continue the run whose output is in `out` from its `checkpoint.bin`.
    pub restart: bool,
    /// Write the point caches and USD of the problem's skin, where it has one
    /// ([`crate::export`]), after the frames.
    pub export: bool,
}

impl RunOptions {
    /// A quiet CPU run into `out` with `threads` threads, no checkpoints.
    pub fn new(out: impl Into<PathBuf>, precision: Precision, threads: usize) -> Self {
        RunOptions {
            out: out.into(),
            precision,
            backend: Backend::Cpu,
            threads,
            force_dt: false,
            cancel: CancelToken::new(),
            progress: None,
            checkpoint_every: None,
            restart: false,
            export: true,
        }
    }
}

/// Steps between two looks at the run's [`CancelToken`] (the stepping is cut into pieces of
/// at most this many steps; results do not depend on it).
pub const INTERRUPT_CHECK_STEPS: usize = 512;

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.max(1))
        .build()
        .expect("thread pool")
}

/// What the driver needs from a time stepper: the CPU [`Simulation`] and the GPU
/// `GpuSimulation` both provide it, so output, measures and progress are shared.
pub trait Stepper {
    fn disc(&self) -> &crate::tled::precompute::Discretisation;
    fn step_index(&self) -> usize;
    fn num_steps(&self) -> usize;
    fn time(&self) -> f64;
    fn num_elements(&self) -> usize;
    fn precision_name(&self) -> &'static str;
    /// `cpu` or `gpu: <adapter>`.
    fn backend_name(&self) -> String;
    /// Advances `n` steps (fewer at the end of the run).
    fn advance(&mut self, n: usize) -> Result<()>;
    fn displacement_f64(&mut self) -> Result<Vec<[f64; 3]>>;
    fn energies(&mut self) -> Result<Energies>;
    /// The saliva state of the last step (`None` without saliva elements).
    fn saliva_frame(&mut self) -> Result<Option<SalivaFrame>>;
    /// The state a checkpoint holds; `None` where the backend does not write checkpoints.
    fn checkpoint_state(&self) -> Option<SolverState> {
        None
    }
    /// Continues from a checkpoint's state.
    fn restore(&mut self, _state: &SolverState) -> Result<()> {
        Err(no_checkpoints())
    }
    fn is_finished(&self) -> bool {
        self.step_index() >= self.num_steps()
    }
}

fn no_checkpoints() -> crate::error::Error {
    crate::error::Error::input(
        "--checkpoint-every / --restart",
        crate::error::Location::None,
        "checkpoints are written and read by the CPU backend only (give --backend cpu)",
    )
}

fn saliva_frame_of<T: Real>(s: &crate::tled::saliva_forces::SalivaState<T>) -> SalivaFrame {
    SalivaFrame {
        moisture: s.moisture.clone(),
        z: s.z.clone(),
        q: s.q.clone(),
        broken: s.broken.clone(),
        broken_at: s.broken_at.clone(),
    }
}

impl<T: crate::tled::simd::SimdReal> Stepper for Simulation<T> {
    fn disc(&self) -> &crate::tled::precompute::Discretisation {
        &self.disc
    }
    fn step_index(&self) -> usize {
        Simulation::step_index(self)
    }
    fn num_steps(&self) -> usize {
        Simulation::num_steps(self)
    }
    fn time(&self) -> f64 {
        Simulation::time(self)
    }
    fn num_elements(&self) -> usize {
        Simulation::num_elements(self)
    }
    fn precision_name(&self) -> &'static str {
        T::NAME
    }
    fn backend_name(&self) -> String {
        "cpu".into()
    }
    fn advance(&mut self, n: usize) -> Result<()> {
        for _ in 0..n.min(Simulation::num_steps(self) - Simulation::step_index(self)) {
            self.step()?;
        }
        Ok(())
    }
    fn displacement_f64(&mut self) -> Result<Vec<[f64; 3]>> {
        Ok(Simulation::displacement_f64(self))
    }
    fn energies(&mut self) -> Result<Energies> {
        Ok(Simulation::energies(self))
    }
    fn saliva_frame(&mut self) -> Result<Option<SalivaFrame>> {
        Ok((!self.disc.saliva.elements.is_empty()).then(|| saliva_frame_of(self.saliva())))
    }
    fn checkpoint_state(&self) -> Option<SolverState> {
        Some(Simulation::checkpoint_state(self))
    }
    fn restore(&mut self, state: &SolverState) -> Result<()> {
        Simulation::restore(self, state)
    }
}

#[cfg(feature = "gpu")]
impl<T: crate::gpu::GpuReal> Stepper for crate::gpu::GpuSimulation<T> {
    fn disc(&self) -> &crate::tled::precompute::Discretisation {
        &self.disc
    }
    fn step_index(&self) -> usize {
        crate::gpu::GpuSimulation::step_index(self)
    }
    fn num_steps(&self) -> usize {
        crate::gpu::GpuSimulation::num_steps(self)
    }
    fn time(&self) -> f64 {
        crate::gpu::GpuSimulation::time(self)
    }
    fn num_elements(&self) -> usize {
        crate::gpu::GpuSimulation::num_elements(self)
    }
    fn precision_name(&self) -> &'static str {
        T::NAME
    }
    fn backend_name(&self) -> String {
        format!(
            "gpu: {}, kernels {:?}",
            self.context().describe(),
            self.shader_real()
        )
    }
    fn advance(&mut self, n: usize) -> Result<()> {
        self.step_many(n)
    }
    fn displacement_f64(&mut self) -> Result<Vec<[f64; 3]>> {
        crate::gpu::GpuSimulation::displacement_f64(self)
    }
    fn energies(&mut self) -> Result<Energies> {
        crate::gpu::GpuSimulation::energies(self)
    }
    fn saliva_frame(&mut self) -> Result<Option<SalivaFrame>> {
        if self.disc.saliva.elements.is_empty() {
            return Ok(None);
        }
        Ok(Some(saliva_frame_of(self.saliva()?)))
    }
}

/// Explicit dynamic run, on the backend of `opts` (see [`Backend`]).
pub fn run(problem: &Problem, opts: &RunOptions) -> Result<RunSummary> {
    pool(opts.threads).install(|| {
        let t0 = Instant::now();
        match (opts.backend.resolve(opts.precision), opts.precision) {
            (Backend::Gpu, _precision) => {
                #[cfg(feature = "gpu")]
                {
                    match _precision {
                        Precision::F64 => run_with(
                            crate::gpu::GpuSimulation::<f64>::new(problem)?,
                            problem,
                            opts,
                            t0,
                        ),
                        Precision::F32 => run_with(
                            crate::gpu::GpuSimulation::<f32>::new(problem)?,
                            problem,
                            opts,
                            t0,
                        ),
                    }
                }
                #[cfg(not(feature = "gpu"))]
                Err(crate::error::Error::Gpu(
                    "this build has no GPU backend (cargo feature `gpu`)".into(),
                ))
            }
            (_, Precision::F64) => run_with(Simulation::<f64>::new(problem)?, problem, opts, t0),
            (_, Precision::F32) => run_with(Simulation::<f32>::new(problem)?, problem, opts, t0),
        }
    })
}

fn run_with<S: Stepper>(
    mut sim: S,
    problem: &Problem,
    opts: &RunOptions,
    t0: Instant,
) -> Result<RunSummary> {
    let report = analyse(problem, sim.disc());
    check_time_step(problem, &report, opts.force_dt)?;
    let checkpoint_every = opts.checkpoint_every.filter(|&n| n > 0);
    if (checkpoint_every.is_some() || opts.restart) && sim.checkpoint_state().is_none() {
        return Err(no_checkpoints());
    }
    let saliva_elements = sim.disc().saliva.elements.clone();
    let (mut writer, mut history, restarted_from) = if opts.restart {
        let path = opts.out.join(checkpoint::FILE_NAME);
        let (header, state) = checkpoint::read(&path)?;
        checkpoint::check_matches(&path, &header, problem, sim.precision_name())?;
        checkpoint::check_frames(&path, &header, &opts.out)?;
        sim.restore(&state)?;
        let writer = FrameWriter::resume(
            &opts.out,
            &problem.mesh.nodes,
            &problem.mesh.elements,
            &problem.element_material,
            &saliva_elements,
            header.history.pvd_entries(),
        )?;
        (writer, header.history, Some(header.step))
    } else {
        let writer = FrameWriter::new(
            &opts.out,
            &problem.mesh.nodes,
            &problem.mesh.elements,
            &problem.element_material,
            &saliva_elements,
        )?;
        let history = RunHistory {
            measures: problem
                .physics
                .lip_columns
                .clone()
                .map(|c| crate::measures::RunMeasures::new(c, crate::measures::OPEN_THRESHOLD)),
            ..Default::default()
        };
        (writer, history, None)
    };
    // the animation files gathered while the frames are recorded (a restarted run's earlier
    // frames are only on disk: its export reads them back)
    let mut recorder = match (&problem.physics.skin, opts.export, restarted_from) {
        (Some(_), true, None) => Some(crate::export::Recorder::new(
            problem.mesh.elements.len(),
            &saliva_elements,
        )),
        _ => None,
    };
    let problem_hash = checkpoint_every.map(|_| checkpoint::problem_hash(problem));
    // absolute, so that `run --restart DIR` finds the input from any directory
    let input = std::fs::canonicalize(&problem.source)
        .map_or_else(|_| problem.source.clone(), |p| p.display().to_string());
    if restarted_from.is_none() {
        record(
            &mut sim,
            &mut writer,
            &mut history,
            recorder.as_mut(),
            problem,
        )?;
    }
    let n = sim.num_steps();
    let start_step = sim.step_index();
    let every = problem.time.output_every;
    let mut stepping = 0.0;
    let mut interrupted = None;
    let write_checkpoint =
        |sim: &S, writer: &mut FrameWriter, history: &mut RunHistory, stepping: f64| {
            let Some(hash) = &problem_hash else {
                return Ok(());
            };
            save_checkpoint(sim, writer, history, stepping, hash, &input)
        };
    let report_progress = |sim: &S, frames: usize, stepping: f64| {
        if let Some(p) = &opts.progress {
            let done = sim.step_index() - start_step;
            p.call(&ProgressUpdate {
                step: sim.step_index(),
                steps: n,
                time: sim.time(),
                end_time: problem.time.total_time,
                frames,
                elapsed: stepping,
                seconds_left: (done > 0)
                    .then(|| stepping / done as f64 * (n - sim.step_index()) as f64),
            });
        }
    };
    report_progress(&sim, writer.frames_written(), 0.0);
    while !sim.is_finished() {
        if opts.cancel.is_cancelled() {
            interrupted = Some(Interruption {
                step: sim.step_index(),
                time: sim.time(),
            });
            write_checkpoint(&sim, &mut writer, &mut history, stepping)?;
            break;
        }
        let ts = Instant::now();
        let to_frame = every - sim.step_index() % every;
        let to_checkpoint = checkpoint_every.map_or(usize::MAX, |c| c - sim.step_index() % c);
        let chunk = to_frame
            .min(to_checkpoint)
            .min(n - sim.step_index())
            .min(INTERRUPT_CHECK_STEPS);
        sim.advance(chunk)?;
        stepping += ts.elapsed().as_secs_f64();
        if chunk == to_frame || sim.is_finished() {
            record(
                &mut sim,
                &mut writer,
                &mut history,
                recorder.as_mut(),
                problem,
            )?;
        }
        if chunk == to_checkpoint && !sim.is_finished() {
            write_checkpoint(&sim, &mut writer, &mut history, stepping)?;
        }
        report_progress(&sim, writer.frames_written(), stepping);
    }
    let mut summary = dynamic_summary(
        &sim,
        problem,
        report,
        &history,
        writer.frames_written(),
        t0,
        stepping,
        restarted_from,
    );
    summary.interrupted = interrupted.clone();
    if let Some(m) = &history.measures {
        crate::run_dir::write_measures(&opts.out, m)?;
    }
    // an interrupted run stops here: its token is cancelled, so the export would refuse at
    // once and take the summary with it (`sticky-lips export` writes the files from its frames)
    if let (Some(skin), true, None) = (&problem.physics.skin, opts.export, &interrupted) {
        // every frame handed over first; the files from the frames gathered while running,
        // else from the frames on disk
        writer.flush()?;
        if writer.frames_written() > 0 {
            summary.export = Some(match recorder {
                Some(r) if r.len() == writer.frames_written() => r.finish(skin, &opts.out)?,
                _ => crate::export::export_with(skin, &opts.out, &opts.cancel)?,
            });
        }
    }
    if let Some(i) = interrupted {
        writer.finish_interrupted(&summary)?;
        return Err(crate::error::Error::Interrupted {
            step: i.step,
            time: i.time,
        });
    }
    writer.finish(&summary)?;
    if checkpoint_every.is_some() || opts.restart {
        // the run is complete: its checkpoint serves nothing any more
        let p = opts.out.join(checkpoint::FILE_NAME);
        std::fs::remove_file(&p).map_err(|e| crate::error::Error::io(&p, e))?;
    }
    Ok(summary)
}

/// Writes the checkpoint of `sim` at its step into the run's directory (through `writer`):
/// the frames written so far recorded in `history`, `stepping` (this process's stepping
/// time) added to the history's, `hash` the problem's and `input` the run's input.
fn save_checkpoint<S: Stepper>(
    sim: &S,
    writer: &mut FrameWriter,
    history: &mut RunHistory,
    stepping: f64,
    hash: &str,
    input: &str,
) -> Result<()> {
    let state = sim.checkpoint_state().expect("checked at the start");
    history.frames = writer
        .entries()
        .iter()
        .map(|e| (e.time, e.file.clone()))
        .collect();
    let mut header = checkpoint::Header {
        format: checkpoint::FORMAT,
        precision: sim.precision_name().into(),
        problem_hash: hash.to_string(),
        input: input.to_string(),
        step: state.step,
        num_nodes: state.u.len(),
        num_saliva: state.broken.len(),
        history: history.clone(),
    };
    // the stepping before the checkpoint, this process's included
    header.history.stepping_time += stepping;
    writer.checkpoint(checkpoint::encode(&header, &state))
}

/// The summary of a dynamic run of `sim` that has written `frames` frames, not interrupted:
/// `history` the run's (a restarted run's from its start), `stepping` this process's stepping
/// time, `t0` when the run began, `restarted_from` the step it restarted from.
#[allow(clippy::too_many_arguments)]
fn dynamic_summary<S: Stepper>(
    sim: &S,
    problem: &Problem,
    report: crate::tled::stability::StabilityReport,
    history: &RunHistory,
    frames: usize,
    t0: Instant,
    stepping: f64,
    restarted_from: Option<usize>,
) -> RunSummary {
    let stepping = history.stepping_time + stepping;
    let steps_here = sim.step_index() - restarted_from.unwrap_or(0);
    RunSummary {
        input: problem.source.clone(),
        kind: "dynamic".into(),
        steps: sim.step_index(),
        simulated_time: sim.time(),
        dt: problem.time.dt,
        subcycles: problem.numerics.subcycles,
        wall_time: t0.elapsed().as_secs_f64(),
        stepping_time: stepping,
        element_updates_per_second: (steps_here * sim.num_elements()) as f64
            / (stepping - history.stepping_time).max(1e-12),
        precision: sim.precision_name().into(),
        backend: sim.backend_name(),
        threads: rayon::current_num_threads(),
        num_nodes: problem.mesh.nodes.len(),
        num_elements: problem.mesh.elements.len(),
        variant: format!("{:?}", problem.numerics.variant),
        niftysim_timing: problem.numerics.niftysim_timing,
        critical_time_step: report.critical_time_step,
        stability: Some(report),
        frames,
        saliva_elements: sim.disc().saliva.elements.len(),
        broken_saliva: history.broken_saliva.clone(),
        energy: history.energy.clone(),
        newton_iterations: None,
        residual_norm: None,
        interrupted: None,
        restarted_from,
        shapes: Vec::new(),
        export: None,
    }
}

/// Records the state as a frame: energies, broken saliva count, lip measures, the VTU file.
fn record<S: Stepper>(
    sim: &mut S,
    writer: &mut FrameWriter,
    history: &mut RunHistory,
    recorder: Option<&mut crate::export::Recorder>,
    problem: &Problem,
) -> Result<()> {
    let u = sim.displacement_f64()?;
    let saliva = sim.saliva_frame()?;
    let broken_count = saliva
        .as_ref()
        .map_or(0, |s| s.broken.iter().filter(|b| **b).count());
    if let Some(m) = history.measures.as_mut() {
        m.push(sim.time(), &problem.mesh.nodes, &u, broken_count);
    }
    let e = sim.energies()?;
    history.energy.time.push(sim.time());
    history.energy.kinetic.push(e.kinetic);
    history.energy.strain.push(e.strain);
    if saliva.is_some() {
        history.broken_saliva.push(broken_count);
    }
    let volume_ratio = volume_ratios(sim.disc(), &u);
    // a state with an inverted element is not written as a frame: the run stops here
    if let Some(e) = volume_ratio
        .iter()
        .position(|j| !(*j > 0.0 && j.is_finite()))
    {
        return Err(crate::error::Error::Diverged {
            step: sim.step_index(),
            time: sim.time(),
            element: Some(e),
            node: None,
            reason: format!(
                "element inverted or degenerate (det F = {}) in the state to be written as a frame; not written",
                volume_ratio[e]
            ),
        });
    }
    history.last_frame_hash = Some(checkpoint::displacement_hash(u.as_flattened()));
    if let (Some(r), Some(skin)) = (recorder, &problem.physics.skin) {
        r.push(skin, sim.time(), &u, saliva.as_ref());
    }
    writer.frame(Frame {
        time: sim.time(),
        u,
        volume_ratio,
        saliva,
    })
}

/// Static equilibrium at the end-of-run loads, written like a run with one frame.
#[cfg(feature = "equilibrium")]
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
            &[],
        )?;
        writer.frame(Frame {
            time: problem.time.total_time,
            u: res.u.clone(),
            volume_ratio: volume_ratios(&disc, &res.u),
            saliva: None,
        })?;
        let strain = crate::tled::solver::strain_energy(&disc, &res.u);
        let report = analyse(problem, &disc);
        let summary = RunSummary {
            steps: res.newton_iterations,
            newton_iterations: Some(res.newton_iterations),
            residual_norm: Some(res.residual_norm),
            ..RunSummary::one_frame(
                problem,
                "static",
                problem.time.total_time,
                report,
                strain,
                t0.elapsed().as_secs_f64(),
            )
        };
        writer.finish(&summary)?;
        Ok(summary)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The MakeHuman face at a quarter of the resolution with Table 1's materials and
    /// stickiness, the jaw opening by 0.15 rad over `jaw_duration` s; `total` s simulated, a
    /// frame every `interval` s, at `dt = "auto"`. `path`: the scenario's name.
    fn coarse_face(
        path: &std::path::Path,
        jaw_duration: f64,
        total: f64,
        interval: f64,
    ) -> Problem {
        let text = format!(
            "[mesh]\ngenerator = \"face\"\n[mesh.face]\nresolution = 0.25\n\
            [[materials]]\nname = \"tissue\"\nelements = \"tissue\"\nmu = 800.0\nK = 7000.0\ndensity = 1050.0\n\
            [[materials]]\nname = \"saliva\"\nelements = \"saliva\"\nmu = 7700.0\nK = 191000.0\ndensity = 1050.0\n\
            [[saliva]]\nmaterial = \"saliva\"\ncritical_moisture = 100.0\ninitial_moisture = 100.0\nk_glue = 0.1\n\
            [[fix]]\nnodes = \"skull\"\n[jaw]\nangle = 0.15\nduration = {jaw_duration:?}\n\
            [time]\ndt = \"auto\"\ntotal = {total:?}\noutput_interval = {interval:?}\n"
        );
        crate::io::scenario::parse(&text, path).unwrap().problem
    }

    /// A face run cancelled after its second frame (as SIGINT does on the command line) ends
    /// with `Interrupted` and leaves what the README promises: `summary.json` saying where it
    /// stopped and its complete frames, from which `export` then writes the animation files
    /// (before, the driver's own export refused on the cancelled token and no summary was
    /// written).
    #[test]
    fn a_cancelled_face_run_keeps_its_summary_and_frames_for_export() {
        let dir =
            std::env::temp_dir().join(format!("sticky-lips-cancel-face-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let p = coarse_face(&dir.join("long.toml"), 0.5, 10.0, 0.004);
        let mut opts = RunOptions::new(dir.join("run"), Precision::F64, 2);
        let cancel = opts.cancel.clone();
        opts.progress = Some(OnProgress::new(move |u: &ProgressUpdate| {
            if u.frames >= 2 {
                cancel.cancel();
            }
        }));
        let e = run(&p, &opts).unwrap_err();
        let crate::error::Error::Interrupted { step, .. } = e else {
            panic!("not interrupted: {e}");
        };
        let out = dir.join("run");
        let summary: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
        assert_eq!(summary["interrupted"]["step"].as_u64(), Some(step as u64));
        let frames = summary["frames"].as_u64().unwrap() as usize;
        assert!(frames >= 2 && step < 2500, "{frames} frames, step {step}");
        assert!(
            !out.join("skin.pc2").exists(),
            "the driver exported after the cancel"
        );
        let e = crate::export::export(p.physics.skin.as_ref().unwrap(), &out).unwrap();
        assert_eq!(e.frames, frames);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// The animation files the driver gathers while running are byte for byte those that
    /// `export` writes afterwards from the run's frame files (the frames hold the same `f64`
    /// displacements and saliva state), on a face with a saliva layer that breaks.
    #[test]
    fn the_files_gathered_while_running_equal_those_read_back_from_the_frames() {
        let dir = std::env::temp_dir().join(format!("sticky-lips-recorder-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let p = coarse_face(&dir.join("open.toml"), 0.2, 0.3, 0.01);
        let out = dir.join("run");
        let s = run(&p, &RunOptions::new(&out, Precision::F64, 2)).unwrap();
        let gathered = s.export.expect("a face run exports");
        assert_eq!(gathered.read_seconds, 0.0, "read back from disk");
        assert!(gathered.saliva_faces > 0);
        let usda = std::fs::read_to_string(out.join("skin.usda")).unwrap();
        let broken = usda.split("primvars:broken.timeSamples").nth(1).unwrap();
        let broken = broken.split('}').next().unwrap();
        assert!(broken.contains("1.0"), "no saliva element broke");
        let names = ["skin.obj", "skin.pc2", "skin.mdd", "skin.usda"];
        let files: Vec<Vec<u8>> = names
            .iter()
            .map(|n| std::fs::read(out.join(n)).unwrap())
            .collect();
        for n in names {
            std::fs::remove_file(out.join(n)).unwrap();
        }
        let e = crate::export::export(p.physics.skin.as_ref().unwrap(), &out).unwrap();
        assert!(e.read_seconds > 0.0);
        assert_eq!(e.frames, gathered.frames);
        for (n, bytes) in names.iter().zip(&files) {
            assert!(
                std::fs::read(out.join(n)).unwrap() == *bytes,
                "{n} differs from the one read back"
            );
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
