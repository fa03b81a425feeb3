//! A NiftySim XML model, read both ways (our gradients, and NiftySim's with its timing), then
//! validated and for a small model stepped twice.
#![no_main]
use libfuzzer_sys::fuzz_target;
use sticky_lips::element::hex8::GradientVariant;
#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    common::init();
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    for (variant, compat) in [
        (GradientVariant::MeanGradient, false),
        (GradientVariant::Centroid, true),
    ] {
        let Ok(p) = sticky_lips::io::niftysim::parse(text, "fuzz.xml", variant, compat) else {
            continue;
        };
        if p.validate().is_err() || p.mesh.nodes.len() > 500 {
            continue;
        }
        if let Ok(mut sim) = sticky_lips::tled::Simulation::<f64>::new(&p) {
            for _ in 0..2.min(sim.num_steps()) {
                if sim.step().is_err() {
                    break;
                }
            }
        }
    }
});
