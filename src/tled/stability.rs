//! The critical time step of central differences.
//!
//! Central differences are stable for `dt <= 2 / omega_max`, with `omega_max^2` the
//! largest eigenvalue of `M^-1 K` (the linearised stiffness at rest, hourglass control
//! included, on the unconstrained DOFs). Mass-proportional damping does not move this
//! limit: the characteristic polynomial of the damped recursion has its root at -1 exactly
//! when `omega dt = 2`.
//!
//! Two estimates: per element, `dt_e = L_e / c_e` with `L_e` = volume / largest face area
//! and `c_e = sqrt((K + 4 mu / 3) / rho)` (it names the limiting element), and the global
//! `2 / omega_max` from a Lanczos iteration on `M^-1/2 K M^-1/2`, which is what a run is
//! checked against.

use crate::element::hex8;
use crate::problem::Problem;
use crate::tled::precompute::Discretisation;
use rayon::prelude::*;

#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct StabilityReport {
    /// `2 / omega_max` (s).
    pub critical_time_step: f64,
    /// `omega_max` (rad/s).
    pub omega_max: f64,
    /// Smallest per-element estimate `L_e / c_e` (s) and its element.
    pub element_estimate: f64,
    pub limiting_element: usize,
    /// Lanczos iterations used.
    pub iterations: usize,
    /// For a model with saliva: `2 / omega_max` of the model without the saliva's stiffness
    /// (s), the limit of a subcycled run's large step (`tled::subcycle`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tissue_critical_time_step: Option<f64>,
}

/// Per-element estimates `L_e / c_e` (s).
pub fn element_estimates(p: &Problem) -> Vec<f64> {
    (0..p.mesh.elements.len())
        .map(|e| {
            let m = &p.materials[p.element_material[e] as usize];
            let c = (m.law.p_wave_modulus() / m.density).sqrt();
            hex8::characteristic_length(&p.mesh.element_coords(e)) / c
        })
        .collect()
}

/// `K v` for the stiffness linearised at `u = 0`: `W (lambda tr(H) I + mu (H + H^T)) D_a`
/// plus the hourglass term, with `H = sum_a v_a (x) D_a`. (At rest the neo-Hookean
/// tangent is the isotropic linear-elastic one with `lambda = K - 2 mu / 3`.)
pub fn linear_stiffness_times(d: &Discretisation, v: &[f64], out: &mut [f64]) {
    let mut blocks = Vec::new();
    linear_stiffness_times_with(d, v, out, &mut blocks);
}

/// [`linear_stiffness_times`] with the per-element force blocks in a buffer the caller keeps
/// between calls (the Lanczos iteration calls it about 50 times).
fn linear_stiffness_times_with(
    d: &Discretisation,
    v: &[f64],
    out: &mut [f64],
    blocks: &mut Vec<[[f64; 3]; 8]>,
) {
    blocks.resize(d.num_elements(), [[0.0; 3]; 8]);
    blocks.par_iter_mut().enumerate().for_each(|(e, block)| {
        let conn = &d.conn[e];
        let ve: [[f64; 3]; 8] = std::array::from_fn(|a| {
            let n = conn[a] as usize;
            [v[3 * n], v[3 * n + 1], v[3 * n + 2]]
        });
        let mut h = [[0.0; 3]; 3];
        for a in 0..8 {
            for i in 0..3 {
                for j in 0..3 {
                    h[i][j] += ve[a][i] * d.dhdx[e][a][j];
                }
            }
        }
        let lambda = d.bulk[e] - 2.0 * d.mu[e] / 3.0;
        let tr = h[0][0] + h[1][1] + h[2][2];
        let mut s = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                s[i][j] = d.weight[e]
                    * (d.mu[e] * (h[i][j] + h[j][i]) + if i == j { lambda * tr } else { 0.0 });
            }
        }
        let mut hg = [[0.0; 3]; 4];
        for b in 0..8 {
            for alpha in 0..4 {
                for i in 0..3 {
                    hg[alpha][i] += d.gamma[e][b][alpha] * ve[b][i];
                }
            }
        }
        let mut f = [[0.0; 3]; 8];
        for a in 0..8 {
            for i in 0..3 {
                let el: f64 = (0..3).map(|j| s[i][j] * d.dhdx[e][a][j]).sum();
                let hgf: f64 = (0..4).map(|al| d.gamma[e][a][al] * hg[al][i]).sum();
                f[a][i] = el + d.hg_k[e] * hgf;
            }
        }
        *block = f;
    });
    let blocks = &blocks[..];
    out.par_chunks_mut(3).enumerate().for_each(|(n, o)| {
        let mut f = [0.0; 3];
        for &s in d.gather.of(n) {
            let b = &blocks[s as usize / 8][s as usize % 8];
            for k in 0..3 {
                f[k] += b[k];
            }
        }
        o.copy_from_slice(&f);
    });
}

