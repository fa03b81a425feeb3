// Uniform and status structs shared by every kernel.
// Each struct must stay in sync with its #[repr(C)] twin in src/gpu/layout.rs (same name);
// src/gpu/layout.rs::tests checks sizes and offsets with naga. The constants used below
// (WG, DOF_FREE, DOF_FIXED, RULE_LATCHED, NEVER) are generated from Rust by
// src/gpu/shaders.rs and prepended to every kernel.

// Sizes and per-step row layout of one model (rows: src/gpu/sim/pack.rs). Twin: layout::Params.
struct Params {
    num_elements: u32,
    num_nodes: u32,
    num_saliva: u32,
    // imposed DOFs: imp_key holds num_imposed + 1 offsets, then the terms' row indices
    num_imposed: u32,
    // load_reals per step row: [1 | load curves | prescribed curves | rotation matrices]
    row_stride: u32,
    // reals per saliva row (the breaking point Z of each saliva element; at least 1)
    table_stride: u32,
    _pad0: u32,
    _pad1: u32,
}

// The step a dispatch belongs to (bound with a dynamic offset, one per step of a batch).
// Twin: layout::StepInfo.
struct StepInfo {
    // iteration s (t_s = s dt)
    step: u32,
    // row of this step in the per-step buffers (0 .. batch length)
    row: u32,
    _pad0: u32,
    _pad1: u32,
}

// First failure, or NEVER. Twin: layout::Status. Integers only, so the result is
// deterministic: the step is the same for every thread of one dispatch and the index is
// the minimum over the threads that failed.
struct Status {
    element_step: atomic<u32>,
    element: atomic<u32>,
    node_step: atomic<u32>,
    node: atomic<u32>,
}
