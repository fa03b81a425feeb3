//! The element (paper eq. 4) and the material (NiftySim's neo-Hookean) against calculus:
//! forces are the gradient of the stored energy, the hourglass part vanishes on linear
//! fields, rigid motions give no force, `S = 2 dPsi/dC` and the tangent is `dS/dE`.
//! Also holds the small problem builders shared by the other verification modules.
#![allow(dead_code, clippy::needless_range_loop)] // index loops mirror the tensor notation

use sticky_lips::boundary::BoundaryConditions;
use sticky_lips::element::hex8::GradientVariant;
use sticky_lips::material::neo_hookean::{material_tangent, pk2_stress, strain_energy_density};
use sticky_lips::material::NeoHookean;
use sticky_lips::mesh::generate::{distorted_block, SplitMix64};
use sticky_lips::mesh::Mesh;
use sticky_lips::problem::{MaterialSpec, Numerics, Problem, TimeSettings};
use sticky_lips::tled::element_forces::element_force;
use sticky_lips::tled::precompute::Discretisation;
use sticky_lips::tled::solver::element_energy;
use sticky_lips::Real;

pub const VARIANTS: [GradientVariant; 2] =
    [GradientVariant::MeanGradient, GradientVariant::Centroid];

/// A one-material problem (mu = 1000 Pa, K = 10000 Pa, rho = 1000 kg/m^3) on `mesh`.
pub fn problem(
    mesh: Mesh,
    variant: GradientVariant,
    bc: BoundaryConditions,
    time: TimeSettings,
    damping: f64,
) -> Problem {
    let ne = mesh.elements.len();
    Problem {
        source: "verification".into(),
        mesh,
        materials: vec![MaterialSpec {
            name: "tissue".into(),
            law: NeoHookean {
                mu: 1000.0,
                bulk: 10000.0,
            },
            density: 1000.0,
        }],
        element_material: vec![0; ne],
        bc,
        time,
        numerics: Numerics {
            damping,
            hourglass_kappa: 0.075,
            variant,
            niftysim_timing: false,
            subcycles: 1,
        },
        additive_constraints: false,
        physics: Default::default(),
    }
}

/// `problem` with no loads and the brief's default time settings (only the element matters).
pub fn bare_problem(mesh: Mesh, variant: GradientVariant) -> Problem {
    problem(
        mesh,
        variant,
        BoundaryConditions::default(),
        TimeSettings {
            dt: 1e-4,
            total_time: 1e-3,
            output_every: 1,
        },
        0.0,
    )
}

/// Nodal displacements of element `e`.
pub fn element_u<T: Real>(d: &Discretisation, u: &[[f64; 3]], e: usize) -> [[T; 3]; 8] {
    std::array::from_fn(|a| u[d.conn[e][a] as usize].map(T::from_f64))
}

/// `element_force` in precision `T` for element `e` of `d` at displacement `u` (returned in f64).
pub fn force_of<T: Real>(d: &Discretisation, u: &[[f64; 3]], e: usize) -> [[f64; 3]; 8] {
    force_of_k::<T>(d, u, e, d.hg_k[e])
}

/// Same, with the hourglass stiffness replaced by `k` (0 gives the elastic part alone).
pub fn force_of_k<T: Real>(d: &Discretisation, u: &[[f64; 3]], e: usize, k: f64) -> [[f64; 3]; 8] {
    let c3 = |g: &[[f64; 3]; 8]| g.map(|r| r.map(T::from_f64));
    let c4 = |g: &[[f64; 4]; 8]| g.map(|r| r.map(T::from_f64));
    let (f, _) = element_force::<T>(
        &element_u::<T>(d, u, e),
        &c3(&d.dhdx[e]),
        T::from_f64(d.weight[e]),
        &c4(&d.gamma[e]),
        T::from_f64(k),
        T::from_f64(d.mu[e]),
        T::from_f64(d.bulk[e]),
    );
    f.map(|r| r.map(T::to_f64))
}

pub fn max_abs8(f: &[[f64; 3]; 8]) -> f64 {
    f.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()))
}

pub fn random_matrix(rng: &mut SplitMix64, scale: f64) -> [[f64; 3]; 3] {
    std::array::from_fn(|_| std::array::from_fn(|_| scale * rng.symmetric()))
}

/// `u = G X + c` at every node of `mesh`.
pub fn linear_field(mesh: &Mesh, g: &[[f64; 3]; 3], c: [f64; 3]) -> Vec<[f64; 3]> {
    mesh.nodes
        .iter()
        .map(|x| std::array::from_fn(|i| g[i][0] * x[0] + g[i][1] * x[1] + g[i][2] * x[2] + c[i]))
        .collect()
}

