//! Stage 1 of a TLED step: the internal nodal forces of every element.
//!
//! Paper eq. (4), `f^(e) = 8 det(J) dh S F^T`: with the displacement gradient
//! `H = sum_a u_a (x) D_a` (eq. 8, `F = I + H`), the second Piola-Kirchhoff stress
//! `S(H)` of the neo-Hookean material, and the force weight `W` of the gradient variant,
//!
//! $$ f_a = W\, F S D_a + k \sum_{\alpha=1}^{4} \gamma_{a\alpha} \sum_b \gamma_{b\alpha} u_b $$
//!
//! where the second term is the Flanagan-Belytschko hourglass control (linear in the
//! total displacement, zero for every linear field). With `W = 8 det J(0)` and `D_a` the
//! centre gradients this is the paper's eq. (4) exactly.
//!
//! | symbol | code | unit |
//! |---|---|---|
//! | `D_a = dN_a/dX` | `d` | 1/m |
//! | `W` | `w` | m^3 |
//! | `gamma` | `gamma` | - |
//! | `k` | `k` | N/m |
//! | `f_a` | return value | N |
//!
//! Verified by `verification/element.rs` (forces are the gradient of the energy; rigid
//! rotations give no force; hourglass forces vanish for linear fields) and
//! `verification/niftysim.rs` (NiftySim's `Urand` element-force tests).

use crate::material::neo_hookean::pk2_stress;
use crate::real::Real;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Forces of one element (8x3, N) and its volume ratio `J = det F`.
#[allow(non_snake_case, clippy::too_many_arguments)]
#[inline(always)]
pub fn element_force<T: Real>(
    ue: &[[T; 3]; 8],
    d: &[[T; 3]; 8],
    w: T,
    gamma: &[[T; 4]; 8],
    k: T,
    mu: T,
    bulk: T,
) -> ([[T; 3]; 8], T) {
    // H_ij = sum_a u_a,i D_a,j
    let mut H = [[T::ZERO; 3]; 3];
    for a in 0..8 {
        for i in 0..3 {
            for j in 0..3 {
                H[i][j] += ue[a][i] * d[a][j];
            }
        }
    }
    let (S, J) = pk2_stress(&H, mu, bulk);
    // P = F S = S + H S, scaled by the weight
    let mut P = [[T::ZERO; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            P[i][j] = w * (S[i][j] + H[i][0] * S[0][j] + H[i][1] * S[1][j] + H[i][2] * S[2][j]);
        }
    }
    // hourglass: h_alpha = sum_b gamma_b,alpha u_b
    let mut hg = [[T::ZERO; 3]; 4];
    for b in 0..8 {
        for alpha in 0..4 {
            for i in 0..3 {
                hg[alpha][i] += gamma[b][alpha] * ue[b][i];
            }
        }
    }
    let mut f = [[T::ZERO; 3]; 8];
    for a in 0..8 {
        for i in 0..3 {
            let elastic = P[i][0] * d[a][0] + P[i][1] * d[a][1] + P[i][2] * d[a][2];
            let hourglass = gamma[a][0] * hg[0][i]
                + gamma[a][1] * hg[1][i]
                + gamma[a][2] * hg[2][i]
                + gamma[a][3] * hg[3][i];
            f[a][i] = elastic + k * hourglass;
        }
    }
    (f, J)
}

/// Per-element constants in the stepping precision (structure of arrays).
#[derive(Clone, Debug)]
pub struct ElementArrays<T> {
    pub conn: Vec<[u32; 8]>,
    pub dhdx: Vec<[[T; 3]; 8]>,
    pub weight: Vec<T>,
    pub gamma: Vec<[[T; 4]; 8]>,
    pub hg_k: Vec<T>,
    pub mu: Vec<T>,
    pub bulk: Vec<T>,
}

impl<T: Real> ElementArrays<T> {
    pub fn from_discretisation(d: &crate::tled::precompute::Discretisation) -> Self {
        let c3 = |g: &[[f64; 3]; 8]| g.map(|r| r.map(T::from_f64));
        let c4 = |g: &[[f64; 4]; 8]| g.map(|r| r.map(T::from_f64));
        let cv = |v: &[f64]| v.iter().map(|&x| T::from_f64(x)).collect::<Vec<T>>();
        ElementArrays {
            conn: d.conn.clone(),
            dhdx: d.dhdx.iter().map(c3).collect(),
            weight: cv(&d.weight),
            gamma: d.gamma.iter().map(c4).collect(),
            hg_k: cv(&d.hg_k),
            mu: cv(&d.mu),
            bulk: cv(&d.bulk),
        }
    }

    pub fn len(&self) -> usize {
        self.conn.len()
    }
    pub fn is_empty(&self) -> bool {
        self.conn.is_empty()
    }
}

/// Elements per parallel work item.
pub const ELEMENT_CHUNK: usize = 256;

/// Stage `element_forces`: writes the 8x3 force block of every element into `out`.
/// Returns the smallest index of an element whose `det F` is not positive (or not
/// finite), if any: the caller stops the run there.
pub fn element_forces<T: Real>(
    el: &ElementArrays<T>,
    u: &[[T; 3]],
    out: &mut [[[T; 3]; 8]],
) -> Option<usize> {
    let bad = AtomicUsize::new(usize::MAX);
    out.par_chunks_mut(ELEMENT_CHUNK)
        .enumerate()
        .for_each(|(c, chunk)| {
            let base = c * ELEMENT_CHUNK;
            for (i, fe) in chunk.iter_mut().enumerate() {
                let e = base + i;
                let conn = &el.conn[e];
                let ue: [[T; 3]; 8] = std::array::from_fn(|a| u[conn[a] as usize]);
                let (f, j) = element_force(
                    &ue,
                    &el.dhdx[e],
                    el.weight[e],
                    &el.gamma[e],
                    el.hg_k[e],
                    el.mu[e],
                    el.bulk[e],
                );
                if !(j > T::ZERO && j.is_finite()) {
                    bad.fetch_min(e, Ordering::Relaxed);
                }
                *fe = f;
            }
        });
    let b = bad.into_inner();
    (b != usize::MAX).then_some(b)
}
