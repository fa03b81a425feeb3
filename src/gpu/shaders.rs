//! WGSL assembly: each kernel is `shaders/<name>.wgsl` with the shared files of
//! `shaders/common/` in front of it, all embedded with `include_str!`. The precision
//! prelude (`real` = f32 or f64, `cbrt_r`, `is_finite_r`) comes first, then the constants
//! of [`crate::gpu::layout`] generated from Rust.

/// The f32-only cube root every prelude builds on.
const CBRT: &str = include_str!("../../shaders/common/cbrt.wgsl");

/// The scalar of a kernel and how its cube root is computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShaderReal {
    /// f32, cube root in f32 arithmetic (within one ulp of the CPU's).
    F32,
    /// f32, cube root refined in f64 arithmetic: bit-identical to the CPU's (needs SHADER_F64).
    F32ExactCbrt,
    /// f64 (needs SHADER_F64).
    F64,
}

impl ShaderReal {
    pub const ALL: [ShaderReal; 3] = [ShaderReal::F32, ShaderReal::F32ExactCbrt, ShaderReal::F64];
    /// Whether the kernel needs the adapter feature SHADER_F64.
    pub fn needs_f64(self) -> bool {
        self != ShaderReal::F32
    }
    /// Bytes of one `load_real` (f64 wherever the kernels may use f64).
    pub fn load_size(self) -> usize {
        if self.needs_f64() {
            8
        } else {
            4
        }
    }
    fn prelude(self) -> &'static str {
        match self {
            ShaderReal::F32 => include_str!("../../shaders/common/real_f32.wgsl"),
            ShaderReal::F32ExactCbrt => {
                include_str!("../../shaders/common/real_f32_exact_cbrt.wgsl")
            }
            ShaderReal::F64 => include_str!("../../shaders/common/real_f64.wgsl"),
        }
    }
}
/// Shared functions and structs, in dependency order.
const COMMON: [&str; 4] = [
    include_str!("../../shaders/common/layout.wgsl"),
    include_str!("../../shaders/common/neo_hookean.wgsl"),
    include_str!("../../shaders/common/element.wgsl"),
    include_str!("../../shaders/common/saliva.wgsl"),
];

/// The compute kernels; each has one entry point named like the CPU stage it mirrors.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernel {
    /// `shaders/element_forces.wgsl`, twin of `tled::element_forces::element_forces`
    /// followed, for saliva elements, by `tled::saliva_forces::saliva_forces` (a WGSL
    /// function of the same name in the same file: one dispatch per step for both).
    ElementForces,
    /// `shaders/node_update.wgsl`, twin of `tled::node_update::node_update` +
    /// `tled::solver::apply_constraints`.
    NodeUpdate,
    /// `shaders/function_tests.wgsl`: one entry point per shared WGSL function, used by
    /// `verification/gpu.rs` to compare each with its Rust twin.
    FunctionTests,
}

pub const ALL_KERNELS: &[Kernel] = &[
    Kernel::ElementForces,
    Kernel::NodeUpdate,
    Kernel::FunctionTests,
];

impl Kernel {
    pub fn name(self) -> &'static str {
        match self {
            Kernel::ElementForces => "element_forces",
            Kernel::NodeUpdate => "node_update",
            Kernel::FunctionTests => "function_tests",
        }
    }
    fn body(self) -> &'static str {
        match self {
            Kernel::ElementForces => include_str!("../../shaders/element_forces.wgsl"),
            Kernel::NodeUpdate => include_str!("../../shaders/node_update.wgsl"),
            Kernel::FunctionTests => include_str!("../../shaders/function_tests.wgsl"),
        }
    }
}

/// The complete WGSL of `kernel` with scalar `real`.
pub fn kernel_source(kernel: Kernel, real: ShaderReal) -> String {
    let mut s = String::new();
    s.push_str(CBRT);
    s.push('\n');
    s.push_str(real.prelude());
    s.push('\n');
    s.push_str(&crate::gpu::layout::wgsl_constants());
    if real == ShaderReal::F32ExactCbrt {
        s.push_str(&crate::gpu::layout::wgsl_f64_constants());
    }
    for c in COMMON {
        s.push_str(c);
        s.push('\n');
    }
    s.push_str(kernel.body());
    s
}
