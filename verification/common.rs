//! Shared helpers for the verification modules.
#![allow(dead_code)]

use std::path::PathBuf;

/// The repository root.
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// NiftySim's reference data, committed with the repository
/// (`verification/reference/niftysim/README.md`: the models, the two builds, checksums).
pub fn oracle_dir() -> PathBuf {
    let d = repo()
        .join("verification")
        .join("reference")
        .join("niftysim");
    assert!(
        d.join("SHA256SUMS").exists(),
        "NiftySim reference data missing at {} (it is part of the repository: is the checkout complete?)",
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
