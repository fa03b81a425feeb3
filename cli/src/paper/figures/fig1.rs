//! Fig. 1: the mouth opening with sticky lips: the output frame of the wide opening closest
//! to half open (by the zip front's count of open columns), lips apart at the centre and
//! joined towards the corners.

use crate::paper::look::picture;
use crate::paper::{Context, Output};
use serde_json::json;
use sticky_lips::error::Result;

pub fn produce(ctx: &Context) -> Result<Output> {
    let run = ctx.run("fig4_sticky");
    let z = &run.zip;
    let counted = z.counted.iter().filter(|c| **c).count().max(1);
    // the open fraction of the counted columns at each frame
    let fraction = |f: usize| {
        let t = run.measures.frames[f].time;
        (0..z.counted.len())
            .filter(|&c| z.counted[c] && z.opening_time[c].is_some_and(|o| o <= t))
            .count() as f64
            / counted as f64
    };
    let f1 = (0..run.measures.frames.len())
        .min_by(|&a, &b| {
            (fraction(a) - 0.5)
                .abs()
                .total_cmp(&(fraction(b) - 0.5).abs())
        })
        .unwrap_or(0);
    let img = picture(run, ctx.skin.as_ref(), f1, 900, 560)?;
    Ok(Output {
        images: vec![("fig1_sticky_opening.png".into(), img)],
        measured: json!({
            "time_s": run.measures.frames[f1].time,
            "open_fraction_counted_columns": fraction(f1),
            "broken_saliva_elements": run.measures.frames[f1].broken,
        }),
    })
}
