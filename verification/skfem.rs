//! scikit-fem as an independent oracle (`verification/reference/skfem_neohookean.json`, made by
//! `scripts/skfem_reference.py`): a generic Galerkin assembly of NiftySim's neo-Hookean material
//! on distorted trilinear hexahedra with 2x2x2 Gauss quadrature. For a homogeneous deformation the
//! fully integrated element force equals `V P(F0)` times the mean gradient, which is exactly the
//! mean-gradient one-point element (paper eq. 4 with `D_a = (1/V) int dN_a/dX`).
#![allow(clippy::needless_range_loop)] // index loops mirror the tensor notation

use crate::element::{bare_problem, force_of, problem};
use crate::patch::internal_forces;
use serde_json::Value;
use sticky_lips::boundary::{
    BoundaryConditions, Fixed, LoadCurve, LoadShape, PrescribedDisplacement,
};
use sticky_lips::element::hex8::GradientVariant;
use sticky_lips::mesh::Mesh;
use sticky_lips::problem::TimeSettings;
use sticky_lips::static_solve::{solve_equilibrium, StaticOptions};
use sticky_lips::tled::precompute::Discretisation;

fn reference() -> Value {
    let path = crate::common::repo().join("verification/reference/skfem_neohookean.json");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap()
}

fn f(v: &Value) -> f64 {
    v.as_f64().expect("number")
}

fn vec3s(v: &Value) -> Vec<[f64; 3]> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|r| [f(&r[0]), f(&r[1]), f(&r[2])])
        .collect()
}

fn u32s(v: &Value) -> Vec<u32> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_u64().unwrap() as u32)
        .collect()
}

fn mesh(r: &Value, name: &str) -> Mesh {
    let m = &r["meshes"][name];
    let elements = m["elements"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| u32s(e).try_into().unwrap())
        .collect();
    Mesh {
        nodes: vec3s(&m["nodes"]),
        elements,
        ..Default::default()
    }
}

fn max_abs(u: &[[f64; 3]]) -> f64 {
    u.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()))
}

#[test]
fn skfem_volumes_and_mean_gradients() {
    let r = reference();
    assert_eq!(f(&r["material"]["mu"]), 1000.0);
    assert_eq!(f(&r["material"]["K"]), 10000.0);
    for name in ["hex1_distorted", "patch3_distorted"] {
        let d = Discretisation::new(&bare_problem(mesh(&r, name), GradientVariant::MeanGradient));
        let el = &r["elements"][name];
        let (mut wv, mut wg): (f64, f64) = (0.0, 0.0);
        for e in 0..d.num_elements() {
            let v = f(&el["volume"][e]);
            wv = wv.max((d.volume[e] - v).abs() / v);
            // mean-gradient variant: the force weight is the exact volume
            assert_eq!(d.weight[e], d.volume[e]);
            let g = vec3s(&el["mean_gradient"][e]);
            let gmax = max_abs(&g);
            for a in 0..8 {
                for k in 0..3 {
                    wg = wg.max((d.dhdx[e][a][k] - g[a][k]).abs() / gmax);
                }
            }
        }
        println!("skfem_volumes_and_mean_gradients {name}: volume rel {wv:.1e}, mean gradient rel {wg:.1e}");
        // 1e-13: both are 8-point Gauss sums of the same polynomials in f64 (~10 roundings of eps each)
        assert!(
            wv < 1e-13 && wg < 1e-13,
            "{name}: volume {wv:e} / gradient {wg:e} differ from scikit-fem"
        );
    }
}

