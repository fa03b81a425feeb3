//! The time-step convergence study (issue 30): the paper's wide opening with stickiness at
//! the steps of `sticky_lips::paper::DT_STUDY`, frames every 10 ms and eq. 11's decay in
//! physical time, compared with the smallest step:
//! - the displacements at fixed times before any saliva element breaks, and the observed
//!   order of central differences from three steps each a factor 2 apart;
//! - every lip column's opening time (the zip front), the open fraction over time and the
//!   final displacements.

use crate::paper::look::mm;
use crate::paper::{Context, Output};
use serde_json::json;
use sticky_lips::error::Result;
use sticky_lips::paper::{dt_run_name, DT_STUDY};
use sticky_lips::render::plot::{line_plot, PlotSpec, Series};

pub fn names() -> Vec<String> {
    DT_STUDY.iter().map(|&dt| dt_run_name(dt)).collect()
}

fn max_diff(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|(p, q)| (0..3).map(move |k| (p[k] - q[k]).abs()))
        .fold(0.0, f64::max)
}

pub fn produce(ctx: &Context) -> Result<Output> {
    let runs: Vec<(f64, &crate::paper::runs::Run)> = DT_STUDY
        .iter()
        .map(|&dt| (dt, ctx.run(&dt_run_name(dt))))
        .collect();
    let (_, finest) = runs[0];
    let interval = finest.times().get(1).copied().unwrap_or(0.0);
    // before the first break: the frames at 0.05 and 0.1 s (where no element has broken in
    // the finest run) and the order of the steps 2.5e-6, 5e-6, 1e-5 and 1e-5, 2e-5, 4e-5
    let unbroken = |t: f64| {
        let f = finest.frame_at(t);
        finest.measures.frames[f].broken == 0
    };
    let mut orders = Vec::new();
    for t in [0.05, 0.1] {
        if !unbroken(t) {
            continue;
        }
        let u: Vec<Vec<[f64; 3]>> = runs
            .iter()
            .map(|(_, r)| r.displacement(r.frame_at(t)))
            .collect::<Result<_>>()?;
        let largest = u[0]
            .iter()
            .flat_map(|p| p.iter().map(|x| x.abs()))
            .fold(0.0, f64::max);
        for (a, b, c) in [(0, 1, 2), (2, 3, 4)] {
            let (e1, e2) = (max_diff(&u[c], &u[b]), max_diff(&u[b], &u[a]));
            orders.push(json!({
                "time": t,
                "steps": [runs[a].0, runs[b].0, runs[c].0],
                "coarse_difference_m": e1,
                "fine_difference_m": e2,
                "order": (e1 / e2).log2(),
                "largest_displacement_m": largest,
            }));
        }
    }
    // the zipper, the open fraction and the final shape against the finest step
    let u_final = finest.displacement(finest.last())?;
    let largest_final = u_final
        .iter()
        .flat_map(|p| p.iter().map(|x| x.abs()))
        .fold(0.0, f64::max);
    let mut per_step = Vec::new();
    let mut opening = PlotSpec::new(
        "Opening time of every lip column at each time step",
        "position along the mouth (mm)",
        "opening time (s)",
    );
    let mut fraction = PlotSpec::new(
        "Open fraction of the mouth width at each time step",
        "time (s)",
        "open fraction",
    );
    let colours: [[u8; 3]; 6] = [
        [20, 20, 20],
        [40, 90, 200],
        [30, 150, 60],
        [230, 140, 20],
        [200, 40, 40],
        [140, 60, 170],
    ];
    for (k, (dt, r)) in runs.iter().enumerate() {
        let cols = &r.measures.columns;
        let zip_diff = r
            .zip
            .opening_time
            .iter()
            .zip(&finest.zip.opening_time)
            .map(|(a, b)| match (a, b) {
                (Some(a), Some(b)) => (a - b).abs(),
                (None, None) => 0.0,
                _ => f64::INFINITY,
            })
            .fold(0.0, f64::max);
        let fraction_diff = r
            .measures
            .frames
            .iter()
            .zip(&finest.measures.frames)
            .map(|(a, b)| (a.open_fraction - b.open_fraction).abs())
            .fold(0.0, f64::max);
        let u = r.displacement(r.last())?;
        let final_diff = max_diff(&u, &u_final);
        per_step.push(json!({
            "dt": dt,
            "steps": r.summary.steps,
            "stepping_s": r.summary.stepping_time,
            "first_opening": r.zip.first,
            "spearman": r.zip.spearman,
            "zip_front_max_difference_s": zip_diff,
            "open_fraction_max_difference": fraction_diff,
            "final_displacement_max_difference_m": final_diff,
            "final_displacement_relative": final_diff / largest_final,
        }));
        let points: Vec<(f64, f64)> = cols
            .x
            .iter()
            .zip(&r.zip.opening_time)
            .map(|(x, t)| (mm(x - cols.center), t.unwrap_or(f64::NAN)))
            .collect();
        let name = format!("dt = {dt:e} s");
        let mut s = Series::new(name.clone(), points)
            .colour(colours[k % 6])
            .markers();
        let mut f = Series::new(name, r.series(&|m| m.open_fraction)).colour(colours[k % 6]);
        if k % 2 == 1 {
            s = s.dashed();
            f = f.dashed();
        }
        opening.series.push(s);
        fraction.series.push(f);
    }
    Ok(Output {
        images: vec![
            ("plot_dt_opening.png".into(), line_plot(&opening)),
            ("plot_dt_open_fraction.png".into(), line_plot(&fraction)),
        ],
        measured: json!({
            "reference_dt": runs[0].0,
            "output_interval_s": interval,
            "order_before_breaking": orders,
            "per_step": per_step,
        }),
    })
}
