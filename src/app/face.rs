//! A user's head to a runnable model directory (`sticky-lips face`, the Python package's
//! `face()`): the head read and checked, its units and axes detected or taken as given, the
//! lips found ([`crate::mesh::face::prepare`]), the model built
//! ([`crate::mesh::face::build`]), and its files written together into the output directory
//! (a refusal or a cancellation leaves nothing there).

use crate::control::CancelToken;
use crate::error::{Error, Location, Result};
use crate::io::scenario;
use crate::mesh::face;
use crate::mesh::surface::PolySurface;
use std::path::Path;

/// What to build, and where; the values are checked by [`face`] (errors name the command
/// line's option, `--units` etc., as the CLI spells them).
#[derive(Clone, Debug)]
pub struct FaceJob<'a> {
    /// The head (OBJ).
    pub input: &'a Path,
    /// A rig (JSON): named lips, jaw weights, blend-shape targets.
    pub rig: Option<&'a Path>,
    /// The head's length unit (m, dm, cm, mm, in) or `auto` (from its size).
    pub units: &'a str,
    /// The head's up and forward axes (`x,y,z`), or both `auto` (detected).
    pub up: &'a str,
    pub forward: &'a str,
    /// The crop parameters (TOML, [`face::PrepareParams`]).
    pub params: Option<&'a Path>,
    /// The model's resolution (1: the paper's, [`face::FaceParams`]).
    pub resolution: f64,
    /// The output directory.
    pub out: &'a Path,
}

/// What [`face`] did, for the front end to show.
#[derive(Clone, Debug, PartialEq)]
pub struct FaceReport {
    /// The unit detected from the head's size, when `units` was `auto`.
    pub detected_unit: Option<&'static str>,
    /// What the pipeline decided on the way (axes detected, folds trimmed, ...).
    pub notes: Vec<String>,
    /// Wall time (s).
    pub seconds: f64,
}

/// The files [`face`] writes into its output directory.
pub const FACE_OUTPUTS: [&str; 9] = [
    "face.obj",
    "face.json",
    "head.obj",
    "head.json",
    "model.obj",
    "mesh.vtu",
    "model.xml",
    "groups.png",
    "scenario.toml",
];

/// Metres per unit of a length unit's name.
fn unit_scale(name: &str) -> Option<f64> {
    scenario::LengthUnit::from_name(name).map(scenario::LengthUnit::metres)
}

fn unknown_unit(units: &str) -> Error {
    Error::input(
        "command line",
        Location::Field("--units".into()),
        format!("unknown unit `{units}` (m, dm, cm, mm, in or auto)"),
    )
}

