//! Criterion benchmarks of the TLED time step, stage by stage (see `benches/README.md`).
//!
//! Benchmark ids are `STAGE/PRECISION/threads=K/hex=N`:
//!
//! - `element_forces`: stage 1, the 8x3 internal-force block of every element
//!   (`tled::element_forces::element_forces`) at a fixed deformed state;
//! - `node_update`: stage 2, gather of the element blocks at every node and the
//!   central-difference update (`tled::node_update::node_update`), fixed inputs;
//! - `step`: one full `Simulation::step` (both stages, constraints, buffer rotation),
//!   the state advancing from one iteration to the next as in a run.
//!
//! The model is NiftySim's `timing_block20` setup scaled to `N = n^3` hexahedra: a block
//! of side 0.04 m, neo-Hookean mu = 1000 Pa, K = 10000 Pa, density 1000 kg/m^3, damping
//! 50 1/s, hourglass kappa 0.075, centroid gradients, base (`z_min`) fixed, top (`z_max`)
//! driven in z by a RAMP to -0.004 m over 0.1 s, dt = 1e-4 s. The state is seeded with a
//! deformed displacement field (lateral bulge and axial compression, zero at the constrained
//! faces) and advanced a few steps, so every element is in a deformed configuration.
//!
//! Throughput is `Elements(N)`: criterion's "elem/s" is element-updates per second for
//! every stage (for `node_update` too, so that stage times per element add up to `step`).
//!
//! Sizes: `STICKY_LIPS_BENCH_SIZES=1000,8000` (default `1000,8000,64000`; any cube
//! `n^3` is accepted, e.g. `512000` = 80^3; a `k` suffix means thousands, `64k`).
//! Thread counts: `STICKY_LIPS_BENCH_THREADS=1,2` (default `1,2`).
//! `step/PRECISION/threads=K/mouth=N` is the paper's scene (the procedural mouth's `fig4_sticky` run (`sticky_lips::paper`, Table 1 on the procedural mouth):
//! the mouth at paper resolution with its saliva layer, breaking rule and jaw);
//! `STICKY_LIPS_BENCH_MOUTH=0` leaves it out.
//! `STICKY_LIPS_BENCH_STABILITY=1` prints each block's critical time step (Lanczos) first.
//! `STICKY_LIPS_BENCH_QUIET=10` waits (up to 10 s) before each sample until no other
//! process is using the CPUs (Linux; for shared machines, see `benches/README.md`).
//! Criterion's own flags work after `--`, e.g.
//! `cargo bench --bench tled -- 'element_forces/f32' --measurement-time 10`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use rayon::ThreadPool;
use std::hint::black_box;
use std::time::{Duration, Instant};
use sticky_lips::tled::element_forces::{element_forces, ElementArrays};
use sticky_lips::tled::node_update::{node_update, CentralDifference};
use sticky_lips::tled::simd::SimdReal;
use sticky_lips::tled::Simulation;
use sticky_lips::Problem;

mod common;
use common::RAMP_TIME;

/// Steps run after seeding the state, before any measurement.
const SEED_STEPS: usize = 5;

fn parse_list(var: &str, default: &str) -> Vec<usize> {
    let s = std::env::var(var).unwrap_or_else(|_| default.to_string());
    s.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
        .map(|t| {
            let t = t.trim();
            let (num, mul) = match t.strip_suffix(['k', 'K']) {
                Some(n) => (n, 1000),
                None => (t, 1),
            };
            num.parse::<usize>()
                .map(|v| v * mul)
                .unwrap_or_else(|_| panic!("{var}: cannot parse {t:?} as a count"))
        })
        .collect()
}

/// Cells per side for `n` hexahedra (`n` must be a cube).
fn cells_per_side(n: usize) -> usize {
    let c = (n as f64).cbrt().round() as usize;
    assert!(
        c >= 1 && c * c * c == n,
        "STICKY_LIPS_BENCH_SIZES: {n} is not a cube number of hexahedra (1000, 8000, 64000, 512000, ...)"
    );
    c
}

