//! Central differences (paper eq. 3 with lumped mass and mass-proportional damping):
//! second-order convergence, energy conservation without damping, the stability limit
//! `2 / omega_max`, and convergence of a damped run to the static equilibrium.

use crate::element::problem;
use sticky_lips::boundary::{
    BoundaryConditions, Fixed, LoadCurve, LoadShape, NodalForce, PrescribedDisplacement,
};
use sticky_lips::element::hex8::GradientVariant;
use sticky_lips::mesh::generate::{block, distorted_block};
use sticky_lips::mesh::Mesh;
use sticky_lips::problem::{Problem, TimeSettings};
use sticky_lips::static_solve::{solve_equilibrium, StaticOptions};
use sticky_lips::tled::precompute::Discretisation;
use sticky_lips::tled::solver::strain_energy;
use sticky_lips::tled::stability::{analyse, check_time_step, linear_stiffness_times};
use sticky_lips::tled::Simulation;
use sticky_lips::Error;

fn fix_all(nodes: &[u32]) -> Fixed {
    Fixed {
        nodes: nodes.to_vec(),
        dofs: [true; 3],
    }
}

fn force(nodes: &[u32], dof: usize, each: f64, curve: LoadCurve) -> NodalForce {
    NodalForce {
        nodes: nodes.to_vec(),
        dof,
        values: vec![each; nodes.len()],
        curve,
    }
}

fn max_abs(u: &[[f64; 3]]) -> f64 {
    u.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()))
}

fn max_diff(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|(x, y)| (0..3).map(move |k| (x[k] - y[k]).abs()))
        .fold(0.0, f64::max)
}

/// Critical time step of `p` (Lanczos, `2 / omega_max`).
fn critical_dt(p: &Problem) -> f64 {
    analyse(p, &Discretisation::new(p)).critical_time_step
}

/// Runs `p` with time step `dt` to its end, returns the final displacement.
fn run_with_dt(p: &Problem, dt: f64) -> Vec<[f64; 3]> {
    let mut q = p.clone();
    q.time.dt = dt;
    let mut sim = Simulation::<f64>::new(&q).unwrap();
    assert_eq!(
        sim.num_steps() as f64 * dt,
        q.time.total_time,
        "dt must divide the run"
    );
    while !sim.is_finished() {
        sim.step().unwrap();
    }
    sim.displacement_f64()
}

/// 2x2x2 block, 0.02 m, base fixed, a smooth (POLY345 over the whole run) shear force on the top.
fn convergence_problem(total_time: f64) -> Problem {
    let mesh = block([0.0; 3], [0.02; 3], [2, 2, 2]);
    let top = mesh.node_sets["z_max"].clone();
    let mut bc = BoundaryConditions::default();
    bc.fixed.push(fix_all(&mesh.node_sets["z_min"]));
    let curve = LoadCurve {
        shape: LoadShape::Poly345,
        start: 0.0,
        duration: total_time,
    };
    // ~10 % shear at the end of the ramp: non-linear, but far from inversion
    bc.forces.push(force(&top, 0, 5e-3, curve.clone()));
    bc.forces.push(force(&top, 2, 2e-3, curve));
    problem(
        mesh,
        GradientVariant::MeanGradient,
        bc,
        TimeSettings {
            dt: 1e-3,
            total_time,
            output_every: 1,
        },
        0.0,
    )
}

