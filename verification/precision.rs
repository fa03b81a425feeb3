//! Precision and determinism: the f64 path carries f64 information end to end (no silent
//! f32 stage), the f32 path cannot, and results are bit-identical on any thread count.

use crate::element::{bare_problem, force_of, problem};
use sticky_lips::boundary::{
    BoundaryConditions, Fixed, LoadCurve, LoadShape, NodalForce, PrescribedDisplacement,
};
use sticky_lips::element::hex8::GradientVariant;
use sticky_lips::mesh::generate::{block, SplitMix64};
use sticky_lips::problem::{Problem, TimeSettings};
use sticky_lips::tled::precompute::Discretisation;
use sticky_lips::tled::simd::SimdReal;
use sticky_lips::tled::Simulation;

/// One 10 mm hexahedron, x = 0 face fixed, x = max face pulled to `value` in x (STEP).
fn single_element(value: f64) -> Problem {
    let mesh = block([0.0; 3], [0.01; 3], [1, 1, 1]);
    let mut bc = BoundaryConditions::default();
    bc.fixed.push(Fixed {
        nodes: mesh.node_sets["x_min"].clone(),
        dofs: [true; 3],
    });
    let pulled = mesh.node_sets["x_max"].clone();
    let curve = LoadCurve {
        shape: LoadShape::Step,
        start: 0.0,
        duration: 1e-3,
    };
    bc.displacements.push(PrescribedDisplacement {
        nodes: pulled.clone(),
        dof: 0,
        values: vec![value; pulled.len()],
        curve,
    });
    problem(
        mesh,
        GradientVariant::MeanGradient,
        bc,
        TimeSettings {
            dt: 1e-4,
            total_time: 1e-3,
            output_every: 1,
        },
        0.0,
    )
}

fn run_steps<T: SimdReal>(p: &Problem, steps: usize) -> Vec<[T; 3]> {
    let mut sim = Simulation::<T>::new(p).unwrap();
    for _ in 0..steps {
        sim.step().unwrap();
    }
    sim.displacement().to_vec()
}

#[test]
fn f64_carries_information_f32_cannot() {
    let base = 1e-3;
    let v = base * (1.0 + 2f64.powi(-30)); // exact in f64, below half an f32 ulp of 1e-3
    assert_ne!(v, base);
    assert_eq!(
        v as f32, base as f32,
        "the offset must be invisible in f32 for this test to mean anything"
    );
    let p = single_element(v);
    let pulled = p.mesh.node_sets["x_max"].clone();
    // after one step the prescribed DOFs hold the value
    let u64_1 = run_steps::<f64>(&p, 1);
    let u32_1 = run_steps::<f32>(&p, 1);
    for &n in &pulled {
        assert_eq!(
            u64_1[n as usize][0].to_bits(),
            v.to_bits(),
            "f64 run lost bits of the prescribed value"
        );
        assert_ne!(u32_1[n as usize][0] as f64, v, "f32 cannot hold v");
        assert_eq!(u32_1[n as usize][0], v as f32);
    }
    // and it reaches the free DOFs: after three steps the lateral (free) displacements of the
    // pulled nodes differ from those of a run pulled to 1e-3 in f64, and are identical in f32
    let q = single_element(base);
    let (a64, b64) = (run_steps::<f64>(&p, 3), run_steps::<f64>(&q, 3));
    let (a32, b32) = (run_steps::<f32>(&p, 3), run_steps::<f32>(&q, 3));
    let free_differs = pulled
        .iter()
        .any(|&n| (1..3).any(|k| a64[n as usize][k] != b64[n as usize][k]));
    let moved = pulled
        .iter()
        .any(|&n| (1..3).any(|k| a64[n as usize][k] != 0.0));
    println!(
        "f64_carries_information_f32_cannot: free DOF after 3 steps f64 {:e} vs {:e}",
        a64[pulled[0] as usize][1], b64[pulled[0] as usize][1]
    );
    assert!(
        moved,
        "the free DOFs did not move: the test would be vacuous"
    );
    assert!(
        free_differs,
        "a 2^-30 relative change of the load did not reach the free DOFs in f64"
    );
    let bits32 = |u: &[[f32; 3]]| u.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits32(&a32), bits32(&b32), "f32 runs should be identical");
}

