// Stage `saliva_forces` (Rust twin: src/tled/saliva_forces.rs::saliva_forces): the breaking
// rule of paper eq. (11) on the block of every saliva element, with its stretch across the
// layer (eqs. 8-10) and its breaking point Z (eqs. 6-7, evaluated in f64 by Rust for each
// step and read from the per-step saliva row). One invocation per saliva element.

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<uniform> step: StepInfo;
@group(0) @binding(2) var<storage, read> u: array<real>;
@group(0) @binding(3) var<storage, read> conn: array<u32>;
@group(0) @binding(4) var<storage, read> dhdx: array<real>;
@group(0) @binding(5) var<storage, read_write> elem_f: array<real>;
@group(0) @binding(6) var<storage, read_write> status: Status;
// per step: the breaking point Z of each saliva element (table_stride per row)
@group(0) @binding(7) var<storage, read> table: array<real>;
// per saliva element: element index, group, rule
@group(0) @binding(8) var<storage, read> sal_meta: array<u32>;
// per saliva element: unit axis across the layer (3)
@group(0) @binding(9) var<storage, read> sal_across: array<real>;
// per saliva group: decay factor per step
@group(0) @binding(10) var<storage, read> sal_decay: array<real>;
// per saliva element: the modified force F of the previous step (24)
@group(0) @binding(11) var<storage, read_write> sal_prev: array<real>;
// per saliva element: broken (0/1), first step broken (NEVER if never)
@group(0) @binding(12) var<storage, read_write> sal_state: array<u32>;
// per saliva element: Q of the last step
@group(0) @binding(13) var<storage, read_write> sal_q: array<real>;

@compute @workgroup_size(WG)
fn saliva_forces(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = gid.x;
    if (k >= params.num_saliva) {
        return;
    }
    let s = step.step;
    if (atomicLoad(&status.element_step) <= s || atomicLoad(&status.node_step) < s) {
        return;
    }
    let e = sal_meta[3u * k];
    let g = sal_meta[3u * k + 1u];
    let rule = sal_meta[3u * k + 2u];
    var ue: array<real, 24>;
    var d: array<real, 24>;
    var f: array<real, 24>;
    var prev: array<real, 24>;
    for (var a = 0u; a < 8u; a++) {
        let n = conn[8u * e + a];
        for (var i = 0u; i < 3u; i++) {
            ue[3u * a + i] = u[3u * n + i];
            d[3u * a + i] = dhdx[24u * e + 3u * a + i];
        }
    }
    for (var i = 0u; i < 24u; i++) {
        f[i] = elem_f[24u * e + i];
        prev[i] = sal_prev[24u * k + i];
    }
    let h = displacement_gradient(&ue, &d);
    let y = vec3<real>(sal_across[3u * k], sal_across[3u * k + 1u], sal_across[3u * k + 2u]);
    let q = stretch_across(h, y);
    let z = table[step.row * params.table_stride + k];
    let broken = apply_breaking_rule(q, z, rule, sal_decay[g], sal_state[2u * k] != 0u, &f, &prev);
    for (var i = 0u; i < 24u; i++) {
        elem_f[24u * e + i] = f[i];
        sal_prev[24u * k + i] = prev[i];
    }
    if (broken && sal_state[2u * k + 1u] == NEVER) {
        sal_state[2u * k + 1u] = s;
    }
    sal_state[2u * k] = select(0u, 1u, broken);
    sal_q[k] = q;
}