#[test]
fn central_differences_second_order() {
    let t_end = 0.1; // s, longer than the first shear period (~0.08 s)
    let p = convergence_problem(t_end);
    let dtc = critical_dt(&p);
    // coarsest step: at most 0.4 dt_crit, and an integer number of steps to t_end
    let n0 = (t_end / (0.4 * dtc)).ceil() as usize;
    let dts: Vec<f64> = (0..6).map(|k| t_end / (n0 << k) as f64).collect();
    let sols: Vec<Vec<[f64; 3]>> = dts.iter().map(|&dt| run_with_dt(&p, dt)).collect();
    // reference: Richardson extrapolation of the two finest runs (error O(dt^4))
    let reference: Vec<[f64; 3]> = sols[4]
        .iter()
        .zip(&sols[5])
        .map(|(a, b)| std::array::from_fn(|k| (4.0 * b[k] - a[k]) / 3.0))
        .collect();
    let scale = max_abs(&reference);
    let errs: Vec<f64> = sols[..4]
        .iter()
        .map(|u| max_diff(u, &reference) / scale)
        .collect();
    // least-squares slope of log(err) against log(dt)
    let xs: Vec<f64> = dts[..4].iter().map(|d| d.ln()).collect();
    let ys: Vec<f64> = errs.iter().map(|e| e.ln()).collect();
    let (mx, my) = (xs.iter().sum::<f64>() / 4.0, ys.iter().sum::<f64>() / 4.0);
    let slope = xs
        .iter()
        .zip(&ys)
        .map(|(x, y)| (x - mx) * (y - my))
        .sum::<f64>()
        / xs.iter().map(|x| (x - mx) * (x - mx)).sum::<f64>();
    let pairwise: Vec<f64> = errs.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
    println!(
        "central_differences_second_order: dt_crit {dtc:.3e}, dt0 {:.3e} (n0 {n0}), max |u| {scale:.3e} m, errors {}, pairwise orders {pairwise:.3?}, fitted order {slope:.4}",
        dts[0],
        errs.iter().map(|e| format!("{e:.3e}")).collect::<Vec<_>>().join(" ")
    );
    // [1.8, 2.2]: the scheme is second order; 0.2 allows the pre-asymptotic bend of the coarsest step
    assert!(
        (1.8..=2.2).contains(&slope),
        "observed order {slope} (errors {errs:?})"
    );
}

/// Cantilever-like 4x2x2 block (0.02 x 0.01 x 0.01 m), x = 0 clamped.
fn cantilever(forces: Vec<NodalForce>, damping: f64, dt: f64, total_time: f64) -> Problem {
    let mesh = block([0.0; 3], [0.02, 0.01, 0.01], [4, 2, 2]);
    let mut bc = BoundaryConditions::default();
    bc.fixed.push(fix_all(&mesh.node_sets["x_min"]));
    bc.forces = forces;
    problem(
        mesh,
        GradientVariant::MeanGradient,
        bc,
        TimeSettings {
            dt,
            total_time,
            output_every: 1,
        },
        damping,
    )
}