#[test]
fn f64_element_force_sees_2_pow_minus_40() {
    // a single element has no interior node for distorted_block to move; distort it by hand
    let mut mesh = block([0.0; 3], [0.01; 3], [1, 1, 1]);
    let mut rng = SplitMix64(12);
    for x in mesh.nodes.iter_mut() {
        for c in x.iter_mut() {
            *c += 0.002 * rng.symmetric();
        }
    }
    let d = Discretisation::new(&bare_problem(mesh.clone(), GradientVariant::MeanGradient));
    let u: Vec<[f64; 3]> = (0..8)
        .map(|_| {
            [
                0.002 * rng.symmetric(),
                0.002 * rng.symmetric(),
                0.002 * rng.symmetric(),
            ]
        })
        .collect();
    let eps = 2f64.powi(-40);
    let up: Vec<[f64; 3]> = u.iter().map(|v| v.map(|x| x * (1.0 + eps))).collect();
    assert!(u.iter().zip(&up).all(|(a, b)| (0..3).all(|k| a[k] != b[k])));
    let (f, fp) = (force_of::<f64>(&d, &u, 0), force_of::<f64>(&d, &up, 0));
    let fmax = f.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let change = f
        .iter()
        .flatten()
        .zip(fp.iter().flatten())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max)
        / fmax;
    println!("f64_element_force_sees_2_pow_minus_40: relative force change {change:.2e} (2^-40 = {eps:.2e})");
    // the force is smooth in u: a relative change eps of u changes it by ~eps (within 0.1..10 eps)
    assert!(
        change > 0.1 * eps && change < 10.0 * eps,
        "f64 force change {change:e} for a 2^-40 perturbation"
    );
    // in f32 the perturbed input rounds to the same numbers, so the force is bit-identical
    let (g, gp) = (force_of::<f32>(&d, &u, 0), force_of::<f32>(&d, &up, 0));
    let b = |x: &[[f64; 3]; 8]| x.iter().flatten().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(
        b(&g),
        b(&gp),
        "f32 force should not see a 2^-40 perturbation"
    );
}

/// A 10x6x6 block (360 elements, 539 nodes: more than one work chunk of each parallel stage).
fn threaded_problem() -> Problem {
    let mesh = block([0.0; 3], [0.05, 0.03, 0.03], [10, 6, 6]);
    let mut bc = BoundaryConditions::default();
    bc.fixed.push(Fixed {
        nodes: mesh.node_sets["x_min"].clone(),
        dofs: [true; 3],
    });
    let tip = mesh.node_sets["x_max"].clone();
    let curve = LoadCurve {
        shape: LoadShape::Poly345,
        start: 0.0,
        duration: 0.01,
    };
    bc.forces.push(NodalForce {
        nodes: tip.clone(),
        dof: 2,
        values: vec![-1e-3; tip.len()],
        curve,
    });
    problem(
        mesh,
        GradientVariant::MeanGradient,
        bc,
        TimeSettings {
            dt: 2e-4,
            total_time: 0.02,
            output_every: 1,
        },
        20.0,
    )
}

fn run_in_pool<T: SimdReal>(p: &Problem, threads: usize) -> Vec<u64> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let mut sim = Simulation::<T>::new(p).unwrap();
        while !sim.is_finished() {
            sim.step().unwrap();
        }
        let mut bits: Vec<u64> = sim
            .displacement()
            .iter()
            .flatten()
            .map(|x| x.to_f64().to_bits())
            .collect();
        bits.extend(sim.internal_forces().iter().flatten().map(|x| x.to_bits()));
        bits
    })
}

