//! Everything that does not depend on the displacement, computed once in `f64`:
//! element gradients and weights, hourglass vectors and stiffnesses, lumped masses,
//! the node gather lists, and the constraint and load plans.

use crate::boundary::{LoadCurve, PrescribedRotation};
use crate::element::hex8;
use crate::material::saliva::{self, SalivaParams};
use crate::mesh::NodeGather;
use crate::problem::Problem;

/// Per-DOF constraint plan. A DOF index is `3 * node + component`.
#[derive(Clone, Debug, Default)]
pub struct ConstraintPlan {
    /// DOFs held at zero.
    pub fixed: Vec<u32>,
    /// Prescribed-displacement DOFs (unique, sorted): zeroed, then every group adds its part.
    pub prescribed_dofs: Vec<u32>,
    /// `(curve, [(dof, magnitude)])`: the DOF gets `magnitude * curve(t)` added.
    pub prescribed: Vec<(LoadCurve, Vec<(u32, f64)>)>,
    pub rotations: Vec<PrescribedRotation>,
    /// `true` for every DOF whose value is imposed.
    pub constrained: Vec<bool>,
}

impl ConstraintPlan {
    /// The part of the plan that acts on the nodes `keep` marks (subcycling: the constraints
    /// a substep applies to the fast nodes). `constrained` is kept whole.
    pub fn restricted_to(&self, keep: &[bool]) -> ConstraintPlan {
        let k = |dof: &u32| keep[*dof as usize / 3];
        ConstraintPlan {
            fixed: self.fixed.iter().copied().filter(k).collect(),
            prescribed_dofs: self.prescribed_dofs.iter().copied().filter(k).collect(),
            prescribed: self
                .prescribed
                .iter()
                .map(|(c, e)| (c.clone(), e.iter().copied().filter(|(d, _)| k(d)).collect()))
                .filter(|(_, e): &(LoadCurve, Vec<(u32, f64)>)| !e.is_empty())
                .collect(),
            rotations: self
                .rotations
                .iter()
                .map(|r| PrescribedRotation {
                    nodes: r
                        .nodes
                        .iter()
                        .copied()
                        .filter(|&n| keep[n as usize])
                        .collect(),
                    ..r.clone()
                })
                .filter(|r| !r.nodes.is_empty())
                .collect(),
            constrained: self.constrained.clone(),
        }
    }
}

/// External load plan: `R(t) = sum_g curve_g(t) r_g`, each `r_g` sparse.
#[derive(Clone, Debug)]
pub struct LoadGroup {
    pub curve: LoadCurve,
    pub entries: Vec<(u32, f64)>,
}

/// Per-saliva-element constants (paper section 3.4), in saliva-element order.
#[derive(Clone, Debug, Default)]
pub struct SalivaPlan {
    /// Element index of each saliva element (increasing).
    pub elements: Vec<u32>,
    /// Unit local y axis (across the layer) in the reference configuration.
    pub across: Vec<[f64; 3]>,
    /// Initial moisture `0M` (um).
    pub initial_moisture: Vec<f64>,
    /// Index into `groups` (the saliva set the element belongs to).
    pub group: Vec<u32>,
    pub groups: Vec<SalivaParams>,
    /// Eq. (11)'s force decay factor per step of each group (at the problem's `dt`), the
    /// value both backends round to their precision.
    pub decay_factor: Vec<f64>,
    /// Keyed wetting ([`crate::problem::Wetting`]): the saliva elements (indices `k` into
    /// the fields above) each adds moisture to, its amount (um) and curve.
    pub wetting: Vec<(Vec<u32>, f64, LoadCurve)>,
}

impl SalivaPlan {
    /// Moisture `tM` (eq. 6) and breaking point `Z` (eq. 7) of saliva element `k` at time
    /// `t`, given the amount its group has evaporated; the values both backends step with.
    /// Wetting adds to the initial moisture before evaporation takes its share:
    /// `tM = max(0, 0M + W(t) - E(t))`.
    pub fn moisture_and_breaking_point(&self, k: usize, evaporated: f64, t: f64) -> (f64, f64) {
        let g = &self.groups[self.group[k] as usize];
        let mut m0 = self.initial_moisture[k];
        for (ks, amount, curve) in &self.wetting {
            if ks.binary_search(&(k as u32)).is_ok() {
                m0 += amount * curve.value(t, true);
            }
        }
        let m = saliva::moisture(m0, evaporated);
        (m, saliva::breaking_point(m, g.critical_moisture, g.k_glue))
    }

