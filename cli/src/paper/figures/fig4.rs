//! Fig. 4: the jaw opens; without stickiness (left) and with (right), rows 0.04 s apart,
//! from just before the dry lips part to just after the sticky ones have opened to the
//! corners (at most ten rows).

use crate::paper::look::{picture, WHITE};
use crate::paper::{Context, Output};
use serde_json::json;
use sticky_lips::error::Result;
use sticky_lips::render::{GridLabels, Image};

pub const ROW_INTERVAL: f64 = 0.04;

pub fn produce(ctx: &Context) -> Result<Output> {
    let (dry, sticky) = (ctx.run("fig4_dry"), ctx.run("fig4_sticky"));
    let end = dry.times().last().copied().unwrap_or(0.0);
    let t_dry = dry.zip.first.map(|f| f.0).unwrap_or(0.0);
    let t_sticky_done = sticky
        .zip
        .t90
        .or(sticky.zip.first.map(|f| f.0))
        .unwrap_or(end);
    let t_last = (t_sticky_done + ROW_INTERVAL).min(end);
    let t0 =
        (((t_dry - ROW_INTERVAL).max(0.0)).max(t_last - 9.0 * ROW_INTERVAL) / 0.01).round() * 0.01;
    let mut rows = Vec::new();
    let mut t = t0;
    while rows.len() < 10 && t <= t_last + 1e-9 {
        rows.push(t);
        t += ROW_INTERVAL;
    }
    let mut panels = Vec::new();
    let mut titles = Vec::new();
    for &t in &rows {
        for run in [dry, sticky] {
            panels.push(picture(run, ctx.skin.as_ref(), run.frame_at(t), 420, 260)?);
        }
        titles.push(format!("t = {t:.2} s"));
    }
    let rt: Vec<&str> = titles.iter().map(|s| s.as_str()).collect();
    let labels = GridLabels {
        title: Some("Fig. 4: the jaw opens; rows 0.04 s apart"),
        column_titles: &["without stickiness", "with stickiness"],
        row_titles: &rt,
        ..Default::default()
    };
    Ok(Output {
        images: vec![(
            "fig4_opening_over_time.png".into(),
            Image::grid_labelled(&panels, 2, 8, WHITE, &labels),
        )],
        measured: json!({ "row_times_s": rows }),
    })
}
