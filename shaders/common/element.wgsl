// One hexahedron's internal forces. Rust twin: tled::element_forces::element_force.

struct ElementForce {
    // f[3 a + i]: force on local node a, component i (N)
    f: array<real, 24>,
    // J = det F
    j: real,
}

// H_ij = sum_a u_a,i D_a,j (paper eq. 8: F = I + H). `ue[3 a + i]`, `d[3 a + j]`.
fn displacement_gradient(ue: ptr<function, array<real, 24>>, d: ptr<function, array<real, 24>>) -> mat3r {
    var h: mat3r;
    for (var a = 0; a < 8; a++) {
        for (var i = 0; i < 3; i++) {
            for (var j = 0; j < 3; j++) {
                h[i][j] = h[i][j] + (*ue)[3 * a + i] * (*d)[3 * a + j];
            }
        }
    }
    return h;
}

// Paper eq. (4) with Flanagan-Belytschko hourglass control (src/tled/element_forces.rs):
// f_a = W F S D_a + k sum_alpha gamma_a,alpha sum_b gamma_b,alpha u_b.
// `gamma[4 a + alpha]`; w, k, mu, bulk: weight W, hourglass stiffness, moduli.
fn element_force(
    ue: ptr<function, array<real, 24>>,
    d: ptr<function, array<real, 24>>,
    w: real,
    gamma: ptr<function, array<real, 32>>,
    k: real,
    mu: real,
    bulk: real,
) -> ElementForce {
    let h = displacement_gradient(ue, d);
    let sj = pk2_stress(h, mu, bulk);
    let s = sj.s;
    // P = F S = S + H S, scaled by the weight
    var p: mat3r;
    for (var i = 0; i < 3; i++) {
        for (var j = 0; j < 3; j++) {
            p[i][j] = w * (s[i][j] + h[i][0] * s[0][j] + h[i][1] * s[1][j] + h[i][2] * s[2][j]);
        }
    }
    // hourglass: h_alpha = sum_b gamma_b,alpha u_b
    var hg: array<array<real, 3>, 4>;
    for (var b = 0; b < 8; b++) {
        for (var alpha = 0; alpha < 4; alpha++) {
            for (var i = 0; i < 3; i++) {
                hg[alpha][i] = hg[alpha][i] + (*gamma)[4 * b + alpha] * (*ue)[3 * b + i];
            }
        }
    }
    var out: ElementForce;
    for (var a = 0; a < 8; a++) {
        for (var i = 0; i < 3; i++) {
            let elastic = p[i][0] * (*d)[3 * a] + p[i][1] * (*d)[3 * a + 1] + p[i][2] * (*d)[3 * a + 2];
            let hourglass = (*gamma)[4 * a] * hg[0][i]
                + (*gamma)[4 * a + 1] * hg[1][i]
                + (*gamma)[4 * a + 2] * hg[2][i]
                + (*gamma)[4 * a + 3] * hg[3][i];
            out.f[3 * a + i] = elastic + k * hourglass;
        }
    }
    out.j = sj.j;
    return out;
}
