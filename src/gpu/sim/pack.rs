//! Packing the model for the kernels, with no wgpu in sight: the flat arrays behind every
//! binding of `shaders/element_forces.wgsl` and `shaders/node_update.wgsl` (layouts as
//! documented at the bindings there), the load and constraint lists in the CPU's order of
//! operations, and the per-step row. The tests below check the packed constraints against
//! `tled::solver::apply_constraints_into` on the CPU.

use crate::error::{Error, Result};
use crate::gpu::layout::*;
use crate::gpu::sim::GpuReal;
use crate::material::saliva::BreakingRule;
use crate::problem::Problem;
use crate::tled::element_forces::ElementArrays;
use crate::tled::node_update::CentralDifference;
use crate::tled::precompute::Discretisation;
use crate::tled::solver::{constraint_time, load_value};

/// Index in the step row of the constant 1 (see the module documentation of `gpu::sim`).
pub(crate) const ROW_ONE: u32 = 0;

/// The model as the kernels read it.
pub(crate) struct Packed<T> {
    /// Element connectivity, 8 per element.
    pub conn: Vec<u32>,
    /// Shape-function derivatives, 8 x 3 per element.
    pub dhdx: Vec<T>,
    /// Hourglass vectors, 8 x 4 per element.
    pub gamma: Vec<T>,
    /// Per element: weight, hourglass stiffness, mu, K.
    pub escal: Vec<T>,
    /// `NodeGather` offsets (nodes + 1), then its slots.
    pub gather: Vec<u32>,
    /// Central-difference `A` per node, then `c_1`.
    pub node_a: Vec<T>,
    /// Per-node load lists: offsets (nodes + 1), then keys `component | row << 2`.
    pub load_key: Vec<u32>,
    /// The magnitude of each load entry (f64; rounded to `load_real` on upload).
    pub load_val: Vec<f64>,
    /// Per DOF: `DOF_FREE`, `DOF_FIXED` or the index of its imposed value.
    pub dof_slot: Vec<u32>,
    /// Imposed values as CSR: offsets (imposed + 1), then the row index of every term.
    pub imp_key: Vec<u32>,
    /// The coefficient of every term (f64; rounded to `load_real` on upload).
    pub imp_coef: Vec<f64>,
    /// Saliva index per element (`NO_SALIVA` if none), then group and rule per saliva element.
    pub sal_meta: Vec<u32>,
    /// Unit axis across the layer per saliva element (3), then the decay factor per group.
    pub sal_const: Vec<T>,
    /// Initial saliva state: previous force (24) and Q (1) per saliva element.
    pub sal_real0: Vec<T>,
    /// Initial saliva flags: broken (0) and first broken step (`NEVER`) per saliva element.
    pub sal_state0: Vec<u32>,
    pub params: Params,
}

/// Packs `problem` (discretised as `disc`, in the stepping precision as `el` and `cd`).
pub(crate) fn pack<T: GpuReal>(
    problem: &Problem,
    disc: &Discretisation,
    el: &ElementArrays<T>,
    cd: &CentralDifference<T>,
) -> Result<Packed<T>> {
    let nn = disc.num_nodes;
    let ne = disc.num_elements();
    // ---- model arrays (layouts as documented at the bindings in shaders/*.wgsl)
    let conn: Vec<u32> = el.conn.iter().flatten().copied().collect();
    let dhdx: Vec<T> = el.dhdx.iter().flatten().flatten().copied().collect();
    let gamma: Vec<T> = el.gamma.iter().flatten().flatten().copied().collect();
    let escal: Vec<T> = (0..ne)
        .flat_map(|e| [el.weight[e], el.hg_k[e], el.mu[e], el.bulk[e]])
        .collect();
    let mut gather = disc.gather.offsets.clone();
    gather.extend_from_slice(&disc.gather.slots);
    let mut node_a = cd.a.clone();
    node_a.push(cd.c1);
    // the step row: [1 | load curves | prescribed curves | rotation matrices]
    let c = &disc.constraints;
    let n_loads = disc.loads.len();
    let pres_base = 1 + n_loads;
    let rot_base = pres_base + c.prescribed.len();
    let row_stride = rot_base + 9 * c.rotations.len();
    let (load_key, load_val) = load_lists(disc);
    let (dof_slot, imposed) = imposed_dofs(problem, disc, pres_base, rot_base);
    let (imp_key, imp_coef) = imposed_csr(&imposed);
    let ns = disc.saliva.elements.len();
    let (sal_meta, sal_const, sal_real0) = saliva_arrays::<T>(disc)?;

    let stride = ns.max(1);
    let params = Params {
        num_elements: ne as u32,
        num_nodes: nn as u32,
        num_saliva: ns as u32,
        num_imposed: imposed.len() as u32,
        row_stride: row_stride as u32,
        table_stride: stride as u32,
        _pad0: 0,
        _pad1: 0,
    };
    Ok(Packed {
        conn,
        dhdx,
        gamma,
        escal,
        gather,
        node_a,
        load_key,
        load_val,
        dof_slot,
        imp_key,
        imp_coef,
        sal_meta,
        sal_const,
        sal_state0: [0u32, NEVER].repeat(ns),
        sal_real0,
        params,
    })
}

