//! Stage `saliva_forces`, between `element_forces` and `node_update`: the breaking rule of
//! paper eq. (11) applied to the force block of every saliva element, with its moisture
//! (eq. 6), breaking point (eq. 7) and stretch across the layer (eqs. 8-10) at this step.
//! The equations themselves live in `material::saliva`; this stage holds their state.

use crate::material::saliva::{apply_breaking_rule, breaking_point, stretch_across};
use crate::real::Real;
use crate::tled::element_forces::ElementArrays;
use crate::tled::precompute::SalivaPlan;

/// Saliva state carried from step to step, in saliva-element order.
#[derive(Clone, Debug)]
pub struct SalivaState<T> {
    across: Vec<[T; 3]>,
    decay: Vec<T>,
    /// Evaporated depth per group at the current step (um); kept here so the step
    /// allocates nothing.
    pub(crate) evaporated: Vec<f64>,
    /// The modified force `F` of the previous step (8x3 per element).
    pub previous: Vec<[[T; 3]; 8]>,
    /// Broken at the last step (for `literal`: `Q >= Z` now; for `latched`: ever).
    pub broken: Vec<bool>,
    /// Time (s) at which the element first broke, NaN if never.
    pub broken_at: Vec<f64>,
    /// Last step's moisture (um), breaking point `Z` and stretch `Q`.
    pub moisture: Vec<f64>,
    pub z: Vec<f64>,
    pub q: Vec<f64>,
}

impl<T: Real> SalivaState<T> {
    pub fn new(plan: &SalivaPlan) -> Self {
        let n = plan.elements.len();
        SalivaState {
            across: plan.across.iter().map(|a| a.map(T::from_f64)).collect(),
            decay: plan.decay_factor.iter().map(|&f| T::from_f64(f)).collect(),
            evaporated: vec![0.0; plan.groups.len()],
            previous: vec![[[T::ZERO; 3]; 8]; n],
            broken: vec![false; n],
            broken_at: vec![f64::NAN; n],
            moisture: plan.initial_moisture.clone(),
            z: (0..n)
                .map(|k| {
                    let g = &plan.groups[plan.group[k] as usize];
                    breaking_point(plan.initial_moisture[k], g.critical_moisture, g.k_glue)
                })
                .collect(),
            q: vec![1.0; n],
        }
    }

    /// Copies `other`'s state into `self` (same plan) without allocating.
    pub fn copy_from(&mut self, other: &Self) {
        self.previous.copy_from_slice(&other.previous);
        self.broken.copy_from_slice(&other.broken);
        self.broken_at.copy_from_slice(&other.broken_at);
        self.moisture.copy_from_slice(&other.moisture);
        self.z.copy_from_slice(&other.z);
        self.q.copy_from_slice(&other.q);
    }

    pub fn broken_count(&self) -> usize {
        self.broken.iter().filter(|b| **b).count()
    }
}

/// Applies eq. (11) to every saliva element's block in `elem_f`, at time `t` (s).
pub fn saliva_forces<T: Real>(
    plan: &SalivaPlan,
    state: &mut SalivaState<T>,
    el: &ElementArrays<T>,
    u: &[[T; 3]],
    elem_f: &mut [[[T; 3]; 8]],
    t: f64,
) {
    plan.evaporated_into(t, &mut state.evaporated);
    for k in 0..plan.elements.len() {
        let e = plan.elements[k] as usize;
        let g = plan.group[k] as usize;
        let params = &plan.groups[g];
        let conn = &el.conn[e];
        let d = &el.dhdx[e];
        let mut h = [[T::ZERO; 3]; 3];
        for a in 0..8 {
            let ua = u[conn[a] as usize];
            for i in 0..3 {
                for j in 0..3 {
                    h[i][j] += ua[i] * d[a][j];
                }
            }
        }
        let q = stretch_across(&h, &state.across[k]);
        let (m, z) = plan.moisture_and_breaking_point(k, state.evaporated[g], t);
        let broken = apply_breaking_rule(
            q,
            T::from_f64(z),
            params.rule,
            state.decay[g],
            state.broken[k],
            &mut elem_f[e],
            &mut state.previous[k],
        );
        if broken && state.broken_at[k].is_nan() {
            state.broken_at[k] = t;
        }
        state.broken[k] = broken;
        state.moisture[k] = m;
        state.z[k] = z;
        state.q[k] = q.to_f64();
    }
}