/// Energy record of an undamped run under constant forces: `(E_n - E_0) / max SE` extremes and trend.
fn energy_drift(dt_fraction: f64) -> (f64, f64, f64, usize) {
    let step = LoadCurve {
        shape: LoadShape::Step,
        start: 0.0,
        duration: 1.0,
    };
    let probe = cantilever(vec![], 0.0, 1e-3, 1.0);
    let tip = probe.mesh.node_sets["x_max"].clone();
    let forces = vec![
        force(&tip, 2, -2e-3, step.clone()),
        force(&tip, 1, 1e-3, step),
    ];
    let p0 = cantilever(forces.clone(), 0.0, 1e-3, 1.0);
    let dtc = critical_dt(&p0);
    let t_end = 2.0; // s: ~15 periods of the first bending mode
    let n = (t_end / (dt_fraction * dtc)).ceil() as usize;
    let dt = t_end / n as f64;
    let p = cantilever(forces, 0.0, dt, t_end);
    let d = Discretisation::new(&p);
    // f as a nodal vector
    let mut f = vec![[0.0; 3]; d.num_nodes];
    for g in &p.bc.forces {
        for (&node, &v) in g.nodes.iter().zip(&g.values) {
            f[node as usize][g.dof] += v;
        }
    }
    let mut sim = Simulation::<f64>::new(&p).unwrap();
    // E_n = KE(v_n) + SE(u_n) - f . u_n with the central velocity v_n = (u_{n+1} - u_{n-1}) / (2 dt)
    let mut energies = Vec::with_capacity(n);
    let mut se_max: f64 = 0.0;
    while !sim.is_finished() {
        let u_prev = sim.previous_displacement().to_vec(); // u_{n-1}
        let u = sim.displacement_f64(); // u_n
        sim.step().unwrap(); // now displacement() = u_{n+1}
        let u_next = sim.displacement();
        let mut ke = 0.0;
        for k in 0..d.num_nodes {
            for c in 0..3 {
                let v = (u_next[k][c] - u_prev[k][c]) / (2.0 * dt);
                ke += 0.5 * d.mass[k] * v * v;
            }
        }
        let se = strain_energy(&d, &u);
        let work: f64 = f
            .iter()
            .zip(&u)
            .map(|(a, b)| a[0] * b[0] + a[1] * b[1] + a[2] * b[2])
            .sum();
        se_max = se_max.max(se);
        energies.push(ke + se - work);
    }
    let e0 = energies[0];
    let spread = energies.iter().map(|e| (e - e0).abs()).fold(0.0, f64::max) / se_max;
    // secular trend: mean of the last quarter minus the mean of the first quarter
    let q = energies.len() / 4;
    let mean = |s: &[f64]| s.iter().sum::<f64>() / s.len() as f64;
    let trend = (mean(&energies[3 * q..]) - mean(&energies[..q])) / se_max;
    (spread, trend, dt, n)
}

#[test]
fn energy_conserved_without_damping() {
    let (s1, t1, dt1, n1) = energy_drift(0.5);
    let (s2, t2, dt2, n2) = energy_drift(0.25);
    println!(
        "energy_conserved_without_damping: dt {dt1:.3e} ({n1} steps): max |E-E0| {s1:.2e}, trend {t1:.2e}; dt {dt2:.3e} ({n2} steps): max |E-E0| {s2:.2e}, trend {t2:.2e} (of max strain energy); ratio {:.2}",
        s1 / s2
    );
    // central differences conserve a modified energy exactly; the central-velocity energy differs
    // from it by O((omega dt)^2) of the energy in each mode, bounded and without growth. 2e-3 of the
    // strain energy at dt = 0.5 dt_crit: the modes that carry the energy here have omega dt < 0.1,
    // (omega dt)^2 / 4 < 2.5e-3; that it is the scheme's O(dt^2) is checked by the scaling below
    assert!(
        s1 < 2e-3 && s2 < 2e-3,
        "energy oscillation {s1:e} / {s2:e} of the strain energy"
    );
    // no secular drift: the first and last quarters of the run (~15 periods) have the same mean energy
    // to 1e-3 of the strain energy; a spurious drift of 1e-7 per step (the size of f32's B + C - 1)
    // would accumulate to 3e-4 .. 6e-4 over these 3000 .. 6000 steps
    assert!(
        t1.abs() < 1e-3 && t2.abs() < 1e-3,
        "secular energy drift {t1:e} / {t2:e}"
    );
    // the oscillation is the O(dt^2) error of the scheme: halving dt divides it by ~4 (3..5)
    assert!(
        (3.0..=5.0).contains(&(s1 / s2)),
        "energy oscillation does not scale as dt^2: ratio {}",
        s1 / s2
    );
}

/// 2x2x2 block, base fixed, top face pulled up by 1e-4 m (0.5 %) with a smooth step.
fn stability_problem(dt: f64) -> Problem {
    let mesh = block([0.0; 3], [0.02; 3], [2, 2, 2]);
    let top = mesh.node_sets["z_max"].clone();
    let mut bc = BoundaryConditions::default();
    bc.fixed.push(fix_all(&mesh.node_sets["z_min"]));
    let curve = LoadCurve {
        shape: LoadShape::SmoothStep,
        start: 0.0,
        duration: 0.05,
    };
    bc.displacements.push(PrescribedDisplacement {
        nodes: top.clone(),
        dof: 2,
        values: vec![1e-4; top.len()],
        curve,
    });
    problem(
        mesh,
        GradientVariant::MeanGradient,
        bc,
        TimeSettings {
            dt,
            total_time: 400.0 * dt,
            output_every: 1,
        },
        0.0,
    )
}

