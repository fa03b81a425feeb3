//! An input file to a [`Problem`]: the reader chosen by the file's extension (a `.toml`
//! scenario, [`crate::io::scenario`]; a `.xml` NiftySim model, [`crate::io::niftysim`]), at a
//! time step and with saliva substeps asked for; the default job's scenario.

use crate::element::hex8::GradientVariant;
use crate::error::Result;
use crate::io::{niftysim, scenario};
use crate::Problem;
use std::path::{Path, PathBuf};

/// An input file and how to read it.
#[derive(Clone, Debug)]
pub struct Input {
    /// A scenario (.toml) or a NiftySim model (.xml).
    pub path: PathBuf,
    /// Reproduce NiftySim: centroid gradients and its timing quirks (XML input only).
    pub niftysim_compat: bool,
}

impl Input {
    /// `path`, read as its extension says, without NiftySim's quirks.
    pub fn new(path: impl Into<PathBuf>) -> Self {
        Input {
            path: path.into(),
            niftysim_compat: false,
        }
    }
}

/// The problem in `input`, and the output directory its scenario names (if any).
pub fn load(input: &Input) -> Result<(Problem, Option<PathBuf>)> {
    load_with(input, None, None)
}

/// Substeps of the saliva layer asked for (`[time] subcycles`, `run --subcycles`): `auto`
/// or a count, at least 1.
#[derive(Clone, Copy, Debug)]
pub enum Subcycles {
    Auto,
    Count(i64),
}

impl std::str::FromStr for Subcycles {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match (s, s.parse::<i64>()) {
            ("auto", _) => Ok(Subcycles::Auto),
            (_, Ok(n)) if n >= 1 => Ok(Subcycles::Count(n)),
            _ => Err(format!(
                "`{s}`: give auto or a whole number of substeps (at least 1)"
            )),
        }
    }
}

/// [`load`], at the time step `dt` where given, with `subcycles` where given (`scenario::with_dt`; for a NiftySim model
/// seconds only, the frames' interval kept).
pub fn load_with(
    args: &Input,
    dt: Option<scenario::DtChoice>,
    subcycles: Option<Subcycles>,
) -> crate::Result<(Problem, Option<PathBuf>)> {
    let name = args.path.display().to_string();
    let is_toml = args
        .path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
    if let Some(k) = subcycles {
        if !is_toml {
            return Err(crate::Error::input(
                "command line",
                crate::error::Location::Field("--subcycles".into()),
                format!("subcycling applies to scenarios (.toml); {name} is a NiftySim model"),
            ));
        }
        let mut text = scenario::read_text(&args.path)?;
        if let Some(dt) = dt {
            text = scenario::with_dt(&text, &name, dt)?;
        }
        let value = match k {
            Subcycles::Auto => toml::Value::String("auto".into()),
            Subcycles::Count(n) => toml::Value::Integer(n),
        };
        let text = scenario::with_overrides(&text, &name, &[("time.subcycles", value)])?;
        let s = scenario::parse(&text, &args.path)?;
        return Ok((s.problem, s.default_output));
    }
    let Some(dt) = dt else {
        return load_plain(args);
    };
    if is_toml {
        let text = scenario::read_text(&args.path)?;
        let text = scenario::with_dt(&text, &name, dt)?;
        let s = scenario::parse(&text, &args.path)?;
        return Ok((s.problem, s.default_output));
    }
    let (mut p, out) = load_plain(args)?;
    match dt {
        scenario::DtChoice::Seconds(x) => {
            let interval = p.time.output_every as f64 * p.time.dt;
            p.time.output_every = (interval / x).round().max(1.0) as usize;
            p.time.dt = x;
            p.validate()?;
            Ok((p, out))
        }
        scenario::DtChoice::Auto => Err(crate::Error::input(
            "command line",
            crate::error::Location::Field("--dt".into()),
            format!("auto applies to scenarios (.toml); {name} is a NiftySim model: give seconds"),
        )),
    }
}

/// [`load`] as the file says, without a step or substeps asked for.
fn load_plain(args: &Input) -> crate::Result<(Problem, Option<PathBuf>)> {
    let ext = args
        .path
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
            let p = niftysim::read(&args.path, variant, args.niftysim_compat)?;
            p.validate()?;
            Ok((p, None))
        }
        "toml" => {
            if args.niftysim_compat {
                return Err(crate::Error::input(
                    args.path.display().to_string(),
                    crate::error::Location::None,
                    "--niftysim-compat applies to NiftySim XML models only",
                ));
            }
            let s = scenario::read(&args.path)?;
            Ok((s.problem, s.default_output))
        }
        _ => Err(crate::Error::input(
            args.path.display().to_string(),
            crate::error::Location::None,
            "unknown input kind: expected a .toml scenario or a .xml NiftySim model",
        )),
    }
}

/// Where a run writes: `explicit` (`--out`), else the scenario's `[output] dir`, else
/// `out/<input's stem>`.
pub fn out_dir(explicit: Option<PathBuf>, default: Option<PathBuf>, input: &Path) -> PathBuf {
    explicit.or(default).unwrap_or_else(|| {
        Path::new("out").join(
            input
                .file_stem()
                .map(|s| s.to_string_lossy().to_string())
                .unwrap_or_else(|| "run".into()),
        )
    })
}

/// The default job's scenario (what `sticky-lips run` runs with no input): the sticky lips
/// opening on the MakeHuman face, the paper's run `fig4_sticky` at the quick resolution, at
/// `dt` (default `auto`), writing into the directory of `path` (where the text is to be saved;
/// it names it in its comment and errors).
pub fn default_job_text(path: &Path, dt: Option<scenario::DtChoice>) -> Result<String> {
    use crate::paper::{scenario_of, spec, Model};
    let run = spec(Model::Face, true, "fig4_sticky").expect("the paper defines fig4_sticky");
    let (text, _) = scenario_of(Model::Face, true, &run, path)?;
    let label = path.display().to_string();
    // at dt = "auto" unless asked otherwise: the frames every 10 ms and eq. 11's decay in
    // physical time (Table 1's 0.99 per 1e-5 s), as the paper's run has them
    let text = scenario::with_dt(&text, &label, dt.unwrap_or(scenario::DtChoice::Auto))?;
    Ok(format!(
        "# sticky-lips run (no input given): the sticky lips opening on the MakeHuman face, the\n\
         # paper's run fig4_sticky at the quick resolution, at dt = {}; `sticky-lips run {label}`\n\
         # repeats it.\n{}",
        match dt {
            Some(scenario::DtChoice::Seconds(x)) => format!("{x:e} s"),
            _ => "\"auto\" (Table 1's physics, the step from the model's critical step)".into(),
        },
        crate::io::scenario::with_overrides(
            &text,
            &label,
            &[("output.dir", toml::Value::String(".".into()))],
        )?
    ))
}