/// The `timing_block20` problem with `c^3` hexahedra (`common::block_problem`).
fn block_problem(c: usize) -> Problem {
    let p = common::block_problem(c, RAMP_TIME);
    if std::env::var_os("STICKY_LIPS_BENCH_STABILITY").is_some() {
        let d = sticky_lips::tled::precompute::Discretisation::new(&p);
        let r = sticky_lips::tled::stability::analyse(&p, &d);
        eprintln!(
            "block {c}^3: dt = {:.3e} s, critical (2/omega_max) = {:.3e} s, L_e/c_e = {:.3e} s",
            p.time.dt, r.critical_time_step, r.element_estimate
        );
    }
    p
}

/// Everything one (size, precision) pair needs: a running simulation in a deformed state,
/// and the inputs of the two stages taken from it.
struct Fixture<T: SimdReal> {
    sim: Simulation<T>,
    el: ElementArrays<T>,
    cd: CentralDifference<T>,
    u: Vec<[T; 3]>,
    u_prev: Vec<[T; 3]>,
    u_next: Vec<[T; 3]>,
    elem_f: Vec<[[T; 3]; 8]>,
}

impl<T: SimdReal> Fixture<T> {
    fn new(p: &Problem) -> Self {
        let mut sim = Simulation::<T>::new(p).expect("bench problem is valid");
        let u0 = common::seed_displacement(p);
        sim.set_state(&u0, &u0);
        for _ in 0..SEED_STEPS {
            sim.step().expect("seed steps stay stable");
        }
        let el = ElementArrays::<T>::from_discretisation(&sim.disc);
        let cd = CentralDifference::<T>::new(p.time.dt, p.numerics.damping, &sim.disc.mass);
        let u = sim.displacement().to_vec();
        let u_prev = sim.previous_displacement().to_vec();
        let mut elem_f = vec![[[T::ZERO; 3]; 8]; el.len()];
        assert_eq!(element_forces(&el, &u, &mut elem_f), None);
        Fixture {
            u_next: vec![[T::ZERO; 3]; u.len()],
            sim,
            el,
            cd,
            u,
            u_prev,
            elem_f,
        }
    }
}

/// `(busy, total)` CPU time of all CPUs since boot, in clock ticks (Linux `/proc/stat`).
fn cpu_ticks() -> Option<(u64, u64)> {
    let s = std::fs::read_to_string("/proc/stat").ok()?;
    let v: Vec<u64> = s
        .lines()
        .next()?
        .split_whitespace()
        .skip(1)
        .filter_map(|x| x.parse().ok())
        .collect();
    let total: u64 = v.iter().sum();
    Some((total - v.get(3)? - v.get(4)?, total))
}

/// With `STICKY_LIPS_BENCH_QUIET=S`, waits (at most `S` s) before each sample until the
/// machine is idle: less than 5 % of all CPUs busy over 0.25 s. For shared machines. It is
/// called outside `iter_custom`, so criterion's clock (warm-up included) never sees it.
/// Off by default, and where `/proc/stat` is missing.
fn wait_quiet() {
    static LIMIT: std::sync::OnceLock<Option<Duration>> = std::sync::OnceLock::new();
    let limit = LIMIT.get_or_init(|| {
        std::env::var("STICKY_LIPS_BENCH_QUIET")
            .ok()
            .and_then(|v| v.parse::<f64>().ok())
            .filter(|&s| s > 0.0)
            .map(Duration::from_secs_f64)
    });
    let Some(limit) = *limit else { return };
    let t0 = Instant::now();
    while t0.elapsed() < limit {
        let Some((b0, a0)) = cpu_ticks() else { return };
        std::thread::sleep(Duration::from_millis(250));
        let Some((b1, a1)) = cpu_ticks() else { return };
        if 20 * (b1 - b0) < (a1 - a0).max(1) {
            return;
        }
    }
}

/// `iters` calls of `f` on the pool's workers; the wall time of the loop.
fn timed_in(pool: &ThreadPool, iters: u64, mut f: impl FnMut() + Send) -> Duration {
    pool.install(|| {
        let t = Instant::now();
        for _ in 0..iters {
            f();
        }
        t.elapsed()
    })
}