/// Rodrigues rotation about a unit axis.
pub fn rotation(axis: [f64; 3], angle: f64) -> [[f64; 3]; 3] {
    sticky_lips::linalg::rotation_matrix(&axis, angle)
}

fn random_unit(rng: &mut SplitMix64) -> [f64; 3] {
    let v = [rng.symmetric(), rng.symmetric(), rng.symmetric()];
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    v.map(|x| x / n)
}

const H: f64 = 0.01; // element size of the 2x2x2, 0.02 m test blocks (m)

#[test]
fn element_force_is_energy_gradient() {
    // Central differences of element_energy in every nodal DOF. Step delta = 1e-5 h:
    // truncation ~ (delta/h)^2 |f| ~ 1e-10 |f| (times the 3rd-derivative constant, K/mu ~ 10),
    // round-off ~ eps E / delta ~ eps (h/delta) |f| ~ 2e-11 |f|; so ~1e-9 is expected.
    let delta = 1e-5 * H;
    let mut worst: f64 = 0.0;
    for variant in VARIANTS {
        for seed in 1..=3u64 {
            let mesh = distorted_block([0.0; 3], [0.02; 3], [2, 2, 2], 0.25, seed);
            let p = bare_problem(mesh.clone(), variant);
            let d = Discretisation::new(&p);
            let mut rng = SplitMix64(100 + seed);
            // a finite homogeneous part (|grad u| up to 0.3) plus a non-linear nodal part
            // (0.05 h), which also exercises the hourglass term
            let g = random_matrix(&mut rng, 0.3);
            let mut u = linear_field(&mesh, &g, [0.0; 3]);
            for v in u.iter_mut() {
                for c in v.iter_mut() {
                    *c += 0.05 * H * rng.symmetric();
                }
            }
            for e in 0..d.num_elements() {
                let f = force_of::<f64>(&d, &u, e);
                let scale = max_abs8(&f);
                let mut err: f64 = 0.0;
                for a in 0..8 {
                    let n = d.conn[e][a] as usize;
                    for i in 0..3 {
                        let mut up = u.clone();
                        up[n][i] += delta;
                        let mut um = u.clone();
                        um[n][i] -= delta;
                        let fd = (element_energy(&d, &up, e) - element_energy(&d, &um, e))
                            / (2.0 * delta);
                        err = err.max((fd - f[a][i]).abs());
                    }
                }
                worst = worst.max(err / scale);
            }
        }
    }
    println!("element_force_is_energy_gradient: max rel error {worst:.2e}");
    // 1e-6: three orders above the expected FD error (see delta above), far below any real bug
    assert!(
        worst < 1e-6,
        "element force differs from the energy gradient by {worst:e} (relative)"
    );
}

#[test]
fn hourglass_force_vanishes_for_linear_fields() {
    let mut worst: f64 = 0.0;
    let mut hg_mode_ratio = f64::INFINITY;
    for variant in VARIANTS {
        for seed in 1..=3u64 {
            let mesh = distorted_block([0.0; 3], [0.02; 3], [2, 2, 2], 0.25, seed);
            let d = Discretisation::new(&bare_problem(mesh.clone(), variant));
            let mut rng = SplitMix64(200 + seed);
            let g = random_matrix(&mut rng, 0.2);
            let c = [
                0.01 * rng.symmetric(),
                0.01 * rng.symmetric(),
                0.01 * rng.symmetric(),
            ];
            let u = linear_field(&mesh, &g, c);
            for e in 0..d.num_elements() {
                // f_HG_a = k sum_alpha gamma_a,alpha (sum_b gamma_b,alpha u_b), from disc.gamma
                let ue = element_u::<f64>(&d, &u, e);
                let hg = hourglass_force(&d, &ue, e);
                let elastic = force_of_k::<f64>(&d, &u, e, 0.0);
                worst = worst.max(max_abs8(&hg) / max_abs8(&elastic));
                // the library's element_force carries the same hourglass term
                let total = force_of::<f64>(&d, &u, e);
                for a in 0..8 {
                    for i in 0..3 {
                        assert!(
                            (total[a][i] - elastic[a][i] - hg[a][i]).abs()
                                <= 1e-13 * max_abs8(&elastic)
                        );
                    }
                }
                // and the test can fail: an hourglass mode (base vector h_1 in x) is resisted
                let mode: [[f64; 3]; 8] = std::array::from_fn(|a| {
                    [
                        1e-4 * sticky_lips::element::hex8::HOURGLASS_BASE[0][a],
                        0.0,
                        0.0,
                    ]
                });
                let hgm = hourglass_force(&d, &mode, e);
                hg_mode_ratio = hg_mode_ratio.min(max_abs8(&hgm) / (d.hg_k[e] * 1e-4));
            }
        }
    }
    println!("hourglass_force_vanishes_for_linear_fields: max |f_HG|/|f_el| {worst:.2e}; hourglass-mode response >= {hg_mode_ratio:.2} k|u|");
    // 1e-12: gamma^T X = 0 holds to round-off (|gamma| |X| eps); the elastic force of a 20 % gradient is
    // ~1e12 times larger than k eps |u|, so any structural error shows far above it
    assert!(
        worst < 1e-12,
        "hourglass force of a linear field is {worst:e} of the elastic force"
    );
    // an hourglass mode must produce a force of order k |u| (0.1 k|u| is a conservative floor)
    assert!(
        hg_mode_ratio > 0.1,
        "hourglass mode not resisted: {hg_mode_ratio}"
    );
}