#[test]
fn stability_limit() {
    let p = stability_problem(1e-3);
    let rep = analyse(&p, &Discretisation::new(&p));
    let dtc = rep.critical_time_step;
    let amplitude = 1e-4; // m, the prescribed displacement
                          // 0.95 dt_crit: bounded for 400 steps
    let stable = stability_problem(0.95 * dtc);
    let mut sim = Simulation::<f64>::new(&stable).unwrap();
    let mut umax: f64 = 0.0;
    while !sim.is_finished() {
        sim.step().unwrap();
        umax = umax.max(max_abs(&sim.displacement_f64()));
    }
    // 1.05 dt_crit: the highest mode grows by |lambda| ~ 1.9 per step; within 400 steps it either
    // inverts an element (Diverged) or grows past 1e6 x the load
    let unstable = stability_problem(1.05 * dtc);
    let mut sim = Simulation::<f64>::new(&unstable).unwrap();
    let mut diverged_at = None;
    let mut why = String::new();
    while !sim.is_finished() {
        match sim.step() {
            Err(e @ Error::Diverged { .. }) => {
                diverged_at = Some(sim.step_index());
                why = e.to_string();
                break;
            }
            Err(e) => panic!("unexpected error {e}"),
            Ok(()) => {
                if max_abs(&sim.displacement_f64()) > 1e6 * amplitude {
                    diverged_at = Some(sim.step_index());
                    why = "|u| > 1e6 x load".into();
                    break;
                }
            }
        }
    }
    println!(
        "stability_limit: dt_crit {dtc:.4e} s (omega_max {:.4e}, {} Lanczos its; element estimate {:.4e} s, element {}); 0.95 dt_crit: max |u| {:.3} x load; 1.05 dt_crit: diverged at step {diverged_at:?} ({why})",
        rep.omega_max, rep.iterations, rep.element_estimate, rep.limiting_element, umax / amplitude
    );
    // 10x: a stable run overshoots a smoothly applied displacement by far less
    assert!(
        umax < 10.0 * amplitude,
        "run at 0.95 dt_crit grew to {umax:e} m"
    );
    assert!(
        diverged_at.is_some(),
        "run at 1.05 dt_crit did not diverge in 400 steps"
    );
    // the refusal names the limiting element
    assert!(check_time_step(&stable, &rep, false).is_ok());
    match check_time_step(&unstable, &rep, false) {
        Err(e @ Error::UnstableTimeStep { .. }) => {
            let msg = e.to_string();
            let Error::UnstableTimeStep { element, .. } = e else {
                unreachable!()
            };
            assert_eq!(element, rep.limiting_element);
            assert!(
                msg.contains(&format!("limiting element is {element}")),
                "message does not name the element: {msg}"
            );
        }
        other => panic!("check_time_step accepted 1.05 dt_crit: {other:?}"),
    }
    assert!(
        check_time_step(&unstable, &rep, true).is_ok(),
        "force = true must let the run go"
    );
}

