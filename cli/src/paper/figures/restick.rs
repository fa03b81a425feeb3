//! Lips that stick again (run `plosive`, the jaw keyed as `paper::PLOSIVE_JAW`: open, close
//! until the lips touch, hold closed, open again). With eq. (11) as written a broken saliva
//! element whose stretch falls back below Z gets its force back, so the closed lips re-bond
//! and the second opening unzips like the first. `fig_restick.png`: the first opening (top
//! row) and the second (bottom row) at the same times after each opening's start, 0.01 s
//! apart (one output frame) from just before the first column opens to just after 90 % of
//! the columns are open; `plot_restick.png`: broken saliva and the open fraction over time.
//! Made on the face only (see `skipped` in `measured.json` for the procedural mouth).

use crate::paper::look::{picture, GREEN, RED, WHITE};
use crate::paper::{Context, Output};
use serde_json::json;
use sticky_lips::error::Result;
use sticky_lips::measures::{ZipFront, ZIP_THRESHOLD};
use sticky_lips::paper::PLOSIVE_JAW;
use sticky_lips::render::plot::{line_plot, LegendPosition, PlotSpec, Series};
use sticky_lips::render::{GridLabels, Image};

/// Output frames are 0.01 s apart (Table 1's `output_every` x `dt`).
const FRAME: f64 = 0.01;
/// At most this many frames per row.
const MAX_COLUMNS: usize = 6;

pub fn produce(ctx: &Context) -> Result<Output> {
    let Some(run) = ctx.runs.get("plosive") else {
        // not asked for on the procedural mouth (figures::TABLE)
        return Ok(Output {
            images: Vec::new(),
            measured: json!({
                "skipped": "the face only: on the procedural mouth (--quick) run plosive \
                            diverged as the lips closed again (an inverted hexahedron at \
                            t = 0.610 s, 2026-12-03)"
            }),
        });
    };
    let m = &run.measures;
    let k = |i: usize| PLOSIVE_JAW[i][0];
    // the openings: from the jaw's start to the start of the closing, and from the end of
    // the closed hold to the top of the second opening
    let windows = [(k(0), k(2)), (k(4), k(5))];
    let zips: Vec<ZipFront> = windows
        .iter()
        .map(|&(a, b)| ZipFront::between(m, ZIP_THRESHOLD, a, b))
        .collect();
    let rel = |z: &ZipFront, t0: f64| {
        json!({
            "first_opening_s": z.first.map(|f| f.0 - t0),
            "first_opening_position_w": z.first.map(|f| f.1),
            "t10_s": z.t10.map(|t| t - t0),
            "t90_s": z.t90.map(|t| t - t0),
            "t10_to_t90_s": z.spread(),
            "spearman": z.spearman,
            "final_open_fraction": z.final_open_fraction,
        })
    };
    // the frames: the first opening's zip, the same times after the second opening's start
    let z1 = &zips[0];
    let start = z1.first.map_or(0.0, |f| f.0) - windows[0].0;
    let end = z1.t90.map_or(start, |t| t - windows[0].0);
    let from = ((start / FRAME).floor() * FRAME).max(0.0);
    let to = (end / FRAME).ceil() * FRAME + FRAME;
    let n = (((to - from) / FRAME).round() as usize + 1).clamp(1, 64);
    let step = n.div_ceil(MAX_COLUMNS).max(1);
    let times: Vec<f64> = (0..n)
        .step_by(step)
        .map(|i| from + i as f64 * FRAME)
        .collect();
    let grid = restick_grid(ctx, run, &windows, &times)?;

    // broken saliva over time and when it re-bonds against when the lips touch
    let p = &run.problem;
    let n_saliva = p
        .element_material
        .iter()
        .filter(|&&mat| p.physics.saliva.iter().any(|s| s.material == mat))
        .count()
        .max(1);
    let spec = restick_plot(run, n_saliva);
    let closing = |f: &&sticky_lips::measures::FrameMeasures| f.time > k(2) && f.time <= k(4);
    let all_broken_until = m
        .frames
        .iter()
        .filter(closing)
        .take_while(|f| f.broken == n_saliva)
        .last()
        .map(|f| f.time);
    let rebonded = m
        .frames
        .iter()
        .filter(closing)
        .find(|f| f.broken == 0)
        .map(|f| f.time);
    let touch = m
        .frames
        .iter()
        .filter(closing)
        .find(|f| f.gap.iter().any(|g| *g <= 0.0))
        .map(|f| f.time);
    Ok(Output {
        images: vec![
            ("fig_restick.png".into(), grid),
            ("plot_restick.png".into(), line_plot(&spec)),
        ],
        measured: json!({
            "jaw_keys": PLOSIVE_JAW,
            "frame_times_after_opening_s": times,
            "first_opening": rel(&zips[0], windows[0].0),
            "second_opening": rel(&zips[1], windows[1].0),
            "saliva_elements": n_saliva,
            "jaw_closed_s": k(3),
            "closing_all_broken_until_s": all_broken_until,
            "closing_first_frame_a_lip_column_touches_s": touch,
            "closing_all_rebonded_by_s": rebonded,
            "broken_when_second_opening_starts": m
                .frames
                .iter()
                .rev()
                .find(|f| f.time <= k(4) + 1e-9)
                .map(|f| f.broken),
        }),
    })
}

