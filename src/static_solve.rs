//! Static equilibrium of the TLED discretisation: Newton's method with load stepping.
//!
//! The explicit solver integrates `M a + F_int(u) = R(t)` in time; this module finds
//! the state it should settle to, `F_int(u) = R` on the free DOFs with the constrained
//! DOFs imposed, on exactly the same [`Discretisation`] (same `D_a`, `W`, hourglass
//! vectors and stiffnesses, same constraint and load plans). It is the reference the
//! dynamic runs are checked against once their transients have been damped out.
//!
//! The equilibrium sought is the one the loads reach at the end of the run,
//! `t = T = total_time`. The load is applied in increments of the load factor
//! `lambda = 1/n, 2/n, ..., 1`; at `lambda`
//!
//! * fixed and prescribed DOFs take `lambda` times their value at `T`,
//! * nodes of a prescribed rotation take the rigid rotation by `lambda * angle * curve(T)`
//!   (so that large jaw rotations are followed along the circle, not the chord),
//! * the external forces are `R = lambda * sum_g curve_g(T) r_g`.
//!
//! Each increment is solved by Newton's method with the consistent tangent of
//! [`element_tangent`], assembled on the free DOFs into a sparse matrix and factorised
//! by faer's sparse LU with partial pivoting (the tangent may be indefinite under
//! compression or buckling, so no Cholesky). The first iteration of an increment also
//! carries the increment of the imposed DOFs (`K_ff du_f = r_f - K_fc du_c`), which keeps
//! the elements next to a moving boundary from inverting. A failed increment (no
//! convergence, a non-finite value, an inverted element, a singular tangent) is halved,
//! up to 8 times.
//!
//! Everything runs in `f64` and is deterministic: element tangents are computed in
//! parallel but summed in element order into a fixed sparsity pattern.

use crate::boundary::PrescribedRotation;
use crate::error::{Error, Result};
use crate::material::neo_hookean::{material_tangent, pk2_stress};
use crate::problem::Problem;
use crate::tled::element_forces::{element_forces, ElementArrays};
use crate::tled::node_update::gather_all;
use crate::tled::precompute::Discretisation;
use crate::tled::solver::{apply_constraints, displacement_gradient};
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::ColMut;
use rayon::prelude::*;

/// Consistent tangent of the element force of [`element_force`](crate::tled::element_forces::element_force):
/// entry `(3a + i, 3b + k)` is `d f_a,i / d u_b,k` (N/m), for element `e` at displacement `u`.
///
/// # Derivation
///
/// The element force is
/// `f_a,i = W P_iJ D_aJ + k sum_alpha gamma_a,alpha sum_b gamma_b,alpha u_b,i`
/// with `P = F S`, `F = I + H`, `H_iJ = sum_b u_b,i D_bJ` (summation over repeated
/// capital indices). Differentiating with respect to `u_b,k`:
///
/// * `dF_iJ / du_b,k = delta_ik D_bJ`;
/// * `dE_LM / du_b,k = (D_bL F_kM + F_kL D_bM) / 2` for `E = (F^T F - I) / 2`;
/// * `dS_JK / du_b,k = CC_JKLM dE_LM / du_b,k = CC_JKLM F_kM D_bL`, because the
///   material tangent `CC = dS/dE` ([`material_tangent`]) has the minor symmetry
///   `CC_JKLM = CC_JKML`, so both halves of `dE` contribute the same;
/// * `dP_iK / du_b,k = delta_ik D_bJ S_JK + F_iJ CC_JKLM F_kM D_bL`.
///
/// Contracting with `W D_aK` and adding the (linear) hourglass term gives
///
/// `K_(ai)(bk) = W (D_a . S D_b) delta_ik`   (geometric, initial stress)
/// `           + W F_iJ D_aK CC_JKLM F_kM D_bL`   (material)
/// `           + k sum_alpha gamma_a,alpha gamma_b,alpha delta_ik`   (hourglass).
///
/// `S` is symmetric and `CC` has the major symmetry `CC_JKLM = CC_LMJK` (it is the
/// second derivative of the strain energy), so the tangent is symmetric: it is the
/// Hessian of [`element_energy`](crate::tled::solver::element_energy).
///
/// Written in `f64` for clarity, not speed (about 10^4 flops per element).
#[allow(non_snake_case, clippy::needless_range_loop)]
pub fn element_tangent(d: &Discretisation, u: &[[f64; 3]], e: usize) -> [[f64; 24]; 24] {
    let D = &d.dhdx[e];
    let W = d.weight[e];
    let gamma = &d.gamma[e];
    let k_hg = d.hg_k[e];
    let H = displacement_gradient(d, u, e);
    let (S, _) = pk2_stress(&H, d.mu[e], d.bulk[e]);
    let CC = material_tangent(&H, d.mu[e], d.bulk[e]);
    let mut F = H;
    for i in 0..3 {
        F[i][i] += 1.0;
    }
    // G[a][i][L][M] = sum_JK F_iJ D_aK CC_JKLM
    let mut G = [[[[0.0; 3]; 3]; 3]; 8];
    for a in 0..8 {
        for i in 0..3 {
            for l in 0..3 {
                for m in 0..3 {
                    let mut s = 0.0;
                    for j in 0..3 {
                        for kk in 0..3 {
                            s += F[i][j] * D[a][kk] * CC[j][kk][l][m];
                        }
                    }
                    G[a][i][l][m] = s;
                }
            }
        }
    }
    let mut K = [[0.0; 24]; 24];
    for a in 0..8 {
        for b in 0..8 {
            // the parts proportional to delta_ik
            let mut geo = 0.0;
            for j in 0..3 {
                for l in 0..3 {
                    geo += D[a][j] * S[j][l] * D[b][l];
                }
            }
            let hg: f64 = (0..4).map(|alpha| gamma[a][alpha] * gamma[b][alpha]).sum();
            let diagonal = W * geo + k_hg * hg;
            for i in 0..3 {
                for k in 0..3 {
                    let mut material = 0.0;
                    for l in 0..3 {
                        for m in 0..3 {
                            material += G[a][i][l][m] * D[b][l] * F[k][m];
                        }
                    }
                    K[3 * a + i][3 * b + k] = W * material + if i == k { diagonal } else { 0.0 };
                }
            }
        }
    }
    K
}

