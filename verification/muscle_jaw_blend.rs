//! The drivers of the mouth: linear vector muscles (paper section 3.3), the jaw as a
//! prescribed rigid rotation, and the blend-shape baseline (eq. 1).
#![allow(clippy::needless_range_loop)] // index loops mirror the tensor notation

use crate::element::{max_abs8, problem};
use sticky_lips::blend::blend;
use sticky_lips::boundary::{
    BoundaryConditions, Fixed, LoadCurve, LoadShape, PrescribedDisplacement, PrescribedRotation,
};
use sticky_lips::element::hex8::GradientVariant;
use sticky_lips::linalg::{cross, dot, norm, sub};
use sticky_lips::mesh::generate::{distorted_block, SplitMix64};
use sticky_lips::muscle::Muscle;
use sticky_lips::problem::{Problem, TimeSettings};
use sticky_lips::static_solve::{solve_equilibrium, StaticOptions};
use sticky_lips::tled::precompute::Discretisation;
use sticky_lips::tled::simd::SimdReal;
use sticky_lips::tled::solver::{displacement_gradient, Simulation};

type V3 = [f64; 3];

// ---------------------------------------------------------------------------------------
// Muscles
// ---------------------------------------------------------------------------------------

/// Brute force, written independently of `Muscle::contains`: the distance of `x` to the
/// muscle's axis line (`|v x d| / |d|`) and the position of its foot along the segment
/// insertion -> origin (`t = v.d / |d|^2`, inside for `0 <= t <= 1`), and the distance to the
/// segment itself (the capsule a point-to-segment test would select).
fn axis_distance(m: &Muscle, x: &V3) -> (f64, f64, f64) {
    let d = sub(&m.origin, &m.insertion);
    let v = sub(x, &m.insertion);
    let t = dot(&v, &d) / dot(&d, &d);
    let line = norm(&cross(&v, &d)) / norm(&d);
    let seg = if t < 0.0 {
        norm(&v)
    } else if t > 1.0 {
        norm(&sub(x, &m.origin))
    } else {
        line
    };
    (line, t, seg)
}

fn muscle(origin: V3, insertion: V3, radius: f64) -> Muscle {
    Muscle {
        name: "test".into(),
        origin,
        insertion,
        radius,
        strength: 0.05,
        activation: 0.6,
        curve: LoadCurve {
            shape: LoadShape::Step,
            start: 0.0,
            duration: 1.0,
        },
    }
}

