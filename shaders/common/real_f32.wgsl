// Precision prelude for f32 kernels (chosen by src/gpu/shaders.rs; the f64 twin is
// common/real_f64.wgsl). Every kernel writes `real` for the stepping scalar.
alias real = f32;

// x is finite (neither infinite nor NaN), by its exponent bits: comparisons against NaN
// may be folded away by shader compilers, bit tests are not.
fn is_finite_r(x: real) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

// Cube root of x > 0 (Rust twin: `Real::cbrt`, std's f32::cbrt). WGSL has no cbrt and
// pow() is a transcendental; a bit-level first guess (exponent / 3) refined by Newton
// steps y <- y - (y^3 - x) / (3 y^2) reaches f32 round-off (within ~1 ulp of a correctly
// rounded cube root: verified by verification/gpu.rs::wgsl_functions_match_rust_f32).
fn cbrt_r(x: real) -> real {
    if (!(x > 0.0) || !is_finite_r(x)) {
        // 0 -> 0 as std does (a zero J is caught by the element kernel's J test).
        return select(x, 0.0, x == 0.0);
    }
    var y = bitcast<f32>(bitcast<u32>(x) / 3u + 0x2a5137a0u);
    for (var i = 0; i < 4; i++) {
        y = y - (y * y * y - x) / (3.0 * y * y);
    }
    return y;
}
