//! Stage 2 of a TLED step: gather the element forces at each node in a fixed order and
//! advance the displacement by central differences (paper eq. 3 with lumped mass `M`
//! and mass-proportional damping `C = alpha M`).
//!
//! The textbook recursion is `u_{n+1} = A (R_n - F_n) + B u_n + C u_{n-1}` with
//! `A = dt^2 / (m (1 + alpha dt/2))`, `B = 2 / (1 + alpha dt/2)`,
//! `C = -(1 - alpha dt/2) / (1 + alpha dt/2)`. Because `B + C = 1` exactly in real
//! arithmetic, it is evaluated here in increment form,
//!
//! $$ u_{n+1} = u_n + A (R_n - F_n) + c_1 (u_n - u_{n-1}), \quad c_1 = \frac{1 - \alpha\,dt/2}{1 + \alpha\,dt/2}, $$
//!
//! which keeps a body at rest exactly at rest in `f32` (the rounded `B + C - 1` of the
//! textbook form acts as a spurious spring; NiftySim's float32 build has that form and
//! drifts by up to 1e-3 over long runs).
//!
//! Verified by `verification/time_integration.rs` (second-order convergence, energy
//! conservation without damping, stability limit).

use crate::mesh::NodeGather;
use crate::real::Real;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Nodes per parallel work item.
pub const NODE_CHUNK: usize = 512;

/// Central-difference coefficients, derived once from `dt`, `alpha` and the masses.
#[derive(Clone, Debug)]
pub struct CentralDifference<T> {
    /// `A_n = dt^2 / (m_n (1 + alpha dt / 2))` per node (s^2/kg).
    pub a: Vec<T>,
    /// `c_1 = (1 - alpha dt/2) / (1 + alpha dt/2)`.
    pub c1: T,
}

impl<T: Real> CentralDifference<T> {
    pub fn new(dt: f64, damping: f64, mass: &[f64]) -> Self {
        let h = 0.5 * damping * dt;
        CentralDifference {
            a: mass
                .iter()
                .map(|&m| T::from_f64(dt * dt / (m * (1.0 + h))))
                .collect(),
            c1: T::from_f64((1.0 - h) / (1.0 + h)),
        }
    }
}

/// Sum of the element force blocks at node `n`, in the gather list's fixed order.
#[inline(always)]
pub fn gather_node<T: Real>(gather: &NodeGather, elem_f: &[[[T; 3]; 8]], n: usize) -> [T; 3] {
    gather_slots(gather.of(n), elem_f.as_flattened())
}

/// Sum of `corners[s]` over the slots `s` (`corners` = the element blocks flattened, slot
/// `8 e + a`), starting from zero, in the order given.
#[inline(always)]
fn gather_slots<T: Real>(slots: &[u32], corners: &[[T; 3]]) -> [T; 3] {
    let mut f = [T::ZERO; 3];
    let mut add = |s: u32| {
        let c = &corners[s as usize];
        f[0] += c[0];
        f[1] += c[1];
        f[2] += c[2];
    };
    // unrolled by 4 (same order of terms)
    let mut quads = slots.chunks_exact(4);
    for q in quads.by_ref() {
        add(q[0]);
        add(q[1]);
        add(q[2]);
        add(q[3]);
    }
    for &s in quads.remainder() {
        add(s);
    }
    f
}

/// Eq. (3) in increment form for one node: `u_n + A (R - F) + c_1 (u_n - u_{n-1})`.
/// (Written out per component: `[0, 1, 2].map(..)` was left as a call per node by some
/// builds, whichever way the compiler split the crate, and the stepping took 35 % longer.)
#[inline(always)]
fn advance<T: Real>(un: [T; 3], up: [T; 3], a: T, c1: T, r: [T; 3], f: [T; 3]) -> [T; 3] {
    [
        un[0] + a * (r[0] - f[0]) + c1 * (un[0] - up[0]),
        un[1] + a * (r[1] - f[1]) + c1 * (un[1] - up[1]),
        un[2] + a * (r[2] - f[2]) + c1 * (un[2] - up[2]),
    ]
}

