//! A run directory's frames as NumPy arrays: the frames listed in `frames.pvd` (the complete
//! ones, for an interrupted run too), each frame file read with the library's array reader,
//! in parallel and without the GIL. The points and the cells, which the library does not
//! read back, are read here from the first frame.

use crate::errors::IntoPy;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use sticky_lips::error::{Error, Location, Result};
use sticky_lips::io::vtu;
use sticky_lips::run_dir::RunDir;

/// The saliva elements' cell arrays of a frame file, in this order.
const SALIVA: [&str; 5] = [
    "saliva_broken",
    "saliva_moisture",
    "saliva_Z",
    "saliva_Q",
    "saliva_broken_at",
];

/// What one frame file holds: the displacement (3 per node) and the saliva arrays (one value
/// per element each, in [`SALIVA`]'s order; empty without saliva).
struct FrameData {
    displacement: Vec<f64>,
    saliva: Vec<Vec<f64>>,
}

/// The model, from the first frame: rest positions, cells, material codes.
struct ModelData {
    rest: Vec<f64>,
    cells: Vec<i64>,
    material: Vec<f64>,
}

struct Frames {
    times: Vec<f64>,
    files: Vec<String>,
    model: Option<ModelData>,
    frames: Vec<FrameData>,
}

fn bad(file: &str, message: String) -> Error {
    Error::input(file, Location::None, message)
}

fn read_text(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|e| Error::io(path, e))
}

fn read_frame(path: &Path, with_saliva: bool) -> Result<FrameData> {
    let text = read_text(path)?;
    frame_of(&text, &path.display().to_string(), with_saliva)
}

/// The displacement and saliva arrays of a frame file's text (`file` names it in errors).
fn frame_of(text: &str, file: &str, with_saliva: bool) -> Result<FrameData> {
    let mut wanted = vec![("PointData", "displacement")];
    if with_saliva {
        wanted.extend(SALIVA.iter().map(|n| ("CellData", *n)));
    }
    let mut arrays = vtu::parse_arrays(text, file, &wanted)?.into_iter();
    let (displacement, comps, _) = arrays.next().expect("one result per array asked for")?;
    if comps != 3 {
        return Err(bad(
            file,
            format!("array `displacement` has {comps} components (3 expected)"),
        ));
    }
    let saliva = arrays
        .map(|a| a.map(|(v, _, _)| v))
        .collect::<Result<Vec<_>>>()?;
    Ok(FrameData {
        displacement,
        saliva,
    })
}

/// The payload of a binary `<DataArray>` of our frame files (base64 of a UInt64 byte count
/// and the values), checked against the count and `width`.
fn binary_payload(node: roxmltree::Node, file: &str, what: &str, width: usize) -> Result<Vec<u8>> {
    if node.attribute("format") != Some("binary") {
        return Err(bad(file, format!("{what}: not a binary array")));
    }
    let raw = vtu::base64_decode(node.text().unwrap_or(""))
        .ok_or_else(|| bad(file, format!("{what}: malformed base64")))?;
    let (count, data) = raw
        .split_at_checked(8)
        .ok_or_else(|| bad(file, format!("{what}: truncated")))?;
    let count = u64::from_le_bytes(count.try_into().expect("8 bytes"));
    if data.len() as u64 != count || data.len() % width != 0 {
        return Err(bad(
            file,
            format!("{what}: byte count {count} does not match the data"),
        ));
    }
    Ok(data.to_vec())
}

/// The points (3 per node, Float64) and the connectivity (8 per hexahedron, Int64) of a
/// frame file's text.
fn points_and_cells(text: &str, file: &str) -> Result<(Vec<f64>, Vec<i64>)> {
    let doc =
        roxmltree::Document::parse(text).map_err(|e| bad(file, format!("malformed XML: {e}")))?;
    let array_in = |section: &str, name: &str, ty: &str| {
        doc.descendants()
            .filter(|n| n.has_tag_name(section))
            .flat_map(|s| s.children())
            .find(|n| {
                n.has_tag_name("DataArray")
                    && n.attribute("Name") == Some(name)
                    && n.attribute("type") == Some(ty)
            })
            .ok_or_else(|| bad(file, format!("no {ty} array `{name}` in <{section}>")))
    };
    let points = binary_payload(array_in("Points", "Points", "Float64")?, file, "Points", 8)?;
    let cells = binary_payload(
        array_in("Cells", "connectivity", "Int64")?,
        file,
        "connectivity",
        8,
    )?;
    let points: Vec<f64> = points
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
        .collect();
    let cells: Vec<i64> = cells
        .chunks_exact(8)
        .map(|c| i64::from_le_bytes(c.try_into().expect("8 bytes")))
        .collect();
    if points.len() % 3 != 0 || cells.len() % 8 != 0 {
        return Err(bad(
            file,
            "the points are not triples or the cells not hexahedra".into(),
        ));
    }
    Ok((points, cells))
}

