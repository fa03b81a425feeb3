//! "The output is bit-identical for any thread count" (README, `--threads`), on the real model:
//! the MakeHuman face at full resolution (3392 hexahedra, 7020 nodes: more elements than
//! `ELEMENT_CHUNK` x 7 and more nodes than `NODE_CHUNK` x 7, so every thread count up to 7
//! gets chunks of its own in every parallel stage), with everything a run of the paper does
//! at once: saliva that breaks (eqs. 7-11), the jaw keyed (a rigid rotation about the rig's
//! hinge), two muscles keyed (section 3.3), the skull and the modioli fixed, mass damping
//! and hourglass control. Each run goes through the driver into its own directory, as
//! `sticky-lips run --threads N` does; every frame (`frame_*.vtu`, `final.vtu`),
//! `frames.pvd` and `measures.json` must be the same bytes as the one-thread run's, and
//! `summary.json` the same but for its timings and thread count.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use sticky_lips::driver::{self, RunOptions};
use sticky_lips::io::scenario;
use sticky_lips::tled::element_forces::ELEMENT_CHUNK;
use sticky_lips::tled::node_update::NODE_CHUNK;
use sticky_lips::Precision;

/// Table 1 on the full-resolution face, with the jaw keyed open in 0.08 s (the first saliva
/// element breaks at 0.05 s, all 40 by 0.07 s: the run stays short) and two depressors keyed.
const SCENARIO: &str = r#"
title = "determinism: the face with saliva breaking, a keyed jaw and keyed muscles"

[mesh]
generator = "face"

[mesh.face]
resolution = 1.0

[[materials]]
name = "tissue"
elements = "tissue"
mu = 800.0
K = 7000.0
density = 1050.0

[[materials]]
name = "saliva"
elements = "saliva"
mu = 7700.0
K = 191000.0
density = 1050.0

[[saliva]]
material = "saliva"
critical_moisture = 100.0
initial_moisture = 100.0
k_glue = 0.1
evaporation_rate = 0.0
decay_per_step = 0.99

[[fix]]
nodes = "skull"

[jaw]
keys = [[0.0, 0.0], [0.08, 0.15]]

[[model_muscle]]
name = "depressor_labii_inferioris_l"
strength = 0.05
keys = [[0.0, 0.0], [0.05, 1.0], [0.15, 0.0]]

[[model_muscle]]
name = "depressor_anguli_oris_r"
strength = 0.05
keys = [[0.0, 0.0], [0.1, 0.5]]

[time]
dt = 1e-5
total = 0.08
output_every = 1000

[numerics]
damping = 80.0
hourglass_kappa = 0.075
"#;

/// Every file a run wrote, by name (bytes).
fn files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut out = BTreeMap::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let e = e.unwrap();
        if e.file_type().unwrap().is_file() {
            out.insert(
                e.file_name().to_string_lossy().into_owned(),
                std::fs::read(e.path()).unwrap(),
            );
        }
    }
    out
}

/// Keys of the JSON files a run writes whose values are timings or the thread count.
const NOT_RESULTS: [(&str, &[&str]); 2] = [
    (
        "summary.json",
        &[
            "wall_time",
            "stepping_time",
            "element_updates_per_second",
            "threads",
            "export",
        ],
    ),
    ("export.json", &["read_seconds", "write_seconds"]),
];

/// A JSON file of a run without the values that depend on the machine's speed or the
/// thread count (`None`: the file holds only results, compared byte for byte).
fn without_timings(file: &str, bytes: &[u8]) -> Option<serde_json::Value> {
    let (_, keys) = NOT_RESULTS.iter().find(|(f, _)| *f == file)?;
    let mut v: serde_json::Value = serde_json::from_slice(bytes).unwrap();
    let obj = v.as_object_mut().unwrap();
    for k in *keys {
        obj.remove(*k);
    }
    Some(v)
}

fn run(p: &sticky_lips::Problem, precision: Precision, threads: usize, dir: &Path) {
    let _ = std::fs::remove_dir_all(dir);
    driver::run(p, &RunOptions::new(dir.to_path_buf(), precision, threads)).unwrap();
}

#[test]
fn face_runs_are_bit_identical_on_any_thread_count() {
    let p = scenario::parse(SCENARIO, Path::new("determinism.toml"))
        .unwrap()
        .problem;
    let (ne, nn) = (p.mesh.elements.len(), p.mesh.nodes.len());
    let max_threads = 7;
    assert!(
        ne > ELEMENT_CHUNK * max_threads && nn > NODE_CHUNK * max_threads,
        "{ne} elements, {nn} nodes: too few for {max_threads} threads to each get a chunk"
    );
    assert!(!p.physics.saliva.is_empty(), "the face has saliva");
    let root: PathBuf =
        std::env::temp_dir().join(format!("sticky-lips-determinism-{}", std::process::id()));
    for (precision, counts) in [
        (Precision::F64, &[1usize, 2, 3, 4, 7][..]),
        (Precision::F32, &[1, 7][..]),
    ] {
        let name = format!("{precision:?}").to_lowercase();
        let base_dir = root.join(format!("{name}_1"));
        run(&p, precision, counts[0], &base_dir);
        let base = files(&base_dir);
        let summary = without_timings("summary.json", &base["summary.json"]).unwrap();
        // the run does what it is meant to cover: frames, and saliva that breaks during it
        let frames = base.keys().filter(|k| k.starts_with("frame_")).count();
        assert!(frames >= 9, "{name}: {frames} frames");
        let series: Vec<u64> = summary["broken_saliva"]
            .as_array()
            .unwrap()
            .iter()
            .map(|b| b.as_u64().unwrap())
            .collect();
        let broken = *series.last().unwrap();
        assert!(
            series[0] == 0 && broken > 0,
            "{name}: broken saliva per frame {series:?}; the run must cover breaking"
        );
        for &k in &counts[1..] {
            let dir = root.join(format!("{name}_{k}"));
            run(&p, precision, k, &dir);
            let other = files(&dir);
            assert_eq!(
                base.keys().collect::<Vec<_>>(),
                other.keys().collect::<Vec<_>>(),
                "{name}: {k} threads wrote other files than 1 thread"
            );
            for (file, bytes) in &base {
                if let Some(v) = without_timings(file, bytes) {
                    assert_eq!(
                        v,
                        without_timings(file, &other[file]).unwrap(),
                        "{name}: {file} differs between 1 and {k} threads"
                    );
                } else {
                    assert!(
                        bytes == &other[file],
                        "{name}: {file} differs between 1 and {k} threads"
                    );
                }
            }
            let _ = std::fs::remove_dir_all(&dir);
        }
        println!(
            "face_runs_are_bit_identical_on_any_thread_count: {name}: {} files ({frames} frames, \
             {broken} of {} saliva elements broken at the end) identical on {counts:?} threads",
            base.len(),
            summary["saliva_elements"]
        );
        let _ = std::fs::remove_dir_all(&base_dir);
    }
    let _ = std::fs::remove_dir_all(&root);
}
