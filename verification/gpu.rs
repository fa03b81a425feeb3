//! The GPU backend (wgpu, `shaders/*.wgsl`) against the CPU, on any adapter (lavapipe
//! included). Three families of claims:
//! - each shared WGSL function equals its Rust f32 twin on seeded random inputs;
//! - whole runs in f32 on the GPU follow the CPU's f32 runs (NiftySim oracle models, a
//!   distorted block with every kind of load and constraint, the coarse mouth with
//!   stickiness, whose breaking events must agree);
//! - GPU runs are deterministic (two runs, identical bits).
//!
//! Without an adapter every test here prints `SKIPPED` and passes; with
//! `STICKY_LIPS_REQUIRE_GPU=1` (set in CI, where lavapipe is installed) it fails instead.
//! Each test writes whether it ran, and on which adapter, to the file named by
//! `STICKY_LIPS_GPU_REPORT`; `scripts/test.sh` prints the count from it (`report`).

use crate::common::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sticky_lips::element::hex8::GradientVariant;
use sticky_lips::gpu::shaders::ShaderReal;
use sticky_lips::gpu::sim::run_function_test;
use sticky_lips::gpu::{GpuContext, GpuSimulation};
use sticky_lips::io::{niftysim, scenario};
use sticky_lips::linalg::{det_identity_plus_minus_one, inverse};
use sticky_lips::material::neo_hookean::{pk2_stress, two_green_strain};
use sticky_lips::material::saliva::{apply_breaking_rule, stretch_across, BreakingRule};
use sticky_lips::tled::element_forces::element_force;
use sticky_lips::tled::Simulation;
use sticky_lips::{Problem, Real};

/// Appends one line to the file `STICKY_LIPS_GPU_REPORT` names (where set): `ran TEST on
/// ADAPTER`, `skipped TEST: WHY` or `partial TEST: WHY`. The test harness captures what a test
/// prints, so a skip would otherwise show as a plain `ok`; `scripts/test.sh` reads the file
/// after `cargo test` and prints how many GPU tests ran, on which adapter, or why they did not.
fn report(line: &str) {
    use std::io::Write;
    let Some(path) = std::env::var_os("STICKY_LIPS_GPU_REPORT") else {
        return;
    };
    // one write of a whole line to a file opened for appending: the tests run on parallel
    // threads, and each line arrives whole
    let mut f = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&path)
        .unwrap_or_else(|e| panic!("STICKY_LIPS_GPU_REPORT {}: {e}", path.to_string_lossy()));
    f.write_all(format!("{line}\n").as_bytes())
        .unwrap_or_else(|e| panic!("STICKY_LIPS_GPU_REPORT {}: {e}", path.to_string_lossy()));
}

/// A device, or `None` after a loud message (a failure with `STICKY_LIPS_REQUIRE_GPU=1`).
fn adapter(test: &str) -> Option<GpuContext> {
    match GpuContext::new() {
        Ok(c) => {
            println!("{test}: adapter {}", c.describe());
            report(&format!("ran {test} on {}", c.describe()));
            Some(c)
        }
        Err(e) => {
            if std::env::var("STICKY_LIPS_REQUIRE_GPU").is_ok_and(|v| v == "1") {
                report(&format!("failed {test}: no adapter: {e}"));
                panic!("{test}: STICKY_LIPS_REQUIRE_GPU=1 and {e}");
            }
            report(&format!("skipped {test}: {e}"));
            eprintln!(
                "SKIPPED {test}: {e}. Install a Vulkan driver (lavapipe: mesa-vulkan-drivers) \
                 and set WGPU_BACKEND=vulkan; STICKY_LIPS_REQUIRE_GPU=1 turns this into a failure"
            );
            None
        }
    }
}

/// Distance in units in the last place between two finite f32 (0 = same bits).
fn ulps(a: f32, b: f32) -> u32 {
    let key = |x: f32| {
        let i = x.to_bits() as i32;
        if i < 0 {
            i32::MIN.wrapping_sub(i)
        } else {
            i
        }
    };
    (key(a) as i64 - key(b) as i64).unsigned_abs() as u32
}

/// An `R x C` array of `scale * U(-1, 1)` draws, row by row.
fn rand_mat<const R: usize, const C: usize>(rng: &mut ChaCha8Rng, scale: f32) -> [[f32; C]; R] {
    std::array::from_fn(|_| std::array::from_fn(|_| scale * rng.random_range(-1.0f32..1.0)))
}

