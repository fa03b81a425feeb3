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
//! In the code ([`crate::tled::Simulation::step`]) the interface nodes' `u(t_n + dt)` are
//! computed first; then the pass over every other node and the substeps run side by side
//! (`rayon::join`): the substeps advance their own copy of the fast elements' nodes
//! ([`FastPart`]), so that the two share nothing they write. The operations, and so the bits,
//! are those of the sequential order above, on any thread count. On the paper's scene (2
//! threads, f32) that and advancing every node into the step's output buffer took the
//! stepping from 1.50 s to 0.86 s (`benches/README.md`).
//!
//! `run` checks each partition against its own limit: `dt / k` against the whole model's
//! critical step, `dt` against that of the model without the saliva's stiffness
//! (`tled::stability`). With `k = 1` it is the single-rate scheme exactly. The partition is fixed: saliva elements that
//! break keep their nodes fast (their forces decay by eq. 11 at the small step).
//!
//! Verified by `verification/subcycling.rs`: no energy growth over a long undamped run at 1.8
//! times the critical step, order 2 towards the single-rate solution as the steps shrink, the
//! same bits on any thread count and after a restore.

use crate::error::{Error, Result};
use crate::mesh::NodeGather;
use crate::real::Real;
use crate::tled::element_forces::{element_forces, ElementArrays};
use crate::tled::node_update::{node_update_listed, CentralDifference};
use crate::tled::precompute::{ConstraintPlan, Discretisation, SalivaPlan};
use crate::tled::saliva_forces::{saliva_forces, SalivaState};
use crate::tled::solver::apply_plan_into;

pub use crate::problem::MAX_SUBCYCLES;

/// The two partitions of a subcycled run, in the stepping precision.
#[derive(Clone, Debug)]
pub struct Subcycling<T> {
    /// Per node: a node of a saliva element (the substeps' own nodes are `fast.nodes`).
    pub is_fast: Vec<bool>,
    /// Elements touching a slow node (global indices, increasing) and their arrays.
    pub slow_ids: Vec<u32>,
    pub slow_el: ElementArrays<T>,
    pub slow_gather: NodeGather,
    /// Scratch: the slow elements' force blocks, the interface nodes' new displacements
    /// (listed), and the constraints restricted to the interface nodes with their accumulator.
    pub slow_f: Vec<[[T; 3]; 8]>,
    pub interface_next: Vec<[T; 3]>,
    pub interface_constraints: ConstraintPlan,
    pub interface_acc: Vec<f64>,
    /// The saliva state at the step's start (restored on divergence); built from the fast
    /// plan, it is also the run's initial state (eq. 11's decay per substep).
    pub saliva_start: SalivaState<T>,
    /// What the substeps use and change: nothing in it is read by the slow pass, so the two
    /// run side by side.
    pub fast: FastPart<T>,
}