fn hourglass_force(d: &Discretisation, ue: &[[f64; 3]; 8], e: usize) -> [[f64; 3]; 8] {
    let gamma = &d.gamma[e];
    let mut h = [[0.0; 3]; 4];
    for b in 0..8 {
        for al in 0..4 {
            for i in 0..3 {
                h[al][i] += gamma[b][al] * ue[b][i];
            }
        }
    }
    std::array::from_fn(|a| {
        std::array::from_fn(|i| d.hg_k[e] * (0..4).map(|al| gamma[a][al] * h[al][i]).sum::<f64>())
    })
}

/// Max element force of a large rigid motion, relative to the max element force of a 1 % strain.
fn rigid_motion_ratio<T: Real>(variant: GradientVariant) -> (f64, f64) {
    let mut worst: f64 = 0.0;
    let mut hmax: f64 = 0.0;
    for seed in 1..=3u64 {
        let mesh = distorted_block([0.0; 3], [0.02; 3], [2, 2, 2], 0.25, seed);
        let d = Discretisation::new(&bare_problem(mesh.clone(), variant));
        let mut rng = SplitMix64(300 + seed);
        let r = rotation(random_unit(&mut rng), 40f64.to_radians());
        let rm: [[f64; 3]; 3] = std::array::from_fn(|i| {
            std::array::from_fn(|j| r[i][j] - if i == j { 1.0 } else { 0.0 })
        });
        hmax = hmax.max(rm.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs())));
        let c = [
            0.02 * rng.symmetric(),
            0.02 * rng.symmetric(),
            0.02 * rng.symmetric(),
        ];
        let u = linear_field(&mesh, &rm, c);
        let strain = linear_field(
            &mesh,
            &[[0.01, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]],
            [0.0; 3],
        );
        for e in 0..d.num_elements() {
            let f = force_of::<T>(&d, &u, e);
            let fs = force_of::<f64>(&d, &strain, e);
            worst = worst.max(max_abs8(&f) / max_abs8(&fs));
        }
    }
    (worst, hmax)
}

#[test]
fn rigid_motion_gives_no_force() {
    for variant in VARIANTS {
        let (r64, hmax) = rigid_motion_ratio::<f64>(variant);
        let (r32, _) = rigid_motion_ratio::<f32>(variant);
        // C - I = H + H^T + H^T H cancels to ~8 eps |H| (|H| ~ 0.7 here); a 1 % strain is 0.01: so the
        // force ratio is ~ 8 eps |H| / 0.01. Bound: 4x that (eps = machine epsilon of each precision).
        let tol = |eps: f64| 4.0 * 8.0 * eps * hmax / 0.01;
        println!(
            "rigid_motion_gives_no_force {variant:?}: f64 {r64:.2e} (tol {:.1e}), f32 {r32:.2e} (tol {:.1e})",
            tol(f64::EPSILON),
            tol(f32::EPSILON as f64)
        );
        assert!(
            r64 < tol(f64::EPSILON),
            "{variant:?} f64: rigid motion force {r64:e} of a 1 % strain force"
        );
        assert!(
            r32 < tol(f32::EPSILON as f64),
            "{variant:?} f32: rigid motion force {r32:e} of a 1 % strain force"
        );
    }
}

fn random_h(rng: &mut SplitMix64, scale: f64) -> [[f64; 3]; 3] {
    random_matrix(rng, scale)
}