/// `max_i |a_i - b_i| / max_i |b_i|`.
fn rel(a: &[f32], b: &[f32]) -> f64 {
    let num = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs() as f64)
        .fold(0.0, f64::max);
    let den = b.iter().map(|y| y.abs() as f64).fold(0.0, f64::max);
    num / den
}

const RECORDS: usize = 4096;

#[test]
fn wgsl_functions_match_rust_f32() {
    let Some(ctx) = adapter("wgsl_functions_match_rust_f32") else {
        return;
    };
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    let eps = f32::EPSILON as f64;

    // cbrt_r vs the CPU's Real::cbrt (f32) over the range J^2 takes in practice and beyond
    // many more inputs for the cube root (cheap): 2^16
    const CBRT_RECORDS: usize = 1 << 16;
    let x: Vec<f32> = (0..CBRT_RECORDS)
        .map(|i| {
            if i % 2 == 0 {
                rng.random_range(0.2f32..5.0)
            } else {
                10f32.powf(rng.random_range(-6.0f32..6.0))
            }
        })
        .collect();
    let g =
        run_function_test::<f32>(&ctx, ShaderReal::F32, "test_cbrt", &x, CBRT_RECORDS, 1).unwrap();
    let worst = x
        .iter()
        .zip(&g)
        .map(|(x, g)| ulps(*g, <f32 as Real>::cbrt(*x)))
        .max()
        .unwrap();
    println!(
        "cbrt_r (f32 only): max {worst} ulp from Real::cbrt (f32) over {CBRT_RECORDS} inputs in [1e-6, 1e6]"
    );
    // 1 ulp: Newton's iteration converges to within round-off of the exact root; the CPU's
    // is the correctly rounded root; the two differ by at most one ulp
    assert!(worst <= 1, "cbrt_r differs from Real::cbrt by {worst} ulp");
    if ctx.has_f64 {
        let g = run_function_test::<f32>(
            &ctx,
            ShaderReal::F32ExactCbrt,
            "test_cbrt",
            &x,
            CBRT_RECORDS,
            1,
        )
        .unwrap();
        let differ = x
            .iter()
            .zip(&g)
            .filter(|(x, g)| g.to_bits() != <f32 as Real>::cbrt(**x).to_bits())
            .count();
        println!(
            "cbrt_r (refined in f64): {differ} of {CBRT_RECORDS} differ from Real::cbrt (f32)"
        );
        // the f64 refinement is below one f64 ulp: rounding it gives the CPU's root
        assert_eq!(
            differ, 0,
            "the f64-refined cbrt_r must equal Real::cbrt bit for bit"
        );
    }
    // the rest runs the kernels a run uses on this adapter
    let real = if ctx.has_f64 {
        ShaderReal::F32ExactCbrt
    } else {
        ShaderReal::F32
    };

    // pk2_stress, det_identity_plus_minus_one, two_green_strain, inverse3
    let mut input = Vec::with_capacity(11 * RECORDS);
    let mut hs = Vec::new();
    for _ in 0..RECORDS {
        let h = rand_mat(&mut rng, 0.3);
        let mu = rng.random_range(500.0f32..8000.0);
        let k = rng.random_range(5e3f32..2e5);
        input.extend(h.iter().flatten());
        input.push(mu);
        input.push(k);
        hs.push((h, mu, k));
    }
    let g = run_function_test::<f32>(&ctx, real, "test_pk2_stress", &input, RECORDS, 29).unwrap();
    let (mut w_s, mut w_j, mut w_e, mut w_i) = (0.0f64, 0u32, 0u32, 0.0f64);
    for (r, (h, mu, k)) in hs.iter().enumerate() {
        let o = &g[29 * r..29 * (r + 1)];
        let (s, j) = pk2_stress(h, *mu, *k);
        w_s = w_s.max(rel(&o[0..9], s.as_flattened()));
        w_j = w_j
            .max(ulps(o[9], j))
            .max(ulps(o[10], det_identity_plus_minus_one(h)));
        let e2 = two_green_strain(h);
        w_e = w_e.max(
            e2.as_flattened()
                .iter()
                .zip(&o[11..20])
                .map(|(a, b)| ulps(*a, *b))
                .max()
                .unwrap(),
        );
        let mut f = *h;
        for (i, row) in f.iter_mut().enumerate() {
            row[i] += 1.0;
        }
        w_i = w_i.max(rel(&o[20..29], inverse(&f).as_flattened()));
    }
    println!(
        "pk2_stress: S rel {:.2e} ({:.1} eps); J, det(I+H)-1: {w_j} ulp; two_green_strain: {w_e} ulp; inverse3: rel {:.2e} ({:.1} eps)",
        w_s,
        w_s / eps,
        w_i,
        w_i / eps
    );
    // The same operations in the same order: only FMA contraction by the shader compiler
    // (each contracted a*b+c saves one rounding) and cbrt_r's 1 ulp can differ. A rounding
    // difference in C = I + E is amplified by C^-1 by the condition number of C (< 10 for
    // |H| <= 0.3): 32 eps covers both; a wrong term or index would give O(1).
    assert!(w_j <= 4, "J differs by {w_j} ulp");
    assert!(w_e <= 2, "two_green_strain differs by {w_e} ulp");
    assert!(w_i <= 32.0 * eps, "inverse3 differs by {w_i:e}");
    assert!(w_s <= 32.0 * eps, "pk2_stress differs by {w_s:e}");

    // element_force (eq. 4 + hourglass) on random distorted-element data
    let mut input = Vec::with_capacity(84 * RECORDS);
    let mut recs = Vec::new();
    for _ in 0..RECORDS {
        let ue: [[f32; 3]; 8] = rand_mat(&mut rng, 1e-3);
        let d: [[f32; 3]; 8] = rand_mat(&mut rng, 50.0);
        let w = rng.random_range(1e-7f32..1e-6);
        let gamma: [[f32; 4]; 8] = rand_mat(&mut rng, 1.0);
        let k = rng.random_range(1e-2f32..1.0);
        let mu = rng.random_range(500.0f32..8000.0);
        let bulk = rng.random_range(5e3f32..2e5);
        input.extend(ue.as_flattened());
        input.extend(d.as_flattened());
        input.push(w);
        input.extend(gamma.as_flattened());
        input.extend([k, mu, bulk]);
        recs.push((ue, d, w, gamma, k, mu, bulk));
    }
    let g =
        run_function_test::<f32>(&ctx, real, "test_element_force", &input, RECORDS, 25).unwrap();
    let (mut w_f, mut w_j) = (0.0f64, 0u32);
    for (r, (ue, d, w, gamma, k, mu, bulk)) in recs.iter().enumerate() {
        let (f, j) = element_force(ue, d, *w, gamma, *k, *mu, *bulk);
        w_f = w_f.max(rel(&g[25 * r..25 * r + 24], f.as_flattened()));
        w_j = w_j.max(ulps(g[25 * r + 24], j));
    }
    println!(
        "element_force: f rel {w_f:.2e} ({:.1} eps), J {w_j} ulp",
        w_f / eps
    );
    // as pk2_stress, plus the sums of 8 products (each may be contracted): 64 eps
    assert!(w_f <= 64.0 * eps, "element_force differs by {w_f:e}");
    assert!(w_j <= 4, "element J differs by {w_j} ulp");

    // stretch_across (eqs. 8-10) and apply_breaking_rule (eq. 11), both rules, both states
    let mut input = Vec::with_capacity(64 * RECORDS);
    let mut recs = Vec::new();
    for r in 0..RECORDS {
        let h = rand_mat(&mut rng, 0.2);
        let y: [f32; 3] = {
            let v: [f32; 3] = std::array::from_fn(|_| rng.random_range(-1.0f32..1.0));
            let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            v.map(|c| c / n)
        };
        let z = rng.random_range(0.8f32..1.6);
        let rule = (r % 2) as u32;
        let decay = 0.99f32;
        let broken = (r / 2) % 2 == 1;
        let f: [[f32; 3]; 8] = rand_mat(&mut rng, 1.0);
        let p: [[f32; 3]; 8] = rand_mat(&mut rng, 1.0);
        input.extend(h.as_flattened());
        input.extend(y);
        input.extend([z, rule as f32, decay, if broken { 1.0 } else { 0.0 }]);
        input.extend(f.as_flattened());
        input.extend(p.as_flattened());
        recs.push((h, y, z, rule, decay, broken, f, p));
    }
    let g = run_function_test::<f32>(&ctx, real, "test_saliva", &input, RECORDS, 50).unwrap();
    let (mut w_q, mut mismatched, mut decided_equal) = (0u32, 0usize, 0usize);
    for (r, (h, y, z, rule, decay, broken, f, p)) in recs.iter().enumerate() {
        let o = &g[50 * r..50 * (r + 1)];
        let q = stretch_across(h, y);
        w_q = w_q.max(ulps(o[0], q));
        if o[0] != q {
            continue; // the rule below is compared where both sides see the same Q
        }
        let (mut f, mut p) = (*f, *p);
        let rule = if *rule == 1 {
            BreakingRule::Latched
        } else {
            BreakingRule::Literal
        };
        let b = apply_breaking_rule(q, *z, rule, *decay, *broken, &mut f, &mut p);
        decided_equal += 1;
        if (o[1] != 0.0) != b || o[2..26] != *f.as_flattened() || o[26..50] != *p.as_flattened() {
            mismatched += 1;
        }
    }
    println!("stretch_across: {w_q} ulp; apply_breaking_rule: {mismatched} of {decided_equal} records differ");
    assert!(w_q <= 4, "stretch_across differs by {w_q} ulp");
    // the rule is a selection and one multiplication: identical bits
    assert_eq!(mismatched, 0, "apply_breaking_rule differs");
    assert!(decided_equal > RECORDS / 2);
}

