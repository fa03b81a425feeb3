//! The lane-parallel element kernel: [`element_force`](super::element_forces::element_force)
//! for a block of `L` elements at once (`L = T::LANES`: 4 in `f64`, 8 in `f32`, one 256-bit
//! register), every operation applied to all lanes.
//!
//! Each lane runs exactly the scalar reference's sequence of IEEE-754 operations (same
//! order, no fused multiply-add, the cube root of [`Real::cbrt`]), so every lane's forces
//! and `J` are bit for bit those of `element_force` for that element, on every machine and
//! whichever copy the dispatch picks; the tests below and `verification/precision.rs`
//! check this equality. The neo-Hookean stress of `material::neo_hookean::pk2_stress` and
//! the `linalg` helpers it uses are mirrored here operation for operation.
//!
//! The kernel is generic over a lane type [`Lanes`]: [`V`] (`[T; L]`, portable, compiled for
//! the baseline instruction set) and, on x86-64, `F64x4` / `F32x8` (AVX2 registers through
//! `core::arch` intrinsics, used only after `is_x86_feature_detected!("avx2")`, so one
//! binary runs everywhere). Every helper is `#[inline(always)]`: a call that is not inlined
//! into the AVX2 function would run without AVX2 (and slowly).
//!
//! Block layout (`ElementArrays`): per block of `L` elements, the node indices `[a][l]`
//! (`8 L` u32) and the constants as `BLOCK_CONSTANTS` rows of `L` lanes: `D_a,j` (24 rows),
//! `gamma_a,alpha` (32 rows), `W`, `k`, `mu`, `K`. Lanes past the last element are padding
//! (node 0, all constants zero: zero force, `J = 1`) and never written.

use crate::real::Real;
use std::ops::{Add, Div, Mul, Sub};

/// Rows of `L` constants per block: `D` (8x3), `gamma` (8x4), `W`, `k`, `mu`, `K`.
pub const BLOCK_CONSTANTS: usize = 24 + 32 + 4;
/// First row of `gamma`, and the rows of `W`, `k`, `mu`, `K`.
pub const ROW_GAMMA: usize = 24;
pub const ROW_W: usize = 56;
pub const ROW_K: usize = 57;
pub const ROW_MU: usize = 58;
pub const ROW_BULK: usize = 59;

/// `L` lanes of `T` with lane-wise IEEE arithmetic.
pub trait Lanes<T: Real, const L: usize>:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
    fn splat(x: T) -> Self;
    fn from_array(a: [T; L]) -> Self;
    fn to_array(self) -> [T; L];
    /// Row `r` of a block: `blk[r L .. r L + L]`.
    #[inline(always)]
    fn row(blk: &[T], r: usize) -> Self {
        let mut a = [T::ZERO; L];
        a.copy_from_slice(&blk[r * L..r * L + L]);
        Self::from_array(a)
    }
    /// `x`, `y`, `z` of the nodes `idx[0..L]`.
    #[inline(always)]
    fn gather(u: &[[T; 3]], idx: &[u32]) -> [Self; 3] {
        let (mut x, mut y, mut z) = ([T::ZERO; L], [T::ZERO; L], [T::ZERO; L]);
        for l in 0..L {
            let p = u[idx[l] as usize];
            x[l] = p[0];
            y[l] = p[1];
            z[l] = p[2];
        }
        [
            Self::from_array(x),
            Self::from_array(y),
            Self::from_array(z),
        ]
    }
    /// The displacements of a block's corners: `[a][i]` from the node indices `c[a L + l]`.
    #[inline(always)]
    fn gather_block(u: &[[T; 3]], c: &[u32]) -> [[Self; 3]; 8] {
        let mut ue = [[Self::splat(T::ZERO); 3]; 8];
        for (a, ua) in ue.iter_mut().enumerate() {
            *ua = Self::gather(u, &c[a * L..a * L + L]);
        }
        ue
    }
    /// Writes the force `f[a][i]` of lane `l` to `out[l][a][i]` for `l < out.len() <= L`.
    #[inline(always)]
    fn store_block(f: &[[Self; 3]; 8], out: &mut [[[T; 3]; 8]]) {
        for (a, fa) in f.iter().enumerate() {
            let (x, y, z) = (fa[0].to_array(), fa[1].to_array(), fa[2].to_array());
            for (l, o) in out.iter_mut().enumerate() {
                o[a] = [x[l], y[l], z[l]];
            }
        }
    }
    /// [`Real::cbrt`] of every lane.
    #[inline(always)]
    fn cbrt(self) -> Self {
        Self::from_array(T::cbrt_lanes(self.to_array()))
    }
}

pub use crate::lanes::V;

impl<T: Real, const L: usize> Lanes<T, L> for V<T, L> {
    #[inline(always)]
    fn splat(x: T) -> Self {
        V([x; L])
    }
    #[inline(always)]
    fn from_array(a: [T; L]) -> Self {
        V(a)
    }
    #[inline(always)]
    fn to_array(self) -> [T; L] {
        self.0
    }
}

type M3<W> = [[W; 3]; 3];

