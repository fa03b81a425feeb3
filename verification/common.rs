//! Shared helpers for the verification modules.
#![allow(dead_code)]

use std::path::PathBuf;

/// The repository root.
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// `shared/` beside the checkout (or `$STICKY_LIPS_SHARED`): NiftySim's oracle lives there.
pub fn shared() -> PathBuf {
    if let Ok(p) = std::env::var("STICKY_LIPS_SHARED") {
        return PathBuf::from(p);
    }
    let beside = repo().join("..").join("shared");
    if beside.exists() {
        return beside;
    }
    repo().join("shared")
}

pub fn oracle_dir() -> PathBuf {
    let d = shared().join("oracle").join("niftysim");
    assert!(
        d.join("README.md").exists(),
        "NiftySim oracle not found at {} (set STICKY_LIPS_SHARED to the shared/ folder)",
        d.display()
    );
    d
}

/// Reads whitespace-separated rows of numbers, skipping `#` comments; the first column is an index.
pub fn read_table(path: &std::path::Path) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    text.lines()
        .filter(|l| !l.trim().is_empty() && !l.trim_start().starts_with('#'))
        .map(|l| {
            l.split_whitespace()
                .map(|t| t.parse::<f64>().unwrap())
                .collect()
        })
        .collect()
}

/// `max |a - b| / max |b|` over all entries.
pub fn rel_max_diff(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let mut num: f64 = 0.0;
    let mut den: f64 = 0.0;
    for (x, y) in a.iter().zip(b) {
        for k in 0..3 {
            num = num.max((x[k] - y[k]).abs());
            den = den.max(y[k].abs());
        }
    }
    num / den
}
