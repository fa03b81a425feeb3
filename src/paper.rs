//! The paper's runs as data (no figures here: `sticky-lips paper` makes them): Table 1 once
//! (`paper/scenarios/table1.toml`, compiled in), the two models it can run on, the
//! parameters chosen for each, and every run as a short list of overrides on Table 1. The
//! `paper` command and `verification/paper_claims.rs` both build their runs from this.

use crate::error::Result;
use crate::io::scenario;
use crate::Problem;
use toml::Value;

/// Table 1 and the face model at the wide opening with stickiness.
pub const TABLE1: &str = include_str!("../paper/scenarios/table1.toml");
/// Where [`TABLE1`] comes from.
pub const TABLE1_NAME: &str = "paper/scenarios/table1.toml";

/// Which model the figures are made on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Model {
    /// The MakeHuman head (`assets/makehuman/`).
    Face,
    /// The procedural mouth (`src/mesh/mouth.rs`), with its own choice of K_glue and angles.
    Procedural,
}

/// The parameters chosen once for a model (paper/README.md): K_glue and the two jaw angles.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Choice {
    pub k_glue: f64,
    pub slight_angle: f64,
    pub wide_angle: f64,
}

impl Model {
    pub fn name(self) -> &'static str {
        match self {
            Model::Face => crate::mesh::face::MAKEHUMAN,
            Model::Procedural => "procedural mouth",
        }
    }

    /// K_glue and the wide angle as Table 1's file has them (face) and the slight angle.
    pub fn choice(self) -> Choice {
        match self {
            Model::Face => {
                let t: toml::Table = toml::from_str(TABLE1).expect("table1.toml is TOML");
                let num =
                    |v: Option<&Value>| v.and_then(|v| v.as_float()).expect("table1.toml value");
                Choice {
                    k_glue: num(t["saliva"].as_array().and_then(|a| a[0].get("k_glue"))),
                    slight_angle: SLIGHT_FACE,
                    wide_angle: num(t["jaw"].get("angle")),
                }
            }
            // paper/README.md before the face: chosen on the procedural mouth
            Model::Procedural => Choice {
                k_glue: 0.2,
                slight_angle: 0.05,
                wide_angle: 0.15,
            },
        }
    }

    /// Overrides that turn Table 1 into this model at full or quick resolution.
    pub fn base(self, quick: bool) -> Vec<(String, Value)> {
        let c = self.choice();
        let res = Value::Float(if quick { 0.25 } else { 1.0 });
        let mut o = match self {
            Model::Face => vec![("mesh.face.resolution".to_string(), res)],
            Model::Procedural => vec![
                ("mesh.generator".to_string(), Value::String("mouth".into())),
                ("mesh.mouth.resolution".to_string(), res),
                ("saliva.0.k_glue".into(), Value::Float(c.k_glue)),
                ("jaw.angle".into(), Value::Float(c.wide_angle)),
            ],
        };
        if quick {
            o.push(("time.total".into(), Value::Float(0.8)));
        }
        o
    }
}

/// The slight jaw opening on the face (rad), chosen with K_glue (paper/README.md).
pub const SLIGHT_FACE: f64 = 0.075;
/// Moisture above the critical one: no glue (eq. 7 gives Z = 1): "without stickiness".
pub const WET: f64 = 110.0;
/// K_glue so large that the saliva never breaks (Z = 11: a stretch of 3.3): the load
/// profile with breaking off.
pub const NO_BREAKING: f64 = 10.0;

/// The jaw of run `plosive` and `examples/plosive.toml` ("papa"): (time s, angle rad) keys
/// that open the jaw, hold, close it until the lips touch, hold it closed and open it again.
pub const PLOSIVE_JAW: [[f64; 2]; 7] = [
    [0.0, 0.0],
    [0.3, 0.15],
    [0.4, 0.15],
    [0.6, 0.0],
    [0.8, 0.0],
    [1.1, 0.15],
    [1.25, 0.15],
];

/// A run: its name (its directory under `OUT/runs/`) and its overrides on Table 1.
#[derive(Clone, Debug)]
pub struct Spec {
    pub name: String,
    pub what: String,
    pub overrides: Vec<(String, Value)>,
}

fn make(name: &str, what: &str, overrides: Vec<(&str, Value)>) -> Spec {
    Spec {
        name: name.into(),
        what: what.into(),
        overrides: overrides
            .into_iter()
            .map(|(k, v)| (k.to_string(), v))
            .collect(),
    }
}