/// `linalg::det`.
#[inline(always)]
fn det<W: Copy + Add<Output = W> + Sub<Output = W> + Mul<Output = W>>(m: &M3<W>) -> W {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// `material::neo_hookean::pk2_stress`: `S` and `J` from `H`, operation for operation
/// (with `two_green_strain`, `linalg::det_identity_plus_minus_one`, `linalg::inverse`).
#[allow(non_snake_case)]
#[inline(always)]
fn pk2_stress<T: Real, const L: usize, W: Lanes<T, L>>(h: &M3<W>, mu: W, bulk: W) -> (M3<W>, W) {
    let one = W::splat(T::ONE);
    let zero = W::splat(T::ZERO);
    // two_green_strain
    let mut E2 = [[zero; 3]; 3];
    for i in 0..3 {
        for j in i..3 {
            let v = h[i][j] + h[j][i] + h[0][i] * h[0][j] + h[1][i] * h[1][j] + h[2][i] * h[2][j];
            E2[i][j] = v;
            E2[j][i] = v;
        }
    }
    let mut C = E2;
    for i in 0..3 {
        C[i][i] = C[i][i] + one;
    }
    // det_identity_plus_minus_one
    let tr_h = h[0][0] + h[1][1] + h[2][2];
    let minors = h[0][0] * h[1][1] - h[0][1] * h[1][0] + h[1][1] * h[2][2] - h[1][2] * h[2][1]
        + h[0][0] * h[2][2]
        - h[0][2] * h[2][0];
    let Jm1 = tr_h + minors + det(h);
    let J = one + Jm1;
    // inverse: adjugate times 1/det
    let m = &C;
    let adj = [
        [
            m[1][1] * m[2][2] - m[1][2] * m[2][1],
            m[0][2] * m[2][1] - m[0][1] * m[2][2],
            m[0][1] * m[1][2] - m[0][2] * m[1][1],
        ],
        [
            m[1][2] * m[2][0] - m[1][0] * m[2][2],
            m[0][0] * m[2][2] - m[0][2] * m[2][0],
            m[0][2] * m[1][0] - m[0][0] * m[1][2],
        ],
        [
            m[1][0] * m[2][1] - m[1][1] * m[2][0],
            m[0][1] * m[2][0] - m[0][0] * m[2][1],
            m[0][0] * m[1][1] - m[0][1] * m[1][0],
        ],
    ];
    let inv_det = one / det(m);
    let mut Cinv = adj;
    for row in Cinv.iter_mut() {
        for v in row.iter_mut() {
            *v = *v * inv_det;
        }
    }
    let third = W::splat(T::from_f64(1.0 / 3.0));
    let tr = E2[0][0] + E2[1][1] + E2[2][2];
    let mut dev = E2;
    for i in 0..3 {
        dev[i][i] = dev[i][i] - tr * third;
    }
    let jm23 = one / (J * J).cbrt();
    let iso = mu * jm23;
    let vol = bulk * J * Jm1;
    let mut S = [[zero; 3]; 3];
    for i in 0..3 {
        for j in i..3 {
            let cd = Cinv[i][0] * dev[0][j] + Cinv[i][1] * dev[1][j] + Cinv[i][2] * dev[2][j];
            let v = iso * cd + vol * Cinv[i][j];
            S[i][j] = v;
            S[j][i] = v;
        }
    }
    (S, J)
}

/// First half of [`block_force`]: `H`, `S` and `J` of every lane.
#[allow(non_snake_case)]
#[inline(always)]
fn block_stress<T: Real, const L: usize, W: Lanes<T, L>>(
    ue: &[[W; 3]; 8],
    blk: &[T],
) -> (M3<W>, M3<W>, W) {
    let blk = &blk[..BLOCK_CONSTANTS * L];
    let zero = W::splat(T::ZERO);
    let mut H = [[zero; 3]; 3];
    for (a, ua) in ue.iter().enumerate() {
        for i in 0..3 {
            for j in 0..3 {
                H[i][j] = H[i][j] + ua[i] * W::row(blk, 3 * a + j);
            }
        }
    }
    let (S, J) = pk2_stress::<T, L, W>(&H, W::row(blk, ROW_MU), W::row(blk, ROW_BULK));
    (H, S, J)
}

/// Second half of [`block_force`]: the forces `f[a][i]` from `H` and `S`.
#[allow(non_snake_case)]
#[inline(always)]
fn block_corner_forces<T: Real, const L: usize, W: Lanes<T, L>>(
    ue: &[[W; 3]; 8],
    blk: &[T],
    H: &M3<W>,
    S: &M3<W>,
) -> [[W; 3]; 8] {
    let blk = &blk[..BLOCK_CONSTANTS * L];
    let zero = W::splat(T::ZERO);
    let d = |a: usize, j: usize| W::row(blk, 3 * a + j);
    let gamma = |a: usize, alpha: usize| W::row(blk, ROW_GAMMA + 4 * a + alpha);
    let w = W::row(blk, ROW_W);
    let mut P = [[zero; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            P[i][j] = w * (S[i][j] + H[i][0] * S[0][j] + H[i][1] * S[1][j] + H[i][2] * S[2][j]);
        }
    }
    let mut hg = [[zero; 3]; 4];
    for (b, ub) in ue.iter().enumerate() {
        for (alpha, hga) in hg.iter_mut().enumerate() {
            let g = gamma(b, alpha);
            for i in 0..3 {
                hga[i] = hga[i] + g * ub[i];
            }
        }
    }
    let k = W::row(blk, ROW_K);
    let mut f = [[zero; 3]; 8];
    for (a, fa) in f.iter_mut().enumerate() {
        let (d0, d1, d2) = (d(a, 0), d(a, 1), d(a, 2));
        let (g0, g1, g2, g3) = (gamma(a, 0), gamma(a, 1), gamma(a, 2), gamma(a, 3));
        for i in 0..3 {
            let elastic = P[i][0] * d0 + P[i][1] * d1 + P[i][2] * d2;
            let hourglass = g0 * hg[0][i] + g1 * hg[1][i] + g2 * hg[2][i] + g3 * hg[3][i];
            fa[i] = elastic + k * hourglass;
        }
    }
    f
}

/// Forces `f[a][i]` and `J` of one block: `element_force` lane by lane. `ue[a][i]` are
/// the gathered displacements, `blk` the block's `BLOCK_CONSTANTS * L` constants.
#[allow(non_snake_case)]
#[inline(always)]
pub fn block_force<T: Real, const L: usize, W: Lanes<T, L>>(
    ue: &[[W; 3]; 8],
    blk: &[T],
) -> ([[W; 3]; 8], W) {
    let (H, S, J) = block_stress::<T, L, W>(ue, blk);
    (block_corner_forces::<T, L, W>(ue, blk, &H, &S), J)
}

/// Runs [`block_force`] over consecutive blocks: `out` holds the force blocks of the
/// elements `first_block * L ..`, `conn` and `data` the block arrays of all elements.
/// Returns the smallest element index in `out`'s range with `J <= 0` or non-finite, or
/// `usize::MAX`.
#[inline(always)]
fn blocks<T: Real, const L: usize, W: Lanes<T, L>>(
    conn: &[u32],
    data: &[T],
    u: &[[T; 3]],
    first_block: usize,
    out: &mut [[[T; 3]; 8]],
) -> usize {
    let mut bad = usize::MAX;
    for (k, fo) in out.chunks_mut(L).enumerate() {
        let b = first_block + k;
        let ue = W::gather_block(u, &conn[b * 8 * L..(b + 1) * 8 * L]);
        let blk = &data[b * BLOCK_CONSTANTS * L..(b + 1) * BLOCK_CONSTANTS * L];
        let (f, j) = block_force::<T, L, W>(&ue, blk);
        W::store_block(&f, fo);
        let j = j.to_array();
        let mut ok = true;
        for jl in j {
            ok &= jl > T::ZERO && jl.is_finite();
        }
        if !ok && bad == usize::MAX {
            for (l, &jl) in j.iter().enumerate().take(fo.len()) {
                if !(jl > T::ZERO && jl.is_finite()) {
                    bad = b * L + l;
                    break;
                }
            }
        }
    }
    bad
}

/// The stage's kernel per precision: the lane type and the run-time dispatch.
pub trait LaneKernel: Sized {
    /// Forces of the elements `first_block * LANES ..` into `out` (`out.len()` elements,
    /// a multiple of the lane count unless it ends at the last element) with the widest
    /// instruction set the processor has. Returns the smallest index of an element with
    /// `J <= 0` or non-finite, or `usize::MAX`. The result does not depend on the choice.
    fn element_blocks(
        conn: &[u32],
        data: &[Self],
        u: &[[Self; 3]],
        first_block: usize,
        out: &mut [[[Self; 3]; 8]],
    ) -> usize;
    /// [`LaneKernel::element_blocks`] with the portable lanes, whatever the processor.
    fn element_blocks_portable(
        conn: &[u32],
        data: &[Self],
        u: &[[Self; 3]],
        first_block: usize,
        out: &mut [[[Self; 3]; 8]],
    ) -> usize;
}

/// A [`Real`] the lane-parallel element kernel is implemented for (`f32`, `f64`): what the
/// stepping code asks of its precision.
pub trait SimdReal: Real + LaneKernel {}
impl<T: Real + LaneKernel> SimdReal for T {}

macro_rules! lane_kernel {
    ($t:ty, $lanes:literal, $avx:ident) => {
        impl LaneKernel for $t {
            fn element_blocks(
                conn: &[u32],
                data: &[$t],
                u: &[[$t; 3]],
                first_block: usize,
                out: &mut [[[$t; 3]; 8]],
            ) -> usize {
                #[cfg(target_arch = "x86_64")]
                if std::arch::is_x86_feature_detected!("avx2") {
                    // SAFETY: the processor has AVX2 (checked just above).
                    return unsafe { avx::$avx(conn, data, u, first_block, out) };
                }
                Self::element_blocks_portable(conn, data, u, first_block, out)
            }
            fn element_blocks_portable(
                conn: &[u32],
                data: &[$t],
                u: &[[$t; 3]],
                first_block: usize,
                out: &mut [[[$t; 3]; 8]],
            ) -> usize {
                blocks::<$t, $lanes, V<$t, $lanes>>(conn, data, u, first_block, out)
            }
        }
    };
}
lane_kernel!(f64, 4, blocks_f64);
lane_kernel!(f32, 8, blocks_f32);

/// Which copy of the kernel [`LaneKernel::element_blocks`] runs here: `"avx2"` or
/// `"portable"`.
pub fn instruction_set() -> &'static str {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        return "avx2";
    }
    "portable"
}