#[test]
fn muscle_selects_the_nodes_in_its_cylinder() {
    // 1. by hand: a regular 4x4x4 block of 5 mm cells, a muscle along the row of nodes at
    // y = z = 10 mm from x = 5 to x = 15 mm, radius 1 mm: exactly the 3 nodes of that row
    // with 5 <= x <= 15 (the ends are inside: 0 <= t <= 1 and distance <= r are inclusive)
    let grid = sticky_lips::mesh::generate::block([0.0; 3], [0.02; 3], [4, 4, 4]);
    let m = muscle([0.015, 0.01, 0.01], [0.005, 0.01, 0.01], 1e-3);
    let idx = |i: u32, j: u32, k: u32| i + 5 * (j + 5 * k);
    assert_eq!(
        m.select_nodes(&grid.nodes),
        vec![idx(1, 2, 2), idx(2, 2, 2), idx(3, 2, 2)]
    );
    // radius 5 mm reaches the 4 neighbouring rows (distance 5 mm, inclusive), not the diagonals
    // (7.07 mm), and still not the nodes at x = 0 or 20 mm beyond the ends
    let m5 = muscle([0.015, 0.01, 0.01], [0.005, 0.01, 0.01], 5e-3);
    assert_eq!(m5.select_nodes(&grid.nodes).len(), 3 * 5);

    // 2. random muscles through a distorted 6x6x6 block against the brute force
    let mesh = distorted_block([0.0; 3], [0.03; 3], [6, 6, 6], 0.25, 5);
    let mut rng = SplitMix64(2024);
    let (mut total, mut caps, mut ambiguous) = (0usize, 0usize, 0usize);
    for _ in 0..50 {
        let p = |rng: &mut SplitMix64| {
            [
                0.015 + 0.02 * rng.symmetric(),
                0.015 + 0.02 * rng.symmetric(),
                0.015 + 0.02 * rng.symmetric(),
            ]
        };
        let m = muscle(
            p(&mut rng),
            p(&mut rng),
            0.002 + 0.004 * (rng.symmetric() + 1.0),
        );
        let selected = m.select_nodes(&mesh.nodes);
        let mut expected = Vec::new();
        for (n, x) in mesh.nodes.iter().enumerate() {
            let (line, t, seg) = axis_distance(&m, x);
            // a node within 1e-9 of the surface could go either way by rounding: count them
            if (line - m.radius).abs() < 1e-9 * m.radius || t.abs() < 1e-9 || (t - 1.0).abs() < 1e-9
            {
                ambiguous += 1;
                continue;
            }
            let inside = (0.0..=1.0).contains(&t) && line <= m.radius;
            if inside {
                expected.push(n as u32);
            } else if seg <= m.radius {
                caps += 1; // in the capsule's end caps, not in the cylinder
            }
        }
        let selected: Vec<u32> = selected
            .into_iter()
            .filter(|&n| {
                let (line, t, _) = axis_distance(&m, &mesh.nodes[n as usize]);
                !((line - m.radius).abs() < 1e-9 * m.radius
                    || t.abs() < 1e-9
                    || (t - 1.0).abs() < 1e-9)
            })
            .collect();
        assert_eq!(selected, expected, "muscle {m:?}");
        total += expected.len();
    }
    println!(
        "muscle_selects_the_nodes_in_its_cylinder: 50 random muscles, {total} nodes selected as by brute force; \
         {caps} nodes lie in the end caps of the capsule (a point-to-segment test would take them), {ambiguous} within 1e-9 of the surface"
    );
    assert!(total > 100 && caps > 0 && ambiguous == 0);
}

/// A 3x3x3 distorted block (20 mm) fixed at `x_min`, with one muscle along x through the
/// far half of the block, and `extra` as further boundary conditions.
fn muscle_problem(
    activation: Option<f64>,
    damping: f64,
    steps: usize,
    extra: BoundaryConditions,
) -> Problem {
    let mesh = distorted_block([0.0; 3], [0.02; 3], [3, 3, 3], 0.2, 9);
    let mut bc = extra;
    bc.fixed.push(Fixed {
        nodes: mesh.node_sets["x_min"].clone(),
        dofs: [true, true, true],
    });
    let mut p = problem(
        mesh,
        GradientVariant::MeanGradient,
        bc,
        TimeSettings {
            dt: 1e-4,
            total_time: steps as f64 * 1e-4,
            output_every: 1,
        },
        damping,
    );
    if let Some(a) = activation {
        // from the far face (insertion, x = 21 mm) towards the origin at x = 8 mm, tilted
        let mut m = muscle([0.008, 0.012, 0.009], [0.021, 0.008, 0.011], 0.006);
        m.activation = a;
        p.physics.muscles.push(m);
    }
    p
}

