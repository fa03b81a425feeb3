//! Subcycling of the saliva layer: nodal-partition subcycling of central differences
//! (Belytschko, Yen & Mullen 1979, "Mixed methods for time integration", Comput. Methods
//! Appl. Mech. Eng. 17/18), the slow nodes at the interface interpolated linearly in time.
//! Undamped, its energy was measured to grow slowly at large steps above about 2.5 times the
//! whole model's critical step (`paper/README.md`, "Subcycling"); `subcycles = "auto"` stays
//! at twice it.
//!
//! The saliva elements are far stiffer than the tissue for their size: they alone set the
//! critical step of the paper's scene (Table 1's dt is 17 % of it; the tissue alone allows
//! about 3.5 times the saliva's limit). The nodes are split in two:
//! - **fast** nodes: every node of a saliva element. They advance by paper eq. (3) with the
//!   small step `dt / k`, from the forces of the elements that touch them (the saliva
//!   elements, whose forces go through the breaking rule of eq. (11) at every substep, and the
//!   tissue elements at the lips' edge);
//! - **slow** nodes: all others. They advance by eq. (3) with the large step `dt`, from the
//!   forces of the elements that touch them at the start of the step (tissue only).
//!
//! One large step `t_n -> t_n + dt`:
//! 1. the slow nodes' `u(t_n + dt)` from the forces at `t_n`, constraints applied at `t_n + dt`;
//! 2. `k` substeps `t_j = t_n + j dt/k` of the fast nodes; the slow nodes that fast elements
//!    touch (the interface) take `u(t_n) + (j / k) (u(t_n + dt) - u(t_n))`, linear in time;
//! 3. the slow nodes move to `t_n + dt`.
//!
//! `run` checks each partition against its own limit: `dt / k` against the whole model's
//! critical step, `dt` against that of the model without the saliva's stiffness
//! (`tled::stability`). With `k = 1` it is the single-rate scheme exactly. The partition is fixed: saliva elements that
//! break keep their nodes fast (their forces decay by eq. 11 at the small step).
//!
//! Verified by `verification/subcycling.rs`: no energy growth over a long undamped run at 1.8
//! times the critical step, order 2 towards the single-rate solution as the steps shrink, the
//! same bits on any thread count and after a restore.

use crate::mesh::NodeGather;
use crate::real::Real;
use crate::tled::element_forces::ElementArrays;
use crate::tled::node_update::CentralDifference;
use crate::tled::precompute::{ConstraintPlan, Discretisation, SalivaPlan};
use crate::tled::saliva_forces::SalivaState;

pub use crate::problem::MAX_SUBCYCLES;

/// The two partitions of a subcycled run, in the stepping precision.
#[derive(Clone, Debug)]
pub struct Subcycling<T> {
    /// Substeps per step (`k >= 2`).
    pub k: usize,
    /// Node lists (increasing).
    pub fast_nodes: Vec<u32>,
    pub slow_nodes: Vec<u32>,
    /// Slow nodes that a fast element touches (increasing), interpolated during substeps.
    pub interface: Vec<u32>,
    pub is_fast: Vec<bool>,
    /// Elements touching a slow node (global indices, increasing) and their arrays.
    pub slow_ids: Vec<u32>,
    pub slow_el: ElementArrays<T>,
    pub slow_gather: NodeGather,
    /// Elements touching a fast node and their arrays; the saliva plan indexed into them.
    pub fast_ids: Vec<u32>,
    pub fast_el: ElementArrays<T>,
    pub fast_gather: NodeGather,
    pub fast_saliva: SalivaPlan,
    pub fast_constraints: ConstraintPlan,
    /// Central-difference coefficients of the substep `dt / k`.
    pub fast_cd: CentralDifference<T>,
    /// Scratch: force blocks of each partition, the fast nodes' new displacements, the
    /// interface's start values, and the fast nodes' state at the step's start (restored on
    /// divergence).
    pub slow_f: Vec<[[T; 3]; 8]>,
    pub fast_f: Vec<[[T; 3]; 8]>,
    pub fast_next: Vec<[T; 3]>,
    pub interface_start: Vec<[T; 3]>,
    pub fast_u_start: Vec<[T; 3]>,
    pub fast_u_prev_start: Vec<[T; 3]>,
    /// The saliva state at the step's start (restored on divergence); built from the fast
    /// plan, it is also the run's initial state (eq. 11's decay per substep).
    pub saliva_start: SalivaState<T>,
}

