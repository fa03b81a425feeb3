//! Fig. 2: the material regions (soft tissue of the upper and lower face, the saliva layer).

use crate::paper::look::{element_codes, groups_picture, BLUE, GREEN, RED, WHITE};
use crate::paper::{Context, Output};
use serde_json::json;
use sticky_lips::error::Result;
use sticky_lips::render::Image;

pub fn produce(ctx: &Context) -> Result<Output> {
    let run = ctx.run("fig4_sticky");
    let p = &run.problem;
    let codes = element_codes(p);
    let img = groups_picture(p, &run.measures.columns, 900, 560);
    let legend = Image::legend(
        &[
            ("soft tissue, upper face", BLUE),
            ("soft tissue, lower face", RED),
            ("saliva layer", GREEN),
        ],
        18.0,
        WHITE,
    );
    let count = |c: u8| codes.iter().filter(|&&x| x == c).count();
    Ok(Output {
        images: vec![(
            "fig2_materials.png".into(),
            Image::grid(&[img, legend], 2, 10, WHITE),
        )],
        measured: json!({
            "upper_face_elements": count(0),
            "lower_face_elements": count(1),
            "saliva_elements": count(2),
        }),
    })
}