/// Options of [`solve_equilibrium`].
#[derive(Clone, Debug, PartialEq)]
pub struct StaticOptions {
    /// Number of equal load increments `n` (load factors `1/n, 2/n, ..., 1`).
    pub load_steps: usize,
    /// Newton iterations (linear solves) allowed per increment before it is halved.
    pub max_iterations: usize,
    /// Convergence: `||r_free|| <= tolerance * reaction_scale`.
    pub tolerance: f64,
}

impl Default for StaticOptions {
    fn default() -> Self {
        StaticOptions {
            load_steps: 10,
            max_iterations: 50,
            tolerance: 1e-10,
        }
    }
}

/// The equilibrium found by [`solve_equilibrium`].
#[derive(Clone, Debug, serde::Serialize)]
pub struct StaticResult {
    /// Nodal displacements (m), constrained DOFs included.
    #[serde(skip)]
    pub u: Vec<[f64; 3]>,
    /// Load increments accepted (more than `StaticOptions::load_steps` if some were halved).
    pub load_steps: usize,
    /// Newton iterations (linear solves) in all, those of halved increments included.
    pub newton_iterations: usize,
    /// `||R - F_int||` over the free DOFs at the solution (N).
    pub residual_norm: f64,
    /// `||F_int||` over the constrained DOFs (the reactions) plus `||R||` (N): the force
    /// scale the residual is measured against.
    pub reaction_scale: f64,
}

/// Halvings of a load increment allowed before the solver gives up.
const MAX_HALVINGS: u32 = 8;
/// Relative size of a Newton update below which the iteration counts as converged.
const UPDATE_TOLERANCE: f64 = 1e-14;
/// Elements whose tangents are computed in parallel before being summed in order.
const TANGENT_CHUNK: usize = 1024;
/// Marks a constrained DOF in the free-DOF numbering.
const CONSTRAINED: usize = usize::MAX;

