//! A run's frames as files the animation packages play ([`crate::io::cache`]): the user's
//! mesh ([`crate::mesh::skin::Skin`]) at rest as `skin.obj`, its vertices in every frame as
//! `skin.pc2` and `skin.mdd`, and `skin.usda` with the mesh's points as time samples and the
//! saliva layer's front faces with their state (`broken`, `moisture`) as per-face primvars.
//!
//! `export.json` says what was written (counts, seconds). [`export`] reads the run's
//! directory (`frames.pvd` and the frames it lists), so it works on a finished run, on an
//! interrupted one (every listed frame is complete), and again later (`sticky-lips export`).
//! A run gathers the same files while it records its frames ([`Recorder`]), so that its own
//! export reads nothing back (on the paper's scene, 101 frames of 1 MB each: 0.38 s of
//! reading saved); the bytes are the same. Positions are `f32` in the user's units and axes,
//! the same values in every file.

use crate::error::{Error, Location, Result};
use crate::io::cache::{mdd_bytes, pc2_bytes, usda_text, UsdLayer, UsdMesh};
use crate::mesh::skin::Skin;
use std::path::Path;

/// The files [`export`] writes (a new run into the directory removes old ones).
pub const FILES: [&str; 7] = [
    "export.json",
    "skin.obj",
    "skin.pc2",
    "skin.mdd",
    "skin.usda",
    "preview.png",
    "preview_sheet.png",
];

/// What [`export`] wrote.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ExportSummary {
    pub frames: usize,
    pub vertices: usize,
    /// Vertices over the model, beside it, elsewhere ([`Skin::counts`]).
    pub tied: [usize; 3],
    pub saliva_faces: usize,
    /// The skin is the model's own outer surface (its vertices are the first nodes).
    pub skin_is_model: bool,
    pub files: Vec<String>,
    /// Seconds spent reading the frames, and writing the files.
    pub read_seconds: f64,
    pub write_seconds: f64,
}

/// The frames `frames.pvd` lists: `(time, file)`.
pub fn read_pvd(dir: &Path) -> Result<Vec<(f64, String)>> {
    let path = dir.join("frames.pvd");
    let text = std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?;
    let name = path.display().to_string();
    let doc = roxmltree::Document::parse(&text)
        .map_err(|e| Error::input(&name, Location::None, e.to_string()))?;
    let mut out = Vec::new();
    for n in doc.descendants().filter(|n| n.has_tag_name("DataSet")) {
        let line = doc.text_pos_at(n.range().start).row as usize;
        let t = n
            .attribute("timestep")
            .and_then(|t| t.parse::<f64>().ok())
            .filter(|t| t.is_finite())
            .ok_or_else(|| {
                Error::input(
                    &name,
                    Location::Line(line),
                    "DataSet without a finite timestep",
                )
            })?;
        let f = n
            .attribute("file")
            .filter(|f| !f.is_empty() && !f.contains('/') && !f.contains('\\'))
            .ok_or_else(|| {
                Error::input(
                    &name,
                    Location::Line(line),
                    "DataSet without a file in this directory",
                )
            })?;
        out.push((t, f.to_string()));
        // a run writes at most MAX_FRAMES + 1 frames (the first at t = 0)
        if out.len() > crate::problem::MAX_FRAMES + 1 {
            return Err(Error::input(
                &name,
                Location::Line(line),
                format!(
                    "lists more than {} frames; a run writes at most {} (not a run's frames.pvd?)",
                    crate::problem::MAX_FRAMES + 1,
                    crate::problem::MAX_FRAMES + 1
                ),
            ));
        }
    }
    Ok(out)
}