/// The per-node load lists ([`Packed::load_key`], [`Packed::load_val`]): per node, in the
/// CPU's accumulation order (group, then entry); a key is component | (row index of the
/// group's curve value) << 2.
fn load_lists(disc: &Discretisation) -> (Vec<u32>, Vec<f64>) {
    let nn = disc.num_nodes;
    let mut per_node: Vec<Vec<(u32, f64)>> = vec![Vec::new(); nn];
    for (g, grp) in disc.loads.iter().enumerate() {
        for &(dof, v) in &grp.entries {
            per_node[dof as usize / 3].push(((dof % 3) | (((1 + g) as u32) << 2), v));
        }
    }
    let mut load_key: Vec<u32> = Vec::with_capacity(nn + 1);
    let mut load_val: Vec<f64> = Vec::new();
    let mut keys = Vec::new();
    load_key.push(0);
    for list in &per_node {
        for &(k, v) in list {
            keys.push(k);
            load_val.push(v);
        }
        load_key.push(keys.len() as u32);
    }
    load_key.extend(keys);
    (load_key, load_val)
}

/// The constraints ([`Packed::dof_slot`]) and the imposed values' terms `(coefficient, row
/// index)`, the prescribed curves' rows from `pres_base`, the rotations' from `rot_base`.
///
/// What each DOF becomes after the update (rotation > prescribed > fixed, the order in which
/// the CPU's apply_constraints overwrites); an imposed DOF is a list of terms (coefficient,
/// row index), see the module documentation.
fn imposed_dofs(
    problem: &Problem,
    disc: &Discretisation,
    pres_base: usize,
    rot_base: usize,
) -> (Vec<u32>, Vec<Vec<(f64, u32)>>) {
    let c = &disc.constraints;
    let mut dof_slot = vec![DOF_FREE; 3 * disc.num_nodes];
    for &k in &c.fixed {
        dof_slot[k as usize] = DOF_FIXED;
    }
    let mut imposed: Vec<Vec<(f64, u32)>> = c
        .prescribed_dofs
        .iter()
        .map(|_| vec![(0.0, ROW_ONE)])
        .collect();
    for (j, (_, entries)) in c.prescribed.iter().enumerate() {
        for &(k, v) in entries {
            let i = c
                .prescribed_dofs
                .binary_search(&k)
                .expect("prescribed dof planned");
            imposed[i].push((v, (pres_base + j) as u32));
        }
    }
    for (i, &k) in c.prescribed_dofs.iter().enumerate() {
        dof_slot[k as usize] = i as u32;
    }
    for (r, rot) in c.rotations.iter().enumerate() {
        for &n in &rot.nodes {
            let x = problem.mesh.nodes[n as usize];
            let d = [
                x[0] - rot.point[0],
                x[1] - rot.point[1],
                x[2] - rot.point[2],
            ];
            for k in 0..3 {
                let m = (rot_base + 9 * r + 3 * k) as u32;
                dof_slot[3 * n as usize + k] = imposed.len() as u32;
                imposed.push(vec![
                    (d[0], m),
                    (d[1], m + 1),
                    (d[2], m + 2),
                    (-d[k], ROW_ONE),
                ]);
            }
        }
    }
    (dof_slot, imposed)
}

/// The imposed values' terms as CSR ([`Packed::imp_key`]: offsets (num_imposed + 1), then
/// the row index of every term) and their coefficients apart ([`Packed::imp_coef`]).
fn imposed_csr(imposed: &[Vec<(f64, u32)>]) -> (Vec<u32>, Vec<f64>) {
    let mut imp_key: Vec<u32> = Vec::with_capacity(imposed.len() + 1);
    imp_key.push(0);
    for terms in imposed {
        imp_key.push(imp_key.last().unwrap() + terms.len() as u32);
    }
    imp_key.extend(imposed.iter().flatten().map(|&(_, i)| i));
    let mut imp_coef: Vec<f64> = imposed.iter().flatten().map(|&(v, _)| v).collect();
    if imp_coef.is_empty() {
        imp_coef.push(0.0); // never read; a binding holds at least one element
    }
    (imp_key, imp_coef)
}