/// Solves `F_int(u) = R` for the loads and imposed displacements of `p` at the end of the
/// run, `t = p.time.total_time`, by Newton's method with load stepping (see the module
/// documentation). Returns [`Error::NotConverged`] when an increment still fails after
/// 8 halvings, naming the load factor, the Newton iteration and the residual.
pub fn solve_equilibrium(p: &Problem, opts: &StaticOptions) -> Result<StaticResult> {
    p.validate()?;
    let what = "static solver options";
    if opts.load_steps == 0 {
        return Err(Error::field(what, "load_steps", "must be at least 1"));
    }
    if opts.max_iterations == 0 {
        return Err(Error::field(what, "max_iterations", "must be at least 1"));
    }
    if !(opts.tolerance.is_finite() && opts.tolerance >= 0.0) {
        return Err(Error::field(
            what,
            "tolerance",
            format!("must be finite and >= 0, got {}", opts.tolerance),
        ));
    }
    let mut model = Model::new(p);

    // The load factor in units of 1 / (n 2^8), so that halved increments add up exactly.
    let unit = 1u64 << MAX_HALVINGS;
    let total = opts.load_steps as u64 * unit;
    let mut done = 0u64;
    let mut halvings = 0u32;
    let mut u = vec![[0.0; 3]; model.d.num_nodes];
    let mut result = StaticResult {
        u: Vec::new(),
        load_steps: 0,
        newton_iterations: 0,
        residual_norm: 0.0,
        reaction_scale: 0.0,
    };
    while done < total {
        let next = (done + (unit >> halvings)).min(total);
        let lambda = next as f64 / total as f64;
        match model.newton(&u, lambda, opts) {
            Ok(c) => {
                u = c.u;
                result.load_steps += 1;
                result.newton_iterations += c.iterations;
                result.residual_norm = c.residual;
                result.reaction_scale = c.scale;
                done = next;
                // try a longer increment again after a success
                halvings = halvings.saturating_sub(1);
            }
            Err(f) => {
                result.newton_iterations += f.iterations;
                if halvings == MAX_HALVINGS {
                    return Err(Error::NotConverged(format!(
                        "load factor {lambda:.6} (increment from {:.6}, after {MAX_HALVINGS} halvings of the load step): \
                         {} at Newton iteration {}, residual norm {:.3e} N (target {:.3e} N)",
                        done as f64 / total as f64,
                        f.reason,
                        f.iteration,
                        f.residual,
                        opts.tolerance * f.scale,
                    )));
                }
                halvings += 1;
            }
        }
    }
    result.u = u;
    Ok(result)
}

/// A converged load increment.
struct Converged {
    u: Vec<[f64; 3]>,
    iterations: usize,
    residual: f64,
    scale: f64,
}

/// A failed load increment.
struct Failure {
    /// Newton iteration at which it failed (0 = before the first update).
    iteration: usize,
    /// Linear solves spent on it.
    iterations: usize,
    /// The last residual norm evaluated (N), NaN if none.
    residual: f64,
    /// The last reaction scale evaluated (N), NaN if none.
    scale: f64,
    reason: String,
}

/// The discretisation plus what the Newton iterations need: the free-DOF numbering, the
/// final imposed displacements and forces, and the sparsity pattern of the tangent.
struct Model<'a> {
    d: Discretisation,
    el: ElementArrays<f64>,
    reference: &'a [[f64; 3]],
    total_time: f64,
    clamp: bool,
    /// Free index of every DOF, [`CONSTRAINED`] for imposed ones.
    free_of: Vec<usize>,
    /// DOF of every free index.
    free: Vec<usize>,
    /// Imposed displacements at `t = T` (rotated nodes are recomputed per load factor).
    u_final: Vec<[f64; 3]>,
    /// External force per DOF at `t = T` (N).
    r_final: Vec<f64>,
    /// Column-compressed pattern of the free-free tangent (sorted row indices).
    pattern: SymbolicSparseColMat<usize>,
    /// Fill-reducing ordering and symbolic factorisation, computed at the first solve.
    symbolic_lu: Option<SymbolicLu<usize>>,
    elem_f: Vec<[[f64; 3]; 8]>,
}

impl<'a> Model<'a> {
    fn new(p: &'a Problem) -> Self {
        let d = Discretisation::new(p);
        let nn = d.num_nodes;
        let total_time = p.time.total_time;
        let clamp = !p.numerics.niftysim_timing;
        let mut u_final = vec![[0.0; 3]; nn];
        apply_constraints(&d, &p.mesh.nodes, &mut u_final, total_time, clamp);
        let mut r_final = vec![0.0; 3 * nn];
        for g in &d.loads {
            let c = g.curve.value(total_time, clamp);
            for &(dof, v) in &g.entries {
                r_final[dof as usize] += v * c;
            }
        }
        let mut free_of = vec![CONSTRAINED; 3 * nn];
        let mut free = Vec::new();
        for (dof, &c) in d.constraints.constrained.iter().enumerate() {
            if !c {
                free_of[dof] = free.len();
                free.push(dof);
            }
        }
        let pattern = free_pattern(&d, &free_of, &free);
        Model {
            el: ElementArrays::from_discretisation(&d),
            elem_f: vec![[[0.0; 3]; 8]; d.num_elements()],
            reference: &p.mesh.nodes,
            total_time,
            clamp,
            free_of,
            free,
            u_final,
            r_final,
            pattern,
            symbolic_lu: None,
            d,
        }
    }

