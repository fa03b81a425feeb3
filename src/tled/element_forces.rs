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
//!
//! The stage runs the lane-parallel copy of [`element_force`] in `tled::simd` on blocks of
//! `T::LANES` elements; it returns the same bits as [`element_force`] for every element
//! ([`element_forces_scalar`] is the reference it is tested against).

use crate::material::neo_hookean::pk2_stress;
use crate::real::Real;
use crate::tled::simd::{SimdReal, BLOCK_CONSTANTS};
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

/// Per-element constants in the stepping precision: per element (structure of arrays, for
/// the scalar reference and the saliva stage), and block-wise for the lane kernel (built
/// once from the same values; read-only afterwards).
#[derive(Clone, Debug)]
pub struct ElementArrays<T> {
    pub conn: Vec<[u32; 8]>,
    pub dhdx: Vec<[[T; 3]; 8]>,
    pub weight: Vec<T>,
    pub gamma: Vec<[[T; 4]; 8]>,
    pub hg_k: Vec<T>,
    pub mu: Vec<T>,
    pub bulk: Vec<T>,
    /// Node indices per block of `T::LANES` elements, `[block][a][lane]`.
    block_conn: Vec<u32>,
    /// Constants per block, `[block][row][lane]` (rows: see `tled::simd`).
    block_data: Vec<T>,
}

impl<T: Real> ElementArrays<T> {
    pub fn from_discretisation(d: &crate::tled::precompute::Discretisation) -> Self {
        let c3 = |g: &[[f64; 3]; 8]| g.map(|r| r.map(T::from_f64));
        let c4 = |g: &[[f64; 4]; 8]| g.map(|r| r.map(T::from_f64));
        let cv = |v: &[f64]| v.iter().map(|&x| T::from_f64(x)).collect::<Vec<T>>();
        let mut el = ElementArrays {
            conn: d.conn.clone(),
            dhdx: d.dhdx.iter().map(c3).collect(),
            weight: cv(&d.weight),
            gamma: d.gamma.iter().map(c4).collect(),
            hg_k: cv(&d.hg_k),
            mu: cv(&d.mu),
            bulk: cv(&d.bulk),
            block_conn: Vec::new(),
            block_data: Vec::new(),
        };
        el.build_blocks();
        el
    }

    /// Fills the block arrays from the per-element ones. Padding lanes of the last block:
    /// node 0 and zero constants (zero force, `J = 1`).
    fn build_blocks(&mut self) {
        let l = T::LANES;
        let nb = self.len().div_ceil(l);
        self.block_conn = vec![0; nb * 8 * l];
        self.block_data = vec![T::ZERO; nb * BLOCK_CONSTANTS * l];
        for e in 0..self.len() {
            let (b, lane) = (e / l, e % l);
            for a in 0..8 {
                self.block_conn[(b * 8 + a) * l + lane] = self.conn[e][a];
            }
            let row = |r: usize| (b * BLOCK_CONSTANTS + r) * l + lane;
            for a in 0..8 {
                for j in 0..3 {
                    self.block_data[row(3 * a + j)] = self.dhdx[e][a][j];
                }
                for alpha in 0..4 {
                    self.block_data[row(24 + 4 * a + alpha)] = self.gamma[e][a][alpha];
                }
            }
            self.block_data[row(56)] = self.weight[e];
            self.block_data[row(57)] = self.hg_k[e];
            self.block_data[row(58)] = self.mu[e];
            self.block_data[row(59)] = self.bulk[e];
        }
    }

    /// The elements `ids` (in that order) as arrays of their own: element `i` of the result
    /// is element `ids[i]` of `self`, with the same constants (node indices unchanged).
    pub fn subset(&self, ids: &[u32]) -> Self {
        let pick = |e: &u32| *e as usize;
        let mut el = ElementArrays {
            conn: ids.iter().map(|e| self.conn[pick(e)]).collect(),
            dhdx: ids.iter().map(|e| self.dhdx[pick(e)]).collect(),
            weight: ids.iter().map(|e| self.weight[pick(e)]).collect(),
            gamma: ids.iter().map(|e| self.gamma[pick(e)]).collect(),
            hg_k: ids.iter().map(|e| self.hg_k[pick(e)]).collect(),
            mu: ids.iter().map(|e| self.mu[pick(e)]).collect(),
            bulk: ids.iter().map(|e| self.bulk[pick(e)]).collect(),
            block_conn: Vec::new(),
            block_data: Vec::new(),
        };
        el.build_blocks();
        el
    }

    pub fn len(&self) -> usize {
        self.conn.len()
    }
    pub fn is_empty(&self) -> bool {
        self.conn.is_empty()
    }
}