    /// The amount each group has evaporated by time `t` (um), into `out` (one per group).
    pub fn evaporated_into(&self, t: f64, out: &mut [f64]) {
        for (ev, g) in out.iter_mut().zip(&self.groups) {
            *ev = g.evaporation.evaporated(t);
        }
    }
}

/// The discretised model in `f64`: the single source of every derived constant that the
/// CPU stepping (in either precision), the static solver and the stability analysis use.
#[derive(Clone, Debug)]
pub struct Discretisation {
    pub num_nodes: usize,
    pub conn: Vec<[u32; 8]>,
    /// Shape-function gradients `D_a` (1/m) of the chosen variant.
    pub dhdx: Vec<[[f64; 3]; 8]>,
    /// Force weight `W` (m^3): `V` for `mean_gradient`, `8 det J(0)` for `centroid`.
    pub weight: Vec<f64>,
    /// Exact element volume `V` (m^3).
    pub volume: Vec<f64>,
    /// Hourglass shape vectors `gamma` (8x4, dimensionless).
    pub gamma: Vec<[[f64; 4]; 8]>,
    /// Hourglass stiffness `k` (N/m).
    pub hg_k: Vec<f64>,
    pub mu: Vec<f64>,
    pub bulk: Vec<f64>,
    pub density: Vec<f64>,
    /// Lumped nodal mass `m_n = sum_e rho_e V_e / 8` (kg).
    pub mass: Vec<f64>,
    pub gather: NodeGather,
    pub constraints: ConstraintPlan,
    pub loads: Vec<LoadGroup>,
    pub saliva: SalivaPlan,
    /// Nodes driven by each muscle (same order as `Problem::physics.muscles`).
    pub muscle_nodes: Vec<Vec<u32>>,
}

impl Discretisation {
    /// Builds the discretisation; the problem must have been validated.
    pub fn new(p: &Problem) -> Self {
        let mesh = &p.mesh;
        let ne = mesh.elements.len();
        let nn = mesh.nodes.len();
        let mut d = Discretisation {
            num_nodes: nn,
            conn: mesh.elements.clone(),
            dhdx: Vec::with_capacity(ne),
            weight: Vec::with_capacity(ne),
            volume: Vec::with_capacity(ne),
            gamma: Vec::with_capacity(ne),
            hg_k: Vec::with_capacity(ne),
            mu: Vec::with_capacity(ne),
            bulk: Vec::with_capacity(ne),
            density: Vec::with_capacity(ne),
            mass: vec![0.0; nn],
            gather: NodeGather::new(nn, &mesh.elements),
            constraints: ConstraintPlan::default(),
            loads: Vec::new(),
            saliva: SalivaPlan::default(),
            muscle_nodes: Vec::new(),
        };
        for e in 0..ne {
            let x = mesh.element_coords(e);
            let (g, w) = hex8::gradients(&x, p.numerics.variant);
            let v = hex8::volume(&x);
            let m = &p.materials[p.element_material[e] as usize];
            d.dhdx.push(g);
            d.weight.push(w);
            d.volume.push(v);
            d.gamma.push(hex8::hourglass_vectors(&x, &g));
            d.hg_k.push(hex8::hourglass_stiffness(
                p.numerics.hourglass_kappa,
                v,
                m.law.mu,
                m.law.bulk,
                &g,
            ));
            d.mu.push(m.law.mu);
            d.bulk.push(m.law.bulk);
            d.density.push(m.density);
        }
        // lumped mass, gathered per node in the fixed slot order
        for n in 0..nn {
            d.mass[n] = d
                .gather
                .of(n)
                .iter()
                .map(|&s| d.density[s as usize / 8] * d.volume[s as usize / 8] / 8.0)
                .sum();
        }
        d.constraints = plan_constraints(p);
        d.loads = plan_loads(p, &d.mass);
        for m in &p.physics.muscles {
            let nodes = m.select_nodes(&mesh.nodes);
            let f = m.nodal_force(nodes.len());
            let entries = nodes
                .iter()
                .flat_map(|&n| {
                    (0..3)
                        .filter(|&k| f[k] != 0.0)
                        .map(move |k| (3 * n + k as u32, f[k]))
                })
                .collect();
            d.loads.push(LoadGroup {
                curve: m.curve.clone(),
                entries,
            });
            d.muscle_nodes.push(nodes);
        }
        d.saliva = plan_saliva(p);
        d
    }

