//! Blend shapes (paper eq. 1, section 2), the baseline the paper compares against.

/// Paper eq. (1): `x' = X + sum_i w_i B_i`, with `B_i` displacement fields (m) over the same
/// nodes as the reference positions `X` (m) and `w_i` their weights.
/// Verified by `verification/muscle_jaw_blend.rs::blend_shapes_eq1`.
pub fn blend(reference: &[[f64; 3]], shapes: &[(f64, &[[f64; 3]])]) -> Vec<[f64; 3]> {
    let mut x = reference.to_vec();
    for (w, b) in shapes {
        for (xi, bi) in x.iter_mut().zip(b.iter()) {
            for k in 0..3 {
                xi[k] += w * bi[k];
            }
        }
    }
    x
}