/// Elements per parallel work item (a multiple of every `T::LANES`).
pub const ELEMENT_CHUNK: usize = 256;

/// Stage `element_forces`: writes the 8x3 force block of every element into `out`.
/// Returns the smallest index of an element whose `det F` is not positive (or not
/// finite), if any: the caller stops the run there.
///
/// Lane-parallel (`tled::simd`), bit-identical to [`element_forces_scalar`].
pub fn element_forces<T: SimdReal>(
    el: &ElementArrays<T>,
    u: &[[T; 3]],
    out: &mut [[[T; 3]; 8]],
) -> Option<usize> {
    element_forces_with(el, u, out, T::element_blocks)
}

/// [`element_forces`] with the portable lanes (no AVX2) whatever the processor (for tests:
/// both copies must give the same bits).
pub fn element_forces_portable<T: SimdReal>(
    el: &ElementArrays<T>,
    u: &[[T; 3]],
    out: &mut [[[T; 3]; 8]],
) -> Option<usize> {
    element_forces_with(el, u, out, T::element_blocks_portable)
}

type BlockFn<T> = fn(&[u32], &[T], &[[T; 3]], usize, &mut [[[T; 3]; 8]]) -> usize;

fn element_forces_with<T: Real>(
    el: &ElementArrays<T>,
    u: &[[T; 3]],
    out: &mut [[[T; 3]; 8]],
    run: BlockFn<T>,
) -> Option<usize> {
    assert_eq!(out.len(), el.len(), "one force block per element");
    assert_eq!(ELEMENT_CHUNK % T::LANES, 0);
    let bad = AtomicUsize::new(usize::MAX);
    out.par_chunks_mut(ELEMENT_CHUNK)
        .enumerate()
        .for_each(|(c, chunk)| {
            let first_block = c * ELEMENT_CHUNK / T::LANES;
            let b = run(&el.block_conn, &el.block_data, u, first_block, chunk);
            if b != usize::MAX {
                bad.fetch_min(b, Ordering::Relaxed);
            }
        });
    let b = bad.into_inner();
    (b != usize::MAX).then_some(b)
}