/// Runs `p` on the CPU in f32, on the GPU in f32 (kernels `real`) and on the CPU in f64,
/// `frame` steps at a time, and returns the largest `|u_gpu - u_cpu32| / max|u_cpu32|` over
/// the frames, the same for CPU f32 vs f64, and both f32 simulations.
fn compare_runs(
    ctx: GpuContext,
    real: ShaderReal,
    p: &Problem,
    frame: usize,
) -> (
    f64,
    f64,
    Simulation<f32>,
    GpuSimulation<f32>,
    Simulation<f64>,
) {
    let mut cpu = Simulation::<f32>::new(p).unwrap();
    let mut cpu64 = Simulation::<f64>::new(p).unwrap();
    let mut gpu = GpuSimulation::<f32>::with_shader_real(ctx, p, real).unwrap();
    let (mut gpu_vs_cpu, mut f32_vs_f64) = (0.0f64, 0.0f64);
    while !cpu.is_finished() {
        for _ in 0..frame {
            if cpu.is_finished() {
                break;
            }
            cpu.step().unwrap();
            cpu64.step().unwrap();
        }
        gpu.step_many(frame).unwrap();
        assert_eq!(gpu.step_index(), cpu.step_index());
        let uc = cpu.displacement_f64();
        gpu_vs_cpu = gpu_vs_cpu.max(rel_max_diff(&gpu.displacement_f64().unwrap(), &uc));
        f32_vs_f64 = f32_vs_f64.max(rel_max_diff(&uc, &cpu64.displacement_f64()));
    }
    (gpu_vs_cpu, f32_vs_f64, cpu, gpu, cpu64)
}

