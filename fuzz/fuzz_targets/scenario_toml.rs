//! A TOML scenario: parsed, validated, and for a small model built and stepped twice. Any
//! input must give a scenario or an error, never a panic, an abort or a hang.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;
#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    common::init();
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(s) = sticky_lips::io::scenario::parse(text, Path::new("fuzz/case.toml")) else {
        return;
    };
    let p = s.problem;
    if p.validate().is_err() {
        return;
    }
    let _ = p.num_steps();
    if p.mesh.nodes.len() <= 500 {
        if let Ok(mut sim) = sticky_lips::tled::Simulation::<f64>::new(&p) {
            for _ in 0..2.min(sim.num_steps()) {
                if sim.step().is_err() {
                    break;
                }
            }
        }
    }
});
