//! Subcycling of the saliva layer (`tled::subcycle`, issue 30): nodal-partition subcycling of
//! central differences (Belytschko, Yen & Mullen 1979) keeps the physics of the single-rate
//! scheme of paper eq. (3).
//!
//! On two tissue slabs joined by a saliva layer (the `examples/sticky_slabs.toml` geometry,
//! Table 1's materials):
//! - undamped and free, the total energy shows no growth over a long run at twice the
//!   saliva's stable step;
//! - pulled apart, the subcycled displacements converge to the single-rate solution as the
//!   steps shrink (fixed number of substeps), at second order;
//! - the bits are the same on 1, 2 and 3 threads;
//! - the GPU path refuses a subcycled problem with a message.

use std::path::Path;
use sticky_lips::io::scenario;
use sticky_lips::tled::Simulation;
use sticky_lips::Problem;

/// The slabs scenario: `k_glue` sets when the layer breaks; `pull` (mm) the displacement of
/// the lower face over 0.25 s (0: free, nothing held, no damping).
fn slabs(dt: f64, total: f64, subcycles: usize, k_glue: f64, pull: f64) -> Problem {
    let loads = if pull != 0.0 {
        format!(
            "[[fix]]\nnodes = \"z_max\"\n\n[[displacement]]\nnodes = \"z_min\"\ndof = \"z\"\n\
             value = {pull:?}\nshape = \"smooth_step\"\nduration = 0.25\n\n\
             [numerics]\ndamping = 80.0\n"
        )
    } else {
        String::new()
    };
    let text = format!(
        r#"
[units]
length = "mm"
[mesh]
generator = "layers"
size = [10.0, 10.0, 0.0]
cells = [4, 4, 0]
layers = [
  {{ name = "lower", thickness = 5.0, cells = 3 }},
  {{ name = "saliva_layer", thickness = 0.5, cells = 1 }},
  {{ name = "upper", thickness = 5.0, cells = 3 }},
]
[[materials]]
name = "tissue lower"
elements = "lower"
mu = 800.0
K = 7000.0
density = 1050.0
[[materials]]
name = "saliva"
elements = "saliva_layer"
mu = 7700.0
K = 191000.0
density = 1050.0
[[materials]]
name = "tissue upper"
elements = "upper"
mu = 800.0
K = 7000.0
density = 1050.0
[[saliva]]
material = "saliva"
critical_moisture = 100.0
initial_moisture = 100.0
k_glue = {k_glue:?}
evaporation_rate = 0.0
rule = "literal"
decay_time = 9.94992e-4
[time]
dt = {dt:?}
total = {total:?}
output_every = 1
subcycles = {subcycles}
{loads}"#
    );
    scenario::parse(&text, Path::new("slabs.toml"))
        .unwrap()
        .problem
}

/// Runs `p` to its end on `threads` threads from `u0` at rest (or from rest), returning the
/// final displacement and the total energy after every step.
fn run(p: &Problem, threads: usize, u0: Option<&[[f64; 3]]>) -> (Vec<[f64; 3]>, Vec<f64>) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let mut sim = Simulation::<f64>::new(p).unwrap();
        if let Some(u0) = u0 {
            sim.set_state(u0, u0);
        }
        let mut energy = Vec::new();
        while !sim.is_finished() {
            sim.step().unwrap();
            let e = sim.energies();
            energy.push(e.kinetic + e.strain);
        }
        (sim.displacement_f64(), energy)
    })
}

fn critical_steps(p: &Problem) -> (f64, f64) {
    let d = sticky_lips::tled::precompute::Discretisation::new(p);
    let r = sticky_lips::tled::stability::analyse(p, &d);
    (r.critical_time_step, r.tissue_critical_time_step.unwrap())
}