/// Stage `node_update`: `u_next` from `u`, `u_prev`, the element forces and the external
/// forces `r_ext` (`None` = no external load). Returns the smallest node index with a
/// non-finite result, if any.
pub fn node_update<T: Real>(
    gather: &NodeGather,
    cd: &CentralDifference<T>,
    elem_f: &[[[T; 3]; 8]],
    r_ext: Option<&[[T; 3]]>,
    u: &[[T; 3]],
    u_prev: &[[T; 3]],
    u_next: &mut [[T; 3]],
) -> Option<usize> {
    let bad = AtomicUsize::new(usize::MAX);
    let c1 = cd.c1;
    let n = u_next.len();
    assert!(u.len() == n && u_prev.len() == n && cd.a.len() == n);
    assert!(gather.offsets.len() == n + 1 && r_ext.is_none_or(|r| r.len() == n));
    let corners = elem_f.as_flattened();
    u_next
        .par_chunks_mut(NODE_CHUNK)
        .enumerate()
        .for_each(|(c, chunk)| {
            let base = c * NODE_CHUNK;
            let end = base + chunk.len();
            let (u, u_prev, a) = (&u[base..end], &u_prev[base..end], &cd.a[base..end]);
            let offsets = &gather.offsets[base..=end];
            let mut first_bad = usize::MAX;
            for i in 0..chunk.len() {
                let slots = &gather.slots[offsets[i] as usize..offsets[i + 1] as usize];
                let f = gather_slots(slots, corners);
                let r = match r_ext {
                    Some(r) => r[base + i],
                    None => [T::ZERO; 3],
                };
                let v = advance(u[i], u_prev[i], a[i], c1, r, f);
                chunk[i] = v;
                if !(v[0].is_finite() && v[1].is_finite() && v[2].is_finite())
                    && first_bad == usize::MAX
                {
                    first_bad = base + i;
                }
            }
            if first_bad != usize::MAX {
                bad.fetch_min(first_bad, Ordering::Relaxed);
            }
        });
    let b = bad.into_inner();
    (b != usize::MAX).then_some(b)
}

/// [`node_update`] for the listed nodes only (subcycling: one partition of the nodes).
/// `a` and `gather` are indexed by node (`gather`'s slots point into `elem_f`); `out[i]`
/// receives node `nodes[i]`'s new displacement, with the same operations as
/// [`node_update`]. Returns the smallest listed node with a non-finite result.
#[allow(clippy::too_many_arguments)]
pub fn node_update_listed<T: Real>(
    nodes: &[u32],
    gather: &NodeGather,
    cd: &CentralDifference<T>,
    elem_f: &[[[T; 3]; 8]],
    r_ext: Option<&[[T; 3]]>,
    u: &[[T; 3]],
    u_prev: &[[T; 3]],
    out: &mut [[T; 3]],
) -> Option<usize> {
    assert_eq!(nodes.len(), out.len());
    let bad = AtomicUsize::new(usize::MAX);
    let c1 = cd.c1;
    let corners = elem_f.as_flattened();
    out.par_chunks_mut(NODE_CHUNK)
        .zip(nodes.par_chunks(NODE_CHUNK))
        .for_each(|(chunk, ids)| {
            let mut first_bad = usize::MAX;
            for (v, &n) in chunk.iter_mut().zip(ids) {
                let n = n as usize;
                let f = gather_slots(gather.of(n), corners);
                let r = r_ext.map_or([T::ZERO; 3], |r| r[n]);
                *v = advance(u[n], u_prev[n], cd.a[n], c1, r, f);
                if !(v[0].is_finite() && v[1].is_finite() && v[2].is_finite()) {
                    first_bad = first_bad.min(n);
                }
            }
            if first_bad != usize::MAX {
                bad.fetch_min(first_bad, Ordering::Relaxed);
            }
        });
    let b = bad.into_inner();
    (b != usize::MAX).then_some(b)
}

