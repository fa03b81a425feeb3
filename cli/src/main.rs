//! `sticky-lips`: the command line. One subcommand per variant of `Command` below (run,
//! equilibrium, check, evaporation, mouth, face, extrude, paper, blend, export, sweep);
//! `sticky-lips help
//! COMMAND` prints each one's options, and README.md shows them in use.

mod paper;
mod progress;
mod sweep;

use clap::{Parser, Subcommand, ValueEnum};
use progress::Progress;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use sticky_lips::app;
use sticky_lips::driver::{self, Backend, RunOptions};
use sticky_lips::io::scenario;
use sticky_lips::static_solve::StaticOptions;
use sticky_lips::tled::precompute::Discretisation;
use sticky_lips::tled::stability;
use sticky_lips::{Precision, Problem};

#[derive(Parser)]
#[command(
    name = "sticky-lips",
    version,
    about = "Physically-based sticky lips: a verified TLED finite element solver"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Clone, Copy, ValueEnum)]
enum PrecisionArg {
    F64,
    F32,
}

impl PrecisionArg {
    fn precision(self) -> Precision {
        match self {
            PrecisionArg::F64 => Precision::F64,
            PrecisionArg::F32 => Precision::F32,
        }
    }
}

/// Where the explicit steps run: `cpu`, `gpu` (wgpu; an error without an adapter) or
/// `auto` (the GPU when an adapter exists, else the CPU).
#[derive(Clone, Copy, ValueEnum)]
enum BackendArg {
    Cpu,
    Gpu,
    Auto,
}

impl BackendArg {
    fn backend(self) -> Backend {
        match self {
            BackendArg::Cpu => Backend::Cpu,
            BackendArg::Gpu => Backend::Gpu,
            BackendArg::Auto => Backend::Auto,
        }
    }
}

/// The model `paper` makes the figures on.
#[derive(Clone, Copy, ValueEnum)]
enum ModelArg {
    Face,
    Procedural,
}

#[derive(clap::Args)]
struct InputArgs {
    /// A scenario (.toml) or a NiftySim model (.xml).
    input: PathBuf,
    /// Reproduce NiftySim: centroid gradients and its timing quirks (XML input only).
    #[arg(long)]
    niftysim_compat: bool,
}

#[derive(clap::Args)]
struct RunArgs {
    /// A scenario (.toml) or a NiftySim model (.xml); with --restart, the checkpoint's
    /// input when not given; else the default job: the sticky lips opening on the
    /// MakeHuman face (Table 1 at the quick resolution), written to out/face.
    input: Option<PathBuf>,
    /// Reproduce NiftySim: centroid gradients and its timing quirks (XML input only).
    #[arg(long)]
    niftysim_compat: bool,
    /// Output directory (default: the scenario's [output] dir, else out/<input name>).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Write the run's full state to OUT/checkpoint.bin every N steps (CPU backend),
    /// so that `--restart` can continue it; removed when the run completes.
    #[arg(long, value_name = "N", value_parser = steps_arg)]
    checkpoint_every: Option<usize>,
    /// Continue the run in DIR from its checkpoint: the frames after the checkpoint are
    /// written again, bit-identical to an uninterrupted run's.
    #[arg(long, value_name = "DIR")]
    restart: Option<PathBuf>,
    #[arg(long, value_enum, default_value = "f64")]
    precision: PrecisionArg,
    /// Where the steps run (the GPU runs f32 everywhere, f64 where the adapter has SHADER_F64).
    #[arg(long, value_enum, default_value = "cpu")]
    backend: BackendArg,
    /// Worker threads (default: every core; results are bit-identical for any count).
    #[arg(long, value_parser = threads_arg)]
    threads: Option<usize>,
    /// Run even if the time step exceeds the critical time step.
    #[arg(long)]
    force_dt: bool,
    /// The time step: `auto` (0.8 of the model's critical step, a whole number of steps
    /// per frame) or seconds; the frames' interval and eq. 11's decay stay in physical
    /// time. Default: the scenario's (the default job's is `auto`).
    #[arg(long, value_name = "auto|SECONDS")]
    dt: Option<scenario::DtChoice>,
    /// Substeps of the saliva layer per step (scenarios only; `[time] subcycles`): `auto`
    /// (as many as the saliva's critical step needs; with `--dt auto` the step is then set
    /// by the tissue's) or a count (1: single rate).
    #[arg(long, value_name = "auto|COUNT")]
    subcycles: Option<app::input::Subcycles>,
    /// No progress output (the same as `--progress none`).
    #[arg(long, conflicts_with = "progress")]
    quiet: bool,
    /// What is printed while stepping: a bar (default on a terminal), a plain line every
    /// 10 % (default otherwise), one JSON object per line on stdout (for programs that
    /// drive the CLI), or nothing.
    #[arg(long, value_enum, value_name = "bar|plain|json|none")]
    progress: Option<Progress>,
}

