// One entry point per shared WGSL function, for verification/gpu.rs: each reads one
// record of `input` per invocation and writes one record of `output`. The Rust side
// runs the twin of the function on the same record and compares.
// Record layouts (reals) are written next to each entry point.

@group(0) @binding(0) var<storage, read> input: array<real>;
@group(0) @binding(1) var<storage, read_write> output: array<real>;
@group(0) @binding(2) var<uniform> count: vec4<u32>;

fn load_mat(base: u32) -> mat3r {
    var m: mat3r;
    for (var i = 0u; i < 3u; i++) {
        for (var j = 0u; j < 3u; j++) {
            m[i][j] = input[base + 3u * i + j];
        }
    }
    return m;
}

fn store_mat(base: u32, m: mat3r) {
    for (var i = 0u; i < 3u; i++) {
        for (var j = 0u; j < 3u; j++) {
            output[base + 3u * i + j] = m[i][j];
        }
    }
}

// in: x (1); out: cbrt_r(x) (1)
@compute @workgroup_size(WG)
fn test_cbrt(@builtin(global_invocation_id) gid: vec3<u32>) {
    let r = gid.x;
    if (r >= count.x) {
        return;
    }
    output[r] = cbrt_r(input[r]);
}

// in: H (9), mu, K (11); out: S (9), J, det_identity_plus_minus_one(H),
// two_green_strain(H) (9), inverse3(I + H) (9) (29)
@compute @workgroup_size(WG)
fn test_pk2_stress(@builtin(global_invocation_id) gid: vec3<u32>) {
    let r = gid.x;
    if (r >= count.x) {
        return;
    }
    let h = load_mat(11u * r);
    let sj = pk2_stress(h, input[11u * r + 9u], input[11u * r + 10u]);
    let o = 29u * r;
    store_mat(o, sj.s);
    output[o + 9u] = sj.j;
    output[o + 10u] = det_identity_plus_minus_one(h);
    store_mat(o + 11u, two_green_strain(h));
    var f = h;
    for (var i = 0; i < 3; i++) {
        f[i][i] = f[i][i] + real(1.0);
    }
    store_mat(o + 20u, inverse3(f));
}

// in: u (24), D (24), W, gamma (32), k, mu, K (84); out: f (24), J (25)
@compute @workgroup_size(WG)
fn test_element_force(@builtin(global_invocation_id) gid: vec3<u32>) {
    let r = gid.x;
    if (r >= count.x) {
        return;
    }
    let b = 84u * r;
    var ue: array<real, 24>;
    var d: array<real, 24>;
    var g: array<real, 32>;
    for (var i = 0u; i < 24u; i++) {
        ue[i] = input[b + i];
        d[i] = input[b + 24u + i];
    }
    for (var i = 0u; i < 32u; i++) {
        g[i] = input[b + 49u + i];
    }
    let ef = element_force(&ue, &d, input[b + 48u], &g, input[b + 81u], input[b + 82u], input[b + 83u]);
    for (var i = 0u; i < 24u; i++) {
        output[25u * r + i] = ef.f[i];
    }
    output[25u * r + 24u] = ef.j;
}

// in: H (9), y (3), z, rule, decay, broken, force (24), previous (24) (64);
// out: Q, broken, force (24), previous (24) (50)
@compute @workgroup_size(WG)
fn test_saliva(@builtin(global_invocation_id) gid: vec3<u32>) {
    let r = gid.x;
    if (r >= count.x) {
        return;
    }
    let b = 64u * r;
    let h = load_mat(b);
    let y = vec3<real>(input[b + 9u], input[b + 10u], input[b + 11u]);
    let q = stretch_across(h, y);
    var f: array<real, 24>;
    var p: array<real, 24>;
    for (var i = 0u; i < 24u; i++) {
        f[i] = input[b + 16u + i];
        p[i] = input[b + 40u + i];
    }
    let broken = apply_breaking_rule(q, input[b + 12u], u32(input[b + 13u]), input[b + 14u], input[b + 15u] != 0.0, &f, &p);
    let o = 50u * r;
    output[o] = q;
    output[o + 1u] = select(real(0.0), real(1.0), broken);
    for (var i = 0u; i < 24u; i++) {
        output[o + 2u + i] = f[i];
        output[o + 26u + i] = p[i];
    }
}