/// Largest eigenvalue of `M^-1/2 K M^-1/2` on the free DOFs by Lanczos iteration
/// (no reorthogonalisation: only the extreme Ritz value is wanted, and it converges
/// first). Returns `(lambda_max, iterations)`.
pub fn largest_eigenvalue(d: &Discretisation, max_iter: usize, tol: f64) -> (f64, usize) {
    let n = 3 * d.num_nodes;
    let free: Vec<bool> = d.constraints.constrained.iter().map(|c| !c).collect();
    let inv_sqrt_m: Vec<f64> = (0..n).map(|k| 1.0 / d.mass[k / 3].sqrt()).collect();
    let mut xs = vec![0.0; n];
    let mut blocks = Vec::new();
    let mut op = |x: &[f64], y: &mut [f64]| {
        for k in 0..n {
            xs[k] = if free[k] { x[k] * inv_sqrt_m[k] } else { 0.0 };
        }
        linear_stiffness_times_with(d, &xs, y, &mut blocks);
        for k in 0..n {
            y[k] = if free[k] { y[k] * inv_sqrt_m[k] } else { 0.0 };
        }
    };
    let mut rng = crate::mesh::generate::SplitMix64(0x5EED);
    let mut q: Vec<f64> = (0..n)
        .map(|k| if free[k] { rng.symmetric() } else { 0.0 })
        .collect();
    let nrm = dot(&q, &q).sqrt();
    if nrm == 0.0 {
        return (0.0, 0);
    }
    q.iter_mut().for_each(|v| *v /= nrm);
    let mut q_prev = vec![0.0; n];
    let mut w = vec![0.0; n];
    let (mut alphas, mut betas) = (Vec::new(), Vec::new());
    let mut beta_prev = 0.0;
    let mut last = 0.0;
    let mut stable_count = 0;
    for it in 0..max_iter {
        op(&q, &mut w);
        let alpha = dot(&q, &w);
        for k in 0..n {
            w[k] -= alpha * q[k] + beta_prev * q_prev[k];
        }
        let beta = dot(&w, &w).sqrt();
        alphas.push(alpha);
        let lmax = tridiagonal_max_eigenvalue(&alphas, &betas);
        if (lmax - last).abs() <= tol * lmax.abs() {
            stable_count += 1;
            if stable_count >= 3 {
                return (lmax, it + 1);
            }
        } else {
            stable_count = 0;
        }
        last = lmax;
        if beta <= 1e-14 * lmax.abs() {
            return (lmax, it + 1);
        }
        betas.push(beta);
        std::mem::swap(&mut q_prev, &mut q);
        for k in 0..n {
            q[k] = w[k] / beta;
        }
        beta_prev = beta;
    }
    (last, max_iter)
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Largest eigenvalue of the symmetric tridiagonal matrix (diagonal `a`, off-diagonal `b`)
/// by bisection on the Sturm sequence count.
fn tridiagonal_max_eigenvalue(a: &[f64], b: &[f64]) -> f64 {
    let m = a.len();
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for i in 0..m {
        let r = if i > 0 { b[i - 1].abs() } else { 0.0 } + if i + 1 < m { b[i].abs() } else { 0.0 };
        lo = lo.min(a[i] - r);
        hi = hi.max(a[i] + r);
    }
    // count of eigenvalues < x
    let count = |x: f64| {
        let mut c = 0;
        let mut q = 1.0;
        for i in 0..m {
            let bb = if i > 0 { b[i - 1] * b[i - 1] } else { 0.0 };
            q = a[i] - x - if i > 0 { bb / q } else { 0.0 };
            // an exact zero pivot stands for the limit from above (not counted, the next
            // pivot towards -infinity): the least positive normal does that, and keeps
            // `bb / q` a number (0 / 0 where b vanishes)
            if q == 0.0 {
                q = f64::MIN_POSITIVE;
            }
            if q < 0.0 {
                c += 1;
            }
        }
        c
    };
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if count(mid) >= m {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi
}

/// Both estimates of the critical time step.
pub fn analyse(p: &Problem, d: &Discretisation) -> StabilityReport {
    let est = element_estimates(p);
    let (limiting_element, element_estimate) = est.iter().enumerate().fold(
        (0, f64::INFINITY),
        |acc, (e, &v)| if v < acc.1 { (e, v) } else { acc },
    );
    let (lmax, iterations) = largest_eigenvalue(d, 300, 1e-10);
    let omega_max = lmax.max(0.0).sqrt();
    StabilityReport {
        critical_time_step: critical_of(lmax),
        omega_max,
        element_estimate,
        limiting_element,
        iterations,
        tissue_critical_time_step: (!d.saliva.elements.is_empty())
            .then(|| tissue_critical_time_step(d)),
    }
}

/// `2 / sqrt(lambda_max)` (infinite for no stiffness).
fn critical_of(lmax: f64) -> f64 {
    let omega_max = lmax.max(0.0).sqrt();
    if omega_max > 0.0 {
        2.0 / omega_max
    } else {
        f64::INFINITY
    }
}

/// The critical step of `d` with the saliva elements' stiffness (moduli and hourglass
/// stiffness) removed and every mass kept: what the slow nodes of a subcycled run need
/// (they touch tissue elements only; by eigenvalue interlacing their own limit is no smaller).
pub fn tissue_critical_time_step(d: &Discretisation) -> f64 {
    let mut t = d.clone();
    for &e in &d.saliva.elements {
        let e = e as usize;
        (t.mu[e], t.bulk[e], t.hg_k[e]) = (0.0, 0.0, 0.0);
    }
    critical_of(largest_eigenvalue(&t, 300, 1e-10).0)
}

/// Refuses a time step above the critical one (unless `force`).
pub fn check_time_step(
    p: &Problem,
    report: &StabilityReport,
    force: bool,
) -> crate::error::Result<()> {
    let k = p.numerics.subcycles;
    let fast = p.time.dt / k as f64;
    if fast > report.critical_time_step && !force {
        return Err(crate::error::Error::UnstableTimeStep {
            dt: fast,
            critical: report.critical_time_step,
            element: report.limiting_element,
            element_estimate: report.element_estimate,
        });
    }
    if let (true, Some(tissue)) = (k > 1, report.tissue_critical_time_step) {
        if p.time.dt > tissue && !force {
            return Err(crate::error::Error::UnstableLargeStep {
                dt: p.time.dt,
                critical: tissue,
                subcycles: k,
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dense_max(a: &[f64], b: &[f64]) -> f64 {
        let m = a.len();
        let t = nalgebra::DMatrix::<f64>::from_fn(m, m, |i, j| {
            if i == j {
                a[i]
            } else if i + 1 == j {
                b[i]
            } else if j + 1 == i {
                b[j]
            } else {
                0.0
            }
        });
        t.symmetric_eigenvalues()
            .iter()
            .cloned()
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// The bisection's answer is the dense solver's largest eigenvalue, for random symmetric
    /// tridiagonal matrices of every size up to 12 (off-diagonals of both signs, some zero),
    /// the 1-D Laplacian (`2 + 2 cos(pi / (m + 1))`) and a zero pivot (`[[0, 1], [1, 0]]`, whose
    /// Sturm sequence meets an exact zero at the bisection's first midpoint).
    #[test]
    fn tridiagonal_max_eigenvalue_is_the_dense_solvers_largest() {
        let mut rng = crate::mesh::generate::SplitMix64(11);
        for m in 1..=12 {
            for case in 0..20 {
                let a: Vec<f64> = (0..m).map(|_| 10.0 * rng.symmetric()).collect();
                let b: Vec<f64> = (0..m - 1)
                    .map(|i| {
                        if (i + case) % 7 == 3 {
                            0.0
                        } else {
                            3.0 * rng.symmetric()
                        }
                    })
                    .collect();
                let (got, want) = (tridiagonal_max_eigenvalue(&a, &b), dense_max(&a, &b));
                let scale = a.iter().chain(&b).fold(1.0f64, |s, x| s.max(x.abs()));
                assert!(
                    (got - want).abs() <= 1e-13 * scale,
                    "m {m}: {got} vs {want}"
                );
            }
        }
        for m in [1usize, 2, 5, 40] {
            let a = vec![2.0; m];
            let b = vec![-1.0; m - 1];
            let want = 2.0 + 2.0 * (std::f64::consts::PI / (m as f64 + 1.0)).cos();
            let got = tridiagonal_max_eigenvalue(&a, &b);
            assert!((got - want).abs() <= 1e-14 * want, "m {m}: {got} vs {want}");
        }
        assert_eq!(tridiagonal_max_eigenvalue(&[0.0, 0.0], &[1.0]), 1.0);
        assert_eq!(tridiagonal_max_eigenvalue(&[5.0], &[]), 5.0);
    }
}