fn max_diff(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .flatten()
        .zip(b.iter().flatten())
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// Undamped and free, at twice the saliva's stable step (1.8 times the whole model's
/// critical step, 4 substeps): the total energy (kinetic from backward differences, strain)
/// shows no growth over 20 000 steps. (Larger steps, up to the tissue's own limit, show a slow
/// growth in bands of the step (3 times the critical step: x2.6 over 17 000 steps); the
/// report is in `paper/README.md`, "Subcycling".)
#[test]
fn undamped_subcycled_energy_stays_bounded() {
    let probe = slabs(1e-5, 1e-5, 1, 1e6, 0.0);
    let (critical, tissue) = critical_steps(&probe);
    // the layer is the stiff part: the tissue alone allows a much larger step
    assert!(
        tissue > 3.0 * critical,
        "tissue {tissue:e} s, whole {critical:e} s"
    );
    let dt = 1.8 * critical;
    let k = 4;
    let steps = 20_000;
    let p = slabs(dt, steps as f64 * dt, k, 1e6, 0.0);
    // a smooth stretch of the whole block across the layer (z), released at rest
    let u0: Vec<[f64; 3]> = p
        .mesh
        .nodes
        .iter()
        .map(|x| [0.0, 0.0, 0.02 * (x[2] - 0.005) * (1.0 + 20.0 * x[0])])
        .collect();
    let (_, e) = run(&p, 2, Some(&u0));
    let window = |w: &[f64]| w.iter().fold(0.0f64, |m, &x| m.max(x));
    let quarters: Vec<f64> = e.chunks(steps / 4).map(|w| window(w) / e[0]).collect();
    eprintln!(
        "{steps} steps of {dt:.3e} s with {k} substeps (critical {critical:.3e} s, tissue {tissue:.3e} s): energy {:.6e} J, largest per quarter of the run / initial {quarters:.3?}",
        e[0]
    );
    // no growth: the last quarter's largest energy is no more than the first quarter's
    assert!(
        quarters[3] <= quarters[0] * 1.01,
        "energy grows: largest per quarter / initial {quarters:?}"
    );
}

#[test]
fn subcycled_displacements_converge_to_the_single_rate_solution() {
    // pulled apart, before the layer breaks (k_glue large): 0.03 s
    let total = 0.03;
    let k = 4;
    let h = 1e-4;
    let reference = run(&slabs(h / 64.0, total, 1, 1e3, -3.0), 2, None).0;
    let errors: Vec<f64> = [h, h / 2.0, h / 4.0]
        .iter()
        .map(|&dt| max_diff(&run(&slabs(dt, total, k, 1e3, -3.0), 2, None).0, &reference))
        .collect();
    let scale = reference
        .iter()
        .flatten()
        .fold(0.0f64, |m, x| m.max(x.abs()));
    let order: Vec<f64> = errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
    eprintln!(
        "subcycled ({k} substeps) vs single rate at {:e} s, largest displacement {scale:.3e} m: errors {errors:?} m, observed order {order:?}",
        h / 64.0
    );
    assert!(errors[2] < 1e-3 * scale);
    assert!(order.iter().all(|&o| o >= 1.8), "observed order {order:?}");
}

#[test]
fn subcycled_runs_give_the_same_bits_on_any_thread_count() {
    // through the break: the layer lets go within the run
    let p = slabs(4e-5, 0.25, 4, 0.05, -3.0);
    let one = run(&p, 1, None).0;
    for threads in [2, 3] {
        let other = run(&p, threads, None).0;
        assert!(
            one.iter()
                .flatten()
                .zip(other.iter().flatten())
                .all(|(a, b)| a.to_bits() == b.to_bits()),
            "{threads} threads differ from 1"
        );
    }
}

/// The GPU path does not subcycle: it refuses such a problem with a message that says so
/// (before looking for an adapter).
#[cfg(feature = "gpu")]
#[test]
fn the_gpu_path_refuses_a_subcycled_problem() {
    let p = slabs(4e-5, 0.01, 4, 0.05, -3.0);
    let e = sticky_lips::gpu::GpuSimulation::<f32>::new(&p)
        .err()
        .expect("refused")
        .to_string();
    assert!(
        e.contains("does not subcycle") && e.contains("--backend cpu"),
        "{e}"
    );
}

/// A subcycled run continued from its state half way (a checkpoint's contents) gives the same
/// bits as the run that did not stop (the fast nodes' previous substep is part of the state).
#[test]
fn a_subcycled_run_restored_half_way_gives_the_same_bits() {
    let p = slabs(4e-5, 0.25, 4, 0.05, -3.0);
    let mut whole = Simulation::<f64>::new(&p).unwrap();
    let half = whole.num_steps() / 2;
    let mut state = None;
    while !whole.is_finished() {
        if whole.step_index() == half {
            state = Some(whole.checkpoint_state());
        }
        whole.step().unwrap();
    }
    let mut resumed = Simulation::<f64>::new(&p).unwrap();
    resumed.restore(&state.unwrap()).unwrap();
    while !resumed.is_finished() {
        resumed.step().unwrap();
    }
    assert_eq!(resumed.checkpoint_state(), whole.checkpoint_state());
}

/// `run`'s check refuses each partition's step above its own limit: the substep above the
/// whole model's critical step, the large step above the tissue's.
#[test]
fn each_step_is_checked_against_its_own_limit() {
    use sticky_lips::tled::stability::check_time_step;
    let probe = slabs(1e-5, 1e-5, 1, 1e6, 0.0);
    let d = sticky_lips::tled::precompute::Discretisation::new(&probe);
    let report = sticky_lips::tled::stability::analyse(&probe, &d);
    let (critical, tissue) = critical_steps(&probe);
    // within both limits
    assert!(check_time_step(&slabs(2.0 * critical, 0.01, 4, 1e6, 0.0), &report, false).is_ok());
    // the substep too large
    let e = check_time_step(&slabs(2.0 * critical, 0.01, 1, 1e6, 0.0), &report, false)
        .unwrap_err()
        .to_string();
    assert!(e.contains("exceeds the critical time step"), "{e}");
    // the large step above the tissue's limit, however many substeps
    let e = check_time_step(&slabs(1.1 * tissue, 0.05, 64, 1e6, 0.0), &report, false)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("64 substeps") && e.contains("critical time step of the tissue"),
        "{e}"
    );
    assert!(check_time_step(&slabs(1.1 * tissue, 0.05, 64, 1e6, 0.0), &report, true).is_ok());
}

