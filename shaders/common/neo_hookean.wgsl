// 3x3 algebra and the neo-Hookean stress. Rust twins: src/linalg.rs and
// src/material/neo_hookean.rs (same names, same order of operations, so GPU-f32 and
// CPU-f32 differ only where a compiler contracts a*b+c into an FMA or in cbrt_r).
// Matrices are row-major m[i][j], as in Rust.

alias mat3r = array<array<real, 3>, 3>;

// Twin: linalg::det.
fn det3(m: mat3r) -> real {
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

// Twin: linalg::inverse (adjugate times 1/det).
fn inverse3(m: mat3r) -> mat3r {
    var a: mat3r;
    a[0][0] = m[1][1] * m[2][2] - m[1][2] * m[2][1];
    a[0][1] = m[0][2] * m[2][1] - m[0][1] * m[2][2];
    a[0][2] = m[0][1] * m[1][2] - m[0][2] * m[1][1];
    a[1][0] = m[1][2] * m[2][0] - m[1][0] * m[2][2];
    a[1][1] = m[0][0] * m[2][2] - m[0][2] * m[2][0];
    a[1][2] = m[0][2] * m[1][0] - m[0][0] * m[1][2];
    a[2][0] = m[1][0] * m[2][1] - m[1][1] * m[2][0];
    a[2][1] = m[0][1] * m[2][0] - m[0][0] * m[2][1];
    a[2][2] = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    let inv_det = real(1.0) / det3(m);
    for (var i = 0; i < 3; i++) {
        for (var j = 0; j < 3; j++) {
            a[i][j] = a[i][j] * inv_det;
        }
    }
    return a;
}

// det(I + H) - 1 without forming I + H. Twin: linalg::det_identity_plus_minus_one.
fn det_identity_plus_minus_one(h: mat3r) -> real {
    let tr = h[0][0] + h[1][1] + h[2][2];
    let minors = h[0][0] * h[1][1] - h[0][1] * h[1][0] + h[1][1] * h[2][2] - h[1][2] * h[2][1]
        + h[0][0] * h[2][2]
        - h[0][2] * h[2][0];
    return tr + minors + det3(h);
}

// C - I = H + H^T + H^T H. Twin: neo_hookean::two_green_strain.
fn two_green_strain(h: mat3r) -> mat3r {
    var e: mat3r;
    for (var i = 0; i < 3; i++) {
        for (var j = i; j < 3; j++) {
            let v = h[i][j] + h[j][i] + h[0][i] * h[0][j] + h[1][i] * h[1][j] + h[2][i] * h[2][j];
            e[i][j] = v;
            e[j][i] = v;
        }
    }
    return e;
}

struct Pk2 {
    s: mat3r,
    j: real,
}

// NiftySim's neo-Hookean second Piola-Kirchhoff stress from H (src/material/neo_hookean.rs):
// S = mu J^(-2/3) (I - tr C / 3 C^-1) + K J (J - 1) C^-1, with I - tr C/3 C^-1 = C^-1 dev(C - I).
// Twin: neo_hookean::pk2_stress.
fn pk2_stress(h: mat3r, mu: real, bulk: real) -> Pk2 {
    let e2 = two_green_strain(h);
    var c = e2;
    for (var i = 0; i < 3; i++) {
        c[i][i] = c[i][i] + real(1.0);
    }
    let jm1 = det_identity_plus_minus_one(h);
    let jac = real(1.0) + jm1;
    let cinv = inverse3(c);
    let third = real(1.0 / 3.0);
    let tr = e2[0][0] + e2[1][1] + e2[2][2];
    var dev = e2;
    for (var i = 0; i < 3; i++) {
        dev[i][i] = dev[i][i] - tr * third;
    }
    let jm23 = real(1.0) / cbrt_r(jac * jac);
    let iso = mu * jm23;
    let vol = bulk * jac * jm1;
    var s: mat3r;
    for (var i = 0; i < 3; i++) {
        for (var j = i; j < 3; j++) {
            let cd = cinv[i][0] * dev[0][j] + cinv[i][1] * dev[1][j] + cinv[i][2] * dev[2][j];
            let v = iso * cd + vol * cinv[i][j];
            s[i][j] = v;
            s[j][i] = v;
        }
    }
    return Pk2(s, jac);
}