#[test]
fn muscle_force_total_is_activation_times_strength() {
    let p = muscle_problem(Some(0.6), 0.0, 1, BoundaryConditions::default());
    let m = &p.physics.muscles[0];
    let d = Discretisation::new(&p);
    let nodes = &d.muscle_nodes[0];
    assert_eq!(nodes, &m.select_nodes(&p.mesh.nodes));
    let dir = m.direction();
    // the direction is the unit vector insertion -> origin
    let raw = sub(&m.origin, &m.insertion);
    assert!(norm(&sub(&dir, &raw.map(|c| c / norm(&raw)))) < 4.0 * f64::EPSILON);
    let group = d.loads.last().unwrap();
    // every selected node gets the same vector, activation x strength / N along the axis
    let mut per_node = std::collections::BTreeMap::<u32, V3>::new();
    for &(dof, v) in &group.entries {
        per_node.entry(dof / 3).or_insert([0.0; 3])[(dof % 3) as usize] += v;
    }
    assert_eq!(per_node.keys().copied().collect::<Vec<_>>(), *nodes);
    let share = m.activation * m.strength / nodes.len() as f64;
    let mut total = [0.0; 3];
    for f in per_node.values() {
        for k in 0..3 {
            // one product and one division each: 4 ulps of the share
            assert!((f[k] - share * dir[k]).abs() <= 4.0 * f64::EPSILON * share);
            total[k] += f[k];
        }
    }
    let target = m.activation * m.strength;
    let along = dot(&total, &dir);
    let across = norm(&sub(&total, &dir.map(|c| c * along)));
    println!(
        "muscle force: {} nodes, total along the axis {along:.15e} N (activation x strength = {target:e} N), across {across:.1e} N",
        nodes.len()
    );
    // N additions of equal shares: N ulps
    assert!((along - target).abs() <= nodes.len() as f64 * f64::EPSILON * target);
    assert!(across <= nodes.len() as f64 * f64::EPSILON * target);

    // and the force that reaches the nodes: one undamped step from rest with no internal force,
    // u_1 = dt^2 R_0 / m, so sum_n m_n u_1 / dt^2 is the applied total
    let mut sim = Simulation::<f64>::new(&p).unwrap();
    sim.step().unwrap();
    let u = sim.displacement_f64();
    let dt = p.time.dt;
    let mut applied = [0.0; 3];
    for n in 0..u.len() {
        for k in 0..3 {
            applied[k] += d.mass[n] * u[n][k] / (dt * dt);
        }
    }
    let err = norm(&sub(&applied, &dir.map(|c| c * target))) / target;
    println!("muscle force after one step: sum m u / dt^2 = {applied:?}, rel. error {err:.1e}");
    // a handful of roundings per node (A = dt^2 / m, the update, the back-conversion): 1e-12
    assert!(err < 1e-12, "{err:e}");
    // nothing reached the unselected nodes
    for n in 0..u.len() as u32 {
        if !nodes.contains(&n) {
            assert_eq!(u[n as usize], [0.0; 3]);
        }
    }
}

fn passive_vs_zero_activation<T: SimdReal>() {
    // a pull on the far face (prescribed x displacement, POLY345) and damping: a non-trivial run
    let face = |p: &Problem| p.mesh.node_sets["x_max"].clone();
    let bc = |nodes: Vec<u32>| BoundaryConditions {
        displacements: vec![PrescribedDisplacement {
            values: vec![1e-3; nodes.len()],
            nodes,
            dof: 0,
            curve: LoadCurve {
                shape: LoadShape::Poly345,
                start: 0.0,
                duration: 0.02,
            },
        }],
        ..Default::default()
    };
    let steps = 300;
    let template = muscle_problem(None, 20.0, steps, BoundaryConditions::default());
    let bcs = bc(face(&template));
    let run = |activation: Option<f64>| -> Vec<Vec<u64>> {
        let p = muscle_problem(activation, 20.0, steps, bcs.clone());
        let mut sim = Simulation::<T>::new(&p).unwrap();
        let mut out = Vec::new();
        while !sim.is_finished() {
            sim.step().unwrap();
            out.push(
                sim.displacement()
                    .iter()
                    .flatten()
                    .map(|v| v.to_f64().to_bits())
                    .collect(),
            );
        }
        out
    };
    let passive = run(None);
    let zero = run(Some(0.0));
    let active = run(Some(0.5));
    assert_eq!(passive.len(), steps);
    assert!(
        passive == zero,
        "{}: zero activation differs from the passive run",
        T::NAME
    );
    assert!(
        passive.last() != active.last(),
        "activation 0.5 changed nothing"
    );
    println!("zero activation: {steps} steps bit-identical to the passive run ({}); activation 0.5 differs", T::NAME);
}