fn muscle(name: &str) -> Value {
    let mut t = toml::Table::new();
    t.insert("name".into(), Value::String(name.into()));
    t.insert("strength".into(), Value::Float(0.3));
    t.insert("activation".into(), Value::Float(1.0));
    t.insert("shape".into(), Value::String("smooth_step".into()));
    t.insert("duration".into(), Value::Float(0.5));
    Value::Table(t)
}

fn bands(edges: &[f64], values: &[f64]) -> Value {
    let mut b = toml::Table::new();
    b.insert(
        "axis".into(),
        Value::Array(vec![
            Value::Float(1.0),
            Value::Float(0.0),
            Value::Float(0.0),
        ]),
    );
    b.insert(
        "edges".into(),
        Value::Array(edges.iter().map(|e| Value::Float(*e)).collect()),
    );
    b.insert(
        "values".into(),
        Value::Array(values.iter().map(|e| Value::Float(*e)).collect()),
    );
    let mut t = toml::Table::new();
    t.insert("bands".into(), Value::Table(b));
    Value::Table(t)
}

/// The `[jaw]` table of run `plosive`: [`PLOSIVE_JAW`] as keys (replacing Table 1's shape).
fn plosive_jaw() -> Value {
    let keys = PLOSIVE_JAW
        .iter()
        .map(|k| Value::Array(vec![Value::Float(k[0]), Value::Float(k[1])]))
        .collect();
    let mut t = toml::Table::new();
    t.insert("keys".into(), Value::Array(keys));
    Value::Table(t)
}

/// K_glue values and jaw angles of the sweep (the chosen ones are among them).
pub fn sweep_grid(quick: bool) -> (Vec<f64>, Vec<f64>) {
    if quick {
        (vec![0.05, 0.1, 0.15], vec![0.05, 0.075, 0.15])
    } else {
        (
            vec![0.05, 0.08, 0.1, 0.12, 0.15, 0.18],
            vec![0.05, 0.065, 0.075, 0.08, 0.1, 0.125, 0.15],
        )
    }
}

/// The name of a sweep run.
pub fn sweep_name(k: f64, angle: f64) -> String {
    format!("sweep_k{k}_a{angle}")
}

/// Every run the figures can ask for.
/// The time steps of the convergence study (issue 30): from a quarter of Table 1's 1e-5 s
/// to five times it (5e-5 s: 65 % of the full face's critical step, 7.67e-5 s).
pub const DT_STUDY: [f64; 6] = [2.5e-6, 5e-6, 1e-5, 2e-5, 4e-5, 5e-5];

/// The name of the convergence study's run at step `dt`.
pub fn dt_run_name(dt: f64) -> String {
    format!("dt_{dt:e}")
}