#[test]
fn skfem_homogeneous_forces() {
    let r = reference();
    // force scale of the 20 % uniaxial stretch on each mesh: the absolute floor for the rigid rotation
    let uniaxial_scale = |m: &str| {
        let c = r["homogeneous"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["mesh"] == m && c["name"] == "uniaxial_x_1.2")
            .unwrap();
        max_abs(&vec3s(&c["forces"]))
    };
    for case in r["homogeneous"].as_array().unwrap() {
        let (mname, cname) = (
            case["mesh"].as_str().unwrap(),
            case["name"].as_str().unwrap(),
        );
        let m = mesh(&r, mname);
        let d = Discretisation::new(&bare_problem(m, GradientVariant::MeanGradient));
        let u = vec3s(&case["u"]);
        let f_ref = vec3s(&case["forces"]);
        let rotation = cname.starts_with("rotation");
        // scikit-fem's forces for a rigid rotation are round-off (~1e-16 N); they are compared against
        // 1e-12 of the 20 % stretch's forces on the same mesh instead (an absolute floor of ~1e-13 N)
        let scale = if rotation {
            uniaxial_scale(mname)
        } else {
            max_abs(&f_ref)
        };
        let mut we: f64 = 0.0;
        for e in 0..d.num_elements() {
            let fe = force_of::<f64>(&d, &u, e);
            let fr = vec3s(&case["element_forces"][e]);
            for a in 0..8 {
                for k in 0..3 {
                    we = we.max((fe[a][k] - fr[a][k]).abs() / scale);
                }
            }
        }
        let assembled = internal_forces::<f64>(&d, &u);
        let wa = assembled
            .iter()
            .zip(&f_ref)
            .flat_map(|(x, y)| (0..3).map(move |k| (x[k] - y[k]).abs()))
            .fold(0.0, f64::max)
            / scale;
        println!("skfem_homogeneous_forces {mname} {cname}: per element {we:.1e}, assembled {wa:.1e} (scale {scale:.2e} N)");
        // 1e-12: same quantity, both in f64; the ~100 roundings of the stress and the 8-term
        // quadrature sums in scikit-fem give ~1e-14, and the interior nodes' near-cancelling sums
        // of the patch amplify that by at most ~10
        assert!(
            we < 1e-12,
            "{mname} {cname}: element forces differ from scikit-fem by {we:e}"
        );
        assert!(
            wa < 1e-12,
            "{mname} {cname}: assembled forces differ from scikit-fem by {wa:e}"
        );
    }
}

#[test]
fn skfem_static_solution() {
    let r = reference();
    let s = &r["static"];
    let m = mesh(&r, s["mesh"].as_str().unwrap());
    let bc_json = &s["bc"];
    let time = TimeSettings {
        dt: 1e-4,
        total_time: 1e-3,
        output_every: 1,
    };
    let mut bc = BoundaryConditions::default();
    for (key, dof) in [("fix_x", 0), ("fix_y", 1), ("fix_z", 2)] {
        let mut dofs = [false; 3];
        dofs[dof] = true;
        bc.fixed.push(Fixed {
            nodes: u32s(&bc_json[key]),
            dofs,
        });
    }
    let pull = u32s(&bc_json["pull_x"]);
    let value = f(&bc_json["pull_value"]);
    let curve = LoadCurve {
        shape: LoadShape::Ramp,
        start: 0.0,
        duration: time.total_time,
    };
    bc.displacements.push(PrescribedDisplacement {
        nodes: pull.clone(),
        dof: 0,
        values: vec![value; pull.len()],
        curve,
    });
    let p = problem(m, GradientVariant::MeanGradient, bc, time, 0.0);
    let res = solve_equilibrium(
        &p,
        &StaticOptions {
            tolerance: 1e-13,
            ..Default::default()
        },
    )
    .unwrap();
    let u_ref = vec3s(&s["u"]);
    let err = res
        .u
        .iter()
        .zip(&u_ref)
        .flat_map(|(x, y)| (0..3).map(move |k| (x[k] - y[k]).abs()))
        .fold(0.0, f64::max)
        / max_abs(&u_ref);
    // and both are the analytic homogeneous solution F = diag(1.2, lt, lt)
    let lt = f(&s["lateral_stretch"]);
    let exact: Vec<[f64; 3]> = p
        .mesh
        .nodes
        .iter()
        .map(|x| [0.2 * x[0], (lt - 1.0) * x[1], (lt - 1.0) * x[2]])
        .collect();
    let err_exact = res
        .u
        .iter()
        .zip(&exact)
        .flat_map(|(x, y)| (0..3).map(move |k| (x[k] - y[k]).abs()))
        .fold(0.0, f64::max)
        / max_abs(&exact);
    println!(
        "skfem_static_solution: |u - u_skfem| / max|u| = {err:.1e}, vs analytic {err_exact:.1e} ({} Newton its, residual {:.1e} N)",
        res.newton_iterations, res.residual_norm
    );
    // 1e-10: both solvers converged to ~1e-13..1e-14 of the reaction scale; the tangent's condition
    // number (~1e2 on this 64-node patch) turns that into ~1e-11 in u
    assert!(
        err < 1e-10,
        "static solution differs from scikit-fem by {err:e}"
    );
    assert!(
        err_exact < 1e-10,
        "static solution differs from the analytic one by {err_exact:e}"
    );
}
