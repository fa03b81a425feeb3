// Stage `element_forces` (Rust twin: src/tled/element_forces.rs::element_forces): the 8x3
// force block of every element from the displacement u_s (paper eq. 4 + hourglass control),
// one invocation per element. The first element whose J = det F is not positive (or not
// finite) is recorded in `status`; once any stage has failed, later steps do nothing, so
// the state read back is the one before the failing step (the CPU's contract).

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
    for (var i = 0u; i < 24u; i++) {
        elem_f[24u * e + i] = r.f[i];
    }
    if (!(r.j > 0.0 && is_finite_r(r.j))) {
        atomicMin(&status.element_step, s);
        atomicMin(&status.element, e);
    }
}
