//! The explicit TLED run: one [`Simulation`] per run, advanced one step at a time.
//!
//! One step (iteration `s`, from `t_s = s dt` to `t_{s+1}`):
//! 1. `element_forces`: `F_int` blocks from `u_s`, stop if an element inverted;
//! 2. `saliva_forces`: the breaking rule (eq. 11) on every saliva element's block;
//! 3. external forces `R_s` at `t_s` (loads, gravity, muscles);
//! 4. `node_update`: central differences for every DOF;
//! 5. `apply_constraints`: fixed, prescribed and rotated DOFs set at `t_{s+1}`;
//! 6. buffers rotate.

use crate::boundary::LoadCurve;
use crate::error::{Error, Result};
use crate::problem::Problem;
use crate::real::Real;
use crate::tled::element_forces::{element_forces, ElementArrays};
use crate::tled::node_update::{gather_all, node_update, CentralDifference};
use crate::tled::precompute::Discretisation;
use crate::tled::saliva_forces::{saliva_forces, SalivaState};
use crate::tled::simd::SimdReal;
use crate::tled::subcycle::{diverged, substeps, Subcycling};

/// The solver's state after `step` iterations, every value as `f64` (exact for `f32`).
#[derive(Clone, Debug, PartialEq)]
pub struct SolverState {
    pub step: usize,
    /// Displacement at `step` and at `step - 1` (m), per node.
    pub u: Vec<[f64; 3]>,
    pub u_prev: Vec<[f64; 3]>,
    /// Per saliva element: the modified force of the last step (eq. 11's `F_{s-1}`).
    pub saliva_previous: Vec<[[f64; 3]; 8]>,
    pub broken: Vec<bool>,
    /// Time of the first breaking (s), NaN if never.
    pub broken_at: Vec<f64>,
    /// The last step's moisture (um), breaking point Z and stretch Q.
    pub moisture: Vec<f64>,
    pub z: Vec<f64>,
    pub q: Vec<f64>,
}

impl SolverState {
    /// Every number of the state in a fixed order (the checkpoint file's order).
    pub fn numbers(&self) -> impl Iterator<Item = f64> + '_ {
        let nodes = self.u.iter().chain(&self.u_prev).flatten().copied();
        let previous = self.saliva_previous.iter().flatten().flatten().copied();
        let saliva = self
            .broken_at
            .iter()
            .chain(&self.moisture)
            .chain(&self.z)
            .chain(&self.q)
            .copied();
        nodes.chain(previous).chain(saliva)
    }
}

/// Energies of a state (J).
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct Energies {
    pub kinetic: f64,
    pub strain: f64,
}

pub struct Simulation<T: Real> {
    pub disc: Discretisation,
    reference: Vec<[f64; 3]>,
    el: ElementArrays<T>,
    cd: CentralDifference<T>,
    u: Vec<[T; 3]>,
    u_prev: Vec<[T; 3]>,
    u_next: Vec<[T; 3]>,
    elem_f: Vec<[[T; 3]; 8]>,
    r_ext: Vec<[T; 3]>,
    saliva: SalivaState<T>,
    /// Scratch for `apply_constraints_into` (no allocation inside a step).
    prescribed_acc: Vec<f64>,
    step: usize,
    num_steps: usize,
    dt: f64,
    total_time: f64,
    niftysim_timing: bool,
    /// The saliva layer's partition when it is subcycled (`numerics.subcycles > 1`).
    sub: Option<Box<Subcycling<T>>>,
}

