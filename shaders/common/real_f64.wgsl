// Precision prelude for f64 kernels (adapter feature SHADER_F64; twins: real_f32.wgsl,
// real_f32_exact_cbrt.wgsl). No f64 transcendental is used anywhere: naga's f64
// exp/log/pow return garbage on some drivers (gfx-rs/wgpu#6087); only + - * / and
// comparisons are.
alias real = f64;
// Scalar of external-load magnitudes and curve values.
alias load_real = f64;

// x is finite: NaN fails every ordered comparison, +-inf exceeds the largest f64
// (naga has no bitcast of f64 to two u32).
fn is_finite_r(x: real) -> bool {
    return abs(x) <= 1.7976931348623157e308;
}

// Cube root of x > 0: the f32 Newton root as the first guess, then two Newton steps in
// f64 (quadratic: 1e-7 -> 1e-14 -> round-off): within about one ulp of the CPU's f64 cbrt.
fn cbrt_r(x: real) -> real {
    if (!(x > 0.0) || !is_finite_r(x)) {
        return select(x, 0.0, x == 0.0);
    }
    var y = f64(cbrt_f32_newton(f32(x)));
    for (var i = 0; i < 2; i++) {
        y = y - (y * y * y - x) / (3.0 * y * y);
    }
    return y;
}
