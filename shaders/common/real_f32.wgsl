// Precision prelude for f32 kernels on an adapter without SHADER_F64 (chosen by
// src/gpu/shaders.rs; twins: real_f32_exact_cbrt.wgsl, real_f64.wgsl). Every kernel
// writes `real` for the stepping scalar.
alias real = f32;
// Scalar of external-load magnitudes and curve values (f64 where the adapter has it).
alias load_real = f32;

// x is finite (neither infinite nor NaN), by its exponent bits: comparisons against NaN
// may be folded away by shader compilers, bit tests are not.
fn is_finite_r(x: real) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

// Cube root of x (Rust twin: `Real::cbrt`, the correctly rounded f32 root). Without f64
// this is cbrt_f32_newton: within one ulp of the CPU's value (the only source of a
// GPU-f32 vs CPU-f32 difference on such adapters; verification/gpu.rs states the bound).
fn cbrt_r(x: real) -> real {
    if (!(x > 0.0) || !is_finite_r(x)) {
        // 0 -> 0 as std does (a zero J is caught by the element kernel's J test).
        return select(x, 0.0, x == 0.0);
    }
    return cbrt_f32_newton(x);
}
