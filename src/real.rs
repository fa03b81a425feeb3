//! The floating-point scalar the solver is generic over (`f32` or `f64`).
//!
//! Everything that does not depend on the displacement is precomputed in `f64` and
//! converted once; the time step itself runs in `T`. Both precisions live in one binary.
//!
//! `cbrt` is not the platform's: it is [`cbrt_f64`], a fixed sequence of IEEE-754
//! operations (error below one ulp in `f64`; the `f32` value is the `f64` one rounded), so
//! that the lane-parallel element kernel (`tled::simd`) returns the same bits as the scalar
//! reference, on every machine and every SIMD width.

use std::fmt::{Debug, Display};
use std::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

/// A real scalar: `f32` or `f64`.
pub trait Real:
    Copy
    + Send
    + Sync
    + 'static
    + Debug
    + Display
    + Default
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
{
    /// `"f32"` or `"f64"`.
    const NAME: &'static str;
    /// Machine epsilon.
    const EPSILON: Self;
    /// Elements per block of the lane-parallel element kernel: one 256-bit register of
    /// `Self` (4 for `f64`, 8 for `f32`).
    const LANES: usize;
    const ZERO: Self;
    const ONE: Self;
    fn from_f64(x: f64) -> Self;
    fn to_f64(self) -> f64;
    fn sqrt(self) -> Self;
    /// Cube root by [`cbrt_f64`] (not the platform's `cbrt`): equal, bit for bit, to
    /// lane `l` of [`Real::cbrt_lanes`].
    fn cbrt(self) -> Self;
    /// `cbrt` of every lane, in lane-parallel arithmetic.
    fn cbrt_lanes<const L: usize>(x: [Self; L]) -> [Self; L];
    fn abs(self) -> Self;
    fn is_finite(self) -> bool;
    fn max(self, other: Self) -> Self;
    fn min(self, other: Self) -> Self;
}

macro_rules! impl_real {
    ($t:ty, $name:literal, $lanes:literal) => {
        impl Real for $t {
            const NAME: &'static str = $name;
            const EPSILON: Self = <$t>::EPSILON;
            const LANES: usize = $lanes;
            const ZERO: Self = 0.0;
            const ONE: Self = 1.0;
            #[inline(always)]
            fn from_f64(x: f64) -> Self {
                x as $t
            }
            #[inline(always)]
            fn to_f64(self) -> f64 {
                self as f64
            }
            #[inline(always)]
            fn sqrt(self) -> Self {
                <$t>::sqrt(self)
            }
            #[inline(always)]
            fn cbrt(self) -> Self {
                Self::cbrt_lanes([self])[0]
            }
            #[inline(always)]
            fn cbrt_lanes<const L: usize>(x: [Self; L]) -> [Self; L] {
                cbrt_lanes_impl(x)
            }
            #[inline(always)]
            fn abs(self) -> Self {
                <$t>::abs(self)
            }
            #[inline(always)]
            fn is_finite(self) -> bool {
                <$t>::is_finite(self)
            }
            #[inline(always)]
            fn max(self, other: Self) -> Self {
                <$t>::max(self, other)
            }
            #[inline(always)]
            fn min(self, other: Self) -> Self {
                <$t>::min(self, other)
            }
        }
    };
}

impl_real!(f32, "f32", 8);
impl_real!(f64, "f64", 4);

trait CbrtLanes: Sized {
    fn cbrt_lanes_impl<const L: usize>(x: [Self; L]) -> [Self; L];
}
#[inline(always)]
fn cbrt_lanes_impl<T: CbrtLanes, const L: usize>(x: [T; L]) -> [T; L] {
    T::cbrt_lanes_impl(x)
}
impl CbrtLanes for f64 {
    #[inline(always)]
    fn cbrt_lanes_impl<const L: usize>(x: [f64; L]) -> [f64; L] {
        cbrt_f64_lanes(x)
    }
}
impl CbrtLanes for f32 {
    #[inline(always)]
    fn cbrt_lanes_impl<const L: usize>(x: [f32; L]) -> [f32; L] {
        // The f64 root (error below one ulp of f64) rounded once to f32. (Plain loops: the
        // kernel calling this is compiled for a wider instruction set, and a call into
        // `array::map` would not be inlined into it.)
        let mut x64 = [0.0f64; L];
        for l in 0..L {
            x64[l] = x[l] as f64;
        }
        let r64 = cbrt_f64_lanes(x64);
        let mut r = [0.0f32; L];
        for l in 0..L {
            r[l] = r64[l] as f32;
        }
        r
    }
}