impl<T: SimdReal> Simulation<T> {
    /// Validates the problem and precomputes everything. Starts from rest, `u = 0`.
    pub fn new(problem: &Problem) -> Result<Self> {
        problem.validate()?;
        let disc = Discretisation::new(problem);
        let nn = disc.num_nodes;
        let ne = disc.num_elements();
        let el = ElementArrays::from_discretisation(&disc);
        let cd = CentralDifference::new(problem.time.dt, problem.numerics.damping, &disc.mass);
        let k = problem.numerics.subcycles;
        let sub = (k > 1).then(|| {
            Box::new(Subcycling::new(
                &disc,
                &el,
                k,
                problem.time.dt,
                problem.numerics.damping,
            ))
        });
        let saliva = match &sub {
            Some(s) => s.saliva_start.clone(),
            None => SalivaState::new(&disc.saliva),
        };
        Ok(Simulation {
            reference: problem.mesh.nodes.clone(),
            el,
            cd,
            u: vec![[T::ZERO; 3]; nn],
            u_prev: vec![[T::ZERO; 3]; nn],
            u_next: vec![[T::ZERO; 3]; nn],
            elem_f: vec![[[T::ZERO; 3]; 8]; ne],
            r_ext: vec![[T::ZERO; 3]; nn],
            saliva,
            prescribed_acc: Vec::with_capacity(disc.constraints.prescribed_dofs.len()),
            step: 0,
            num_steps: problem.num_steps(),
            dt: problem.time.dt,
            total_time: problem.time.total_time,
            niftysim_timing: problem.numerics.niftysim_timing,
            sub,
            disc,
        })
    }

    /// Iterations executed so far.
    pub fn step_index(&self) -> usize {
        self.step
    }
    /// Iterations the run executes in all.
    pub fn num_steps(&self) -> usize {
        self.num_steps
    }
    /// Time of the current displacement (s).
    pub fn time(&self) -> f64 {
        self.step as f64 * self.dt
    }
    pub fn dt(&self) -> f64 {
        self.dt
    }
    pub fn is_finished(&self) -> bool {
        self.step >= self.num_steps
    }
    pub fn num_elements(&self) -> usize {
        self.el.len()
    }
    pub fn displacement(&self) -> &[[T; 3]] {
        &self.u
    }
    pub fn previous_displacement(&self) -> &[[T; 3]] {
        &self.u_prev
    }
    pub fn displacement_f64(&self) -> Vec<[f64; 3]> {
        self.u.iter().map(|v| v.map(T::to_f64)).collect()
    }

    /// Sets the current displacement and the previous one (an initial condition:
    /// `u_prev = u - dt v0` gives initial velocity `v0`).
    pub fn set_state(&mut self, u: &[[f64; 3]], u_prev: &[[f64; 3]]) {
        for (d, s) in self.u.iter_mut().zip(u) {
            *d = s.map(T::from_f64);
        }
        for (d, s) in self.u_prev.iter_mut().zip(u_prev) {
            *d = s.map(T::from_f64);
        }
    }

    /// Everything the next steps depend on (for a checkpoint), as `f64` (exact for `f32`).
    pub fn checkpoint_state(&self) -> SolverState {
        let s = &self.saliva;
        SolverState {
            step: self.step,
            u: self.displacement_f64(),
            u_prev: self.u_prev.iter().map(|v| v.map(T::to_f64)).collect(),
            saliva_previous: s
                .previous
                .iter()
                .map(|b| b.map(|r| r.map(T::to_f64)))
                .collect(),
            broken: s.broken.clone(),
            broken_at: s.broken_at.clone(),
            moisture: s.moisture.clone(),
            z: s.z.clone(),
            q: s.q.clone(),
        }
    }