pub fn all(model: Model, quick: bool) -> Vec<Spec> {
    let c = model.choice();
    let f = Value::Float;
    let mut v = vec![
        make(
            "fig4_dry",
            "wide opening without stickiness",
            vec![("saliva.0.initial_moisture", f(WET))],
        ),
        make("fig4_sticky", "wide opening with stickiness", vec![]),
        make(
            "fig7_dry",
            "slight opening without stickiness",
            vec![
                ("jaw.angle", f(c.slight_angle)),
                ("saliva.0.initial_moisture", f(WET)),
            ],
        ),
        make(
            "fig7_sticky",
            "slight opening with stickiness",
            vec![("jaw.angle", f(c.slight_angle))],
        ),
        make(
            "fig9_bands",
            "slight opening, two wet bands (no glue) either side of the centre",
            vec![
                ("jaw.angle", f(c.slight_angle)),
                (
                    "saliva.0.initial_moisture",
                    bands(
                        &[-0.016, -0.006, 0.006, 0.016],
                        &[100.0, WET, 100.0, WET, 100.0],
                    ),
                ),
            ],
        ),
        make(
            "fig10_asym",
            "wide opening with the depressors of the subject's left side active",
            vec![(
                "model_muscle",
                Value::Array(vec![
                    muscle("depressor_labii_inferioris_l"),
                    muscle("depressor_anguli_oris_l"),
                ]),
            )],
        ),
        make(
            "load_profile",
            "wide opening with breaking off (K_glue = 10): the load on the saliva",
            vec![("saliva.0.k_glue", f(NO_BREAKING))],
        ),
    ];
    v.push(make(
        "plosive",
        "the jaw opens, closes until the lips touch, holds and opens again (lips that stick again)",
        vec![
            ("jaw", plosive_jaw()),
            ("time.total", f(PLOSIVE_JAW[PLOSIVE_JAW.len() - 1][0])),
        ],
    ));
    let (ks, angles) = sweep_grid(quick);
    for &a in &angles {
        for &k in &ks {
            v.push(make(
                &sweep_name(k, a),
                "K_glue x jaw angle sweep",
                vec![("saliva.0.k_glue", f(k)), ("jaw.angle", f(a))],
            ));
        }
    }
    v.extend(study(quick));
    for dt in DT_STUDY {
        v.push(make(
            &dt_run_name(dt),
            &format!(
                "wide opening with stickiness at dt = {dt:e} s (frames every 10 ms, eq. 11's decay in physical time)"
            ),
            vec![("time.dt", f(dt))],
        ));
    }
    for c in choices(quick).into_iter().filter(|_| model == Model::Face) {
        for &a in &choice_angles(quick) {
            let mut o = choice_pins();
            o.retain(|(k, _)| c.overrides.iter().all(|(ck, _)| ck != k));
            o.extend(c.overrides.iter().cloned());
            o.push(("jaw.angle", f(a)));
            v.push(make(
                &choice_name(c.name, a),
                &format!("model choice `{}`: {}, jaw {a} rad", c.choice, c.what),
                o,
            ));
        }
    }
    v
}

