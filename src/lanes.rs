//! Portable lanes: `V<T, L>` is `[T; L]` with one scalar operation per lane, in lane order.
//! The lane-parallel element kernel (`tled::simd`) uses it where the processor has no wider
//! registers, and `real::cbrt_f64_lanes` for its cube roots; it depends on nothing else in
//! the crate.

use std::ops::{Add, Div, Mul, Sub};

/// `L` values of `T`, operated on lane by lane.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(transparent)]
pub struct V<T, const L: usize>(pub [T; L]);

macro_rules! array_op {
    ($tr:ident, $f:ident, $op:tt) => {
        impl<T: Copy + $tr<Output = T>, const L: usize> $tr for V<T, L> {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: Self) -> Self {
                let mut r = self.0;
                for l in 0..L {
                    r[l] = self.0[l] $op o.0[l];
                }
                V(r)
            }
        }
    };
}
array_op!(Add, add, +);
array_op!(Sub, sub, -);
array_op!(Mul, mul, *);
array_op!(Div, div, /);

#[cfg(test)]
mod tests {
    use super::V;

    #[test]
    fn each_lane_on_its_own() {
        let (a, b) = (V([1.0f64, 2.0, 3.0]), V([4.0f64, 5.0, 0.0]));
        assert_eq!((a + b).0, [5.0, 7.0, 3.0]);
        assert_eq!((a - b).0, [-3.0, -3.0, 3.0]);
        assert_eq!((a * b).0, [4.0, 10.0, 0.0]);
        let q = (a / b).0;
        assert_eq!(&q[..2], &[0.25, 0.4]);
        assert_eq!(q[2], f64::INFINITY);
    }
}
