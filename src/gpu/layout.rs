//! `#[repr(C)]` Pod structs shared with the WGSL kernels, and the constants the kernels
//! are given (prepended to every shader by [`crate::gpu::shaders`], never repeated in WGSL).
//!
//! Every struct here must stay in sync with its twin of the same name in
//! `shaders/common/layout.wgsl`; the tests below check sizes and member offsets with naga.
//! Everything else on the GPU is a flat array of `u32` or of the stepping scalar; the
//! layout of each is documented at its binding in the kernel and at its upload in
//! [`crate::gpu::sim`].

use bytemuck::{Pod, Zeroable};

/// Invocations per workgroup of every kernel (`WG` in WGSL).
pub const WORKGROUP_SIZE: u32 = 64;
/// `dof_slot` value of a DOF that is integrated freely (`DOF_FREE` in WGSL).
pub const DOF_FREE: u32 = u32::MAX;
/// `dof_slot` value of a fixed DOF, set to 0 after every update (`DOF_FIXED` in WGSL).
pub const DOF_FIXED: u32 = u32::MAX - 1;
/// Breaking-rule codes (`RULE_LITERAL`, `RULE_LATCHED` in WGSL), from
/// [`crate::material::saliva::BreakingRule`].
pub const RULE_LITERAL: u32 = 0;
pub const RULE_LATCHED: u32 = 1;
/// "No step" in [`Status`] and in a saliva element's first-broken step (`NEVER` in WGSL).
pub const NEVER: u32 = u32::MAX;
/// Per-element saliva index of an element that is not a saliva element (`NO_SALIVA` in WGSL).
pub const NO_SALIVA: u32 = u32::MAX;

/// Sizes and per-step row layout of one model (rows: see [`crate::gpu::sim`]).
/// Must stay in sync with `struct Params` in `shaders/common/layout.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Params {
    pub num_elements: u32,
    pub num_nodes: u32,
    pub num_saliva: u32,
    /// Imposed (prescribed or rotated) DOFs: the length of the `imp_key` offsets minus one.
    pub num_imposed: u32,
    /// `load_real`s per step row (`[1 | load curves | prescribed curves | rotations]`).
    pub row_stride: u32,
    /// Stepping scalars per saliva row (the breaking points `Z`; at least 1).
    pub table_stride: u32,
    pub _pad0: u32,
    pub _pad1: u32,
}

/// The step one dispatch belongs to; one per step of a batch, bound at a dynamic offset.
/// Must stay in sync with `struct StepInfo` in `shaders/common/layout.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct StepInfo {
    /// Iteration `s` (`t_s = s dt`).
    pub step: u32,
    /// Row of this step in the per-step table.
    pub row: u32,
    pub _pad0: u32,
    pub _pad1: u32,
}

/// The first failure of a run: the step and smallest element (det F <= 0) or node
/// (non-finite displacement), or [`NEVER`].
/// Must stay in sync with `struct Status` in `shaders/common/layout.wgsl` (atomics there).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable)]
pub struct Status {
    pub element_step: u32,
    pub element: u32,
    pub node_step: u32,
    pub node: u32,
}

impl Status {
    pub const OK: Status = Status {
        element_step: NEVER,
        element: NEVER,
        node_step: NEVER,
        node: NEVER,
    };
}

/// Constants of the CPU's fixed-operation cube root (`real::cbrt_f64`: a quadratic first
/// guess `G0 + G1 m + G2 m^2` of `m^(-1/3)` on [1, 2) and `2^(-r/3)`), used by the f32
/// kernels' f64-refined cube root (`shaders/common/real_f32_exact_cbrt.wgsl`). Rust owns
/// them in `real.rs`; the WGSL gets them from [`wgsl_f64_constants`].
pub use crate::real::{CBRT_G0, CBRT_G1, CBRT_G2, CBRT_INV_ROOT2};

/// The f64 constants of the f64-refined cube root, for kernels that may use f64.
pub fn wgsl_f64_constants() -> String {
    format!(
        "const CBRT_G0: f64 = {:?};\n\
         const CBRT_G1: f64 = {:?};\n\
         const CBRT_G2: f64 = {:?};\n\
         const CBRT_INV_ROOT2_1: f64 = {:?};\n\
         const CBRT_INV_ROOT2_2: f64 = {:?};\n\
         const CBRT_THIRD: f64 = {:?};\n",
        CBRT_G0,
        CBRT_G1,
        CBRT_G2,
        CBRT_INV_ROOT2[1],
        CBRT_INV_ROOT2[2],
        1.0 / 3.0
    )
}