/// The skin mapping of `skin` at the frames of `dir` (`frames.pvd`), as JSON, for checking
/// the animation files against the frames outside this crate (`scripts/check_animation.py`):
/// vertex `v` of frame `k` is `to_user(x_v + f sum_i w_i u[n_i] + (1 - f) jaw (R_k - I)(x_v - p))`
/// ([`Skin::positions`]), with `x_v` = `rest[v]` (model frame, m), `u` the frame's nodal
/// displacements, `R_k` the rotation by `jaw_angles[k]` about `jaw_axis` through `jaw_point`,
/// and `to_user(p) = rows^T p / scale`.
pub fn skin_map(skin: &Skin, dir: &Path) -> Result<serde_json::Value> {
    let entries = read_pvd(dir)?;
    let jaw = skin.jaw.as_ref();
    Ok(serde_json::json!({
        "name": skin.name,
        "unit": skin.frame.unit,
        "scale": skin.frame.scale,
        "rows": skin.frame.rows,
        "rest": skin.surface.vertices,
        "nodes": skin.weights.iter().map(|w| w.nodes).collect::<Vec<_>>(),
        "w": skin.weights.iter().map(|w| w.w).collect::<Vec<_>>(),
        "f": skin.weights.iter().map(|w| w.f).collect::<Vec<_>>(),
        "jaw": skin.weights.iter().map(|w| w.jaw).collect::<Vec<_>>(),
        "jaw_point": jaw.map(|j| j.point),
        "jaw_axis": jaw.map(|j| j.axis),
        "times": entries.iter().map(|e| e.0).collect::<Vec<_>>(),
        "jaw_angles": entries
            .iter()
            .map(|e| jaw.map_or(0.0, |j| j.angle * j.curve.value(e.0, true)))
            .collect::<Vec<_>>(),
    }))
}

/// Writes `skin.obj`, `skin.pc2`, `skin.mdd` and `skin.usda` into `dir` from its frames.
pub fn export(skin: &Skin, dir: &Path) -> Result<ExportSummary> {
    export_with(skin, dir, &crate::control::CancelToken::new())
}

/// A position as the files hold it.
fn to32(p: [f64; 3]) -> [f32; 3] {
    p.map(|x| x as f32)
}

/// Refuses frames `entries` (of `dir`'s `frames.pvd`) that are none or not in time order:
/// the files hold one sample per frame in time order.
fn check_frames_listed(entries: &[(f64, String)], dir: &Path) -> Result<()> {
    if entries.is_empty() {
        return Err(Error::input(
            dir.join("frames.pvd").display().to_string(),
            Location::None,
            "lists no frames",
        ));
    }
    // the files hold one sample per frame in time order: frames out of order are refused
    for (k, w) in entries.windows(2).enumerate() {
        if w[1].0 <= w[0].0 {
            return Err(Error::input(
                dir.join("frames.pvd").display().to_string(),
                Location::Field(format!("DataSet {}", k + 1)),
                format!(
                    "{} at t = {} s does not come after {} at t = {} s",
                    w[1].1, w[1].0, w[0].1, w[0].0
                ),
            ));
        }
    }
    Ok(())
}

/// The frames as the files hold them ([`read_frames`]), in the user's units and axes.
struct Frames {
    /// The skin's vertices in each frame.
    skin: Vec<Vec<[f32; 3]>>,
    /// The saliva layer: the model quads whose element is a saliva element (from the first
    /// frame's `saliva_broken`; none if it has none).
    saliva_quads: Vec<usize>,
    /// The model surface's vertices that the saliva quads use (increasing).
    saliva_vertices: Vec<usize>,
    /// In each frame: those vertices, and each saliva quad's `broken` and `moisture`.
    saliva_pts: Vec<Vec<[f32; 3]>>,
    broken: Vec<Vec<f32>>,
    moisture: Vec<Vec<f32>>,
}

impl Frames {
    fn new(capacity: usize) -> Self {
        Frames {
            skin: Vec::with_capacity(capacity),
            saliva_quads: Vec::new(),
            saliva_vertices: Vec::new(),
            saliva_pts: Vec::with_capacity(capacity),
            broken: Vec::new(),
            moisture: Vec::new(),
        }
    }

