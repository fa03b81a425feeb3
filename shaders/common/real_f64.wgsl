// Precision prelude for f64 kernels (adapter feature SHADER_F64; the f32 twin is
// common/real_f32.wgsl). No f64 transcendental is used anywhere: naga's f64 exp/log/pow
// return garbage on some drivers (gfx-rs/wgpu#6087); only arithmetic and sqrt are.
alias real = f64;

// x is finite: NaN fails every ordered comparison, +-inf exceeds the largest f64
// (naga has no bitcast of f64 to two u32).
fn is_finite_r(x: real) -> bool {
    return abs(x) <= 1.7976931348623157e308;
}

// Cube root of x > 0: the f32 cube root (bit guess + Newton in f32, 4 steps) as the
// first guess, then two Newton steps in f64 (quadratic: 1e-7 -> 1e-14 -> round-off).
fn cbrt_r(x: real) -> real {
    if (!(x > 0.0) || !is_finite_r(x)) {
        return select(x, 0.0, x == 0.0);
    }
    let xf = f32(x);
    var yf = bitcast<f32>(bitcast<u32>(xf) / 3u + 0x2a5137a0u);
    for (var i = 0; i < 4; i++) {
        yf = yf - (yf * yf * yf - xf) / (3.0 * yf * yf);
    }
    var y = f64(yf);
    for (var i = 0; i < 2; i++) {
        y = y - (y * y * y - x) / (3.0 * y * y);
    }
    return y;
}
