//! The model-choice study (`sticky_lips::paper::choices`): for each modelling choice the
//! paper leaves open, the reference and the variants of that choice side by side, one plot
//! per choice (`plot_choice_NAME.png`):
//!
//! * left, the mechanism: the load on the saliva along the mouth, `Q - 1` (paper eq. 10: the
//!   squared stretch across the layer, minus one) of every saliva element at the last output
//!   frame before the first element breaks (the centre, where the opening starts there), in
//!   the run of the smallest jaw angle at which one breaks: the load before any element has
//!   let go and shifted it; the number is the centre's `Q - 1` over the mean of the two
//!   elements nearest 0.8 w. The steeper the load falls from the centre to the corners, the further the
//!   centre can open before the corners let go;
//! * right, the outcome: the fraction of the lip columns open at the end (1 s: the jaw has
//!   stood still for 0.5 s) against the jaw angle. A partial opening is stable where it lies
//!   strictly between 0 and 1.
//!
//! `measured.json` adds, per variant, C3 at the wide opening (0.15 rad) and the angles at
//! which C5 holds.

use crate::paper::runs::{Model, Run};
use crate::paper::{Context, Output};
use serde_json::{json, Value};
use sticky_lips::claims;
use sticky_lips::error::Result;
use sticky_lips::paper::{choice_angles, choice_name, choices, Variant, CHOICE_REFERENCE};
use sticky_lips::render::plot::{line_plot, LegendPosition, PlotSpec, Series};
use sticky_lips::render::{Image, WHITE};

const PALETTE: [[u8; 3]; 4] = [[40, 40, 40], [200, 60, 60], [40, 120, 200], [60, 170, 80]];

/// The wide opening's angle (rad): C3 is measured there.
const WIDE: f64 = 0.15;

pub fn names(model: Model, quick: bool) -> Vec<String> {
    let mut v = Vec::new();
    if model != Model::Face {
        return v;
    }
    for c in choices(quick) {
        for &a in &choice_angles(quick) {
            v.push(choice_name(c.name, a));
        }
    }
    v
}

/// The load along the mouth at the last output frame before the first saliva element breaks.
struct Load {
    angle: f64,
    time: f64,
    /// Where the first element to break lies (|x| / w).
    first_w: f64,
    /// `(x - centre` (m), `Q - 1)` of each saliva element, by `x`.
    profile: Vec<(f64, f64)>,
    /// The centre's `Q - 1` over that at 0.8 w.
    ratio: f64,
}

/// The saliva elements of `run` with their position along the mouth (m from its centre),
/// by position.
fn saliva_by_x(run: &Run) -> Vec<(f64, u32)> {
    let p = &run.problem;
    let cols = &run.measures.columns;
    let mut v: Vec<(f64, u32)> = p
        .mesh
        .element_sets
        .get("saliva")
        .map(|s| s.as_slice())
        .unwrap_or(&[])
        .iter()
        .map(|&e| {
            let x = p.mesh.elements[e as usize]
                .iter()
                .map(|&n| p.mesh.nodes[n as usize][0])
                .sum::<f64>()
                / 8.0;
            (x - cols.center, e)
        })
        .collect();
    v.sort_by(|a, b| a.0.total_cmp(&b.0));
    v
}

/// [`Load`] of one run, `None` if no saliva element breaks.
fn load(run: &Run, angle: f64) -> Result<Option<Load>> {
    let els = saliva_by_x(run);
    if els.is_empty() {
        return Ok(None);
    }
    let cols = &run.measures.columns;
    let half = 0.5 * (cols.x.last().copied().unwrap_or(0.0) - cols.x[0]);
    let nearest = |pos: f64| {
        (0..els.len())
            .min_by(|&a, &b| (els[a].0 - pos).abs().total_cmp(&(els[b].0 - pos).abs()))
            .unwrap_or(0)
    };
    let centre = nearest(0.0);
    let (left, right) = (nearest(-0.8 * half), nearest(0.8 * half));
    for f in 1..run.measures.frames.len() {
        let broken = run.cell_field(f, "saliva_broken")?;
        if let Some(first) = els.iter().position(|&(_, e)| broken[e as usize] > 0.5) {
            let q = run.cell_field(f - 1, "saliva_Q")?;
            let v: Vec<f64> = els.iter().map(|&(_, e)| q[e as usize] - 1.0).collect();
            return Ok(Some(Load {
                angle,
                time: run.measures.frames[f - 1].time,
                first_w: els[first].0.abs() / half,
                profile: els.iter().zip(&v).map(|(e, q)| (e.0, *q)).collect(),
                ratio: v[centre] / (0.5 * (v[left] + v[right])),
            }));
        }
    }
    Ok(None)
}

