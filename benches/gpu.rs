//! Criterion benchmarks of the GPU backend against the CPU (see `benches/GPU.md`).
//!
//! Ids are `STAGE/BACKEND-PRECISION/hex=N` (`hex=mouth` for the paper's mouth model):
//!
//! - `element_forces/gpu-f32`: the `element_forces` kernel alone, dispatched repeatedly at
//!   a fixed deformed state in one submission;
//! - `node_update/gpu-f32`: the `node_update` kernel alone, likewise;
//! - `host/gpu-f32`: what a step costs the CPU whatever the adapter: the per-step data
//!   Rust evaluates and the recording of the step's dispatches, nothing uploaded or
//!   submitted (`GpuSimulation::bench_host`); a floor under `step/gpu-f32` on any GPU;
//! - `step/gpu-f32`: full steps (`GpuSimulation::step_many`: element forces, saliva rule if
//!   any, node update; one submission per call, the status read back at the end);
//! - `step/gpu-f64`: the same with the f64 kernels, on adapters with `SHADER_F64`;
//! - `step/gpu-f32only`: on adapters with `SHADER_F64`, the f32 kernels without the f64
//!   cube-root refinement (what adapters without it run; `gpu-f32` there returns the CPU's
//!   f32 bits);
//! - `step/cpu-f32` and `step/cpu-f64`: `Simulation::step` on all cores (rayon), the same
//!   model and state, for comparison.
//!
//! The block model is the one of `benches/tled.rs` (NiftySim's `timing_block20` scaled to
//! `N = n^3` hexahedra, base fixed, top driven down by a clamped RAMP), seeded with the same
//! deformed state. The mouth is the procedural mouth's `fig4_sticky` run (`sticky_lips::paper`, Table 1 on the procedural mouth) at full resolution (its
//! 3414-hexahedra-class mesh, saliva included).
//!
//! Throughput is `Elements(N)`: "elem/s" is element-updates per second.
//! Sizes: `STICKY_LIPS_BENCH_SIZES=1000,8000,mouth` (default `1000,8000,64000,mouth`, and
//! `1000,mouth` when `cargo test` runs the benchmarks once; `512k` = 80^3 accepted). `STICKY_LIPS_BENCH_CPU=0` skips the CPU ids.
//! Without an adapter the GPU ids are skipped with a message.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use std::time::{Duration, Instant};
use sticky_lips::gpu::shaders::ShaderReal;
use sticky_lips::gpu::sim::Stage;
use sticky_lips::gpu::{GpuContext, GpuSimulation};
use sticky_lips::tled::Simulation;
use sticky_lips::Problem;

mod common;

const SEED_STEPS: usize = 5;

#[derive(Clone, Copy)]
enum Size {
    Block(usize),
    Mouth,
}

fn sizes() -> Vec<Size> {
    // `cargo test --all-targets` runs each benchmark once as a smoke test (no `--bench`
    // argument): the small sizes are enough there
    let default = if std::env::args().any(|a| a == "--bench") {
        "1000,8000,64000,mouth"
    } else {
        "1000,mouth"
    };
    let s = std::env::var("STICKY_LIPS_BENCH_SIZES").unwrap_or_else(|_| default.into());
    s.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
        .map(|t| {
            if t == "mouth" {
                return Size::Mouth;
            }
            let (num, mul) = match t.strip_suffix(['k', 'K']) {
                Some(n) => (n, 1000),
                None => (t, 1),
            };
            let n = num
                .parse::<usize>()
                .unwrap_or_else(|_| panic!("STICKY_LIPS_BENCH_SIZES: cannot parse {t:?}"))
                * mul;
            let c = (n as f64).cbrt().round() as usize;
            assert!(c * c * c == n, "STICKY_LIPS_BENCH_SIZES: {n} is not a cube");
            Size::Block(c)
        })
        .collect()
}

/// `benches/tled.rs`'s block, run for a very long time (the top holds after the ramp) so
/// that criterion can step it as often as it likes.
fn block_problem(c: usize) -> Problem {
    common::block_problem(c, 1e4)
}

fn mouth_problem() -> Problem {
    let mut p = common::mouth_problem(100.0);
    p.source = "mouth".into();
    p
}

fn bench_cpu<T: sticky_lips::tled::simd::SimdReal>(
    c: &mut Criterion,
    p: &Problem,
    label: &str,
    seeded: bool,
) {
    let mut sim = Simulation::<T>::new(p).expect("valid bench problem");
    if seeded {
        let u0 = common::seed_displacement(p);
        sim.set_state(&u0, &u0);
    }
    for _ in 0..SEED_STEPS {
        sim.step().expect("stable");
    }
    let ne = p.mesh.elements.len() as u64;
    let mut g = c.benchmark_group("step");
    g.throughput(Throughput::Elements(ne));
    g.bench_function(BenchmarkId::new(format!("cpu-{}", T::NAME), label), |b| {
        b.iter_custom(|iters| {
            let t = Instant::now();
            for _ in 0..iters {
                sim.step().expect("stable");
            }
            t.elapsed()
        })
    });
    g.finish();
}