/// The panels: the frames `times` after each opening's start (a row per window).
fn restick_grid(
    ctx: &Context,
    run: &crate::paper::runs::Run,
    windows: &[(f64, f64)],
    times: &[f64],
) -> Result<Image> {
    let mut panels = Vec::new();
    for &(t0, _) in windows {
        for &t in times {
            panels.push(picture(
                run,
                ctx.skin.as_ref(),
                run.frame_at(t0 + t),
                360,
                220,
            )?);
        }
    }
    let titles: Vec<String> = times
        .iter()
        .map(|t| format!("{:.2} s after the jaw opens", t))
        .collect();
    let ct: Vec<&str> = titles.iter().map(|s| s.as_str()).collect();
    let rows = [
        format!("first opening ({} s)", windows[0].0),
        format!("second opening ({} s)", windows[1].0),
    ];
    let rt: Vec<&str> = rows.iter().map(|s| s.as_str()).collect();
    let labels = GridLabels {
        title: Some(
            "Lips that stick again: the jaw opens, closes, holds the lips closed, opens again",
        ),
        column_titles: &ct,
        row_titles: &rt,
        ..Default::default()
    };
    Ok(Image::grid_labelled(
        &panels,
        times.len(),
        8,
        WHITE,
        &labels,
    ))
}

/// Broken saliva, the open fraction and the jaw angle over time.
fn restick_plot(run: &crate::paper::runs::Run, n_saliva: usize) -> PlotSpec {
    let top = PLOSIVE_JAW.iter().fold(0.0f64, |a, k| a.max(k[1]));
    let mut spec = PlotSpec::new(
        "Lips that stick again: broken saliva and the open mouth width",
        "time (s)",
        "fraction",
    );
    spec.series = vec![
        Series::new(
            format!("broken saliva elements (of {n_saliva})"),
            run.series(&|f| f.broken as f64 / n_saliva as f64),
        )
        .colour(RED),
        Series::new(
            "open fraction of the mouth width",
            run.series(&|f| f.open_fraction),
        )
        .colour(GREEN)
        .dashed(),
        Series::new(
            format!("jaw angle / {top} rad"),
            PLOSIVE_JAW.iter().map(|k| (k[0], k[1] / top)).collect(),
        )
        .colour([120, 120, 120]),
    ];
    // room above the curves for the legend
    spec.y_range = Some((0.0, 1.4));
    spec.legend = LegendPosition::UpperRight;
    spec
}
