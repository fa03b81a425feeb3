//! `sticky-lips paper`: runs every scenario of `paper/scenarios/` and writes every figure.
//!
//! The library computes (runs, measures, pixel buffers); this module decides which runs make
//! which figure and writes the PNG files, the data behind them, and Table 1 as used.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::time::Instant;
use sticky_lips::driver::{self, Backend, Progress, RunOptions};
use sticky_lips::error::{Error, Location, Result};
use sticky_lips::io::scenario;
use sticky_lips::io::vtu::read_point_data_f64;
use sticky_lips::mesh::mouth;
use sticky_lips::render::plot::{line_plot, profile_plot, PlotSpec, ProfileSpec, Series};
use sticky_lips::render::raster::{Camera, Projection, RenderOptions};
use sticky_lips::render::{boundary_quads, render_mesh_with, save_png, GridLabels, Image};
use sticky_lips::{Precision, Problem};

/// Fig. 2's colours: soft tissue of the upper face (blue), lower face (red), saliva (green).
const BLUE: [u8; 3] = [70, 105, 190];
const RED: [u8; 3] = [195, 70, 65];
const GREEN: [u8; 3] = [60, 170, 80];
/// Renderings of the animation: skin, saliva, and a dark mouth cavity behind the lips.
const SKIN: [u8; 3] = [222, 170, 140];
const LIP: [u8; 3] = [190, 95, 95];
const CAVITY: [u8; 3] = [28, 18, 22];
const WHITE: [u8; 3] = [255, 255, 255];

/// The K_glue values of the stickiness sweep (the chosen one is in the scenarios).
const SWEEP: [f64; 3] = [0.1, 0.5, 1.0];

pub struct PaperOptions {
    pub out: PathBuf,
    pub scenarios: PathBuf,
    pub quick: bool,
    pub threads: usize,
    pub backend: Backend,
    pub precision: Precision,
    pub progress: Progress,
    /// Reuse a run whose outputs are already complete (same scenario, same step count): only
    /// the figures are redrawn.
    pub reuse: bool,
}

struct Run {
    name: String,
    problem: Problem,
    dir: PathBuf,
    measures: Value,
    summary: Value,
    wall: f64,
}