/// The reference: [`element_force`] element by element. Same contract as [`element_forces`].
pub fn element_forces_scalar<T: Real>(
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_flattened_element_with_det_f_exactly_zero_is_reported() {
        // the unit cube at its centre: D_a = xi_a / 4; u = (0, 0, -Z) flattens it onto z = 0,
        // H = diag(0, 0, -1) and J = det(I + H) = 0 exactly: degenerate, not a valid state
        use crate::element::hex8::NATURAL;
        let (mut el, _) = random_case::<f64>(1, 8, 3);
        el.conn = vec![[0, 1, 2, 3, 4, 5, 6, 7]];
        el.dhdx = vec![std::array::from_fn(|a| NATURAL[a].map(|x| x / 4.0))];
        assert!(!el.is_empty() && el.len() == 1);
        let u: Vec<[f64; 3]> = (0..8)
            .map(|a| [0.0, 0.0, -(1.0 + NATURAL[a][2]) / 2.0])
            .collect();
        el.build_blocks();
        let mut out = vec![[[0.0; 3]; 8]];
        assert_eq!(element_forces_scalar(&el, &u, &mut out), Some(0));
        // the lane kernels too (their quick all-lanes test and the per-lane recheck)
        assert_eq!(element_forces(&el, &u, &mut out), Some(0));
        assert_eq!(element_forces_portable(&el, &u, &mut out), Some(0));
        // half flattened: J = 1/2, valid
        let half: Vec<[f64; 3]> = u.iter().map(|v| [0.0, 0.0, v[2] / 2.0]).collect();
        assert_eq!(element_forces_scalar(&el, &half, &mut out), None);
        assert_eq!(element_forces(&el, &half, &mut out), None);
        assert_eq!(element_forces_portable(&el, &half, &mut out), None);
        // eight copies: a whole block of lanes with J = 0 (no padding lane with J = 1)
        let mut full = el.clone();
        full.conn = vec![el.conn[0]; 8];
        full.dhdx = vec![el.dhdx[0]; 8];
        full.weight = vec![el.weight[0]; 8];
        full.gamma = vec![el.gamma[0]; 8];
        full.hg_k = vec![el.hg_k[0]; 8];
        full.mu = vec![el.mu[0]; 8];
        full.bulk = vec![el.bulk[0]; 8];
        full.build_blocks();
        let mut out8 = vec![[[0.0; 3]; 8]; 8];
        assert_eq!(element_forces(&full, &u, &mut out8), Some(0));
        assert_eq!(element_forces_portable(&full, &u, &mut out8), Some(0));
        // and a whole block turned inside out (J = -1/2 in every lane)
        let inverted: Vec<[f64; 3]> = u.iter().map(|v| [0.0, 0.0, 1.5 * v[2]]).collect();
        assert_eq!(element_forces(&full, &inverted, &mut out8), Some(0));
        assert_eq!(
            element_forces_portable(&full, &inverted, &mut out8),
            Some(0)
        );
        let none = ElementArrays::<f64> {
            conn: vec![],
            ..el.clone()
        };
        assert!(none.is_empty());
    }

    fn lcg(s: &mut u64) -> f64 {
        *s = s
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (*s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }

    /// `ne` elements on `nn` nodes with random constants of realistic size (gradients
    /// ~ 1/h for h = 2 mm) and displacements giving strains of a few percent.
    fn random_case<T: Real>(ne: usize, nn: usize, seed: u64) -> (ElementArrays<T>, Vec<[T; 3]>) {
        let mut s = seed;
        let mut r = |scale: f64| T::from_f64(scale * lcg(&mut s));
        let conn: Vec<[u32; 8]> = (0..ne)
            .map(|e| std::array::from_fn(|a| ((e * 7 + a * 13 + (a * a * e) % 11) % nn) as u32))
            .collect();
        let mut el = ElementArrays {
            conn,
            dhdx: (0..ne)
                .map(|_| std::array::from_fn(|_| std::array::from_fn(|_| r(500.0))))
                .collect(),
            weight: (0..ne).map(|_| r(1e-8) + T::from_f64(1e-8)).collect(),
            gamma: (0..ne)
                .map(|_| std::array::from_fn(|_| std::array::from_fn(|_| r(0.5))))
                .collect(),
            hg_k: (0..ne).map(|_| r(10.0) + T::from_f64(10.0)).collect(),
            mu: (0..ne).map(|_| r(500.0) + T::from_f64(1000.0)).collect(),
            bulk: (0..ne).map(|_| r(5000.0) + T::from_f64(10000.0)).collect(),
            block_conn: Vec::new(),
            block_data: Vec::new(),
        };
        el.build_blocks();
        let u = (0..nn).map(|_| std::array::from_fn(|_| r(2e-5))).collect();
        (el, u)
    }

    fn bits<T: Real>(f: &[[[T; 3]; 8]]) -> Vec<u64> {
        f.iter()
            .flatten()
            .flatten()
            .map(|x| x.to_f64().to_bits())
            .collect()
    }

    fn lanes_equal_scalar<T: SimdReal>() {
        for (k, ne) in [1, 3, 4, 5, 8, 13, 255, 256, 300, 517]
            .into_iter()
            .enumerate()
        {
            let (el, u) = random_case::<T>(ne, ne + 9, 17 + k as u64);
            let mut reference = vec![[[T::ZERO; 3]; 8]; ne];
            let mut lanes = reference.clone();
            let mut portable = reference.clone();
            assert_eq!(element_forces_scalar(&el, &u, &mut reference), None);
            assert_eq!(element_forces(&el, &u, &mut lanes), None);
            assert_eq!(element_forces_portable(&el, &u, &mut portable), None);
            assert!(reference.iter().flatten().flatten().any(|&x| x != T::ZERO));
            assert_eq!(bits(&lanes), bits(&reference), "{} ne = {ne}", T::NAME);
            assert_eq!(bits(&portable), bits(&reference), "{} ne = {ne}", T::NAME);
        }
    }

    #[test]
    fn lane_kernel_equals_scalar_reference_bit_for_bit_f64() {
        lanes_equal_scalar::<f64>();
    }

    #[test]
    fn lane_kernel_equals_scalar_reference_bit_for_bit_f32() {
        lanes_equal_scalar::<f32>();
    }

    /// `u` copied into the last bytes of readable memory, the page after it mapped
    /// unreadable: a read of even one value past the end of `u` stops the test process with
    /// SIGSEGV instead of reading a neighbour's bytes unnoticed.
    #[cfg(target_os = "linux")]
    struct GuardedNodes {
        map: *mut u8,
        len: usize,
        start: *mut u8,
    }

    #[cfg(target_os = "linux")]
    impl GuardedNodes {
        fn new<T: Real>(u: &[[T; 3]]) -> Self {
            let bytes = std::mem::size_of_val(u);
            // SAFETY: plain POSIX calls on a fresh anonymous mapping of our own; `start` is
            // `bytes` before the guard page, aligned for T (page and node sizes are multiples
            // of T's size and alignment).
            unsafe {
                let page = libc::sysconf(libc::_SC_PAGESIZE) as usize;
                let data = bytes.div_ceil(page) * page;
                let len = data + page;
                let map = libc::mmap(
                    std::ptr::null_mut(),
                    len,
                    libc::PROT_READ | libc::PROT_WRITE,
                    libc::MAP_PRIVATE | libc::MAP_ANONYMOUS,
                    -1,
                    0,
                );
                assert!(map != libc::MAP_FAILED, "mmap failed");
                let map = map as *mut u8;
                assert_eq!(
                    libc::mprotect(map.add(data) as *mut libc::c_void, page, libc::PROT_NONE),
                    0
                );
                let start = map.add(data - bytes);
                std::ptr::copy_nonoverlapping(u.as_ptr() as *const u8, start, bytes);
                GuardedNodes { map, len, start }
            }
        }
        fn nodes<T: Real>(&self, n: usize) -> &[[T; 3]] {
            // SAFETY: `new` copied exactly n nodes of T to `start`.
            unsafe { std::slice::from_raw_parts(self.start as *const [T; 3], n) }
        }
    }

    #[cfg(target_os = "linux")]
    impl Drop for GuardedNodes {
        fn drop(&mut self) {
            // SAFETY: the mapping `new` made, no slice of it outlives `self`.
            unsafe { libc::munmap(self.map as *mut libc::c_void, self.len) };
        }
    }

    /// The vector gathers load four values from the start of a node (its x, y, z and the next
    /// node's x): a block that holds the last node must take the per-lane path. With the
    /// displacements ending at an unreadable page and the last node in the first and the last
    /// block, every kernel reads inside `u` and gives the scalar reference's bits.
    #[cfg(target_os = "linux")]
    fn lanes_read_only_inside_u<T: SimdReal>() {
        for (k, ne) in [1, 3, 4, 5, 8, 13, 300].into_iter().enumerate() {
            let nn = ne + 9;
            let (mut el, u) = random_case::<T>(ne, nn, 40 + k as u64);
            el.conn[0][0] = (nn - 1) as u32;
            el.conn[ne - 1][7] = (nn - 1) as u32;
            el.build_blocks();
            let guarded = GuardedNodes::new(&u);
            let u = guarded.nodes::<T>(nn);
            let mut reference = vec![[[T::ZERO; 3]; 8]; ne];
            let (mut lanes, mut portable) = (reference.clone(), reference.clone());
            assert_eq!(element_forces_scalar(&el, u, &mut reference), None);
            assert_eq!(element_forces(&el, u, &mut lanes), None);
            assert_eq!(element_forces_portable(&el, u, &mut portable), None);
            assert_eq!(bits(&lanes), bits(&reference), "{} ne = {ne}", T::NAME);
            assert_eq!(bits(&portable), bits(&reference), "{} ne = {ne}", T::NAME);
        }
    }

    #[test]
    #[cfg(target_os = "linux")]
    fn lane_kernels_read_only_inside_the_displacements() {
        lanes_read_only_inside_u::<f64>();
        lanes_read_only_inside_u::<f32>();
    }

    fn reports_first_bad_element<T: SimdReal>() {
        let ne = 300;
        let (el, mut u) = random_case::<T>(ne, ne + 9, 5);
        let mut f = vec![[[T::ZERO; 3]; 8]; ne];
        // large displacements of one node invert some of its elements
        let n = el.conn[201][3] as usize;
        let first = (0..ne).find(|&e| el.conn[e].contains(&(n as u32))).unwrap();
        let mut g = f.clone();
        let mut inverted = 0;
        for k in 0..20 {
            u[n] = [0, 1, 2].map(|i| T::from_f64(0.01 * ((k * 3 + i) as f64 - 30.0)));
            let s = element_forces_scalar(&el, &u, &mut f);
            inverted += usize::from(s.is_some());
            assert!(s.is_none_or(|e| e >= first), "{s:?}");
            assert_eq!(element_forces(&el, &u, &mut g), s);
            assert_eq!(element_forces_portable(&el, &u, &mut g), s);
        }
        assert!(inverted > 0);
        u[n] = [T::from_f64(f64::NAN); 3];
        let s = element_forces_scalar(&el, &u, &mut f);
        assert_eq!(s, Some(first));
        assert_eq!(element_forces(&el, &u, &mut g), Some(first));
    }

    #[test]
    fn lane_kernel_reports_the_first_bad_element() {
        reports_first_bad_element::<f64>();
        reports_first_bad_element::<f32>();
    }
}
