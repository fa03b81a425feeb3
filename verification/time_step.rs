//! Convergence in the time step (issue 30): the sticky face converges in `dt`.
//!
//! The coarse face (the default job: the paper's wide opening with stickiness on the
//! MakeHuman face at the quick resolution, eq. 11's decay in physical time) run through the
//! command line at several steps:
//! - before any saliva element breaks, the displacements converge at the order of central
//!   differences: the observed order `log2(|u(4h) - u(2h)| / |u(2h) - u(h)|)` is at least 1.8;
//! - through the zipper, every lip column opens (gap over the open threshold) at the same
//!   output frame, or one apart, at `dt` and `dt / 2`.

use std::path::{Path, PathBuf};
use sticky_lips::io::scenario;

/// The default job's scenario (the paper's fig4_sticky on the face at the quick resolution)
/// at step `dt`, cut to `total` seconds where asked, run through the library without the
/// animation files (the frames and measures are what is compared).
fn run(dir: &Path, dt: f64, total: Option<f64>) -> PathBuf {
    use sticky_lips::paper::{scenario_of, spec, Model};
    let out = dir.join(format!("dt_{dt:e}_{}", total.unwrap_or(0.8)));
    std::fs::create_dir_all(&out).unwrap();
    let path = out.join("scenario.toml");
    let job = spec(Model::Face, true, "fig4_sticky").unwrap();
    let (text, _) = scenario_of(Model::Face, true, &job, &path).unwrap();
    let mut text =
        scenario::with_dt(&text, "default job", scenario::DtChoice::Seconds(dt)).unwrap();
    if let Some(t) = total {
        text = scenario::with_overrides(
            &text,
            "default job",
            &[("time.total", toml::Value::Float(t))],
        )
        .unwrap();
    }
    let problem = scenario::parse(&text, &path).unwrap().problem;
    let mut opts = sticky_lips::driver::RunOptions::new(&out, sticky_lips::real::Precision::F64, 2);
    opts.export = false;
    sticky_lips::driver::run(&problem, &opts).unwrap();
    out
}

fn displacement(dir: &Path, frame: usize) -> Vec<f64> {
    let p = dir.join(format!("frame_{frame:06}.vtu"));
    sticky_lips::io::vtu::read_point_data_f64(&p, "displacement")
        .unwrap()
        .0
}

/// Per lip column, the index of the first frame whose gap exceeds the open threshold.
fn opening_frames(dir: &Path) -> Vec<Option<usize>> {
    let m: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("measures.json")).unwrap()).unwrap();
    let threshold = m["open_threshold"].as_f64().unwrap();
    let frames = m["frames"].as_array().unwrap();
    let columns = frames[0]["gap"].as_array().unwrap().len();
    (0..columns)
        .map(|c| {
            frames
                .iter()
                .position(|f| f["gap"][c].as_f64().unwrap() > threshold)
        })
        .collect()
}

#[test]
fn the_coarse_face_converges_in_the_time_step() {
    let dir = std::env::temp_dir().join(format!("sticky-lips-dt-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // before breaking (0.1 s: the jaw has turned, no saliva element has broken)
    let h = [4e-5, 2e-5, 1e-5];
    let dirs: Vec<PathBuf> = h.iter().map(|&dt| run(&dir, dt, Some(0.1))).collect();
    for frame in [5, 10] {
        let u: Vec<Vec<f64>> = dirs.iter().map(|d| displacement(d, frame)).collect();
        let diff = |a: &[f64], b: &[f64]| {
            a.iter()
                .zip(b)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max)
        };
        let (e1, e2) = (diff(&u[0], &u[1]), diff(&u[1], &u[2]));
        let order = (e1 / e2).log2();
        let largest = u[2].iter().fold(0.0_f64, |a, x| a.max(x.abs()));
        println!(
            "frame {frame}: max |u| {largest:.3e} m; |u(4e-5) - u(2e-5)| = {e1:.3e}, |u(2e-5) - u(1e-5)| = {e2:.3e}: order {order:.3}"
        );
        assert!(largest > 1e-4, "the jaw has not moved by frame {frame}");
        assert!(order >= 1.8, "observed order {order} at frame {frame}");
    }
    // through the zipper: the whole opening at dt and dt / 2
    let (a, b) = (run(&dir, 4e-5, None), run(&dir, 2e-5, None));
    let (oa, ob) = (opening_frames(&a), opening_frames(&b));
    let mut worst = 0;
    for (c, (x, y)) in oa.iter().zip(&ob).enumerate() {
        let (Some(x), Some(y)) = (x, y) else {
            panic!("column {c}: opens at {x:?} and {y:?} (frame indices)");
        };
        worst = worst.max(x.abs_diff(*y));
    }
    println!(
        "zip front: {} columns, opening frames differ by at most {worst} between dt = 4e-5 and 2e-5 s",
        oa.len()
    );
    assert!(worst <= 1, "a column opens {worst} frames apart");
    let _ = std::fs::remove_dir_all(&dir);
}