#[test]
fn zero_activation_is_the_passive_run() {
    passive_vs_zero_activation::<f64>();
    passive_vs_zero_activation::<f32>();
}

// ---------------------------------------------------------------------------------------
// Jaw: a prescribed rigid rotation
// ---------------------------------------------------------------------------------------

/// Rodrigues in the form `R = I + sin(a) K + (1 - cos(a)) K^2` (K the cross-product matrix of
/// the unit axis), independent of the library's expanded form.
fn rodrigues(axis: &V3, angle: f64) -> [[f64; 3]; 3] {
    let k = [
        [0.0, -axis[2], axis[1]],
        [axis[2], 0.0, -axis[0]],
        [-axis[1], axis[0], 0.0],
    ];
    let k2: [[f64; 3]; 3] =
        std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|l| k[i][l] * k[l][j]).sum()));
    let (s, c) = angle.sin_cos();
    std::array::from_fn(|i| {
        std::array::from_fn(|j| (i == j) as u8 as f64 + s * k[i][j] + (1.0 - c) * k2[i][j])
    })
}

fn rigid(r: &[[f64; 3]; 3], point: &V3, x: &V3) -> V3 {
    let d = sub(x, point);
    std::array::from_fn(|i| (0..3).map(|j| r[i][j] * d[j]).sum::<f64>() - d[i])
}

/// Max |E| (Green strain) and max |det F - 1| over all elements at displacement `u`.
fn strain_of(d: &Discretisation, u: &[[f64; 3]]) -> (f64, f64) {
    let (mut e_max, mut j_max) = (0.0f64, 0.0f64);
    for e in 0..d.num_elements() {
        let h = displacement_gradient(d, u, e);
        let two_e = sticky_lips::material::neo_hookean::two_green_strain(&h);
        e_max = two_e
            .iter()
            .flatten()
            .fold(e_max, |m, v| m.max(0.5 * v.abs()));
        j_max = j_max.max(sticky_lips::linalg::det_identity_plus_minus_one(&h).abs());
    }
    (e_max, j_max)
}

const HINGE: V3 = [-0.03, 0.05, 0.012]; // m, a jaw hinge well outside the 20 mm block
fn jaw_axis() -> V3 {
    let a = [0.2, 0.1, 1.0];
    let n = norm(&a);
    a.map(|c| c / n)
}