/// `M^-1/2 K M^-1/2` on the free DOFs as a dense symmetric matrix (columns from
/// `linear_stiffness_times`, symmetrised).
fn dense_free_operator(d: &Discretisation) -> nalgebra::DMatrix<f64> {
    let n = 3 * d.num_nodes;
    let free: Vec<usize> = (0..n).filter(|&k| !d.constraints.constrained[k]).collect();
    let m = free.len();
    let mut kmat = nalgebra::DMatrix::<f64>::zeros(m, m);
    let mut e = vec![0.0; n];
    let mut col = vec![0.0; n];
    for (j, &kj) in free.iter().enumerate() {
        e[kj] = 1.0;
        linear_stiffness_times(d, &e, &mut col);
        e[kj] = 0.0;
        for (i, &ki) in free.iter().enumerate() {
            kmat[(i, j)] = col[ki] / (d.mass[ki / 3] * d.mass[kj / 3]).sqrt();
        }
    }
    0.5 * (&kmat + kmat.transpose())
}

/// Smallest circular frequency `omega_1` (rad/s) of the linearised, constrained model (dense eigen).
fn lowest_frequency(d: &Discretisation) -> f64 {
    let kmat = dense_free_operator(d);
    let lmin = kmat
        .symmetric_eigen()
        .eigenvalues
        .iter()
        .cloned()
        .fold(f64::INFINITY, f64::min);
    lmin.sqrt()
}

fn damped_problem(damping: f64, dt: f64, t_load: f64, total_time: f64) -> Problem {
    let mesh: Mesh = distorted_block([0.0; 3], [0.03; 3], [3, 3, 3], 0.25, 5);
    let top = mesh.node_sets["z_max"].clone();
    let side = mesh.node_sets["x_max"].clone();
    let ramp = LoadCurve {
        shape: LoadShape::Ramp,
        start: 0.0,
        duration: t_load,
    };
    let mut bc = BoundaryConditions::default();
    bc.fixed.push(fix_all(&mesh.node_sets["z_min"]));
    // top face stretched by 15 % (only u_z prescribed), a lateral force on the x = max face
    bc.displacements.push(PrescribedDisplacement {
        nodes: top.clone(),
        dof: 2,
        values: vec![0.15 * 0.03; top.len()],
        curve: ramp.clone(),
    });
    let side_free: Vec<u32> = side.iter().copied().filter(|n| !top.contains(n)).collect();
    bc.forces.push(force(&side_free, 1, 2e-3, ramp));
    problem(
        mesh,
        GradientVariant::MeanGradient,
        bc,
        TimeSettings {
            dt,
            total_time,
            output_every: 1,
        },
        damping,
    )
}

#[test]
fn damped_run_reaches_static_equilibrium() {
    let probe = damped_problem(0.0, 1e-3, 1.0, 1.0);
    let d = Discretisation::new(&probe);
    let omega1 = lowest_frequency(&d);
    let dtc = analyse(&probe, &d).critical_time_step;
    // alpha = 2 omega_1: critical damping of the first mode; every underdamped mode then decays at
    // alpha / 2, and an overdamped one (omega < omega_1 after the deformation) no slower than
    // alpha/2 - sqrt(alpha^2/4 - omega^2), i.e. 0.4 omega_1 for omega = 0.8 omega_1
    let alpha = 2.0 * omega1;
    let t_load = 5.0 / omega1;
    let t_settle = 60.0 / omega1;
    // 0.7 dt_crit: margin for the stiffening of the tangent at 15 % stretch
    let n = ((t_load + t_settle) / (0.7 * dtc)).ceil() as usize;
    let total = t_load + t_settle;
    let dt = total / n as f64;
    let p = damped_problem(alpha, dt, t_load, total);
    let mut sim = Simulation::<f64>::new(&p).unwrap();
    while !sim.is_finished() {
        sim.step().unwrap();
    }
    let u_dyn = sim.displacement_f64();
    let res = solve_equilibrium(
        &p,
        &StaticOptions {
            tolerance: 1e-12,
            ..Default::default()
        },
    )
    .unwrap();
    let err = max_diff(&u_dyn, &res.u) / max_abs(&res.u);
    let predicted = (-0.4 * omega1 * t_settle).exp();
    println!(
        "damped_run_reaches_static_equilibrium: omega_1 {omega1:.2} rad/s, alpha {alpha:.2} 1/s, dt {dt:.3e} s ({n} steps, dt_crit {dtc:.3e}), \
         settle {t_settle:.3} s; |u_TLED - u_static| / max|u| = {err:.2e} (transient bound exp(-0.4 omega_1 t) = {predicted:.1e}); static: {} Newton its, residual {:.1e} of {:.1e}",
        res.newton_iterations, res.residual_norm, res.reaction_scale
    );
    // 1e-6: the transient has decayed to < 4e-11 (see above) and the fixed point of central
    // differences is exactly F_int(u) = R; 1e-6 leaves room for a slower nonlinear decay
    assert!(
        err < 1e-6,
        "damped TLED run differs from the static equilibrium by {err:e} (relative)"
    );
}

