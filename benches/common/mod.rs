//! Models shared by the benchmarks (`benches/tled.rs`, `benches/gpu.rs`): NiftySim's
//! `timing_block20` scaled to `c^3` hexahedra, and the paper's mouth scene.

use sticky_lips::boundary::{
    BoundaryConditions, Fixed, LoadCurve, LoadShape, PrescribedDisplacement,
};
use sticky_lips::element::hex8::GradientVariant;
use sticky_lips::material::NeoHookean;
use sticky_lips::mesh::generate::block;
use sticky_lips::problem::{MaterialSpec, Numerics, TimeSettings};
use sticky_lips::tled::stability::element_estimates;
use sticky_lips::Problem;

/// Side of the block (m), as in `timing_block20.xml`.
pub const SIDE: f64 = 0.04;
/// Top displacement at the end of the ramp (m) and the ramp's duration (s).
pub const TOP_DISP: f64 = -0.004;
pub const RAMP_TIME: f64 = 0.1;
/// NiftySim's time step (s).
pub const DT: f64 = 1e-4;
pub const DAMPING: f64 = 50.0;

/// The `timing_block20` problem with `c^3` hexahedra, simulated for `total_time` (the load
/// curve is clamped: the top holds at `TOP_DISP` after the ramp, however long a benchmark
/// steps). dt = 1e-4 s is stable up to 80^3 (critical 2/omega_max = 1.41e-4 s there, 0.95 of
/// the smallest L_e / c_e); finer blocks get 0.8 L_e / c_e so a step cannot diverge.
pub fn block_problem(c: usize, total_time: f64) -> Problem {
    let mesh = block([0.0; 3], [SIDE; 3], [c, c, c]);
    let ne = mesh.elements.len();
    let base = mesh.node_sets["z_min"].clone();
    let top = mesh.node_sets["z_max"].clone();
    let ntop = top.len();
    let bc = BoundaryConditions {
        fixed: vec![Fixed {
            nodes: base,
            dofs: [true; 3],
        }],
        displacements: vec![PrescribedDisplacement {
            nodes: top,
            dof: 2,
            values: vec![TOP_DISP; ntop],
            curve: LoadCurve {
                shape: LoadShape::Ramp,
                start: 0.0,
                duration: RAMP_TIME,
            },
        }],
        ..Default::default()
    };
    let mut p = Problem {
        source: format!("bench block {c}^3"),
        mesh,
        materials: vec![MaterialSpec {
            name: "block".into(),
            law: NeoHookean {
                mu: 1000.0,
                bulk: 10000.0,
            },
            density: 1000.0,
        }],
        element_material: vec![0; ne],
        bc,
        time: TimeSettings {
            dt: DT,
            total_time,
            output_every: 100,
        },
        numerics: Numerics {
            damping: DAMPING,
            hourglass_kappa: 0.075,
            variant: GradientVariant::Centroid,
            // clamped load curve: the top holds at -0.004 m however long criterion steps
            niftysim_timing: false,
            subcycles: 1,
        },
        additive_constraints: false,
        physics: Default::default(),
    };
    let est = element_estimates(&p)
        .into_iter()
        .fold(f64::INFINITY, f64::min);
    p.time.dt = DT.min(0.8 * est);
    few_frames(&mut p);
    p
}

/// The benchmarks step for as long as criterion wants (`total_time` far beyond what they
/// run) and write no frames; the output interval only has to keep the frame count within
/// `problem::MAX_FRAMES` so that the problem validates.
fn few_frames(p: &mut Problem) {
    p.time.output_every = p.time.output_every.max(p.num_steps().div_ceil(1000));
}

/// The procedural mouth's paper scene (Table 1, `paper/scenarios/table1.toml`, on the
/// procedural mouth at full resolution with its saliva layer, breaking rule and jaw: the run
/// `fig4_sticky` of `sticky_lips::paper` for `Model::Procedural`), simulated for
/// `total_time`. The benchmarks keep the procedural mouth: its resolution scales freely.
pub fn mouth_problem(total_time: f64) -> Problem {
    use sticky_lips::paper::{scenario_of, spec, Model};
    let s = spec(Model::Procedural, false, "fig4_sticky").expect("paper run");
    let (_, mut p) = scenario_of(
        Model::Procedural,
        false,
        &s,
        std::path::Path::new("fig4_sticky"),
    )
    .unwrap_or_else(|e| panic!("the paper's procedural scene: {e}"));
    p.time.total_time = total_time;
    few_frames(&mut p);
    p
}

/// A deformed state of the block that satisfies its constraints at t = 0: zero on the base
/// and top faces, lateral bulge of 5 % and axial compression of up to 2 % of the side in
/// between (so that every element is deformed before anything is measured).
pub fn seed_displacement(p: &Problem) -> Vec<[f64; 3]> {
    let h = 0.5 * SIDE;
    p.mesh
        .nodes
        .iter()
        .map(|x| {
            let s = (std::f64::consts::PI * x[2] / SIDE).sin();
            [
                0.05 * (x[0] - h) * s,
                0.05 * (x[1] - h) * s,
                -0.02 * SIDE * s * (x[2] / SIDE),
            ]
        })
        .collect()
}