/// One variant of the model-choice study ([`choices`]): the face model with one modelling
/// choice the paper does not fix changed.
#[derive(Clone, Debug)]
pub struct Variant {
    /// Its name in run names (`choice_NAME_aANGLE`).
    pub name: &'static str,
    /// The choice it belongs to (one plot per choice); the reference belongs to all.
    pub choice: &'static str,
    pub what: &'static str,
    pub overrides: Vec<(&'static str, Value)>,
}

/// The name of the reference variant of [`choices`].
pub const CHOICE_REFERENCE: &str = "reference";

/// The study's reference, pinned: every choice the study varies, at the value of the
/// reference (the uniform saliva layer, nothing more held than the skull's edges, K_glue
/// 0.1), so that a study run means the same whatever the defaults become.
fn choice_pins() -> Vec<(&'static str, Value)> {
    let f = Value::Float;
    vec![
        ("mesh.face.saliva_thickness", Value::String("median".into())),
        ("mesh.face.jaw_weight", f(0.5)),
        ("mesh.face.thickness", f(0.010)),
        ("mesh.face.commissure", f(0.0)),
        ("mesh.face.modiolus_radius", f(0.0)),
        ("mesh.face.vestibule", f(0.0)),
        (
            "mesh.face.hinge_offset",
            Value::Array(vec![f(0.0), f(0.0), f(0.0)]),
        ),
        ("saliva.0.k_glue", f(0.1)),
    ]
}

/// The modelling choices the paper leaves open, one change at a time from the reference
/// (paper/README.md, "What makes a partial opening stable"): the saliva layer as the head's
/// contours have it, K_glue, where the jaw's rigid motion reaches, what holds the corners
/// of the mouth (the modiolus), what holds the lips from inside (the vestibule), whether the
/// lips join through tissue at the commissure, the extrusion depth and the hinge.
pub fn choices(quick: bool) -> Vec<Variant> {
    let f = Value::Float;
    let v = |name, choice, what, overrides| Variant {
        name,
        choice,
        what,
        overrides,
    };
    let all = vec![
        v(CHOICE_REFERENCE, "all", "reference: uniform saliva layer, skull edges held", vec![]),
        v(
            "contours",
            "layer",
            "saliva layer as high as the lip contours are apart (uneven)",
            vec![("mesh.face.saliva_thickness", Value::String("contours".into()))],
        ),
        v("kglue005", "kglue", "K_glue = 0.05", vec![("saliva.0.k_glue", f(0.05))]),
        v("kglue02", "kglue", "K_glue = 0.2", vec![("saliva.0.k_glue", f(0.2))]),
        v(
            "jawweight03",
            "jaw",
            "rigid jaw: jaw weight >= 0.3 (reaches closer to the lower lip)",
            vec![("mesh.face.jaw_weight", f(0.3))],
        ),
        v(
            "jawweight08",
            "jaw",
            "rigid jaw: jaw weight >= 0.8 (the chin only)",
            vec![("mesh.face.jaw_weight", f(0.8))],
        ),
        v(
            "modiolus",
            "corners",
            "the modioli held: 5 mm around a point 10 mm beyond each corner",
            vec![("mesh.face.modiolus_radius", f(0.005))],
        ),
        v(
            "vestibule",
            "inside",
            "the inner layer held by the bones 8 mm beyond the lip lines (maxilla above, mandible below)",
            vec![("mesh.face.vestibule", f(0.008))],
        ),
        v(
            "commissure",
            "commissure",
            "lips joined through tissue for 3 mm at each corner",
            vec![("mesh.face.commissure", f(0.003))],
        ),
        v(
            "depth15",
            "depth",
            "extruded 15 mm deep instead of 10",
            vec![("mesh.face.thickness", f(0.015))],
        ),
        v(
            "hingelow",
            "hinge",
            "the hinge 15 mm lower",
            vec![(
                "mesh.face.hinge_offset",
                Value::Array(vec![f(0.0), f(-0.015), f(0.0)]),
            )],
        ),
    ];
    if quick {
        all.into_iter()
            .filter(|c| [CHOICE_REFERENCE, "modiolus", "contours"].contains(&c.name))
            .collect()
    } else {
        all
    }
}

/// The jaw angles of the model-choice study (rad).
pub fn choice_angles(quick: bool) -> Vec<f64> {
    if quick {
        vec![0.075, 0.1, 0.15]
    } else {
        vec![0.05, 0.075, 0.09, 0.105, 0.125, 0.15, 0.2]
    }
}

/// The name of a model-choice run.
pub fn choice_name(variant: &str, angle: f64) -> String {
    format!("choice_{variant}_a{angle}")
}

/// The zipper study: the wide opening with stickiness with one thing changed at a time, to
/// see what sets how fast the opening runs from the centre to the corners. Names start with
/// `study_`; the first run of the list is the reference (`fig4_sticky`, not repeated).
pub fn study(quick: bool) -> Vec<Spec> {
    let f = Value::Float;
    let dt = crate::problem::table1::TIME_STEP;
    let per_step = |tau: f64| f((-dt / tau).exp());
    let gradient = |centre: f64| {
        // moisture falling in equal steps from 100 (critical: the strongest glue) at
        // |x| >= 20 mm to `centre` at |x| < 4 mm (bands 8 mm wide)
        let step = (100.0 - centre) / 3.0;
        let (a, b) = (100.0 - step, 100.0 - 2.0 * step);
        bands(
            &[-0.020, -0.012, -0.004, 0.004, 0.012, 0.020],
            &[100.0, a, b, centre, b, a, 100.0],
        )
    };
    let mut v = vec![
        make(
            "study_decay50ms",
            "force decay time 50 ms instead of 1 ms (eq. 11's 0.99 per step at dt = 1e-5 s)",
            vec![("saliva.0.decay_per_step", per_step(0.05))],
        ),
        make(
            "study_jaw1s",
            "the jaw opens over 1 s instead of 0.5 s",
            vec![("jaw.duration", f(1.0)), ("time.total", f(1.5))],
        ),
        make(
            "study_moisture_steep",
            "moisture falling from 100 at the corners to 10 at the centre (weaker glue at the centre)",
            vec![("saliva.0.initial_moisture", gradient(10.0))],
        ),
    ];
    if !quick {
        v.extend([
            make(
                "study_decay10ms",
                "force decay time 10 ms",
                vec![("saliva.0.decay_per_step", per_step(0.01))],
            ),
            make(
                "study_latched",
                "the latched reading of eq. 11 (once broken, always broken)",
                vec![("saliva.0.rule", Value::String("latched".into()))],
            ),
            make(
                "study_jaw2s",
                "the jaw opens over 2 s",
                vec![("jaw.duration", f(2.0)), ("time.total", f(2.5))],
            ),
            make(
                "study_damping20",
                "mass damping 20 1/s instead of 80",
                vec![("numerics.damping", f(20.0))],
            ),
            make(
                "study_damping320",
                "mass damping 320 1/s",
                vec![("numerics.damping", f(320.0))],
            ),
            make(
                "study_tissue_dense",
                "tissue density x4 (its wave speed / 2)",
                vec![("materials.0.density", f(4200.0))],
            ),
            make(
                "study_tissue_stiff",
                "tissue moduli x4",
                vec![("materials.0.mu", f(3200.0)), ("materials.0.K", f(28000.0))],
            ),
            make(
                "study_saliva_soft",
                "saliva moduli / 10",
                vec![("materials.1.mu", f(770.0)), ("materials.1.K", f(19100.0))],
            ),
            make(
                "study_moisture_mild",
                "moisture falling from 100 at the corners to 55 at the centre",
                vec![("saliva.0.initial_moisture", gradient(55.0))],
            ),
            make(
                "study_resolution_quarter",
                "a quarter of the hexahedra (resolution 0.25)",
                vec![("mesh.face.resolution", f(0.25))],
            ),
        ]);
    }
    v
}

/// The scenario text of run `s` on `model` (quick or full) and its problem; `label` names the
/// scenario in errors (e.g. the path it is written to).
pub fn scenario_of(
    model: Model,
    quick: bool,
    s: &Spec,
    label: &std::path::Path,
) -> Result<(String, Problem)> {
    let mut o: Vec<(String, Value)> = model.base(quick);
    o.extend(s.overrides.iter().cloned());
    // `time.dt` is not a plain override: the run goes to that step with the frames' interval
    // and eq. 11's decay kept in seconds (`scenario::with_dt`)
    let dt = o
        .iter()
        .position(|(k, _)| k == "time.dt")
        .map(|i| o.remove(i).1);
    let refs: Vec<(&str, Value)> = o.iter().map(|(k, v)| (k.as_str(), v.clone())).collect();
    let mut text = scenario::with_overrides(TABLE1, TABLE1_NAME, &refs)?;
    if let Some(v) = dt {
        let choice = match v {
            Value::Float(x) if x.is_finite() && x > 0.0 => scenario::DtChoice::Seconds(x),
            Value::String(w) if w == "auto" => scenario::DtChoice::Auto,
            other => {
                return Err(crate::error::Error::field(
                    TABLE1_NAME,
                    "time.dt",
                    format!("run {}: `{other}` is neither seconds nor \"auto\"", s.name),
                ))
            }
        };
        text = scenario::with_dt(&text, TABLE1_NAME, choice)?;
    }
    text.insert_str(
        0,
        &format!(
            "# sticky-lips paper, run {}: {} ({}; {})\n",
            s.name,
            s.what,
            model.name(),
            if quick { "--quick" } else { "full resolution" }
        ),
    );
    let problem = scenario::parse(&text, label)?.problem;
    Ok((text, problem))
}

/// The run called `name` of [`all`].
pub fn spec(model: Model, quick: bool, name: &str) -> Option<Spec> {
    all(model, quick).into_iter().find(|s| s.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::saliva::{Decay, EvaporationSchedule};
    use crate::problem::table1;

    /// `paper/scenarios/table1.toml` says what `problem::table1` says: the base scenario of
    /// the figures cannot drift from Table 1 as the code defines it.
    #[test]
    fn table1_toml_is_table_1() {
        let p = scenario::parse(TABLE1, std::path::Path::new(TABLE1_NAME))
            .unwrap()
            .problem;
        let by_name = |n: &str| p.materials.iter().find(|m| m.name == n).unwrap();
        for (name, t) in [("tissue", table1::TISSUE), ("saliva", table1::SALIVA)] {
            assert_eq!(by_name(name), &t.spec(name), "{name}");
        }
        assert_eq!(p.time.dt, table1::TIME_STEP);
        assert_eq!(p.time.total_time, table1::TOTAL_TIME);
        assert_eq!(p.numerics.damping, table1::DAMPING);
        assert_eq!(p.numerics.hourglass_kappa, table1::HOURGLASS_KAPPA);
        let s = &p.physics.saliva[0].params;
        assert_eq!(s.critical_moisture, table1::CRITICAL_MOISTURE);
        assert_eq!(s.decay, Decay::PerStep(table1::DECAY_PER_STEP));
        assert_eq!(
            s.evaporation,
            EvaporationSchedule::constant(table1::EVAPORATION_RATE)
        );
        assert_eq!(
            s.initial_moisture,
            crate::material::saliva::MoistureMap::Constant(table1::INITIAL_MOISTURE)
        );
    }
}
