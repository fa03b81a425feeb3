//! A NiftySim XML model, read both ways (our gradients, and NiftySim's with its timing), then
//! validated and for a small model stepped twice.
#![no_main]
use libfuzzer_sys::fuzz_target;
use sticky_lips::element::hex8::GradientVariant;
#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    let Some(text) = common::text(data) else {
        return;
    };
    for (variant, compat) in [
        (GradientVariant::MeanGradient, false),
        (GradientVariant::Centroid, true),
    ] {
        if let Ok(p) = sticky_lips::io::niftysim::parse(text, "fuzz.xml", variant, compat) {
            common::step_small(&p);
        }
    }
});
