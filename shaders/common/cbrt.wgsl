// Cube root in f32 arithmetic only: a bit-level first guess (exponent / 3) refined by
// Newton steps y <- y - (y^3 - x) / (3 y^2); within one ulp of the correctly rounded root.
// Used by every precision prelude (real_*.wgsl), which defines `cbrt_r` from it.
fn cbrt_f32_newton(x: f32) -> f32 {
    var y = bitcast<f32>(bitcast<u32>(x) / 3u + 0x2a5137a0u);
    for (var i = 0; i < 4; i++) {
        y = y - (y * y * y - x) / (3.0 * y * y);
    }
    return y;
}
