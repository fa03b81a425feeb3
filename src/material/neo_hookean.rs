//! NiftySim's compressible neo-Hookean material (the paper's soft tissue and, with
//! the breaking rule on top, its saliva: Table 1).
//!
//! Strain energy per unit reference volume, with `C = F^T F`, `J = det F`:
//!
//! $$ \Psi(C) = \tfrac{\mu}{2}\left(J^{-2/3}\,\mathrm{tr}\,C - 3\right) + \tfrac{K}{2}(J-1)^2 $$
//!
//! Second Piola-Kirchhoff stress `S = 2 dPsi/dC`:
//!
//! $$ S = \mu J^{-2/3}\left(I - \tfrac{\mathrm{tr}\,C}{3} C^{-1}\right) + K J (J-1) C^{-1} $$
//!
//! | symbol | code | unit |
//! |---|---|---|
//! | `mu` (shear modulus) | `mu` | Pa |
//! | `K` (bulk modulus) | `bulk` | Pa |
//! | `H = grad_X u` | `h` | - |
//!
//! The stress is evaluated from the displacement gradient `H` (never from `F = I + H`
//! directly) so that small strains keep their relative precision in `f32`:
//! `C - I = H + H^T + H^T H`, `J - 1` from the invariants of `H`, and
//! `I - (tr C/3) C^-1 = C^-1 dev(C)` with `dev(C) = dev(C - I)`.
//!
//! Verified by `verification/material.rs` (stress = derivative of energy, tangent =
//! derivative of stress, against NiftySim's `SE` output) and used by paper eq. (4).

use crate::linalg::{det_identity_plus_minus_one, inverse, Mat3};
use crate::real::Real;

/// Material constants of one neo-Hookean element set.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct NeoHookean {
    /// Shear modulus `mu` (Pa).
    pub mu: f64,
    /// Bulk modulus `K` (Pa).
    pub bulk: f64,
}

impl NeoHookean {
    /// Lamé's first parameter `lambda = K - 2 mu / 3` (Pa).
    pub fn lambda(&self) -> f64 {
        self.bulk - 2.0 * self.mu / 3.0
    }
    /// P-wave modulus `K + 4 mu / 3` (Pa), which sets the dilatational wave speed.
    pub fn p_wave_modulus(&self) -> f64 {
        self.bulk + 4.0 * self.mu / 3.0
    }
}

/// `C - I = H + H^T + H^T H` (twice the Green-Lagrange strain).
/// GPU twin: `shaders/common/neo_hookean.wgsl::two_green_strain`.
#[inline(always)]
pub fn two_green_strain<T: Real>(h: &Mat3<T>) -> Mat3<T> {
    let mut e = [[T::ZERO; 3]; 3];
    for i in 0..3 {
        for j in i..3 {
            let v = h[i][j] + h[j][i] + h[0][i] * h[0][j] + h[1][i] * h[1][j] + h[2][i] * h[2][j];
            e[i][j] = v;
            e[j][i] = v;
        }
    }
    e
}

/// Second Piola-Kirchhoff stress `S` and `J = det F` from the displacement gradient `H`.
/// See the module documentation for the formula.
/// GPU twin: `shaders/common/neo_hookean.wgsl::pk2_stress` (`verification/gpu.rs`).
#[allow(non_snake_case)]
#[inline(always)]
pub fn pk2_stress<T: Real>(h: &Mat3<T>, mu: T, bulk: T) -> (Mat3<T>, T) {
    let E2 = two_green_strain(h);
    let mut C = E2;
    for (i, row) in C.iter_mut().enumerate() {
        row[i] += T::ONE;
    }
    let Jm1 = det_identity_plus_minus_one(h);
    let J = T::ONE + Jm1;
    let Cinv = inverse(&C);
    let third = T::from_f64(1.0 / 3.0);
    let tr = E2[0][0] + E2[1][1] + E2[2][2];
    let mut dev = E2;
    for (i, row) in dev.iter_mut().enumerate() {
        row[i] -= tr * third;
    }
    // J^(-2/3)
    let jm23 = T::ONE / (J * J).cbrt();
    let iso = mu * jm23;
    let vol = bulk * J * Jm1;
    let mut S = [[T::ZERO; 3]; 3];
    for i in 0..3 {
        for j in i..3 {
            // (C^-1 dev C)_ij, symmetric because C^-1 and dev C commute.
            let cd = Cinv[i][0] * dev[0][j] + Cinv[i][1] * dev[1][j] + Cinv[i][2] * dev[2][j];
            let v = iso * cd + vol * Cinv[i][j];
            S[i][j] = v;
            S[j][i] = v;
        }
    }
    (S, J)
}