/// The fast partition: its elements and nodes, and the substeps' own copy of the state.
#[derive(Clone, Debug)]
pub struct FastPart<T> {
    /// Substeps per step (`k >= 2`).
    pub k: usize,
    /// The fast nodes, and the slow nodes that a fast element touches (the interface,
    /// interpolated during the substeps); both increasing.
    pub nodes: Vec<u32>,
    pub interface: Vec<u32>,
    /// Elements touching a fast node (global indices, increasing) and their arrays; the
    /// saliva plan indexed into them.
    pub ids: Vec<u32>,
    pub el: ElementArrays<T>,
    pub gather: NodeGather,
    pub saliva: SalivaPlan,
    pub constraints: ConstraintPlan,
    /// Central-difference coefficients of the substep `dt / k`.
    pub cd: CentralDifference<T>,
    /// Scratch: force blocks, the fast nodes' new displacements (listed), the constraints'
    /// accumulator, the external forces at a substep's time (by node).
    pub f: Vec<[[T; 3]; 8]>,
    pub next: Vec<[T; 3]>,
    pub acc: Vec<f64>,
    pub r: Vec<[T; 3]>,
    /// The displacements the substeps advance (by node; only the fast and interface nodes'
    /// entries are used): `u` and the fast nodes' `u_prev`, copied in at the step's start.
    pub u: Vec<[T; 3]>,
    pub u_prev: Vec<[T; 3]>,
    /// The interface nodes' displacements at the step's start (listed) and end (by node).
    pub interface_start: Vec<[T; 3]>,
    pub interface_end: Vec<[T; 3]>,
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
        let fast = FastPart {
            k,
            nodes: fast_nodes,
            interface,
            constraints: d.constraints.restricted_to(&is_fast),
            cd: CentralDifference::new(h, alpha, &d.mass),
            f: vec![[[T::ZERO; 3]; 8]; fast_el.len()],
            next: vec![[T::ZERO; 3]; nf],
            acc: Vec::new(),
            r: vec![[T::ZERO; 3]; nn],
            u: vec![[T::ZERO; 3]; nn],
            u_prev: vec![[T::ZERO; 3]; nn],
            interface_start: vec![[T::ZERO; 3]; ni],
            interface_end: vec![[T::ZERO; 3]; nn],
            ids: fast_ids,
            el: fast_el,
            gather: fast_gather,
            saliva: fast_saliva,
        };
        Subcycling {
            interface_constraints: d.constraints.restricted_to(&on_interface),
            interface_next: vec![[T::ZERO; 3]; ni],
            interface_acc: Vec::new(),
            slow_f: vec![[[T::ZERO; 3]; 8]; slow_el.len()],
            saliva_start: SalivaState::new(&fast.saliva),
            is_fast,
            slow_ids,
            slow_el,
            slow_gather,
            fast,
        }
    }

    /// Substeps per step.
    pub fn k(&self) -> usize {
        self.fast.k
    }

    /// The substep `dt / k` (s).
    pub fn substep(&self, dt: f64) -> f64 {
        dt / self.fast.k as f64
    }
}

/// The divergence error of step `step` at time `time` (s).
pub(crate) fn diverged(
    step: usize,
    time: f64,
    element: Option<usize>,
    node: Option<usize>,
) -> Error {
    Error::Diverged {
        step,
        time,
        element,
        node,
        reason: match element {
            Some(_) => "element inverted or degenerate (det F <= 0 or not finite)".into(),
            None => "non-finite displacement".into(),
        },
    }
}

/// Step 2 of the module's description: the fast nodes' `k` substeps of step `step` (from
/// `t` to `t + dt`) on `f.u`/`f.u_prev` (the state at `t` copied in, and the interface's end
/// `f.interface_end`), the saliva state `saliva` advanced by each. Touches nothing else.
pub fn substeps<T: crate::tled::simd::SimdReal>(
    f: &mut FastPart<T>,
    d: &Discretisation,
    reference: &[[f64; 3]],
    saliva: &mut SalivaState<T>,
    step: usize,
    t: f64,
    dt: f64,
) -> Result<()> {
    let k = f.k;
    let h = dt / k as f64;
    let has_loads = !d.loads.is_empty();
    for j in 0..k {
        let tj = t + j as f64 * h;
        if j > 0 {
            let w = T::from_f64(j as f64 / k as f64);
            for (i, &n) in f.interface.iter().enumerate() {
                let (a, b) = (f.interface_start[i], f.interface_end[n as usize]);
                f.u[n as usize] = [
                    a[0] + w * (b[0] - a[0]),
                    a[1] + w * (b[1] - a[1]),
                    a[2] + w * (b[2] - a[2]),
                ];
            }
        }
        if let Some(e) = element_forces(&f.el, &f.u, &mut f.f) {
            return Err(diverged(step, tj, Some(f.ids[e] as usize), None));
        }
        saliva_forces(&f.saliva, saliva, &f.el, &f.u, &mut f.f, tj);
        if has_loads {
            crate::tled::solver::fill_loads(d, tj, &mut f.r);
        }
        let r = has_loads.then_some(f.r.as_slice());
        if let Some(n) = node_update_listed(
            &f.nodes,
            &f.gather,
            &f.cd,
            &f.f,
            r,
            &f.u,
            &f.u_prev,
            &mut f.next,
        ) {
            return Err(diverged(step, tj, None, Some(n)));
        }
        for (&n, v) in f.nodes.iter().zip(&f.next) {
            f.u_prev[n as usize] = f.u[n as usize];
            f.u[n as usize] = *v;
        }
        apply_plan_into(
            &f.constraints,
            reference,
            &mut f.u,
            tj + h,
            true,
            &mut f.acc,
        );
    }
    Ok(())
}