/// A subcycled step that diverges, in its slow pass or in its substeps (which run side by
/// side), stops with the step, the time and the element or node, and leaves the state (both
/// displacements and the saliva layer's) bit for bit as it was before that step. The
/// slabs' tissue allows 8.5 times the whole model's critical step: with 2 substeps of a step
/// of 4 times it the substeps are unstable and the slow pass is not; with 16 substeps of a
/// step of 12 times it the slow pass is unstable and the substeps are not.
#[test]
fn a_diverging_subcycled_step_leaves_the_state_as_it_was() {
    let (whole, tissue) = critical_steps(&slabs(1e-5, 0.5, 1, 0.1, 2.0));
    assert!(
        tissue / whole > 8.0 && tissue / whole < 9.0,
        "{}",
        tissue / whole
    );
    for (factor, k) in [(4.0, 2), (12.0, 16)] {
        let dt = factor * whole;
        let p = slabs(dt, 0.5, k, 0.1, 2.0);
        let mut sim = Simulation::<f64>::new(&p).unwrap();
        let err = loop {
            let before = sim.checkpoint_state();
            match sim.step() {
                Ok(()) => assert!(
                    !sim.is_finished(),
                    "{factor} x, {k} substeps: no divergence"
                ),
                Err(e) => {
                    // NaN != NaN: the states compared as their printed bits
                    assert!(
                        format!("{:?}", sim.checkpoint_state()) == format!("{before:?}"),
                        "{factor} x, {k} substeps: the state changed by the failed step"
                    );
                    break (e, before.step);
                }
            }
        };
        match err.0 {
            sticky_lips::Error::Diverged {
                step,
                time,
                element,
                node,
                ..
            } => {
                assert_eq!(step, err.1);
                let t0 = step as f64 * dt;
                assert!(time >= t0 && time < t0 + dt, "t = {time} in step {step}");
                assert!(element.is_some() != node.is_some());
                eprintln!("{factor} x, {k} substeps: step {step}, t = {time:e}, element {element:?}, node {node:?}");
            }
            e => panic!("{factor} x, {k} substeps: {e}"),
        }
    }
    // a node that turns non-finite in the pass over every node while the substeps have
    // already advanced the saliva state beside it: a fast node (87, on the saliva layer's lower
    // face; the substeps fail too) and a slow one away from the layer (37)
    for bad in [87, 37] {
        let p = slabs(1.5 * whole, 0.5, 2, 0.1, 2.0);
        let mut sim = Simulation::<f64>::new(&p).unwrap();
        for _ in 0..20 {
            sim.step().unwrap();
        }
        let s = sim.checkpoint_state();
        let mut u_prev = s.u_prev.clone();
        u_prev[bad][0] = f64::NAN;
        sim.set_state(&s.u, &u_prev);
        let before = format!("{:?}", sim.checkpoint_state());
        match sim.step() {
            Err(sticky_lips::Error::Diverged {
                step, time, node, ..
            }) => {
                assert_eq!((step, node), (20, Some(bad)));
                assert_eq!(time, 20.0 * 1.5 * whole);
            }
            r => panic!("node {bad}: {r:?}"),
        }
        assert!(
            format!("{:?}", sim.checkpoint_state()) == before,
            "node {bad}: the state changed by the failed step"
        );
    }
}
