//! Scenario files (TOML): mesh source, node sets, materials, boundary conditions and
//! loads, time stepping, numerics, output. Quantities are SI unless `[units] length`
//! says otherwise, in which case every length in the file (coordinates, sizes, boxes,
//! displacement values, rotation points) is converted to metres here, on reading.
//! Unknown keys are errors (a typo must not be silently ignored). See
//! `examples/cantilever.toml` for a complete, commented example.

use crate::boundary::{
    BoundaryConditions, Fixed, Gravity, LoadCurve, LoadShape, NodalForce, PrescribedDisplacement,
    PrescribedRotation,
};
use crate::element::hex8::GradientVariant;
use crate::error::{Error, Location, Result};
use crate::material::NeoHookean;
use crate::mesh::{generate, Mesh};
use crate::muscle::Muscle;
use crate::problem::{table1, MaterialSpec, Numerics, Physics, Problem, SalivaSet, TimeSettings};
use serde::Deserialize;
use std::path::{Path, PathBuf};

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct ScenarioFile {
    pub title: Option<String>,
    #[serde(default)]
    pub units: Units,
    pub mesh: MeshSection,
    #[serde(default)]
    pub node_sets: Vec<NodeSetDef>,
    pub materials: Vec<MaterialDef>,
    #[serde(default)]
    pub fix: Vec<FixDef>,
    #[serde(default)]
    pub displacement: Vec<DisplacementDef>,
    #[serde(default)]
    pub rotation: Vec<RotationDef>,
    #[serde(default)]
    pub force: Vec<ForceDef>,
    pub gravity: Option<GravityDef>,
    #[serde(default)]
    pub saliva: Vec<SalivaDef>,
    #[serde(default)]
    pub muscle: Vec<MuscleDef>,
    /// The jaw opening (mouth models only: generators `mouth` and `face`): rotation of the
    /// model's jaw nodes about its hinge.
    pub jaw: Option<JawDef>,
    /// Muscles of the mouth model, by name (generators `mouth` and `face`).
    #[serde(default)]
    pub model_muscle: Vec<ModelMuscleDef>,
    /// Keyed moisture: saliva wetted over time, by zone of the mouth or element set.
    #[serde(default)]
    pub wet: Vec<WetDef>,
    pub time: TimeDef,
    #[serde(default)]
    pub numerics: NumericsDef,
    #[serde(default)]
    pub output: OutputDef,
}

#[derive(Deserialize, Debug, Default)]
#[serde(deny_unknown_fields)]
pub struct Units {
    /// `"m"` (default), `"dm"`, `"cm"`, `"mm"` or `"in"`.
    pub length: Option<LengthUnit>,
}

/// A length unit: of a scenario file's coordinates, sizes and displacements (`[units]
/// length`), and of a head's OBJ (`face --units`). The one table of units in the project.
#[derive(Deserialize, Debug, Default, Clone, Copy, PartialEq, Eq)]
pub enum LengthUnit {
    #[default]
    #[serde(rename = "m")]
    Metre,
    #[serde(rename = "dm")]
    Decimetre,
    #[serde(rename = "cm")]
    Centimetre,
    #[serde(rename = "mm")]
    Millimetre,
    #[serde(rename = "in")]
    Inch,
}

impl LengthUnit {
    /// Every unit, largest first.
    pub const ALL: [LengthUnit; 5] = [
        LengthUnit::Metre,
        LengthUnit::Decimetre,
        LengthUnit::Centimetre,
        LengthUnit::Millimetre,
        LengthUnit::Inch,
    ];

    /// Metres per unit.
    pub fn metres(self) -> f64 {
        match self {
            LengthUnit::Metre => 1.0,
            LengthUnit::Decimetre => 0.1,
            LengthUnit::Centimetre => 1e-2,
            LengthUnit::Millimetre => 1e-3,
            LengthUnit::Inch => 0.0254,
        }
    }

    /// The unit's symbol (`m`, `dm`, `cm`, `mm`, `in`), as files and the command line write it.
    pub fn name(self) -> &'static str {
        match self {
            LengthUnit::Metre => "m",
            LengthUnit::Decimetre => "dm",
            LengthUnit::Centimetre => "cm",
            LengthUnit::Millimetre => "mm",
            LengthUnit::Inch => "in",
        }
    }

    /// The unit of symbol `name`, if any.
    pub fn from_name(name: &str) -> Option<LengthUnit> {
        LengthUnit::ALL.into_iter().find(|u| u.name() == name)
    }
}

/// `mesh.generator`: where the mesh comes from.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Generator {
    /// A box of `cells` hexahedra (`origin`, `size`).
    Block,
    /// A box with its interior nodes moved at random (`distortion`, `seed`).
    DistortedBlock,
    /// Boxes stacked along z (`layers`).
    Layers,
    /// The procedural mouth (`[mesh.mouth]`).
    Mouth,
    /// A real face (`file`, `[mesh.face]`).
    Face,
    /// The nodes, elements and element sets of a NiftySim XML model (`file`).
    Niftysim,
}

/// `materials[].model`: the constitutive law.
#[derive(Deserialize, Debug, Default, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum MaterialModel {
    #[default]
    NeoHookean,
}

/// `fix[].dofs`: `"all"` or a list of DOFs (`"x"`, `"y"`, `"z"` or `0`, `1`, `2`), read as a
/// mask of the three DOFs.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(try_from = "toml::Value")]
pub struct DofMask(pub [bool; 3]);

impl TryFrom<toml::Value> for DofMask {
    type Error = String;
    fn try_from(v: toml::Value) -> std::result::Result<Self, String> {
        let mut mask = [false; 3];
        match &v {
            toml::Value::String(s) if s == "all" => Ok(DofMask([true; 3])),
            toml::Value::Array(a) if !a.is_empty() => {
                for d in a {
                    let k = match d {
                        toml::Value::String(s) => dof_of_name(s),
                        toml::Value::Integer(k) => (0..3).contains(k).then_some(*k as usize),
                        _ => None,
                    };
                    let k =
                        k.ok_or_else(|| format!("dofs: {d} is not a DOF (x, y, z or 0, 1, 2)"))?;
                    mask[k] = true;
                }
                Ok(DofMask(mask))
            }
            _ => Err(format!(
                "dofs: expected \"all\" or a list like [\"x\", \"z\"], got {v}"
            )),
        }
    }
}

fn dof_of_name(s: &str) -> Option<usize> {
    match s {
        "x" => Some(0),
        "y" => Some(1),
        "z" => Some(2),
        _ => None,
    }
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct MeshSection {
    pub generator: Generator,
    pub origin: Option<[f64; 3]>,
    pub size: Option<[f64; 3]>,
    pub cells: Option<[usize; 3]>,
    /// Interior node displacement as a fraction of the cell size (`distorted_block`).
    pub distortion: Option<f64>,
    pub seed: Option<u64>,
    /// Mesh file, relative to the scenario file (`niftysim`); for `face`, a directory with
    /// `face.obj` and `face.json` (as `sticky-lips face` writes them; default: the shipped
    /// MakeHuman face).
    pub file: Option<PathBuf>,
    /// Layers stacked along z, bottom first (`layers`): `{ name, thickness, cells }`.
    pub layers: Option<Vec<generate::Layer>>,
    /// Parameters of the procedural mouth (`mouth`); every field has a default (SI units,
    /// not affected by `[units]`).
    pub mouth: Option<crate::mesh::mouth::MouthParams>,
    /// Parameters of the face model (`face`): subdivision level, thickness, jaw weight
    /// threshold, muscles; every field has a default (SI units, not affected by `[units]`).
    pub face: Option<crate::mesh::face::FaceParams>,
}

/// `[jaw]`: the angle (rad, positive opens) and its curve.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct JawDef {
    /// The opening (rad) the curve's value multiplies; with keys, default 1 (the keys are
    /// then the angle itself).
    pub angle: Option<f64>,
    #[serde(flatten)]
    pub curve: CurveDef,
}

/// `[[wet]]`: moisture added to the saliva of a zone over time (um, the curve's value times
/// `amount`; with keys, `amount` defaults to 1 and the keys are the moisture added).
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct WetDef {
    /// `left`, `right` (the subject's: `+x` is left), `centre` (the middle third of the
    /// mouth's width, left and right the outer thirds) or `all` (mouth models).
    pub zone: Option<String>,
    /// Or the saliva elements of an element set.
    pub elements: Option<String>,
    pub amount: Option<f64>,
    #[serde(flatten)]
    pub curve: CurveDef,
}

/// `[[model_muscle]]`: one of the mouth model's muscles (e.g.
/// `depressor_labii_inferioris_l`), with its strength (N) and activation curve.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct ModelMuscleDef {
    pub name: String,
    pub strength: f64,
    pub activation: Option<f64>,
    #[serde(flatten)]
    pub curve: CurveDef,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct NodeSetDef {
    pub name: String,
    /// Nodes inside this axis-aligned box (inclusive, with a relative tolerance of 1e-9).
    pub box_min: Option<[f64; 3]>,
    pub box_max: Option<[f64; 3]>,
    /// Explicit node indices.
    pub nodes: Option<Vec<u32>>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(untagged)]