    pub fn num_elements(&self) -> usize {
        self.conn.len()
    }
}

fn plan_saliva(p: &Problem) -> SalivaPlan {
    let mut plan = SalivaPlan {
        groups: p.physics.saliva.iter().map(|s| s.params.clone()).collect(),
        decay_factor: p
            .physics
            .saliva
            .iter()
            .map(|s| s.params.decay.factor(p.time.dt))
            .collect(),
        ..Default::default()
    };
    for (e, &m) in p.element_material.iter().enumerate() {
        let Some(g) = p.physics.saliva.iter().position(|s| s.material == m) else {
            continue;
        };
        let params = &p.physics.saliva[g].params;
        let x = p.mesh.element_coords(e);
        let unit = |a: [f64; 3]| {
            let n = crate::linalg::norm(&a);
            [a[0] / n, a[1] / n, a[2] / n]
        };
        let across = match &params.across {
            Some(saliva::AcrossAxis::Uniform(a)) => unit(*a),
            // Problem::validate checks that every saliva element has its axis
            Some(saliva::AcrossAxis::PerElement(m)) => match m.get(&(e as u32)) {
                Some(a) => unit(*a),
                None => saliva::across_direction(&x),
            },
            None => saliva::across_direction(&x),
        };
        let mut c = [0.0; 3];
        for xa in &x {
            for k in 0..3 {
                c[k] += xa[k] / 8.0;
            }
        }
        // index of this element within its own saliva set (for per-element moisture files)
        let k = plan.group.iter().filter(|&&h| h == g as u32).count();
        plan.elements.push(e as u32);
        plan.across.push(across);
        plan.initial_moisture
            .push(params.initial_moisture.value(&c, k));
        plan.group.push(g as u32);
    }
    for w in &p.physics.wetting {
        // Problem::validate checks that the elements are saliva elements
        let ks: Vec<u32> = w
            .elements
            .iter()
            .filter_map(|e| plan.elements.binary_search(e).ok().map(|k| k as u32))
            .collect();
        plan.wetting.push((ks, w.amount, w.curve.clone()));
    }
    plan
}

fn plan_constraints(p: &Problem) -> ConstraintPlan {
    let nn = p.mesh.nodes.len();
    let mut c = ConstraintPlan {
        constrained: vec![false; 3 * nn],
        ..Default::default()
    };
    for f in &p.bc.fixed {
        for &n in &f.nodes {
            for k in 0..3 {
                if f.dofs[k] {
                    c.fixed.push(3 * n + k as u32);
                }
            }
        }
    }
    c.fixed.sort_unstable();
    c.fixed.dedup();
    for pd in &p.bc.displacements {
        let entries: Vec<(u32, f64)> = pd
            .nodes
            .iter()
            .zip(&pd.values)
            .map(|(&n, &v)| (3 * n + pd.dof as u32, v))
            .collect();
        c.prescribed_dofs.extend(entries.iter().map(|e| e.0));
        c.prescribed.push((pd.curve.clone(), entries));
    }
    c.prescribed_dofs.sort_unstable();
    c.prescribed_dofs.dedup();
    c.rotations = p.bc.rotations.clone();
    for &k in c.fixed.iter().chain(&c.prescribed_dofs) {
        c.constrained[k as usize] = true;
    }
    for r in &c.rotations {
        for &n in &r.nodes {
            for k in 0..3 {
                c.constrained[3 * n as usize + k] = true;
            }
        }
    }
    c
}

fn plan_loads(p: &Problem, mass: &[f64]) -> Vec<LoadGroup> {
    let mut groups = Vec::new();
    for f in &p.bc.forces {
        let entries = f
            .nodes
            .iter()
            .zip(&f.values)
            .map(|(&n, &v)| (3 * n + f.dof as u32, v))
            .collect();
        groups.push(LoadGroup {
            curve: f.curve.clone(),
            entries,
        });
    }
    for g in &p.bc.gravity {
        let nodes: Vec<u32> = match &g.nodes {
            Some(n) => n.clone(),
            None => (0..mass.len() as u32).collect(),
        };
        let mut entries = Vec::with_capacity(3 * nodes.len());
        for n in nodes {
            for k in 0..3 {
                if g.acceleration[k] != 0.0 {
                    entries.push((3 * n + k as u32, mass[n as usize] * g.acceleration[k]));
                }
            }
        }
        groups.push(LoadGroup {
            curve: g.curve.clone(),
            entries,
        });
    }
    groups
}