#[test]
fn jaw_rotation_of_all_nodes_is_strain_free() {
    let mesh = distorted_block([0.0; 3], [0.02; 3], [3, 3, 3], 0.25, 4);
    let all: Vec<u32> = (0..mesh.nodes.len() as u32).collect();
    let angle = 0.6; // rad, ~34 degrees: a wide-open jaw
    let steps = 200;
    let bc = BoundaryConditions {
        rotations: vec![PrescribedRotation {
            nodes: all,
            point: HINGE,
            axis: jaw_axis(),
            angle,
            curve: LoadCurve {
                shape: LoadShape::Poly345,
                start: 0.0,
                duration: steps as f64 * 1e-4,
            },
        }],
        ..Default::default()
    };
    let p = problem(
        mesh,
        GradientVariant::MeanGradient,
        bc,
        TimeSettings {
            dt: 1e-4,
            total_time: steps as f64 * 1e-4,
            output_every: 1,
        },
        80.0,
    );
    let d = Discretisation::new(&p);
    // round-off scale of H: each u_a = R d_a - d_a carries a few eps |d_a| (|d_a| = |X_a - hinge|)
    // and H = sum_a u_a (x) D_a, so |dH| ~ eps sum_a |d_a| |D_a|
    let scale = (0..d.num_elements())
        .map(|e| {
            (0..8)
                .map(|a| {
                    norm(&sub(&p.mesh.nodes[d.conn[e][a] as usize], &HINGE)) * norm(&d.dhdx[e][a])
                })
                .sum::<f64>()
        })
        .fold(0.0, f64::max);
    // the force of a 1 % uniaxial strain on the same mesh, for the internal forces' scale
    let strain: Vec<[f64; 3]> = p
        .mesh
        .nodes
        .iter()
        .map(|x| [0.01 * x[0], 0.0, 0.0])
        .collect();
    let f_ref = (0..d.num_elements())
        .map(|e| max_abs8(&crate::element::force_of::<f64>(&d, &strain, e)))
        .fold(0.0, f64::max);
    let mut sim = Simulation::<f64>::new(&p).unwrap();
    let (mut e_worst, mut j_worst, mut u_worst, mut f_worst) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    while !sim.is_finished() {
        sim.step().unwrap();
        let t = sim.time();
        let tau = t / p.time.total_time;
        let theta = angle * LoadShape::Poly345.eval(tau.min(1.0));
        let r = rodrigues(&jaw_axis(), theta);
        let u = sim.displacement_f64();
        for (x, un) in p.mesh.nodes.iter().zip(&u) {
            let expected = rigid(&r, &HINGE, x);
            u_worst = u_worst.max(norm(&sub(un, &expected)) / norm(&sub(x, &HINGE)));
        }
        let (e, j) = strain_of(&d, &u);
        e_worst = e_worst.max(e);
        j_worst = j_worst.max(j);
        let f = sim.internal_forces();
        f_worst = f.iter().flatten().fold(f_worst, |m, v| m.max(v.abs()));
    }
    let tol_e = 8.0 * f64::EPSILON * scale;
    println!(
        "jaw (all nodes, {steps} steps to {angle} rad): max |u - rigid| / |X - hinge| {u_worst:.1e}; max |E| {e_worst:.1e}, \
         max |J - 1| {j_worst:.1e} (tol {tol_e:.1e} = 8 eps x {scale:.1} round-off scale of H); max |F_int| {f_worst:.1e} N \
         = {:.1e} of a 1 % strain's force",
        f_worst / f_ref
    );
    // the two Rodrigues forms agree to a few roundings of |X - hinge|: 16 eps
    assert!(u_worst < 16.0 * f64::EPSILON, "{u_worst:e}");
    // 8 eps x scale: a few roundings per u_a, gathered into H; E and J - 1 are linear in dH
    assert!(
        e_worst < tol_e && j_worst < 3.0 * tol_e,
        "E {e_worst:e}, J-1 {j_worst:e}"
    );
    // forces ~ stiffness x strain error: relative to a 1 % strain, 4 x tol_e / 0.01
    assert!(f_worst < 4.0 * tol_e / 0.01 * f_ref, "{f_worst:e}");
}

#[test]
fn jaw_rotating_one_face_moves_the_free_body_rigidly() {
    // the static solver, the jaw on the x_min face only, everything else free and unloaded:
    // the equilibrium is the rigid rotation of the whole body
    let mesh = distorted_block([0.0; 3], [0.02; 3], [3, 3, 3], 0.25, 6);
    let angle = 0.6;
    let bc = BoundaryConditions {
        rotations: vec![PrescribedRotation {
            nodes: mesh.node_sets["x_min"].clone(),
            point: HINGE,
            axis: jaw_axis(),
            angle,
            curve: LoadCurve {
                shape: LoadShape::Ramp,
                start: 0.0,
                duration: 1.0,
            },
        }],
        ..Default::default()
    };
    let p = problem(
        mesh,
        GradientVariant::MeanGradient,
        bc,
        TimeSettings {
            dt: 1e-4,
            total_time: 1.0,
            output_every: 1,
        },
        0.0,
    );
    let res = solve_equilibrium(&p, &StaticOptions::default()).unwrap();
    let d = Discretisation::new(&p);
    let (e, j) = strain_of(&d, &res.u);
    let r = rodrigues(&jaw_axis(), angle);
    let u_err = p
        .mesh
        .nodes
        .iter()
        .zip(&res.u)
        .map(|(x, u)| norm(&sub(u, &rigid(&r, &HINGE, x))) / norm(&sub(x, &HINGE)))
        .fold(0.0, f64::max);
    println!(
        "jaw (one face, static): {} load steps, {} Newton iterations; max |E| {e:.1e}, max |J - 1| {j:.1e}, \
         max |u - rigid| / |X - hinge| {u_err:.1e}",
        res.load_steps, res.newton_iterations
    );
    // Newton converges quadratically to the rigid state; what is left is round-off of the
    // free DOFs' update (relative 1e-14) times the lever arm / element size (~10): 1e-12
    assert!(e < 1e-12 && j < 1e-12, "E {e:e}, J-1 {j:e}");
    assert!(u_err < 1e-12, "{u_err:e}");
}