pub enum NodeRef {
    Set(String),
    List(Vec<u32>),
}

#[derive(Deserialize, Debug, Clone)]
#[serde(untagged)]
pub enum DofRef {
    Name(String),
    Index(usize),
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct MaterialDef {
    pub name: String,
    /// Element set the material applies to (`"all"` by default).
    pub elements: Option<String>,
    /// The constitutive law (`"neo_hookean"`, the default and only one).
    pub model: Option<MaterialModel>,
    /// Shear modulus (Pa).
    pub mu: f64,
    /// Bulk modulus (Pa).
    #[serde(rename = "K")]
    pub bulk: f64,
    /// Density (kg/m^3).
    pub density: f64,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct FixDef {
    pub nodes: NodeRef,
    /// `"all"` or a list of `"x"`, `"y"`, `"z"` (default `"all"`).
    pub dofs: Option<DofMask>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct CurveDef {
    /// `ramp`, `poly345`, `step`, `hilly`, `ramphold`, `smooth_step`.
    pub shape: Option<String>,
    /// Start time (s), default 0.
    pub start: Option<f64>,
    /// Duration (s), default the whole run.
    pub duration: Option<f64>,
    /// Keyframes `[[time, value], ...]` (s), interpolated linearly: the curve's value over
    /// time, in place of `shape`, `start` and `duration`.
    pub keys: Option<Vec<[f64; 2]>>,
    /// Keyframes from a file an animation package exported (CSV or JSON, `io::keys`),
    /// relative to the scenario.
    pub keys_file: Option<String>,
    /// The keys' times are frame numbers at this rate (frames per second).
    pub keys_fps: Option<f64>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct DisplacementDef {
    pub nodes: NodeRef,
    pub dof: DofRef,
    /// Final displacement (length unit of the file).
    pub value: f64,
    #[serde(flatten)]
    pub curve: CurveDef,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct RotationDef {
    pub nodes: NodeRef,
    /// A point on the hinge axis (length unit of the file).
    pub point: [f64; 3],
    /// Axis direction (normalised on reading).
    pub axis: [f64; 3],
    /// Final angle (rad), right-handed about `axis`.
    pub angle: f64,
    #[serde(flatten)]
    pub curve: CurveDef,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct ForceDef {
    pub nodes: NodeRef,
    pub dof: DofRef,
    /// Force on each node (N).
    pub value: f64,
    #[serde(flatten)]
    pub curve: CurveDef,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct GravityDef {
    /// Acceleration vector (m/s^2).
    pub acceleration: [f64; 3],
    #[serde(flatten)]
    pub curve: CurveDef,
}

/// A saliva material (paper section 3.4). Moisture is in micrometres of film.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct SalivaDef {
    /// Name of the material (in `[[materials]]`) whose elements are saliva.
    pub material: String,
    /// Critical moisture `M_c` (um).
    pub critical_moisture: f64,
    /// Maximum glue strength `K` of eq. (7).
    pub k_glue: f64,
    /// Initial moisture `0M` (um): a number, or a map (see `MoistureDef`).
    pub initial_moisture: MoistureDef,
    /// Constant evaporation rate `phi` (um/s); default 0 (Table 1).
    pub evaporation_rate: Option<f64>,
    /// Piecewise-constant evaporation: `{ starts = [0.0, ...], rates = [...] }` (s, um/s).
    pub evaporation: Option<EvaporationDef>,
    /// `"literal"` (default) or `"latched"`.
    pub rule: Option<crate::material::saliva::BreakingRule>,
    /// Force factor per step once broken (default 0.99, the paper's).
    pub decay_per_step: Option<f64>,
    /// Alternatively a dt-independent decay time (s).
    pub decay_time: Option<f64>,
    /// Local y axis (across the layer) for all elements; default: each element's thin direction.
    pub across: Option<[f64; 3]>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct EvaporationDef {
    pub starts: Vec<f64>,
    pub rates: Vec<f64>,
}

/// Initial moisture: `90.0`, or one of the tables
/// `{ gradient = { axis = [1,0,0], from = [x0, m0], to = [x1, m1] } }`,
/// `{ bands = { axis = [1,0,0], edges = [x1, x2], values = [m0, m1, m2] } }`,
/// `{ left_right = { axis = [1,0,0], center = 0.0, left = m_l, right = m_r } }`,
/// `{ file = "moisture.csv" }` (one value per saliva element, in element order; `#` comments).
/// Coordinates are in the file's length unit.
#[derive(Deserialize, Debug)]
#[serde(untagged)]
pub enum MoistureDef {
    Constant(f64),
    Map(MoistureMapDef),
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub enum MoistureMapDef {
    Gradient {
        axis: [f64; 3],
        from: [f64; 2],
        to: [f64; 2],
    },
    Bands {
        axis: [f64; 3],
        edges: Vec<f64>,
        values: Vec<f64>,
    },
    LeftRight {
        axis: [f64; 3],
        center: f64,
        left: f64,
        right: f64,
    },
    File(PathBuf),
}

/// A linear vector muscle (paper section 3.3).
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct MuscleDef {
    pub name: String,
    /// Origin (attached end) and insertion (pulled end), in the file's length unit.
    pub origin: [f64; 3],
    pub insertion: [f64; 3],
    pub radius: f64,
    /// Total force at full activation (N), shared equally by the nodes in the cylinder.
    pub strength: f64,
    /// Peak activation in [0, 1] (default 1).
    pub activation: Option<f64>,
    #[serde(flatten)]
    pub curve: CurveDef,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct TimeDef {
    /// Time step (s), or `"auto"`: [`AUTO_DT_FRACTION`] (or `dt_fraction`) of the model's
    /// critical step, rounded down so that a whole number of steps fills `output_interval`.
    pub dt: DtDef,
    /// Simulated time (s).
    pub total: f64,
    /// Steps between output frames (default: 100); not with `dt = "auto"`.
    pub output_every: Option<usize>,
    /// With `dt = "auto"`: seconds between output frames (default 1 ms: 100 steps of Table
    /// 1's 1e-5 s).
    pub output_interval: Option<f64>,
    /// With `dt = "auto"`: the fraction of the critical step (default [`AUTO_DT_FRACTION`]).
    pub dt_fraction: Option<f64>,
    /// Substeps of the saliva layer per step (`tled::subcycle`; default 1, single rate), or
    /// `"auto"`: as many as the saliva's critical step needs, with `dt = "auto"` a large step
    /// set by the tissue's critical step.
    pub subcycles: Option<SubcyclesDef>,
}

/// `[time] subcycles`: a count or `"auto"`.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq)]
#[serde(untagged)]
pub enum SubcyclesDef {
    Count(i64),
    Auto(AutoWord),
}

/// `[time] dt`: seconds or `"auto"`.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq)]
#[serde(untagged)]
pub enum DtDef {
    Seconds(f64),
    Auto(AutoWord),
}

/// The word `auto`.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq)]
#[serde(rename_all = "lowercase")]
pub enum AutoWord {
    Auto,
}

/// The fraction of the critical step `2 / omega_max` that `dt = "auto"` takes. The critical
/// step is that of the undeformed model (`tled::stability`); as the lips deform, stretched
/// saliva and compressed tissue stiffen and the true limit falls, so a margin is kept: 0.8.
/// Measured on the paper's scene (issue 30): the wide opening at 85 % of the critical step
/// ran to the end, its lip gaps within 0.12 mm of the run at Table 1's step.
pub const AUTO_DT_FRACTION: f64 = 0.8;

/// With `subcycles = "auto"` and `dt = "auto"`, the large step is at most this many times
/// the whole model's critical step (and at most the tissue's): the subcycled scheme
/// (`tled::subcycle`) was measured free of energy growth, undamped, at 1.8 times it with 4
/// substeps, and showed slow growth in bands from 2.5 times it (`paper/README.md`,
/// "Subcycling").
pub const SUBCYCLED_STEP_RATIO: f64 = 2.0;

/// Paper eq. (11): Table 1's decay of a broken saliva element's forces, 0.99 per step of 1e-5 s, as a decay
/// time (s): `-1e-5 / ln 0.99`. With `dt = "auto"` the decay is given in physical time.
pub fn table1_decay_time() -> f64 {
    -table1::TIME_STEP / table1::DECAY_PER_STEP.ln()
}

#[derive(Deserialize, Debug, Default)]
#[serde(deny_unknown_fields)]
pub struct NumericsDef {
    /// Mass-proportional damping `alpha` (1/s), default 0.
    pub damping: Option<f64>,
    /// Hourglass coefficient `kappa`, default `Numerics::default()` (Table 1's 0.075).
    pub hourglass_kappa: Option<f64>,
    /// `"mean_gradient"` (default) or `"centroid"`.
    pub variant: Option<GradientVariant>,
}

#[derive(Deserialize, Debug, Default)]
#[serde(deny_unknown_fields)]
pub struct OutputDef {
    /// Default output directory, relative to the scenario file.
    pub dir: Option<PathBuf>,
}

/// A scenario read from disk: the problem and where its outputs go by default.
pub struct Scenario {
    pub problem: Problem,
    pub title: Option<String>,
    pub default_output: Option<PathBuf>,
}

/// The largest scenario file read (16 MiB): a scenario is a few kilobytes; 10^7 inline keys
/// (about 150 MB of text) took gigabytes in the TOML parser and aborted. Long key lists
/// belong in a `keys_file` ([`crate::io::keys::MAX_KEYS_FILE_BYTES`]).
pub const MAX_SCENARIO_BYTES: u64 = 16 << 20;

fn too_large(file: &str, bytes: u64) -> Error {
    Error::input(
        file,
        Location::None,
        format!(
            "is {bytes} bytes; a scenario may have at most {MAX_SCENARIO_BYTES} (16 MiB): put long \
             key lists in a keys_file (CSV or JSON)"
        ),
    )
}

pub fn read(path: &Path) -> Result<Scenario> {
    parse(&read_text(path)?, path)
}

/// A scenario file's text, at most [`MAX_SCENARIO_BYTES`].
pub fn read_text(path: &Path) -> Result<String> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if meta.is_file() && meta.len() > MAX_SCENARIO_BYTES {
        return Err(too_large(&path.display().to_string(), meta.len()));
    }
    std::fs::read_to_string(path).map_err(|e| Error::io(path, e))
}

/// The scenario text `text` (named `file` in errors) with some values replaced: each
/// override is a dotted key path (`"mesh.face.resolution"`, `"saliva.0.k_glue"`) and its
/// new value; missing tables are created. Returns the new TOML text (comments are lost).
pub fn with_overrides(text: &str, file: &str, overrides: &[(&str, toml::Value)]) -> Result<String> {
    let doc: toml::Table = from_toml(text, file)?;
    let mut doc = toml::Value::Table(doc);
    for (key, value) in overrides {
        let parts: Vec<&str> = key.split('.').collect();
        let mut cur = &mut doc;
        for (i, p) in parts.iter().enumerate() {
            let last = i + 1 == parts.len();
            cur = match cur {
                toml::Value::Table(t) => {
                    if last {
                        t.insert(p.to_string(), value.clone());
                        break;
                    }
                    t.entry(p.to_string())
                        .or_insert_with(|| toml::Value::Table(toml::Table::new()))
                }
                toml::Value::Array(a) => {
                    let k: usize = p.parse().map_err(|_| {
                        Error::field(file, key.to_string(), "expected an array index")
                    })?;
                    let n = a.len();
                    let slot = a.get_mut(k).ok_or_else(|| {
                        Error::field(file, key.to_string(), format!("index {k} out of {n}"))
                    })?;
                    if last {
                        *slot = value.clone();
                        break;
                    }
                    slot
                }
                _ => {
                    return Err(Error::field(
                        file,
                        key.to_string(),
                        "override path crosses a plain value",
                    ))
                }
            };
        }
    }
    Ok(toml::to_string(&doc).expect("a TOML table serialises"))
}

/// A time step chosen on the command line (`--dt auto|SECONDS`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DtChoice {
    Auto,
    Seconds(f64),
}

impl std::str::FromStr for DtChoice {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        if s == "auto" {
            return Ok(DtChoice::Auto);
        }
        match s.parse::<f64>() {
            Ok(x) if x.is_finite() && x > 0.0 => Ok(DtChoice::Seconds(x)),
            _ => Err(format!(
                "`{s}`: give auto or a time step in seconds (a positive number)"
            )),
        }
    }
}

/// The scenario text `text` (named `file` in errors) run at another time step, with what
/// depends on the step kept in physical time: the frames' interval (`output_every` steps of
/// the old step become `output_interval` seconds, or the steps of the new one) and eq. 11's
/// decay (a `decay_per_step` of the old step becomes the `decay_time` it amounts to). For
/// `--dt` on `run`, `paper` and `sweep`. Returns the new TOML text (comments are lost).
pub fn with_dt(text: &str, file: &str, dt: DtChoice) -> Result<String> {
    let mut doc: toml::Table = from_toml(text, file)?;
    let time = doc
        .get_mut("time")
        .and_then(|t| t.as_table_mut())
        .ok_or_else(|| Error::field(file, "time", "missing: --dt needs the scenario's [time]"))?;
    let num = |v: Option<&toml::Value>| {
        v.and_then(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64)))
    };
    let old_dt = num(time.get("dt"));
    // the frames' interval in seconds, as the scenario has it
    let interval = match old_dt {
        Some(d) => {
            let every = time
                .get("output_every")
                .and_then(|v| v.as_integer())
                .unwrap_or(table1::OUTPUT_EVERY as i64);
            every as f64 * d
        }
        None => num(time.get("output_interval"))
            .unwrap_or(table1::OUTPUT_EVERY as f64 * table1::TIME_STEP),
    };
    time.remove("output_every");
    time.remove("output_interval");
    match dt {
        DtChoice::Auto => {
            time.insert("dt".into(), toml::Value::String("auto".into()));
            time.insert("output_interval".into(), toml::Value::Float(interval));
        }
        DtChoice::Seconds(x) => {
            time.remove("dt_fraction");
            time.insert("dt".into(), toml::Value::Float(x));
            let every = (interval / x).round().max(1.0);
            time.insert("output_every".into(), toml::Value::Integer(every as i64));
        }
    }
    // eq. 11's decay in physical time: per step of the old step, or Table 1's
    let step = old_dt.unwrap_or(table1::TIME_STEP);
    if let Some(sets) = doc.get_mut("saliva").and_then(|v| v.as_array_mut()) {
        for set in sets.iter_mut().filter_map(|v| v.as_table_mut()) {
            if let Some(p) = set.remove("decay_per_step") {
                let p = num(Some(&p)).unwrap_or(table1::DECAY_PER_STEP);
                if !(p > 0.0 && p < 1.0) {
                    return Err(Error::field(
                        file,
                        "saliva.decay_per_step",
                        format!("must be in (0, 1) to become a decay time, got {p}"),
                    ));
                }
                set.insert("decay_time".into(), toml::Value::Float(-step / p.ln()));
            } else if !set.contains_key("decay_time") {
                set.insert(
                    "decay_time".into(),
                    toml::Value::Float(-step / table1::DECAY_PER_STEP.ln()),
                );
            }
        }
    }
    Ok(toml::to_string(&doc).expect("a TOML table serialises"))
}

/// `text`, the TOML file `file`, read as a `T`: the one reader of TOML whose errors name the
/// file and the line (a scenario, a sweep's spec, `face --params`, `mouth --params`).
pub fn from_toml<T: serde::de::DeserializeOwned>(text: &str, file: &str) -> Result<T> {
    toml::from_str(text).map_err(|e| Error::input(file, line_of(text, e.span()), e.message()))
}

/// The TOML file `path` read as a `T` ([`from_toml`]; an I/O error names the file).
pub fn read_toml<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    from_toml(&text, &path.display().to_string())
}

fn line_of(text: &str, span: Option<std::ops::Range<usize>>) -> Location {
    match span {
        Some(r) => Location::Line(text[..r.start.min(text.len())].matches('\n').count() + 1),
        None => Location::None,
    }
}

/// The TOML key paths of the time and numerics fields, named in the messages.
const SCENARIO_TIME_KEYS: crate::problem::TimeKeys = crate::problem::TimeKeys {
    dt: "time.dt",
    total: "time.total",
    output_every: "time.output_every",
    damping: "numerics.damping",
    hourglass_kappa: "numerics.hourglass_kappa",
};

pub fn parse(text: &str, path: &Path) -> Result<Scenario> {
    let file = path.display().to_string();
    let f = file.as_str();
    if text.len() as u64 > MAX_SCENARIO_BYTES {
        return Err(too_large(f, text.len() as u64));
    }
    let sf: ScenarioFile = toml::from_str(text).map_err(|e| {
        let msg = e.message().to_string();
        Error::input(f, line_of(text, e.span()), msg)
    })?;
    if let Ok(table) = toml::from_str::<toml::Table>(text) {
        if let Some((field, v)) = first_non_finite(&table, "") {
            return Err(Error::field(
                f,
                field,
                format!("{v} is not a finite number"),
            ));
        }
    }
    let nd = &sf.numerics;
    let default = Numerics::default();
    let auto = auto_time(&sf.time, f)?;
    let time = TimeSettings {
        // with dt = "auto", one step per frame until the model is built (to check the
        // settings before that): the step is set from the model's critical step below
        dt: match (sf.time.dt, auto) {
            (DtDef::Seconds(dt), _) => dt,
            (DtDef::Auto(_), Some((interval, _))) => interval,
            (DtDef::Auto(_), None) => unreachable!("auto_time returns the interval for auto"),
        },
        total_time: sf.time.total,
        output_every: sf.time.output_every.unwrap_or(table1::OUTPUT_EVERY),
    };
    let numerics = Numerics {
        damping: nd.damping.unwrap_or(default.damping),
        hourglass_kappa: nd.hourglass_kappa.unwrap_or(default.hourglass_kappa),
        variant: nd.variant.unwrap_or(default.variant),
        niftysim_timing: false,
        subcycles: match sf.time.subcycles {
            None | Some(SubcyclesDef::Auto(_)) => 1,
            Some(SubcyclesDef::Count(n)) => {
                let max = crate::problem::MAX_SUBCYCLES;
                if !(1..=max as i64).contains(&n) {
                    return Err(Error::field(
                        f,
                        "time.subcycles",
                        format!("must be between 1 and {max} (or \"auto\"), got {n}"),
                    ));
                }
                n as usize
            }
        },
    };
    // `[time]` and `[numerics]` are checked before the mesh is read or generated: a bad step
    // is refused without the cost of building the model
    crate::problem::validate_time_and_numerics(&time, &numerics, f, &SCENARIO_TIME_KEYS)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let scale = sf.units.length.unwrap_or_default().metres();
    let (mut mesh, anatomy, skin) = build_mesh(&sf.mesh, f, base, scale)?;
    // a mouth model's saliva by zone (`saliva_left`, `saliva_centre`, `saliva_right`)
    if let Some(a) = &anatomy {
        crate::mesh::zones::add_saliva_sets(&mut mesh, &a.columns);
    }
    add_node_sets(&mut mesh, &sf.node_sets, f, scale)?;
    let r = Reader {
        f,
        base,
        mesh: &mesh,
        scale,
        total: sf.time.total,
    };
    let (materials, element_material) = r.materials(&sf.materials)?;
    let bc = r.boundary_conditions(&sf, anatomy.as_ref())?;
    let curve = |c: &CurveDef, field: &str, default: LoadShape| r.curve(c, field, default);
    let mut physics = read_physics(&sf, f, base, scale, &materials, &curve)?;
    r.mouth_model_physics(&sf, anatomy.as_ref(), &mut physics)?;
    physics.wetting = r.wetting(&sf, anatomy.as_ref(), &element_material, &physics)?;
    // the skin follows the jaw's prescribed rotation beside the model
    physics.skin = skin.map(|mut s| {
        s.jaw = anatomy.as_ref().and_then(|a| {
            bc.rotations
                .iter()
                .find(|r| r.nodes == a.jaw_nodes)
                .cloned()
        });
        s
    });
    let mut problem = Problem {
        source: file.clone(),
        mesh,
        materials,
        element_material,
        bc,
        time,
        numerics,
        additive_constraints: false,
        physics,
    };
    let auto_subcycles = matches!(sf.time.subcycles, Some(SubcyclesDef::Auto(_)));
    if let Some((interval, fraction)) = auto {
        set_auto_step(&mut problem, &sf, interval, fraction, auto_subcycles, f)?;
    } else if auto_subcycles || problem.numerics.subcycles > 1 {
        // the substep is not the step: eq. 11's decay must be in seconds
        decay_in_physical_time(&mut problem, &sf, "time.subcycles", f)?;
        if auto_subcycles {
            set_auto_subcycles(&mut problem, f)?;
        }
    }
    problem.validate()?;
    Ok(Scenario {
        problem,
        title: sf.title,
        default_output: sf.output.dir.map(|d| base.join(d)),
    })
}

/// With `dt = "auto"`: the output interval and the fraction, checked (`None` for a fixed
/// step, where `output_interval` and `dt_fraction` are refused).
fn auto_time(t: &TimeDef, f: &str) -> Result<Option<(f64, f64)>> {
    match t.dt {
        DtDef::Seconds(_) => {
            for (name, v) in [
                ("time.output_interval", t.output_interval),
                ("time.dt_fraction", t.dt_fraction),
            ] {
                if v.is_some() {
                    return Err(Error::field(f, name, "applies to dt = \"auto\" only"));
                }
            }
            Ok(None)
        }
        DtDef::Auto(_) => {
            if t.output_every.is_some() {
                return Err(Error::field(
                    f,
                    "time.output_every",
                    "with dt = \"auto\" the step is not known in advance: give output_interval (s)",
                ));
            }
            let interval = t
                .output_interval
                .unwrap_or(table1::OUTPUT_EVERY as f64 * table1::TIME_STEP);
            if !(interval.is_finite() && interval > 0.0) {
                return Err(Error::field(
                    f,
                    "time.output_interval",
                    format!("must be positive and finite, got {interval}"),
                ));
            }
            let fraction = t.dt_fraction.unwrap_or(AUTO_DT_FRACTION);
            if !(fraction > 0.0 && fraction <= 1.0) {
                return Err(Error::field(
                    f,
                    "time.dt_fraction",
                    format!("must be in (0, 1], got {fraction}"),
                ));
            }
            Ok(Some((interval, fraction)))
        }
    }
}

/// Paper eq. (3), central differences: `dt = "auto"`: the step from the built model's critical step (the largest eigenvalue of
/// `M^-1 K`, `tled::stability`): `fraction` of it, made smaller so that `interval` is a
/// whole number of steps (which become `output_every`). The saliva's decay (eq. 11) is then
/// in physical time: Table 1's 0.99 per 1e-5 s as a decay time where none is given; a
/// `decay_per_step` is refused (per step of an unknown step).
#[allow(clippy::too_many_arguments)]
fn set_auto_step(
    problem: &mut Problem,
    sf: &ScenarioFile,
    interval: f64,
    fraction: f64,
    auto_subcycles: bool,
    f: &str,
) -> Result<()> {
    decay_in_physical_time(problem, sf, "dt = \"auto\"", f)?;
    let d = crate::tled::precompute::Discretisation::new(problem);
    let report = crate::tled::stability::analyse(problem, &d);
    let critical = report.critical_time_step;
    if !(critical.is_finite() && critical > 0.0) {
        return Err(Error::field(
            f,
            "time.dt",
            format!("\"auto\" needs a finite critical time step; the model's is {critical:e}"),
        ));
    }
    // the large step's limit: the whole model's, or with subcycling the tissue's (and no
    // more than k substeps of the whole model's)
    let k = problem.numerics.subcycles;
    let tissue = report.tissue_critical_time_step;
    let limit = match (auto_subcycles, k, tissue) {
        (true, _, Some(t)) => t.min(SUBCYCLED_STEP_RATIO * critical).max(critical),
        (false, k, Some(t)) if k > 1 => t.min(k as f64 * critical),
        _ => critical,
    };
    let per_frame = (interval / (fraction * limit)).ceil().max(1.0);
    if per_frame > crate::problem::MAX_STEPS as f64 {
        return Err(Error::field(
            f,
            "time.output_interval",
            format!("{interval:e} s is {per_frame:e} steps of the critical step {limit:e} s"),
        ));
    }
    problem.time.output_every = per_frame as usize;
    problem.time.dt = interval / per_frame;
    if auto_subcycles {
        problem.numerics.subcycles = subcycles_for(problem.time.dt, fraction * critical, f)?;
    }
    Ok(())
}

/// Eq. 11's decay in physical time, for a step not known in advance (`why`): Table 1's 0.99
/// per 1e-5 s as a decay time where none is given; a `decay_per_step` is refused.
fn decay_in_physical_time(
    problem: &mut Problem,
    sf: &ScenarioFile,
    why: &str,
    f: &str,
) -> Result<()> {
    use crate::material::saliva::Decay;
    for (i, def) in sf.saliva.iter().enumerate() {
        if def.decay_per_step.is_some() {
            return Err(Error::field(
                f,
                format!("saliva[{i}].decay_per_step"),
                format!(
                    "with {why} give decay_time (s) instead: Table 1's 0.99 per step of \
                     1e-5 s is decay_time = {:.5e}",
                    table1_decay_time()
                ),
            ));
        }
    }
    // every other decay is the default (a model's own saliva sets included)
    for set in problem.physics.saliva.iter_mut() {
        if let Decay::PerStep(_) = set.params.decay {
            set.params.decay = Decay::Time(table1_decay_time());
        }
    }
    Ok(())
}

/// `subcycles = "auto"` with a fixed step: as many substeps as the whole model's critical
/// step needs at [`AUTO_DT_FRACTION`] of it.
fn set_auto_subcycles(problem: &mut Problem, f: &str) -> Result<()> {
    let d = crate::tled::precompute::Discretisation::new(problem);
    let critical = crate::tled::stability::analyse(problem, &d).critical_time_step;
    problem.numerics.subcycles = subcycles_for(problem.time.dt, AUTO_DT_FRACTION * critical, f)?;
    Ok(())
}

/// The substeps that bring `dt` to at most `fast` (s), refused above `MAX_SUBCYCLES`.
fn subcycles_for(dt: f64, fast: f64, f: &str) -> Result<usize> {
    let max = crate::problem::MAX_SUBCYCLES;
    let k = (dt / fast).ceil().max(1.0);
    if !(k <= max as f64) {
        return Err(Error::field(
            f,
            "time.subcycles",
            format!(
                "\"auto\" would need {k:e} substeps of {fast:e} s in a step of {dt:e} s; at most {max}"
            ),
        ));
    }
    Ok(k as usize)
}

/// The first `nan` or `inf` in the file (TOML allows both), with its key path
/// (`displacement[0].value`), in the file's order of tables and keys.
fn first_non_finite(table: &toml::Table, prefix: &str) -> Option<(String, f64)> {
    fn walk(v: &toml::Value, path: String) -> Option<(String, f64)> {
        match v {
            toml::Value::Float(x) if !x.is_finite() => Some((path, *x)),
            toml::Value::Array(a) => a
                .iter()
                .enumerate()
                .find_map(|(i, v)| walk(v, format!("{path}[{i}]"))),
            toml::Value::Table(t) => first_non_finite(t, &path),
            _ => None,
        }
    }
    table.iter().find_map(|(k, v)| {
        let path = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        walk(v, path)
    })
}

/// `[mesh]`: the mesh of the generator, in metres, with the element set `all`; for mouth
/// models also their anatomy (jaw, skull, muscles, lip columns) and the skin the point caches
/// play ([`crate::mesh::skin`]).
type Built = (
    Mesh,
    Option<crate::mesh::anatomy::MouthAnatomy>,
    Option<crate::mesh::skin::Skin>,
);

fn build_mesh(m: &MeshSection, f: &str, base: &Path, scale: f64) -> Result<Built> {
    let sc3 = |v: [f64; 3]| v.map(|x| x * scale);
    let need = |v: Option<[f64; 3]>, k: &str| {
        v.ok_or_else(|| Error::field(f, format!("mesh.{k}"), "required by this generator"))
    };
    let mut anatomy = None;
    let mut skin = None;
    let mut mesh: Mesh = match m.generator {
        Generator::Block | Generator::DistortedBlock => {
            let cells = m
                .cells
                .ok_or_else(|| Error::field(f, "mesh.cells", "required by this generator"))?;
            if cells.contains(&0) {
                return Err(Error::field(
                    f,
                    "mesh.cells",
                    "every count must be at least 1",
                ));
            }
            let (nodes, elements) = crate::mesh::budget::block_counts(cells);
            crate::mesh::budget::check(f, "mesh.cells", nodes, elements)?;
            let size = sc3(need(m.size, "size")?);
            if size.iter().any(|&s| !(s > 0.0)) {
                return Err(Error::field(f, "mesh.size", "every edge must be positive"));
            }
            let origin = sc3(m.origin.unwrap_or([0.0; 3]));
            if m.generator == Generator::Block {
                generate::block(origin, size, cells)
            } else {
                let frac = m.distortion.unwrap_or(0.25);
                if !(0.0..0.5).contains(&frac) {
                    return Err(Error::field(
                        f,
                        "mesh.distortion",
                        "must be in [0, 0.5) of the cell size",
                    ));
                }
                generate::distorted_block(origin, size, cells, frac, m.seed.unwrap_or(1))
            }
        }
        Generator::Layers => {
            let layers = m.layers.clone().ok_or_else(|| {
                Error::field(f, "mesh.layers", "required by the layers generator")
            })?;
            let cells = m.cells.ok_or_else(|| {
                Error::field(f, "mesh.cells", "required (x and y counts; z is ignored)")
            })?;
            let size = sc3(need(m.size, "size")?);
            if cells[0] == 0 || cells[1] == 0 || !(size[0] > 0.0 && size[1] > 0.0) {
                return Err(Error::field(
                    f,
                    "mesh.size",
                    "x and y sizes and cell counts must be positive",
                ));
            }
            if layers.is_empty() {
                return Err(Error::field(f, "mesh.layers", "at least one layer"));
            }
            let nz = layers.iter().fold(0usize, |n, l| n.saturating_add(l.cells));
            let (nodes, elements) = crate::mesh::budget::block_counts([cells[0], cells[1], nz]);
            crate::mesh::budget::check(f, "mesh.cells", nodes, elements)?;
            let mut scaled = layers.clone();
            for (i, l) in scaled.iter_mut().enumerate() {
                if !(l.thickness > 0.0) || l.cells == 0 {
                    return Err(Error::field(
                        f,
                        format!("mesh.layers[{i}]"),
                        "thickness and cells must be positive",
                    ));
                }
                l.thickness *= scale;
            }
            generate::layered_block(
                sc3(m.origin.unwrap_or([0.0; 3])),
                [size[0], size[1]],
                [cells[0], cells[1]],
                &scaled,
            )
        }
        Generator::Mouth => {
            let params = m.mouth.clone().unwrap_or_default();
            params.validate(f, "mesh.mouth.")?;
            let model = crate::mesh::mouth::generate(&params)?;
            anatomy = Some(model.anatomy());
            let zero = vec![0.0; model.surface.vertices.len()];
            skin = Some(crate::mesh::skin::Skin::tie(
                "procedural mouth (mouth.obj)",
                model.surface.clone(),
                &zero,
                &model.surface,
                None,
                crate::mesh::skin::OutputFrame::metres(),
                &crate::mesh::skin::SkinParams::default(),
            )?);
            model.mesh
        }
        Generator::Face => {
            use crate::mesh::face;
            let src = match &m.file {
                Some(rel) => face::read_dir(&base.join(rel)).map_err(|e| in_mesh_file(f, e))?,
                None => face::makehuman()?,
            };
            let params = m.face.clone().unwrap_or_default();
            params.validate(f, "mesh.face.")?;
            let model = face::build(&src, &params, f)?;
            anatomy = Some(model.anatomy());
            skin = Some(face::skin(&src, &model)?);
            model.mesh
        }
        Generator::Niftysim => {
            let rel = m.file.as_ref().ok_or_else(|| {
                Error::field(f, "mesh.file", "required by the niftysim generator")
            })?;
            let p =
                crate::io::niftysim::read(&base.join(rel), GradientVariant::MeanGradient, false)
                    .map_err(|e| in_mesh_file(f, e))?;
            let mut mesh = p.mesh;
            for n in mesh.nodes.iter_mut() {
                *n = sc3(*n);
            }
            for (i, &mi) in p.element_material.iter().enumerate() {
                mesh.element_sets
                    .entry(format!("set{mi}"))
                    .or_default()
                    .push(i as u32);
            }
            mesh
        }
    };
    mesh.element_sets
        .entry("all".into())
        .or_insert_with(|| (0..mesh.elements.len() as u32).collect());
    Ok((mesh, anatomy, skin))
}

/// A file named by `mesh.file` that cannot be read: the error names the scenario and the
/// field too (an error inside the file, naming its own line, is kept as it is).
fn in_mesh_file(f: &str, e: Error) -> Error {
    match e {
        Error::Io { .. } => Error::field(f, "mesh.file", e.to_string()),
        other => other,
    }
}

/// `[[node_sets]]`: each set by index list or box (in the file's length unit).
fn add_node_sets(mesh: &mut Mesh, sets: &[NodeSetDef], f: &str, scale: f64) -> Result<()> {
    let sc3 = |v: [f64; 3]| v.map(|x| x * scale);
    for (i, ns) in sets.iter().enumerate() {
        let field = format!("node_sets[{i}] ({})", ns.name);
        let nodes: Vec<u32> = match (&ns.nodes, ns.box_min, ns.box_max) {
            (Some(list), None, None) => {
                let mut l = list.clone();
                l.sort_unstable();
                l.dedup();
                l
            }
            (None, Some(lo), Some(hi)) => {
                let (lo, hi) = (sc3(lo), sc3(hi));
                let tol = 1e-9
                    * (0..3)
                        .map(|k| (hi[k] - lo[k]).abs())
                        .fold(0.0, f64::max)
                        .max(1e-12);
                (0..mesh.nodes.len() as u32)
                    .filter(|&n| {
                        let x = mesh.nodes[n as usize];
                        (0..3).all(|k| x[k] >= lo[k] - tol && x[k] <= hi[k] + tol)
                    })
                    .collect()
            }
            _ => {
                return Err(Error::field(
                    f,
                    field,
                    "give either `nodes` or both `box_min` and `box_max`",
                ))
            }
        };
        if nodes.is_empty() {
            return Err(Error::field(f, field, "selects no node"));
        }
        mesh.node_sets.insert(ns.name.clone(), nodes);
    }
    Ok(())
}

/// What the sections after `[mesh]` are read against: the file's name (for errors), the
/// mesh with its node sets, the length scale and the run's duration (the default end of a
/// load curve).
struct Reader<'a> {
    f: &'a str,
    /// The scenario's directory (files it names are relative to it).
    base: &'a Path,
    mesh: &'a Mesh,
    scale: f64,
    total: f64,
}

impl Reader<'_> {
    fn sc3(&self, v: [f64; 3]) -> [f64; 3] {
        v.map(|x| x * self.scale)
    }

    /// The nodes of a set name or index list.
    fn nodes(&self, r: &NodeRef, field: &str) -> Result<Vec<u32>> {
        match r {
            NodeRef::Set(name) => self.mesh.node_sets.get(name).cloned().ok_or_else(|| {
                let known: Vec<&String> = self.mesh.node_sets.keys().collect();
                Error::field(
                    self.f,
                    field,
                    format!("unknown node set `{name}` (known: {known:?})"),
                )
            }),
            NodeRef::List(l) => Ok(l.clone()),
        }
    }

    fn dof(&self, d: &DofRef, field: &str) -> Result<usize> {
        let (k, shown) = match d {
            DofRef::Index(i) => ((*i < 3).then_some(*i), i.to_string()),
            DofRef::Name(s) => (dof_of_name(s), format!("\"{s}\"")),
        };
        k.ok_or_else(|| {
            Error::field(
                self.f,
                field,
                format!("{shown} is not a DOF (x, y, z or 0, 1, 2)"),
            )
        })
    }

    fn curve(&self, c: &CurveDef, field: &str, default: LoadShape) -> Result<LoadCurve> {
        if c.keys.is_some() || c.keys_file.is_some() {
            return self.keyed_curve(c, field);
        }
        if c.keys_fps.is_some() {
            return Err(Error::field(
                self.f,
                format!("{field}.keys_fps"),
                "applies to keys or keys_file",
            ));
        }
        let shape = match &c.shape {
            None => default,
            Some(s) => LoadShape::parse(s).ok_or_else(|| {
                Error::field(
                    self.f,
                    format!("{field}.shape"),
                    format!(
                        "unknown shape `{s}` (ramp, poly345, step, hilly, ramphold, smooth_step)"
                    ),
                )
            })?,
        };
        let start = c.start.unwrap_or(0.0);
        let duration = c.duration.unwrap_or(self.total - start);
        if !(duration > 0.0) {
            return Err(Error::field(
                self.f,
                format!("{field}.duration"),
                format!("must be positive, got {duration}"),
            ));
        }
        Ok(LoadCurve {
            shape,
            start,
            duration,
        })
    }

    /// `[[wet]]`: the saliva elements of each zone or set and their moisture curve.
    fn wetting(
        &self,
        sf: &ScenarioFile,
        anatomy: Option<&crate::mesh::anatomy::MouthAnatomy>,
        element_material: &[u32],
        physics: &Physics,
    ) -> Result<Vec<crate::problem::Wetting>> {
        let f = self.f;
        let saliva_mats: Vec<u32> = physics.saliva.iter().map(|s| s.material).collect();
        let saliva: Vec<u32> = (0..element_material.len() as u32)
            .filter(|&e| saliva_mats.contains(&element_material[e as usize]))
            .collect();
        let mut out = Vec::new();
        for (i, w) in sf.wet.iter().enumerate() {
            let field = format!("wet[{i}]");
            let elements: Vec<u32> = match (&w.zone, &w.elements) {
                (Some(_), Some(_)) | (None, None) => {
                    return Err(Error::field(f, field, "give one of zone and elements"))
                }
                (None, Some(set)) => {
                    let members = self.mesh.element_sets.get(set).ok_or_else(|| {
                        Error::field(
                            f,
                            format!("{field}.elements"),
                            format!("no element set `{set}`"),
                        )
                    })?;
                    saliva
                        .iter()
                        .copied()
                        .filter(|e| members.binary_search(e).is_ok())
                        .collect()
                }
                (Some(zone), None) => {
                    let cols = &anatomy
                        .ok_or_else(|| {
                            Error::field(
                                f,
                                format!("{field}.zone"),
                                "zones need a mouth model (generator `mouth` or `face`); give elements",
                            )
                        })?
                        .columns;
                    let zone = crate::mesh::zones::Zone::from_name(zone).ok_or_else(|| {
                        Error::field(
                            f,
                            format!("{field}.zone"),
                            format!("unknown zone `{zone}` (left, right, centre, all)"),
                        )
                    })?;
                    crate::mesh::zones::elements(self.mesh, &saliva, cols, zone)
                }
            };
            if elements.is_empty() {
                return Err(Error::field(f, field, "selects no saliva element"));
            }
            let keyed = w.curve.keys.is_some() || w.curve.keys_file.is_some();
            let amount = match (w.amount, keyed) {
                (Some(a), _) => a,
                (None, true) => 1.0,
                (None, false) => {
                    return Err(Error::field(
                        f,
                        format!("{field}.amount"),
                        "required (um of moisture added), unless keys give it over time",
                    ))
                }
            };
            let curve = self.curve(&w.curve, &field, LoadShape::SmoothStep)?;
            out.push(crate::problem::Wetting {
                elements,
                amount,
                curve,
            });
        }
        Ok(out)
    }

    /// A curve given by keyframes (`keys` or `keys_file`).
    fn keyed_curve(&self, c: &CurveDef, field: &str) -> Result<LoadCurve> {
        for (name, set) in [
            ("shape", c.shape.is_some()),
            ("start", c.start.is_some()),
            ("duration", c.duration.is_some()),
        ] {
            if set {
                return Err(Error::field(
                    self.f,
                    format!("{field}.{name}"),
                    "keys replace shape, start and duration: give one or the other",
                ));
            }
        }
        let (keys, label, key_field) = match (&c.keys, &c.keys_file) {
            (Some(_), Some(_)) => {
                return Err(Error::field(
                    self.f,
                    format!("{field}.keys_file"),
                    "give keys or keys_file, not both",
                ))
            }
            (Some(k), None) => {
                let scale =
                    crate::io::keys::time_scale(c.keys_fps, self.f, &format!("{field}.keys_fps"))?;
                (
                    k.iter().map(|p| (p[0] * scale, p[1])).collect(),
                    self.f.to_string(),
                    format!("{field}.keys"),
                )
            }
            (None, Some(file)) => {
                // the rate is the scenario's field: checked (and named) here, before the file
                crate::io::keys::time_scale(c.keys_fps, self.f, &format!("{field}.keys_fps"))?;
                let path = self.base.join(file);
                let k = crate::io::keys::read_keys(&path, c.keys_fps).map_err(|e| match e {
                    Error::Io { .. } => {
                        Error::field(self.f, format!("{field}.keys_file"), e.to_string())
                    }
                    e => e,
                })?;
                (k, path.display().to_string(), format!("{field}.keys_file"))
            }
            (None, None) => unreachable!("called with keys"),
        };
        let k = crate::boundary::Keyframes::new(keys)
            .map_err(|m| Error::field(&label, key_field, m))?;
        Ok(LoadCurve {
            shape: LoadShape::Keyed(std::sync::Arc::new(k)),
            start: 0.0,
            duration: self.total,
        })
    }

    /// `[[materials]]`: the materials and the material of every element.
    fn materials(&self, defs: &[MaterialDef]) -> Result<(Vec<MaterialSpec>, Vec<u32>)> {
        let mut materials = Vec::new();
        let mut element_material = vec![u32::MAX; self.mesh.elements.len()];
        for (i, md) in defs.iter().enumerate() {
            let MaterialModel::NeoHookean = md.model.unwrap_or_default();
            let set_name = md.elements.clone().unwrap_or_else(|| "all".into());
            let set = self.mesh.element_sets.get(&set_name).ok_or_else(|| {
                Error::field(
                    self.f,
                    format!("materials[{i}].elements"),
                    format!("unknown element set `{set_name}`"),
                )
            })?;
            for &e in set {
                element_material[e as usize] = i as u32;
            }
            materials.push(MaterialSpec {
                name: md.name.clone(),
                law: NeoHookean {
                    mu: md.mu,
                    bulk: md.bulk,
                },
                density: md.density,
            });
        }
        if materials.is_empty() {
            return Err(Error::field(
                self.f,
                "materials",
                "at least one material is needed",
            ));
        }
        Ok((materials, element_material))
    }

    /// `[[fix]]`, `[[displacement]]`, `[[rotation]]`, `[[force]]`, `[jaw]` (after the
    /// rotations), `[gravity]`.
    fn boundary_conditions(
        &self,
        sf: &ScenarioFile,
        anatomy: Option<&crate::mesh::anatomy::MouthAnatomy>,
    ) -> Result<BoundaryConditions> {
        let f = self.f;
        let mut bc = BoundaryConditions::default();
        for (i, d) in sf.fix.iter().enumerate() {
            let field = format!("fix[{i}]");
            bc.fixed.push(Fixed {
                nodes: self.nodes(&d.nodes, &format!("{field}.nodes"))?,
                dofs: d.dofs.map_or([true; 3], |m| m.0),
            });
        }
        for (i, d) in sf.displacement.iter().enumerate() {
            let field = format!("displacement[{i}]");
            let nodes = self.nodes(&d.nodes, &format!("{field}.nodes"))?;
            let values = vec![d.value * self.scale; nodes.len()];
            bc.displacements.push(PrescribedDisplacement {
                dof: self.dof(&d.dof, &format!("{field}.dof"))?,
                nodes,
                values,
                curve: self.curve(&d.curve, &field, LoadShape::Ramp)?,
            });
        }
        for (i, d) in sf.rotation.iter().enumerate() {
            let field = format!("rotation[{i}]");
            let n = crate::linalg::norm(&d.axis);
            if !(n > 0.0) || !n.is_finite() {
                return Err(Error::field(
                    f,
                    format!("{field}.axis"),
                    "must be a non-zero vector",
                ));
            }
            bc.rotations.push(PrescribedRotation {
                nodes: self.nodes(&d.nodes, &format!("{field}.nodes"))?,
                point: self.sc3(d.point),
                axis: d.axis.map(|v| v / n),
                angle: d.angle,
                curve: self.curve(&d.curve, &field, LoadShape::SmoothStep)?,
            });
        }
        for (i, d) in sf.force.iter().enumerate() {
            let field = format!("force[{i}]");
            let nodes = self.nodes(&d.nodes, &format!("{field}.nodes"))?;
            let values = vec![d.value; nodes.len()];
            bc.forces.push(NodalForce {
                dof: self.dof(&d.dof, &format!("{field}.dof"))?,
                nodes,
                values,
                curve: self.curve(&d.curve, &field, LoadShape::Step)?,
            });
        }
        if let Some(j) = &sf.jaw {
            let model = anatomy.ok_or_else(|| {
                Error::field(
                    f,
                    "jaw",
                    "[jaw] needs a mouth model (generator `mouth` or `face`)",
                )
            })?;
            let keyed = j.curve.keys.is_some() || j.curve.keys_file.is_some();
            let angle = match (j.angle, keyed) {
                (Some(a), _) => a,
                (None, true) => 1.0,
                (None, false) => {
                    return Err(Error::field(
                        f,
                        "jaw.angle",
                        "required (the opening in rad), unless keys give the angle over time",
                    ))
                }
            };
            bc.rotations.push(
                model.jaw_rotation(angle, self.curve(&j.curve, "jaw", LoadShape::SmoothStep)?),
            );
        }
        if let Some(g) = &sf.gravity {
            bc.gravity.push(Gravity {
                nodes: None,
                acceleration: g.acceleration,
                curve: self.curve(&g.curve, "gravity", LoadShape::Step)?,
            });
        }
        Ok(bc)
    }

    /// What a mouth model adds to the physics: `[[model_muscle]]` by name, the saliva's
    /// axis across the layer where the scenario gives none, the lip columns and the model's
    /// name.
    fn mouth_model_physics(
        &self,
        sf: &ScenarioFile,
        anatomy: Option<&crate::mesh::anatomy::MouthAnatomy>,
        physics: &mut Physics,
    ) -> Result<()> {
        let f = self.f;
        let Some(model) = anatomy else {
            if !sf.model_muscle.is_empty() {
                return Err(Error::field(
                    f,
                    "model_muscle",
                    "[[model_muscle]] needs a mouth model (generator `mouth` or `face`)",
                ));
            }
            return Ok(());
        };
        for (i, mm) in sf.model_muscle.iter().enumerate() {
            let field = format!("model_muscle[{i}]");
            let mut m = model
                .muscles
                .iter()
                .find(|m| m.name == mm.name)
                .cloned()
                .ok_or_else(|| {
                    let names: Vec<&str> = model.muscles.iter().map(|m| m.name.as_str()).collect();
                    Error::field(
                        f,
                        format!("{field}.name"),
                        format!(
                            "no muscle `{}` in the mouth model (it has {names:?})",
                            mm.name
                        ),
                    )
                })?;
            m.strength = mm.strength;
            m.activation = mm.activation.unwrap_or(1.0);
            m.curve = self.curve(&mm.curve, &field, LoadShape::SmoothStep)?;
            physics.muscles.push(m);
        }
        for s in physics.saliva.iter_mut() {
            if s.params.across.is_none() {
                s.params.across = Some(model.saliva_across.clone());
            }
        }
        physics.lip_columns = Some(model.columns.clone());
        physics.model = Some(model.source.clone());
        Ok(())
    }
}

type CurveFn<'a> = dyn Fn(&CurveDef, &str, LoadShape) -> Result<LoadCurve> + 'a;

fn read_physics(
    sf: &ScenarioFile,
    f: &str,
    base: &Path,
    scale: f64,
    materials: &[MaterialSpec],
    curve: &CurveFn,
) -> Result<Physics> {
    use crate::material::saliva::{
        AcrossAxis, Decay, EvaporationSchedule, MoistureMap, SalivaParams,
    };
    let mut physics = Physics::default();
    let unit_axis = |a: [f64; 3], field: &str| -> Result<[f64; 3]> {
        let n = crate::linalg::norm(&a);
        if !(n > 0.0) || !n.is_finite() {
            return Err(Error::field(f, field, "must be a non-zero vector"));
        }
        Ok(a.map(|v| v / n))
    };
    for (i, sd) in sf.saliva.iter().enumerate() {
        let field = |k: &str| format!("saliva[{i}].{k}");
        let material = materials
            .iter()
            .position(|m| m.name == sd.material)
            .ok_or_else(|| {
                Error::field(
                    f,
                    field("material"),
                    format!("no material named `{}` in [[materials]]", sd.material),
                )
            })? as u32;
        let initial_moisture = match &sd.initial_moisture {
            MoistureDef::Constant(m) => MoistureMap::Constant(*m),
            MoistureDef::Map(MoistureMapDef::Gradient { axis, from, to }) => {
                MoistureMap::Gradient {
                    axis: unit_axis(*axis, &field("initial_moisture.gradient.axis"))?,
                    positions: (from[0] * scale, to[0] * scale),
                    values: (from[1], to[1]),
                }
            }
            MoistureDef::Map(MoistureMapDef::Bands {
                axis,
                edges,
                values,
            }) => {
                if values.len() != edges.len() + 1 || edges.windows(2).any(|w| !(w[1] > w[0])) {
                    return Err(Error::field(
                        f,
                        field("initial_moisture.bands"),
                        "needs increasing edges and one more value than edges",
                    ));
                }
                MoistureMap::Bands {
                    axis: unit_axis(*axis, &field("initial_moisture.bands.axis"))?,
                    edges: edges.iter().map(|e| e * scale).collect(),
                    values: values.clone(),
                }
            }
            MoistureDef::Map(MoistureMapDef::LeftRight {
                axis,
                center,
                left,
                right,
            }) => MoistureMap::LeftRight {
                axis: unit_axis(*axis, &field("initial_moisture.left_right.axis"))?,
                center: center * scale,
                left: *left,
                right: *right,
            },
            MoistureDef::Map(MoistureMapDef::File(rel)) => {
                let path = base.join(rel);
                let text = std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?;
                let mut v = Vec::new();
                for (ln, line) in text.lines().enumerate() {
                    let t = line.split('#').next().unwrap_or("").trim();
                    if t.is_empty() {
                        continue;
                    }
                    let x: f64 = t.parse().map_err(|_| {
                        Error::input(
                            path.display().to_string(),
                            Location::Line(ln + 1),
                            format!("`{t}` is not a number"),
                        )
                    })?;
                    v.push(x);
                }
                MoistureMap::PerElement(v)
            }
        };
        let evaporation = match (&sd.evaporation, sd.evaporation_rate) {
            (Some(_), Some(_)) => {
                return Err(Error::field(
                    f,
                    field("evaporation"),
                    "give `evaporation` or `evaporation_rate`, not both",
                ))
            }
            (Some(e), None) => EvaporationSchedule {
                starts: e.starts.clone(),
                rates: e.rates.clone(),
            },
            (None, r) => EvaporationSchedule::constant(r.unwrap_or(table1::EVAPORATION_RATE)),
        };
        let decay = match (sd.decay_per_step, sd.decay_time) {
            (Some(_), Some(_)) => {
                return Err(Error::field(
                    f,
                    field("decay_time"),
                    "give `decay_per_step` or `decay_time`, not both",
                ))
            }
            (None, Some(t)) => Decay::Time(t),
            (d, None) => Decay::PerStep(d.unwrap_or(table1::DECAY_PER_STEP)),
        };
        let across = match sd.across {
            Some(a) => Some(AcrossAxis::Uniform(unit_axis(a, &field("across"))?)),
            None => None,
        };
        physics.saliva.push(SalivaSet {
            material,
            params: SalivaParams {
                critical_moisture: sd.critical_moisture,
                k_glue: sd.k_glue,
                initial_moisture,
                evaporation,
                rule: sd.rule.unwrap_or_default(),
                decay,
                across,
            },
        });
    }
    for (i, md) in sf.muscle.iter().enumerate() {
        let field = format!("muscle[{i}]");
        physics.muscles.push(Muscle {
            name: md.name.clone(),
            origin: md.origin.map(|v| v * scale),
            insertion: md.insertion.map(|v| v * scale),
            radius: md.radius * scale,
            strength: md.strength,
            activation: md.activation.unwrap_or(1.0),
            curve: curve(&md.curve, &field, LoadShape::SmoothStep)?,
        });
    }
    Ok(physics)
}

#[cfg(test)]
mod dt_tests {
    use super::*;