    /// Imposed displacements at load factor `lambda` (only constrained entries are meaningful).
    fn imposed(&self, lambda: f64) -> Vec<[f64; 3]> {
        let mut v: Vec<[f64; 3]> = self.u_final.iter().map(|x| x.map(|c| lambda * c)).collect();
        for r in &self.d.constraints.rotations {
            let scaled = PrescribedRotation {
                nodes: Vec::new(),
                point: r.point,
                axis: r.axis,
                angle: lambda * r.angle,
                curve: r.curve.clone(),
            };
            for &n in &r.nodes {
                v[n as usize] =
                    scaled.displacement(&self.reference[n as usize], self.total_time, self.clamp);
            }
        }
        v
    }

    /// Internal nodal forces (N), or the first element with `det F <= 0` (or not finite).
    fn internal_forces(&mut self, u: &[[f64; 3]]) -> std::result::Result<Vec<[f64; 3]>, usize> {
        if let Some(e) = element_forces(&self.el, u, &mut self.elem_f) {
            return Err(e);
        }
        Ok(gather_all(&self.d.gather, &self.elem_f, self.d.num_nodes))
    }

    /// Newton iterations for load factor `lambda`, starting from the equilibrium `u0` of
    /// the previous load factor.
    fn newton(
        &mut self,
        u0: &[[f64; 3]],
        lambda: f64,
        opts: &StaticOptions,
    ) -> std::result::Result<Converged, Failure> {
        let nd = 3 * self.d.num_nodes;
        let mut u = u0.to_vec();
        let target = self.imposed(lambda);
        // increment of the imposed DOFs, carried by the first linear solve
        let mut du_c = vec![0.0; nd];
        for dof in (0..nd).filter(|&k| self.free_of[k] == CONSTRAINED) {
            du_c[dof] = target[dof / 3][dof % 3] - u[dof / 3][dof % 3];
        }
        let mut pending = du_c.iter().any(|&v| v != 0.0);
        let r_ext: Vec<f64> = self.r_final.iter().map(|&r| lambda * r).collect();
        let r_ext_norm = norm(&r_ext);
        let mut small_update = false;
        let (mut residual, mut scale, mut solves) = (f64::NAN, f64::NAN, 0);
        for it in 0..=opts.max_iterations {
            let fail = |reason: String, residual: f64, scale: f64, iterations: usize| Failure {
                iteration: it,
                iterations,
                residual,
                scale,
                reason,
            };
            let fint = match self.internal_forces(&u) {
                Ok(f) => f,
                Err(e) => {
                    return Err(fail(
                        format!("element {e} inverted or degenerate (det F <= 0 or not finite)"),
                        residual,
                        scale,
                        solves,
                    ))
                }
            };
            let r: Vec<f64> = self
                .free
                .iter()
                .map(|&k| r_ext[k] - fint[k / 3][k % 3])
                .collect();
            residual = norm(&r);
            let reaction: f64 = (0..nd)
                .filter(|&k| self.free_of[k] == CONSTRAINED)
                .map(|k| fint[k / 3][k % 3].powi(2))
                .sum();
            scale = reaction.sqrt() + r_ext_norm;
            if !(residual.is_finite() && scale.is_finite()) {
                return Err(fail("non-finite residual".into(), residual, scale, solves));
            }
            if !pending
                && (residual <= opts.tolerance * scale.max(f64::MIN_POSITIVE) || small_update)
            {
                return Ok(Converged {
                    u,
                    iterations: solves,
                    residual,
                    scale,
                });
            }
            if it == opts.max_iterations {
                return Err(fail(
                    format!("no convergence in {} iterations", opts.max_iterations),
                    residual,
                    scale,
                    solves,
                ));
            }
            let du_f = match self.solve_linearised(&u, r, pending.then_some(du_c.as_slice())) {
                Ok(x) => x,
                Err(reason) => return Err(fail(reason, residual, scale, solves)),
            };
            solves += 1;
            if pending {
                for dof in (0..nd).filter(|&k| self.free_of[k] == CONSTRAINED) {
                    u[dof / 3][dof % 3] = target[dof / 3][dof % 3];
                }
                du_c.fill(0.0);
                pending = false;
            }
            for (&dof, &x) in self.free.iter().zip(&du_f) {
                u[dof / 3][dof % 3] += x;
            }
            let update = norm(&du_f);
            if !update.is_finite() {
                return Err(fail(
                    "non-finite Newton update".into(),
                    residual,
                    scale,
                    solves,
                ));
            }
            small_update = update <= UPDATE_TOLERANCE * norm(u.as_flattened());
        }
        unreachable!("the loop returns at it == max_iterations")
    }

