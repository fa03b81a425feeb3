//! The measures over time: the open fraction of the mouth width, broken saliva elements, the
//! lip gap along the mouth at every other output frame (without and with stickiness), and
//! the left/right asymmetry.

use crate::paper::look::{mm, GREEN, RED};
use crate::paper::{Context, Output};
use serde_json::json;
use sticky_lips::error::Result;
use sticky_lips::render::plot::{line_plot, profile_plot, PlotSpec, ProfileSpec, Series};

pub fn produce(ctx: &Context) -> Result<Output> {
    let (dry, sticky, asym) = (
        ctx.run("fig4_dry"),
        ctx.run("fig4_sticky"),
        ctx.run("fig10_asym"),
    );
    let k = ctx.choice.k_glue;
    let purple = [120, 80, 170];
    let mut images = Vec::new();
    let mut spec = PlotSpec::new(
        "Open fraction of the mouth width",
        "time (s)",
        "open fraction",
    );
    spec.series = vec![
        Series::new("without stickiness", dry.series(&|f| f.open_fraction)).colour(RED),
        Series::new(
            format!("with stickiness (K_glue = {k})"),
            sticky.series(&|f| f.open_fraction),
        )
        .colour(GREEN),
        Series::new(
            "asymmetric muscles (Fig. 10)",
            asym.series(&|f| f.open_fraction),
        )
        .colour(purple)
        .dashed(),
    ];
    images.push(("plot_open_fraction.png".to_string(), line_plot(&spec)));
    let mut spec = PlotSpec::new("Broken saliva elements", "time (s)", "broken elements");
    spec.series = vec![
        Series::new("without stickiness", dry.series(&|f| f.broken as f64)).colour(RED),
        Series::new(
            format!("with stickiness (K_glue = {k})"),
            sticky.series(&|f| f.broken as f64),
        )
        .colour(GREEN),
    ];
    images.push(("plot_broken.png".to_string(), line_plot(&spec)));
    for (run, title, file) in [
        (
            dry,
            "Lip gap along the mouth over time, without stickiness",
            "plot_gap_profiles_dry.png",
        ),
        (
            sticky,
            "Lip gap along the mouth over time, with stickiness",
            "plot_gap_profiles_sticky.png",
        ),
    ] {
        let mut spec = ProfileSpec::new(
            title,
            "position along the mouth (mm)",
            "lip gap (mm)",
            "time (s)",
        );
        let cols = &run.measures.columns;
        spec.x = cols.x.iter().map(|x| mm(x - cols.center)).collect();
        spec.profiles = run
            .measures
            .frames
            .iter()
            .step_by(2)
            .map(|f| (f.time, f.gap.iter().map(|g| mm(*g)).collect()))
            .collect();
        images.push((file.to_string(), profile_plot(&spec)));
    }
    let mut spec = PlotSpec::new(
        "Left/right asymmetry of the lip gap",
        "time (s)",
        "(mean gap subject's left - right) / mean gap",
    );
    spec.series = vec![
        Series::new(
            "symmetric opening (Fig. 4, with stickiness)",
            sticky.series(&|f| f.asymmetry),
        )
        .colour(GREEN),
        Series::new(
            "left depressors active (Fig. 10)",
            asym.series(&|f| f.asymmetry),
        )
        .colour(purple),
    ];
    images.push(("plot_asymmetry.png".to_string(), line_plot(&spec)));
    Ok(Output {
        images,
        measured: json!({}),
    })
}