/// The WGSL declarations of the constants above, prepended to every kernel.
pub fn wgsl_constants() -> String {
    format!(
        "const WG: u32 = {WORKGROUP_SIZE}u;\n\
         const DOF_FREE: u32 = {DOF_FREE}u;\n\
         const DOF_FIXED: u32 = {DOF_FIXED}u;\n\
         const RULE_LITERAL: u32 = {RULE_LITERAL}u;\n\
         const RULE_LATCHED: u32 = {RULE_LATCHED}u;\n\
         const NEVER: u32 = {NEVER}u;\n\
         const NO_SALIVA: u32 = {NO_SALIVA}u;\n"
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::shaders::{kernel_source, Kernel, ShaderReal, ALL_KERNELS};
    use std::mem::{offset_of, size_of};

    fn validate(src: &str, caps: naga::valid::Capabilities) -> naga::Module {
        let module = naga::front::wgsl::parse_str(src)
            .unwrap_or_else(|e| panic!("WGSL parse error:\n{}", e.emit_to_string(src)));
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), caps)
            .validate(&module)
            .unwrap_or_else(|e| panic!("WGSL validation error:\n{}", e.emit_to_string(src)));
        module
    }

    /// Every kernel, in both precisions, parses and validates with naga (no GPU needed).
    #[test]
    fn every_shader_validates_with_naga() {
        for &k in ALL_KERNELS {
            for real in ShaderReal::ALL {
                let caps = if real.needs_f64() {
                    naga::valid::Capabilities::FLOAT64
                } else {
                    naga::valid::Capabilities::empty()
                };
                validate(&kernel_source(k, real), caps);
            }
        }
    }

    fn struct_layout(module: &naga::Module, name: &str) -> (u32, Vec<(String, u32)>) {
        for (_, ty) in module.types.iter() {
            if ty.name.as_deref() == Some(name) {
                if let naga::TypeInner::Struct { members, span } = &ty.inner {
                    return (
                        *span,
                        members
                            .iter()
                            .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
                            .collect(),
                    );
                }
            }
        }
        panic!("struct {name} not found in the WGSL");
    }

    /// Sizes and member offsets of every Pod struct equal those of its WGSL twin.
    #[test]
    fn pod_structs_match_their_wgsl_twins() {
        let module = validate(
            &kernel_source(Kernel::NodeUpdate, ShaderReal::F32),
            naga::valid::Capabilities::empty(),
        );
        macro_rules! check {
            ($ty:ident, $($field:ident),+) => {{
                let (size, members) = struct_layout(&module, stringify!($ty));
                assert_eq!(size as usize, size_of::<$ty>(), "size of {}", stringify!($ty));
                let rust: Vec<(String, u32)> =
                    vec![$((stringify!($field).to_string(), offset_of!($ty, $field) as u32)),+];
                assert_eq!(members, rust, "members of {}", stringify!($ty));
            }};
        }
        check!(
            Params,
            num_elements,
            num_nodes,
            num_saliva,
            num_imposed,
            row_stride,
            table_stride,
            _pad0,
            _pad1
        );
        check!(StepInfo, step, row, _pad0, _pad1);
        check!(Status, element_step, element, node_step, node);
    }

    /// The constants the kernels see are the Rust ones (read back from naga's module).
    #[test]
    fn wgsl_constants_are_the_rust_ones() {
        let module = validate(
            &kernel_source(Kernel::ElementForces, ShaderReal::F32),
            naga::valid::Capabilities::empty(),
        );
        let value = |name: &str| -> u32 {
            let (_, c) = module
                .constants
                .iter()
                .find(|(_, c)| c.name.as_deref() == Some(name))
                .unwrap_or_else(|| panic!("constant {name}"));
            match module.global_expressions[c.init] {
                naga::Expression::Literal(naga::Literal::U32(v)) => v,
                ref other => panic!("{name}: {other:?}"),
            }
        };
        assert_eq!(value("WG"), WORKGROUP_SIZE);
        assert_eq!(value("DOF_FREE"), DOF_FREE);
        assert_eq!(value("DOF_FIXED"), DOF_FIXED);
        assert_eq!(value("RULE_LITERAL"), RULE_LITERAL);
        assert_eq!(value("RULE_LATCHED"), RULE_LATCHED);
        assert_eq!(value("NEVER"), NEVER);
        assert_eq!(value("NO_SALIVA"), NO_SALIVA);
    }
}