    const BLOCK: &str =
        "[mesh]\ngenerator = \"block\"\nsize = [0.01, 0.01, 0.01]\ncells = [2, 2, 2]\n\
        [[materials]]\nname = \"tissue\"\nmu = 800.0\nK = 7000.0\ndensity = 1050.0\n\
        [[fix]]\nnodes = \"z_min\"\n";

    /// `dt = "auto"`: the step is at most 0.8 of the critical step and a whole number of
    /// steps fills the output interval; what only makes sense with a fixed step is refused.
    #[test]
    fn auto_takes_a_fraction_of_the_critical_step() {
        let text = format!("{BLOCK}[time]\ndt = \"auto\"\ntotal = 0.05\noutput_interval = 0.01\n");
        let p = parse(&text, Path::new("a.toml")).unwrap().problem;
        let d = crate::tled::precompute::Discretisation::new(&p);
        let critical = crate::tled::stability::analyse(&p, &d).critical_time_step;
        assert!(p.time.dt <= AUTO_DT_FRACTION * critical * (1.0 + 1e-12));
        assert!(p.time.dt > 0.5 * AUTO_DT_FRACTION * critical);
        assert!((p.time.dt * p.time.output_every as f64 - 0.01).abs() < 1e-15);
        let err = |t: &str| parse(t, Path::new("a.toml")).err().unwrap().to_string();
        let e = err(&format!(
            "{BLOCK}[time]\ndt = \"auto\"\ntotal = 0.05\noutput_every = 10\n"
        ));
        assert!(
            e.contains("field `time.output_every`") && e.contains("output_interval"),
            "{e}"
        );
        let e = err(&format!(
            "{BLOCK}[time]\ndt = \"auto\"\ntotal = 0.05\ndt_fraction = 1.5\n"
        ));
        assert!(
            e.contains("field `time.dt_fraction`: must be in (0, 1]"),
            "{e}"
        );
        let e = err(&format!(
            "{BLOCK}[time]\ndt = 1e-5\ntotal = 0.05\noutput_interval = 0.01\n"
        ));
        assert!(
            e.contains("field `time.output_interval`: applies to dt = \"auto\" only"),
            "{e}"
        );
        let e = err(&format!("{BLOCK}[time]\ndt = \"fast\"\ntotal = 0.05\n"));
        assert!(e.starts_with("a.toml:"), "{e}");
    }

