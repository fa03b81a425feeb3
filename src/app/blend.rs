//! `sticky-lips blend`: a weighted blend of displacement fields ([`crate::blend`]) written
//! like a run with one frame.

use crate::error::{Error, Location, Result};
use crate::io::output::{Frame, FrameWriter};
use crate::run_dir::RunSummary;
use crate::tled::precompute::Discretisation;
use crate::Problem;
use std::path::Path;

/// One shape of a blend: `PATH.vtu=WEIGHT`, its displacements checked against `p`'s mesh.
fn read_shape(p: &Problem, spec: &str) -> Result<(f64, Vec<[f64; 3]>)> {
    let nn = p.mesh.nodes.len();
    let (path, w) = crate::io::args::name_value(spec, "--shape", "PATH.vtu=WEIGHT")?;
    let (v, comps, points) = crate::io::vtu::read_point_data_f64(Path::new(path), "displacement")?;
    if comps != 3 || points != nn {
        return Err(Error::input(
            path,
            Location::None,
            format!("shape has {points} points x {comps} components; the model has {nn} nodes x 3"),
        ));
    }
    if let Some(k) = v.iter().position(|x| !x.is_finite()) {
        return Err(Error::input(
            path,
            Location::Field(format!("point data `displacement`, point {}", k / 3)),
            format!("{} is not a finite number", v[k]),
        ));
    }
    Ok((w, v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()))
}

/// Blends the displacement fields `shapes` (`PATH.vtu=WEIGHT` each) on `p`'s mesh and writes
/// the result into `out` as one frame at time 0, with a summary of kind `blend` listing them.
pub fn blend(p: &Problem, shapes: &[String], out: &Path) -> Result<RunSummary> {
    let t0 = std::time::Instant::now();
    let fields = shapes
        .iter()
        .map(|s| read_shape(p, s))
        .collect::<Result<Vec<_>>>()?;
    let refs: Vec<(f64, &[[f64; 3]])> = fields.iter().map(|(w, b)| (*w, b.as_slice())).collect();
    let x = crate::blend::blend(&p.mesh.nodes, &refs);
    let u: Vec<[f64; 3]> = x
        .iter()
        .zip(&p.mesh.nodes)
        .map(|(a, b)| crate::linalg::sub(a, b))
        .collect();
    let disc = Discretisation::new(p);
    let mut w = FrameWriter::new(
        out,
        &p.mesh.nodes,
        &p.mesh.elements,
        &p.element_material,
        &[],
    )?;
    w.frame(Frame {
        time: 0.0,
        u: u.clone(),
        volume_ratio: crate::tled::solver::volume_ratios(&disc, &u),
        saliva: None,
    })?;
    let summary = RunSummary {
        shapes: shapes.to_vec(),
        threads: 1,
        ..RunSummary::one_frame(
            p,
            "blend",
            0.0,
            crate::tled::stability::analyse(p, &disc),
            crate::tled::solver::strain_energy(&disc, &u),
            t0.elapsed().as_secs_f64(),
        )
    };
    w.finish(&summary)?;
    Ok(summary)
}