/// The saliva's arrays: [`Packed::sal_meta`], [`Packed::sal_const`] and
/// [`Packed::sal_real0`]. Fails if an element is listed twice among the saliva elements.
fn saliva_arrays<T: GpuReal>(disc: &Discretisation) -> Result<(Vec<u32>, Vec<T>, Vec<T>)> {
    let sp = &disc.saliva;
    let ns = sp.elements.len();
    // [saliva index per element (NO_SALIVA if none) | group, rule per saliva element]
    let mut sal_meta = vec![NO_SALIVA; disc.num_elements()];
    for (k, &e) in sp.elements.iter().enumerate() {
        if sal_meta[e as usize] != NO_SALIVA {
            return Err(Error::Gpu(format!(
                "element {e} is listed twice among the saliva elements"
            )));
        }
        sal_meta[e as usize] = k as u32;
    }
    for k in 0..ns {
        let g = sp.group[k];
        let rule = match sp.groups[g as usize].rule {
            BreakingRule::Literal => RULE_LITERAL,
            BreakingRule::Latched => RULE_LATCHED,
        };
        sal_meta.extend([g, rule]);
    }
    // [unit axis across per saliva element (3) | decay factor per group]
    let mut sal_const: Vec<T> = sp
        .across
        .iter()
        .flatten()
        .map(|&x| T::from_f64(x))
        .collect();
    sal_const.extend(sp.decay_factor.iter().map(|&f| T::from_f64(f)));
    // initial saliva state: no previous force, Q = 1, intact, never broken
    let sal_real0: Vec<T> = (0..ns)
        .flat_map(|_| {
            let mut v = [T::ZERO; 25];
            v[24] = T::ONE;
            v
        })
        .collect();
    Ok((sal_meta, sal_const, sal_real0))
}