#[test]
fn pk2_stress_is_energy_derivative() {
    // P = F S must equal dPsi/dH. Central FD in each H_ij with step delta = 1e-6:
    // truncation ~ delta^2 |Psi'''| ~ 1e-12 * 1e5 Pa, round-off ~ eps Psi / delta ~ 2e-16 * 1e3 / 1e-6 = 2e-7 Pa,
    // against |P| ~ 1e3 Pa: ~1e-10 relative expected.
    let (mu, bulk) = (1000.0, 10000.0);
    let delta = 1e-6;
    let mut rng = SplitMix64(7);
    let mut worst: f64 = 0.0;
    for trial in 0..20 {
        let h = random_h(&mut rng, 0.1 + 0.2 * (trial as f64 / 19.0));
        let (s, _) = pk2_stress(&h, mu, bulk);
        let p: [[f64; 3]; 3] = std::array::from_fn(|i| {
            std::array::from_fn(|j| s[i][j] + (0..3).map(|k| h[i][k] * s[k][j]).sum::<f64>())
        });
        let pmax = p.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        for i in 0..3 {
            for j in 0..3 {
                let mut hp = h;
                hp[i][j] += delta;
                let mut hm = h;
                hm[i][j] -= delta;
                let fd = (strain_energy_density(&hp, mu, bulk)
                    - strain_energy_density(&hm, mu, bulk))
                    / (2.0 * delta);
                worst = worst.max((fd - p[i][j]).abs() / pmax);
            }
        }
    }
    println!("pk2_stress_is_energy_derivative: max rel error {worst:.2e}");
    // 1e-7: three orders above the FD error estimate above
    assert!(worst < 1e-7, "F S differs from dPsi/dH by {worst:e}");
}

#[test]
fn material_tangent_is_stress_derivative() {
    // dS = CC : dE for symmetric dE. A symmetric strain perturbation is produced through
    // dH = F^-T dE (then sym(F^T dH) = dE; the second-order term dH^T dH / 2 is even in the sign
    // of dE and cancels in central differences). delta = 1e-6 as in the stress test.
    let (mu, bulk) = (1000.0, 10000.0);
    let delta = 1e-6;
    let mut rng = SplitMix64(11);
    let mut worst: f64 = 0.0;
    let pairs = [(0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2)];
    for trial in 0..20 {
        let h = random_h(&mut rng, 0.1 + 0.2 * (trial as f64 / 19.0));
        let f: [[f64; 3]; 3] = std::array::from_fn(|i| {
            std::array::from_fn(|j| h[i][j] + if i == j { 1.0 } else { 0.0 })
        });
        let finv_t = sticky_lips::linalg::transpose(&sticky_lips::linalg::inverse(&f));
        let cc = material_tangent(&h, mu, bulk);
        let ccmax = cc
            .iter()
            .flatten()
            .flatten()
            .flatten()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        for (k, l) in pairs {
            let mut de = [[0.0; 3]; 3];
            de[k][l] = if k == l { delta } else { 0.5 * delta };
            de[l][k] = de[k][l];
            let dh = sticky_lips::linalg::mul(&finv_t, &de);
            let hp: [[f64; 3]; 3] =
                std::array::from_fn(|i| std::array::from_fn(|j| h[i][j] + dh[i][j]));
            let hm: [[f64; 3]; 3] =
                std::array::from_fn(|i| std::array::from_fn(|j| h[i][j] - dh[i][j]));
            let (sp, _) = pk2_stress(&hp, mu, bulk);
            let (sm, _) = pk2_stress(&hm, mu, bulk);
            for i in 0..3 {
                for j in 0..3 {
                    let fd = (sp[i][j] - sm[i][j]) / (2.0 * delta);
                    // CC_ijKL dE_KL / delta (dE symmetric: both (k,l) and (l,k) entries)
                    let an: f64 = (0..3)
                        .flat_map(|a| (0..3).map(move |b| (a, b)))
                        .map(|(a, b)| cc[i][j][a][b] * de[a][b])
                        .sum::<f64>()
                        / delta;
                    worst = worst.max((fd - an).abs() / ccmax);
                }
            }
        }
    }
    println!("material_tangent_is_stress_derivative: max rel error {worst:.2e}");
    // 1e-7: three orders above the FD error (round-off eps |S| / delta ~ 2e-16 * 1e4 / 1e-6 = 2e-6 Pa
    // against |CC| ~ 1e4 Pa: 2e-10; truncation ~ delta^2 |S'''| similar)
    assert!(
        worst < 1e-7,
        "material tangent differs from dS/dE by {worst:e}"
    );
}