fn bench_gpu(c: &mut Criterion, p: &Problem, label: &str, seeded: bool) {
    let ctx = match GpuContext::new() {
        Ok(ctx) => ctx,
        Err(e) => {
            eprintln!("SKIPPED gpu benchmarks for {label}: {e}");
            return;
        }
    };
    eprintln!("gpu benchmarks on {}", ctx.describe());
    let mut sim = GpuSimulation::<f32>::with_context(ctx, p).expect("GPU simulation");
    seed(&mut sim, p, seeded);
    let ne = p.mesh.elements.len() as u64;
    {
        let mut g = c.benchmark_group("host");
        g.throughput(Throughput::Elements(ne));
        g.bench_function(BenchmarkId::new("gpu-f32", label), |b| {
            b.iter_custom(|iters| {
                let t = Instant::now();
                let mut left = iters as usize;
                while left > 0 {
                    let n = left.min(sticky_lips::gpu::sim::MAX_BATCH);
                    drop(std::hint::black_box(sim.bench_host(n)));
                    left -= n;
                }
                t.elapsed()
            })
        });
        g.finish();
    }
    for (name, stage) in [
        ("element_forces", Stage::ElementForces),
        ("node_update", Stage::NodeUpdate),
    ] {
        let mut g = c.benchmark_group(name);
        g.throughput(Throughput::Elements(ne));
        g.bench_function(BenchmarkId::new("gpu-f32", label), |b| {
            b.iter_custom(|iters| {
                let t = Instant::now();
                sim.bench_stage(stage, iters as usize).expect("dispatch");
                t.elapsed()
            })
        });
        g.finish();
    }
    bench_gpu_step(c, &mut sim, "gpu-f32", label);
    let exact_cbrt = sim.shader_real() == ShaderReal::F32ExactCbrt;
    drop(sim);
    let f64_sim = GpuContext::new().and_then(|ctx| GpuSimulation::<f64>::with_context(ctx, p));
    match f64_sim {
        Ok(mut sim) => {
            seed(&mut sim, p, seeded);
            bench_gpu_step(c, &mut sim, "gpu-f64", label);
        }
        Err(e) => eprintln!("SKIPPED step/gpu-f64/{label}: {e}"),
    }
    // on adapters with SHADER_F64 `gpu-f32` refines the cube root in f64 (the CPU's bits);
    // `gpu-f32only` is what adapters without it run, for the price of that exactness
    if exact_cbrt {
        let f32_sim = GpuContext::new()
            .and_then(|ctx| GpuSimulation::<f32>::with_shader_real(ctx, p, ShaderReal::F32));
        match f32_sim {
            Ok(mut sim) => {
                seed(&mut sim, p, seeded);
                bench_gpu_step(c, &mut sim, "gpu-f32only", label);
            }
            Err(e) => eprintln!("SKIPPED step/gpu-f32only/{label}: {e}"),
        }
    }
}

/// The state every GPU measurement starts from: the block's deformed field (when `seeded`),
/// then [`SEED_STEPS`] steps.
fn seed<T: sticky_lips::gpu::GpuReal>(sim: &mut GpuSimulation<T>, p: &Problem, seeded: bool) {
    if seeded {
        let u0 = common::seed_displacement(p);
        sim.set_state(&u0, &u0);
    }
    sim.step_many(SEED_STEPS).expect("stable");
}

/// `step/ID/LABEL`: full steps of `sim` (`GpuSimulation::step_many`).
fn bench_gpu_step<T: sticky_lips::gpu::GpuReal>(
    c: &mut Criterion,
    sim: &mut GpuSimulation<T>,
    id: &str,
    label: &str,
) {
    let mut g = c.benchmark_group("step");
    g.throughput(Throughput::Elements(sim.num_elements() as u64));
    g.bench_function(BenchmarkId::new(id, label), |b| {
        b.iter_custom(|iters| {
            let t = Instant::now();
            sim.step_many(iters as usize).expect("stable");
            t.elapsed()
        })
    });
    g.finish();
}

fn benches(c: &mut Criterion) {
    let cpu = std::env::var("STICKY_LIPS_BENCH_CPU").map_or(true, |v| v != "0");
    for size in sizes() {
        let (p, label, seeded) = match size {
            Size::Block(n) => (block_problem(n), format!("hex={}", n * n * n), true),
            Size::Mouth => (mouth_problem(), "hex=mouth".to_string(), false),
        };
        bench_gpu(c, &p, &label, seeded);
        if cpu {
            bench_cpu::<f32>(c, &p, &label, seeded);
            bench_cpu::<f64>(c, &p, &label, seeded);
        }
    }
}

criterion_group! {
    name = gpu;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    targets = benches
}
criterion_main!(gpu);
