//! Fig. 10: asymmetric opening: the jaw opens with the depressors (depressor labii
//! inferioris and depressor anguli oris) of the subject's left side active.

use crate::paper::look::picture;
use crate::paper::{Context, Output};
use serde_json::json;
use sticky_lips::error::Result;

pub fn produce(ctx: &Context) -> Result<Output> {
    let run = ctx.run("fig10_asym");
    let last = run.last();
    let f = &run.measures.frames[last];
    Ok(Output {
        images: vec![(
            "fig10_asymmetric.png".into(),
            picture(run, ctx.skin.as_ref(), last, 900, 560)?,
        )],
        measured: json!({
            "final_asymmetry": f.asymmetry,
            "final_max_gap_m": f.gap.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        }),
    })
}
