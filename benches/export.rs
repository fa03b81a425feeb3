//! What the animation files cost next to the steps they record (`benches/README.md`).
//!
//! The model is the default job's (`sticky-lips run` without input: the paper's
//! `fig4_sticky` run on the MakeHuman face at the quick resolution, 864 hexahedra, a frame
//! every 1000 steps), one thread. Benchmark ids are `export/WHAT`:
//!
//! - `frame_steps`: the 1000 steps between two frames (`Simulation::step`, `f64`);
//! - `skin_positions`: the skin's vertices of one frame from the model's displacements
//!   (`Skin::positions`, the face's 686 vertices);
//! - `encode_frame`: one frame's share of the files: its PC2 and MDD samples and its USDA time
//!   samples (the skin's points and the saliva faces' state), encoded in memory;
//! - `export_run`: `export::export` on a finished run of 81 frames (reading the frames back,
//!   writing the four files): divide by 81 for a frame's share.

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use sticky_lips::driver::{self, RunOptions};
use sticky_lips::io::cache::{mdd_bytes, pc2_bytes, usda_text, UsdLayer, UsdMesh};
use sticky_lips::paper::{scenario_of, spec, Model};
use sticky_lips::real::Precision;
use sticky_lips::tled::Simulation;

fn bench(c: &mut Criterion) {
    let run = spec(Model::Face, true, "fig4_sticky").expect("the paper's run");
    let dir = std::env::temp_dir().join(format!("sticky-lips-bench-export-{}", std::process::id()));
    let (_, problem) = scenario_of(Model::Face, true, &run, &dir.join("scenario.toml")).unwrap();
    let skin = problem.physics.skin.clone().expect("the face has a skin");
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let mut g = c.benchmark_group("export");
    g.sample_size(10);
    {
        let mut sim = pool.install(|| Simulation::<f64>::new(&problem).unwrap());
        // into the opening, so that the state is a deformed one
        pool.install(|| {
            for _ in 0..30_000 {
                sim.step().unwrap();
            }
        });
        let every = problem.time.output_every;
        g.bench_function("frame_steps", |b| {
            b.iter(|| {
                pool.install(|| {
                    for _ in 0..every {
                        sim.step().unwrap();
                    }
                })
            })
        });
        let u = sim.displacement_f64();
        let t = sim.time();
        g.bench_function("skin_positions", |b| {
            b.iter(|| black_box(skin.positions(black_box(&u), t)))
        });
        let pts: Vec<[f32; 3]> = skin
            .positions(&u, t)
            .into_iter()
            .map(|p| p.map(|x| x as f32))
            .collect();
        let frames = vec![pts.clone()];
        let faces: Vec<Vec<u32>> = skin.surface.faces.clone();
        g.bench_function("encode_frame", |b| {
            b.iter(|| {
                let pc2 = pc2_bytes(&frames, 0.0);
                let mdd = mdd_bytes(&frames, &[t]);
                let usda = usda_text(&UsdLayer {
                    doc: "bench",
                    up_axis: "Y",
                    metres_per_unit: 0.1,
                    frames_per_second: 100.0,
                    meshes: vec![UsdMesh {
                        name: "skin",
                        faces: &faces,
                        rest: &pts,
                        frames: &frames,
                        uv: None,
                        face_data: vec![],
                    }],
                });
                black_box((pc2.len(), mdd.len(), usda.len()))
            })
        });
    }
    // a whole run, then its export
    let mut opts = RunOptions::new(&dir, Precision::F64, 2);
    opts.export = false;
    driver::run(&problem, &opts).unwrap();
    g.bench_function("export_run", |b| {
        b.iter(|| black_box(sticky_lips::export::export(&skin, &dir).unwrap()))
    });
    g.finish();
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group!(benches, bench);
criterion_main!(benches);
