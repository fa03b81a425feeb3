//! Fig. 9: moisture varying along the lips: two wet bands (moisture above critical: no
//! glue) either side of the centre, at the slight opening. The wet parts separate first; the
//! glued parts (the centre and the corners) hold for a while and then let go as well. The
//! figure is the frame halfway between the last wet column opening and the first glued one
//! (the last frame if no glued column opens). The saliva is coloured by its moisture (wet
//! blue, gluing green: per element, averaged at the nodes and interpolated per pixel, so a
//! band's edge blends over one element); the lips are the CC0 lips mask sampled per pixel.

use crate::paper::look::{lips_texture, render, Paint, CAVITY, GREEN, SKIN, WET_BLUE, WHITE};
use crate::paper::{Context, Output};
use serde_json::json;
use sticky_lips::error::Result;
use sticky_lips::render::Image;
use sticky_lips::tled::precompute::Discretisation;

pub fn produce(ctx: &Context) -> Result<Output> {
    let run = ctx.run("fig9_bands");
    let p = &run.problem;
    let disc = Discretisation::new(p);
    let mc = p.physics.saliva[0].params.critical_moisture;
    let mut wet = vec![false; p.mesh.elements.len()];
    for (k, &e) in disc.saliva.elements.iter().enumerate() {
        wet[e as usize] = disc.saliva.initial_moisture[k] > mc;
    }
    let tissue = match (&p.mesh.uv, ctx.lips_mask.as_ref()) {
        (Some(_), Some(mask)) => lips_texture(mask),
        _ => Image::new(1, 1, SKIN),
    };
    let saliva = |e: u32| if wet[e as usize] { WET_BLUE } else { GREEN };
    // a counted column is wet if every saliva element at its upper node is wet, glued if
    // none is (the columns on a band's edge are neither)
    let z = &run.zip;
    let cols = &run.measures.columns;
    let mut wet_times = Vec::new();
    let mut glued_times = Vec::new();
    for c in 0..cols.x.len() {
        if !z.counted[c] {
            continue;
        }
        let u = cols.upper[c];
        let around: Vec<bool> = disc
            .saliva
            .elements
            .iter()
            .filter(|&&e| p.mesh.elements[e as usize].contains(&u))
            .map(|&e| wet[e as usize])
            .collect();
        let t = z.opening_time[c];
        if !around.is_empty() && around.iter().all(|w| *w) {
            wet_times.push(t);
        } else if around.iter().all(|w| !*w) {
            glued_times.push(t);
        }
    }
    let last_wet = wet_times
        .iter()
        .flatten()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    let all_wet_open = wet_times.iter().all(|t| t.is_some());
    let first_glued = glued_times
        .iter()
        .flatten()
        .copied()
        .fold(f64::INFINITY, f64::min);
    let frame = if all_wet_open && first_glued.is_finite() && first_glued > last_wet {
        run.frame_at(0.5 * (last_wet + first_glued))
    } else {
        run.last()
    };
    let img = render(
        p,
        cols,
        &run.displacement(frame)?,
        &run.broken(frame)?,
        Paint::TextureAndSaliva(&tissue, &saliva),
        CAVITY,
        900,
        560,
    );
    let legend = Image::legend(
        &[
            ("saliva wetter than critical (no glue)", WET_BLUE),
            ("saliva at critical moisture (glue)", GREEN),
        ],
        18.0,
        WHITE,
    );
    let t = run.measures.frames[frame].time;
    let open_at = |list: &[Option<f64>]| list.iter().filter(|o| o.is_some_and(|o| o <= t)).count();
    Ok(Output {
        images: vec![(
            "fig9_moisture_bands.png".into(),
            Image::grid(&[img, legend], 1, 8, WHITE),
        )],
        measured: json!({
            "frame_time_s": t,
            "wet_columns": wet_times.len(),
            "wet_columns_open_at_frame": open_at(&wet_times),
            "glued_columns": glued_times.len(),
            "glued_columns_open_at_frame": open_at(&glued_times),
            "last_wet_opening_s": if last_wet.is_finite() { Some(last_wet) } else { None },
            "first_glued_opening_s": if first_glued.is_finite() { Some(first_glued) } else { None },
            "final_open_fraction": z.final_open_fraction,
        }),
    })
}