#[derive(Subcommand)]
enum Command {
    /// Explicit dynamic run (TLED, central differences).
    Run(RunArgs),
    /// Static equilibrium (Newton with load stepping) at the end-of-run loads.
    Equilibrium {
        #[command(flatten)]
        input: InputArgs,
        #[arg(long)]
        out: Option<PathBuf>,
        /// Worker threads (default: every core).
        #[arg(long, value_parser = threads_arg)]
        threads: Option<usize>,
        /// Load steps.
        #[arg(long, default_value_t = 10)]
        load_steps: usize,
    },
    /// Validate the input; print mesh statistics and the critical time step.
    Check {
        #[command(flatten)]
        input: InputArgs,
    },
    /// Evaporation rate of the saliva film from physical inputs (paper eq. 5, Herz-Knudsen).
    Evaporation {
        /// Sticking (evaporation) coefficient alpha, dimensionless, 0 to 1.
        #[arg(long, default_value_t = 1.0, value_parser = fraction_arg, allow_negative_numbers = true)]
        sticking: f64,
        /// Liquid (lip surface) temperature in degrees Celsius (above -273.15, at most 1000).
        #[arg(long, default_value_t = 34.0, value_parser = celsius_arg, allow_negative_numbers = true)]
        temperature: f64,
        /// Liquid pressure p_liq (Pa, at least 0); default: water's saturation vapour pressure
        /// at --temperature.
        #[arg(long, value_parser = pressure_arg, allow_negative_numbers = true)]
        p_liq: Option<f64>,
        /// Equilibrium pressure p_eq (Pa, at least 0); default: --humidity x saturation
        /// pressure at --ambient.
        #[arg(long, value_parser = pressure_arg, allow_negative_numbers = true)]
        p_eq: Option<f64>,
        /// Relative humidity of the air, 0 to 1, used when --p-eq is not given.
        #[arg(long, default_value_t = 0.5, value_parser = fraction_arg, allow_negative_numbers = true)]
        humidity: f64,
        /// Air temperature in degrees Celsius (above -273.15, at most 1000), used when --p-eq
        /// is not given.
        #[arg(long, default_value_t = 22.0, value_parser = celsius_arg, allow_negative_numbers = true)]
        ambient: f64,
        /// Molar mass of the evaporating species (kg/mol, above 0); water by default.
        #[arg(long, default_value_t = 0.018015, value_parser = positive_arg, allow_negative_numbers = true)]
        molar_mass: f64,
        /// Density of the liquid film (kg/m^3, above 0).
        #[arg(long, default_value_t = 1000.0, value_parser = positive_arg, allow_negative_numbers = true)]
        density: f64,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Generate the procedural mouth: its quad surface (OBJ with groups and texture
    /// coordinates), the extruded hexahedral mesh (VTU, and NiftySim XML with Table 1's
    /// materials), and a JSON description (hinge, muscles, node sets, counts).
    Mouth {
        /// Mouth parameters (TOML, the `[mesh.mouth]` table's fields); defaults otherwise.
        #[arg(long)]
        params: Option<PathBuf>,
        /// Resolution multiplier (1 = the paper's ~3400 hexahedra); overrides the file.
        #[arg(long)]
        resolution: Option<f64>,
        #[arg(long, default_value = "out/mouth")]
        out: PathBuf,
    },
    /// Bring a face: find the inner lip contours of a head surface, keep the lower front half
    /// of the face around the mouth without the mouth's interior, and write it as the model's
    /// source (face.obj, face.json) and the model at --resolution (model.obj with the saliva
    /// strip, mesh.vtu, model.xml).
    Face {
        /// The head: Wavefront OBJ of quads, triangles or other polygons (a face of n corners
        /// becomes n quads; texture coordinates kept).
        input: PathBuf,
        /// Rig data on the head's vertices (JSON: source, jaw_weight, hinge_point, hinge_axis,
        /// targets, upper_lip, lower_lip), in the head's units and axes.
        #[arg(long)]
        rig: Option<PathBuf>,
        /// Length unit of the head and the rig: m, dm, cm, mm or in; `auto`: the one in which
        /// the head's largest extent is a head's (0.12 to 0.45 m), refused when several are.
        #[arg(long, default_value = "auto")]
        units: String,
        /// The face's up axis in the input, X,Y,Z; `auto` (with --forward auto): detected from
        /// the mouth, among the file's coordinate axes.
        #[arg(long, default_value = "auto")]
        up: String,
        /// The face's forward axis (out of the face) in the input, X,Y,Z; or `auto`.
        #[arg(long, default_value = "auto")]
        forward: String,
        /// Crop parameters (TOML: half_width, below, above, behind, pinch, min_mouth_width; metres).
        #[arg(long)]
        params: Option<PathBuf>,
        /// Resolution of the model written beside the source (1: about the paper's 3414 hexahedra).
        #[arg(long, default_value_t = 1.0)]
        resolution: f64,
        /// Output directory (default `out/model`: not `run`'s `out/face`, so that neither
        /// overwrites the other's scenario).
        #[arg(long, default_value = "out/model")]
        out: PathBuf,
    },
    /// Extrude a quad OBJ surface (with groups) into hexahedra, as the paper's pipeline did.
    Extrude {
        /// The surface: Wavefront OBJ, quads only, consistently oriented.
        surface: PathBuf,
        /// Thickness (m) for every group without its own.
        #[arg(long)]
        thickness: Option<f64>,
        /// Thickness for one group: NAME=METRES. Repeatable.
        #[arg(long = "group")]
        groups: Vec<String>,
        /// Extrude along this fixed direction X,Y,Z (into the body) instead of the normals.
        #[arg(long)]
        direction: Option<String>,
        /// Output directory: mesh.vtu and model.xml (NiftySim format, Table 1 tissue material).
        #[arg(long, default_value = "out/extruded")]
        out: PathBuf,
    },
    /// Reproduce the paper: run Table 1 (paper/scenarios/table1.toml, compiled in) with each
    /// figure's overrides and write every figure (PNG), Table 1 as used, the claims and the
    /// measured numbers (measured.json). Works from any directory.
    Paper {
        /// Where the figures go; each run's outputs go to OUT/runs/NAME/. The committed
        /// figures are remade only when named: `--out paper/figures`.
        #[arg(long, default_value = "out/paper")]
        out: PathBuf,
        /// A coarse, short version (for CI): a quarter of the hexahedra, 0.8 s simulated.
        #[arg(long)]
        quick: bool,
        /// The model: the MakeHuman face, or the procedural mouth (with its own parameters).
        #[arg(long, value_enum, default_value = "face")]
        model: ModelArg,
        /// Make only these figures (e.g. --only fig4 --only sweep) and only their runs.
        #[arg(long)]
        only: Vec<String>,
        /// Worker threads (default: every core).
        #[arg(long, value_parser = threads_arg)]
        threads: Option<usize>,
        /// Where the runs step (see `run --backend`).
        #[arg(long, value_enum, default_value = "cpu")]
        backend: BackendArg,
        #[arg(long, value_enum, default_value = "f64")]
        precision: PrecisionArg,
        /// Reuse complete runs in OUT/runs (same scenario) and only redraw the figures.
        #[arg(long)]
        reuse: bool,
        /// The runs' time step (see `run --dt`); default: Table 1's 1e-5 s.
        #[arg(long, value_name = "auto|SECONDS")]
        dt: Option<scenario::DtChoice>,
    },
    /// Blend shapes (paper eq. 1): x' = X + sum_i w_i B_i, written as an output frame.
    Blend {
        /// The model the shapes belong to (its reference positions X and mesh).
        #[command(flatten)]
        input: InputArgs,
        /// A shape and its weight: PATH.vtu=WEIGHT (PATH's point data `displacement` is B_i),
        /// e.g. out/open/final.vtu=0.3. Repeat for several shapes.
        #[arg(long = "shape", required = true)]
        shapes: Vec<String>,
        #[arg(long)]
        out: PathBuf,
    },
    /// Many shots: expand SPEC.toml (a base scenario, a [grid] of overrides and/or [[shot]]s)
    /// into run directories and a job list (OUT/jobs.txt), and run them here in parallel.
    Sweep {
        spec: PathBuf,
        /// Write the run directories and the job list only (for GNU parallel, Slurm, ...).
        #[arg(long)]
        plan: bool,
        /// The runs' time step (see `run --dt`), before the spec's `dt`; default: the
        /// base's own (the default job's: auto).
        #[arg(long, value_name = "auto|SECONDS")]
        dt: Option<scenario::DtChoice>,
    },
    /// Write a finished or interrupted run's animation files again: skin.obj, skin.pc2,
    /// skin.mdd, skin.usda (the user's mesh moved by the model) and the preview, from the
    /// frames in RUN_DIR (mouth and face models).
    Export {
        /// The run's directory (frames.pvd and its frames).
        run_dir: PathBuf,
        /// The scenario the run solved (default: the `input` of RUN_DIR/summary.json).
        #[arg(long)]
        scenario: Option<PathBuf>,
        /// Write only the skin mapping (JSON: rest positions, weights, the jaw's angle at
        /// each frame) to this file, for checking the animation files against the frames;
        /// the animation files are not written.
        #[arg(long, value_name = "FILE.json")]
        skin_map: Option<PathBuf>,
    },
}

impl InputArgs {
    fn input(&self) -> app::input::Input {
        app::input::Input {
            path: self.input.clone(),
            niftysim_compat: self.niftysim_compat,
        }
    }
}

fn load(args: &InputArgs) -> sticky_lips::Result<(Problem, Option<PathBuf>)> {
    app::input::load(&args.input())
}

fn default_job(out: Option<&Path>, dt: Option<scenario::DtChoice>) -> sticky_lips::Result<PathBuf> {
    let dir = out.map_or_else(|| PathBuf::from("out/face"), Path::to_path_buf);
    let path = dir.join("scenario.toml");
    let text = app::input::default_job_text(&path, dt)?;
    std::fs::create_dir_all(&dir).map_err(|e| sticky_lips::Error::io(&dir, e))?;
    sticky_lips::io::atomic::write_atomic(&path, text.as_bytes())
        .map_err(|e| sticky_lips::Error::io(&path, e))?;
    Ok(path)
}

/// Exit status of a run stopped by SIGINT or SIGTERM (128 + SIGINT's number, as shells
/// report an interrupted command).
const EXIT_INTERRUPTED: u8 = 130;

/// Seconds after a first SIGINT/SIGTERM within which further ones are the same request.
const SIGNAL_BURST_S: f64 = 1.0;

fn main() -> ExitCode {
    // Rust ignores SIGPIPE, so writing to a closed pipe (`sticky-lips ... | head`) would
    // panic in println!; a command-line tool ends quietly there, as the default action does.
    #[cfg(unix)]
    // SAFETY: setting a signal's disposition to its default before any thread is started.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = Cli::parse();
    // SIGINT/SIGTERM: runs stop between steps, finish the frames handed to the writer and
    // write summary.json marked interrupted; `face`, `export`, `sweep` and `paper` stop at
    // their next check and remove what they had not finished. Signals within
    // SIGNAL_BURST_S of the first are one request (GNU timeout and job schedulers signal
    // the process and then its group, which can arrive as two); a signal after that ends
    // the process at once, removing its temporary files first.
    let _ = ctrlc::set_handler(|| {
        static FIRST: std::sync::OnceLock<std::time::Instant> = std::sync::OnceLock::new();
        let now = std::time::Instant::now();
        let first = *FIRST.get_or_init(|| now);
        if first == now {
            progress::cancel_token().cancel();
        } else if now.duration_since(first).as_secs_f64() > SIGNAL_BURST_S {
            sticky_lips::io::atomic::remove_pending();
            eprintln!("interrupted twice: stopped at once; temporary files removed, the last frames may be missing");
            std::process::exit(EXIT_INTERRUPTED as i32);
        }
    });
    match real_main(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e @ (sticky_lips::Error::Interrupted { .. } | sticky_lips::Error::Cancelled(_))) => {
            eprintln!("{e}");
            ExitCode::from(EXIT_INTERRUPTED)
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn real_main(cli: Cli) -> sticky_lips::Result<()> {
    match cli.command {
        Command::Run(a) => run(a)?,
        Command::Equilibrium {
            input,
            out,
            threads,
            load_steps,
        } => {
            let (p, default_out) = load(&input)?;
            let out = app::input::out_dir(out, default_out, &input.input);
            let opts = RunOptions::new(out.clone(), Precision::F64, all_cores(threads));
            let so = StaticOptions {
                load_steps,
                ..Default::default()
            };
            let s = driver::equilibrium(&p, &opts, &so)?;
            println!(
                "{}: equilibrium in {} Newton iterations, residual {:.3e}; written to {}",
                p.source,
                s.newton_iterations.unwrap_or(0),
                s.residual_norm.unwrap_or(f64::NAN),
                out.display()
            );
        }
        Command::Evaporation {
            sticking,
            temperature,
            p_liq,
            p_eq,
            humidity,
            ambient,
            molar_mass,
            density,
            json,
        } => {
            evaporation(
                sticking,
                temperature,
                p_liq,
                p_eq,
                humidity,
                ambient,
                molar_mass,
                density,
                json,
            )?;
        }
        Command::Blend { input, shapes, out } => blend(&input, &shapes, &out)?,
        Command::Sweep { spec, plan, dt } => sweep::sweep(&sweep::Options {
            spec: &spec,
            plan_only: plan,
            dt,
        })?,
        Command::Export {
            run_dir,
            scenario,
            skin_map,
        } => export(&run_dir, scenario, skin_map)?,
        Command::Paper {
            out,
            quick,
            model,
            only,
            threads,
            backend,
            precision,
            reuse,
            dt,
        } => {
            let progress = if std::io::stderr().is_terminal() {
                Progress::Bar
            } else {
                Progress::None
            };
            paper::paper(&paper::PaperOptions {
                out,
                quick,
                threads: all_cores(threads),
                backend: backend.backend(),
                precision: precision.precision(),
                progress,
                reuse,
                model: match model {
                    ModelArg::Face => paper::Model::Face,
                    ModelArg::Procedural => paper::Model::Procedural,
                },
                only,
                dt,
            })?;
        }
        Command::Mouth {
            params,
            resolution,
            out,
        } => mouth(params.as_deref(), resolution, &out)?,
        Command::Face {
            input,
            rig,
            units,
            up,
            forward,
            params,
            resolution,
            out,
        } => {
            let r = app::face::face(
                &app::face::FaceJob {
                    input: &input,
                    rig: rig.as_deref(),
                    units: &units,
                    up: &up,
                    forward: &forward,
                    params: params.as_deref(),
                    resolution,
                    out: &out,
                },
                &progress::cancel_token(),
            )?;
            if let Some(unit) = r.detected_unit {
                println!("face: units {unit}, from the head's size (give --units to choose)");
            }
            for n in &r.notes {
                println!("face: {n}");
            }
            println!(
                "face: wrote face.obj, face.json, head.obj, head.json (the source), model.obj, mesh.vtu, model.xml (resolution {}), groups.png and scenario.toml to {} in {:.2} s",
                resolution,
                out.display(),
                r.seconds
            );
        }
        Command::Extrude {
            surface,
            thickness,
            groups,
            direction,
            out,
        } => extrude(&surface, thickness, &groups, direction.as_deref(), &out)?,
        Command::Check { input } => check(&input)?,
    }
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn evaporation(
    sticking: f64,
    temperature: f64,
    p_liq: Option<f64>,
    p_eq: Option<f64>,
    humidity: f64,
    ambient: f64,
    molar_mass: f64,
    density: f64,
    json: bool,
) -> sticky_lips::Result<()> {
    use sticky_lips::material::saliva::{evaporation_rates, water_saturation_pressure};
    let p_liq = p_liq.unwrap_or_else(|| water_saturation_pressure(temperature));
    let p_eq = p_eq.unwrap_or_else(|| humidity * water_saturation_pressure(ambient));
    let t_k = temperature + 273.15;
    let r = evaporation_rates(sticking, p_liq, p_eq, molar_mass, t_k, density);
    if json {
        let v = serde_json::json!({
            "inputs": {"sticking": sticking, "temperature_K": t_k, "p_liq_Pa": p_liq, "p_eq_Pa": p_eq,
                       "molar_mass_kg_per_mol": molar_mass, "density_kg_per_m3": density},
            "molecular_flux_per_m2_s": r.molecular_flux,
            "mass_flux_kg_per_m2_s": r.mass_flux,
            "thinning_rate_m_per_s": r.thinning_rate,
            "moisture_rate_um_per_s": r.moisture_rate,
        });
        println!("{}", serde_json::to_string_pretty(&v).expect("json"));
    } else {
        println!("Herz-Knudsen evaporation (paper eq. 5)");
        println!("  sticking coefficient alpha   {sticking}");
        println!("  liquid temperature T_liq     {t_k:.2} K ({temperature} C)");
        println!(
            "  p_liq - p_eq                 {p_liq:.2} Pa - {p_eq:.2} Pa = {:.2} Pa",
            p_liq - p_eq
        );
        println!(
            "  molecule mass m              {:.4e} kg",
            molar_mass / sticky_lips::material::saliva::AVOGADRO
        );
        println!(
            "  molecular flux phi           {:.4e} molecules / (m^2 s)",
            r.molecular_flux
        );
        println!(
            "  mass flux                    {:.4e} kg / (m^2 s)",
            r.mass_flux
        );
        println!("  film thinning rate           {:.4e} m/s", r.thinning_rate);
        println!(
            "  model evaporation rate       {:.4e} um/s (moisture units per second)",
            r.moisture_rate
        );
        if r.moisture_rate > 0.0 {
            println!(
                "  a 100 um film dries in       {:.4e} s",
                100.0 / r.moisture_rate
            );
        }
    }
    Ok(())
}

/// `--checkpoint-every N`: at least 1.
fn steps_arg(s: &str) -> Result<usize, String> {
    sticky_lips::io::args::count(s, "step")
}

/// The input file a checkpoint in `dir` was written for.
/// `sticky-lips run` without an input: the sticky lips opening on the MakeHuman face (the
/// paper's `fig4_sticky` run at `--quick` resolution: Table 1, the wide jaw opening), its
/// scenario written to `OUT/scenario.toml` (OUT: `--out`, else `out/face`) and run from there.
/// `sticky-lips run`: a run of an input, the default job, or a restart; the animation files
/// and the preview after it where the model has a skin.
fn run(a: RunArgs) -> sticky_lips::Result<()> {
    let RunArgs {
        input,
        niftysim_compat,
        out,
        checkpoint_every,
        restart,
        precision,
        backend,
        threads,
        force_dt,
        dt,
        subcycles,
        quiet,
        progress,
    } = a;
    let default = input.is_none() && restart.is_none();
    let input = InputArgs {
        input: match (input, &restart) {
            (Some(i), _) => i,
            (None, Some(dir)) => sticky_lips::run_dir::RunDir::new(dir).checkpoint_input()?,
            (None, None) => default_job(out.as_deref(), dt)?,
        },
        niftysim_compat,
    };
    // the default job's scenario already has the step asked for
    let (p, default_out) =
        app::input::load_with(&input.input(), if default { None } else { dt }, subcycles)?;
    let out = match (&restart, out) {
        (Some(dir), Some(o)) if o != *dir => {
            return Err(sticky_lips::Error::input(
                "--out",
                sticky_lips::error::Location::None,
                format!(
                    "--restart {} continues the run in that directory; --out {} differs",
                    dir.display(),
                    o.display()
                ),
            ))
        }
        (Some(dir), _) => dir.clone(),
        (None, o) => app::input::out_dir(o, default_out, &input.input),
    };
    let progress = match (quiet, progress) {
        (true, _) => Progress::None,
        (false, Some(p)) => p,
        (false, None) => Progress::default_for_stderr(),
    };
    let opts = RunOptions {
        out: out.clone(),
        precision: precision.precision(),
        backend: backend.backend(),
        threads: all_cores(threads),
        force_dt,
        cancel: progress::cancel_token(),
        progress: progress.callback(),
        checkpoint_every,
        restart: restart.is_some(),
        export: true,
    };
    let json = progress == Progress::Json;
    let s = match driver::run(&p, &opts) {
        Err(sticky_lips::Error::Interrupted { step, time }) if json => {
            progress::json_line(&serde_json::json!({
                "event": "interrupted", "step": step, "time": time, "out": out,
            }));
            return Err(sticky_lips::Error::Interrupted { step, time });
        }
        r => r?,
    };
    if json {
        if s.export.is_some() {
            app::preview::write(&p, &out)?;
        }
        progress::json_line(&serde_json::json!({
            "event": "finished",
            "out": out,
            "steps": s.steps,
            "simulated_time": s.simulated_time,
            "frames": s.frames,
            "wall_time": s.wall_time,
        }));
        return Ok(());
    }
    println!(
        "{}: {} steps, t = {:.6} s, {} frames in {}; wall {:.3} s, {:.3e} element-updates/s ({}, {}, {} thread{})",
        p.source,
        s.steps,
        s.simulated_time,
        s.frames,
        out.display(),
        s.wall_time,
        s.element_updates_per_second,
        s.precision,
        s.backend,
        s.threads,
        if s.threads == 1 { "" } else { "s" }
    );
    if let Some(e) = &s.export {
        let t = std::time::Instant::now();
        app::preview::write(&p, &out)?;
        println!(
            "{}: skin.obj, skin.pc2, skin.mdd, skin.usda ({} frames of {} vertices; {:.2} s) and preview.png, preview_sheet.png ({:.2} s)",
            out.display(),
            e.frames,
            e.vertices,
            e.read_seconds + e.write_seconds,
            t.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

/// `sticky-lips export`: a run's animation files and preview written again from its frames,
/// or only its skin mapping (`--skin-map`).
fn export(
    run_dir: &Path,
    scenario: Option<PathBuf>,
    skin_map: Option<PathBuf>,
) -> sticky_lips::Result<()> {
    let input = InputArgs {
        input: match scenario {
            Some(s) => s,
            None => sticky_lips::run_dir::RunDir::new(run_dir).input()?,
        },
        niftysim_compat: false,
    };
    let (p, _) = load(&input)?;
    let Some(skin) = &p.physics.skin else {
        return Err(sticky_lips::Error::input(
            input.input.display().to_string(),
            sticky_lips::error::Location::Field("mesh.generator".into()),
            "only mouth and face models have a skin to export",
        ));
    };
    if let Some(path) = skin_map {
        // the map is a new file: never one of the run's files or the scenario
        let mut inputs: Vec<PathBuf> = std::fs::read_dir(run_dir)
            .map_err(|e| sticky_lips::Error::io(run_dir, e))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .collect();
        inputs.push(input.input.clone());
        let named: Vec<(&Path, &str)> = inputs
            .iter()
            .map(|p| (p.as_path(), "a file of the run or its scenario"))
            .collect();
        let (dir, name) = (
            path.parent().unwrap_or(Path::new(".")),
            path.file_name().and_then(|n| n.to_str()).unwrap_or(""),
        );
        sticky_lips::io::atomic::refuse_overwriting_inputs(dir, &[name], &named)?;
        let map = sticky_lips::export::skin_map(skin, run_dir)?;
        let text = serde_json::to_string(&map).expect("json");
        sticky_lips::io::atomic::write_atomic(&path, text.as_bytes())
            .map_err(|e| sticky_lips::Error::io(&path, e))?;
        println!("export: the skin mapping written to {}", path.display());
        return Ok(());
    }
    let e = sticky_lips::export::export_with(skin, run_dir, &progress::cancel_token())?;
    app::preview::write(&p, run_dir)?;
    println!(
        "export: {} frames of {} vertices ({} over the model, {} beside it, {} following the jaw) to {}",
        e.frames,
        e.vertices,
        e.tied[0],
        e.tied[1],
        e.tied[2],
        run_dir.display()
    );
    Ok(())
}

/// `sticky-lips check`: an input's mesh statistics, time step and stability limits.
fn check(input: &InputArgs) -> sticky_lips::Result<()> {
    let (p, _) = load(input)?;
    let st = p.mesh.stats();
    let d = Discretisation::new(&p);
    let r = stability::analyse(&p, &d);
    println!("{}: valid", p.source);
    println!(
        "  nodes {}, hexahedra {}, materials {}",
        st.nodes,
        st.elements,
        p.materials.len()
    );
    println!(
        "  bounding box {:?} .. {:?} m",
        st.bounding_box_min, st.bounding_box_max
    );
    println!(
        "  volume {:.6e} m^3 (elements {:.3e} .. {:.3e}), worst corner-Jacobian ratio {:.3}",
        st.total_volume, st.min_element_volume, st.max_element_volume, st.worst_jacobian_ratio
    );
    println!(
        "  variant {:?}, damping {} 1/s, hourglass kappa {}",
        p.numerics.variant, p.numerics.damping, p.numerics.hourglass_kappa
    );
    println!(
        "  steps {} of dt = {:e} s (T = {} s), output every {} steps",
        p.num_steps(),
        p.time.dt,
        p.time.total_time,
        p.time.output_every
    );
    println!(
        "  critical time step 2/omega_max = {:.4e} s ({} Lanczos iterations); per-element estimate {:.4e} s at element {}",
        r.critical_time_step, r.iterations, r.element_estimate, r.limiting_element
    );
    if let Some(t) = r.tissue_critical_time_step {
        println!(
            "  critical time step of the tissue (the saliva's stiffness left out, the limit of a subcycled step) = {t:.4e} s"
        );
    }
    let k = p.numerics.subcycles;
    let judge = |what: &str, dt: f64, critical: f64| {
        let ratio = dt / critical;
        if ratio <= 1.0 {
            println!("  {what} is stable ({:.1} % of critical)", 100.0 * ratio);
        } else {
            println!(
                "  {what} is UNSTABLE ({:.1} % of critical): `run` will refuse it",
                100.0 * ratio
            );
        }
    };
    if k > 1 {
        let tissue = r.tissue_critical_time_step.unwrap_or(f64::INFINITY);
        judge(
            &format!("the saliva's substep dt/{k} = {:e} s", p.time.dt / k as f64),
            p.time.dt / k as f64,
            r.critical_time_step,
        );
        judge("the large step (against the tissue's)", p.time.dt, tissue);
    } else {
        judge("time step", p.time.dt, r.critical_time_step);
    }
    Ok(())
}

fn all_cores(threads: Option<usize>) -> usize {
    threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
}

/// `--threads N`: at least 1.
fn fraction_arg(s: &str) -> Result<f64, String> {
    sticky_lips::io::args::number_in(s, (0.0, true), (1.0, true), "a fraction, 0 to 1")
}

fn celsius_arg(s: &str) -> Result<f64, String> {
    sticky_lips::io::args::number_in(
        s,
        (-273.15, false),
        (1000.0, true),
        "degrees Celsius, above -273.15 and at most 1000",
    )
}

fn pressure_arg(s: &str) -> Result<f64, String> {
    sticky_lips::io::args::number_in(s, (0.0, true), (f64::MAX, true), "pascals, at least 0")
}

fn positive_arg(s: &str) -> Result<f64, String> {
    sticky_lips::io::args::number_in(s, (0.0, false), (f64::MAX, true), "a number above 0")
}

fn threads_arg(s: &str) -> Result<usize, String> {
    sticky_lips::io::args::threads(s)
}

fn blend(input: &InputArgs, shapes: &[String], out: &Path) -> sticky_lips::Result<()> {
    let (p, _) = load(input)?;
    app::blend::blend(&p, shapes, out)?;
    println!(
        "blend of {} shape(s) written to {}",
        shapes.len(),
        out.display()
    );
    Ok(())
}

fn mouth(params: Option<&Path>, resolution: Option<f64>, out: &Path) -> sticky_lips::Result<()> {
    use sticky_lips::error::Error;
    use sticky_lips::mesh::mouth;
    if let Some(path) = params {
        sticky_lips::io::atomic::refuse_overwriting_inputs(
            out,
            &["mouth.obj", "mesh.vtu", "model.xml", "mouth.json"],
            &[(path, "the parameters (--params)")],
        )?;
    }
    let mut p: mouth::MouthParams = match params {
        Some(path) => scenario::read_toml(path)?,
        None => mouth::MouthParams::default(),
    };
    if let Some(r) = resolution {
        p.resolution = r;
    }
    let t0 = std::time::Instant::now();
    let model = mouth::generate(&p)?;
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    sticky_lips::io::obj::write_obj(&out.join("mouth.obj"), &model.surface)?;
    let groups: Vec<(String, Vec<u32>)> = ["upper_face", "lower_face", "saliva"]
        .iter()
        .map(|g| {
            (
                g.to_string(),
                model.mesh.element_sets.get(*g).cloned().unwrap_or_default(),
            )
        })
        .collect();
    app::mesh_outputs::write(out, &model.mesh, &groups)?;
    let info = serde_json::json!({
        "hexahedra": model.mesh.elements.len(),
        "nodes": model.mesh.nodes.len(),
        "params": p,
        "jaw_hinge": {"point": model.jaw_hinge.0, "axis": model.jaw_hinge.1},
        "muscles": model.muscles.iter().map(|m| serde_json::json!({
            "name": m.name, "origin": m.origin, "insertion": m.insertion, "radius": m.radius,
            "nodes": m.select_nodes(&model.mesh.nodes).len()})).collect::<Vec<_>>(),
        "node_sets": model.mesh.node_sets.iter().map(|(k, v)| (k.clone(), v.len())).collect::<std::collections::BTreeMap<_, _>>(),
        "element_sets": model.mesh.element_sets.iter().map(|(k, v)| (k.clone(), v.len())).collect::<std::collections::BTreeMap<_, _>>(),
        "saliva_columns": model.saliva_columns.len(),
    });
    let path = out.join("mouth.json");
    sticky_lips::io::atomic::write_atomic(
        &path,
        serde_json::to_string_pretty(&info)
            .expect("json")
            .as_bytes(),
    )
    .map_err(|e| Error::io(&path, e))?;
    println!(
        "mouth: {} hexahedra, {} nodes ({} saliva elements) in {:.2} s; wrote mouth.obj, mesh.vtu, model.xml, mouth.json to {}",
        model.mesh.elements.len(),
        model.mesh.nodes.len(),
        model.mesh.element_sets.get("saliva").map_or(0, |s| s.len()),
        t0.elapsed().as_secs_f64(),
        out.display()
    );
    Ok(())
}

fn extrude(
    surface: &Path,
    thickness: Option<f64>,
    groups: &[String],
    direction: Option<&str>,
    out: &Path,
) -> sticky_lips::Result<()> {
    use sticky_lips::mesh::extrude;
    let file = surface.display().to_string();
    sticky_lips::io::atomic::refuse_overwriting_inputs(
        out,
        &["mesh.vtu", "model.xml"],
        &[(surface, "the surface")],
    )?;
    let s = sticky_lips::io::obj::read_obj(surface)?;
    let mut per_group = Vec::new();
    for g in groups {
        let (name, t) = sticky_lips::io::args::name_value(g, "--group", "NAME=METRES")?;
        per_group.push((name.to_string(), t));
    }
    let t = extrude::group_thickness(&s, thickness, &per_group, &file)?;
    let dir = match direction {
        None => extrude::Direction::Normal,
        Some(d) => extrude::Direction::Fixed(sticky_lips::io::args::vec3(d, "--direction")?),
    };
    let mesh = extrude::extrude_with(&s, &|g| t[g], dir, &file)?;
    mesh.validate(&file)?;
    let groups: Vec<(String, Vec<u32>)> = s
        .groups
        .iter()
        .map(|g| {
            (
                g.clone(),
                mesh.element_sets.get(g).cloned().unwrap_or_default(),
            )
        })
        .collect();
    app::mesh_outputs::write(out, &mesh, &groups)?;
    println!(
        "{}: {} quads in {} groups -> {} hexahedra, {} nodes; wrote mesh.vtu and model.xml to {}",
        file,
        s.quads.len(),
        s.groups.len(),
        mesh.elements.len(),
        mesh.nodes.len(),
        out.display()
    );
    Ok(())
}