const ORACLE: [&str; 5] = [
    "hex1_stretch",
    "hex1_stretch_minbc",
    "hex1_distorted",
    "block4_compress",
    "cantilever_tipdisp",
];

/// Whether the element kernel's functions return the CPU's bits on this adapter with the
/// f64-refined cube root (no FMA contraction or other reassociation by the shader
/// compiler): probed on 256 seeded random elements.
fn kernels_bit_exact(ctx: &GpuContext) -> bool {
    if !ctx.has_f64 {
        return false;
    }
    let mut rng = ChaCha8Rng::seed_from_u64(61);
    let n = 256;
    let mut input = Vec::with_capacity(84 * n);
    let mut recs = Vec::new();
    for _ in 0..n {
        let ue: [[f32; 3]; 8] = rand_mat(&mut rng, 1e-3);
        let d: [[f32; 3]; 8] = rand_mat(&mut rng, 50.0);
        let gamma: [[f32; 4]; 8] = rand_mat(&mut rng, 1.0);
        input.extend(ue.as_flattened());
        input.extend(d.as_flattened());
        input.push(5e-7);
        input.extend(gamma.as_flattened());
        input.extend([0.1, 800.0, 7000.0]);
        recs.push((ue, d, gamma));
    }
    let g = run_function_test::<f32>(
        ctx,
        ShaderReal::F32ExactCbrt,
        "test_element_force",
        &input,
        n,
        25,
    )
    .unwrap();
    recs.iter().enumerate().all(|(r, (ue, d, gamma))| {
        let (f, _) = element_force(ue, d, 5e-7, gamma, 0.1, 800.0, 7000.0);
        g[25 * r..25 * r + 24] == *f.as_flattened()
    })
}

