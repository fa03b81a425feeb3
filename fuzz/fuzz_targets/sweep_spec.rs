//! A sweep spec (`sticky-lips sweep SPEC.toml`) as `sweep::plan` reads it: the spec parsed,
//! its grid and shots expanded, names, keys and paths checked, and every run's scenario made
//! from the base and parsed, as the command does before writing anything. The spec is taken
//! to lie in `fuzz/fixtures/`, and its base must be `block.toml` there (a small block,
//! quick to parse): specs naming another base or none (the default job, the face at the
//! quick resolution, a second or more per run) are skipped, and so are grids of more than
//! `MAX_RUNS` runs that the 100000 limit would let through (each run's scenario is parsed;
//! larger grids are refused by the plan and are fed to it).
//!
//! Must hold: an error or a plan, never a panic, an abort or a hang; a plan has at least one
//! run, every run a distinct plain name, a directory inside `out` and a scenario that parses.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;
#[path = "common.rs"]
mod common;

/// The most runs of one input: the block's scenario parses in well under a millisecond, so
/// this keeps an input far below the 10 s hang limit.
const MAX_RUNS: usize = 200;

fn spec_path() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/spec.toml"))
}

/// Whether the spec is one this target plans: its base is `block.toml`, and it has at most
/// `MAX_RUNS` runs or more than the plan allows. Text that is not a TOML table is planned
/// (the plan refuses it).
fn wanted(text: &str) -> bool {
    let Ok(t) = text.parse::<toml::Table>() else {
        return true;
    };
    if t.get("base").and_then(|b| b.as_str()) != Some("block.toml") {
        return false;
    }
    let grid = match t.get("grid").and_then(|g| g.as_table()) {
        Some(g) => g
            .values()
            .map(|v| v.as_array().map_or(1, |a| a.len().max(1)))
            .try_fold(1usize, |a, n| a.checked_mul(n)),
        None => Some(0),
    };
    let shots = t
        .get("shot")
        .and_then(|s| s.as_array())
        .map_or(0, |s| s.len());
    match grid {
        Some(g) => g + shots <= MAX_RUNS || g > sticky_lips::sweep::MAX_RUNS,
        None => true,
    }
}

fuzz_target!(|data: &[u8]| {
    let Some(text) = common::text(data) else {
        return;
    };
    if !wanted(text) {
        return;
    }
    let Ok(plan) = sticky_lips::sweep::plan(text, spec_path(), Path::new("/fuzz/sticky-lips"))
    else {
        return;
    };
    assert!(!plan.jobs.is_empty());
    let mut names = std::collections::BTreeSet::new();
    for j in &plan.jobs {
        assert!(names.insert(j.name.as_str()), "two runs called {}", j.name);
        assert!(
            !j.name.is_empty() && !j.name.contains(['/', '\n', '\\']),
            "{:?}",
            j.name
        );
        assert!(
            j.dir.starts_with(&plan.out) && j.dir != plan.out,
            "{:?}",
            j.dir
        );
        let path = j.dir.join("scenario.toml");
        assert!(sticky_lips::io::scenario::parse(&j.scenario, &path).is_ok());
    }
});