    /// Two slabs joined by a saliva layer (the stiff part).
    const SLABS: &str = "[units]\nlength = \"mm\"\n[mesh]\ngenerator = \"layers\"\n\
        size = [10.0, 10.0, 0.0]\ncells = [2, 2, 0]\nlayers = [\
        { name = \"lower\", thickness = 5.0, cells = 2 }, \
        { name = \"layer\", thickness = 0.5, cells = 1 }, \
        { name = \"upper\", thickness = 5.0, cells = 2 }]\n\
        [[materials]]\nname = \"lo\"\nelements = \"lower\"\nmu = 800.0\nK = 7000.0\ndensity = 1050.0\n\
        [[materials]]\nname = \"saliva\"\nelements = \"layer\"\nmu = 7700.0\nK = 191000.0\ndensity = 1050.0\n\
        [[materials]]\nname = \"up\"\nelements = \"upper\"\nmu = 800.0\nK = 7000.0\ndensity = 1050.0\n\
        [[saliva]]\nmaterial = \"saliva\"\ncritical_moisture = 100.0\ninitial_moisture = 100.0\n\
        k_glue = 0.05\nevaporation_rate = 0.0\nrule = \"literal\"\n";

    /// `subcycles`: `"auto"` with `dt = "auto"` takes the large step from the tissue's critical
    /// step (at most `SUBCYCLED_STEP_RATIO` times the whole model's) and enough substeps for
    /// the saliva; with a fixed step, enough substeps for it; counts out of range, a model
    /// without saliva and a decay per step are refused, naming the field.
    #[test]
    fn subcycles_auto_and_counts() {
        use crate::material::saliva::Decay;
        let parse_ok = |t: &str| parse(t, Path::new("s.toml")).unwrap().problem;
        let p = parse_ok(&format!(
            "{SLABS}[time]\ndt = \"auto\"\nsubcycles = \"auto\"\ntotal = 0.05\noutput_interval = 0.01\n"
        ));
        let d = crate::tled::precompute::Discretisation::new(&p);
        let r = crate::tled::stability::analyse(&p, &d);
        let (critical, tissue) = (r.critical_time_step, r.tissue_critical_time_step.unwrap());
        let k = p.numerics.subcycles;
        assert!(
            tissue > 2.0 * critical && k >= 2,
            "k {k}, {critical:e} {tissue:e}"
        );
        let limit = AUTO_DT_FRACTION * tissue.min(SUBCYCLED_STEP_RATIO * critical);
        assert!(p.time.dt <= limit * (1.0 + 1e-12) && p.time.dt > 0.5 * limit);
        assert!(p.time.dt / k as f64 <= AUTO_DT_FRACTION * critical * (1.0 + 1e-12));
        assert!(matches!(p.physics.saliva[0].params.decay, Decay::Time(_)));
        // a fixed step: the substeps it needs, eq. 11's decay in seconds
        let p = parse_ok(&format!(
            "{SLABS}[time]\ndt = 4e-4\nsubcycles = \"auto\"\ntotal = 0.05\n"
        ));
        let want = (4e-4 / (AUTO_DT_FRACTION * critical)).ceil() as usize;
        assert_eq!(p.numerics.subcycles, want);
        assert!(matches!(p.physics.saliva[0].params.decay, Decay::Time(_)));
        let p = parse_ok(&format!(
            "{SLABS}[time]\ndt = 1e-4\nsubcycles = 3\ntotal = 0.05\n"
        ));
        assert_eq!(p.numerics.subcycles, 3);
        let err = |t: &str| parse(t, Path::new("s.toml")).err().unwrap().to_string();
        for bad in ["0", "65", "-2"] {
            let e = err(&format!(
                "{SLABS}[time]\ndt = 1e-4\nsubcycles = {bad}\ntotal = 0.05\n"
            ));
            assert!(
                e.contains("field `time.subcycles`: must be between 1 and 64"),
                "{e}"
            );
        }
        let e = err(&format!(
            "{SLABS}decay_per_step = 0.99\n[time]\ndt = 1e-4\nsubcycles = 2\ntotal = 0.05\n"
        ));
        assert!(
            e.contains("field `saliva[0].decay_per_step`") && e.contains("time.subcycles"),
            "{e}"
        );
        let e = err(&format!(
            "{BLOCK}[time]\ndt = 1e-4\nsubcycles = 2\ntotal = 0.05\n"
        ));
        assert!(
            e.contains("field `time.subcycles`") && e.contains("no saliva element"),
            "{e}"
        );
    }