#[cfg(target_arch = "x86_64")]
mod avx {
    //! AVX2 lanes. Every function here may only run on a processor with AVX2: the types
    //! are used only inside `#[target_feature(enable = "avx2")]` functions, which the
    //! dispatch calls after checking the processor.
    use super::{blocks, Lanes};
    use std::arch::x86_64::*;
    use std::ops::{Add, Div, Mul, Sub};

    #[derive(Clone, Copy)]
    pub struct F64x4(__m256d);
    #[derive(Clone, Copy)]
    pub struct F32x8(__m256);

    macro_rules! avx_op {
        ($ty:ident, $tr:ident, $f:ident, $intr:ident) => {
            impl $tr for $ty {
                type Output = Self;
                #[inline(always)]
                fn $f(self, o: Self) -> Self {
                    // SAFETY: AVX is available (module contract).
                    $ty(unsafe { $intr(self.0, o.0) })
                }
            }
        };
    }
    avx_op!(F64x4, Add, add, _mm256_add_pd);
    avx_op!(F64x4, Sub, sub, _mm256_sub_pd);
    avx_op!(F64x4, Mul, mul, _mm256_mul_pd);
    avx_op!(F64x4, Div, div, _mm256_div_pd);
    avx_op!(F32x8, Add, add, _mm256_add_ps);
    avx_op!(F32x8, Sub, sub, _mm256_sub_ps);
    avx_op!(F32x8, Mul, mul, _mm256_mul_ps);
    avx_op!(F32x8, Div, div, _mm256_div_ps);

