//! Fig. 8: a wide opening reaches the same equilibrium with and without stickiness: both
//! final frames and their lip gap profiles.

use crate::paper::look::{mm, picture, GREEN, RED, WHITE};
use crate::paper::{Context, Output};
use serde_json::json;
use sticky_lips::error::Result;
use sticky_lips::render::plot::{line_plot, PlotSpec, Series};
use sticky_lips::render::{GridLabels, Image};

pub fn produce(ctx: &Context) -> Result<Output> {
    let (dry, sticky) = (ctx.run("fig4_dry"), ctx.run("fig4_sticky"));
    let (w, h) = (640, 400);
    let panels = vec![
        picture(dry, ctx.skin.as_ref(), dry.last(), w, h)?,
        picture(sticky, ctx.skin.as_ref(), sticky.last(), w, h)?,
    ];
    let labels = GridLabels {
        title: Some("Fig. 8: a wide opening at equilibrium"),
        column_titles: &["without stickiness", "with stickiness"],
        ..Default::default()
    };
    let xs: Vec<f64> = dry
        .measures
        .columns
        .x
        .iter()
        .map(|x| mm(x - dry.measures.columns.center))
        .collect();
    let prof = |name: &str, g: &[f64], c: [u8; 3]| {
        Series::new(name, xs.iter().zip(g).map(|(x, g)| (*x, mm(*g))).collect()).colour(c)
    };
    let gd = &dry.measures.frames[dry.last()].gap;
    let gs = &sticky.measures.frames[sticky.last()].gap;
    let mut spec = PlotSpec::new(
        "Fig. 8: lip gap at a wide opening (equilibrium)",
        "position along the mouth (mm)",
        "lip gap (mm)",
    );
    spec.series = vec![
        prof("without stickiness", gd, RED),
        prof("with stickiness", gs, GREEN).dashed(),
    ];
    let diff = gd
        .iter()
        .zip(gs)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let max = gd.iter().copied().fold(0.0, f64::max);
    Ok(Output {
        images: vec![
            (
                "fig8_wide_opening.png".into(),
                Image::grid_labelled(&panels, 2, 8, WHITE, &labels),
            ),
            ("fig8_gap_profiles.png".into(), line_plot(&spec)),
        ],
        measured: json!({
            "max_gap_dry_m": max,
            "max_gap_difference_m": diff,
        }),
    })
}