#[test]
fn identical_bits_on_any_thread_count() {
    let p = threaded_problem();
    assert!(p.mesh.elements.len() > sticky_lips::tled::element_forces::ELEMENT_CHUNK);
    assert!(p.mesh.nodes.len() > sticky_lips::tled::node_update::NODE_CHUNK);
    for (name, runs) in [
        (
            "f64",
            (1..=3)
                .map(|k| run_in_pool::<f64>(&p, k))
                .collect::<Vec<_>>(),
        ),
        (
            "f32",
            (1..=3)
                .map(|k| run_in_pool::<f32>(&p, k))
                .collect::<Vec<_>>(),
        ),
    ] {
        assert!(runs[0].iter().any(|&b| b != 0), "{name}: nothing moved");
        for (k, r) in runs.iter().enumerate().skip(1) {
            assert!(
                r == &runs[0],
                "{name}: {} threads differ from 1 thread",
                k + 1
            );
        }
        println!("identical_bits_on_any_thread_count: {name} bit-identical on 1, 2, 3 threads");
    }
}

/// Bits of every force component.
fn force_bits<T: SimdReal>(f: &[[[T; 3]; 8]]) -> Vec<u64> {
    f.iter()
        .flatten()
        .flatten()
        .map(|x| x.to_f64().to_bits())
        .collect()
}

/// The lane-parallel element kernel (`tled::simd`, the one every run uses) against the
/// scalar reference `element_force`, along a whole run of a distorted block (both gradient
/// variants, f64 and f32): at every 10th step the forces of the dispatched copy (AVX2 where
/// the processor has it) and of the portable copy equal the reference bit for bit.
fn lane_kernel_matches_reference_along_a_run<T: SimdReal>(variant: GradientVariant) {
    use sticky_lips::mesh::generate::distorted_block;
    use sticky_lips::tled::element_forces::{
        element_forces, element_forces_portable, element_forces_scalar, ElementArrays,
    };
    // 7x5x4 = 140 elements: not a multiple of either lane count, so the last block is padded
    let mesh = distorted_block([0.0; 3], [0.035, 0.025, 0.02], [7, 5, 4], 0.25, 42);
    let mut p = threaded_problem();
    p.element_material = vec![0; mesh.elements.len()];
    p.bc.fixed[0].nodes = mesh.node_sets["x_min"].clone();
    p.bc.forces[0].nodes = mesh.node_sets["x_max"].clone();
    p.bc.forces[0].values = vec![-2e-3; p.bc.forces[0].nodes.len()];
    p.mesh = mesh;
    p.numerics.variant = variant;
    let mut sim = Simulation::<T>::new(&p).unwrap();
    let el = ElementArrays::<T>::from_discretisation(&sim.disc);
    let ne = el.len();
    let zero = [[T::ZERO; 3]; 8];
    let (mut reference, mut lanes, mut portable) = (vec![zero; ne], vec![zero; ne], vec![zero; ne]);
    let mut compared = 0;
    while !sim.is_finished() {
        if sim.step_index() % 10 == 0 {
            let u = sim.displacement();
            assert_eq!(element_forces_scalar(&el, u, &mut reference), None);
            assert_eq!(element_forces(&el, u, &mut lanes), None);
            assert_eq!(element_forces_portable(&el, u, &mut portable), None);
            let r = force_bits(&reference);
            assert!(
                r == force_bits(&lanes),
                "{} {variant:?}: lane kernel differs from the reference at step {}",
                T::NAME,
                sim.step_index()
            );
            assert!(
                r == force_bits(&portable),
                "{} {variant:?}: portable lanes differ from the reference at step {}",
                T::NAME,
                sim.step_index()
            );
            compared += 1;
        }
        sim.step().unwrap();
    }
    assert!(compared >= 10);
    assert!(sim.displacement().iter().flatten().any(|&x| x != T::ZERO));
    println!(
        "lane_kernel_equals_scalar_reference: {} {variant:?}: {compared} states bit-identical ({})",
        T::NAME,
        sticky_lips::tled::simd::instruction_set()
    );
}

#[test]
fn lane_kernel_equals_scalar_reference() {
    for v in [GradientVariant::MeanGradient, GradientVariant::Centroid] {
        lane_kernel_matches_reference_along_a_run::<f64>(v);
        lane_kernel_matches_reference_along_a_run::<f32>(v);
    }
}