    /// Continues from a state of [`Simulation::checkpoint_state`] of the same problem and
    /// precision: the following steps give the same bits as if the run had not stopped.
    pub fn restore(&mut self, state: &SolverState) -> Result<()> {
        let ns = self.saliva.broken.len();
        let saliva_lengths = [
            state.saliva_previous.len(),
            state.broken.len(),
            state.broken_at.len(),
            state.moisture.len(),
            state.z.len(),
            state.q.len(),
        ];
        if state.u.len() != self.u.len()
            || state.u_prev.len() != self.u.len()
            || saliva_lengths.iter().any(|&l| l != ns)
            || state.step > self.num_steps
        {
            return Err(Error::input(
                "checkpoint",
                crate::error::Location::None,
                format!(
                    "the state ({} nodes, {} saliva elements, step {}) does not fit this model ({} nodes, {ns} saliva elements, {} steps)",
                    state.u.len(),
                    state.broken.len(),
                    state.step,
                    self.u.len(),
                    self.num_steps
                ),
            ));
        }
        let narrow =
            |v: &[[f64; 3]]| -> Vec<[T; 3]> { v.iter().map(|x| x.map(T::from_f64)).collect() };
        self.u = narrow(&state.u);
        self.u_prev = narrow(&state.u_prev);
        let s = &mut self.saliva;
        s.previous = state
            .saliva_previous
            .iter()
            .map(|b| b.map(|r| r.map(T::from_f64)))
            .collect();
        s.broken.clone_from(&state.broken);
        s.broken_at.clone_from(&state.broken_at);
        s.moisture.clone_from(&state.moisture);
        s.z.clone_from(&state.z);
        s.q.clone_from(&state.q);
        self.step = state.step;
        Ok(())
    }

    /// Substeps per step (1: single rate).
    pub fn subcycles(&self) -> usize {
        self.sub.as_ref().map_or(1, |s| s.k())
    }

    /// Advances one iteration. On divergence the state is left as it was before the step.
    pub fn step(&mut self) -> Result<()> {
        if self.sub.is_some() {
            return self.step_subcycled();
        }
        let s = self.step;
        let t = s as f64 * self.dt;
        if let Some(e) = element_forces(&self.el, &self.u, &mut self.elem_f) {
            return Err(Error::Diverged {
                step: s,
                time: t,
                element: Some(e),
                node: None,
                reason: "element inverted or degenerate (det F <= 0 or not finite)".into(),
            });
        }
        if !self.disc.saliva.elements.is_empty() {
            saliva_forces(
                &self.disc.saliva,
                &mut self.saliva,
                &self.el,
                &self.u,
                &mut self.elem_f,
                t,
            );
        }
        let has_loads = !self.disc.loads.is_empty();
        if has_loads {
            self.assemble_external(s);
        }
        let r = has_loads.then_some(self.r_ext.as_slice());
        if let Some(n) = node_update(
            &self.disc.gather,
            &self.cd,
            &self.elem_f,
            r,
            &self.u,
            &self.u_prev,
            &mut self.u_next,
        ) {
            return Err(Error::Diverged {
                step: s,
                time: t,
                element: None,
                node: Some(n),
                reason: "non-finite displacement".into(),
            });
        }
        let (t_next, clamp) = self.constraint_time(s + 1);
        apply_constraints_into(
            &self.disc,
            &self.reference,
            &mut self.u_next,
            t_next,
            clamp,
            &mut self.prescribed_acc,
        );
        std::mem::swap(&mut self.u_prev, &mut self.u);
        std::mem::swap(&mut self.u, &mut self.u_next);
        self.step += 1;
        Ok(())
    }

    /// One step of `dt` with the saliva layer's nodes in `k` substeps (`tled::subcycle`).
    fn step_subcycled(&mut self) -> Result<()> {
        let mut sub = self.sub.take().expect("subcycled");
        let r = self.step_subcycled_with(&mut sub);
        self.sub = Some(sub);
        r
    }