    /// `--dt`: the frames' interval and eq. 11's decay kept in physical time.
    #[test]
    fn with_dt_keeps_the_frame_interval_and_the_decay_in_seconds() {
        let text = "[time]\ndt = 1e-5\ntotal = 1.0\noutput_every = 1000\n\
                    [[saliva]]\nmaterial = \"s\"\ndecay_per_step = 0.99\n[[saliva]]\nmaterial = \"t\"\n";
        let auto: toml::Table =
            toml::from_str(&with_dt(text, "t", DtChoice::Auto).unwrap()).unwrap();
        assert_eq!(auto["time"]["dt"].as_str(), Some("auto"));
        assert_eq!(
            auto["time"]["output_interval"].as_float(),
            Some(1000.0 * 1e-5)
        );
        assert!(auto["time"].get("output_every").is_none());
        let tau = -1e-5 / 0.99_f64.ln();
        for k in 0..2 {
            let t = auto["saliva"][k]["decay_time"].as_float().unwrap();
            assert!((t - tau).abs() < 1e-18, "{t}");
            assert!(auto["saliva"][k].get("decay_per_step").is_none());
        }
        let again = with_dt(
            &toml::to_string(&auto).unwrap(),
            "t",
            DtChoice::Seconds(2e-5),
        )
        .unwrap();
        let again: toml::Table = toml::from_str(&again).unwrap();
        assert_eq!(again["time"]["dt"].as_float(), Some(2e-5));
        assert_eq!(again["time"]["output_every"].as_integer(), Some(500));
        assert!(again["time"].get("output_interval").is_none());
        assert_eq!(
            again["saliva"][0]["decay_time"].as_float(),
            auto["saliva"][0]["decay_time"].as_float()
        );
        assert!("0".parse::<DtChoice>().is_err() && "nan".parse::<DtChoice>().is_err());
        assert_eq!("auto".parse::<DtChoice>(), Ok(DtChoice::Auto));
    }
}

#[cfg(test)]
mod size_tests {
    use super::*;