    impl Lanes<f64, 4> for F64x4 {
        #[inline(always)]
        fn splat(x: f64) -> Self {
            // SAFETY: AVX is available (module contract).
            F64x4(unsafe { _mm256_set1_pd(x) })
        }
        #[inline(always)]
        fn from_array(a: [f64; 4]) -> Self {
            // SAFETY: AVX; reads the 4 values of `a`.
            F64x4(unsafe { _mm256_loadu_pd(a.as_ptr()) })
        }
        #[inline(always)]
        fn to_array(self) -> [f64; 4] {
            let mut a = [0.0; 4];
            // SAFETY: AVX; writes the 4 values of `a`.
            unsafe { _mm256_storeu_pd(a.as_mut_ptr(), self.0) };
            a
        }
        #[inline(always)]
        fn row(blk: &[f64], r: usize) -> Self {
            let s = &blk[4 * r..4 * r + 4];
            // SAFETY: AVX; `s` holds 4 values.
            F64x4(unsafe { _mm256_loadu_pd(s.as_ptr()) })
        }
        #[inline(always)]
        fn gather_block(u: &[[f64; 3]], c: &[u32]) -> [[Self; 3]; 8] {
            let c = &c[..32];
            if !all_below(c, u.len()) {
                let mut ue = [[Self::splat(0.0); 3]; 8];
                for (a, ua) in ue.iter_mut().enumerate() {
                    *ua = Self::gather(u, &c[4 * a..4 * a + 4]);
                }
                return ue;
            }
            let p = u.as_flattened().as_ptr();
            let mut ue = [[Self::splat(0.0); 3]; 8];
            for (a, ua) in ue.iter_mut().enumerate() {
                // SAFETY: AVX; every node index n satisfies n + 1 < u.len(), so the 4
                // values read from the start of u[n] (x, y, z and the next node's x) are
                // inside `u`.
                unsafe {
                    let r = |l: usize| p.add(3 * c[4 * a + l] as usize);
                    let xy = |l: usize, h: usize| {
                        _mm256_insertf128_pd::<1>(
                            _mm256_castpd128_pd256(_mm_loadu_pd(r(l))),
                            _mm_loadu_pd(r(h)),
                        )
                    };
                    let zw = |l: usize, h: usize| {
                        _mm256_insertf128_pd::<1>(
                            _mm256_castpd128_pd256(_mm_loadu_pd(r(l).add(2))),
                            _mm_loadu_pd(r(h).add(2)),
                        )
                    };
                    let (a02, a13) = (xy(0, 2), xy(1, 3)); // x0 y0 | x2 y2 ; x1 y1 | x3 y3
                    let (c02, c13) = (zw(0, 2), zw(1, 3)); // z0 w0 | z2 w2 ; z1 w1 | z3 w3
                    *ua = [
                        F64x4(_mm256_unpacklo_pd(a02, a13)),
                        F64x4(_mm256_unpackhi_pd(a02, a13)),
                        F64x4(_mm256_unpacklo_pd(c02, c13)),
                    ];
                }
            }
            ue
        }
        #[inline(always)]
        fn cbrt(self) -> Self {
            cbrt_f64x4(self)
        }
        #[inline(always)]
        fn store_block(f: &[[Self; 3]; 8], out: &mut [[[f64; 3]; 8]]) {
            if out.len() != 4 {
                for (a, fa) in f.iter().enumerate() {
                    let (x, y, z) = (fa[0].to_array(), fa[1].to_array(), fa[2].to_array());
                    for (l, o) in out.iter_mut().enumerate() {
                        o[a] = [x[l], y[l], z[l]];
                    }
                }
                return;
            }
            // lane l's 24 values f[a][i] (k = 3a + i) are out[l] flattened: 4x4 transposes
            // of the vectors k = 4t .. 4t + 3 give 4 values of every lane.
            let flat = out.as_flattened_mut().as_flattened_mut();
            let v = |k: usize| f[k / 3][k % 3].0;
            for t in 0..6 {
                // SAFETY: AVX; every store writes 4 values inside `flat` (96 values).
                unsafe {
                    let (v0, v1, v2, v3) = (v(4 * t), v(4 * t + 1), v(4 * t + 2), v(4 * t + 3));
                    let t0 = _mm256_unpacklo_pd(v0, v1); // v0_0 v1_0 | v0_2 v1_2
                    let t1 = _mm256_unpackhi_pd(v0, v1); // v0_1 v1_1 | v0_3 v1_3
                    let t2 = _mm256_unpacklo_pd(v2, v3);
                    let t3 = _mm256_unpackhi_pd(v2, v3);
                    let rows = [
                        _mm256_permute2f128_pd::<0x20>(t0, t2),
                        _mm256_permute2f128_pd::<0x20>(t1, t3),
                        _mm256_permute2f128_pd::<0x31>(t0, t2),
                        _mm256_permute2f128_pd::<0x31>(t1, t3),
                    ];
                    for (l, row) in rows.into_iter().enumerate() {
                        let o = &mut flat[24 * l + 4 * t..24 * l + 4 * t + 4];
                        _mm256_storeu_pd(o.as_mut_ptr(), row);
                    }
                }
            }
        }
    }