/// The stiffness the stability analysis uses is the element forces' derivative at rest:
/// `K v = (f(eps v) - f(-eps v)) / (2 eps)` (central difference of the internal forces that
/// the time step computes, eq. 4 with hourglass control) for random `v` on a distorted block,
/// both gradient variants, on an unconstrained model. cargo-mutants found the stability
/// analysis's Lamé constant (`K - 2 mu / 3`) and its hourglass term unchecked: the tests of
/// the critical time step tolerate what either changes. The element's own estimate `L / c`
/// is checked against its definition on the same block.
#[test]
fn linear_stiffness_is_the_derivative_of_the_element_forces() {
    use sticky_lips::element::hex8;
    use sticky_lips::mesh::generate::SplitMix64;
    use sticky_lips::tled::element_forces::{element_forces, ElementArrays};
    use sticky_lips::tled::node_update::gather_all;
    for variant in [GradientVariant::MeanGradient, GradientVariant::Centroid] {
        let mesh = distorted_block([0.0; 3], [0.03, 0.02, 0.025], [3, 2, 3], 0.2, 17);
        let p = problem(
            mesh,
            variant,
            BoundaryConditions::default(),
            TimeSettings {
                dt: 1e-5,
                total_time: 1e-3,
                output_every: 100,
            },
            0.0,
        );
        let d = Discretisation::new(&p);
        let el = ElementArrays::<f64>::from_discretisation(&d);
        let n = d.num_nodes;
        let mut rng = SplitMix64(5);
        let v: Vec<f64> = (0..3 * n).map(|_| rng.symmetric()).collect();
        let mut kv = vec![0.0; 3 * n];
        linear_stiffness_times(&d, &v, &mut kv);
        let eps = 1e-7;
        let force = |s: f64| {
            let u: Vec<[f64; 3]> = (0..n)
                .map(|k| [s * v[3 * k], s * v[3 * k + 1], s * v[3 * k + 2]])
                .collect();
            let mut blocks = vec![[[0.0; 3]; 8]; d.num_elements()];
            assert!(element_forces(&el, &u, &mut blocks).is_none());
            gather_all(&d.gather, &blocks, n)
        };
        let (fp, fm) = (force(eps), force(-eps));
        let scale = kv.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let mut worst = 0.0f64;
        for k in 0..n {
            for i in 0..3 {
                let fd = (fp[k][i] - fm[k][i]) / (2.0 * eps);
                worst = worst.max((fd - kv[3 * k + i]).abs() / scale);
            }
        }
        println!("{variant:?}: max |K v - central difference| / max |K v| = {worst:.2e}");
        assert!(scale > 0.0);
        assert!(worst < 1e-6, "{variant:?}: {worst:e}");
        // L / c per element, c the P-wave speed of the material
        let est = sticky_lips::tled::stability::element_estimates(&p);
        let m = &p.materials[0];
        let c = (m.law.p_wave_modulus() / m.density).sqrt();
        assert_eq!(est.len(), p.mesh.elements.len());
        for (e, t) in est.iter().enumerate() {
            let want = hex8::characteristic_length(&p.mesh.element_coords(e)) / c;
            assert_eq!(*t, want);
        }
        assert!(
            c > 3.0 && c < 4.0,
            "c = {c} m/s for mu = 1000 Pa, K = 10000 Pa"
        );
    }
}

