//! The figures' renderings of a paper run's frames, on the library's look
//! ([`sticky_lips::app::look`]: camera, colours, skin, membrane).

use super::runs::Run;
pub use sticky_lips::app::look::*;
use sticky_lips::error::Result;
use sticky_lips::render::Image;

/// A rendering of output frame `frame` of `run` ([`render`]: the broken saliva absent): through
/// the skin texture where there is one (the face), else skin-coloured with the saliva red.
pub fn picture(run: &Run, skin: Option<&Image>, frame: usize, w: u32, h: u32) -> Result<Image> {
    displaced(
        run,
        skin,
        &run.displacement(frame)?,
        &run.broken(frame)?,
        w,
        h,
    )
}

/// [`picture`] for any displacement `u` with the `hidden` elements left out.
pub fn displaced(
    run: &Run,
    skin: Option<&Image>,
    u: &[[f64; 3]],
    hidden: &[bool],
    w: u32,
    h: u32,
) -> Result<Image> {
    let cols = &run.measures.columns;
    Ok(match (skin, &run.problem.mesh.uv) {
        (Some(tex), Some(_)) => render(
            &run.problem,
            cols,
            u,
            hidden,
            Paint::Texture(tex),
            CAVITY,
            w,
            h,
        ),
        _ => {
            let codes = element_codes(&run.problem);
            let paint = |e: u32| if codes[e as usize] == 2 { SALIVA } else { SKIN };
            render(
                &run.problem,
                cols,
                u,
                hidden,
                Paint::Elements(&paint),
                CAVITY,
                w,
                h,
            )
        }
    })
}

/// `1e3 x` (m to mm).
pub fn mm(x: f64) -> f64 {
    1e3 * x
}