    fn step_subcycled_with(&mut self, sub: &mut Subcycling<T>) -> Result<()> {
        use crate::tled::node_update::node_update_listed;
        let s = self.step;
        let dt = self.dt;
        let t = s as f64 * dt;
        // 1. the slow elements' forces at t_n
        if let Some(e) = element_forces(&sub.slow_el, &self.u, &mut sub.slow_f) {
            return Err(diverged(s, t, Some(sub.slow_ids[e] as usize), None));
        }
        let has_loads = !self.disc.loads.is_empty();
        if has_loads {
            self.assemble_external_at(t);
        }
        // 2a. the interface nodes' u(t_n + dt) first, constraints applied: the substeps
        // interpolate them (the same operations as the pass over every node in 2b)
        let r = has_loads.then_some(self.r_ext.as_slice());
        if node_update_listed(
            &sub.fast.interface,
            &sub.slow_gather,
            &self.cd,
            &sub.slow_f,
            r,
            &self.u,
            &self.u_prev,
            &mut sub.interface_next,
        )
        .is_some()
        {
            // reported as the pass over every node reports it: its smallest bad node
            let n = node_update(
                &sub.slow_gather,
                &self.cd,
                &sub.slow_f,
                r,
                &self.u,
                &self.u_prev,
                &mut self.u_next,
            );
            return Err(diverged(s, t, None, n));
        }
        for (&n, v) in sub.fast.interface.iter().zip(&sub.interface_next) {
            sub.fast.interface_end[n as usize] = *v;
        }
        apply_plan_into(
            &sub.interface_constraints,
            &self.reference,
            &mut sub.fast.interface_end,
            t + dt,
            true,
            &mut sub.interface_acc,
        );
        // the substeps' own copy of the fast elements' nodes at t_n
        for (i, &n) in sub.fast.interface.iter().enumerate() {
            sub.fast.interface_start[i] = self.u[n as usize];
            sub.fast.u[n as usize] = self.u[n as usize];
        }
        for &n in &sub.fast.nodes {
            sub.fast.u[n as usize] = self.u[n as usize];
            sub.fast.u_prev[n as usize] = self.u_prev[n as usize];
        }
        sub.saliva_start.copy_from(&self.saliva);
        // 2b. every node's u(t_n + dt) from the slow forces (the fast nodes' values unused),
        // beside the fast nodes' k substeps: they share nothing they write
        let Simulation {
            disc,
            reference,
            cd,
            u,
            u_prev,
            u_next,
            r_ext,
            saliva,
            prescribed_acc,
            ..
        } = self;
        let Subcycling {
            slow_gather,
            slow_f,
            ..
        } = sub;
        let (slow, fast) = rayon::join(
            || {
                let r = has_loads.then_some(r_ext.as_slice());
                let bad = node_update(slow_gather, cd, slow_f, r, u, u_prev, u_next);
                apply_constraints_into(disc, reference, u_next, t + dt, true, prescribed_acc);
                bad
            },
            || substeps(&mut sub.fast, disc, reference, saliva, s, t, dt),
        );
        if let Some(n) = slow {
            self.saliva.copy_from(&sub.saliva_start);
            return Err(diverged(s, t, None, Some(n)));
        }
        if let Err(e) = fast {
            self.saliva.copy_from(&sub.saliva_start);
            return Err(e);
        }
        // 3. every node to t_n + dt: the buffers rotate (u_prev <- u <- u_next) as in a
        // single-rate step, then the fast nodes take the substeps' state
        std::mem::swap(&mut self.u_prev, &mut self.u);
        std::mem::swap(&mut self.u, &mut self.u_next);
        for &n in &sub.fast.nodes {
            let n = n as usize;
            self.u[n] = sub.fast.u[n];
            self.u_prev[n] = sub.fast.u_prev[n];
        }
        self.step += 1;
        Ok(())
    }

    /// External forces at time `t` (s), curves clamped (not under NiftySim's timing: a
    /// subcycled run refuses it).
    fn assemble_external_at(&mut self, t: f64) {
        self.fill_external(|curve| curve.value(t, true));
    }

    fn constraint_time(&self, s: usize) -> (f64, bool) {
        constraint_time(s, self.dt, self.niftysim_timing)
    }

    fn assemble_external(&mut self, s: usize) {
        let (dt, nifty) = (self.dt, self.niftysim_timing);
        self.fill_external(|curve| load_value(curve, s, dt, nifty));
    }

    /// `R = sum_g value(curve_g) r_g` into `r_ext`.
    fn fill_external(&mut self, value: impl Fn(&LoadCurve) -> f64) {
        fill_loads_with(&self.disc, value, &mut self.r_ext);
    }

