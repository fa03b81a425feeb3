//! Small fixed-size 3x3 algebra on plain arrays, generic over [`Real`], and the crate's one
//! set of 3-vector helpers on `[f64; 3]` ([`add`], [`sub`], [`scale`], [`dot`], [`cross`],
//! [`norm`], [`dist`], [`unit`](fn@unit), [`normalize`]).
//!
//! The hot loops use these instead of a general matrix library so that the same code
//! compiles to straight-line arithmetic in both precisions. Matrices are row-major
//! `m[i][j]`. Each helper's floating-point operations are written out in a fixed order
//! (component by component, sums left to right), so that results do not depend on which
//! caller uses them.

use crate::real::Real;

pub type Vec3<T> = [T; 3];
pub type Mat3<T> = [[T; 3]; 3];

#[inline(always)]
pub fn det<T: Real>(m: &Mat3<T>) -> T {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// Cofactor-based adjugate: `adj(m) = det(m) m^-1`.
#[inline(always)]
pub fn adjugate<T: Real>(m: &Mat3<T>) -> Mat3<T> {
    [
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
    ]
}

/// Inverse; the caller guarantees `det(m) != 0`.
#[inline(always)]
pub fn inverse<T: Real>(m: &Mat3<T>) -> Mat3<T> {
    let a = adjugate(m);
    let inv_det = T::ONE / det(m);
    let mut r = a;
    for row in r.iter_mut() {
        for v in row.iter_mut() {
            *v *= inv_det;
        }
    }
    r
}

#[inline(always)]
pub fn mul<T: Real>(a: &Mat3<T>, b: &Mat3<T>) -> Mat3<T> {
    let mut r = [[T::ZERO; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            r[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
        }
    }
    r
}

#[inline(always)]
pub fn transpose<T: Real>(a: &Mat3<T>) -> Mat3<T> {
    [
        [a[0][0], a[1][0], a[2][0]],
        [a[0][1], a[1][1], a[2][1]],
        [a[0][2], a[1][2], a[2][2]],
    ]
}

#[inline(always)]
pub fn mat_vec<T: Real>(a: &Mat3<T>, v: &Vec3<T>) -> Vec3<T> {
    [
        a[0][0] * v[0] + a[0][1] * v[1] + a[0][2] * v[2],
        a[1][0] * v[0] + a[1][1] * v[1] + a[1][2] * v[2],
        a[2][0] * v[0] + a[2][1] * v[1] + a[2][2] * v[2],
    ]
}

#[inline(always)]
pub fn trace<T: Real>(a: &Mat3<T>) -> T {
    a[0][0] + a[1][1] + a[2][2]
}

/// `a + b`, component by component.
#[inline(always)]
pub fn add(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// `a - b`, component by component.
#[inline(always)]
pub fn sub(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `s a`: each component times `s`.
#[inline(always)]
pub fn scale(a: &[f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// `a . b`, summed left to right: `(a0 b0 + a1 b1) + a2 b2`.
#[inline(always)]
pub fn dot<T: Real>(a: &Vec3<T>, b: &Vec3<T>) -> T {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `a x b` (right-handed).
#[inline(always)]
pub fn cross(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `|a|`: the square root of [`dot`]`(a, a)` (same operations in the same order).
#[inline(always)]
pub fn norm(a: &[f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// `|a - b|`: [`norm`] of [`sub`].
#[inline(always)]
pub fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    norm(&sub(a, b))
}

/// `a / |a|`, each component divided by the norm (no guard: a zero vector gives NaN).
/// Not bit-equal to [`normalize`], which multiplies by the reciprocal.
#[inline(always)]
pub fn unit(a: &[f64; 3]) -> [f64; 3] {
    let n = norm(a);
    [a[0] / n, a[1] / n, a[2] / n]
}

/// `a * (1 / |a|)` ([`scale`] by the reciprocal of the norm), or zero for a zero (or
/// non-finite) vector. Not bit-equal to [`unit`](fn@unit), which divides.
#[inline(always)]
pub fn normalize(a: &[f64; 3]) -> [f64; 3] {
    let n = norm(a);
    if n > 0.0 && n.is_finite() {
        scale(a, 1.0 / n)
    } else {
        [0.0; 3]
    }
}

/// `det(I + H) - 1` without forming `I + H`, so that small strains keep their
/// relative precision in `f32` (`1 + tiny` would round to 1).
#[inline(always)]
pub fn det_identity_plus_minus_one<T: Real>(h: &Mat3<T>) -> T {
    // det(I+H) = 1 + tr H + (principal 2x2 minors of H) + det H
    let tr = trace(h);
    let minors = h[0][0] * h[1][1] - h[0][1] * h[1][0] + h[1][1] * h[2][2] - h[1][2] * h[2][1]
        + h[0][0] * h[2][2]
        - h[0][2] * h[2][0];
    tr + minors + det(h)
}

/// Rotation matrix for a right-handed rotation by `angle` (rad) about the unit `axis`
/// (Rodrigues' formula).
pub fn rotation_matrix(axis: &[f64; 3], angle: f64) -> [[f64; 3]; 3] {
    let (s, c) = angle.sin_cos();
    let [x, y, z] = *axis;
    let t = 1.0 - c;
    [
        [c + x * x * t, x * y * t - z * s, x * z * t + y * s],
        [y * x * t + z * s, c + y * y * t, y * z * t - x * s],
        [z * x * t - y * s, z * y * t + x * s, c + z * z * t],
    ]
}

/// Smallest and largest coordinate of `points` along each axis (`+inf`, `-inf` when empty).
pub fn bounding_box<'a>(points: impl IntoIterator<Item = &'a [f64; 3]>) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for x in points {
        for k in 0..3 {
            lo[k] = lo[k].min(x[k]);
            hi[k] = hi[k].max(x[k]);
        }
    }
    (lo, hi)
}
