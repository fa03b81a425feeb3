//! `sticky-lips sweep SPEC.toml`: many shots of one scenario, as independent runs.
//!
//! A spec names a base scenario and what changes: a `[grid]` of override values (every
//! combination) and/or a list of `[[shot]]`s (a name and its overrides). Overrides are key
//! paths into the scenario (`"saliva.0.k_glue"`, `"jaw.angle"`, `"mesh.face.resolution"`)
//! with any TOML value, applied by [`sticky_lips::io::scenario::with_overrides`].
//!
//! Each run gets a directory `OUT/NAME/` holding its `scenario.toml` (the base with the
//! overrides, relative file names made absolute so that it runs from there), and one line of
//! `OUT/jobs.txt`: the command that runs it (`sticky-lips run OUT/NAME/scenario.toml --out
//! OUT/NAME --threads T --quiet`). Every run is an ordinary run: it can go to any machine
//! that sees the directory, in any order (GNU parallel across hosts, a Slurm job array; the
//! README says how). Locally, `jobs` runs go at once, each a process of this binary; when
//! they are done `OUT/sweep.json` lists every run with its overrides, exit status, wall time
//! and, for mouth models, when the lips first opened and how many saliva elements broke.
//! `--plan` writes the directories and the job list only.

use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use sticky_lips::error::{Error, Location, Result};
use sticky_lips::io::scenario::with_overrides;

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
#[derive(Clone, Debug, serde::Serialize)]
struct Job {
    name: String,
    overrides: BTreeMap<String, toml::Value>,
    dir: PathBuf,
    command: Vec<String>,
}

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

pub struct Options<'a> {
    pub spec: &'a Path,
    pub plan_only: bool,
}

