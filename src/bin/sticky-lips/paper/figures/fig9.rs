//! Fig. 9: moisture varying along the lips: two wet bands (moisture above critical: no
//! glue) either side of the centre; the wet parts separate, the glued parts hold. Saliva
//! elements are coloured by their moisture (wet blue, gluing green).

use crate::paper::look::{
    element_codes, render, skin_colours, Paint, CAVITY, GREEN, WET_BLUE, WHITE,
};
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
    let codes = element_codes(p);
    let skin = skin_colours(p, ctx.lips_mask.as_ref());
    let colour = |e: u32| match (codes[e as usize], wet[e as usize]) {
        (2, true) => WET_BLUE,
        (2, false) => GREEN,
        _ => skin[e as usize],
    };
    let last = run.last();
    let img = render(
        p,
        &run.measures.columns,
        &run.displacement(last)?,
        &run.broken(last)?,
        Paint::Elements(&colour),
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
    // which columns are open at the end, wet or glued
    let z = &run.zip;
    let cols = &run.measures.columns;
    let mut wet_open = (0, 0);
    let mut glued_open = (0, 0);
    for c in 0..cols.x.len() {
        if !z.counted[c] {
            continue;
        }
        // a column is wet if a wet saliva element touches its upper node
        let u = cols.upper[c];
        let is_wet = disc
            .saliva
            .elements
            .iter()
            .any(|&e| wet[e as usize] && p.mesh.elements[e as usize].contains(&u));
        let slot = if is_wet {
            &mut wet_open
        } else {
            &mut glued_open
        };
        slot.1 += 1;
        if z.final_open[c] {
            slot.0 += 1;
        }
    }
    Ok(Output {
        images: vec![(
            "fig9_moisture_bands.png".into(),
            Image::grid(&[img, legend], 1, 8, WHITE),
        )],
        measured: json!({
            "wet_columns_open": wet_open.0, "wet_columns": wet_open.1,
            "glued_columns_open": glued_open.0, "glued_columns": glued_open.1,
            "final_open_fraction": z.final_open_fraction,
            "final_broken": run.measures.frames[last].broken,
        }),
    })
}