struct Measured {
    variant: Variant,
    open: Vec<(f64, f64)>,
    load: Option<Load>,
    json: Value,
}

fn measure(ctx: &Context, c: &Variant) -> Result<Measured> {
    let angles = choice_angles(ctx.opts.quick);
    let mut open = Vec::new();
    let mut load_at = None;
    let mut c5_holds = Vec::new();
    let mut wide = Value::Null;
    let mut per_angle = Vec::new();
    for &a in &angles {
        let r = ctx.run(&choice_name(c.name, a));
        let z = &r.zip;
        open.push((a, z.final_open_fraction));
        if load_at.is_none() {
            load_at = load(r, a)?;
        }
        let c5 = claims::c5(z);
        if c5.holds {
            c5_holds.push(a);
        }
        if (a - WIDE).abs() < 1e-12 {
            let c3 = claims::c3(z);
            let c2 = claims::c2(z);
            wide = json!({"c2": c2, "c3": c3, "spread_10_90_s": z.spread()});
        }
        per_angle.push(json!({
            "angle": a,
            "final_open_fraction": z.final_open_fraction,
            "first_opening": z.first.map(|(t, p)| json!({"time_s": t, "position_w": p})),
            "spread_10_90_s": z.spread(),
            "final_broken": r.measures.frames.last().map(|f| f.broken),
            "c5": c5,
        }));
    }
    let partial: Vec<f64> = open
        .iter()
        .filter(|(_, f)| *f > 0.0 && *f < 1.0)
        .map(|(a, _)| *a)
        .collect();
    let json = json!({
        "variant": c.name,
        "choice": c.choice,
        "what": c.what,
        "load_before_first_break": load_at.as_ref().map(|l| json!({
            "angle": l.angle, "time_s": l.time, "first_break_position_w": l.first_w,
            "centre_over_0.8w": l.ratio,
        })),
        "partly_open_angles": partial,
        "c5_holds_at": c5_holds,
        "wide": wide,
        "angles": per_angle,
    });
    Ok(Measured {
        variant: c.clone(),
        open,
        load: load_at,
        json,
    })
}

fn plot(choice: &str, group: &[&Measured]) -> Image {
    let mut left = PlotSpec::new(
        format!("`{choice}`: load on the saliva before the first element breaks"),
        "position along the mouth (mm)",
        "Q - 1",
    );
    let mut right = PlotSpec::new(
        format!("`{choice}`: open at equilibrium (1 s)"),
        "jaw angle (rad)",
        "fraction of the lip columns open",
    );
    right.y_range = Some((-0.05, 1.05));
    right.legend = LegendPosition::LowerRight;
    left.legend = LegendPosition::LowerRight;
    for (i, m) in group.iter().enumerate() {
        let c = PALETTE[i % PALETTE.len()];
        if let Some(l) = &m.load {
            left.series.push(
                Series::new(
                    format!(
                        "{} ({} rad, {:.2} s, first break {:.2} w): centre / 0.8 w = {:.2}",
                        m.variant.name, l.angle, l.time, l.first_w, l.ratio
                    ),
                    l.profile.iter().map(|&(x, q)| (1e3 * x, q)).collect(),
                )
                .colour(c),
            );
        }
        right.series.push(
            Series::new(m.variant.what, m.open.clone())
                .colour(c)
                .markers(),
        );
    }
    Image::grid(&[line_plot(&left), line_plot(&right)], 2, 10, WHITE)
}

pub fn produce(ctx: &Context) -> Result<Output> {
    if ctx.opts.model != Model::Face {
        return Ok(Output {
            images: Vec::new(),
            measured: json!("the face model's choices only"),
        });
    }
    let all = choices(ctx.opts.quick);
    let measured: Vec<Measured> = all.iter().map(|c| measure(ctx, c)).collect::<Result<_>>()?;
    let reference = measured
        .iter()
        .find(|m| m.variant.name == CHOICE_REFERENCE)
        .expect("the study has a reference");
    let mut groups: Vec<&str> = Vec::new();
    for m in &measured {
        if m.variant.name != CHOICE_REFERENCE && !groups.contains(&m.variant.choice) {
            groups.push(m.variant.choice);
        }
    }
    let mut images = Vec::new();
    for g in &groups {
        let mut members = vec![reference];
        members.extend(measured.iter().filter(|m| m.variant.choice == *g));
        images.push((format!("plot_choice_{g}.png"), plot(g, &members)));
    }
    Ok(Output {
        images,
        measured: json!({ "variants": measured.iter().map(|m| m.json.clone()).collect::<Vec<_>>() }),
    })
}