/// The bound for a whole run, GPU-f32 vs CPU-f32.
///
/// - Kernels bit-exact on this adapter (f64-refined cube root, no contraction; lavapipe):
///   the same f32 operations in the same order on the same f32 data, and a fixed gather
///   order: the runs must be identical, bound 0.
/// - Otherwise (f32-only cube root, 1 ulp; or a compiler that contracts a*b+c): each step
///   perturbs the state by a few ulp, which the dynamics carry like the CPU's own f32
///   round-off. The difference is then of the size of the CPU-f32 vs CPU-f64 difference
///   (measured 0.4x-1.4x of it); bound: twice that, at least 64 eps.
fn run_bound(exact: bool, f32_vs_f64: f64) -> f64 {
    if exact {
        0.0
    } else {
        (2.0 * f32_vs_f64).max(64.0 * f32::EPSILON as f64)
    }
}

/// The kernel variants this adapter runs: the one a run picks, and on an adapter with f64
/// also the f32-only cube root (what adapters without SHADER_F64 run).
fn variants(ctx: &GpuContext) -> Vec<ShaderReal> {
    if ctx.has_f64 {
        vec![ShaderReal::F32ExactCbrt, ShaderReal::F32]
    } else {
        vec![ShaderReal::F32]
    }
}

#[test]
fn gpu_f32_follows_cpu_f32_on_niftysim_models() {
    let Some(probe) = adapter("gpu_f32_follows_cpu_f32_on_niftysim_models") else {
        return;
    };
    let exact_adapter = kernels_bit_exact(&probe);
    for real in variants(&probe) {
        for name in ORACLE {
            let ctx = GpuContext::new().unwrap();
            let p = niftysim::read(
                &oracle_dir().join(format!("{name}.xml")),
                GradientVariant::Centroid,
                true,
            )
            .unwrap();
            let every = (p.num_steps() / 10).max(1);
            let (d, prec, mut cpu, mut gpu, mut cpu64) = compare_runs(ctx, real, &p, every);
            let fc = cpu.internal_forces();
            let fg = gpu.internal_forces().unwrap();
            let df = rel_max_diff(&fg, &fc);
            // the internal forces get the same kind of bound as U, from their own f32-vs-f64
            // difference (forces are differences of large element terms, so theirs is larger)
            let prec_f = rel_max_diff(&fc, &cpu64.internal_forces());
            let exact = exact_adapter && real == ShaderReal::F32ExactCbrt;
            let (bound, bound_f) = (run_bound(exact, prec), run_bound(exact, prec_f));
            println!(
                "{name} ({real:?}): {} steps; GPU-f32 vs CPU-f32: U {d:.2e}, Fint {df:.2e}; CPU-f32 vs CPU-f64: U {prec:.2e}, Fint {prec_f:.2e}; bounds U {bound:.2e}, Fint {bound_f:.2e}",
                p.num_steps(),
            );
            assert!(
                d <= bound,
                "{name} ({real:?}): GPU-f32 differs from CPU-f32 by {d:e}"
            );
            assert!(
                df <= bound_f,
                "{name} ({real:?}): GPU-f32 internal forces differ from CPU-f32 by {df:e}"
            );
        }
    }
}

/// A distorted 4x3x3 block (Jacobian ratios far from 1) with every kind of boundary
/// condition and load the node kernel implements: fixed face, prescribed displacement
/// (POLY345), prescribed rigid rotation (the jaw's mechanism), nodal force (HILLY), gravity
/// (RAMP) and a muscle (SMOOTH_STEP), mean-gradient element, damping.
fn distorted_block_problem() -> Problem {
    let text = r#"
[mesh]
generator = "distorted_block"
origin = [0.0, 0.0, 0.0]
size = [0.04, 0.02, 0.02]
cells = [4, 3, 3]
distortion = 0.25
seed = 11

[[node_sets]]
name = "tip"
box_min = [0.04, 0.0, 0.0]
box_max = [0.04, 0.02, 0.02]

[[node_sets]]
name = "top_mid"
box_min = [0.015, 0.0, 0.02]
box_max = [0.025, 0.02, 0.02]

[[materials]]
name = "tissue"
mu = 800.0
K = 7000.0
density = 1050.0

[[fix]]
nodes = "x_min"

[[rotation]]
nodes = "tip"
point = [0.04, 0.01, 0.01]
axis = [0.0, 1.0, 0.0]
angle = 0.2
shape = "smooth_step"
duration = 0.05

[[displacement]]
nodes = "top_mid"
dof = "z"
value = 0.002
shape = "poly345"
duration = 0.04

[[force]]
nodes = "y_max"
dof = "y"
value = 1e-3
shape = "hilly"
duration = 0.06

[gravity]
acceleration = [0.0, 0.0, -9.81]
shape = "ramp"
duration = 0.03

[[muscle]]
name = "pull"
origin = [0.0, 0.01, 0.01]
insertion = [0.03, 0.01, 0.01]
radius = 0.006
strength = 5e-3
shape = "smooth_step"
duration = 0.02

[time]
dt = 1e-4
total = 0.08
output_every = 50

[numerics]
damping = 20.0
"#;
    scenario::parse(text, std::path::Path::new("distorted_block.toml"))
        .unwrap()
        .problem
}

