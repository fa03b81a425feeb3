//! `sticky-lips sweep SPEC.toml`: many shots of one scenario, as independent runs.
//!
//! The spec (a base scenario, a `[grid]` of override values and/or `[[shot]]`s) is read and
//! checked, and every run's scenario built, by [`sticky_lips::sweep::plan`], before anything
//! is written; this command writes the plan and runs it.
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

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use sticky_lips::error::{Error, Location, Result};
use sticky_lips::sweep::Job;

pub struct Options<'a> {
    pub spec: &'a Path,
    pub plan_only: bool,
    /// The runs' time step (`--dt`), before the spec's.
    pub dt: Option<sticky_lips::io::scenario::DtChoice>,
}

pub fn sweep(o: &Options) -> Result<()> {
    let text = std::fs::read_to_string(o.spec).map_err(|e| Error::io(o.spec, e))?;
    // the executable the job lines run (asked before the plan, which puts it in them)
    let exe = std::env::current_exe().map_err(|e| Error::io("sticky-lips", e))?;
    let plan = sticky_lips::sweep::plan_with_dt(&text, o.spec, &exe, o.dt)?;
    let (file, out, base_name, jobs) = (&plan.file, &plan.out, &plan.base_name, &plan.jobs);
    let (threads, jobs_at_once) = (plan.threads, plan.jobs_at_once);
    for j in jobs {
        std::fs::create_dir_all(&j.dir).map_err(|e| Error::io(&j.dir, e))?;
        let p = j.dir.join("scenario.toml");
        sticky_lips::io::atomic::write_atomic(&p, j.scenario.as_bytes())
            .map_err(|e| Error::io(&p, e))?;
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
    let all = run_local(jobs, jobs_at_once)?;
    let not_started: Vec<&str> = jobs
        .iter()
        .zip(&all)
        .filter(|(_, r)| r.is_none())
        .map(|(j, _)| j.name.as_str())
        .collect();
    let results: Vec<Outcome> = all.into_iter().flatten().collect();
    let failed = results.iter().filter(|r| r.status != Some(0)).count();
    let js = out.join("sweep.json");
    let stopped = crate::progress::cancel_token().is_cancelled();
    let json = serde_json::to_vec_pretty(&serde_json::json!({
        "spec": file,
        "base": base_name,
        "jobs_at_once": jobs_at_once,
        "threads_per_run": threads,
        "runs": results,
        "interrupted": stopped,
        "not_started": not_started,
    }))
    .expect("the sweep summary serialises");
    sticky_lips::io::atomic::write_atomic(&js, &json).map_err(|e| Error::io(&js, e))?;
    if stopped {
        return Err(Error::Cancelled(format!(
            "sweep stopped: {} runs ended ({} of them interrupted or failed), {} not started; {} lists them",
            results.len(),
            failed,
            not_started.len(),
            js.display()
        )));
    }
    println!(
        "sweep: {} of {} runs done, {failed} failed; {}",
        results.len() - failed,
        results.len(),
        js.display()
    );
    if failed > 0 {
        return Err(Error::input(
            file.as_str(),
            Location::None,
            format!(
                "{failed} runs failed (their stderr is in RUN/stderr.txt; sweep.json lists them)"
            ),
        ));
    }
    Ok(())
}

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
/// stderr go to its directory. On SIGINT/SIGTERM no further job starts and the running ones
/// get SIGTERM (each stops as an interrupted run); the jobs never started are `None`.
fn run_local(jobs: &[Job], at_once: usize) -> Result<Vec<Option<Outcome>>> {
    use std::process::{Command, Stdio};
    let mut results: Vec<Option<Outcome>> = (0..jobs.len()).map(|_| None).collect();
    let mut running: Vec<(usize, std::process::Child, std::time::Instant)> = Vec::new();
    let mut next = 0;
    let mut forwarded = false;
    while (next < jobs.len() && !forwarded) || !running.is_empty() {
        if crate::progress::cancel_token().is_cancelled() && !forwarded {
            forwarded = true;
            #[cfg(unix)]
            for (_, child, _) in &running {
                // SAFETY: kill(2) on a child this process started and has not reaped
                unsafe {
                    libc::kill(child.id() as libc::pid_t, libc::SIGTERM);
                }
            }
        }
        while !forwarded && next < jobs.len() && running.len() < at_once {
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
                    let run = sticky_lips::run_dir::RunDir::new(&j.dir);
                    let o = Outcome {
                        name: j.name.clone(),
                        overrides: j.overrides.clone(),
                        dir: j.dir.clone(),
                        status: st.code(),
                        wall_seconds: t0.elapsed().as_secs_f64(),
                        first_opening: run.measures().ok().and_then(|m| m.first_opening),
                        broken_saliva: run
                            .summary()
                            .ok()
                            .and_then(|s| s.broken_saliva.last().copied()),
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
    Ok(results)
}
