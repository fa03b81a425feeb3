// The saliva breaking element (paper section 3.4). Rust twins: material::saliva.

// Paper eqs. (8)-(10): Q = y^T C y = 1 + (2 y.Hy + |Hy|^2), y the unit axis across the
// layer in the reference configuration. Twin: saliva::stretch_across.
fn stretch_across(h: mat3r, y: vec3<real>) -> real {
    var hy: array<real, 3>;
    for (var i = 0; i < 3; i++) {
        hy[i] = h[i][0] * y[0] + h[i][1] * y[1] + h[i][2] * y[2];
    }
    let two = real(2.0);
    return real(1.0) + (two * (y[0] * hy[0] + y[1] * hy[1] + y[2] * hy[2])
        + (hy[0] * hy[0] + hy[1] * hy[1] + hy[2] * hy[2]));
}

// Paper eq. (11): F_t = f_t if Q < Z, else decay * F_{t-1} (decay = 0.99 per step in the
// paper). `force` holds f on entry and F on return; `previous` holds F_{t-1} and is updated.
// rule: RULE_LITERAL (eq. 11 as written) or RULE_LATCHED (once broken, stays broken while
// Q >= 1). Returns whether the element is broken at this step.
// Twin: saliva::apply_breaking_rule.
fn apply_breaking_rule(
    q: real,
    z: real,
    rule: u32,
    decay: real,
    broken: bool,
    force: ptr<function, array<real, 24>>,
    previous: ptr<function, array<real, 24>>,
) -> bool {
    var intact: bool;
    if (rule == RULE_LATCHED && broken) {
        intact = q < real(1.0);
    } else {
        intact = q < z;
    }
    if (!intact) {
        for (var i = 0; i < 24; i++) {
            (*force)[i] = decay * (*previous)[i];
        }
    }
    *previous = *force;
    if (rule == RULE_LATCHED) {
        return broken || !intact;
    }
    return !intact;
}
