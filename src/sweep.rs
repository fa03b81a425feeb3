//! A sweep's plan (`sticky-lips sweep SPEC.toml`): the spec's text in, every run's name,
//! overrides, directory, command and scenario text out, all checked, before anything is
//! written. The command line (`cli/src/sweep.rs`) writes the plan's files and
//! runs its jobs.
//!
//! A spec names a base scenario and what changes: a `[grid]` of override values (every
//! combination) and/or a list of `[[shot]]`s (a name and its overrides). Overrides are key
//! paths into the scenario (`"saliva.0.k_glue"`, `"jaw.angle"`, `"mesh.face.resolution"`)
//! with any TOML value, applied by [`crate::io::scenario::with_overrides`]. Each run's
//! scenario is the base with its overrides and relative file names made absolute, parsed
//! as `run` would parse it: a run whose overrides make a bad scenario is refused, naming the
//! run.

use crate::error::{Error, Location, Result};
use crate::io::scenario::with_overrides;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Spec {
    /// The base scenario, relative to the spec (default: the default job's, Table 1 on the
    /// MakeHuman face at the quick resolution).
    base: Option<String>,
    /// Where the runs go, relative to the spec (default: `out/<spec name>`).
    out: Option<String>,
    /// Runs at once on this machine (default: cores / threads).
    jobs: Option<usize>,
    /// Threads per run (default 1: a sweep is parallel across runs).
    threads: Option<usize>,
    /// The runs' time step: `"auto"` or seconds (`scenario::with_dt`: the frames' interval
    /// and eq. 11's decay kept in physical time). Default: the base's own step; the default
    /// job's is `"auto"`. `sweep --dt` takes precedence.
    dt: Option<crate::io::scenario::DtDef>,
    /// Every combination of these values.
    #[serde(default)]
    grid: BTreeMap<String, Vec<toml::Value>>,
    /// Named shots, each with its own overrides.
    #[serde(default)]
    shot: Vec<Shot>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Shot {
    name: String,
    #[serde(default)]
    set: BTreeMap<String, toml::Value>,
}

/// One run of the sweep.
#[derive(Clone, Debug)]
pub struct Job {
    pub name: String,
    pub overrides: BTreeMap<String, toml::Value>,
    /// `OUT/NAME`: where its scenario and its outputs go.
    pub dir: PathBuf,
    /// The command that runs it: `EXE run DIR/scenario.toml --out DIR --threads T --quiet`.
    pub command: Vec<String>,
    /// Its `scenario.toml`: a comment naming the sweep, the run and the overrides, then the
    /// base with the overrides (relative file names absolute).
    pub scenario: String,
}

/// A checked sweep: what `sweep` writes and runs.
#[derive(Clone, Debug)]
pub struct Plan {
    /// The spec's name in messages (its path as given).
    pub file: String,
    /// The base scenario's name in messages (its path, or `the default job`).
    pub base_name: String,
    /// Where the runs go.
    pub out: PathBuf,
    pub threads: usize,
    /// Runs at once on this machine.
    pub jobs_at_once: usize,
    /// The grid's combinations, then the shots.
    pub jobs: Vec<Job>,
}

/// The files a sweep writes beside its runs.
pub const RESERVED: [&str; 2] = ["jobs.txt", "sweep.json"];

/// The most runs one sweep may plan.
pub const MAX_RUNS: usize = 100_000;

fn err(file: &str, field: impl Into<String>, msg: impl Into<String>) -> Error {
    Error::input(file, Location::Field(field.into()), msg.into())
}

/// A value as part of a directory name.
fn tag(v: &toml::Value) -> String {
    let s = match v {
        toml::Value::String(s) => s.clone(),
        other => other.to_string(),
    };
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '.' || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Relative file names in a scenario (`mesh.file`, `keys_file`, any key ending in `file`)
/// made absolute against `base`.
fn absolute_files(v: &mut toml::Value, base: &Path) {
    match v {
        toml::Value::Table(t) => {
            for (k, x) in t.iter_mut() {
                if k.ends_with("file") {
                    if let toml::Value::String(s) = x {
                        let p = Path::new(s.as_str());
                        if p.is_relative() {
                            *s = base.join(p).display().to_string();
                        }
                    }
                } else {
                    absolute_files(x, base);
                }
            }
        }
        toml::Value::Array(a) => a.iter_mut().for_each(|x| absolute_files(x, base)),
        _ => {}
    }
}

/// The plan of the spec `text`, read from `spec_path` (its name in errors; the base and the
/// output directory are relative to its directory), whose runs are commands of `exe`. Reads
/// the base scenario and what the scenarios name (meshes, keys files); writes nothing.
pub fn plan(text: &str, spec_path: &Path, exe: &Path) -> Result<Plan> {
    plan_with_dt(text, spec_path, exe, None)
}

/// A run of the sweep before its scenario is built: its name and its overrides.
type Run = (String, BTreeMap<String, toml::Value>);

/// The base scenario ([`base_scenario`]).
struct Base {
    /// Its text.
    text: String,
    /// Its name in messages: its path, or `the default job`.
    name: String,
    /// The directory its relative file names are relative to.
    dir: PathBuf,
}

/// The spec `text` parsed; a syntax error names the line in `file`.
fn read_spec(text: &str, file: &str) -> Result<Spec> {
    crate::io::scenario::from_toml(text, file)
}

/// The spec's directory, absolute (the current one for a bare file name).
fn spec_dir(spec_path: &Path) -> Result<PathBuf> {
    let spec_dir = spec_path
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default();
    std::fs::canonicalize(if spec_dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        &spec_dir
    })
    .map_err(|e| Error::io(&spec_dir, e))
}

/// The base scenario: the file the spec names (relative to `spec_dir`), or the default job's
/// (Table 1 on the MakeHuman face at the quick resolution, its files relative to `spec_dir`).
fn base_scenario(base: Option<&str>, spec_dir: &Path, file: &str) -> Result<Base> {
    let (text, name, dir) = match base {
        Some(b) => {
            let p = spec_dir.join(b);
            let t = std::fs::read_to_string(&p)
                .map_err(|e| err(file, "base", format!("{}: {e}", p.display())))?;
            let dir = p.parent().map(Path::to_path_buf).unwrap_or_default();
            (t, p.display().to_string(), dir)
        }
        None => {
            use crate::paper::{scenario_of, spec as paper_spec, Model};
            let run = paper_spec(Model::Face, true, "fig4_sticky").expect("the paper's run");
            let (t, _) = scenario_of(Model::Face, true, &run, Path::new("default job"))?;
            (t, "the default job".to_string(), spec_dir.to_path_buf())
        }
    };
    Ok(Base { text, name, dir })
}

/// The runs' time step: `dt` (`sweep --dt`) where given, else the spec's, else `"auto"` for
/// the default job (as `run` without an input); `None`: the base's own.
fn runs_dt(
    dt: Option<crate::io::scenario::DtChoice>,
    spec: &Spec,
    file: &str,
) -> Result<Option<crate::io::scenario::DtChoice>> {
    use crate::io::scenario::{DtChoice, DtDef};
    Ok(match (dt, spec.dt) {
        (Some(d), _) => Some(d),
        (None, Some(DtDef::Seconds(x))) if x.is_finite() && x > 0.0 => Some(DtChoice::Seconds(x)),
        (None, Some(DtDef::Seconds(x))) => {
            return Err(err(
                file,
                "dt",
                format!("must be positive and finite, got {x}"),
            ))
        }
        (None, Some(DtDef::Auto(_))) => Some(DtChoice::Auto),
        // the default job at dt = "auto", as `run` without an input
        (None, None) if spec.base.is_none() => Some(DtChoice::Auto),
        (None, None) => None,
    })
}

/// Where the runs go: the spec's `out` (relative to `spec_dir`), else `out/<spec name>` in
/// the current directory.
fn out_dir(out: Option<&str>, spec_dir: &Path, spec_path: &Path) -> Result<PathBuf> {
    Ok(match out {
        Some(d) => spec_dir.join(d),
        None => std::env::current_dir()
            .map_err(|e| Error::io(".", e))?
            .join("out")
            .join(
                spec_path
                    .file_stem()
                    .map_or("sweep".into(), |s| s.to_string_lossy().to_string()),
            ),
    })
}

/// Threads per run (default 1, at most [`crate::io::args::max_threads`]) and runs at once
/// (default: cores / threads), checked.
fn threads_and_jobs(spec: &Spec, file: &str) -> Result<(usize, usize)> {
    let threads = spec.threads.unwrap_or(1);
    if threads == 0 {
        return Err(err(file, "threads", "must be at least 1"));
    }
    let max = crate::io::args::max_threads();
    if threads > max {
        return Err(err(
            file,
            "threads",
            format!("{threads} per run: at most {max} (four per CPU of this machine)"),
        ));
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let jobs_at_once = spec.jobs.unwrap_or((cores / threads).max(1));
    if jobs_at_once == 0 {
        return Err(err(file, "jobs", "must be at least 1"));
    }
    Ok((threads, jobs_at_once))
}

/// The grid's combinations, the last key varying fastest, each named by its index and its
/// values. Fails if a key lists no values or the combinations are more than [`MAX_RUNS`].
fn grid_runs(grid: &BTreeMap<String, Vec<toml::Value>>, file: &str) -> Result<Vec<Run>> {
    let mut runs = Vec::new();
    let keys: Vec<&String> = grid.keys().collect();
    for k in &keys {
        if grid[*k].is_empty() {
            return Err(err(file, format!("grid.{k}"), "lists no values"));
        }
    }
    if !keys.is_empty() {
        let sizes: Vec<usize> = keys.iter().map(|k| grid[*k].len()).collect();
        // checked: a product that overflows is more runs than allowed, not a small number
        let total = sizes
            .iter()
            .try_fold(1usize, |a, &n| a.checked_mul(n))
            .filter(|&t| t <= MAX_RUNS);
        let Some(total) = total else {
            let shape = sizes
                .iter()
                .map(|n| n.to_string())
                .collect::<Vec<_>>()
                .join(" x ");
            return Err(err(
                file,
                "grid",
                format!("gives {shape} runs (at most {MAX_RUNS})"),
            ));
        };
        for i in 0..total {
            let mut rest = i;
            let mut set = BTreeMap::new();
            let mut name = Vec::new();
            for (k, n) in keys.iter().zip(&sizes).rev() {
                let v = grid[*k][rest % n].clone();
                rest /= n;
                let short = k.rsplit('.').next().unwrap_or(k);
                name.push(format!("{short}-{}", tag(&v)));
                set.insert((*k).clone(), v);
            }
            name.reverse();
            runs.push((format!("{i:03}_{}", name.join("_")), set));
        }
    }
    Ok(runs)
}

/// The shots as runs. Fails if a name is not a plain directory name or is one of the sweep's
/// own files.
fn shot_runs(shots: &[Shot], file: &str) -> Result<Vec<Run>> {
    let mut runs = Vec::new();
    for (i, s) in shots.iter().enumerate() {
        // a name becomes a directory, a line of jobs.txt and a comment in the scenario: letters,
        // digits, `.`, `_` and `-` only (no newline, quote or path), not the sweep's own files
        let plain = !s.name.is_empty()
            && s.name.len() <= 100
            && !s.name.starts_with(['.', '-'])
            && s.name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "._-".contains(c));
        if !plain {
            return Err(err(
                file,
                format!("shot[{i}].name"),
                format!(
                    "{:?} must be a plain directory name: 1 to 100 of A-Z a-z 0-9 . _ -, not \
                     starting with . or -",
                    s.name
                ),
            ));
        }
        if RESERVED.contains(&s.name.as_str()) {
            return Err(err(
                file,
                format!("shot[{i}].name"),
                format!("`{}` is a file of the sweep itself", s.name),
            ));
        }
        runs.push((s.name.clone(), s.set.clone()));
    }
    Ok(runs)
}

/// Checks the override keys of the grid's, then of the shots'.
fn check_keys(spec: &Spec, file: &str) -> Result<()> {
    // override keys are paths into the scenario; they are written into each scenario's
    // first line, so they too are plain
    let plain_key = |k: &str| {
        !k.is_empty()
            && k.chars()
                .all(|c| c.is_ascii_alphanumeric() || "._-".contains(c))
    };
    for (field, key) in spec.grid.keys().map(|k| (format!("grid.{k:?}"), k)).chain(
        spec.shot.iter().enumerate().flat_map(|(i, s)| {
            s.set
                .keys()
                .map(move |k| (format!("shot[{i}].set.{k:?}"), k))
        }),
    ) {
        if !plain_key(key) {
            return Err(err(
                file,
                field,
                "a key is a path of names and indices: A-Z a-z 0-9 _ - joined by .",
            ));
        }
    }
    Ok(())
}

/// Checks that there are runs, each with a name of its own, and that the paths written into
/// job lines and comments (`out`, the base's, the spec's) hold no control character.
fn check_runs_and_paths(runs: &[Run], out: &Path, base_name: &str, file: &str) -> Result<()> {
    if runs.is_empty() {
        return Err(err(file, "grid", "the spec has neither a grid nor shots"));
    }
    let mut seen = std::collections::BTreeSet::new();
    for (n, _) in runs {
        if !seen.insert(n.clone()) {
            return Err(err(file, "shot", format!("two runs are called `{n}`")));
        }
    }
    // paths go into job lines and comments one line each: no control characters
    for (field, path) in [
        ("out", out.display().to_string()),
        ("base", base_name.to_string()),
        ("spec", file.to_string()),
    ] {
        if path.chars().any(char::is_control) {
            return Err(err(
                file,
                field,
                format!("{path:?} holds a control character (a newline?)"),
            ));
        }
    }
    Ok(())
}

/// The job of run `name` with overrides `set`: its scenario (the base with the overrides and
/// its relative file names absolute, under a comment naming the sweep, the run and the
/// overrides), parsed as `run` would parse it in `out/name`, and its command (`exe`,
/// `threads` threads). A bad scenario's error names the run.
fn job(
    name: &str,
    set: &BTreeMap<String, toml::Value>,
    base: &Base,
    out: &Path,
    exe: &Path,
    threads: usize,
    file: &str,
) -> Result<Job> {
    let (base_text, base_name) = (&base.text, &base.name);
    let dir = out.join(name);
    let refs: Vec<(&str, toml::Value)> = set.iter().map(|(k, v)| (k.as_str(), v.clone())).collect();
    let t = with_overrides(base_text, base_name, &refs)?;
    let mut doc: toml::Value =
        toml::from_str(&t).map_err(|e| Error::input(base_name, Location::None, e.message()))?;
    absolute_files(&mut doc, &base.dir);
    let t = format!(
        "# sticky-lips sweep {file}, run {name}: {base_name} with {}\n{}",
        if set.is_empty() {
            "no changes".to_string()
        } else {
            set.iter()
                .map(|(k, v)| format!("{k} = {v}"))
                .collect::<Vec<_>>()
                .join(", ")
        },
        toml::to_string(&doc).expect("a TOML value serialises")
    );
    let path = dir.join("scenario.toml");
    crate::io::scenario::parse(&t, &path)
        .map_err(|e| err(file, format!("run {name}"), e.to_string()))?;
    let command = vec![
        exe.display().to_string(),
        "run".into(),
        path.display().to_string(),
        "--out".into(),
        dir.display().to_string(),
        "--threads".into(),
        threads.to_string(),
        "--quiet".into(),
    ];
    Ok(Job {
        name: name.to_string(),
        overrides: set.clone(),
        dir,
        command,
        scenario: t,
    })
}

/// [`plan`] with the runs' time step `dt` where given (`sweep --dt`), before the spec's.
pub fn plan_with_dt(
    text: &str,
    spec_path: &Path,
    exe: &Path,
    dt: Option<crate::io::scenario::DtChoice>,
) -> Result<Plan> {
    let file = spec_path.display().to_string();
    let spec = read_spec(text, &file)?;
    let spec_dir = spec_dir(spec_path)?;
    // the base scenario's text and the directory its relative files are in
    let mut base = base_scenario(spec.base.as_deref(), &spec_dir, &file)?;
    if let Some(d) = runs_dt(dt, &spec, &file)? {
        base.text = crate::io::scenario::with_dt(&base.text, &base.name, d)?;
    }
    let out = out_dir(spec.out.as_deref(), &spec_dir, spec_path)?;
    let (threads, jobs_at_once) = threads_and_jobs(&spec, &file)?;
    // the runs: the grid's combinations, then the shots
    let mut runs = grid_runs(&spec.grid, &file)?;
    runs.extend(shot_runs(&spec.shot, &file)?);
    check_keys(&spec, &file)?;
    check_runs_and_paths(&runs, &out, &base.name, &file)?;
    // every scenario is built and checked before anything is written
    let jobs = runs
        .iter()
        .map(|(name, set)| job(name, set, &base, &out, exe, threads, &file))
        .collect::<Result<Vec<Job>>>()?;
    Ok(Plan {
        file,
        base_name: base.name,
        out,
        threads,
        jobs_at_once,
        jobs,
    })
}