    /// Solves `K_ff du_f = r_f - K_fc du_c` at displacement `u` (`du_c = None`: zero).
    fn solve_linearised(
        &mut self,
        u: &[[f64; 3]],
        mut rhs: Vec<f64>,
        du_c: Option<&[f64]>,
    ) -> std::result::Result<Vec<f64>, String> {
        if self.free.is_empty() {
            return Ok(rhs);
        }
        let pattern = self.pattern.as_ref();
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        let mut values = vec![0.0; row_idx.len()];
        let (d, free_of) = (&self.d, &self.free_of);
        let ne = d.num_elements();
        for start in (0..ne).step_by(TANGENT_CHUNK) {
            let end = (start + TANGENT_CHUNK).min(ne);
            let tangents: Vec<[[f64; 24]; 24]> = (start..end)
                .into_par_iter()
                .map(|e| element_tangent(d, u, e))
                .collect();
            for (e, ke) in (start..end).zip(&tangents) {
                let dofs: [usize; 24] =
                    std::array::from_fn(|l| 3 * d.conn[e][l / 3] as usize + l % 3);
                for (lb, &gb) in dofs.iter().enumerate() {
                    let col = free_of[gb];
                    if col == CONSTRAINED {
                        let v = du_c.map_or(0.0, |c| c[gb]);
                        if v != 0.0 {
                            for (la, &ga) in dofs.iter().enumerate() {
                                if free_of[ga] != CONSTRAINED {
                                    rhs[free_of[ga]] -= ke[la][lb] * v;
                                }
                            }
                        }
                        continue;
                    }
                    let rows = &row_idx[col_ptr[col]..col_ptr[col + 1]];
                    for (la, &ga) in dofs.iter().enumerate() {
                        let row = free_of[ga];
                        if row != CONSTRAINED {
                            let pos = rows
                                .binary_search(&row)
                                .expect("the pattern holds every element coupling");
                            values[col_ptr[col] + pos] += ke[la][lb];
                        }
                    }
                }
            }
        }
        if !values.iter().all(|v| v.is_finite()) {
            return Err("non-finite tangent".into());
        }
        let symbolic = match &self.symbolic_lu {
            Some(s) => s.clone(),
            None => {
                let s = SymbolicLu::try_new(pattern)
                    .map_err(|e| format!("symbolic LU factorisation failed: {e:?}"))?;
                self.symbolic_lu = Some(s.clone());
                s
            }
        };
        let matrix = SparseColMatRef::new(self.pattern.as_ref(), &values);
        let lu = Lu::try_new_with_symbolic(symbolic, matrix)
            .map_err(|e| format!("LU factorisation of the tangent failed (singular?): {e:?}"))?;
        lu.solve_in_place(ColMut::from_slice_mut(&mut rhs));
        Ok(rhs)
    }
}