    /// Adds frame `k` at time `t`: nodal displacements `u` (every model node), and the cell
    /// arrays `saliva_broken` (-1 on elements that are not saliva) and `saliva_moisture`
    /// (`None`: the model has no saliva layer).
    fn push(
        &mut self,
        skin: &Skin,
        t: f64,
        u: &[[f64; 3]],
        broken: Option<&[f64]>,
        moisture: Option<&[f64]>,
    ) {
        let fr = &skin.frame;
        self.skin
            .push(skin.positions(u, t).into_iter().map(to32).collect());
        // the saliva layer: the model quads whose element is a saliva element
        if self.skin.len() == 1 {
            if let Some(b) = broken {
                self.saliva_quads = (0..skin.model.quads.len().min(b.len()))
                    .filter(|&q| b[q] >= 0.0)
                    .collect();
                let used: std::collections::BTreeSet<usize> = self
                    .saliva_quads
                    .iter()
                    .flat_map(|&q| skin.model.quads[q].iter().map(|&v| v as usize))
                    .collect();
                self.saliva_vertices = used.into_iter().collect();
            }
        }
        if !self.saliva_quads.is_empty() {
            let (b, m) = (broken.unwrap_or_default(), moisture.unwrap_or_default());
            self.broken.push(
                self.saliva_quads
                    .iter()
                    .map(|&q| b.get(q).copied().unwrap_or(0.0) as f32)
                    .collect(),
            );
            self.moisture.push(
                self.saliva_quads
                    .iter()
                    .map(|&q| m.get(q).copied().unwrap_or(f64::NAN) as f32)
                    .collect(),
            );
            self.saliva_pts.push(
                self.saliva_vertices
                    .iter()
                    .map(|&v| {
                        let (x, d) = (skin.model.vertices[v], u[v]);
                        to32(fr.to_user([x[0] + d[0], x[1] + d[1], x[2] + d[2]]))
                    })
                    .collect(),
            );
        }
    }
}

/// Reads frames `entries` of `dir`: each frame's displacements (checked) carried onto the
/// skin, and the saliva layer's state. Stopped by `cancel` before each frame.
fn read_frames(
    skin: &Skin,
    dir: &Path,
    entries: &[(f64, String)],
    cancel: &crate::control::CancelToken,
) -> Result<Frames> {
    let mut out = Frames::new(entries.len());
    let need = skin.max_node().map_or(0, |n| n as usize + 1);
    for (k, (t, file)) in entries.iter().enumerate() {
        cancel.check(|| {
            format!(
                "export stopped at frame {k} of {}; no animation file written (they are written together at the end)",
                entries.len()
            )
        })?;
        let path = dir.join(file);
        let u = read_displacement(skin, &path, need)?;
        let broken = crate::io::vtu::read_cell_data(&path, "saliva_broken")
            .ok()
            .map(|s| s.0);
        let moisture = if k == 0 || !out.saliva_quads.is_empty() {
            crate::io::vtu::read_cell_data(&path, "saliva_moisture")
                .ok()
                .map(|s| s.0)
        } else {
            None
        };
        out.push(skin, *t, &u, broken.as_deref(), moisture.as_deref());
    }
    Ok(out)
}

/// The animation files of a run gathered frame by frame while it runs (the driver's export:
/// nothing is read back from the frame files). Its files are byte for byte those that
/// [`export`] writes from the same run's directory afterwards (the frames hold the same `f64`
/// displacements and saliva state).
pub struct Recorder {
    frames: Frames,
    times: Vec<f64>,
    /// The model's element count and its saliva elements, to lay the saliva state out as
    /// the frame files' cell arrays.
    num_elements: usize,
    saliva_elements: Vec<u32>,
    broken: Vec<f64>,
    moisture: Vec<f64>,
}

impl Recorder {
    /// A recorder for a model of `num_elements` elements whose saliva elements are
    /// `saliva_elements` (in the order of each frame's saliva state).
    pub fn new(num_elements: usize, saliva_elements: &[u32]) -> Self {
        Recorder {
            frames: Frames::new(0),
            times: Vec::new(),
            num_elements,
            saliva_elements: saliva_elements.to_vec(),
            broken: Vec::new(),
            moisture: Vec::new(),
        }
    }

