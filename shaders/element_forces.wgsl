// Stage `element_forces` (Rust twin: src/tled/element_forces.rs::element_forces): the 8x3
// force block of every element from the displacement u_s (paper eq. 4 + hourglass control),
// one invocation per element, followed for a saliva element by the stage `saliva_forces`
// (Rust twin: src/tled/saliva_forces.rs::saliva_forces): the breaking rule of eq. (11) on
// that element's block, so a step needs one dispatch for both stages (the CPU runs the rule
// after all blocks are formed; it reads and writes only the saliva element's own block, so
// the result is the same).
//
// The first element whose J = det F is not positive (or not finite) is recorded in `status`;
// once any stage has failed, later steps do nothing, so the state read back is the one before
// the failing step (the CPU's contract). The saliva state is therefore double-buffered: step
// s reads the `_in` copy and writes the `_out` copy (the bind group of s % 2 swaps them), and
// a failing step leaves the `_in` copy, the state before it, untouched.

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<uniform> step: StepInfo;
@group(0) @binding(2) var<storage, read> u: array<real>;
// 8 node indices per element
@group(0) @binding(3) var<storage, read> conn: array<u32>;
// D_a: 24 per element, [3 a + j]
@group(0) @binding(4) var<storage, read> dhdx: array<real>;
// gamma: 32 per element, [4 a + alpha]
@group(0) @binding(5) var<storage, read> gamma: array<real>;
// W, k, mu, K: 4 per element
@group(0) @binding(6) var<storage, read> escal: array<real>;
// output: 24 per element, [3 a + i]
@group(0) @binding(7) var<storage, read_write> elem_f: array<real>;
@group(0) @binding(8) var<storage, read_write> status: Status;
// per step: the breaking point Z of each saliva element (table_stride per row)
@group(0) @binding(9) var<storage, read> table: array<real>;
// per element: its index k among the saliva elements, or NO_SALIVA (num_elements entries);
// then per saliva element: group, rule
@group(0) @binding(10) var<storage, read> sal_meta: array<u32>;
// per saliva element: unit axis across the layer (3); then per group: decay factor per step
@group(0) @binding(11) var<storage, read> sal_const: array<real>;
// per saliva element: the modified force F of the previous step (24), then Q (1)
@group(0) @binding(12) var<storage, read> sal_real_in: array<real>;
@group(0) @binding(13) var<storage, read_write> sal_real_out: array<real>;
// per saliva element: broken (0/1), first step broken (NEVER if never)
@group(0) @binding(14) var<storage, read> sal_state_in: array<u32>;
@group(0) @binding(15) var<storage, read_write> sal_state_out: array<u32>;

// The saliva stage for saliva element k (element e) at step s: stretch across the layer
// (eqs. 8-10), breaking point Z (eqs. 6-7, evaluated in f64 by Rust, per-step saliva row),
// breaking rule (eq. 11) on the block f.
fn saliva_forces(k: u32, e: u32, s: u32, ue: ptr<function, array<real, 24>>,
                 d: ptr<function, array<real, 24>>, f: ptr<function, array<real, 24>>) {
    let ns = params.num_saliva;
    let g = sal_meta[params.num_elements + 2u * k];
    let rule = sal_meta[params.num_elements + 2u * k + 1u];
    var prev: array<real, 24>;
    for (var i = 0u; i < 24u; i++) {
        prev[i] = sal_real_in[25u * k + i];
    }
    let h = displacement_gradient(ue, d);
    let y = vec3<real>(sal_const[3u * k], sal_const[3u * k + 1u], sal_const[3u * k + 2u]);
    let q = stretch_across(h, y);
    let z = table[step.row * params.table_stride + k];
    let broken = apply_breaking_rule(q, z, rule, sal_const[3u * ns + g],
                                     sal_state_in[2u * k] != 0u, f, &prev);
    for (var i = 0u; i < 24u; i++) {
        sal_real_out[25u * k + i] = prev[i];
    }
    sal_real_out[25u * k + 24u] = q;
    var first = sal_state_in[2u * k + 1u];
    if (broken && first == NEVER) {
        first = s;
    }
    sal_state_out[2u * k] = select(0u, 1u, broken);
    sal_state_out[2u * k + 1u] = first;
}

@compute @workgroup_size(WG)
fn element_forces(@builtin(global_invocation_id) gid: vec3<u32>) {
    let e = gid.x;
    if (e >= params.num_elements) {
        return;
    }
    let s = step.step;
    if (min(atomicLoad(&status.element_step), atomicLoad(&status.node_step)) < s) {
        return;
    }
    var ue: array<real, 24>;
    var d: array<real, 24>;
    var g: array<real, 32>;
    for (var a = 0u; a < 8u; a++) {
        let n = conn[8u * e + a];
        for (var i = 0u; i < 3u; i++) {
            ue[3u * a + i] = u[3u * n + i];
            d[3u * a + i] = dhdx[24u * e + 3u * a + i];
        }
        for (var al = 0u; al < 4u; al++) {
            g[4u * a + al] = gamma[32u * e + 4u * a + al];
        }
    }
    let r = element_force(&ue, &d, escal[4u * e], &g, escal[4u * e + 1u], escal[4u * e + 2u], escal[4u * e + 3u]);
    var f = r.f;
    let k = sal_meta[e];
    if (k != NO_SALIVA) {
        saliva_forces(k, e, s, &ue, &d, &f);
    }
    for (var i = 0u; i < 24u; i++) {
        elem_f[24u * e + i] = f[i];
    }
    if (!(r.j > 0.0 && is_finite_r(r.j))) {
        atomicMin(&status.element_step, s);
        atomicMin(&status.element, e);
    }
}
