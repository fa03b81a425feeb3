//! The load on the saliva along the mouth: `Q - 1` (paper eq. 10: the squared stretch across
//! the layer, minus one) of every saliva element against its position, at several times of
//! the wide opening with breaking switched off (K_glue = 10). Where it is largest the lips
//! must part first; how it falls towards the corners sets how far the opening can run ahead
//! of the jaw.

use crate::paper::look::mm;
use crate::paper::{Context, Output};
use serde_json::json;
use sticky_lips::error::Result;
use sticky_lips::render::plot::{profile_plot, ProfileSpec};

/// Times of the profiles (s).
const TIMES: [f64; 6] = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6];

pub fn produce(ctx: &Context) -> Result<Output> {
    let run = ctx.run("load_profile");
    let p = &run.problem;
    let saliva = p
        .mesh
        .element_sets
        .get("saliva")
        .cloned()
        .unwrap_or_default();
    let cols = &run.measures.columns;
    let half =
        0.5 * (cols.x.last().copied().unwrap_or(0.0) - cols.x.first().copied().unwrap_or(0.0));
    // each saliva element's position along the mouth (mean x of its nodes)
    let mut elems: Vec<(f64, u32)> = saliva
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
    elems.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut spec = ProfileSpec::new(
        "Load on the saliva along the mouth (breaking off): Q - 1",
        "position along the mouth (mm)",
        "Q - 1 (squared stretch across the layer - 1)",
        "time (s)",
    );
    spec.x = elems.iter().map(|e| mm(e.0)).collect();
    let mut profiles = Vec::new();
    let mut ratios = Vec::new();
    for &t in TIMES
        .iter()
        .filter(|&&t| t <= run.times().last().copied().unwrap_or(0.0) + 1e-9)
    {
        let f = run.frame_at(t);
        let q = run.cell_field(f, "saliva_Q")?;
        let v: Vec<f64> = elems.iter().map(|&(_, e)| q[e as usize] - 1.0).collect();
        let at = |pos: f64| {
            let i = (0..elems.len())
                .min_by(|&a, &b| {
                    ((elems[a].0.abs() / half) - pos)
                        .abs()
                        .total_cmp(&((elems[b].0.abs() / half) - pos).abs())
                })
                .unwrap_or(0);
            v[i]
        };
        let centre = at(0.0);
        ratios.push(json!({
            "time_s": run.measures.frames[f].time,
            "centre": centre,
            "max": v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            "centre_over_0.5w": centre / at(0.5),
            "centre_over_0.7w": centre / at(0.7),
            "centre_over_0.9w": centre / at(0.9),
        }));
        profiles.push((run.measures.frames[f].time, v));
    }
    spec.profiles = profiles;
    Ok(Output {
        images: vec![("plot_load_profile.png".into(), profile_plot(&spec))],
        measured: json!({ "q_minus_1": ratios }),
    })
}