    /// Adds the frame at time `t` (after the previous one): displacements `u` of every model
    /// node and the saliva state (`None`: no saliva layer).
    pub fn push(
        &mut self,
        skin: &Skin,
        t: f64,
        u: &[[f64; 3]],
        saliva: Option<&crate::io::output::SalivaFrame>,
    ) {
        // laid out as the frame files' cell arrays, which `read_frames` reads
        if let Some(s) = saliva {
            self.broken.clear();
            self.broken.resize(self.num_elements, -1.0);
            self.moisture.clear();
            self.moisture.resize(self.num_elements, f64::NAN);
            for (k, &e) in self.saliva_elements.iter().enumerate() {
                self.broken[e as usize] = if s.broken[k] { 1.0 } else { 0.0 };
                self.moisture[e as usize] = s.moisture[k];
            }
        }
        let has = saliva.is_some();
        let (b, m) = (
            has.then_some(&self.broken[..]),
            has.then_some(&self.moisture[..]),
        );
        self.frames.push(skin, t, u, b, m);
        self.times.push(t);
    }

    /// Frames added so far.
    pub fn len(&self) -> usize {
        self.times.len()
    }

    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }

    /// Writes the files into `dir` (`export.json` included), as [`export`] does; `read_seconds`
    /// is zero.
    pub fn finish(self, skin: &Skin, dir: &Path) -> Result<ExportSummary> {
        write_files(
            skin,
            dir,
            self.frames,
            &self.times,
            0.0,
            &crate::control::CancelToken::new(),
        )
    }
}

