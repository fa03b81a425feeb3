//! `sticky-lips paper`: the runs behind the paper's figures, one producer per figure, the
//! claims as numbers, Table 1 as used and `measured.json`.
//!
//! The library computes (runs, measures, claims, pixel buffers); this module decides which
//! runs make which figure and writes the files. [`figures::TABLE`] lists every figure with
//! the runs it needs and its producer; `--only NAME` makes just those figures (and only
//! their runs).

mod figures;
pub mod look;
mod runs;

pub use runs::Model;

use crate::progress::Progress;
use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;
use sticky_lips::driver::Backend;
use sticky_lips::error::{Error, Location, Result};
use sticky_lips::render::{save_png, Image};
use sticky_lips::Precision;

pub struct PaperOptions {
    pub out: PathBuf,
    pub quick: bool,
    pub threads: usize,
    pub backend: Backend,
    pub precision: Precision,
    pub progress: Progress,
    /// Reuse a run whose outputs are already complete (same scenario, same step count): only
    /// the figures are redrawn.
    pub reuse: bool,
    pub model: Model,
    /// Make only these figures (names of [`figures::TABLE`]); empty: all.
    pub only: Vec<String>,
    /// The runs' time step where not Table 1's (`--dt`).
    pub dt: Option<sticky_lips::io::scenario::DtChoice>,
}

/// What a figure producer has: the options, the finished runs it asked for, the model's
/// chosen parameters, the CC0 lips mask and the skin texture.
pub struct Context<'a> {
    pub opts: &'a PaperOptions,
    pub runs: &'a BTreeMap<String, runs::Run>,
    pub choice: runs::Choice,
    pub lips_mask: Option<Image>,
    /// The skin texture made from the masks (the face's figures are rendered through it).
    pub skin: Option<Image>,
}

impl Context<'_> {
    pub fn run(&self, name: &str) -> &runs::Run {
        self.runs
            .get(name)
            .unwrap_or_else(|| panic!("figure asked for run {name} without declaring it"))
    }
}

/// What a producer makes: images to write and numbers for `measured.json`.
pub struct Output {
    pub images: Vec<(String, Image)>,
    pub measured: Value,
}

pub fn paper(opts: &PaperOptions) -> Result<()> {
    let t_all = Instant::now();
    let out = &opts.out;
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    let (selected, needed) = selection(opts)?;
    let done = make_runs(opts, &needed)?;
    let (face_mask, lips_mask) = look::makehuman_masks();
    let skin = match (opts.model, &face_mask, &lips_mask) {
        (Model::Face, Some(f), Some(l)) => Some(look::face_skin(f, l)),
        _ => None,
    };
    let ctx = Context {
        opts,
        runs: &done,
        choice: opts.model.choice(),
        lips_mask,
        skin,
    };
    let (written, per_figure) = draw_figures(&ctx, &selected)?;
    let claims = claims_of(&done)?;
    if let Some(s) = done.get("fig4_sticky") {
        write_table1(opts, &ctx, s)?;
    }
    let m = json!({
        "model": opts.model.name(),
        "quick": opts.quick,
        "only": if opts.only.is_empty() { Value::Null } else { json!(opts.only) },
        "reused_runs": opts.reuse,
        "choice": ctx.choice,
        "threads": opts.threads,
        "wall_time_s": t_all.elapsed().as_secs_f64(),
        "figures": written,
        "claims": claims,
        "measured": per_figure,
        "runs": runs_json(&done),
    });
    let mpath = out.join("measured.json");
    sticky_lips::io::atomic::write_atomic(
        &mpath,
        serde_json::to_string_pretty(&m).expect("json").as_bytes(),
    )
    .map_err(|e| Error::io(&mpath, e))?;
    eprintln!(
        "paper: {} figures, table1.md and measured.json written to {} in {:.1} s",
        written.len(),
        out.display(),
        t_all.elapsed().as_secs_f64()
    );
    Ok(())
}

