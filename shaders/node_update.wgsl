// Stage `node_update` + `apply_constraints` (Rust twins: src/tled/node_update.rs::node_update
// and src/tled/solver.rs::apply_constraints), one invocation per node:
// gather the element blocks in the fixed NodeGather order (no float atomics: the same bits
// on every run), the external force R_s = sum_g curve_g(t_s) r_g, the central difference of
// paper eq. (3) in increment form u_{s+1} = u_s + A (R - F) + c1 (u_s - u_{s-1}), then the
// constraints at t_{s+1}: fixed DOFs to 0, prescribed and rotated DOFs to a fixed linear
// combination of this step's row (curve values and rotation matrices Rust evaluated in
// f64), summed in the CPU's order, so the jaw rotation matches the CPU's. WGSL has no load
// shapes and no trigonometry.

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<uniform> step: StepInfo;
@group(0) @binding(2) var<storage, read> u: array<real>;
@group(0) @binding(3) var<storage, read> u_prev: array<real>;
@group(0) @binding(4) var<storage, read_write> u_next: array<real>;
@group(0) @binding(5) var<storage, read> elem_f: array<real>;
// CSR over nodes: gather[n]..gather[n+1] index the slots that follow the num_nodes+1 offsets;
// a slot is 8 e + a (element e, corner a)
@group(0) @binding(6) var<storage, read> gather: array<u32>;
// A_n = dt^2 / (m_n (1 + alpha dt / 2)) per node, then c1 at index num_nodes
@group(0) @binding(7) var<storage, read> node_a: array<real>;
// CSR over nodes of load entries: offsets (num_nodes + 1), then keys
// (component | index in the step row of the entry's curve value << 2)
@group(0) @binding(8) var<storage, read> load_key: array<u32>;
// magnitude of each load entry (N), same order as the keys
@group(0) @binding(9) var<storage, read> load_val: array<load_real>;
// per step (row_stride per row): [1 | load curves at t_s | prescribed curves at t_{s+1} |
// rotation matrices at t_{s+1}]
@group(0) @binding(10) var<storage, read> step_row: array<load_real>;
// per DOF: DOF_FREE, DOF_FIXED or its index among the imposed DOFs
@group(0) @binding(11) var<storage, read> dof_slot: array<u32>;
// CSR over imposed DOFs of terms: offsets (num_imposed + 1), then each term's row index
@group(0) @binding(12) var<storage, read> imp_key: array<u32>;
// coefficient of each term, same order
@group(0) @binding(13) var<storage, read> imp_coef: array<load_real>;
@group(0) @binding(14) var<storage, read_write> status: Status;

@compute @workgroup_size(WG)
fn node_update(@builtin(global_invocation_id) gid: vec3<u32>) {
    let n = gid.x;
    let nn = params.num_nodes;
    if (n >= nn) {
        return;
    }
    let s = step.step;
    if (atomicLoad(&status.element_step) <= s || atomicLoad(&status.node_step) < s) {
        return;
    }
    // gather_node
    var f = array<real, 3>(0.0, 0.0, 0.0);
    let g0 = gather[n];
    let g1 = gather[n + 1u];
    for (var i = g0; i < g1; i++) {
        let slot = gather[nn + 1u + i];
        let base = 3u * slot;
        f[0] = f[0] + elem_f[base];
        f[1] = f[1] + elem_f[base + 1u];
        f[2] = f[2] + elem_f[base + 2u];
    }
    // external forces, in the CPU's accumulation order (group, then entry); each entry is
    // real(v * c), the product formed in load_real
    var r = array<real, 3>(0.0, 0.0, 0.0);
    let row = step.row * params.row_stride;
    let l0 = load_key[n];
    let l1 = load_key[n + 1u];
    for (var i = l0; i < l1; i++) {
        let key = load_key[nn + 1u + i];
        let k = key & 3u;
        r[k] = r[k] + real(load_val[i] * step_row[row + (key >> 2u)]);
    }
    let a = node_a[n];
    let c1 = node_a[nn];
    var finite = true;
    var v: array<real, 3>;
    for (var k = 0u; k < 3u; k++) {
        let uk = u[3u * n + k];
        v[k] = uk + a * (r[k] - f[k]) + c1 * (uk - u_prev[3u * n + k]);
        finite = finite && is_finite_r(v[k]);
    }
    if (!finite) {
        atomicMin(&status.node_step, s);
        atomicMin(&status.node, n);
    }
    // apply_constraints at t_{s+1}: an imposed DOF is c_0 row[i_0] + c_1 row[i_1] + ...,
    // left to right in load_real, rounded once
    let terms = params.num_imposed + 1u;
    for (var k = 0u; k < 3u; k++) {
        let c = dof_slot[3u * n + k];
        if (c == DOF_FIXED) {
            v[k] = 0.0;
        } else if (c != DOF_FREE) {
            let t0 = imp_key[c];
            let t1 = imp_key[c + 1u];
            var acc = imp_coef[t0] * step_row[row + imp_key[terms + t0]];
            for (var t = t0 + 1u; t < t1; t++) {
                acc = acc + imp_coef[t] * step_row[row + imp_key[terms + t]];
            }
            v[k] = real(acc);
        }
        u_next[3u * n + k] = v[k];
    }
}
