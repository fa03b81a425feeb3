// Precision prelude for f32 kernels on an adapter with SHADER_F64 (chosen by
// src/gpu/shaders.rs; twins: real_f32.wgsl, real_f64.wgsl).
alias real = f32;
// Scalar of external-load magnitudes and curve values: f64, so that a load entry is
// real(v * c) with the product in f64, rounded once, as the CPU forms it.
alias load_real = f64;

fn is_finite_r(x: real) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

// Cube root of x, equal bit for bit to the CPU's `Real::cbrt` for f32 (src/real.rs: the
// f64 fixed-operation root `cbrt_f64` of f64(x), rounded once to f32): range reduction on
// the bits, a quadratic first guess of a^(-1/3), three division-free Newton steps, one
// final Newton step for the root (error below one f64 ulp), then rounded once to f32.
// Only + - * / are used in f64 (no transcendental: gfx-rs/wgpu#6087); the range reduction
// works on the f32 bits of x, which give the same (a, w0, s) as the f64 bits of f64(x).
// The constants CBRT_* are Rust's (src/real.rs, prepended by src/gpu/shaders.rs).
fn cbrt_r(x: real) -> real {
    if (!(x > 0.0) || !is_finite_r(x)) {
        return select(x, 0.0, x == 0.0);
    }
    let bits = bitcast<u32>(x);
    let ex = i32((bits >> 23u) & 0xffu);
    if (ex == 0) {
        // subnormal J^2 (J < 1e-19: the element is flagged as inverted anyway)
        return cbrt_f32_newton(x);
    }
    let e = ex - 127;
    let r = ((e % 3) + 3) % 3;
    let q = (e - r) / 3;
    let m = f64(bitcast<f32>((bits & 0x007fffffu) | 0x3f800000u));
    var a = m;
    var inv_root2 = f64(1.0);
    if (r == 1) {
        a = m * 2.0;
        inv_root2 = CBRT_INV_ROOT2_1;
    } else if (r == 2) {
        a = m * 4.0;
        inv_root2 = CBRT_INV_ROOT2_2;
    }
    let w0 = (CBRT_G0 + m * (CBRT_G1 + m * CBRT_G2)) * inv_root2;
    let s = f64(bitcast<f32>(u32(q + 127) << 23u));
    let one = f64(1.0);
    var w = w0;
    for (var i = 0; i < 3; i++) {
        w = w + w * (one - a * (w * w * w)) * CBRT_THIRD;
    }
    let y0 = a * (w * w);
    let y = y0 + (a / (y0 * y0) - y0) * CBRT_THIRD;
    return f32(y * s);
}