// Cube root, written for this project: range reduction on the bits, a quadratic first
// guess of the inverse cube root, three Newton steps for it (no division), and one final
// Newton step for the root itself (one division), which leaves an error below one ulp.
// Only +, -, *, / and integer operations on the bits, so every platform and every lane
// computes the same value.
//
// A normal `x` is `+-m 2^e` with `m` in [1, 2). With `e = 3q + r`, `r` in {0, 1, 2}:
// `cbrt(x) = +-2^q cbrt(a)` where `a = m 2^r` lies in [1, 8). The first guess of
// `a^(-1/3)` is `g(m) 2^(-r/3)`, `g` a quadratic fitted to `m^(-1/3)` on [1, 2) by
// iteratively reweighted least squares in relative error (max. relative error 1.8e-3).
/// Coefficients of the first guess `g(m) = G0 + m (G1 + m G2)` of `m^(-1/3)` on [1, 2).
pub const CBRT_G0: f64 = 1.388_115_48;
pub const CBRT_G1: f64 = -0.483_283_75;
pub const CBRT_G2: f64 = 0.093_390_81;
/// `2^(-r/3)` for `r = 0, 1, 2`.
pub const CBRT_INV_ROOT2: [f64; 3] = [1.0, 0.793_700_525_984_099_7, 0.629_960_524_947_436_6];
const THIRD: f64 = 1.0 / 3.0;

/// Range reduction of a normal `x` (see above): `(a, w0, s)` with `a` in [1, 8), `w0` the
/// first guess of `a^(-1/3)` (relative error < 2e-3) and `s = +-2^q` exact, so that
/// `cbrt(x) = s cbrt(a)`.
#[inline(always)]
pub(crate) fn cbrt_reduce(x: f64) -> (f64, f64, f64) {
    const MANTISSA: u64 = (1 << 52) - 1;
    let bits = x.to_bits();
    let e = ((bits >> 52) & 0x7ff) as i64 - 1023;
    let q = e.div_euclid(3);
    let r = (e - 3 * q) as usize;
    let m = f64::from_bits((1023 << 52) | (bits & MANTISSA));
    let a = f64::from_bits(((1023 + r as u64) << 52) | (bits & MANTISSA));
    let w0 = (CBRT_G0 + m * (CBRT_G1 + m * CBRT_G2)) * CBRT_INV_ROOT2[r];
    let s = f64::from_bits((bits & (1 << 63)) | (((1023 + q) as u64) << 52));
    (a, w0, s)
}

/// The floating-point part of the cube root, for any lane type: from [`cbrt_reduce`]'s
/// `(a, w0, s)` to `s cbrt(a)`. Newton on `w^-3 = a`, `w <- w + w (1 - a w^3) / 3`, takes the
/// relative error 2e-3 -> 7e-6 -> 1e-10 -> rounding; `y = a w^2` is then `cbrt(a)` to a few
/// ulp, and one Newton step on `y^3 = a`, `y <- y + (a / y^2 - y) / 3`, brings it below 1 ulp.
#[inline(always)]
pub(crate) fn cbrt_refine<X>(a: X, w0: X, s: X, c: impl Fn(f64) -> X) -> X
where
    X: Copy + Add<Output = X> + Sub<Output = X> + Mul<Output = X> + Div<Output = X>,
{
    let (one, third) = (c(1.0), c(THIRD));
    let mut w = w0;
    for _ in 0..3 {
        w = w + w * (one - a * (w * w * w)) * third;
    }
    let y = a * (w * w);
    let y = y + (a / (y * y) - y) * third;
    y * s
}

/// Whether `x` takes the reduced path (normal, either sign).
#[inline(always)]
pub(crate) fn cbrt_is_normal(x: f64) -> bool {
    let e = (x.to_bits() >> 52) & 0x7ff;
    e != 0 && e != 0x7ff
}

/// Zero, subnormal, infinite or NaN `x`.
#[cold]
#[inline(never)]
pub(crate) fn cbrt_special(x: f64) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return x + x; // +-0, +-inf, NaN
    }
    // subnormal: 2^60 x is normal (exactly), and cbrt(2^60) = 2^20
    cbrt_f64(x * f64::from_bits((1023 + 60) << 52)) * f64::from_bits((1023 - 20) << 52)
}