fn bench_precision<T: SimdReal>(c: &mut Criterion, p: &Problem, pools: &[(usize, ThreadPool)]) {
    let ne = p.mesh.elements.len();
    // Built on first use, so that benchmarks excluded by a filter cost nothing.
    let mut fixture: Option<Fixture<T>> = None;
    let size = format!("hex={ne}");
    for (k, pool) in pools {
        let id = BenchmarkId::new(format!("{}/threads={k}", T::NAME), &size);

        let mut g = c.benchmark_group("element_forces");
        g.throughput(Throughput::Elements(ne as u64));
        g.bench_function(id.clone(), |b| {
            let fx = fixture.get_or_insert_with(|| Fixture::new(p));
            wait_quiet();
            b.iter_custom(|iters| {
                timed_in(pool, iters, || {
                    let r = element_forces(&fx.el, black_box(&fx.u), &mut fx.elem_f);
                    assert!(r.is_none(), "element inverted in the seeded state");
                    black_box(&mut fx.elem_f);
                })
            })
        });
        g.finish();

        let mut g = c.benchmark_group("node_update");
        g.throughput(Throughput::Elements(ne as u64));
        g.bench_function(id.clone(), |b| {
            let fx = fixture.get_or_insert_with(|| Fixture::new(p));
            wait_quiet();
            b.iter_custom(|iters| {
                timed_in(pool, iters, || {
                    let r = node_update(
                        &fx.sim.disc.gather,
                        &fx.cd,
                        black_box(&fx.elem_f),
                        None,
                        &fx.u,
                        &fx.u_prev,
                        &mut fx.u_next,
                    );
                    assert!(r.is_none(), "non-finite node update");
                    black_box(&mut fx.u_next);
                })
            })
        });
        g.finish();

        let mut g = c.benchmark_group("step");
        g.throughput(Throughput::Elements(ne as u64));
        g.bench_function(id.clone(), |b| {
            let fx = fixture.get_or_insert_with(|| Fixture::new(p));
            wait_quiet();
            b.iter_custom(|iters| {
                timed_in(pool, iters, || {
                    if let Err(e) = fx.sim.step() {
                        panic!("bench simulation diverged: {e}");
                    }
                })
            })
        });
        g.finish();
    }
}

/// The paper's scene: the procedural mouth's `fig4_sticky` run (`sticky_lips::paper`, Table 1 on the procedural mouth) (the mouth at paper resolution,
/// saliva with the breaking rule, jaw rotation; Table 1's dt), advanced `MOUTH_SEED_STEPS`
/// from rest first so that the jaw has started to turn and every element is deformed.
fn bench_mouth<T: SimdReal>(c: &mut Criterion, pools: &[(usize, ThreadPool)]) {
    const MOUTH_SEED_STEPS: usize = 2000;
    let p = common::mouth_problem(1.0);
    let ne = p.mesh.elements.len();
    let mut sim: Option<Simulation<T>> = None;
    for (k, pool) in pools {
        let id = BenchmarkId::new(format!("{}/threads={k}", T::NAME), format!("mouth={ne}"));
        let mut g = c.benchmark_group("step");
        g.throughput(Throughput::Elements(ne as u64));
        g.bench_function(id, |b| {
            let sim = sim.get_or_insert_with(|| {
                let mut s = Simulation::<T>::new(&p).expect("paper scenario is valid");
                for _ in 0..MOUTH_SEED_STEPS {
                    s.step().expect("paper scenario is stable");
                }
                s
            });
            wait_quiet();
            b.iter_custom(|iters| {
                timed_in(pool, iters, || {
                    if let Err(e) = sim.step() {
                        panic!("mouth simulation diverged: {e}");
                    }
                })
            })
        });
        g.finish();
    }
}

fn tled(c: &mut Criterion) {
    let threads = parse_list("STICKY_LIPS_BENCH_THREADS", "1,2");
    let pools: Vec<(usize, ThreadPool)> = threads
        .iter()
        .map(|&k| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(k)
                .build()
                .unwrap();
            (k, pool)
        })
        .collect();
    for n in parse_list("STICKY_LIPS_BENCH_SIZES", "1000,8000,64000") {
        let p = block_problem(cells_per_side(n));
        bench_precision::<f64>(c, &p, &pools);
        bench_precision::<f32>(c, &p, &pools);
    }
    if std::env::var("STICKY_LIPS_BENCH_MOUTH").map_or(true, |v| v != "0") {
        bench_mouth::<f64>(c, &pools);
        bench_mouth::<f32>(c, &pools);
    }
}

fn config() -> Criterion {
    // Group-level settings would override criterion's command-line flags; these do not.
    Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3))
}

criterion_group! {
    name = benches;
    config = config();
    targets = tled
}
criterion_main!(benches);