pub fn sweep(o: &Options) -> Result<()> {
    let file = o.spec.display().to_string();
    let text = std::fs::read_to_string(o.spec).map_err(|e| Error::io(o.spec, e))?;
    let spec: Spec = toml::from_str(&text).map_err(|e| {
        let line = e.span().map(|r| text[..r.start].matches('\n').count() + 1);
        Error::input(
            &file,
            line.map_or(Location::None, Location::Line),
            e.message(),
        )
    })?;
    let spec_dir = o.spec.parent().map(Path::to_path_buf).unwrap_or_default();
    let spec_dir = std::fs::canonicalize(if spec_dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        &spec_dir
    })
    .map_err(|e| Error::io(&spec_dir, e))?;
    // the base scenario's text and the directory its relative files are in
    let (base_text, base_name, base_dir) = match &spec.base {
        Some(b) => {
            let p = spec_dir.join(b);
            let t = std::fs::read_to_string(&p)
                .map_err(|e| err(&file, "base", format!("{}: {e}", p.display())))?;
            let dir = p.parent().map(Path::to_path_buf).unwrap_or_default();
            (t, p.display().to_string(), dir)
        }
        None => {
            use sticky_lips::paper::{scenario_of, spec as paper_spec, Model};
            let run = paper_spec(Model::Face, true, "fig4_sticky").expect("the paper's run");
            let (t, _) = scenario_of(Model::Face, true, &run, Path::new("default job"))?;
            (t, "the default job".to_string(), spec_dir.clone())
        }
    };
    let out = match &spec.out {
        Some(d) => spec_dir.join(d),
        None => std::env::current_dir()
            .map_err(|e| Error::io(".", e))?
            .join("out")
            .join(
                o.spec
                    .file_stem()
                    .map_or("sweep".into(), |s| s.to_string_lossy().to_string()),
            ),
    };
    let threads = spec.threads.unwrap_or(1);
    if threads == 0 {
        return Err(err(&file, "threads", "must be at least 1"));
    }
    let max = sticky_lips::io::args::max_threads();
    if threads > max {
        return Err(err(
            &file,
            "threads",
            format!("{threads} per run: at most {max} (four per CPU of this machine)"),
        ));
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let jobs_at_once = spec.jobs.unwrap_or((cores / threads).max(1));
    if jobs_at_once == 0 {
        return Err(err(&file, "jobs", "must be at least 1"));
    }
    // the runs: the grid's combinations, then the shots
    let mut runs: Vec<(String, BTreeMap<String, toml::Value>)> = Vec::new();
    let keys: Vec<&String> = spec.grid.keys().collect();
    for k in &keys {
        if spec.grid[*k].is_empty() {
            return Err(err(&file, format!("grid.{k}"), "lists no values"));
        }
    }
    if !keys.is_empty() {
        let sizes: Vec<usize> = keys.iter().map(|k| spec.grid[*k].len()).collect();
        // checked: a product that overflows is more runs than allowed, not a small number
        let total = sizes
            .iter()
            .try_fold(1usize, |a, &n| a.checked_mul(n))
            .filter(|&t| t <= 100_000);
        let Some(total) = total else {
            let shape = sizes
                .iter()
                .map(|n| n.to_string())
                .collect::<Vec<_>>()
                .join(" x ");
            return Err(err(
                &file,
                "grid",
                format!("gives {shape} runs (at most 100000)"),
            ));
        };
        if total > 100_000 {
            return Err(err(
                &file,
                "grid",
                format!("gives {total} runs (at most 100000)"),
            ));
        }
        for i in 0..total {
            let mut rest = i;
            let mut set = BTreeMap::new();
            let mut name = Vec::new();
            for (k, n) in keys.iter().zip(&sizes).rev() {
                let v = spec.grid[*k][rest % n].clone();
                rest /= n;
                let short = k.rsplit('.').next().unwrap_or(k);
                name.push(format!("{short}-{}", tag(&v)));
                set.insert((*k).clone(), v);
            }
            name.reverse();
            runs.push((format!("{i:03}_{}", name.join("_")), set));
        }
    }
    for (i, s) in spec.shot.iter().enumerate() {
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
                &file,
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
                &file,
                format!("shot[{i}].name"),
                format!("`{}` is a file of the sweep itself", s.name),
            ));
        }
        runs.push((s.name.clone(), s.set.clone()));
    }
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
                &file,
                field,
                "a key is a path of names and indices: A-Z a-z 0-9 _ - joined by .",
            ));
        }
    }
    if runs.is_empty() {
        return Err(err(&file, "grid", "the spec has neither a grid nor shots"));
    }
    let mut seen = std::collections::BTreeSet::new();
    for (n, _) in &runs {
        if !seen.insert(n.clone()) {
            return Err(err(&file, "shot", format!("two runs are called `{n}`")));
        }
    }
    // paths go into job lines and comments one line each: no control characters
    for (field, path) in [
        ("out", out.display().to_string()),
        ("base", base_name.clone()),
        ("spec", file.clone()),
    ] {
        if path.chars().any(char::is_control) {
            return Err(err(
                &file,
                field,
                format!("{path:?} holds a control character (a newline?)"),
            ));
        }
    }
    // every scenario is built and checked before anything is written
    let exe = std::env::current_exe().map_err(|e| Error::io("sticky-lips", e))?;
    let mut jobs = Vec::new();
    let mut texts = Vec::new();
    for (name, set) in &runs {
        let dir = out.join(name);
        let refs: Vec<(&str, toml::Value)> =
            set.iter().map(|(k, v)| (k.as_str(), v.clone())).collect();
        let t = with_overrides(&base_text, &base_name, &refs)?;
        let mut doc: toml::Value = toml::from_str(&t)
            .map_err(|e| Error::input(&base_name, Location::None, e.message()))?;
        absolute_files(&mut doc, &base_dir);
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
        sticky_lips::io::scenario::parse(&t, &path)
            .map_err(|e| err(&file, format!("run {name}"), e.to_string()))?;
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
        jobs.push(Job {
            name: name.clone(),
            overrides: set.clone(),
            dir,
            command,
        });
        texts.push(t);
    }
    for (j, t) in jobs.iter().zip(&texts) {
        std::fs::create_dir_all(&j.dir).map_err(|e| Error::io(&j.dir, e))?;
        let p = j.dir.join("scenario.toml");
        sticky_lips::io::atomic::write_atomic(&p, t.as_bytes()).map_err(|e| Error::io(&p, e))?;
    }
    let list: String = jobs
        .iter()
        .map(|j| {
            j.command
                .iter()
                .map(|a| shell_quote(a))
                .collect::<Vec<_>>()
                .join(" ")
                + "\n"
        })
        .collect();
    let jl = out.join("jobs.txt");
    sticky_lips::io::atomic::write_atomic(&jl, list.as_bytes()).map_err(|e| Error::io(&jl, e))?;
    println!(
        "sweep: {} runs of {base_name} in {}; job list {}",
        jobs.len(),
        out.display(),
        jl.display()
    );
    if o.plan_only {
        return Ok(());
    }
    let results = run_local(&jobs, jobs_at_once)?;
    let failed = results.iter().filter(|r| r.status != Some(0)).count();
    let js = out.join("sweep.json");
    let json = serde_json::to_vec_pretty(&serde_json::json!({
        "spec": file,
        "base": base_name,
        "jobs_at_once": jobs_at_once,
        "threads_per_run": threads,
        "runs": results,
    }))
    .expect("the sweep summary serialises");
    sticky_lips::io::atomic::write_atomic(&js, &json).map_err(|e| Error::io(&js, e))?;
    println!(
        "sweep: {} of {} runs done, {failed} failed; {}",
        results.len() - failed,
        results.len(),
        js.display()
    );
    if failed > 0 {
        return Err(Error::input(
            file,
            Location::None,
            format!(
                "{failed} runs failed (their stderr is in RUN/stderr.txt; sweep.json lists them)"
            ),
        ));
    }
    Ok(())
}