/// The unit in which a head's largest extent (of the vertices its faces use) is that of a
/// human head, 0.12 to 0.45 m; an error naming the candidates when none or several are.
pub fn detect_units(head: &PolySurface, file: &str) -> Result<(&'static str, f64)> {
    let (lo, hi) = crate::linalg::bounding_box(
        head.faces
            .iter()
            .flatten()
            .map(|&v| &head.vertices[v as usize]),
    );
    let extent = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
    let fits: Vec<(&'static str, f64)> = scenario::LengthUnit::ALL
        .iter()
        .map(|u| (u.name(), u.metres()))
        .filter(|&(_, s)| (0.12..=0.45).contains(&(extent * s)))
        .collect();
    match fits.as_slice() {
        [one] => Ok(*one),
        _ => Err(Error::input(
            file,
            Location::Field("--units".into()),
            format!(
                "the head's largest extent is {extent} units, a head's (0.12 to 0.45 m) in {}: give --units",
                if fits.is_empty() {
                    "none of m, dm, cm, mm, in".to_string()
                } else {
                    fits.iter().map(|f| f.0).collect::<Vec<_>>().join(" and ")
                }
            ),
        )),
    }
}

/// The job's own values, before any file is read: the axes given (`None`: detect both).
fn check_values(a: &FaceJob) -> Result<Option<([f64; 3], [f64; 3])>> {
    let detect = match (a.up == "auto", a.forward == "auto") {
        (true, true) => true,
        (false, false) => false,
        _ => {
            return Err(Error::input(
                "command line",
                Location::Field(if a.up == "auto" { "--up" } else { "--forward" }.into()),
                "give both --up and --forward, or neither (both detected)",
            ))
        }
    };
    let given = if detect {
        None
    } else {
        Some((
            crate::io::args::vec3(a.up, "--up")?,
            crate::io::args::vec3(a.forward, "--forward")?,
        ))
    };
    if a.units != "auto" && unit_scale(a.units).is_none() {
        return Err(unknown_unit(a.units));
    }
    // the model's parameters (only the resolution comes from the job) before the head is
    // read: a model too large for the memory budget is refused here
    face::FaceParams {
        resolution: a.resolution,
        ..Default::default()
    }
    .validate("command line", "--")?;
    // nothing the job writes may land on one of its inputs
    let mut inputs = vec![(a.input, "the head")];
    if let Some(r) = a.rig {
        inputs.push((r, "the rig (--rig)"));
    }
    if let Some(p) = a.params {
        inputs.push((p, "the crop parameters (--params)"));
    }
    crate::io::atomic::refuse_overwriting_inputs(a.out, &FACE_OUTPUTS, &inputs)?;
    Ok(given)
}

/// The rig and the crop parameters, from their files or the defaults.
fn read_rig_and_params(a: &FaceJob) -> Result<(face::FaceRig, face::PrepareParams)> {
    let rig = match a.rig {
        Some(p) => {
            let text = std::fs::read_to_string(p).map_err(|e| Error::io(p, e))?;
            face::FaceRig::from_json(&text, &p.display().to_string())?
        }
        None => face::FaceRig::default(),
    };
    let params = match a.params {
        Some(path) => scenario::read_toml(path)?,
        None => face::PrepareParams::default(),
    };
    Ok((rig, params))
}

/// Builds the model of the head in `a.input` and writes [`FACE_OUTPUTS`] into `a.out`
/// (module docs). `cancel` stops it before anything is written.
pub fn face(a: &FaceJob, cancel: &CancelToken) -> Result<FaceReport> {
    let t0 = std::time::Instant::now();
    let file = a.input.display().to_string();
    // the job's values first, then the files
    let given = check_values(a)?;
    let head = crate::io::obj::read_polygons(a.input)?;
    face::check_head_size(&head, &file)?;
    cancel.check(|| "face stopped after reading the head; nothing written".into())?;
    let (detected_unit, scale) = if a.units == "auto" {
        let (unit, scale) = detect_units(&head, &file)?;
        (Some(unit), scale)
    } else {
        (
            None,
            unit_scale(a.units).ok_or_else(|| unknown_unit(a.units))?,
        )
    };
    let (rig, params) = read_rig_and_params(a)?;
    let (up, forward, axes_note) = match given {
        Some((up, forward)) => (up, forward, None),
        None => {
            let d = face::lips::detect_axes(&head, scale, &params, &file, cancel)?;
            (d.up, d.forward, Some(d.note))
        }
    };
    let frame = face::InputFrame { scale, up, forward };
    let mut src = face::prepare_with(&head, &rig, frame, &params, &file, cancel)?;
    if let Some(n) = axes_note {
        src.data.notes.insert(0, n);
    }
    let fp = face::FaceParams {
        resolution: a.resolution,
        ..Default::default()
    };
    // the model is built, its scenario parsed and its picture drawn before anything is
    // written: a refusal leaves no partial output
    let model = face::build(&src, &fp, &file)?;
    write_model_dir(a, &src, &model, cancel)?;
    Ok(FaceReport {
        detected_unit,
        notes: src.data.notes.iter().chain(&model.notes).cloned().collect(),
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// Writes the source, the model, its scenario and its groups' picture into a staging
/// directory, and moves them into `a.out` together once all are written.
fn write_model_dir(
    a: &FaceJob,
    src: &face::FaceSource,
    model: &face::FaceModel,
    cancel: &CancelToken,
) -> Result<()> {
    let stopped = || "face stopped before writing anything".to_string();
    cancel.check(stopped)?;
    let staging =
        crate::io::atomic::Staging::new(a.out, "face").map_err(|e| Error::io(a.out, e))?;
    let dir = staging.path();
    face::write_dir(dir, src)?;
    crate::io::obj::write_obj(&dir.join("model.obj"), &model.surface)?;
    let groups: Vec<(String, Vec<u32>)> = ["upper_face", "lower_face", "saliva"]
        .iter()
        .map(|g| {
            (
                g.to_string(),
                model.mesh.element_sets.get(*g).cloned().unwrap_or_default(),
            )
        })
        .collect();
    super::mesh_outputs::write(dir, &model.mesh, &groups)?;
    // a scenario that runs on it as it is: Table 1, the wide jaw opening with stickiness
    let label = a.out.join("scenario.toml").display().to_string();
    let path = dir.join("scenario.toml");
    let text = format!(
        "# sticky-lips face {}: Table 1 on this face (the paper's wide jaw opening with\n\
         # stickiness); `sticky-lips run {label}`.\n{}",
        a.input.display(),
        scenario::with_overrides(
            crate::paper::TABLE1,
            crate::paper::TABLE1_NAME,
            &[
                ("mesh.file", toml::Value::String(".".into())),
                ("mesh.face.resolution", toml::Value::Float(a.resolution)),
                ("output.dir", toml::Value::String("run".into())),
                (
                    "title",
                    toml::Value::String(format!(
                        "Table 1 on {}: wide jaw opening, with stickiness",
                        a.input.display()
                    )),
                ),
            ],
        )?
    );
    let problem = scenario::parse(&text, &path)?.problem;
    cancel.check(stopped)?;
    crate::io::atomic::write_atomic(&path, text.as_bytes()).map_err(|e| Error::io(&path, e))?;
    // and a picture of its material groups
    if let Some(cols) = &problem.physics.lip_columns {
        let img = super::look::groups_picture(&problem, cols, 900, 560);
        crate::render::save_png(&dir.join("groups.png"), &img)?;
    }
    // every file is written and checked: all move into the output directory together
    cancel.check(stopped)?;
    staging.commit().map_err(|e| Error::io(a.out, e))?;
    Ok(())
}