    /// The saliva elements' state after the last step.
    pub fn saliva(&self) -> &SalivaState<T> {
        &self.saliva
    }

    /// Internal nodal forces at the current state (N), reactions at constrained DOFs included.
    /// Saliva elements contribute the force of the last step's breaking rule.
    pub fn internal_forces(&mut self) -> Vec<[f64; 3]> {
        element_forces(&self.el, &self.u, &mut self.elem_f);
        for (k, &e) in self.disc.saliva.elements.iter().enumerate() {
            if self.saliva.broken[k] {
                self.elem_f[e as usize] = self.saliva.previous[k];
            }
        }
        gather_all(&self.disc.gather, &self.elem_f, self.disc.num_nodes)
            .into_iter()
            .map(|f| f.map(T::to_f64))
            .collect()
    }

    /// Kinetic energy from the backward difference `(u_n - u_{n-1}) / dt`, strain energy
    /// including the hourglass part, both in `f64`.
    pub fn energies(&self) -> Energies {
        let u = self.displacement_f64();
        let mut kinetic = 0.0;
        for n in 0..self.disc.num_nodes {
            // a subcycled run's fast nodes hold their previous substep
            let dt = match &self.sub {
                Some(sub) if sub.is_fast[n] => sub.substep(self.dt),
                _ => self.dt,
            };
            let mut v2 = 0.0;
            for k in 0..3 {
                let v = (self.u[n][k].to_f64() - self.u_prev[n][k].to_f64()) / dt;
                v2 += v * v;
            }
            kinetic += 0.5 * self.disc.mass[n] * v2;
        }
        Energies {
            kinetic,
            strain: strain_energy(&self.disc, &u),
        }
    }

    pub fn total_time(&self) -> f64 {
        self.total_time
    }
}

/// The time at which load curves are evaluated for iteration index `s`, and whether to
/// clamp. NiftySim's timing is relative time `s dt / T` unclamped, i.e. the same absolute
/// time when curves span the whole run. Shared by both backends.
pub fn constraint_time(s: usize, dt: f64, niftysim_timing: bool) -> (f64, bool) {
    (s as f64 * dt, !niftysim_timing)
}

/// The value of a load curve that iteration `s` applies to its external loads. NiftySim's
/// forces lag: iteration `s` uses the value at `s dt`, and zero at `s = 0`. Shared by both
/// backends.
pub fn load_value(curve: &LoadCurve, s: usize, dt: f64, niftysim_timing: bool) -> f64 {
    if niftysim_timing && s == 0 {
        return 0.0;
    }
    let (t, clamp) = constraint_time(s, dt, niftysim_timing);
    curve.value(t, clamp)
}

/// `R = sum_g value(curve_g) r_g` of `d`'s loads into `r`.
fn fill_loads_with<T: Real>(
    d: &Discretisation,
    value: impl Fn(&LoadCurve) -> f64,
    r: &mut [[T; 3]],
) {
    for x in r.iter_mut() {
        *x = [T::ZERO; 3];
    }
    for g in &d.loads {
        let c = value(&g.curve);
        for &(dof, v) in &g.entries {
            r[dof as usize / 3][dof as usize % 3] += T::from_f64(v * c);
        }
    }
}

/// The external forces of `d` at time `t` (s), curves clamped, into `r` (a subcycled run's
/// substeps; NiftySim's timing is refused there).
pub fn fill_loads<T: Real>(d: &Discretisation, t: f64, r: &mut [[T; 3]]) {
    fill_loads_with(d, |curve| curve.value(t, true), r);
}

/// Sets every constrained DOF of `u` at time `t`: fixed DOFs to zero, prescribed DOFs to
/// the sum of their prescribed values, rotated nodes to the rigid rotation.
pub fn apply_constraints<T: Real>(
    d: &Discretisation,
    reference: &[[f64; 3]],
    u: &mut [[T; 3]],
    t: f64,
    clamp: bool,
) {
    apply_constraints_into(d, reference, u, t, clamp, &mut Vec::new());
}

