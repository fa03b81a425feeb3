//! The K_glue x jaw angle sweep the parameters were chosen from: for each jaw angle and
//! K_glue, the fraction of the lip columns open at the end (left) and where along the
//! mouth the first column opened (right; none if no column opened).

use crate::paper::look::WHITE;
use crate::paper::runs::{self, Model};
use crate::paper::{Context, Output};
use serde_json::json;
use sticky_lips::error::Result;
use sticky_lips::render::plot::{line_plot, PlotSpec, Series};
use sticky_lips::render::Image;

const PALETTE: [[u8; 3]; 6] = [
    [230, 150, 40],
    [60, 170, 80],
    [40, 120, 200],
    [120, 60, 160],
    [200, 60, 60],
    [90, 90, 90],
];

pub fn produce(ctx: &Context) -> Result<Output> {
    let (ks, angles) = runs::sweep_grid(ctx.opts.quick);
    let mut left = PlotSpec::new(
        "K_glue x jaw angle: open at equilibrium",
        "jaw angle (rad)",
        "fraction of the lip columns open at the end",
    );
    let mut right = PlotSpec::new(
        "K_glue x jaw angle: where the opening starts",
        "jaw angle (rad)",
        "first column to open, |x| / w",
    );
    let mut table = Vec::new();
    for (i, &k) in ks.iter().enumerate() {
        let mut open = Vec::new();
        let mut first = Vec::new();
        for &a in &angles {
            let r = ctx.run(&runs::sweep_name(k, a));
            open.push((a, r.zip.final_open_fraction));
            if let Some((t, p)) = r.zip.first {
                first.push((a, p));
                table.push(json!({"k_glue": k, "angle": a, "final_open_fraction": r.zip.final_open_fraction,
                                  "first_time_s": t, "first_position_w": p, "spread_s": r.zip.spread()}));
            } else {
                table.push(json!({"k_glue": k, "angle": a, "final_open_fraction": r.zip.final_open_fraction,
                                  "first_time_s": null, "first_position_w": null, "spread_s": null}));
            }
        }
        let c = PALETTE[i % PALETTE.len()];
        left.series.push(
            Series::new(format!("K_glue = {k}"), open)
                .colour(c)
                .markers(),
        );
        if !first.is_empty() {
            right.series.push(
                Series::new(format!("K_glue = {k}"), first)
                    .colour(c)
                    .markers(),
            );
        }
    }
    let c = ctx.choice;
    for s in [&mut left, &mut right] {
        s.title = format!(
            "{} (chosen: K_glue = {}, {} and {} rad{})",
            s.title,
            c.k_glue,
            c.slight_angle,
            c.wide_angle,
            if ctx.opts.model == Model::Procedural {
                ", procedural mouth"
            } else {
                ""
            }
        );
    }
    left.y_range = Some((-0.05, 1.05));
    right.y_range = Some((-0.05, 1.05));
    let img = Image::grid(&[line_plot(&left), line_plot(&right)], 2, 10, WHITE);
    Ok(Output {
        images: vec![("plot_kglue_sweep.png".into(), img)],
        measured: json!({ "grid": table }),
    })
}
