//! Fig. 11: texture-mapped: the wide opening with stickiness 0.04 s after the lips start to
//! part, through the mesh's texture coordinates; on the face the texture is made from the
//! head's CC0 masks (skin, face, lips), on the procedural mouth from its own layout.

use crate::paper::look::{render, Paint, CAVITY};
use crate::paper::runs::Model;
use crate::paper::{Context, Output};
use serde_json::json;
use sticky_lips::error::Result;

pub fn produce(ctx: &Context) -> Result<Output> {
    let run = ctx.run("fig4_sticky");
    let t = run.zip.first.map(|f| f.0 + 0.04).unwrap_or(0.0);
    let f = run.frame_at(t);
    let tex = match (ctx.opts.model, &ctx.skin) {
        (Model::Face, Some(skin)) => skin.clone(),
        _ => crate::paper::look::procedural_texture(),
    };
    let img = render(
        &run.problem,
        &run.measures.columns,
        &run.displacement(f)?,
        &run.broken(f)?,
        Paint::Texture(&tex),
        CAVITY,
        900,
        560,
    );
    Ok(Output {
        images: vec![("fig11_textured.png".into(), img)],
        measured: json!({ "time_s": run.measures.frames[f].time }),
    })
}