/// Sparsity pattern of the tangent restricted to the free DOFs: free DOF `r` couples to
/// free DOF `c` when their nodes share an element.
fn free_pattern(
    d: &Discretisation,
    free_of: &[usize],
    free: &[usize],
) -> SymbolicSparseColMat<usize> {
    let n = free.len();
    let mut col_ptr = Vec::with_capacity(n + 1);
    let mut row_idx = Vec::new();
    col_ptr.push(0);
    let mut rows: Vec<usize> = Vec::new();
    let mut last_node = usize::MAX;
    for &dof in free {
        let node = dof / 3;
        if node != last_node {
            // the free DOFs of every node sharing an element with `node`
            rows.clear();
            for &slot in d.gather.of(node) {
                for &m in &d.conn[slot as usize / 8] {
                    rows.extend(
                        (0..3)
                            .map(|k| free_of[3 * m as usize + k])
                            .filter(|&r| r != CONSTRAINED),
                    );
                }
            }
            rows.sort_unstable();
            rows.dedup();
            last_node = node;
        }
        row_idx.extend_from_slice(&rows);
        col_ptr.push(row_idx.len());
    }
    SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx)
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::boundary::{
        BoundaryConditions, Fixed, LoadCurve, LoadShape, NodalForce, PrescribedDisplacement,
    };
    use crate::element::hex8::GradientVariant;
    use crate::material::NeoHookean;
    use crate::mesh::generate::{block, distorted_block, SplitMix64};
    use crate::mesh::Mesh;
    use crate::problem::{MaterialSpec, Numerics, TimeSettings};
    use crate::tled::element_forces::element_force;

    const MU: f64 = 1000.0;
    const BULK: f64 = 10000.0;

    fn problem(mesh: Mesh, variant: GradientVariant, bc: BoundaryConditions) -> Problem {
        let ne = mesh.elements.len();
        Problem {
            source: "static_solve test".into(),
            mesh,
            materials: vec![MaterialSpec {
                name: "tissue".into(),
                law: NeoHookean { mu: MU, bulk: BULK },
                density: 1000.0,
            }],
            element_material: vec![0; ne],
            bc,
            time: TimeSettings {
                dt: 1e-4,
                total_time: 1.0,
                output_every: 100,
            },
            numerics: Numerics {
                variant,
                ..Numerics::default()
            },
            additive_constraints: false,
            physics: Default::default(),
        }
    }

    fn ramp() -> LoadCurve {
        LoadCurve {
            shape: LoadShape::Ramp,
            start: 0.0,
            duration: 1.0,
        }
    }

    /// Forces of element `e` at displacement `u`, flattened to 24 entries.
    fn forces(d: &Discretisation, u: &[[f64; 3]], e: usize) -> [f64; 24] {
        let ue: [[f64; 3]; 8] = std::array::from_fn(|a| u[d.conn[e][a] as usize]);
        let (f, _) = element_force(
            &ue,
            &d.dhdx[e],
            d.weight[e],
            &d.gamma[e],
            d.hg_k[e],
            d.mu[e],
            d.bulk[e],
        );
        std::array::from_fn(|l| f[l / 3][l % 3])
    }

    #[test]
    fn tangent_matches_finite_differences_and_is_symmetric() {
        for variant in [GradientVariant::MeanGradient, GradientVariant::Centroid] {
            let mut mesh = distorted_block([0.0; 3], [0.01; 3], [1, 1, 1], 0.2, 7);
            // one cell has no interior node: distort the corners by up to 4 % of the size
            let mut rng = SplitMix64(11);
            for x in mesh.nodes.iter_mut() {
                for c in x.iter_mut() {
                    *c += 0.04 * 0.01 * rng.symmetric();
                }
            }
            let p = problem(mesh, variant, BoundaryConditions::default());
            let d = Discretisation::new(&p);
            // u = H X + a non-linear part (hourglass modes), |H_ij| <= 0.2
            let h: [[f64; 3]; 3] =
                std::array::from_fn(|_| std::array::from_fn(|_| 0.2 * rng.symmetric()));
            let u: Vec<[f64; 3]> = p
                .mesh
                .nodes
                .iter()
                .map(|x| {
                    std::array::from_fn(|i| {
                        (0..3).map(|j| h[i][j] * x[j]).sum::<f64>() + 0.03 * 0.01 * rng.symmetric()
                    })
                })
                .collect();
            let hh = displacement_gradient(&d, &u, 0);
            assert!(crate::linalg::det_identity_plus_minus_one(&hh) > -0.9);
            let k = element_tangent(&d, &u, 0);

            let step = 1e-5 * 0.01;
            let mut fd = [[0.0; 24]; 24];
            for lb in 0..24 {
                let node = d.conn[0][lb / 3] as usize;
                let mut up = u.clone();
                up[node][lb % 3] += step;
                let mut um = u.clone();
                um[node][lb % 3] -= step;
                let (fp, fm) = (forces(&d, &up, 0), forces(&d, &um, 0));
                for la in 0..24 {
                    fd[la][lb] = (fp[la] - fm[la]) / (2.0 * step);
                }
            }
            let frob = |m: &dyn Fn(usize, usize) -> f64| -> f64 {
                (0..24)
                    .flat_map(|a| (0..24).map(move |b| (a, b)))
                    .map(|(a, b)| m(a, b).powi(2))
                    .sum::<f64>()
                    .sqrt()
            };
            let scale = frob(&|a, b| k[a][b]);
            let err = frob(&|a, b| k[a][b] - fd[a][b]) / scale;
            let asym = frob(&|a, b| k[a][b] - k[b][a]) / scale;
            eprintln!(
                "{variant:?}: |K| = {scale:.4e} N/m, |K - K_fd|/|K| = {err:.3e}, \
                 |K - K^T|/|K| = {asym:.3e}"
            );
            assert!(
                err < 1e-6,
                "{variant:?}: finite-difference mismatch {err:.3e}"
            );
            assert!(asym < 1e-10, "{variant:?}: asymmetry {asym:.3e}");
        }
    }

    /// `S_22 = 0` for `F = diag(stretch, lt, lt)`: solved by bisection, independently of
    /// the crate's stress routine. Multiplying `S_22` by `lt^2`:
    /// `g(lt) = mu J^(-2/3) (lt^2 - stretch^2) / 3 + K J (J - 1)`, `J = stretch lt^2`.
    fn lateral_stretch(stretch: f64) -> f64 {
        let g = |lt: f64| {
            let j = stretch * lt * lt;
            MU * j.powf(-2.0 / 3.0) * (lt * lt - stretch * stretch) / 3.0 + BULK * j * (j - 1.0)
        };
        let (mut lo, mut hi) = (0.5, stretch);
        assert!(g(lo) < 0.0 && g(hi) > 0.0);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if g(mid) < 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }

    /// Largest nodal error against `u_exact`, relative to the largest exact displacement.
    fn relative_error(
        u: &[[f64; 3]],
        nodes: &[[f64; 3]],
        exact: impl Fn(&[f64; 3]) -> [f64; 3],
    ) -> f64 {
        let (mut err, mut scale) = (0.0f64, 0.0f64);
        for (un, x) in u.iter().zip(nodes) {
            let ue = exact(x);
            for i in 0..3 {
                err = err.max((un[i] - ue[i]).abs());
                scale = scale.max(ue[i].abs());
            }
        }
        err / scale
    }

    fn rollers(mesh: &Mesh) -> Vec<Fixed> {
        ["x_min", "y_min", "z_min"]
            .iter()
            .enumerate()
            .map(|(k, s)| Fixed {
                nodes: mesh.node_sets[*s].clone(),
                dofs: std::array::from_fn(|i| i == k),
            })
            .collect()
    }

    #[test]
    fn uniaxial_stretch_by_prescribed_displacement_is_homogeneous() {
        let mesh = block([0.0; 3], [0.03; 3], [3, 3, 3]);
        let x_max = mesh.node_sets["x_max"].clone();
        let bc = BoundaryConditions {
            fixed: rollers(&mesh),
            displacements: vec![PrescribedDisplacement {
                values: vec![0.006; x_max.len()],
                nodes: x_max,
                dof: 0,
                curve: ramp(),
            }],
            ..Default::default()
        };
        let p = problem(mesh, GradientVariant::MeanGradient, bc);
        let res = solve_equilibrium(&p, &StaticOptions::default()).unwrap();
        let lt = lateral_stretch(1.2);
        let err = relative_error(&res.u, &p.mesh.nodes, |x| {
            [0.2 * x[0], (lt - 1.0) * x[1], (lt - 1.0) * x[2]]
        });
        eprintln!(
            "uniaxial (displacement): lt = {lt:.12}, {} load steps, {} Newton iterations, \
             residual {:.3e} N of {:.3e} N, max error {err:.3e}",
            res.load_steps, res.newton_iterations, res.residual_norm, res.reaction_scale
        );
        assert_eq!(res.load_steps, 10);
        assert!(res.residual_norm <= 1e-10 * res.reaction_scale || res.residual_norm < 1e-12);
        assert!(err < 1e-9, "max relative error {err:.3e}");
    }

    #[test]
    fn uniaxial_stretch_by_nodal_forces_is_homogeneous() {
        // the same state, reached by the consistent nodal forces of the traction P_11
        let stretch = 1.2;
        let lt = lateral_stretch(stretch);
        let j = stretch * lt * lt;
        let i1 = stretch * stretch + 2.0 * lt * lt;
        let s11 = MU * j.powf(-2.0 / 3.0) * (1.0 - i1 / (3.0 * stretch * stretch))
            + BULK * j * (j - 1.0) / (stretch * stretch);
        let p11 = stretch * s11;
        let mesh = block([0.0; 3], [0.03; 3], [3, 3, 3]);
        let x_max = mesh.node_sets["x_max"].clone();
        let h = 0.01;
        let weight = |c: f64| {
            if c.abs() < 1e-12 || (c - 0.03).abs() < 1e-12 {
                0.5
            } else {
                1.0
            }
        };
        let values = x_max.iter().map(|&n| {
            let x = mesh.nodes[n as usize];
            p11 * h * h * weight(x[1]) * weight(x[2])
        });
        let bc = BoundaryConditions {
            fixed: rollers(&mesh),
            forces: vec![NodalForce {
                values: values.collect(),
                nodes: x_max,
                dof: 0,
                curve: ramp(),
            }],
            ..Default::default()
        };
        let p = problem(mesh, GradientVariant::MeanGradient, bc);
        let res = solve_equilibrium(&p, &StaticOptions::default()).unwrap();
        let err = relative_error(&res.u, &p.mesh.nodes, |x| {
            [(stretch - 1.0) * x[0], (lt - 1.0) * x[1], (lt - 1.0) * x[2]]
        });
        eprintln!(
            "uniaxial (forces): P_11 = {p11:.6e} Pa, {} load steps, {} Newton iterations, \
             residual {:.3e} N of {:.3e} N, max error {err:.3e}",
            res.load_steps, res.newton_iterations, res.residual_norm, res.reaction_scale
        );
        assert!(err < 1e-9, "max relative error {err:.3e}");
    }

    fn rotated_face_problem(angle: f64) -> Problem {
        let mesh = distorted_block([0.0; 3], [0.02; 3], [2, 2, 2], 0.2, 3);
        let bc = BoundaryConditions {
            rotations: vec![PrescribedRotation {
                nodes: mesh.node_sets["x_min"].clone(),
                point: [0.0, 0.01, 0.0],
                axis: [0.0, 0.0, 1.0],
                angle,
                curve: ramp(),
            }],
            ..Default::default()
        };
        problem(mesh, GradientVariant::MeanGradient, bc)
    }

    fn rigid_rotation(angle: f64) -> impl Fn(&[f64; 3]) -> [f64; 3] {
        let r = crate::linalg::rotation_matrix(&[0.0, 0.0, 1.0], angle);
        move |x| {
            let d = [x[0], x[1] - 0.01, x[2]];
            let rd = crate::linalg::mat_vec(&r, &d);
            [rd[0] - d[0], rd[1] - d[1], rd[2] - d[2]]
        }
    }

    #[test]
    fn rotating_one_face_rotates_the_free_body_rigidly() {
        let angle = 1.2;
        let p = rotated_face_problem(angle);
        let res = solve_equilibrium(&p, &StaticOptions::default()).unwrap();
        let err = relative_error(&res.u, &p.mesh.nodes, rigid_rotation(angle));
        eprintln!(
            "rotation {angle} rad: {} load steps, {} Newton iterations, residual {:.3e} N, \
             max error {err:.3e}",
            res.load_steps, res.newton_iterations, res.residual_norm
        );
        assert!(err < 1e-9, "max relative error {err:.3e}");
    }

    #[test]
    fn a_too_large_increment_is_halved() {
        // a half turn in one increment: the first linearised update inverts elements
        let angle = 3.0;
        let p = rotated_face_problem(angle);
        let opts = StaticOptions {
            load_steps: 1,
            ..Default::default()
        };
        let res = solve_equilibrium(&p, &opts).unwrap();
        let err = relative_error(&res.u, &p.mesh.nodes, rigid_rotation(angle));
        eprintln!(
            "rotation {angle} rad in 1 step: {} accepted increments, {} Newton iterations, \
             max error {err:.3e}",
            res.load_steps, res.newton_iterations
        );
        assert!(res.load_steps > 1);
        assert!(err < 1e-9, "max relative error {err:.3e}");
    }

    #[test]
    fn failure_names_the_load_factor() {
        let p = rotated_face_problem(1.0);
        let opts = StaticOptions {
            load_steps: 1,
            max_iterations: 1,
            tolerance: 1e-10,
        };
        let err = solve_equilibrium(&p, &opts).unwrap_err();
        let msg = err.to_string();
        eprintln!("{msg}");
        assert!(matches!(err, Error::NotConverged(_)));
        assert!(
            msg.contains("load factor")
                && msg.contains("Newton iteration")
                && msg.contains("residual"),
            "{msg}"
        );
    }

    #[test]
    fn unloaded_problem_is_at_rest() {
        let mesh = block([0.0; 3], [0.01; 3], [1, 1, 1]);
        let bc = BoundaryConditions {
            fixed: rollers(&mesh),
            ..Default::default()
        };
        let p = problem(mesh, GradientVariant::Centroid, bc);
        let res = solve_equilibrium(&p, &StaticOptions::default()).unwrap();
        assert!(res.u.iter().flatten().all(|&v| v == 0.0));
        assert_eq!(res.newton_iterations, 0);
        assert_eq!(res.residual_norm, 0.0);
    }
}
