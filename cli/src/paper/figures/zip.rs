//! The zip front: the time each lip column opens (its gap grown by 0.2 mm) against its
//! distance from the mouth's centre (in half mouth widths), for the wide opening without and
//! with stickiness and the slight opening with stickiness. The corner-most columns (beyond
//! 0.9 w, shaded in the claims) are drawn but not counted.

use crate::paper::look::{GREEN, RED};
use crate::paper::{Context, Output};
use serde_json::json;
use sticky_lips::error::Result;
use sticky_lips::render::plot::{line_plot, PlotSpec, Series};

pub fn produce(ctx: &Context) -> Result<Output> {
    let mut spec = PlotSpec::new(
        "Zip front: when each lip column opens",
        "distance from the centre |x| / w",
        "opening time (s)",
    );
    let mut measured = serde_json::Map::new();
    for (name, label, colour) in [
        ("fig4_dry", "wide, without stickiness", RED),
        ("fig4_sticky", "wide, with stickiness", GREEN),
        ("fig7_sticky", "slight, with stickiness", [40, 120, 200]),
    ] {
        let z = &ctx.run(name).zip;
        let mut pts: Vec<(f64, f64)> = z
            .position
            .iter()
            .zip(&z.opening_time)
            .filter_map(|(p, t)| t.map(|t| (*p, t)))
            .collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
        measured.insert(
            name.into(),
            json!({
                "position_w": z.position,
                "opening_time_s": z.opening_time,
                "t10_s": z.t10, "t90_s": z.t90, "spread_s": z.spread(), "spearman": z.spearman,
            }),
        );
        if !pts.is_empty() {
            spec.series
                .push(Series::new(label, pts).colour(colour).markers());
        }
    }
    spec.x_range = Some((0.0, 1.0));
    Ok(Output {
        images: vec![("plot_zip_front.png".into(), line_plot(&spec))],
        measured: serde_json::Value::Object(measured),
    })
}