/// The model of the first frame, its saliva arrays' presence, and the frame itself.
fn read_first(path: &Path) -> Result<(ModelData, bool, FrameData)> {
    let text = read_text(path)?;
    let file = path.display().to_string();
    let (points, cells) = points_and_cells(&text, &file)?;
    let mut arrays = vtu::parse_arrays(
        &text,
        &file,
        &[("CellData", "material"), ("CellData", SALIVA[0])],
    )?
    .into_iter();
    let (material, _, _) = arrays.next().expect("one result per array asked for")?;
    if cells.len() != 8 * material.len() {
        return Err(bad(
            &file,
            format!(
                "{} hexahedra and {} material codes",
                cells.len() / 8,
                material.len()
            ),
        ));
    }
    let with_saliva = arrays.next().is_some_and(|a| a.is_ok());
    let first = frame_of(&text, &file, with_saliva)?;
    if first.displacement.len() != points.len() {
        return Err(bad(
            &file,
            format!(
                "{} displacement values for {} points",
                first.displacement.len(),
                points.len() / 3
            ),
        ));
    }
    // the rest positions: the points less the displacement (the same numbers at a run's
    // first frame, whose displacement is zero)
    let rest = points
        .iter()
        .zip(&first.displacement)
        .map(|(x, u)| x - u)
        .collect();
    Ok((
        ModelData {
            rest,
            cells,
            material,
        },
        with_saliva,
        first,
    ))
}

fn read_all(dir: &Path) -> Result<Frames> {
    let rd = RunDir::new(dir);
    let listed = rd.frames()?;
    let (times, files): (Vec<f64>, Vec<String>) = listed.into_iter().unzip();
    let Some(first_file) = files.first() else {
        return Ok(Frames {
            times,
            files,
            model: None,
            frames: Vec::new(),
        });
    };
    let (model, with_saliva, first) = read_first(&dir.join(first_file))?;
    let mut frames = vec![first];
    frames.extend(
        files[1..]
            .par_iter()
            .map(|f| read_frame(&dir.join(f), with_saliva))
            .collect::<Result<Vec<_>>>()?,
    );
    let (n, e) = (model.rest.len(), model.material.len());
    for (f, file) in frames.iter().zip(&files) {
        if f.displacement.len() != n || f.saliva.iter().any(|s| s.len() != e) {
            return Err(bad(
                &dir.join(file).display().to_string(),
                "a mesh other than the first frame's".into(),
            ));
        }
    }
    Ok(Frames {
        times,
        files,
        model: Some(model),
        frames,
    })
}

/// The frames of the run in `dir` as a dict of NumPy arrays (`sticky_lips.Run` documents
/// them): `times` (F), `files`, `displacement` (F, N, 3), `rest` (N, 3), `cells` (E, 8),
/// `material` (E), and for a model with saliva `saliva_elements` (S) and per frame (F, S):
/// `saliva_broken` (bool), `saliva_moisture`, `saliva_Z`, `saliva_Q`, `saliva_broken_at`.
#[pyfunction]
pub fn read_frames<'py>(py: Python<'py>, dir: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let all = py.detach(|| read_all(&dir)).py_err(py)?;
    let f = all.times.len();
    let d = PyDict::new(py);
    d.set_item("times", PyArray1::from_vec(py, all.times))?;
    d.set_item("files", all.files)?;
    let Some(model) = all.model else {
        d.set_item(
            "displacement",
            PyArray1::<f64>::zeros(py, 0, false).reshape([0, 0, 3])?,
        )?;
        d.set_item(
            "rest",
            PyArray1::<f64>::zeros(py, 0, false).reshape([0, 3])?,
        )?;
        d.set_item(
            "cells",
            PyArray1::<i64>::zeros(py, 0, false).reshape([0, 8])?,
        )?;
        d.set_item("material", PyArray1::<i32>::zeros(py, 0, false))?;
        return Ok(d);
    };
    let n = model.rest.len() / 3;
    let e = model.material.len();
    let displacement: Vec<f64> = all
        .frames
        .iter()
        .flat_map(|fr| fr.displacement.iter().copied())
        .collect();
    d.set_item(
        "displacement",
        PyArray1::from_vec(py, displacement).reshape([f, n, 3])?,
    )?;
    d.set_item("rest", PyArray1::from_vec(py, model.rest).reshape([n, 3])?)?;
    d.set_item(
        "cells",
        PyArray1::from_vec(py, model.cells).reshape([e, 8])?,
    )?;
    let material: Vec<i32> = model.material.iter().map(|&m| m as i32).collect();
    d.set_item("material", PyArray1::from_vec(py, material))?;
    let Some(first) = all.frames.first().filter(|fr| !fr.saliva.is_empty()) else {
        return Ok(d);
    };
    // the saliva elements: those whose broken flag is 0 or 1 (the others hold -1)
    let saliva: Vec<usize> = (0..e).filter(|&k| first.saliva[0][k] >= 0.0).collect();
    let s = saliva.len();
    d.set_item(
        "saliva_elements",
        PyArray1::from_vec(py, saliva.iter().map(|&k| k as i64).collect::<Vec<_>>()),
    )?;
    let per_frame = |a: usize| -> Vec<f64> {
        all.frames
            .iter()
            .flat_map(|fr| saliva.iter().map(move |&k| fr.saliva[a][k]))
            .collect()
    };
    let broken: Vec<bool> = per_frame(0).iter().map(|&b| b > 0.0).collect();
    d.set_item(
        "saliva_broken",
        PyArray1::from_vec(py, broken).reshape([f, s])?,
    )?;
    for (a, name) in SALIVA.iter().enumerate().skip(1) {
        d.set_item(*name, PyArray1::from_vec(py, per_frame(a)).reshape([f, s])?)?;
    }
    Ok(d)
}