    /// [`Real::cbrt`](crate::real::Real::cbrt) of 4 lanes: the range reduction of
    /// `real::cbrt_reduce` on the bits in AVX2 integer registers (see
    /// [`cbrt_reduce_f64x4`]), the Newton steps (`real::cbrt_refine`, the same generic code
    /// as the scalar root) in AVX registers, and the rare zero, subnormal, infinite or NaN
    /// lanes by the scalar code.
    #[inline(always)]
    fn cbrt_f64x4(x: F64x4) -> F64x4 {
        use crate::real::{cbrt_is_normal, cbrt_refine, cbrt_special};
        let (a, w0, s, all_normal) = cbrt_reduce_f64x4(x);
        let y = cbrt_refine(a, w0, s, F64x4::splat);
        if all_normal {
            return y;
        }
        let (xa, mut ya) = (x.to_array(), y.to_array());
        for l in 0..4 {
            if !cbrt_is_normal(xa[l]) {
                ya[l] = cbrt_special(xa[l]);
            }
        }
        F64x4::from_array(ya)
    }

    /// `real::cbrt_reduce` of 4 lanes, with the same exact results: for a normal `x` with
    /// biased exponent `E` (1..=2046) and `e = E - 1023 = 3 q + r`,
    /// `q = floor(E / 3) - 341` (1023 = 3 * 341) and `r = E - 3 floor(E / 3)`, where
    /// `floor(E / 3) = (43691 E) >> 17` for every `E < 2^15` (checked exhaustively in the
    /// tests). `a`, `m` and `s` are assembled from the bits; `w0` is the same polynomial in
    /// `m`, evaluated in the same order, times `2^(-r/3)` picked by comparison. The fourth
    /// value says whether every lane is normal (else the caller mends those lanes).
    #[inline(always)]
    fn cbrt_reduce_f64x4(x: F64x4) -> (F64x4, F64x4, F64x4, bool) {
        use crate::real::{CBRT_G0, CBRT_G1, CBRT_G2, CBRT_INV_ROOT2};
        const MANTISSA: i64 = (1 << 52) - 1;
        // SAFETY: AVX2 (module contract); register operations only.
        unsafe {
            let bits = _mm256_castpd_si256(x.0);
            let mant = _mm256_and_si256(bits, _mm256_set1_epi64x(MANTISSA));
            let big_e = _mm256_and_si256(_mm256_srli_epi64::<52>(bits), _mm256_set1_epi64x(0x7ff));
            let special = _mm256_or_si256(
                _mm256_cmpeq_epi64(big_e, _mm256_setzero_si256()),
                _mm256_cmpeq_epi64(big_e, _mm256_set1_epi64x(0x7ff)),
            );
            let all_normal = _mm256_testz_si256(special, special) == 1;
            // floor(E / 3) and r = E - 3 floor(E / 3) (32-bit products in 64-bit lanes)
            let e3 = _mm256_srli_epi64::<17>(_mm256_mul_epu32(big_e, _mm256_set1_epi64x(43691)));
            let r = _mm256_sub_epi64(big_e, _mm256_mul_epu32(e3, _mm256_set1_epi64x(3)));
            let m = _mm256_castsi256_pd(_mm256_or_si256(mant, _mm256_set1_epi64x(1023 << 52)));
            let a = _mm256_castsi256_pd(_mm256_or_si256(
                mant,
                _mm256_slli_epi64::<52>(_mm256_add_epi64(r, _mm256_set1_epi64x(1023))),
            ));
            // 2^(q + 1023) with q + 1023 = floor(E / 3) + 682, and the sign of x
            let s = _mm256_castsi256_pd(_mm256_or_si256(
                _mm256_and_si256(bits, _mm256_set1_epi64x(i64::MIN)),
                _mm256_slli_epi64::<52>(_mm256_add_epi64(e3, _mm256_set1_epi64x(682))),
            ));
            let r1 = _mm256_castsi256_pd(_mm256_cmpeq_epi64(r, _mm256_set1_epi64x(1)));
            let r2 = _mm256_castsi256_pd(_mm256_cmpeq_epi64(r, _mm256_set1_epi64x(2)));
            let root2 = _mm256_blendv_pd(
                _mm256_blendv_pd(
                    _mm256_set1_pd(CBRT_INV_ROOT2[0]),
                    _mm256_set1_pd(CBRT_INV_ROOT2[1]),
                    r1,
                ),
                _mm256_set1_pd(CBRT_INV_ROOT2[2]),
                r2,
            );
            let (m, c) = (F64x4(m), F64x4::splat);
            let w0 = (c(CBRT_G0) + m * (c(CBRT_G1) + m * c(CBRT_G2))) * F64x4(root2);
            (F64x4(a), w0, F64x4(s), all_normal)
        }
    }