#[test]
fn gpu_f32_follows_cpu_f32_on_a_distorted_block() {
    let Some(probe) = adapter("gpu_f32_follows_cpu_f32_on_a_distorted_block") else {
        return;
    };
    let exact_adapter = kernels_bit_exact(&probe);
    let p = distorted_block_problem();
    assert!(
        !p.bc.rotations.is_empty() && !p.bc.gravity.is_empty() && !p.physics.muscles.is_empty()
    );
    for real in variants(&probe) {
        let (d, prec, cpu, _, _) = compare_runs(GpuContext::new().unwrap(), real, &p, 50);
        let umax = cpu
            .displacement_f64()
            .iter()
            .flatten()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        let bound = run_bound(exact_adapter && real == ShaderReal::F32ExactCbrt, prec);
        println!(
            "distorted block ({real:?}): {} steps, max |u| {umax:.3e} m; GPU-f32 vs CPU-f32 {d:.2e}; CPU-f32 vs CPU-f64 {prec:.2e}; bound {bound:.2e}",
            p.num_steps(),
        );
        assert!(umax > 1e-3, "the block must deform (max |u| = {umax:e})");
        assert!(
            d <= bound,
            "({real:?}) GPU-f32 differs from CPU-f32 by {d:e}"
        );
    }
}

#[test]
fn gpu_runs_are_deterministic() {
    let Some(ctx) = adapter("gpu_runs_are_deterministic") else {
        return;
    };
    let p = distorted_block_problem();
    let mut a = GpuSimulation::<f32>::with_context(ctx, &p).unwrap();
    let ctx2 = GpuContext::new().unwrap();
    let mut b = GpuSimulation::<f32>::with_context(ctx2, &p).unwrap();
    // different batchings of the same steps: the result must not depend on them either
    a.step_many(p.num_steps()).unwrap();
    while !b.is_finished() {
        b.step_many(37).unwrap();
    }
    let ua: Vec<u32> = a
        .displacement()
        .unwrap()
        .iter()
        .flatten()
        .map(|x| x.to_bits())
        .collect();
    let ub: Vec<u32> = b
        .displacement()
        .unwrap()
        .iter()
        .flatten()
        .map(|x| x.to_bits())
        .collect();
    let differ = ua.iter().zip(&ub).filter(|(x, y)| x != y).count();
    println!(
        "gpu_runs_are_deterministic: {differ} of {} displacement bits differ",
        ua.len()
    );
    assert_eq!(differ, 0);
    assert!(ua.iter().any(|&x| x != 0));
}