/// [`apply_constraints`] with a caller-owned accumulator (`acc`, resized as needed), so
/// that a step allocates nothing.
pub fn apply_constraints_into<T: Real>(
    d: &Discretisation,
    reference: &[[f64; 3]],
    u: &mut [[T; 3]],
    t: f64,
    clamp: bool,
    acc: &mut Vec<f64>,
) {
    apply_plan_into(&d.constraints, reference, u, t, clamp, acc);
}

/// [`apply_constraints_into`] for a constraint plan of its own (subcycling's fast nodes).
pub fn apply_plan_into<T: Real>(
    c: &crate::tled::precompute::ConstraintPlan,
    reference: &[[f64; 3]],
    u: &mut [[T; 3]],
    t: f64,
    clamp: bool,
    acc: &mut Vec<f64>,
) {
    for &k in &c.fixed {
        u[k as usize / 3][k as usize % 3] = T::ZERO;
    }
    if !c.prescribed.is_empty() {
        // accumulate in f64 per DOF (groups and entries in order), then round once
        acc.clear();
        acc.resize(c.prescribed_dofs.len(), 0.0);
        for (curve, entries) in &c.prescribed {
            let s = curve.value(t, clamp);
            for &(k, v) in entries {
                let i = c
                    .prescribed_dofs
                    .binary_search(&k)
                    .expect("prescribed dof planned");
                acc[i] += v * s;
            }
        }
        for (&k, &v) in c.prescribed_dofs.iter().zip(acc.iter()) {
            u[k as usize / 3][k as usize % 3] = T::from_f64(v);
        }
    }
    for r in &c.rotations {
        let m = r.matrix(t, clamp);
        for &n in &r.nodes {
            let du = r.displacement_by(&m, &reference[n as usize]);
            u[n as usize] = du.map(T::from_f64);
        }
    }
}

/// Displacement gradient `H = sum_a u_a (x) D_a` of element `e` in `f64`.
pub fn displacement_gradient(d: &Discretisation, u: &[[f64; 3]], e: usize) -> [[f64; 3]; 3] {
    let mut h = [[0.0; 3]; 3];
    for a in 0..8 {
        let ua = u[d.conn[e][a] as usize];
        for i in 0..3 {
            for j in 0..3 {
                h[i][j] += ua[i] * d.dhdx[e][a][j];
            }
        }
    }
    h
}

/// `J = det F = det(I + H)` of every element at the element's gradient point (input element
/// order), as the frames' `volume_ratio` records it.
pub fn volume_ratios(d: &Discretisation, u: &[[f64; 3]]) -> Vec<f64> {
    (0..d.num_elements())
        .map(|e| 1.0 + crate::linalg::det_identity_plus_minus_one(&displacement_gradient(d, u, e)))
        .collect()
}

/// Stored energy of the discretisation (J): `sum_e W_e Psi(H_e) + k_e/2 sum_alpha |h_alpha|^2`.
/// Its gradient with respect to `u` is exactly the internal force of eq. (4).
pub fn strain_energy(d: &Discretisation, u: &[[f64; 3]]) -> f64 {
    let per: Vec<f64> = (0..d.num_elements())
        .map(|e| element_energy(d, u, e))
        .collect();
    per.iter().sum()
}

/// Energy of one element (J), elastic and hourglass parts.
pub fn element_energy(d: &Discretisation, u: &[[f64; 3]], e: usize) -> f64 {
    let h = displacement_gradient(d, u, e);
    let psi = crate::material::neo_hookean::strain_energy_density(&h, d.mu[e], d.bulk[e]);
    let mut hg = 0.0;
    for alpha in 0..4 {
        let mut v = [0.0; 3];
        for b in 0..8 {
            let ub = u[d.conn[e][b] as usize];
            for i in 0..3 {
                v[i] += d.gamma[e][b][alpha] * ub[i];
            }
        }
        hg += v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    }
    d.weight[e] * psi + 0.5 * d.hg_k[e] * hg
}