    impl Lanes<f32, 8> for F32x8 {
        #[inline(always)]
        fn splat(x: f32) -> Self {
            // SAFETY: AVX is available (module contract).
            F32x8(unsafe { _mm256_set1_ps(x) })
        }
        #[inline(always)]
        fn from_array(a: [f32; 8]) -> Self {
            // SAFETY: AVX; reads the 8 values of `a`.
            F32x8(unsafe { _mm256_loadu_ps(a.as_ptr()) })
        }
        #[inline(always)]
        fn to_array(self) -> [f32; 8] {
            let mut a = [0.0; 8];
            // SAFETY: AVX; writes the 8 values of `a`.
            unsafe { _mm256_storeu_ps(a.as_mut_ptr(), self.0) };
            a
        }
        #[inline(always)]
        fn row(blk: &[f32], r: usize) -> Self {
            let s = &blk[8 * r..8 * r + 8];
            // SAFETY: AVX; `s` holds 8 values.
            F32x8(unsafe { _mm256_loadu_ps(s.as_ptr()) })
        }
        #[inline(always)]
        fn gather_block(u: &[[f32; 3]], c: &[u32]) -> [[Self; 3]; 8] {
            let c = &c[..64];
            if !all_below(c, u.len()) {
                let mut ue = [[Self::splat(0.0); 3]; 8];
                for (a, ua) in ue.iter_mut().enumerate() {
                    *ua = Self::gather(u, &c[8 * a..8 * a + 8]);
                }
                return ue;
            }
            let p = u.as_flattened().as_ptr();
            let mut ue = [[Self::splat(0.0); 3]; 8];
            for (a, ua) in ue.iter_mut().enumerate() {
                // SAFETY: AVX; every node index n satisfies n + 1 < u.len(), so the 4
                // values read from the start of u[n] (x, y, z and the next node's x) are
                // inside `u`.
                unsafe {
                    let r = |l: usize| _mm_loadu_ps(p.add(3 * c[8 * a + l] as usize));
                    let pair = |l: usize| {
                        _mm256_insertf128_ps::<1>(_mm256_castps128_ps256(r(l)), r(l + 4))
                    };
                    let (a0, a1, a2, a3) = (pair(0), pair(1), pair(2), pair(3));
                    let t0 = _mm256_unpacklo_ps(a0, a1); // x0 x1 y0 y1 | x4 x5 y4 y5
                    let t1 = _mm256_unpackhi_ps(a0, a1); // z0 z1 w0 w1 | z4 z5 w4 w5
                    let t2 = _mm256_unpacklo_ps(a2, a3); // x2 x3 y2 y3 | x6 x7 y6 y7
                    let t3 = _mm256_unpackhi_ps(a2, a3); // z2 z3 w2 w3 | z6 z7 w6 w7
                    *ua = [
                        F32x8(_mm256_shuffle_ps::<0x44>(t0, t2)),
                        F32x8(_mm256_shuffle_ps::<0xEE>(t0, t2)),
                        F32x8(_mm256_shuffle_ps::<0x44>(t1, t3)),
                    ];
                }
            }
            ue
        }
        #[inline(always)]
        fn cbrt(self) -> Self {
            // the f64 root of each lane rounded to f32 (`Real::cbrt` for f32)
            // SAFETY: AVX; register operations only.
            unsafe {
                let lo = cbrt_f64x4(F64x4(_mm256_cvtps_pd(_mm256_castps256_ps128(self.0))));
                let hi = cbrt_f64x4(F64x4(_mm256_cvtps_pd(_mm256_extractf128_ps::<1>(self.0))));
                F32x8(_mm256_insertf128_ps::<1>(
                    _mm256_castps128_ps256(_mm256_cvtpd_ps(lo.0)),
                    _mm256_cvtpd_ps(hi.0),
                ))
            }
        }
        #[inline(always)]
        fn store_block(f: &[[Self; 3]; 8], out: &mut [[[f32; 3]; 8]]) {
            if out.len() != 8 {
                for (a, fa) in f.iter().enumerate() {
                    let (x, y, z) = (fa[0].to_array(), fa[1].to_array(), fa[2].to_array());
                    for (l, o) in out.iter_mut().enumerate() {
                        o[a] = [x[l], y[l], z[l]];
                    }
                }
                return;
            }
            // lane l's 24 values f[a][i] (k = 3a + i) are out[l] flattened: 8x8 transposes
            // of the vectors k = 8t .. 8t + 7 give 8 values of every lane.
            let flat = out.as_flattened_mut().as_flattened_mut();
            let v = |k: usize| f[k / 3][k % 3].0;
            for t in 0..3 {
                // SAFETY: AVX; every store writes 8 values inside `flat` (192 values).
                unsafe {
                    let k = 8 * t;
                    let t0 = _mm256_unpacklo_ps(v(k), v(k + 1));
                    let t1 = _mm256_unpackhi_ps(v(k), v(k + 1));
                    let t2 = _mm256_unpacklo_ps(v(k + 2), v(k + 3));
                    let t3 = _mm256_unpackhi_ps(v(k + 2), v(k + 3));
                    let t4 = _mm256_unpacklo_ps(v(k + 4), v(k + 5));
                    let t5 = _mm256_unpackhi_ps(v(k + 4), v(k + 5));
                    let t6 = _mm256_unpacklo_ps(v(k + 6), v(k + 7));
                    let t7 = _mm256_unpackhi_ps(v(k + 6), v(k + 7));
                    let s0 = _mm256_shuffle_ps::<0x44>(t0, t2);
                    let s1 = _mm256_shuffle_ps::<0xEE>(t0, t2);
                    let s2 = _mm256_shuffle_ps::<0x44>(t1, t3);
                    let s3 = _mm256_shuffle_ps::<0xEE>(t1, t3);
                    let s4 = _mm256_shuffle_ps::<0x44>(t4, t6);
                    let s5 = _mm256_shuffle_ps::<0xEE>(t4, t6);
                    let s6 = _mm256_shuffle_ps::<0x44>(t5, t7);
                    let s7 = _mm256_shuffle_ps::<0xEE>(t5, t7);
                    let rows = [
                        _mm256_permute2f128_ps::<0x20>(s0, s4),
                        _mm256_permute2f128_ps::<0x20>(s1, s5),
                        _mm256_permute2f128_ps::<0x20>(s2, s6),
                        _mm256_permute2f128_ps::<0x20>(s3, s7),
                        _mm256_permute2f128_ps::<0x31>(s0, s4),
                        _mm256_permute2f128_ps::<0x31>(s1, s5),
                        _mm256_permute2f128_ps::<0x31>(s2, s6),
                        _mm256_permute2f128_ps::<0x31>(s3, s7),
                    ];
                    for (l, row) in rows.into_iter().enumerate() {
                        let o = &mut flat[24 * l + k..24 * l + k + 8];
                        _mm256_storeu_ps(o.as_mut_ptr(), row);
                    }
                }
            }
        }
    }

