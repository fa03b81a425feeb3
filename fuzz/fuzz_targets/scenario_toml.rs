//! A TOML scenario: parsed, validated, and for a small model built and stepped twice. Any
//! input must give a scenario or an error, never a panic, an abort or a hang.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;
#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    let Some(text) = common::text(data) else {
        return;
    };
    if let Ok(s) = sticky_lips::io::scenario::parse(text, Path::new("fuzz/case.toml")) {
        let _ = s.problem.num_steps();
        common::step_small(&s.problem);
    }
});
