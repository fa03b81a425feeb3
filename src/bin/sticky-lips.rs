//! `sticky-lips`: the command line.
//!
//! ```text
//! sticky-lips run <scenario.toml | model.xml> --out DIR [--precision f64|f32] [--threads N] [--niftysim-compat]
//! sticky-lips equilibrium <scenario.toml | model.xml> --out DIR
//! sticky-lips check <scenario.toml | model.xml>
//! ```

use clap::{Parser, Subcommand, ValueEnum};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use sticky_lips::driver::{self, Progress, RunOptions};
use sticky_lips::element::hex8::GradientVariant;
use sticky_lips::io::{niftysim, scenario};
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

#[derive(clap::Args)]
struct InputArgs {
    /// A scenario (.toml) or a NiftySim model (.xml).
    input: PathBuf,
    /// Reproduce NiftySim: centroid gradients and its timing quirks (XML input only).
    #[arg(long)]
    niftysim_compat: bool,
}

#[derive(Subcommand)]
enum Command {
    /// Explicit dynamic run (TLED, central differences).
    Run {
        #[command(flatten)]
        input: InputArgs,
        /// Output directory (default: the scenario's [output] dir, else out/<input name>).
        #[arg(long)]
        out: Option<PathBuf>,
        #[arg(long, value_enum, default_value = "f64")]
        precision: PrecisionArg,
        /// Worker threads (results are bit-identical for any count).
        #[arg(long, default_value_t = 1)]
        threads: usize,
        /// Run even if the time step exceeds the critical time step.
        #[arg(long)]
        force_dt: bool,
        /// No progress output.
        #[arg(long)]
        quiet: bool,
    },
    /// Static equilibrium (Newton with load stepping) at the end-of-run loads.
    Equilibrium {
        #[command(flatten)]
        input: InputArgs,
        #[arg(long)]
        out: Option<PathBuf>,
        #[arg(long, default_value_t = 1)]
        threads: usize,
        /// Load steps.
        #[arg(long, default_value_t = 10)]
        load_steps: usize,
    },
    /// Validate the input; print mesh statistics and the critical time step.
    Check {
        #[command(flatten)]
        input: InputArgs,
    },
}

fn load(args: &InputArgs) -> sticky_lips::Result<(Problem, Option<PathBuf>)> {
    let ext = args
        .input
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    match ext.as_str() {
        "xml" => {
            let variant = if args.niftysim_compat {
                GradientVariant::Centroid
            } else {
                GradientVariant::MeanGradient
            };
            let p = niftysim::read(&args.input, variant, args.niftysim_compat)?;
            p.validate()?;
            Ok((p, None))
        }
        "toml" => {
            if args.niftysim_compat {
                return Err(sticky_lips::Error::input(
                    args.input.display().to_string(),
                    sticky_lips::error::Location::None,
                    "--niftysim-compat applies to NiftySim XML models only",
                ));
            }
            let s = scenario::read(&args.input)?;
            Ok((s.problem, s.default_output))
        }
        _ => Err(sticky_lips::Error::input(
            args.input.display().to_string(),
            sticky_lips::error::Location::None,
            "unknown input kind: expected a .toml scenario or a .xml NiftySim model",
        )),
    }
}

fn out_dir(explicit: Option<PathBuf>, default: Option<PathBuf>, input: &Path) -> PathBuf {
    explicit.or(default).unwrap_or_else(|| {
        Path::new("out").join(
            input
                .file_stem()
                .map(|s| s.to_string_lossy().to_string())
                .unwrap_or_else(|| "run".into()),
        )
    })
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match real_main(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn real_main(cli: Cli) -> sticky_lips::Result<()> {
    match cli.command {
        Command::Run {
            input,
            out,
            precision,
            threads,
            force_dt,
            quiet,
        } => {
            let (p, default_out) = load(&input)?;
            let out = out_dir(out, default_out, &input.input);
            let progress = if quiet {
                Progress::Quiet
            } else if std::io::stderr().is_terminal() {
                Progress::Bar
            } else {
                Progress::Plain
            };
            let precision = match precision {
                PrecisionArg::F64 => Precision::F64,
                PrecisionArg::F32 => Precision::F32,
            };
            let opts = RunOptions {
                out: out.clone(),
                precision,
                threads,
                force_dt,
                progress,
            };
            let s = driver::run(&p, &opts)?;
            println!(
                "{}: {} steps, t = {:.6} s, {} frames in {}; wall {:.3} s, {:.3e} element-updates/s ({}, {} thread{})",
                p.source,
                s.steps,
                s.simulated_time,
                s.frames,
                out.display(),
                s.wall_time,
                s.element_updates_per_second,
                s.precision,
                s.threads,
                if s.threads == 1 { "" } else { "s" }
            );
        }
        Command::Equilibrium {
            input,
            out,
            threads,
            load_steps,
        } => {
            let (p, default_out) = load(&input)?;
            let out = out_dir(out, default_out, &input.input);
            let opts = RunOptions {
                out: out.clone(),
                precision: Precision::F64,
                threads,
                force_dt: false,
                progress: Progress::Quiet,
            };
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
        Command::Check { input } => {
            let (p, _) = load(&input)?;
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
            let ratio = p.time.dt / r.critical_time_step;
            if ratio <= 1.0 {
                println!("  time step is stable ({:.1} % of critical)", 100.0 * ratio);
            } else {
                println!(
                    "  time step is UNSTABLE ({:.1} % of critical): `run` will refuse it",
                    100.0 * ratio
                );
            }
        }
    }
    Ok(())
}