/// The coarse mouth of `paper --quick` with stickiness (fig4_sticky.toml), run until the lips
/// have partly separated: the GPU must break the same saliva elements as the CPU, each within a
/// few steps of the CPU's step.
#[test]
fn gpu_breaking_events_match_cpu_on_the_coarse_mouth() {
    let Some(ctx) = adapter("gpu_breaking_events_match_cpu_on_the_coarse_mouth") else {
        return;
    };
    // the procedural mouth's wide opening with stickiness at --quick resolution (0.25)
    use sticky_lips::paper::{scenario_of, spec, Model};
    let run = spec(Model::Procedural, true, "fig4_sticky").unwrap();
    let (_, mut p) = scenario_of(
        Model::Procedural,
        true,
        &run,
        std::path::Path::new("fig4_sticky"),
    )
    .unwrap();
    // every saliva element of this mesh breaks between 0.354 s and 0.373 s (CPU f32)
    p.time.total_time = 0.38;
    let mut cpu = Simulation::<f32>::new(&p).unwrap();
    let exact = kernels_bit_exact(&ctx);
    let mut gpu = GpuSimulation::<f32>::with_context(ctx, &p).unwrap();
    let t0 = std::time::Instant::now();
    while !cpu.is_finished() {
        cpu.step().unwrap();
    }
    let t_cpu = t0.elapsed().as_secs_f64();
    let t0 = std::time::Instant::now();
    gpu.step_many(p.num_steps()).unwrap();
    let t_gpu = t0.elapsed().as_secs_f64();
    let dt = p.time.dt;
    let step_of = |t: f64| {
        if t.is_nan() {
            None
        } else {
            Some((t / dt).round() as i64)
        }
    };
    let ec: Vec<Option<i64>> = cpu.saliva().broken_at.iter().map(|&t| step_of(t)).collect();
    let eg: Vec<Option<i64>> = gpu
        .saliva()
        .unwrap()
        .broken_at
        .iter()
        .map(|&t| step_of(t))
        .collect();
    let broke_cpu = ec.iter().filter(|e| e.is_some()).count();
    let only_one = ec
        .iter()
        .zip(&eg)
        .filter(|(a, b)| a.is_some() != b.is_some())
        .count();
    let worst_shift = ec
        .iter()
        .zip(&eg)
        .filter_map(|(a, b)| Some((a.as_ref()? - b.as_ref()?).abs()))
        .max()
        .unwrap_or(0);
    let same_step = ec
        .iter()
        .zip(&eg)
        .filter(|(a, b)| a.is_some() && a == b)
        .count();
    let d = rel_max_diff(&gpu.displacement_f64().unwrap(), &cpu.displacement_f64());
    println!(
        "coarse mouth ({:?}): {} hexahedra, {} saliva, {} steps (CPU {t_cpu:.1} s, GPU {t_gpu:.1} s); CPU broke {broke_cpu}, \
         GPU broke {}; {only_one} broke on one side only; {same_step} at the same step; worst shift {worst_shift} steps; U rel {d:.2e}",
        gpu.shader_real(),
        p.mesh.elements.len(),
        ec.len(),
        p.num_steps(),
        eg.iter().filter(|e| e.is_some()).count()
    );
    assert!(
        broke_cpu >= 5,
        "the run must break saliva elements (it broke {broke_cpu})"
    );
    // Breaking is a threshold: where the kernels are not bit-exact, a few-ulp difference in
    // Q can move an event by a step or two, after which the runs differ by a decaying-force
    // perturbation. Window: the same set of broken elements, each within 50 steps (0.5 ms
    // of the 19 ms over which the 16 elements break); on a bit-exact adapter, 0 steps.
    if exact {
        assert_eq!(d, 0.0, "bit-exact kernels: the runs must be identical");
        assert_eq!(worst_shift, 0);
    }
    assert_eq!(only_one, 0, "elements broken on one backend only");
    assert!(
        worst_shift <= 50,
        "a breaking event moved by {worst_shift} steps"
    );
}

/// The f64 kernels (adapters with SHADER_F64) on the NiftySim models against the CPU's f64
/// runs. The cube root (f32 guess, two f64 Newton steps) is within about one f64 ulp of the
/// CPU's, so the runs differ at the level of f64 round-off carried by the dynamics: bound
/// 1e-12 relative (~4500 eps64, the round-off of up to 10^4 steps).
#[test]
fn gpu_f64_follows_cpu_f64_on_niftysim_models() {
    let Some(probe) = adapter("gpu_f64_follows_cpu_f64_on_niftysim_models") else {
        return;
    };
    if !probe.has_f64 {
        println!(
            "gpu_f64_follows_cpu_f64_on_niftysim_models: {} has no SHADER_F64; nothing to compare",
            probe.describe()
        );
        report(&format!(
            "partial gpu_f64_follows_cpu_f64_on_niftysim_models: {} has no SHADER_F64, no f64 run compared",
            probe.describe()
        ));
        return;
    }
    for name in ORACLE {
        let p = niftysim::read(
            &oracle_dir().join(format!("{name}.xml")),
            GradientVariant::Centroid,
            true,
        )
        .unwrap();
        let mut cpu = Simulation::<f64>::new(&p).unwrap();
        while !cpu.is_finished() {
            cpu.step().unwrap();
        }
        let mut gpu = GpuSimulation::<f64>::with_context(GpuContext::new().unwrap(), &p).unwrap();
        gpu.step_many(p.num_steps()).unwrap();
        let d = rel_max_diff(&gpu.displacement_f64().unwrap(), &cpu.displacement_f64());
        println!("{name}: GPU-f64 vs CPU-f64: U {d:.2e}");
        assert!(d <= 1e-12, "{name}: GPU-f64 differs from CPU-f64 by {d:e}");
    }
}

