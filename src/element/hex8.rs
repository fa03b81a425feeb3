//! The 8-node trilinear hexahedron: shape functions, exact volume, the two
//! gradient variants used by TLED, and the Flanagan-Belytschko hourglass vectors.
//!
//! Node order (same as `VTK_HEXAHEDRON`): local node `a` sits at natural coordinates
//! `0(-,-,-) 1(+,-,-) 2(+,+,-) 3(-,+,-) 4(-,-,+) 5(+,-,+) 6(+,+,+) 7(-,+,+)`, and
//! `N_a = (1 + xi_a xi)(1 + eta_a eta)(1 + zeta_a zeta) / 8`.
//!
//! Everything here depends only on the reference coordinates `X`, so it runs once,
//! in `f64`, before time stepping ("total Lagrangian": paper section 3.2).

use crate::linalg::{adjugate, cross, det, norm, sub};

/// Natural coordinates of the 8 corners.
pub const NATURAL: [[f64; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
];

/// The four hourglass base vectors `h_1..h_4` (rows), in the node order above:
/// `xi eta`, `eta zeta`, `xi zeta`, `xi eta zeta` evaluated at the corners.
pub const HOURGLASS_BASE: [[f64; 8]; 4] = [
    [1.0, -1.0, 1.0, -1.0, 1.0, -1.0, 1.0, -1.0],
    [1.0, 1.0, -1.0, -1.0, -1.0, -1.0, 1.0, 1.0],
    [1.0, -1.0, -1.0, 1.0, -1.0, 1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0, 1.0, 1.0, -1.0, 1.0, -1.0],
];

/// The 2-point Gauss abscissa `1/sqrt(3)` (weights 1).
pub const GAUSS: f64 = 0.577_350_269_189_625_8;

/// Which shape-function gradient and force weight the one-point element uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum GradientVariant {
    /// Flanagan-Belytschko uniform-strain hexahedron: `D_a = (1/V) int dN_a/dX dV`, weight `V`.
    /// Passes the patch test on distorted hexahedra. The default.
    #[default]
    MeanGradient,
    /// Paper eq. (4) literally (and NiftySim's CPU path): `D_a = dN_a/dX` at the centre,
    /// weight `8 det J(0)`. Fails the patch test on non-parallelepiped elements.
    Centroid,
}

/// `dN_a/dxi` at natural point `p`, one row per node.
pub fn shape_derivatives_natural(p: [f64; 3]) -> [[f64; 3]; 8] {
    let mut d = [[0.0; 3]; 8];
    for (a, n) in NATURAL.iter().enumerate() {
        let fx = 1.0 + n[0] * p[0];
        let fy = 1.0 + n[1] * p[1];
        let fz = 1.0 + n[2] * p[2];
        d[a] = [
            n[0] * fy * fz / 8.0,
            n[1] * fx * fz / 8.0,
            n[2] * fx * fy / 8.0,
        ];
    }
    d
}

/// Jacobian `J_ij = dX_i / dxi_j = sum_a X_a,i dN_a/dxi_j` at natural point `p`.
pub fn jacobian(x: &[[f64; 3]; 8], p: [f64; 3]) -> [[f64; 3]; 3] {
    let dn = shape_derivatives_natural(p);
    let mut j = [[0.0; 3]; 3];
    for a in 0..8 {
        for r in 0..3 {
            for c in 0..3 {
                j[r][c] += x[a][r] * dn[a][c];
            }
        }
    }
    j
}

/// `dN_a/dX` at natural point `p` and `det J` there: `dN/dX = J^-T dN/dxi`.
pub fn shape_gradients_at(x: &[[f64; 3]; 8], p: [f64; 3]) -> ([[f64; 3]; 8], f64) {
    let j = jacobian(x, p);
    let dj = det(&j);
    let adj = adjugate(&j); // adj = det * J^-1
    let dn = shape_derivatives_natural(p);
    let mut g = [[0.0; 3]; 8];
    for a in 0..8 {
        for i in 0..3 {
            // (J^-T dn)_i = sum_k (J^-1)_{k i} dn_k
            g[a][i] = (adj[0][i] * dn[a][0] + adj[1][i] * dn[a][1] + adj[2][i] * dn[a][2]) / dj;
        }
    }
    (g, dj)
}

/// The 8 points of the 2x2x2 Gauss rule (all weights 1).
fn gauss_points() -> impl Iterator<Item = [f64; 3]> {
    NATURAL
        .iter()
        .map(|n| [n[0] * GAUSS, n[1] * GAUSS, n[2] * GAUSS])
}

/// Exact volume of the trilinear hexahedron.
///
/// `det J` is at most quadratic in each natural coordinate, so the 2x2x2 Gauss rule
/// integrates it exactly.
pub fn volume(x: &[[f64; 3]; 8]) -> f64 {
    gauss_points().map(|p| det(&jacobian(x, p))).sum()
}