/// The files a sweep writes beside its runs.
const RESERVED: [&str; 2] = ["jobs.txt", "sweep.json"];

fn shell_quote(s: &str) -> String {
    if !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "/._-=+,:".contains(c))
    {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', "'\\''"))
    }
}

#[derive(serde::Serialize)]
struct Outcome {
    name: String,
    overrides: BTreeMap<String, toml::Value>,
    dir: PathBuf,
    status: Option<i32>,
    wall_seconds: f64,
    /// For mouth models: when and where (x, m) the lips first opened.
    first_opening: Option<(f64, f64)>,
    broken_saliva: Option<usize>,
}

/// Runs the jobs, `at_once` processes at a time, in the list's order; each one's stdout and
/// stderr go to its directory.
fn run_local(jobs: &[Job], at_once: usize) -> Result<Vec<Outcome>> {
    use std::process::{Command, Stdio};
    let mut results: Vec<Option<Outcome>> = (0..jobs.len()).map(|_| None).collect();
    let mut running: Vec<(usize, std::process::Child, std::time::Instant)> = Vec::new();
    let mut next = 0;
    while next < jobs.len() || !running.is_empty() {
        while next < jobs.len() && running.len() < at_once {
            let j = &jobs[next];
            let log = |n: &str| {
                let p = j.dir.join(n);
                std::fs::File::create(&p).map_err(|e| Error::io(&p, e))
            };
            let child = Command::new(&j.command[0])
                .args(&j.command[1..])
                .stdin(Stdio::null())
                .stdout(Stdio::from(log("stdout.txt")?))
                .stderr(Stdio::from(log("stderr.txt")?))
                .spawn()
                .map_err(|e| Error::io(&j.command[0], e))?;
            running.push((next, child, std::time::Instant::now()));
            next += 1;
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
        let mut k = 0;
        while k < running.len() {
            let done = running[k]
                .1
                .try_wait()
                .map_err(|e| Error::io(&jobs[running[k].0].dir, e))?;
            match done {
                Some(st) => {
                    let (i, _, t0) = running.swap_remove(k);
                    let j = &jobs[i];
                    let measures: Option<serde_json::Value> =
                        std::fs::read(j.dir.join("measures.json"))
                            .ok()
                            .and_then(|b| serde_json::from_slice(&b).ok());
                    let summary: Option<serde_json::Value> =
                        std::fs::read(j.dir.join("summary.json"))
                            .ok()
                            .and_then(|b| serde_json::from_slice(&b).ok());
                    let o = Outcome {
                        name: j.name.clone(),
                        overrides: j.overrides.clone(),
                        dir: j.dir.clone(),
                        status: st.code(),
                        wall_seconds: t0.elapsed().as_secs_f64(),
                        first_opening: measures
                            .and_then(|m| serde_json::from_value(m["first_opening"].clone()).ok())
                            .flatten(),
                        broken_saliva: summary.and_then(|s| {
                            s["broken_saliva"]
                                .as_array()
                                .and_then(|a| a.last())
                                .and_then(|b| b.as_u64())
                                .map(|b| b as usize)
                        }),
                    };
                    println!(
                        "sweep: {} {} ({:.1} s)",
                        o.name,
                        if o.status == Some(0) {
                            "done"
                        } else {
                            "FAILED"
                        },
                        o.wall_seconds
                    );
                    results[i] = Some(o);
                }
                None => k += 1,
            }
        }
    }
    Ok(results
        .into_iter()
        .map(|r| r.expect("every job ran"))
        .collect())
}
