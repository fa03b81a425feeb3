//! Fig. 6: the blend-shape baseline (paper eq. 1, `x' = X + w B`) at the slight opening:
//! on the face, `B` is the artist-made `mouth-open` target of the MakeHuman head, with the
//! weight `w` that opens the lips' centre as far as the slight opening without stickiness
//! does at equilibrium; on the procedural mouth (no artist's target), `B` is the wide
//! opening's final displacement and `w` the ratio of the jaw angles. Every saliva element
//! is drawn as broken: a blend shape has no saliva that holds.

use crate::paper::look::{displaced, element_codes};
use crate::paper::runs::Model;
use crate::paper::{Context, Output};
use serde_json::json;
use sticky_lips::error::{Error, Location, Result};
use sticky_lips::measures::lip_gap;
use sticky_lips::render::Image;

/// The target's name in the MakeHuman face.
pub const TARGET: &str = "mouth-open";

/// The blend-shape displacement of every node of the slight runs' mesh, its weight, and
/// where `B` came from.
pub fn blend(ctx: &Context) -> Result<(Vec<[f64; 3]>, f64, String)> {
    let slight = ctx.run("fig7_dry");
    let p = &slight.problem;
    let cols = &slight.measures.columns;
    let (b, source): (Vec<[f64; 3]>, String) = match ctx.opts.model {
        Model::Face => {
            let model = crate::paper::runs::face_model(ctx.opts)?;
            let b = model.target_displacement(TARGET).ok_or_else(|| {
                Error::input(
                    "assets/makehuman/face.json",
                    Location::Field("targets".into()),
                    "no mouth-open target",
                )
            })?;
            (b, format!("the MakeHuman `{TARGET}` target (eq. 1)"))
        }
        Model::Procedural => {
            let wide = ctx.run("fig4_dry");
            (
                wide.displacement(wide.last())?,
                "the wide opening's final displacement (eq. 1; no artist's target)".into(),
            )
        }
    };
    let centre = cols.upper.len() / 2;
    let w = match ctx.opts.model {
        Model::Face => {
            let g1 = lip_gap(&p.mesh.nodes, &b, cols)[centre];
            let goal = slight.measures.frames[slight.last()].gap[centre];
            if g1 > 0.0 {
                goal / g1
            } else {
                0.0
            }
        }
        Model::Procedural => slight.angle() / ctx.run("fig4_dry").angle(),
    };
    Ok((b.iter().map(|v| v.map(|c| w * c)).collect(), w, source))
}

/// The blend's rendering: the slight runs' mesh displaced by the blend, saliva hidden.
pub fn picture(ctx: &Context, u: &[[f64; 3]], w: u32, h: u32) -> Result<Image> {
    let slight = ctx.run("fig7_dry");
    let hidden: Vec<bool> = element_codes(&slight.problem)
        .iter()
        .map(|&c| c == 2)
        .collect();
    displaced(slight, ctx.skin.as_ref(), u, &hidden, w, h)
}

pub fn produce(ctx: &Context) -> Result<Output> {
    let (u, weight, source) = blend(ctx)?;
    let slight = ctx.run("fig7_dry");
    let gap = lip_gap(&slight.problem.mesh.nodes, &u, &slight.measures.columns);
    let z = sticky_lips::measures::ZIP_THRESHOLD;
    let open = gap.iter().filter(|g| **g > z).count() as f64 / gap.len().max(1) as f64;
    Ok(Output {
        images: vec![(
            "fig6_blend_baseline.png".into(),
            picture(ctx, &u, 900, 560)?,
        )],
        measured: json!({
            "blend_shape": source,
            "weight": weight,
            "max_gap_m": gap.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            "open_fraction_all_columns": open,
            "corner_gaps_m": [gap.first(), gap.last()],
        }),
    })
}