impl Run {
    fn frames(&self) -> &Vec<Value> {
        self.measures["frames"].as_array().expect("measures.frames")
    }
    fn times(&self) -> Vec<f64> {
        self.frames()
            .iter()
            .map(|f| f["time"].as_f64().unwrap_or(0.0))
            .collect()
    }
    /// Index of the output frame closest to time `t`.
    fn frame_at(&self, t: f64) -> usize {
        let ts = self.times();
        (0..ts.len())
            .min_by(|&a, &b| (ts[a] - t).abs().total_cmp(&(ts[b] - t).abs()))
            .unwrap_or(0)
    }
    fn displacement(&self, frame: usize) -> Result<Vec<[f64; 3]>> {
        let path = self.dir.join(format!("frame_{frame:06}.vtu"));
        let (v, _, _) = read_point_data_f64(&path, "displacement")?;
        Ok(v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
    }
    /// Which elements are broken saliva elements at output frame `frame` (hidden in renderings).
    fn broken(&self, frame: usize) -> Result<Vec<bool>> {
        let path = self.dir.join(format!("frame_{frame:06}.vtu"));
        if self.problem.physics.saliva.is_empty() {
            return Ok(Vec::new());
        }
        let (v, _, _) = sticky_lips::io::vtu::read_cell_data(&path, "saliva_broken")?;
        Ok(v.iter().map(|b| *b > 0.5).collect())
    }
    /// A rendering of output frame `frame` (broken saliva hidden).
    fn picture(&self, frame: usize, w: u32, h: u32) -> Result<Image> {
        Ok(render_hiding(
            &self.problem,
            &self.displacement(frame)?,
            &self.broken(frame)?,
            &skin_colours,
            CAVITY,
            w,
            h,
        ))
    }
    fn series(&self, key: &str) -> Vec<(f64, f64)> {
        self.frames()
            .iter()
            .map(|f| {
                (
                    f["time"].as_f64().unwrap_or(0.0),
                    f[key].as_f64().unwrap_or(0.0),
                )
            })
            .collect()
    }
    fn gaps(&self, frame: usize) -> Vec<f64> {
        self.frames()[frame]["gap"]
            .as_array()
            .map(|a| a.iter().map(|v| v.as_f64().unwrap_or(0.0)).collect())
            .unwrap_or_default()
    }
    fn columns_x(&self) -> Vec<f64> {
        self.measures["columns"]["x"]
            .as_array()
            .map(|a| a.iter().map(|v| v.as_f64().unwrap_or(0.0)).collect())
            .unwrap_or_default()
    }
    fn first_opening(&self) -> Option<(f64, f64)> {
        let v = &self.measures["first_opening"];
        Some((v[0].as_f64()?, v[1].as_f64()?))
    }
    fn last(&self) -> usize {
        self.frames().len() - 1
    }
}

fn quick_overrides() -> Vec<(&'static str, toml::Value)> {
    vec![
        // a coarse mouth (about 600 hexahedra) and a shorter run: minutes become seconds
        ("mesh.mouth.resolution", toml::Value::Float(0.25)),
        ("time.total", toml::Value::Float(0.7)),
    ]
}

fn run_one(
    opts: &PaperOptions,
    name: &str,
    file: &str,
    extra: &[(&'static str, toml::Value)],
) -> Result<Run> {
    let mut overrides = if opts.quick {
        quick_overrides()
    } else {
        Vec::new()
    };
    overrides.extend(extra.iter().cloned());
    let path = opts.scenarios.join(file);
    let s = scenario::read_with_overrides(&path, &overrides)?;
    let dir = opts.out.join("runs").join(name);
    let ro = RunOptions {
        out: dir.clone(),
        precision: opts.precision,
        backend: opts.backend,
        threads: opts.threads,
        force_dt: false,
        progress: opts.progress,
    };
    eprintln!(
        "paper: {name} ({}; {} hexahedra, {} steps)",
        path.display(),
        s.problem.mesh.elements.len(),
        s.problem.num_steps()
    );
    let t0 = Instant::now();
    let previous: Option<Value> = std::fs::read_to_string(dir.join("summary.json"))
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok());
    let complete = previous.as_ref().is_some_and(|v| {
        v["steps"].as_u64() == Some(s.problem.num_steps() as u64)
            && v["num_elements"].as_u64() == Some(s.problem.mesh.elements.len() as u64)
            && dir.join("measures.json").exists()
    });
    if opts.reuse && complete {
        eprintln!(
            "paper: {name}: reusing the complete run in {}",
            dir.display()
        );
    } else {
        driver::run(&s.problem, &ro)?;
    }
    let wall = match (&previous, opts.reuse && complete) {
        (Some(v), true) => v["wall_time"].as_f64().unwrap_or(0.0),
        _ => t0.elapsed().as_secs_f64(),
    };
    let read_json = |f: &str| -> Result<Value> {
        let p = dir.join(f);
        let text = std::fs::read_to_string(&p).map_err(|e| Error::io(&p, e))?;
        serde_json::from_str(&text)
            .map_err(|e| Error::input(p.display().to_string(), Location::None, e.to_string()))
    };
    Ok(Run {
        name: name.into(),
        measures: read_json("measures.json")?,
        summary: read_json("summary.json")?,
        problem: s.problem,
        dir,
        wall,
    })
}

/// Per-element colour code: 0 upper face, 1 lower face, 2 saliva.
fn element_codes(p: &Problem) -> Vec<u8> {
    let mut code = vec![0u8; p.mesh.elements.len()];
    for (name, c) in [("lower_face", 1u8), ("saliva", 2u8)] {
        if let Some(set) = p.mesh.element_sets.get(name) {
            for &e in set {
                code[e as usize] = c;
            }
        }
    }
    code
}

/// The fixed front camera on the mouth region (reference configuration), so every frame
/// of every run is seen from the same place.
fn mouth_camera(p: &Problem, aspect: f64) -> Camera {
    let pts: Vec<[f64; 3]> = p
        .mesh
        .nodes
        .iter()
        .copied()
        .filter(|x| x[0].abs() < 0.036 && x[1] > -0.032 && x[1] < 0.014)
        .collect();
    Camera::fit(
        &pts,
        [0.0, 0.0, -1.0],
        [0.0, 1.0, 0.0],
        30.0,
        Projection::Perspective,
        aspect,
        0.04,
    )
}

/// The boundary faces of the elements that are drawn: all but the `hidden` ones (broken
/// saliva elements, which no longer join the lips), with `element` indices of the full mesh.
fn visible_faces(p: &Problem, hidden: &[bool]) -> Vec<sticky_lips::render::BoundaryFace> {
    let keep: Vec<u32> = (0..p.mesh.elements.len() as u32)
        .filter(|&e| !hidden.get(e as usize).copied().unwrap_or(false))
        .collect();
    let els: Vec<[u32; 8]> = keep.iter().map(|&e| p.mesh.elements[e as usize]).collect();
    let mut faces = boundary_quads(&els);
    for f in faces.iter_mut() {
        f.element = keep[f.element as usize];
    }
    faces
}

fn render(
    p: &Problem,
    u: &[[f64; 3]],
    colours: &dyn Fn(u8) -> [u8; 3],
    background: [u8; 3],
    w: u32,
    h: u32,
) -> Image {
    render_hiding(p, u, &[], colours, background, w, h)
}

fn render_hiding(
    p: &Problem,
    u: &[[f64; 3]],
    hidden: &[bool],
    colours: &dyn Fn(u8) -> [u8; 3],
    background: [u8; 3],
    w: u32,
    h: u32,
) -> Image {
    let x: Vec<[f64; 3]> = p
        .mesh
        .nodes
        .iter()
        .zip(u)
        .map(|(a, b)| [a[0] + b[0], a[1] + b[1], a[2] + b[2]])
        .collect();
    let faces = visible_faces(p, hidden);
    let codes = element_codes(p);
    let cam = mouth_camera(p, w as f64 / h as f64);
    let mut o = RenderOptions::new(w, h);
    o.background = background;
    render_mesh_with(
        &x,
        &faces,
        &|f| colours(codes[f.element as usize]),
        None,
        &cam,
        &o,
    )
}

fn skin_colours(code: u8) -> [u8; 3] {
    if code == 2 {
        LIP
    } else {
        SKIN
    }
}

fn material_colours(code: u8) -> [u8; 3] {
    [BLUE, RED, GREEN][code as usize]
}

fn save(out: &Path, name: &str, img: &Image, written: &mut Vec<String>) -> Result<()> {
    let path = out.join(name);
    save_png(&path, img)?;
    written.push(name.to_string());
    Ok(())
}

fn ms(x: f64) -> f64 {
    1e3 * x
}

/// A procedural face texture for Fig. 11: skin with a faint mottling, redder lips around
/// the mouth line, a darker line where the lips meet. `u` across the face, `v` up.
fn face_texture(params: &mouth::MouthParams) -> Image {
    let (w, h) = (512u32, 512u32);
    let mut img = Image::new(w, h, SKIN);
    let height = params.height_above + params.height_below;
    let v_mouth = params.height_below / height; // the mouth line's v
    let half = 0.5 * params.mouth_width / params.face_width;
    for j in 0..h {
        for i in 0..w {
            let u = (i as f64 + 0.5) / w as f64 - 0.5;
            let v = 1.0 - (j as f64 + 0.5) / h as f64;
            let dv = v - v_mouth;
            // lip region: an ellipse-like band about the mouth line, fading at the corners
            let along = (u / (half * 1.15)).abs().min(1.0);
            let lip_h = 0.075 * (1.0 - along * along).sqrt();
            let mottling = 6.0 * ((37.0 * u).sin() * (41.0 * v).cos() + (13.0 * u + 7.0 * v).sin());
            let mut c = [
                SKIN[0] as f64 + mottling,
                SKIN[1] as f64 + 0.7 * mottling,
                SKIN[2] as f64 + 0.5 * mottling,
            ];
            if dv.abs() < lip_h {
                let t = 1.0 - (dv.abs() / lip_h).powi(4);
                for (k, l) in [200.0, 100.0, 105.0].iter().enumerate() {
                    c[k] = c[k] * (1.0 - t) + l * t;
                }
            }
            if dv.abs() < 0.004 && along < 1.0 {
                c = [90.0, 40.0, 45.0];
            }
            img.set(i as i64, j as i64, c.map(|x| x.clamp(0.0, 255.0) as u8));
        }
    }
    img
}

pub fn paper(opts: &PaperOptions) -> Result<()> {
    let t_all = Instant::now();
    let out = &opts.out;
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    let k = |v: f64| toml::Value::Float(v);

    // ---- the runs
    let dry = run_one(opts, "fig4_dry", "fig4_dry.toml", &[])?;
    let sticky = run_one(opts, "fig4_sticky", "fig4_sticky.toml", &[])?;
    let small_dry = run_one(opts, "fig7_dry", "fig7_dry.toml", &[])?;
    let small_sticky = run_one(opts, "fig7_sticky", "fig7_sticky.toml", &[])?;
    let bands = run_one(opts, "fig9_bands", "fig9_bands.toml", &[])?;
    let asym = run_one(opts, "fig10_asym", "fig10_asym.toml", &[])?;
    let mut sweep = Vec::new();
    for kg in SWEEP {
        sweep.push(run_one(
            opts,
            &format!("sweep_k{kg}"),
            "fig4_sticky.toml",
            &[("saliva.0.k_glue", k(kg))],
        )?);
    }
    let k_chosen = sticky.problem.physics.saliva[0].params.k_glue;

    let mut written = Vec::new();
    let (w, h) = (640u32, 400u32);

    // ---- Fig. 2: materials
    let zero = vec![[0.0; 3]; sticky.problem.mesh.nodes.len()];
    let fig2 = render(&sticky.problem, &zero, &material_colours, WHITE, 900, 560);
    let legend = Image::legend(
        &[
            ("soft tissue, upper face", BLUE),
            ("soft tissue, lower face", RED),
            ("saliva layer", GREEN),
        ],
        18.0,
        WHITE,
    );
    save(
        out,
        "fig2_materials.png",
        &Image::grid(&[fig2, legend], 2, 10, WHITE),
        &mut written,
    )?;

    // ---- Fig. 4: rows 0.04 s apart, without stickiness left, with right
    let t_dry = dry.first_opening().map(|o| o.0).unwrap_or(0.0);
    let t_sticky = sticky
        .first_opening()
        .map(|o| o.0)
        .unwrap_or(dry.times().last().copied().unwrap_or(0.0));
    // rows 0.04 s apart from just before the dry lips part to just after the sticky ones have
    // unzipped (at most 10 rows: the start moves later if needed)
    let t_end_run = dry.times().last().copied().unwrap_or(0.0);
    let t_last = (t_sticky + 0.12).min(t_end_run);
    let t0 = (((t_dry - 0.04).max(0.0)).max(t_last - 9.0 * 0.04) / 0.01).round() * 0.01;
    let mut rows = Vec::new();
    let mut t = t0;
    while rows.len() < 10 && t <= t_last + 1e-9 {
        rows.push(t);
        t += 0.04;
    }
    let mut panels = Vec::new();
    let mut row_titles = Vec::new();
    for &t in &rows {
        for run in [&dry, &sticky] {
            let f = run.frame_at(t);
            panels.push(run.picture(f, 420, 260)?);
        }
        row_titles.push(format!("t = {t:.2} s"));
    }
    let rt: Vec<&str> = row_titles.iter().map(|s| s.as_str()).collect();
    let labels = GridLabels {
        title: Some("Fig. 4: the jaw opens; rows 0.04 s apart"),
        column_titles: &["without stickiness", "with stickiness"],
        row_titles: &rt,
        ..Default::default()
    };
    save(
        out,
        "fig4_opening_over_time.png",
        &Image::grid_labelled(&panels, 2, 8, WHITE, &labels),
        &mut written,
    )?;

    // ---- Fig. 1: sticky lips while opening (shortly after the first opening)
    // the partly open frame closest to half open: lips apart in the middle, joined towards the corners
    let f1 = (0..sticky.frames().len())
        .min_by(|&a, &b| {
            let d = |f: usize| {
                (sticky.frames()[f]["open_fraction"].as_f64().unwrap_or(0.0) - 0.5).abs()
            };
            d(a).total_cmp(&d(b))
        })
        .unwrap_or(0);
    let fig1 = sticky.picture(f1, 900, 560)?;
    save(out, "fig1_sticky_opening.png", &fig1, &mut written)?;

    // ---- Figs. 5-7: slight opening at equilibrium: blend shapes, without, with stickiness
    let b_wide = dry.displacement(dry.last())?;
    let angle = |r: &Run| {
        r.problem
            .bc
            .rotations
            .first()
            .map(|r| r.angle)
            .unwrap_or(0.0)
    };
    let w_blend = angle(&small_dry) / angle(&dry);
    let blend = sticky_lips::blend::blend(&small_dry.problem.mesh.nodes, &[(w_blend, &b_wide)]);
    let u_blend: Vec<[f64; 3]> = blend
        .iter()
        .zip(&small_dry.problem.mesh.nodes)
        .map(|(a, b)| [a[0] - b[0], a[1] - b[1], a[2] - b[2]])
        .collect();
    let cols = small_dry
        .problem
        .physics
        .lip_columns
        .clone()
        .expect("mouth model");
    let gap_blend = sticky_lips::measures::lip_gap(&small_dry.problem.mesh.nodes, &u_blend, &cols);
    // the blend has no saliva state: like the dry run, its saliva strip holds nothing
    let all_saliva: Vec<bool> = element_codes(&small_dry.problem)
        .iter()
        .map(|&c| c == 2)
        .collect();
    let fig6 = render_hiding(
        &small_dry.problem,
        &u_blend,
        &all_saliva,
        &skin_colours,
        CAVITY,
        w,
        h,
    );
    save(out, "fig6_blend_baseline.png", &fig6, &mut written)?;
    let fig6b = fig6.clone();
    let p_dry = small_dry.picture(small_dry.last(), w, h)?;
    let p_sticky = small_sticky.picture(small_sticky.last(), w, h)?;
    let labels = GridLabels {
        title: Some("Figs. 5-7: a slight opening at equilibrium"),
        column_titles: &[
            "blend shapes (Fig. 6)",
            "without stickiness",
            "with stickiness (Fig. 7)",
        ],
        ..Default::default()
    };
    save(
        out,
        "fig7_slight_opening.png",
        &Image::grid_labelled(&[fig6b, p_dry, p_sticky], 3, 8, WHITE, &labels),
        &mut written,
    )?;
    let xs: Vec<f64> = cols.x.iter().map(|x| ms(*x)).collect();
    let prof = |name: &str, g: &[f64], c: [u8; 3]| {
        Series::new(name, xs.iter().zip(g).map(|(x, g)| (*x, ms(*g))).collect()).colour(c)
    };
    let mut spec = PlotSpec::new(
        "Figs. 5-7: lip gap at a slight opening (equilibrium)",
        "position across the mouth (mm)",
        "lip gap (mm)",
    );
    spec.series = vec![
        prof("blend shapes", &gap_blend, [120, 120, 120]).dashed(),
        prof("without stickiness", &small_dry.gaps(small_dry.last()), RED),
        prof(
            "with stickiness",
            &small_sticky.gaps(small_sticky.last()),
            GREEN,
        ),
    ];
    save(
        out,
        "fig7_gap_profiles.png",
        &line_plot(&spec),
        &mut written,
    )?;

    // ---- Fig. 8: wide opening, both at equilibrium
    let q_dry = dry.picture(dry.last(), w, h)?;
    let q_sticky = sticky.picture(sticky.last(), w, h)?;
    let labels = GridLabels {
        title: Some("Fig. 8: a wide opening at equilibrium"),
        column_titles: &["without stickiness", "with stickiness"],
        ..Default::default()
    };
    save(
        out,
        "fig8_wide_opening.png",
        &Image::grid_labelled(&[q_dry, q_sticky], 2, 8, WHITE, &labels),
        &mut written,
    )?;
    let mut spec = PlotSpec::new(
        "Fig. 8: lip gap at a wide opening (equilibrium)",
        "position across the mouth (mm)",
        "lip gap (mm)",
    );
    spec.series = vec![
        prof("without stickiness", &dry.gaps(dry.last()), RED),
        prof("with stickiness", &sticky.gaps(sticky.last()), GREEN).dashed(),
    ];
    save(
        out,
        "fig8_gap_profiles.png",
        &line_plot(&spec),
        &mut written,
    )?;

    // ---- Fig. 9: moisture bands (saliva coloured by moisture: wet blue, gluing green)
    let moisture_code = {
        let p = &bands.problem;
        let disc = sticky_lips::tled::precompute::Discretisation::new(p);
        let mut wet = vec![false; p.mesh.elements.len()];
        let mc = p.physics.saliva[0].params.critical_moisture;
        for (k, &e) in disc.saliva.elements.iter().enumerate() {
            wet[e as usize] = disc.saliva.initial_moisture[k] > mc;
        }
        wet
    };
    let codes = element_codes(&bands.problem);
    let u9 = bands.displacement(bands.last())?;
    let x9: Vec<[f64; 3]> = bands
        .problem
        .mesh
        .nodes
        .iter()
        .zip(&u9)
        .map(|(a, b)| [a[0] + b[0], a[1] + b[1], a[2] + b[2]])
        .collect();
    let faces = visible_faces(&bands.problem, &bands.broken(bands.last())?);
    let mut o = RenderOptions::new(900, 560);
    o.background = CAVITY;
    let cam = mouth_camera(&bands.problem, 900.0 / 560.0);
    let colour9 = |f: &sticky_lips::render::BoundaryFace| {
        let e = f.element as usize;
        match (codes[e], moisture_code[e]) {
            (2, true) => [80, 120, 220],
            (2, false) => GREEN,
            _ => SKIN,
        }
    };
    let fig9 = render_mesh_with(&x9, &faces, &colour9, None, &cam, &o);
    let legend = Image::legend(
        &[
            ("saliva wetter than critical (no glue)", [80, 120, 220]),
            ("saliva at critical moisture (glue)", GREEN),
        ],
        18.0,
        WHITE,
    );
    save(
        out,
        "fig9_moisture_bands.png",
        &Image::grid(&[fig9, legend], 1, 8, WHITE),
        &mut written,
    )?;

    // ---- Fig. 10: asymmetric opening
    let fig10 = asym.picture(asym.last(), 900, 560)?;
    save(out, "fig10_asymmetric.png", &fig10, &mut written)?;

    // ---- Fig. 11: texture-mapped
    let mp: mouth::MouthParams = {
        let text = std::fs::read_to_string(opts.scenarios.join("fig4_sticky.toml"))
            .map_err(|e| Error::io(opts.scenarios.join("fig4_sticky.toml"), e))?;
        let v: toml::Table = toml::from_str(&text)
            .map_err(|e| Error::input("fig4_sticky.toml", Location::None, e.message()))?;
        let mut mp: mouth::MouthParams = v
            .get("mesh")
            .and_then(|m| m.get("mouth"))
            .map(|m| m.clone().try_into())
            .transpose()
            .map_err(|e: toml::de::Error| {
                Error::input("fig4_sticky.toml", Location::None, e.message())
            })?
            .unwrap_or_default();
        if opts.quick {
            mp.resolution = 0.25;
        }
        mp
    };
    let model = mouth::generate(&mp)?;
    let uv_surface = model.surface.uv.clone().unwrap_or_default();
    let nn = sticky.problem.mesh.nodes.len();
    let uv: Vec<[f64; 2]> = (0..nn)
        .map(|n| {
            let s = if (n as u32) < model.inner_offset {
                n
            } else {
                n - model.inner_offset as usize
            };
            uv_surface.get(s).copied().unwrap_or([0.0, 0.0])
        })
        .collect();
    let tex = face_texture(&mp);
    let f11 = sticky.frame_at(t_sticky + 0.04);
    let u11 = sticky.displacement(f11)?;
    let x11: Vec<[f64; 3]> = sticky
        .problem
        .mesh
        .nodes
        .iter()
        .zip(&u11)
        .map(|(a, b)| [a[0] + b[0], a[1] + b[1], a[2] + b[2]])
        .collect();
    let faces = visible_faces(&sticky.problem, &sticky.broken(f11)?);
    let mut o = RenderOptions::new(900, 560);
    o.background = CAVITY;
    let cam = mouth_camera(&sticky.problem, 900.0 / 560.0);
    let fig11 = render_mesh_with(&x11, &faces, &|_| SKIN, Some((&uv, &tex)), &cam, &o);
    save(out, "fig11_textured.png", &fig11, &mut written)?;

    // ---- plots of the measures
    let mut spec = PlotSpec::new(
        "Open fraction of the mouth width",
        "time (s)",
        "open fraction",
    );
    spec.series = vec![
        Series::new("without stickiness", dry.series("open_fraction")).colour(RED),
        Series::new(
            format!("with stickiness (K_glue = {k_chosen})"),
            sticky.series("open_fraction"),
        )
        .colour(GREEN),
        Series::new("asymmetric muscles (Fig. 10)", asym.series("open_fraction"))
            .colour([120, 80, 170])
            .dashed(),
    ];
    save(
        out,
        "plot_open_fraction.png",
        &line_plot(&spec),
        &mut written,
    )?;
    let mut spec = PlotSpec::new("Broken saliva elements", "time (s)", "broken elements");
    spec.series = vec![
        Series::new("without stickiness", dry.series("broken")).colour(RED),
        Series::new(
            format!("with stickiness (K_glue = {k_chosen})"),
            sticky.series("broken"),
        )
        .colour(GREEN),
    ];
    save(out, "plot_broken.png", &line_plot(&spec), &mut written)?;
    for (run, title, file) in [
        (
            &dry,
            "Lip gap along the mouth over time, without stickiness",
            "plot_gap_profiles_dry.png",
        ),
        (
            &sticky,
            "Lip gap along the mouth over time, with stickiness",
            "plot_gap_profiles_sticky.png",
        ),
    ] {
        let mut spec = ProfileSpec::new(
            title,
            "position across the mouth (mm)",
            "lip gap (mm)",
            "time (s)",
        );
        spec.x = run.columns_x().iter().map(|x| ms(*x)).collect();
        spec.profiles = (0..run.frames().len())
            .step_by(2)
            .map(|f| (run.times()[f], run.gaps(f).iter().map(|g| ms(*g)).collect()))
            .collect();
        save(out, file, &profile_plot(&spec), &mut written)?;
    }
    let mut spec = PlotSpec::new(
        "Degrees of stickiness: K_glue sweep",
        "time (s)",
        "open fraction",
    );
    spec.series.push(
        Series::new(
            "K_glue = 0 (without stickiness)",
            dry.series("open_fraction"),
        )
        .colour(RED),
    );
    let palette = [
        [230, 150, 40],
        [60, 170, 80],
        [40, 120, 200],
        [120, 60, 160],
    ];
    let mut all: Vec<(f64, &Run)> = sweep
        .iter()
        .map(|r| (r.problem.physics.saliva[0].params.k_glue, r))
        .collect();
    all.push((k_chosen, &sticky));
    all.sort_by(|a, b| a.0.total_cmp(&b.0));
    for (i, (kg, r)) in all.iter().enumerate() {
        spec.series.push(
            Series::new(format!("K_glue = {kg}"), r.series("open_fraction"))
                .colour(palette[i % palette.len()]),
        );
    }
    save(out, "plot_kglue_sweep.png", &line_plot(&spec), &mut written)?;
    let mut spec = PlotSpec::new(
        "Left/right asymmetry of the lip gap",
        "time (s)",
        "(mean gap subject's left - right) / mean gap",
    );
    spec.series = vec![
        Series::new(
            "symmetric opening (Fig. 4, with stickiness)",
            sticky.series("asymmetry"),
        )
        .colour(GREEN),
        Series::new("left depressors active (Fig. 10)", asym.series("asymmetry"))
            .colour([120, 80, 170]),
    ];
    save(out, "plot_asymmetry.png", &line_plot(&spec), &mut written)?;

    // ---- Table 1 as used, and the measured numbers
    let p = &sticky.problem;
    let tissue = &p.materials[0];
    let saliva = &p.materials[1];
    let sp = &p.physics.saliva[0].params;
    let table = format!(
        "# Table 1 as used\n\nFrom `paper/scenarios/fig4_sticky.toml`{}.\n\n| property | value |\n|---|---|\n\
         | time step | {} s |\n| total time simulated | {} s |\n| hourglass coefficient | {} |\n| damping coefficient | {} 1/s |\n\
         | soft tissue | neo-Hookean, mu = {} Pa, K = {} Pa, rho = {} kg/m^3 |\n| saliva | neo-Hookean breaking, mu = {} Pa, K = {} Pa, rho = {} kg/m^3 |\n\
         | initial moisture 0M | {:?} um |\n| critical moisture Mc | {} um |\n| evaporation rate | {:?} um/s |\n| max glue strength K_glue | {} (chosen: paper/README.md) |\n\
         | mesh | {} hexahedra, {} nodes |\n",
        if opts.quick { " with the --quick overrides (coarse mouth, shorter run)" } else { "" },
        p.time.dt,
        p.time.total_time,
        p.numerics.hourglass_kappa,
        p.numerics.damping,
        tissue.law.mu,
        tissue.law.bulk,
        tissue.density,
        saliva.law.mu,
        saliva.law.bulk,
        saliva.density,
        sp.initial_moisture,
        sp.critical_moisture,
        sp.evaporation.rates,
        sp.k_glue,
        p.mesh.elements.len(),
        p.mesh.nodes.len()
    );
    let tpath = out.join("table1.md");
    sticky_lips::io::atomic::write_atomic(&tpath, table.as_bytes())
        .map_err(|e| Error::io(&tpath, e))?;

    let runs = [&dry, &sticky, &small_dry, &small_sticky, &bands, &asym];
    let summary: Vec<Value> = runs
        .iter()
        .copied()
        .chain(sweep.iter())
        .map(|r| {
            let last = r.last();
            serde_json::json!({
                "run": r.name,
                "hexahedra": r.problem.mesh.elements.len(),
                "steps": r.summary["steps"],
                "wall_time_s": r.wall,
                "k_glue": r.problem.physics.saliva.first().map(|s| s.params.k_glue),
                "first_opening_time_s": r.first_opening().map(|o| o.0),
                "first_opening_x_m": r.first_opening().map(|o| o.1),
                "final_open_fraction": r.frames()[last]["open_fraction"],
                "final_broken": r.frames()[last]["broken"],
                "saliva_elements": r.summary["saliva_elements"],
                "final_max_gap_m": r.gaps(last).iter().copied().fold(f64::NEG_INFINITY, f64::max),
                "final_asymmetry": r.frames()[last]["asymmetry"],
            })
        })
        .collect();
    let m = serde_json::json!({
        "quick": opts.quick,
        "reused_runs": opts.reuse,
        "wall_time_s": t_all.elapsed().as_secs_f64(),
        "threads": opts.threads,
        "figures": written,
        "blend_weight_fig6": w_blend,
        "blend_max_gap_m": gap_blend.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        "blend_open_fraction": sticky_lips::measures::open_fraction(&cols, &gap_blend, sticky_lips::measures::OPEN_THRESHOLD),
        "runs": summary,
    });
    let mpath = out.join("measured.json");
    sticky_lips::io::atomic::write_atomic(
        &mpath,
        serde_json::to_string_pretty(&m).expect("json").as_bytes(),
    )
    .map_err(|e| Error::io(&mpath, e))?;
    eprintln!(
        "paper: {} figures, table1.md and measured.json written to {} in {:.1} s",
        written.len(),
        out.display(),
        t_all.elapsed().as_secs_f64()
    );
    Ok(())
}