/// Internal nodal forces `F_int` (reactions at constrained nodes included) from element blocks.
pub fn gather_all<T: Real>(
    gather: &NodeGather,
    elem_f: &[[[T; 3]; 8]],
    num_nodes: usize,
) -> Vec<[T; 3]> {
    (0..num_nodes)
        .into_par_iter()
        .map(|n| gather_node(gather, elem_f, n))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::SplitMix64;

    /// A random model of `nodes` nodes (more than one `NODE_CHUNK`) and the node update's
    /// inputs, all random.
    struct Case {
        elements: Vec<[u32; 8]>,
        elem_f: Vec<[[f64; 3]; 8]>,
        r: Vec<[f64; 3]>,
        u: Vec<[f64; 3]>,
        u_prev: Vec<[f64; 3]>,
        cd: CentralDifference<f64>,
    }

    impl Case {
        /// `node_update` on this case, with or without its external forces.
        fn update(&self, gather: &NodeGather, loads: bool) -> (Option<usize>, Vec<[f64; 3]>) {
            let mut out = vec![[0.0; 3]; self.u.len()];
            let r = loads.then_some(self.r.as_slice());
            let bad = node_update(
                gather,
                &self.cd,
                &self.elem_f,
                r,
                &self.u,
                &self.u_prev,
                &mut out,
            );
            (bad, out)
        }
    }

    fn case(nodes: usize) -> Case {
        let mut rng = SplitMix64(2026);
        let elements: Vec<[u32; 8]> = (0..nodes / 2)
            .map(|_| [0; 8].map(|_| (rng.next_u64() % nodes as u64) as u32))
            .collect();
        let mut v3 = |s: f64| [0; 3].map(|_| s * rng.symmetric());
        let elem_f = (0..elements.len())
            .map(|_| [0; 8].map(|_| v3(1.0)))
            .collect();
        let r = (0..nodes).map(|_| v3(0.5)).collect();
        let u = (0..nodes).map(|_| v3(1e-3)).collect();
        let u_prev = (0..nodes).map(|_| v3(1e-3)).collect();
        let mass: Vec<f64> = (0..nodes).map(|i| 1e-3 * (1.0 + (i % 7) as f64)).collect();
        Case {
            elements,
            elem_f,
            r,
            u,
            u_prev,
            cd: CentralDifference::new(1e-4, 50.0, &mass),
        }
    }

    #[test]
    fn every_node_of_every_chunk_follows_eq3() {
        // 2 full chunks and a partial one; the reference sums each node's corners by scanning
        // the elements in order (not through the gather lists) and applies eq. (3)'s
        // increment form with the same operations, so the bits must agree
        let n = 2 * NODE_CHUNK + 37;
        let c = case(n);
        let gather = NodeGather::new(n, &c.elements);
        let (none, out) = c.update(&gather, true);
        assert_eq!(none, None);
        let mut f = vec![[0.0f64; 3]; n];
        for (e, conn) in c.elements.iter().enumerate() {
            for (a, &node) in conn.iter().enumerate() {
                for k in 0..3 {
                    f[node as usize][k] += c.elem_f[e][a][k];
                }
            }
        }
        for i in 0..n {
            for k in 0..3 {
                let want = c.u[i][k]
                    + c.cd.a[i] * (c.r[i][k] - f[i][k])
                    + c.cd.c1 * (c.u[i][k] - c.u_prev[i][k]);
                assert_eq!(
                    out[i][k].to_bits(),
                    want.to_bits(),
                    "node {i}, component {k}"
                );
            }
        }
        // without external forces: R = 0
        let (_, out) = c.update(&gather, false);
        let i = NODE_CHUNK + 3;
        let want = c.u[i][1] + c.cd.a[i] * (0.0 - f[i][1]) + c.cd.c1 * (c.u[i][1] - c.u_prev[i][1]);
        assert_eq!(out[i][1].to_bits(), want.to_bits());
    }

    #[test]
    fn the_smallest_node_with_a_non_finite_component_is_reported() {
        let n = 2 * NODE_CHUNK + 37;
        let mut c = case(n);
        let gather = NodeGather::new(n, &c.elements);
        let run = |c: &Case| c.update(&gather, true).0;
        // one component of one node, in the second chunk: that node
        c.r[NODE_CHUNK + 5][2] = f64::INFINITY;
        assert_eq!(run(&c), Some(NODE_CHUNK + 5));
        // two more in the same chunk and one in the third, each in one component: the smallest
        c.r[NODE_CHUNK + 9][0] = f64::NAN;
        c.r[NODE_CHUNK + 2][1] = f64::NEG_INFINITY;
        c.r[2 * NODE_CHUNK + 1][0] = f64::NAN;
        assert_eq!(run(&c), Some(NODE_CHUNK + 2));
        // and one in the first chunk beats them all
        c.u_prev[7][1] = f64::NAN;
        assert_eq!(run(&c), Some(7));
    }
}