/// Smallest `det J` over the 8 corners and the centre, with where it occurs
/// (`0..8` a corner, `8` the centre). A valid element has all of them positive.
pub fn min_corner_jacobian(x: &[[f64; 3]; 8]) -> (f64, usize) {
    let mut best = (f64::INFINITY, 0);
    for (k, p) in NATURAL
        .iter()
        .chain(std::iter::once(&[0.0, 0.0, 0.0]))
        .enumerate()
    {
        let d = det(&jacobian(x, *p));
        if d < best.0 || d.is_nan() {
            best = (d, k);
        }
    }
    best
}

/// Mean shape-function gradients `D_a = (1/V) int_e dN_a/dX dV` and the exact volume `V`.
///
/// `dN_a/dX det J = adj(J)^T dN_a/dxi` is at most cubic in each natural coordinate,
/// so the 2x2x2 Gauss rule is exact here too.
pub fn mean_gradients(x: &[[f64; 3]; 8]) -> ([[f64; 3]; 8], f64) {
    let mut g = [[0.0; 3]; 8];
    let mut v = 0.0;
    for p in gauss_points() {
        let j = jacobian(x, p);
        let adj = adjugate(&j);
        let dn = shape_derivatives_natural(p);
        v += det(&j);
        for a in 0..8 {
            for i in 0..3 {
                g[a][i] += adj[0][i] * dn[a][0] + adj[1][i] * dn[a][1] + adj[2][i] * dn[a][2];
            }
        }
    }
    for row in g.iter_mut() {
        for c in row.iter_mut() {
            *c /= v;
        }
    }
    (g, v)
}

/// Shape-function gradients and force weight of the chosen variant.
pub fn gradients(x: &[[f64; 3]; 8], variant: GradientVariant) -> ([[f64; 3]; 8], f64) {
    match variant {
        GradientVariant::MeanGradient => mean_gradients(x),
        GradientVariant::Centroid => {
            let (g, dj) = shape_gradients_at(x, [0.0; 3]);
            (g, 8.0 * dj)
        }
    }
}

/// Hourglass shape vectors `gamma = Gamma - D (X^T Gamma)` (8x4), Flanagan & Belytschko
/// (1981) in the precomputed total-Lagrangian form of Joldes, Wittek & Miller (2008).
/// Orthogonal to every linear field: `sum_a gamma_a,alpha X_a = 0` whenever
/// `sum_a X_a (x) D_a = I`.
pub fn hourglass_vectors(x: &[[f64; 3]; 8], d: &[[f64; 3]; 8]) -> [[f64; 4]; 8] {
    // A = X^T Gamma (3x4)
    let mut a_mat = [[0.0; 4]; 3];
    for (alpha, h) in HOURGLASS_BASE.iter().enumerate() {
        for b in 0..8 {
            for i in 0..3 {
                a_mat[i][alpha] += x[b][i] * h[b];
            }
        }
    }
    let mut gamma = [[0.0; 4]; 8];
    for a in 0..8 {
        for alpha in 0..4 {
            gamma[a][alpha] = HOURGLASS_BASE[alpha][a]
                - (d[a][0] * a_mat[0][alpha]
                    + d[a][1] * a_mat[1][alpha]
                    + d[a][2] * a_mat[2][alpha]);
        }
    }
    gamma
}

/// Hourglass stiffness `k = kappa V (lambda + 2 mu) (sum_a |D_a|^2) / 8`, with
/// `lambda = K - 2 mu / 3` (NiftySim's choice).
pub fn hourglass_stiffness(kappa: f64, volume: f64, mu: f64, bulk: f64, d: &[[f64; 3]; 8]) -> f64 {
    let lambda = bulk - 2.0 * mu / 3.0;
    let sum_sq: f64 = d
        .iter()
        .map(|g| g[0] * g[0] + g[1] * g[1] + g[2] * g[2])
        .sum();
    kappa * volume * (lambda + 2.0 * mu) * sum_sq / 8.0
}

/// The six faces of a `VTK_HEXAHEDRON` (nodes 0-3 the bottom, counter-clockwise seen
/// from above; 4-7 the top), each listed counter-clockwise seen from outside, so that the
/// right-hand normal points out of a positively oriented element: bottom, top, then the
/// sides `y-`, `x+`, `y+`, `x-` of the reference cube.
pub const FACES: [[usize; 4]; 6] = [
    [0, 3, 2, 1],
    [4, 5, 6, 7],
    [0, 1, 5, 4],
    [1, 2, 6, 5],
    [2, 3, 7, 6],
    [3, 0, 4, 7],
];

/// A stable-time-step length scale of the element: its volume over its largest face
/// area (the usual estimate for hexahedra, e.g. Hallquist's LS-DYNA theory manual).
pub fn characteristic_length(x: &[[f64; 3]; 8]) -> f64 {
    let mut amax: f64 = 0.0;
    for f in FACES {
        let p = |k: usize| x[f[k]];
        let d1 = sub(&p(2), &p(0));
        let d2 = sub(&p(3), &p(1));
        let c = cross(&d1, &d2);
        amax = amax.max(0.5 * norm(&c));
    }
    volume(x) / amax
}