/// The nodal displacements of frame file `path`; fails unless they are 3 components at
/// `need` points or more (and as many as the model's surface nodes), all finite.
fn read_displacement(skin: &Skin, path: &Path, need: usize) -> Result<Vec<[f64; 3]>> {
    let (u, comps, n) = crate::io::vtu::read_point_data_f64(path, "displacement")?;
    if comps != 3 || n < need.max(skin.model.vertices.len()) {
        return Err(Error::input(
            path.display().to_string(),
            Location::Field("displacement".into()),
            format!(
                "has {n} points of {comps} components; the model has {} surface nodes",
                skin.model.vertices.len()
            ),
        ));
    }
    if let Some(i) = u.iter().position(|x| !x.is_finite()) {
        return Err(Error::input(
            path.display().to_string(),
            Location::Field(format!("point data `displacement`, point {}", i / 3)),
            "is not finite: a frame of a run that diverged? (nothing was written)",
        ));
    }
    Ok(u.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
}

/// `skin.usda`'s text: the skin (`rest32`, its rest positions as the files hold them) and the
/// saliva layer's front faces with their state, a time sample per frame at `times`.
fn usda(skin: &Skin, rest32: &[[f32; 3]], frames: Frames, times: &[f64]) -> String {
    let fr = &skin.frame;
    let faces: &[Vec<u32>] = &skin.surface.faces;
    // the saliva mesh holds only the vertices its faces use, renumbered in order
    let local = |v: u32| {
        frames
            .saliva_vertices
            .binary_search(&(v as usize))
            .expect("a saliva quad's vertex is listed") as u32
    };
    let saliva_faces: Vec<Vec<u32>> = frames
        .saliva_quads
        .iter()
        .map(|&q| skin.model.quads[q].iter().map(|&v| local(v)).collect())
        .collect();
    let model_rest: Vec<[f32; 3]> = frames
        .saliva_vertices
        .iter()
        .map(|&v| to32(fr.to_user(skin.model.vertices[v])))
        .collect();
    let uv32: Option<Vec<[f32; 2]>> = skin
        .surface
        .uv
        .as_ref()
        .map(|uv| uv.iter().map(|t| [t[0] as f32, t[1] as f32]).collect());
    let fps = if times.len() > 1 {
        (times.len() - 1) as f64 / (times[times.len() - 1] - times[0])
    } else {
        1.0
    };
    let up_axis = if fr.rows[1][2].abs() > fr.rows[1][1].abs() {
        "Z"
    } else {
        "Y"
    };
    let mut meshes = vec![UsdMesh {
        name: "skin",
        faces,
        rest: rest32,
        frames: &frames.skin,
        uv: uv32.as_deref(),
        face_data: vec![],
    }];
    if !saliva_faces.is_empty() {
        meshes.push(UsdMesh {
            name: "saliva",
            faces: &saliva_faces,
            rest: &model_rest,
            frames: &frames.saliva_pts,
            uv: None,
            face_data: vec![("broken", frames.broken), ("moisture", frames.moisture)],
        });
    }
    let doc = format!(
        "sticky-lips run: {} ({} frames, time code k = frame k, {} per simulated second)",
        skin.name,
        frames.skin.len(),
        fps
    );
    usda_text(&UsdLayer {
        doc: &doc,
        up_axis,
        metres_per_unit: fr.scale,
        frames_per_second: fps,
        meshes,
    })
}

/// [`export`], stopped by `cancel` between two frames (nothing is written then).
pub fn export_with(
    skin: &Skin,
    dir: &Path,
    cancel: &crate::control::CancelToken,
) -> Result<ExportSummary> {
    let t0 = std::time::Instant::now();
    let entries = read_pvd(dir)?;
    check_frames_listed(&entries, dir)?;
    let times: Vec<f64> = entries.iter().map(|e| e.0).collect();
    let frames = read_frames(skin, dir, &entries, cancel)?;
    write_files(
        skin,
        dir,
        frames,
        &times,
        t0.elapsed().as_secs_f64(),
        cancel,
    )
}

/// Writes the animation files of `frames` (at `times`) and `export.json` into `dir`.
fn write_files(
    skin: &Skin,
    dir: &Path,
    frames: Frames,
    times: &[f64],
    read_seconds: f64,
    cancel: &crate::control::CancelToken,
) -> Result<ExportSummary> {
    let fr = &skin.frame;
    let t1 = std::time::Instant::now();
    // the rest mesh in the user's units and axes
    let mut rest = skin.surface.clone();
    for v in rest.vertices.iter_mut() {
        *v = fr.to_user(*v);
    }
    let rest32: Vec<[f32; 3]> = rest.vertices.iter().map(|&p| to32(p)).collect();
    let (n_frames, saliva_faces) = (frames.skin.len(), frames.saliva_quads.len());
    let pc2 = pc2_bytes(&frames.skin, 0.0);
    let mdd = mdd_bytes(&frames.skin, times);
    let usda = usda(skin, &rest32, frames, times);
    let mut obj = Vec::new();
    crate::io::obj::write_polygons_to(&mut obj, &rest)
        .map_err(|e| Error::io(dir.join("skin.obj"), e))?;
    let files: [(&str, Vec<u8>); 4] = [
        ("skin.obj", obj),
        ("skin.pc2", pc2),
        ("skin.mdd", mdd),
        ("skin.usda", usda.into_bytes()),
    ];
    cancel.check(|| {
        "export stopped after reading every frame; no animation file written".to_string()
    })?;
    for (name, bytes) in &files {
        let p = dir.join(name);
        crate::io::atomic::write_atomic(&p, bytes).map_err(|e| Error::io(&p, e))?;
    }
    let summary = ExportSummary {
        frames: n_frames,
        vertices: rest.vertices.len(),
        tied: skin.counts,
        saliva_faces,
        skin_is_model: skin.surface.vertices == skin.model.vertices,
        files: files.iter().map(|f| f.0.to_string()).collect(),
        read_seconds,
        write_seconds: t1.elapsed().as_secs_f64(),
    };
    let p = dir.join("export.json");
    let json = serde_json::to_vec_pretty(&summary).expect("export summary serialises");
    crate::io::atomic::write_atomic(&p, &json).map_err(|e| Error::io(&p, e))?;
    Ok(summary)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `frames.pvd` of more entries than a run writes (one of 200 000 ran for minutes) is
    /// refused while it is read, with the file and line, before any frame is opened.
    #[test]
    fn a_pvd_longer_than_any_run_is_refused() {
        let dir = std::env::temp_dir().join(format!("sticky_lips_long_pvd_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let n = crate::problem::MAX_FRAMES + 2;
        let entries: Vec<crate::io::vtu::PvdEntry> = (0..n)
            .map(|i| crate::io::vtu::PvdEntry {
                time: i as f64,
                file: format!("frame_{i:06}.vtu"),
            })
            .collect();
        crate::io::vtu::write_pvd(&dir.join("frames.pvd"), &entries).unwrap();
        let e = read_pvd(&dir).unwrap_err().to_string();
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(
            e.contains("frames.pvd:") && e.contains("lists more than 100001 frames"),
            "{e}"
        );
    }
}