    /// Whether every index `n` in `c` has `n + 1 < len` (4-value loads from `u[n]` stay in
    /// `u`).
    #[inline(always)]
    fn all_below(c: &[u32], len: usize) -> bool {
        let mut m = 0u32;
        for &n in c {
            m = m.max(n);
        }
        (m as usize) + 1 < len
    }

    /// The `f64` kernel with AVX2.
    ///
    /// # Safety
    /// The processor must support AVX2.
    #[target_feature(enable = "avx2")]
    pub unsafe fn blocks_f64(
        conn: &[u32],
        data: &[f64],
        u: &[[f64; 3]],
        first_block: usize,
        out: &mut [[[f64; 3]; 8]],
    ) -> usize {
        blocks::<f64, 4, F64x4>(conn, data, u, first_block, out)
    }

    /// The `f32` kernel with AVX2.
    ///
    /// # Safety
    /// The processor must support AVX2.
    #[target_feature(enable = "avx2")]
    pub unsafe fn blocks_f32(
        conn: &[u32],
        data: &[f32],
        u: &[[f32; 3]],
        first_block: usize,
        out: &mut [[[f32; 3]; 8]],
    ) -> usize {
        blocks::<f32, 8, F32x8>(conn, data, u, first_block, out)
    }

    #[cfg(test)]
    mod tests {
        use super::*;
        use crate::real::Real;

        #[target_feature(enable = "avx2")]
        unsafe fn cbrt4(x: [f64; 4]) -> [f64; 4] {
            F64x4::from_array(x).cbrt().to_array()
        }
        #[target_feature(enable = "avx2")]
        unsafe fn cbrt8(x: [f32; 8]) -> [f32; 8] {
            F32x8::from_array(x).cbrt().to_array()
        }