// ---------------------------------------------------------------------------------------
// Blend shapes, eq. (1)
// ---------------------------------------------------------------------------------------

#[test]
fn blend_shapes_eq1() {
    // B: the final displacement of a short simulation (a pull on one face, fixed opposite face)
    let template = muscle_problem(None, 50.0, 200, BoundaryConditions::default());
    let face = template.mesh.node_sets["x_max"].clone();
    let pull = BoundaryConditions {
        displacements: vec![PrescribedDisplacement {
            values: vec![2e-3; face.len()],
            nodes: face,
            dof: 1,
            curve: LoadCurve {
                shape: LoadShape::SmoothStep,
                start: 0.0,
                duration: 0.01,
            },
        }],
        ..Default::default()
    };
    let p = muscle_problem(Some(1.0), 50.0, 200, pull);
    let mut sim = Simulation::<f64>::new(&p).unwrap();
    while !sim.is_finished() {
        sim.step().unwrap();
    }
    let b = sim.displacement_f64();
    let x = &p.mesh.nodes;
    let bits = |v: &[[f64; 3]]| v.iter().flatten().map(|c| c.to_bits()).collect::<Vec<_>>();
    let max_b = b.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(max_b > 1e-3);
    // w = 0 (and no shapes at all) gives X exactly
    assert_eq!(bits(&blend(x, &[(0.0, &b)])), bits(x));
    assert_eq!(bits(&blend(x, &[])), bits(x));
    // w = 1 reproduces the simulated shape X + u exactly
    let xu: Vec<[f64; 3]> = x
        .iter()
        .zip(&b)
        .map(|(x, u)| [x[0] + u[0], x[1] + u[1], x[2] + u[2]])
        .collect();
    assert_eq!(bits(&blend(x, &[(1.0, &b)])), bits(&xu));
    // linear in w: x'(w) - X = w B to the rounding of the sum (1 ulp of |x'|)
    let mut worst = 0.0f64;
    for w in [0.25, 0.5, 0.75, 2.0, -1.0, 1.0 / 3.0] {
        let xw = blend(x, &[(w, &b)]);
        for n in 0..x.len() {
            for k in 0..3 {
                let err = ((xw[n][k] - x[n][k]) - w * b[n][k]).abs();
                worst = worst.max(err / (f64::EPSILON * xw[n][k].abs().max(f64::MIN_POSITIVE)));
                // one rounding of X + w B, and the subtraction's: 1 ulp of |x'| each
                assert!(err <= 2.0 * f64::EPSILON * xw[n][k].abs(), "w {w}");
            }
        }
    }
    // two shapes superpose: x' = (X + a B1) + b B2, in that order, bit for bit
    let b2: Vec<[f64; 3]> = b.iter().map(|v| [v[2], -v[0], 0.5 * v[1]]).collect();
    let two = blend(x, &[(0.3, &b), (0.7, &b2)]);
    let by_hand: Vec<[f64; 3]> = (0..x.len())
        .map(|n| std::array::from_fn(|k| (x[n][k] + 0.3 * b[n][k]) + 0.7 * b2[n][k]))
        .collect();
    assert_eq!(bits(&two), bits(&by_hand));
    println!("blend_shapes_eq1: w = 0 -> X and w = 1 -> X + u bit-exact; linearity within {worst:.2} ulp; two shapes superpose bit-exact");
}