/// The Lanczos estimate of `lambda_max` (the stability analysis's `omega_max^2`) against a
/// dense eigensolver, and its stopping rule as documented: it stops at the first iteration
/// that is the third in a row whose Ritz value changed by at most `tol` of itself (the
/// value before the first is 0), and returns that value with the iteration count. The
/// sequence of Ritz values comes from the same function stopped after `k` iterations
/// (`max_iter = k`, `tol = 0`). cargo-mutants found the stopping rule unchecked (11 mutants
/// of `largest_eigenvalue` missed).
#[test]
fn lanczos_stops_at_the_third_converged_ritz_value() {
    use sticky_lips::tled::stability::largest_eigenvalue;
    let mesh = distorted_block([0.0; 3], [0.03, 0.02, 0.025], [3, 2, 3], 0.2, 17);
    let mut bc = BoundaryConditions::default();
    bc.fixed.push(fix_all(&mesh.node_sets["z_min"]));
    let time = TimeSettings {
        dt: 1e-5,
        total_time: 1e-3,
        output_every: 100,
    };
    let p = problem(mesh, GradientVariant::MeanGradient, bc, time, 0.0);
    let d = Discretisation::new(&p);
    let tol = 1e-10;
    let (lmax, iterations) = largest_eigenvalue(&d, 300, tol);
    assert!(iterations < 300, "did not converge");
    // the dense largest eigenvalue of M^-1/2 K M^-1/2 on the free DOFs
    let kmat = dense_free_operator(&d);
    let dense = kmat
        .symmetric_eigen()
        .eigenvalues
        .iter()
        .cloned()
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(
        (lmax - dense).abs() <= 1e-9 * dense,
        "Lanczos {lmax} vs dense {dense}"
    );
    // the stopping rule, from the Ritz values of iterations 1 ..= iterations
    let ritz: Vec<f64> = (1..=iterations)
        .map(|k| {
            let (r, it) = largest_eigenvalue(&d, k, 0.0);
            assert_eq!(it, k, "stopped early without a tolerance");
            r
        })
        .collect();
    let converged = |k: usize| {
        let before = if k == 0 { 0.0 } else { ritz[k - 1] };
        (ritz[k] - before).abs() <= tol * ritz[k].abs()
    };
    let want = (2..ritz.len())
        .find(|&k| converged(k) && converged(k - 1) && converged(k - 2))
        .map(|k| k + 1)
        .expect("three converged Ritz values in a row");
    assert_eq!(iterations, want);
    assert_eq!(lmax, ritz[iterations - 1]);
    let total = (0..iterations).filter(|&k| converged(k)).count();
    println!("{iterations} iterations, {total} converged Ritz values, lambda_max {lmax:.6e}");
}