/// Elements (global indices, increasing) with at least one node for which `pick` is true.
fn elements_touching(conn: &[[u32; 8]], pick: impl Fn(usize) -> bool) -> Vec<u32> {
    (0..conn.len() as u32)
        .filter(|&e| conn[e as usize].iter().any(|&n| pick(n as usize)))
        .collect()
}

impl<T: Real> Subcycling<T> {
    /// The partition of `d` with `k` substeps per step `dt`, damping `alpha` (1/s). `el`: the
    /// whole model's element arrays. The caller has checked that `d` has saliva elements.
    pub fn new(d: &Discretisation, el: &ElementArrays<T>, k: usize, dt: f64, alpha: f64) -> Self {
        let nn = d.num_nodes;
        let mut is_fast = vec![false; nn];
        for &e in &d.saliva.elements {
            for &n in &d.conn[e as usize] {
                is_fast[n as usize] = true;
            }
        }
        let fast_nodes: Vec<u32> = (0..nn as u32).filter(|&n| is_fast[n as usize]).collect();
        let slow_nodes: Vec<u32> = (0..nn as u32).filter(|&n| !is_fast[n as usize]).collect();
        let fast_ids = elements_touching(&d.conn, |n| is_fast[n]);
        let slow_ids = elements_touching(&d.conn, |n| !is_fast[n]);
        let mut on_interface = vec![false; nn];
        for &e in &fast_ids {
            for &n in &d.conn[e as usize] {
                on_interface[n as usize] = !is_fast[n as usize];
            }
        }
        let interface: Vec<u32> = (0..nn as u32)
            .filter(|&n| on_interface[n as usize])
            .collect();
        let slow_el = el.subset(&slow_ids);
        let fast_el = el.subset(&fast_ids);
        let slow_gather = NodeGather::new(nn, &slow_el.conn);
        let fast_gather = NodeGather::new(nn, &fast_el.conn);
        // the saliva plan with its elements numbered in the fast arrays, eq. 11's decay per
        // substep
        let mut fast_saliva = d.saliva.clone();
        for e in fast_saliva.elements.iter_mut() {
            *e = fast_ids.binary_search(e).expect("a saliva element is fast") as u32;
        }
        let h = dt / k as f64;
        fast_saliva.decay_factor = fast_saliva
            .groups
            .iter()
            .map(|g| g.decay.factor(h))
            .collect();
        let (nf, ni) = (fast_nodes.len(), interface.len());
        Subcycling {
            k,
            fast_constraints: d.constraints.restricted_to(&is_fast),
            fast_cd: CentralDifference::new(h, alpha, &d.mass),
            slow_f: vec![[[T::ZERO; 3]; 8]; slow_el.len()],
            fast_f: vec![[[T::ZERO; 3]; 8]; fast_el.len()],
            fast_next: vec![[T::ZERO; 3]; nf],
            interface_start: vec![[T::ZERO; 3]; ni],
            fast_u_start: vec![[T::ZERO; 3]; nf],
            fast_u_prev_start: vec![[T::ZERO; 3]; nf],
            saliva_start: SalivaState::new(&fast_saliva),
            fast_nodes,
            slow_nodes,
            interface,
            is_fast,
            slow_ids,
            slow_el,
            slow_gather,
            fast_ids,
            fast_el,
            fast_gather,
            fast_saliva,
        }
    }

    /// The substep `dt / k` (s).
    pub fn substep(&self, dt: f64) -> f64 {
        dt / self.k as f64
    }
}