        #[test]
        fn all_below_holds_only_when_every_index_has_a_node_after_it() {
            // a 4-value load from u[n] needs n + 1 < len
            assert!(all_below(&[0, 3, 5], 7));
            assert!(!all_below(&[0, 6, 2], 7));
            assert!(!all_below(&[7], 7));
            assert!(!all_below(&[0], 1));
            assert!(all_below(&[0], 2));
        }

        #[test]
        fn division_by_three_of_every_exponent() {
            for e in 0u64..(1 << 15) {
                assert_eq!((e * 43691) >> 17, e / 3, "{e}");
            }
        }

        #[target_feature(enable = "avx2")]
        unsafe fn reduce4(x: [f64; 4]) -> ([f64; 4], [f64; 4], [f64; 4], bool) {
            let (a, w0, s, n) = cbrt_reduce_f64x4(F64x4::from_array(x));
            (a.to_array(), w0.to_array(), s.to_array(), n)
        }

        #[test]
        fn avx2_range_reduction_equals_scalar_for_every_exponent() {
            if !std::arch::is_x86_feature_detected!("avx2") {
                return;
            }
            // every biased exponent 1..=2046, both signs, several mantissas
            for big_e in 1u64..=2046 {
                let mant = [0u64, 1, (1 << 52) - 1, 0x5_5555_5555_5555 ^ big_e];
                let x: [f64; 4] = std::array::from_fn(|l| {
                    f64::from_bits(((l as u64 & 1) << 63) | (big_e << 52) | mant[l])
                });
                // SAFETY: AVX2 checked above.
                let (a, w0, s, all_normal) = unsafe { reduce4(x) };
                assert!(all_normal);
                for l in 0..4 {
                    let (ea, ew, es) = crate::real::cbrt_reduce(x[l]);
                    assert_eq!(
                        (a[l].to_bits(), w0[l].to_bits(), s[l].to_bits()),
                        (ea.to_bits(), ew.to_bits(), es.to_bits()),
                        "{:e}",
                        x[l]
                    );
                }
            }
            for special in [0.0, -0.0, 1e-310, f64::INFINITY, f64::NAN] {
                // SAFETY: AVX2 checked above.
                let (_, _, _, all_normal) = unsafe { reduce4([1.0, 2.0, special, 3.0]) };
                assert!(!all_normal, "{special:e}");
            }
        }

        #[test]
        fn avx2_cbrt_equals_scalar_cbrt_bit_for_bit() {
            if !std::arch::is_x86_feature_detected!("avx2") {
                return;
            }
            let mut s = 99u64;
            let mut next = || {
                s = s
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                s
            };
            let specials = [
                0.0,
                -0.0,
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::NAN,
                5e-324,
            ];
            for k in 0..100_000 {
                let mut x: [f64; 4] = [0.0; 4];
                let mut y: [f32; 8] = [0.0; 8];
                for (l, v) in x.iter_mut().enumerate() {
                    *v = match (k + l) % 3 {
                        0 => f64::from_bits(next()),
                        1 => 0.5 + (next() >> 11) as f64 / (1u64 << 53) as f64,
                        _ => specials[(next() % 6) as usize] * if k % 2 == 0 { 1.0 } else { -1.0 },
                    };
                }
                for v in y.iter_mut() {
                    *v = f32::from_bits((next() >> 32) as u32);
                }
                // SAFETY: AVX2 checked above.
                let (r4, r8) = unsafe { (cbrt4(x), cbrt8(y)) };
                for l in 0..4 {
                    let e = <f64 as Real>::cbrt(x[l]);
                    assert!(r4[l].to_bits() == e.to_bits() || (e.is_nan() && r4[l].is_nan()));
                }
                for l in 0..8 {
                    let e = <f32 as Real>::cbrt(y[l]);
                    assert!(r8[l].to_bits() == e.to_bits() || (e.is_nan() && r8[l].is_nan()));
                }
            }
        }
    }
}

#[cfg(test)]
mod layout_tests {
    use super::*;

    /// A block's constants are dense: `D` (8 x 3 rows), then `gamma` (8 x 4), then `W`, `k`,
    /// `mu`, `K`, and nothing after them (a longer stride would only waste memory, which no
    /// result shows: cargo-mutants found the sum unchecked).
    /// `instruction_set` names the copy the dispatch of `element_blocks` picks (the
    /// verification target prints it beside the bit-for-bit comparison; benchmarks quote it).
    #[test]
    fn the_dispatch_names_the_copy_it_runs() {
        #[cfg(target_arch = "x86_64")]
        let expected = if std::arch::is_x86_feature_detected!("avx2") {
            "avx2"
        } else {
            "portable"
        };
        #[cfg(not(target_arch = "x86_64"))]
        let expected = "portable";
        assert_eq!(instruction_set(), expected);
    }

    #[test]
    fn a_blocks_constants_are_its_named_rows_and_nothing_else() {
        assert_eq!(ROW_GAMMA, 8 * 3);
        assert_eq!(ROW_W, ROW_GAMMA + 8 * 4);
        assert_eq!([ROW_K, ROW_MU, ROW_BULK], [ROW_W + 1, ROW_W + 2, ROW_W + 3]);
        assert_eq!(BLOCK_CONSTANTS, ROW_BULK + 1);
    }
}
