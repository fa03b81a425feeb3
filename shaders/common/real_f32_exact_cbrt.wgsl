// Precision prelude for f32 kernels on an adapter with SHADER_F64 (chosen by
// src/gpu/shaders.rs; twins: real_f32.wgsl, real_f64.wgsl).
alias real = f32;
// Scalar of external-load magnitudes and curve values: f64, so that a load entry is
// real(v * c) with the product in f64, rounded once, as the CPU forms it.
alias load_real = f64;

fn is_finite_r(x: real) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

// Cube root of x, equal bit for bit to the CPU's `Real::cbrt` for f32 (the correctly
// rounded root): the f32 Newton root refined by two Newton steps in f64 arithmetic (error
// below one f64 ulp; only + - * / are used in f64, no transcendental), rounded once to f32.
// It differs from the correctly rounded root only if the exact root lies within one f64
// ulp of the midpoint of two f32 (probability about 2^-28 per call).
fn cbrt_r(x: real) -> real {
    if (!(x > 0.0) || !is_finite_r(x)) {
        return select(x, 0.0, x == 0.0);
    }
    let xd = f64(x);
    var y = f64(cbrt_f32_newton(x));
    for (var i = 0; i < 2; i++) {
        y = y - (y * y * y - xd) / (3.0 * y * y);
    }
    return f32(y);
}