/// The coarse face's jaw opening over 0.03 s (3000 steps), its `[jaw]` table replaced by
/// `jaw` (TOML text), in `dir`.
fn face_jaw_run(dir: &std::path::Path, jaw: &str) -> Vec<[f64; 3]> {
    let base = sticky_lips::io::scenario::with_overrides(
        sticky_lips::paper::TABLE1,
        sticky_lips::paper::TABLE1_NAME,
        &[
            ("mesh.face.resolution", toml::Value::Float(0.25)),
            ("time.total", toml::Value::Float(0.03)),
        ],
    )
    .unwrap();
    let mut doc: toml::Table = toml::from_str(&base).unwrap();
    doc.insert(
        "jaw".into(),
        toml::Value::Table(toml::from_str(jaw).unwrap()),
    );
    let path = dir.join("scenario.toml");
    std::fs::write(&path, toml::to_string(&doc).unwrap()).unwrap();
    let p = sticky_lips::io::scenario::read(&path).unwrap().problem;
    let mut sim = Simulation::<f64>::new(&p).unwrap();
    for _ in 0..3000 {
        sim.step().unwrap();
    }
    sim.displacement_f64()
}

/// Keyframes are the curve's value in absolute time, linear between keys (a keyed curve,
/// `boundary::Keyframes`): keys on a ramp give the ramp's run bit for bit, from the
/// scenario (`keys`, in seconds) and from a file an animation package writes (`keys_file`,
/// CSV in frames at 24 fps; JSON in seconds). The jaw is 0.6 % of its way after 0.03 s.
#[test]
fn keyed_jaw_angle_is_the_ramp_it_samples() {
    let dir = std::env::temp_dir().join(format!("sticky-lips-keys-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let ramp = face_jaw_run(&dir, "angle = 0.15\nshape = \"ramp\"\nduration = 0.5\n");
    let keyed = face_jaw_run(&dir, "keys = [[0.0, 0.0], [0.5, 0.15], [1.0, 0.15]]\n");
    std::fs::write(dir.join("jaw.csv"), "frame,jaw\n0,0\n12,0.15\n24,0.15\n").unwrap();
    let csv = face_jaw_run(&dir, "keys_file = \"jaw.csv\"\nkeys_fps = 24.0\n");
    std::fs::write(
        dir.join("jaw.json"),
        "{\"time\": [0, 0.5], \"value\": [0, 0.15]}",
    )
    .unwrap();
    let json = face_jaw_run(&dir, "keys_file = \"jaw.json\"\n");
    let moved = ramp.iter().map(norm).fold(0.0, f64::max);
    assert!(moved > 1e-5, "the jaw moved {moved} m");
    assert_eq!(keyed, ramp);
    assert_eq!(csv, ramp);
    assert_eq!(json, ramp);
    // another curve gives another run (the comparison can fail)
    let other = face_jaw_run(&dir, "keys = [[0.0, 0.0], [0.4, 0.15]]\n");
    assert_ne!(other, ramp);
    // a muscle's activation keyed the same way (activation 1: the keys are the activation)
    let base = std::fs::read_to_string(dir.join("scenario.toml")).unwrap();
    let path = dir.join("muscle.toml");
    std::fs::write(
        &path,
        format!("{base}\n[[model_muscle]]\nname = \"depressor_labii_inferioris_l\"\nstrength = 0.05\nkeys = [[0.0, 0.0], [0.01, 1.0], [0.02, 0.25]]\n"),
    )
    .unwrap();
    let p = sticky_lips::io::scenario::read(&path).unwrap().problem;
    let m = &p.physics.muscles[0];
    assert_eq!(m.activation, 1.0);
    for (t, a) in [(0.005, 0.5), (0.015, 0.625), (0.5, 0.25)] {
        assert!(
            (m.curve.value(t, true) - a).abs() < 1e-12,
            "activation at {t}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