/// `(step, element, node)` of a divergence error.
fn divergence(e: &sticky_lips::Error) -> (usize, Option<usize>, Option<usize>) {
    match e {
        sticky_lips::Error::Diverged {
            step,
            element,
            node,
            time,
            ..
        } => {
            assert!(*time >= 0.0);
            (*step, *element, *node)
        }
        other => panic!("expected a divergence, got {other}"),
    }
}

/// A run with a time step 0.5 % above the critical one (the distorted block, fixed at one
/// end, no loads, started from a 1e-20 m seeded perturbation) grows its highest mode until an
/// element inverts, in the second batch of steps while the third is already submitted
/// (batches are pipelined). The GPU must stop there with the step, time and element of the
/// CPU, and leave the state before the failing step: with bit-exact kernels the CPU's state
/// bit for bit; otherwise a finite state, the step within 2 % of the CPU's.
#[test]
fn gpu_divergence_stops_where_the_cpu_does() {
    use sticky_lips::boundary::Fixed;
    use sticky_lips::gpu::sim::MAX_BATCH;
    use sticky_lips::tled::precompute::Discretisation;
    use sticky_lips::tled::stability::analyse;
    let Some(probe) = adapter("gpu_divergence_stops_where_the_cpu_does") else {
        return;
    };
    let exact_adapter = kernels_bit_exact(&probe);
    let mut p = distorted_block_problem();
    p.bc = Default::default();
    p.physics = Default::default();
    p.bc.fixed.push(Fixed {
        nodes: p.mesh.node_sets["x_min"].clone(),
        dofs: [true; 3],
    });
    let dtc = analyse(&p, &Discretisation::new(&p)).critical_time_step;
    p.time.dt = 1.005 * dtc;
    p.time.total_time = 5000.0 * p.time.dt;
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let u0: Vec<[f64; 3]> = p
        .mesh
        .nodes
        .iter()
        .map(|x| {
            if x[0] > 0.0 {
                std::array::from_fn(|_| 1e-20 * rng.random_range(-1.0..1.0))
            } else {
                [0.0; 3]
            }
        })
        .collect();
    let mut cpu = Simulation::<f32>::new(&p).unwrap();
    cpu.set_state(&u0, &u0);
    let cpu_err = loop {
        match cpu.step() {
            Ok(()) => assert!(!cpu.is_finished(), "the CPU run did not diverge"),
            Err(e) => break e,
        }
    };
    let (cs, ce, cn) = divergence(&cpu_err);
    assert_eq!(
        cpu.step_index(),
        cs,
        "the CPU keeps the state before the failing step"
    );
    assert!(
        cs > MAX_BATCH && cs + MAX_BATCH < p.num_steps(),
        "the failure (step {cs}) must fall in a batch that has a later batch behind it"
    );
    for real in variants(&probe) {
        let mut gpu =
            GpuSimulation::<f32>::with_shader_real(GpuContext::new().unwrap(), &p, real).unwrap();
        gpu.set_state(&u0, &u0);
        let e = gpu
            .step_many(p.num_steps())
            .expect_err("the GPU run must diverge");
        let (gs, ge, gn) = divergence(&e);
        println!("divergence ({real:?}): CPU {cpu_err}; GPU {e}");
        assert_eq!(gpu.step_index(), gs);
        let ug = gpu.displacement_f64().unwrap();
        if exact_adapter && real == ShaderReal::F32ExactCbrt {
            assert_eq!((gs, ge, gn), (cs, ce, cn), "GPU {e} vs CPU {cpu_err}");
            assert!(
                ug == cpu.displacement_f64(),
                "the state left behind must be the CPU's, bit for bit"
            );
        } else {
            assert!(
                gs.abs_diff(cs) * 50 <= cs,
                "GPU diverged at step {gs}, CPU at {cs}"
            );
            assert!(ug.iter().flatten().all(|x| x.is_finite()));
        }
    }
}