/// The figures asked for (`--only`, else all) and the runs they need (with the claims' runs
/// for a full set), in the paper's order.
fn selection(opts: &PaperOptions) -> Result<(Vec<&'static figures::Figure>, Vec<String>)> {
    let known: Vec<&str> = figures::TABLE.iter().map(|f| f.name).collect();
    for o in &opts.only {
        if !known.contains(&o.as_str()) {
            return Err(Error::input(
                "command line",
                Location::Field("--only".into()),
                format!("no figure `{o}` (figures: {})", known.join(", ")),
            ));
        }
    }
    let selected: Vec<&figures::Figure> = figures::TABLE
        .iter()
        .filter(|f| opts.only.is_empty() || opts.only.iter().any(|o| o == f.name))
        .collect();
    // the runs: those the selected figures need, and the claims' runs for a full set
    let mut needed: Vec<String> = Vec::new();
    for f in &selected {
        for r in (f.runs)(opts.model, opts.quick) {
            if !needed.contains(&r) {
                needed.push(r);
            }
        }
    }
    if opts.only.is_empty() {
        for r in ["fig4_dry", "fig4_sticky", "fig7_dry", "fig7_sticky"] {
            if !needed.iter().any(|n| n == r) {
                needed.push(r.into());
            }
        }
    }
    Ok((selected, needed))
}

/// The runs named in `needed`, made (or reused) in the paper's order.
fn make_runs(opts: &PaperOptions, needed: &[String]) -> Result<BTreeMap<String, runs::Run>> {
    let all = runs::all(opts.model, opts.quick);
    let mut done: BTreeMap<String, runs::Run> = BTreeMap::new();
    for spec in all.iter().filter(|s| needed.contains(&s.name)) {
        crate::progress::cancel_token().check(|| {
            format!(
                "paper stopped before run {} ({} of {} runs done; each finished run's files are complete)",
                spec.name,
                done.len(),
                needed.len()
            )
        })?;
        let r = runs::run(opts, spec)?;
        done.insert(spec.name.clone(), r);
    }
    Ok(done)
}

/// Draws the `selected` figures: the files written and each figure's measured numbers.
fn draw_figures(
    ctx: &Context,
    selected: &[&figures::Figure],
) -> Result<(Vec<String>, serde_json::Map<String, Value>)> {
    let out = &ctx.opts.out;
    let mut written = Vec::new();
    let mut per_figure = serde_json::Map::new();
    for f in selected {
        crate::progress::cancel_token().check(|| {
            format!(
                "paper stopped before figure {} (the runs are complete; `paper --reuse` draws the figures from them)",
                f.name
            )
        })?;
        let t0 = Instant::now();
        let o = (f.produce)(ctx)?;
        for (name, img) in &o.images {
            save_png(&out.join(name), img)?;
            written.push(name.clone());
        }
        eprintln!(
            "paper: {} ({}): {} in {:.1} s",
            f.name,
            f.what,
            o.images
                .iter()
                .map(|i| i.0.as_str())
                .collect::<Vec<_>>()
                .join(", "),
            t0.elapsed().as_secs_f64()
        );
        per_figure.insert(f.name.into(), o.measured);
    }

    Ok((written, per_figure))
}

/// The paper's claims (`sticky_lips::claims`), where the four runs that carry them were made;
/// each printed with its verdict.
fn claims_of(done: &BTreeMap<String, runs::Run>) -> Result<Vec<sticky_lips::claims::Claim>> {
    let claims: Vec<sticky_lips::claims::Claim> =
        if ["fig4_dry", "fig4_sticky", "fig7_dry", "fig7_sticky"]
            .iter()
            .all(|r| done.contains_key(*r))
        {
            let (d4, s4) = (&done["fig4_dry"], &done["fig4_sticky"]);
            let (d7, s7) = (&done["fig7_dry"], &done["fig7_sticky"]);
            use sticky_lips::claims::*;
            vec![
                c1(&d4.zip),
                c2(&s4.zip),
                c3(&s4.zip),
                c4(&s4.zip),
                c5(&s7.zip),
                c6(&d7.zip),
                c7(&d4.displacement(d4.last())?, &s4.displacement(s4.last())?),
            ]
        } else {
            Vec::new()
        };
    for c in &claims {
        eprintln!(
            "paper: {} (Fig. {}): {} -- {}: {}",
            c.id,
            c.figure,
            c.criterion,
            if c.holds { "holds" } else { "DOES NOT HOLD" },
            c.measured
        );
    }

    Ok(claims)
}

