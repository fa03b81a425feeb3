//! Figs. 5-7: a slight opening at equilibrium: the blend-shape baseline (Fig. 6), without
//! stickiness and with it (Fig. 7), and their lip gap profiles.

use super::fig6;
use crate::paper::look::{mm, picture, GREEN, RED, WHITE};
use crate::paper::{Context, Output};
use serde_json::json;
use sticky_lips::error::Result;
use sticky_lips::measures::lip_gap;
use sticky_lips::render::plot::{line_plot, PlotSpec, Series};
use sticky_lips::render::{GridLabels, Image};

pub fn produce(ctx: &Context) -> Result<Output> {
    let (dry, sticky) = (ctx.run("fig7_dry"), ctx.run("fig7_sticky"));
    let (u, _, _) = fig6::blend(ctx)?;
    let (w, h) = (640, 400);
    let panels = vec![
        fig6::picture(ctx, &u, w, h)?,
        picture(dry, ctx.skin.as_ref(), dry.last(), w, h)?,
        picture(sticky, ctx.skin.as_ref(), sticky.last(), w, h)?,
    ];
    let labels = GridLabels {
        title: Some("Figs. 5-7: a slight opening at equilibrium"),
        column_titles: &[
            "blend shape (Fig. 6)",
            "without stickiness",
            "with stickiness (Fig. 7)",
        ],
        ..Default::default()
    };
    let cols = &dry.measures.columns;
    let xs: Vec<f64> = cols.x.iter().map(|x| mm(x - cols.center)).collect();
    let prof = |name: &str, g: &[f64], c: [u8; 3]| {
        Series::new(name, xs.iter().zip(g).map(|(x, g)| (*x, mm(*g))).collect()).colour(c)
    };
    let gb = lip_gap(&dry.problem.mesh.nodes, &u, cols);
    let mut spec = PlotSpec::new(
        "Figs. 5-7: lip gap at a slight opening (equilibrium)",
        "position along the mouth (mm)",
        "lip gap (mm)",
    );
    spec.series = vec![
        prof("blend shape", &gb, [120, 120, 120]).dashed(),
        prof(
            "without stickiness",
            &dry.measures.frames[dry.last()].gap,
            RED,
        ),
        prof(
            "with stickiness",
            &sticky.measures.frames[sticky.last()].gap,
            GREEN,
        ),
    ];
    Ok(Output {
        images: vec![
            (
                "fig7_slight_opening.png".into(),
                Image::grid_labelled(&panels, 3, 8, WHITE, &labels),
            ),
            ("fig7_gap_profiles.png".into(), line_plot(&spec)),
        ],
        measured: json!({
            "dry_final_open_fraction": dry.zip.final_open_fraction,
            "sticky_final_open_fraction": sticky.zip.final_open_fraction,
            "sticky_final_broken": sticky.measures.frames[sticky.last()].broken,
        }),
    })
}