/// The step row of iteration `s` (see the module documentation of `gpu::sim`): the constant
/// 1, each load group's curve value, each prescribed curve's value at `t_{s+1}`, each
/// rotation's matrix at `t_{s+1}` (row-major); `row.len()` is `Params::row_stride`.
pub(crate) fn fill_step_row(
    disc: &Discretisation,
    s: usize,
    dt: f64,
    niftysim_timing: bool,
    row: &mut [f64],
) {
    let (tn, clamp_n) = constraint_time(s + 1, dt, niftysim_timing);
    let c = &disc.constraints;
    let mut i = 0;
    let mut put = |v: f64| {
        row[i] = v;
        i += 1;
    };
    put(1.0);
    for grp in &disc.loads {
        put(load_value(&grp.curve, s, dt, niftysim_timing));
    }
    for (curve, _) in &c.prescribed {
        put(curve.value(tn, clamp_n));
    }
    for r in &c.rotations {
        r.matrix(tn, clamp_n).iter().flatten().for_each(|&m| put(m));
    }
    debug_assert_eq!(i, row.len());
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::boundary::{
        BoundaryConditions, Fixed, LoadCurve, LoadShape, PrescribedDisplacement, PrescribedRotation,
    };
    use crate::problem::{table1, Numerics, Physics, TimeSettings};
    use crate::tled::solver::apply_constraints_into;

    /// A 3x2x2 block with every kind of constraint: a fixed face, two prescribed
    /// displacements on one DOF set (they add up), and a rotation of the far face.
    fn constrained_block() -> Problem {
        let mesh = crate::mesh::generate::block([0.0; 3], [0.03, 0.02, 0.02], [3, 2, 2]);
        let x_max = mesh.node_sets["x_max"].clone();
        let y_max: Vec<u32> = mesh.node_sets["y_max"]
            .iter()
            .copied()
            .filter(|n| !x_max.contains(n) && !mesh.node_sets["x_min"].contains(n))
            .collect();
        let curve = |shape| LoadCurve {
            shape,
            start: 0.0,
            duration: 0.01,
        };
        let bc = BoundaryConditions {
            fixed: vec![Fixed {
                nodes: mesh.node_sets["x_min"].clone(),
                dofs: [true, true, false],
            }],
            displacements: vec![
                PrescribedDisplacement {
                    nodes: y_max.clone(),
                    dof: 1,
                    values: vec![1e-3; y_max.len()],
                    curve: curve(LoadShape::Ramp),
                },
                PrescribedDisplacement {
                    nodes: y_max.clone(),
                    dof: 1,
                    values: (0..y_max.len()).map(|k| 3e-4 * k as f64).collect(),
                    curve: curve(LoadShape::Poly345),
                },
            ],
            rotations: vec![PrescribedRotation {
                nodes: x_max,
                point: [0.03, 0.01, 0.01],
                axis: [0.0, 0.6, 0.8],
                angle: 0.3,
                curve: curve(LoadShape::SmoothStep),
            }],
            ..Default::default()
        };
        let n = mesh.elements.len();
        Problem {
            source: "block".into(),
            mesh,
            materials: vec![table1::TISSUE.spec("tissue")],
            element_material: vec![0; n],
            bc,
            time: TimeSettings {
                dt: 1e-4,
                total_time: 0.02,
                output_every: 10,
            },
            numerics: Numerics::default(),
            additive_constraints: true,
            physics: Physics::default(),
        }
    }

    /// Every DOF's value after the kernel's constraint step, evaluated from the packed
    /// arrays as `shaders/node_update.wgsl` does (in f64): `None` for a free DOF.
    fn imposed_by_packing(p: &Packed<f64>, row: &[f64]) -> Vec<Option<f64>> {
        let terms = p.params.num_imposed as usize + 1;
        p.dof_slot
            .iter()
            .map(|&c| match c {
                DOF_FREE => None,
                DOF_FIXED => Some(0.0),
                c => {
                    let (t0, t1) = (
                        p.imp_key[c as usize] as usize,
                        p.imp_key[c as usize + 1] as usize,
                    );
                    let term = |t: usize| p.imp_coef[t] * row[p.imp_key[terms + t] as usize];
                    Some((t0 + 1..t1).fold(term(t0), |acc, t| acc + term(t)))
                }
            })
            .collect()
    }

    #[test]
    fn packed_constraints_are_the_cpus_bit_for_bit() {
        let problem = constrained_block();
        problem.validate().unwrap();
        let disc = Discretisation::new(&problem);
        let el = ElementArrays::<f64>::from_discretisation(&disc);
        let cd = CentralDifference::<f64>::new(problem.time.dt, 0.0, &disc.mass);
        let packed = pack(&problem, &disc, &el, &cd).unwrap();
        let mut row = vec![f64::NAN; packed.params.row_stride as usize];
        let mut acc = Vec::new();
        let sentinel = [12345.0f64; 3];
        let mut checked = 0;
        for s in [0, 7, 49, 99, 150] {
            fill_step_row(&disc, s, problem.time.dt, false, &mut row);
            let gpu = imposed_by_packing(&packed, &row);
            let mut u = vec![sentinel; disc.num_nodes];
            let (t, clamp) = constraint_time(s + 1, problem.time.dt, false);
            apply_constraints_into(&disc, &problem.mesh.nodes, &mut u, t, clamp, &mut acc);
            for (k, g) in gpu.iter().enumerate() {
                let cpu = u[k / 3][k % 3];
                match g {
                    None => assert_eq!(cpu, sentinel[0], "DOF {k} is free on the GPU only"),
                    Some(v) => {
                        assert_eq!(v.to_bits(), cpu.to_bits(), "DOF {k} at step {s}");
                        checked += 1;
                    }
                }
            }
        }
        // per step: fixed (2 DOFs of the 9 x_min nodes), prescribed (y of the 6 other y_max
        // nodes) and rotated (3 DOFs of the 9 x_max nodes)
        assert_eq!(checked, 5 * (18 + 6 + 27));
    }

    #[test]
    fn a_saliva_element_listed_twice_is_refused() {
        let problem = constrained_block();
        let mut disc = Discretisation::new(&problem);
        disc.saliva.elements = vec![1, 1];
        disc.saliva.group = vec![0, 0];
        disc.saliva.across = vec![[0.0, 1.0, 0.0]; 2];
        use crate::material::saliva::{Decay, EvaporationSchedule, MoistureMap, SalivaParams};
        disc.saliva.groups = vec![SalivaParams {
            critical_moisture: table1::CRITICAL_MOISTURE,
            k_glue: 0.1,
            initial_moisture: MoistureMap::Constant(table1::INITIAL_MOISTURE),
            evaporation: EvaporationSchedule::constant(0.0),
            rule: BreakingRule::Literal,
            decay: Decay::PerStep(table1::DECAY_PER_STEP),
            across: None,
        }];
        disc.saliva.decay_factor = vec![0.99];
        let el = ElementArrays::<f32>::from_discretisation(&disc);
        let cd = CentralDifference::<f32>::new(problem.time.dt, 0.0, &disc.mass);
        let e = pack(&problem, &disc, &el, &cd).err().unwrap().to_string();
        assert!(e.contains("element 1 is listed twice"), "{e}");
    }
}