/// `table1.md`: Table 1 as the run `s` used it.
fn write_table1(opts: &PaperOptions, ctx: &Context, s: &runs::Run) -> Result<()> {
    let out = &opts.out;
    let p = &s.problem;
    let (tissue, saliva) = (&p.materials[0], &p.materials[1]);
    let sp = &p.physics.saliva[0].params;
    let table = format!(
        "# Table 1 as used\n\n`paper/scenarios/table1.toml` ({}{}); the runs change only their overrides \
         (`OUT/runs/NAME/scenario.toml`).\n\n| property | value |\n|---|---|\n\
         | time step | {} s |\n| total time simulated | {} s |\n| hourglass coefficient | {} |\n| damping coefficient | {} 1/s |\n\
         | soft tissue | neo-Hookean, mu = {} Pa, K = {} Pa, rho = {} kg/m^3 |\n| saliva | neo-Hookean breaking, mu = {} Pa, K = {} Pa, rho = {} kg/m^3 |\n\
         | initial moisture 0M | {:?} um |\n| critical moisture Mc | {} um |\n| evaporation rate | {:?} um/s |\n\
         | max glue strength K_glue | {} (chosen: paper/README.md) |\n| force decay of a broken element | {:?} (eq. 11) |\n\
         | jaw | {} rad wide, {} rad slight, smooth step over 0.5 s |\n| mesh | {} hexahedra, {} nodes |\n",
        opts.model.name(),
        if opts.quick { ", --quick: coarse model, shorter run" } else { "" },
        p.time.dt,
        p.time.total_time,
        p.numerics.hourglass_kappa,
        p.numerics.damping,
        tissue.law.mu,
        tissue.law.bulk,
        tissue.density,
        saliva.law.mu,
        saliva.law.bulk,
        saliva.density,
        sp.initial_moisture,
        sp.critical_moisture,
        sp.evaporation.rates,
        sp.k_glue,
        sp.decay,
        ctx.choice.wide_angle,
        ctx.choice.slight_angle,
        p.mesh.elements.len(),
        p.mesh.nodes.len()
    );
    let tpath = out.join("table1.md");
    sticky_lips::io::atomic::write_atomic(&tpath, table.as_bytes())
        .map_err(|e| Error::io(&tpath, e))?;
    Ok(())
}

/// `measured.json`'s `runs`: each run's size, time and zip front.
fn runs_json(done: &BTreeMap<String, runs::Run>) -> Vec<Value> {
    done
        .values()
        .map(|r| {
            let last = r.measures.frames.last();
            let z = &r.zip;
            json!({
                "run": r.name,
                "what": r.what,
                "hexahedra": r.problem.mesh.elements.len(),
                "nodes": r.problem.mesh.nodes.len(),
                "steps": r.summary.steps,
                "wall_time_s": r.wall,
                "k_glue": r.k_glue(),
                "jaw_angle_rad": r.angle(),
                "zip": {
                    "threshold_m": z.threshold,
                    "first_opening": z.first.map(|(t, p)| json!({"time_s": t, "position_w": p})),
                    "t10_s": z.t10,
                    "t90_s": z.t90,
                    "spread_10_90_s": z.spread(),
                    "spearman": z.spearman,
                    "final_open_fraction": z.final_open_fraction,
                },
                "final_max_gap_m": last.map(|f| f.gap.iter().copied().fold(f64::NEG_INFINITY, f64::max)),
                "final_broken": last.map(|f| f.broken),
                "saliva_elements": r.summary.saliva_elements,
            })
        })
        .collect()
}