/// When the Krylov space is exhausted the iteration stops at the breakdown with the exact
/// largest eigenvalue: a single hexahedron with seven corners fixed leaves a 3 x 3 problem
/// whose eigenvalues are the one-point rule's `(lambda + 2 mu) |g|^2 V` along the free
/// corner's gradient `g` and `mu |g|^2 V` twice across it (each with the same hourglass
/// term added), so a start vector spans two of them and the iteration breaks down after
/// two, as many as the distinct eigenvalues.
#[test]
fn lanczos_stops_when_the_krylov_space_is_exhausted() {
    use sticky_lips::tled::stability::largest_eigenvalue;
    let mut mesh = block([0.0; 3], [0.01, 0.012, 0.009], [1, 1, 1]);
    // every corner moved by a different 0.5-1.5 mm: not a box
    for (i, x) in mesh.nodes.iter_mut().enumerate() {
        for (k, c) in x.iter_mut().enumerate() {
            *c += 1e-3 * (0.5 + ((7 * i + 3 * k) % 5) as f64 / 4.0);
        }
    }
    let mut bc = BoundaryConditions::default();
    bc.fixed.push(fix_all(&(0..7).collect::<Vec<u32>>()));
    let time = TimeSettings {
        dt: 1e-5,
        total_time: 1e-3,
        output_every: 100,
    };
    let p = problem(mesh, GradientVariant::MeanGradient, bc, time, 0.0);
    let d = Discretisation::new(&p);
    let (lmax, iterations) = largest_eigenvalue(&d, 300, 0.0);
    let kmat = dense_free_operator(&d);
    assert_eq!(kmat.nrows(), 3);
    let mut eig: Vec<f64> = kmat.symmetric_eigen().eigenvalues.iter().cloned().collect();
    eig.sort_by(f64::total_cmp);
    let dense = eig[2];
    assert!((lmax - dense).abs() <= 1e-12 * dense, "{lmax} vs {dense}");
    let distinct = 1 + eig
        .windows(2)
        .filter(|w| w[1] - w[0] > 1e-9 * dense)
        .count();
    assert_eq!(distinct, 2, "{eig:?}");
    assert_eq!(iterations, distinct);
}

/// The report's element estimate is the smallest of the per-element estimates and names the
/// first element that has it (equal cubes: element 0; a distorted block: its argmin), and
/// `check_time_step` accepts a time step equal to the critical one and refuses the next
/// larger float ("above the critical step"). cargo-mutants found both unchecked.
#[test]
fn the_report_names_the_smallest_element_estimate_and_the_limit_is_inclusive() {
    use sticky_lips::tled::stability::element_estimates;
    // three copies of one cube on their own nodes at the same place: their estimates are
    // the same computation, equal bit for bit
    let time = TimeSettings {
        dt: 1e-5,
        total_time: 1e-3,
        output_every: 100,
    };
    let mut cubes = block([0.0; 3], [0.01; 3], [1, 1, 1]);
    for copy in 1..3u32 {
        let e = cubes.elements[0].map(|v| v + 8 * copy);
        cubes.nodes.extend_from_within(0..8);
        cubes.elements.push(e);
    }
    cubes.node_sets.clear();
    let uniform = problem(
        cubes,
        GradientVariant::MeanGradient,
        BoundaryConditions::default(),
        time,
        0.0,
    );
    let rep = analyse(&uniform, &Discretisation::new(&uniform));
    let est = element_estimates(&uniform);
    assert!(
        est.iter().all(|&e| e == est[0]),
        "the cubes' estimates differ: {est:?}"
    );
    assert_eq!(rep.limiting_element, 0);
    assert_eq!(rep.element_estimate, est[0]);
    let mesh = distorted_block([0.0; 3], [0.03, 0.02, 0.025], [3, 2, 3], 0.2, 17);
    let time = TimeSettings {
        dt: 1e-5,
        total_time: 1e-3,
        output_every: 100,
    };
    let p = problem(
        mesh,
        GradientVariant::MeanGradient,
        BoundaryConditions::default(),
        time,
        0.0,
    );
    let rep = analyse(&p, &Discretisation::new(&p));
    let est = element_estimates(&p);
    let min = est.iter().cloned().fold(f64::INFINITY, f64::min);
    assert_eq!(rep.element_estimate, min);
    assert_eq!(
        rep.limiting_element,
        est.iter().position(|&e| e == min).unwrap()
    );
    assert!(
        rep.limiting_element > 0,
        "the test should not pass with element 0 by default"
    );
    // the limit itself is allowed; the next float above it is not
    let mut at = p.clone();
    at.time.dt = rep.critical_time_step;
    assert!(check_time_step(&at, &rep, false).is_ok());
    at.time.dt = f64::from_bits(rep.critical_time_step.to_bits() + 1);
    assert!(check_time_step(&at, &rep, false).is_err());
}