/// Strain energy density `Psi` (J/m^3) from the displacement gradient, in `f64`.
#[allow(non_snake_case)]
pub fn strain_energy_density(h: &Mat3<f64>, mu: f64, bulk: f64) -> f64 {
    let E2 = two_green_strain(h);
    let Jm1 = det_identity_plus_minus_one(h);
    let tr = E2[0][0] + E2[1][1] + E2[2][2];
    // J^(-2/3) tr C - 3 = 3 (J^(-2/3) - 1) + J^(-2/3) tr(C - I)
    let jm23_m1 = (-2.0 / 3.0 * Jm1.ln_1p()).exp_m1();
    0.5 * mu * (3.0 * jm23_m1 + (1.0 + jm23_m1) * tr) + 0.5 * bulk * Jm1 * Jm1
}

/// Material tangent `dS/dE` (the 4th-order tensor `CC_IJKL = 2 dS_IJ/dC_KL`), in `f64`,
/// for the static solver's Newton iterations.
///
/// # Derivation
/// With `dJ/dC = J C^-1 / 2`, `d(C^-1)_IJ/dC_KL = -(C^-1_IK C^-1_JL + C^-1_IL C^-1_JK)/2`
/// and `d(tr C)/dC = I`:
/// `CC = mu J^(-2/3) [ -2/3 (C^-1 (x) I + I (x) C^-1) + 2/9 trC C^-1 (x) C^-1 + 2/3 trC Isym(C^-1) ]`
/// ` + K [ (2J - 1) J C^-1 (x) C^-1 - 2 J (J - 1) Isym(C^-1) ]`,
/// where `Isym(C^-1)_IJKL = (C^-1_IK C^-1_JL + C^-1_IL C^-1_JK)/2`.
#[allow(non_snake_case)]
pub fn material_tangent(h: &Mat3<f64>, mu: f64, bulk: f64) -> [[[[f64; 3]; 3]; 3]; 3] {
    let E2 = two_green_strain(h);
    let mut C = E2;
    for (i, row) in C.iter_mut().enumerate() {
        row[i] += 1.0;
    }
    let J = 1.0 + det_identity_plus_minus_one(h);
    let Ci = inverse(&C);
    let I1 = C[0][0] + C[1][1] + C[2][2];
    let jm23 = 1.0 / (J * J).cbrt();
    let d = |i: usize, j: usize| if i == j { 1.0 } else { 0.0 };
    let mut t = [[[[0.0; 3]; 3]; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            for k in 0..3 {
                for l in 0..3 {
                    let isym = 0.5 * (Ci[i][k] * Ci[j][l] + Ci[i][l] * Ci[j][k]);
                    let iso = mu
                        * jm23
                        * (-2.0 / 3.0 * (Ci[i][j] * d(k, l) + d(i, j) * Ci[k][l])
                            + 2.0 / 9.0 * I1 * Ci[i][j] * Ci[k][l]
                            + 2.0 / 3.0 * I1 * isym);
                    let vol = bulk
                        * ((2.0 * J - 1.0) * J * Ci[i][j] * Ci[k][l] - 2.0 * J * (J - 1.0) * isym);
                    t[i][j][k][l] = iso + vol;
                }
            }
        }
    }
    t
}