/// Cube root of every lane (each lane as [`cbrt_f64`]).
#[inline(always)]
pub fn cbrt_f64_lanes<const L: usize>(x: [f64; L]) -> [f64; L] {
    use crate::lanes::V;
    let (mut a, mut w0, mut s) = ([1.0; L], [1.0; L], [1.0; L]);
    let mut all_normal = true;
    for l in 0..L {
        (a[l], w0[l], s[l]) = cbrt_reduce(x[l]);
        all_normal &= cbrt_is_normal(x[l]);
    }
    let mut r = cbrt_refine(V(a), V(w0), V(s), |v| V([v; L])).0;
    if !all_normal {
        for l in 0..L {
            if !cbrt_is_normal(x[l]) {
                r[l] = cbrt_special(x[l]);
            }
        }
    }
    r
}

/// Cube root with error below one ulp, from a fixed sequence of IEEE-754 operations
/// (the same bits on every platform). `cbrt(+-0) = +-0`, `cbrt(+-inf) = +-inf`.
#[inline]
pub fn cbrt_f64(x: f64) -> f64 {
    if cbrt_is_normal(x) {
        let (a, w0, s) = cbrt_reduce(x);
        cbrt_refine(a, w0, s, |v| v)
    } else {
        cbrt_special(x)
    }
}

/// Which precision a run uses (chosen at run time; both are compiled in).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Precision {
    F32,
    #[default]
    F64,
}

impl Precision {
    pub fn name(self) -> &'static str {
        match self {
            Precision::F32 => "f32",
            Precision::F64 => "f64",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distance in units in the last place between two finite f64 of the same sign.
    fn ulps64(a: f64, b: f64) -> u64 {
        (a.to_bits() as i64 - b.to_bits() as i64).unsigned_abs()
    }

    fn lcg(state: &mut u64) -> u64 {
        *state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        *state
    }

    #[test]
    fn cbrt_f64_within_one_ulp_of_the_correctly_rounded_root() {
        let mut s = 12345u64;
        let mut worst = 0;
        for k in 0..400_000 {
            // every binade (random bits), then the range the stress sees (J^2 near 1)
            let x = if k % 2 == 0 {
                f64::from_bits(lcg(&mut s) >> 1)
            } else {
                0.25 + 3.0 * (lcg(&mut s) >> 11) as f64 / (1u64 << 53) as f64
            };
            if !x.is_finite() {
                continue;
            }
            for x in [x, -x] {
                let r = cbrt_f64(x);
                worst = worst.max(ulps64(r, x.cbrt()));
            }
        }
        assert!(worst <= 1, "worst {worst} ulp");
        // exact cubes are exact
        for k in 1..2000 {
            let c = k as f64 * 0.125;
            assert_eq!(cbrt_f64(c * c * c), c);
        }
    }

    #[test]
    fn cbrt_special_values() {
        assert_eq!(cbrt_f64(0.0).to_bits(), 0.0f64.to_bits());
        assert_eq!(cbrt_f64(-0.0).to_bits(), (-0.0f64).to_bits());
        assert_eq!(cbrt_f64(f64::INFINITY), f64::INFINITY);
        assert_eq!(cbrt_f64(f64::NEG_INFINITY), f64::NEG_INFINITY);
        assert!(cbrt_f64(f64::NAN).is_nan());
        for x in [
            f64::from_bits(1),
            f64::MIN_POSITIVE / 3.0,
            f64::MIN_POSITIVE,
            f64::MAX,
        ] {
            assert!(ulps64(cbrt_f64(x), x.cbrt()) <= 1, "{x:e}");
            assert!(ulps64(cbrt_f64(-x), (-x).cbrt()) <= 1, "{x:e}");
        }
        assert_eq!(
            f32::cbrt_lanes([0.0f32, 8.0, -27.0, 1.0]),
            [0.0, 2.0, -3.0, 1.0]
        );
    }

    #[test]
    fn cbrt_f32_within_one_ulp() {
        let mut s = 777u64;
        for _ in 0..200_000 {
            let x = f32::from_bits((lcg(&mut s) >> 33) as u32);
            if !x.is_finite() {
                continue;
            }
            let r = <f32 as Real>::cbrt(x);
            let e = (r.to_bits() as i64 - x.cbrt().to_bits() as i64).unsigned_abs();
            assert!(e <= 1, "{x:e}: {r:e} vs {:e}", x.cbrt());
        }
    }

    #[test]
    fn cbrt_lanes_equal_scalar() {
        let x = [0.7, 1.0, 1.3, f64::from_bits(3)];
        let r = f64::cbrt_lanes(x);
        for l in 0..4 {
            assert_eq!(r[l].to_bits(), <f64 as Real>::cbrt(x[l]).to_bits());
        }
    }
}
