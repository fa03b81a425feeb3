//! The zipper study: what sets how fast the opening runs from the centre to the corners.
//! For the wide opening with stickiness (`fig4_sticky`) and each variant with one thing
//! changed (`sticky_lips::paper::study`): when the first column opens and how long 10 % to
//! 90 % of the columns take (C3 asks for at least 0.08 s).

use crate::paper::runs;
use crate::paper::{Context, Output};
use serde_json::json;
use sticky_lips::error::Result;
use sticky_lips::render::plot::{line_plot, PlotSpec, Series};

const PALETTE: [[u8; 3]; 7] = [
    [60, 170, 80],
    [230, 150, 40],
    [40, 120, 200],
    [120, 60, 160],
    [200, 60, 60],
    [90, 90, 90],
    [20, 160, 160],
];

pub fn names(quick: bool) -> Vec<String> {
    let mut v = vec!["fig4_sticky".to_string()];
    v.extend(sticky_lips::paper::study(quick).into_iter().map(|s| s.name));
    v
}

pub fn produce(ctx: &Context) -> Result<Output> {
    let mut spec = PlotSpec::new(
        "The zip front's speed: 10 % to 90 % of the columns open",
        "first opening (s)",
        "10 % to 90 % (s)",
    );
    let mut rows = Vec::new();
    let specs = runs::all(ctx.opts.model, ctx.opts.quick);
    for (i, name) in names(ctx.opts.quick).iter().enumerate() {
        let r = ctx.run(name);
        let what = specs
            .iter()
            .find(|s| &s.name == name)
            .map(|s| s.what.clone())
            .unwrap_or_default();
        let label = if i == 0 {
            "Table 1 (the figures)".to_string()
        } else {
            what.clone()
        };
        if let (Some((t, _)), Some(s)) = (r.zip.first, r.zip.spread()) {
            spec.series.push(
                Series::new(label, vec![(t, s)])
                    .colour(PALETTE[i % PALETTE.len()])
                    .markers(),
            );
        }
        rows.push(json!({
            "run": name,
            "what": what,
            "first_opening_s": r.zip.first.map(|f| f.0),
            "first_position_w": r.zip.first.map(|f| f.1),
            "spread_10_90_s": r.zip.spread(),
            "spearman": r.zip.spearman,
            "final_open_fraction": r.zip.final_open_fraction,
        }));
    }
    spec.series.push(
        Series::new("C3: at least 0.08 s", vec![(0.0, 0.08), (1.2, 0.08)])
            .colour([160, 160, 160])
            .dashed(),
    );
    spec.width = 1000;
    spec.height = 620;
    spec.y_range = Some((0.0, 0.16));
    spec.legend = sticky_lips::render::plot::LegendPosition::UpperRight;
    Ok(Output {
        images: vec![("plot_zip_study.png".into(), line_plot(&spec))],
        measured: json!({ "variants": rows }),
    })
}