    /// 10^7 inline keys (about 150 MB of text) aborted in the TOML parser: a scenario text over
    /// 16 MiB is refused before it is parsed, and the message points to keys_file.
    #[test]
    fn a_scenario_too_large_is_refused_before_parsing() {
        let mut text = String::from("[jaw]\nkeys = [");
        while text.len() as u64 <= MAX_SCENARIO_BYTES {
            text.push_str("[0.0, 0.0], ");
        }
        text.push_str("]\n");
        let e = parse(&text, Path::new("big.toml"))
            .err()
            .unwrap()
            .to_string();
        assert!(
            e.starts_with("big.toml: is ") && e.contains("keys_file"),
            "{e}"
        );
    }
}

#[cfg(test)]
mod unit_tests {
    use super::LengthUnit;

    /// The one unit table: symbols round-trip, the scale of each, and a scenario's `[units]
    /// length` reads every symbol the command line takes.
    #[test]
    fn length_units_round_trip() {
        let want = [
            ("m", 1.0),
            ("dm", 0.1),
            ("cm", 0.01),
            ("mm", 0.001),
            ("in", 0.0254),
        ];
        for (u, (name, metres)) in LengthUnit::ALL.iter().zip(want) {
            assert_eq!((u.name(), u.metres()), (name, metres));
            assert_eq!(LengthUnit::from_name(name), Some(*u));
            let parsed: super::Units = toml::from_str(&format!("length = \"{name}\"")).unwrap();
            assert_eq!(parsed.length, Some(*u));
        }
        assert_eq!(LengthUnit::from_name("km"), None);
    }
}
