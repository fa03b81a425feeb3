//! How the figures look: the camera on the mouth, the colours, the skin texture made from
//! the CC0 masks, and a rendering of a run's frame (broken saliva elements hidden, the mouth
//! interior dark behind the lips).

use super::runs::Run;
use sticky_lips::error::Result;
use sticky_lips::measures::LipColumns;
use sticky_lips::render::raster::{Camera, Projection, RenderOptions};
use sticky_lips::render::{boundary_quads, render_mesh_with, BoundaryFace, Image};
use sticky_lips::Problem;

/// Fig. 2's colours: soft tissue of the upper face (blue), lower face (red), saliva (green).
pub const BLUE: [u8; 3] = [70, 105, 190];
pub const RED: [u8; 3] = [195, 70, 65];
pub const GREEN: [u8; 3] = [60, 170, 80];
/// Skin, lips and the dark mouth interior behind the lips.
pub const SKIN: [u8; 3] = [224, 176, 148];
pub const LIP: [u8; 3] = [178, 92, 96];
pub const CAVITY: [u8; 3] = [26, 16, 20];
pub const WHITE: [u8; 3] = [255, 255, 255];
/// The wet saliva of Fig. 9 (moisture above critical: no glue).
pub const WET_BLUE: [u8; 3] = [80, 120, 220];

/// Per-element colour code: 0 upper face, 1 lower face, 2 saliva.
pub fn element_codes(p: &Problem) -> Vec<u8> {
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

/// The camera every rendering uses: perspective, from the front, on the mouth region of the
/// reference configuration (1.25 mouth half-widths left and right, from 1.1 below to 0.55
/// above the mouth line), so every frame of every run is seen from the same place.
pub fn mouth_camera(p: &Problem, cols: &LipColumns, aspect: f64) -> Camera {
    let w = 0.5 * (cols.x.last().copied().unwrap_or(0.0) - cols.x.first().copied().unwrap_or(0.0));
    let mid = cols.upper.len() / 2;
    let yc = 0.5
        * (p.mesh.nodes[cols.upper[mid] as usize][1] + p.mesh.nodes[cols.lower[mid] as usize][1]);
    let pts: Vec<[f64; 3]> = p
        .mesh
        .nodes
        .iter()
        .copied()
        .filter(|x| {
            (x[0] - cols.center).abs() < 1.25 * w && x[1] > yc - 1.1 * w && x[1] < yc + 0.55 * w
        })
        .collect();
    Camera::fit(
        &pts,
        [0.0, 0.0, -1.0],
        [0.0, 1.0, 0.0],
        28.0,
        Projection::Perspective,
        aspect,
        0.03,
    )
}

/// The boundary faces of the elements that are drawn: all but the `hidden` ones (broken
/// saliva elements, which no longer join the lips), with `element` indices of the full mesh.
pub fn visible_faces(p: &Problem, hidden: &[bool]) -> Vec<BoundaryFace> {
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

/// What colours a rendering.
pub enum Paint<'a> {
    /// A colour per element.
    Elements(&'a dyn Fn(u32) -> [u8; 3]),
    /// The skin texture through the mesh's texture coordinates.
    Texture(&'a Image),
}

/// Renders the mesh of `p` displaced by `u`, without the `hidden` elements, on `background`.
#[allow(clippy::too_many_arguments)]
pub fn render(
    p: &Problem,
    cols: &LipColumns,
    u: &[[f64; 3]],
    hidden: &[bool],
    paint: Paint,
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
    let cam = mouth_camera(p, cols, w as f64 / h as f64);
    let mut o = RenderOptions::new(w, h);
    o.background = background;
    match paint {
        Paint::Elements(c) => render_mesh_with(&x, &faces, &|f| c(f.element), None, &cam, &o),
        Paint::Texture(t) => match &p.mesh.uv {
            Some(uv) => render_mesh_with(&x, &faces, &|_| SKIN, Some((uv, t)), &cam, &o),
            None => render_mesh_with(&x, &faces, &|_| SKIN, None, &cam, &o),
        },
    }
}

/// The material groups at rest (Fig. 2's picture): upper face blue, lower face red, saliva
/// green.
pub fn groups_picture(p: &Problem, cols: &LipColumns, w: u32, h: u32) -> Image {
    let codes = element_codes(p);
    let colour = |e: u32| [BLUE, RED, GREEN][codes[e as usize] as usize];
    let zero = vec![[0.0; 3]; p.mesh.nodes.len()];
    render(p, cols, &zero, &[], Paint::Elements(&colour), WHITE, w, h)
}

/// The skin's colour per element: lips where the CC0 lips mask is white at the element's
/// texture coordinates (the mean of its skin corners'), skin elsewhere, blended between;
/// the saliva a darker red. Without texture coordinates, lips are the saliva only.
pub fn skin_colours(p: &Problem, lips: Option<&Image>) -> Vec<[u8; 3]> {
    let codes = element_codes(p);
    (0..p.mesh.elements.len())
        .map(|e| {
            if codes[e] == 2 {
                return [150, 70, 78];
            }
            let t = match (&p.mesh.uv, lips) {
                (Some(uv), Some(mask)) => {
                    let el = p.mesh.elements[e];
                    let (mut s, mut t) = (0.0, 0.0);
                    for &n in &el[..4] {
                        s += 0.25 * uv[n as usize][0];
                        t += 0.25 * uv[n as usize][1];
                    }
                    sample(mask, s, t) as f64 / 255.0
                }
                _ => 0.0,
            };
            mix(SKIN, LIP, t)
        })
        .collect()
}

fn mix(a: [u8; 3], b: [u8; 3], t: f64) -> [u8; 3] {
    let t = t.clamp(0.0, 1.0);
    [0, 1, 2].map(|k| (a[k] as f64 * (1.0 - t) + b[k] as f64 * t).round() as u8)
}

/// The red channel of `img` at texture coordinates `(u, v)` (nearest pixel; `v` up).
fn sample(img: &Image, u: f64, v: f64) -> u8 {
    let x = ((u.clamp(0.0, 1.0) * img.width as f64) as u32).min(img.width - 1);
    let y = (((1.0 - v.clamp(0.0, 1.0)) * img.height as f64) as u32).min(img.height - 1);
    img.get(x, y)[0]
}

/// The skin texture of Fig. 11 from the CC0 masks of the MakeHuman head (the body's UV
/// layout): a skin tone with a faint mottling, a rosier tone where the face mask is white,
/// lip colour where the lips mask is white. `size` pixels square.
pub fn skin_texture(face: &Image, lips: &Image, size: u32) -> Image {
    let mut img = Image::new(size, size, SKIN);
    for j in 0..size {
        for i in 0..size {
            let u = (i as f64 + 0.5) / size as f64;
            let v = 1.0 - (j as f64 + 0.5) / size as f64;
            let f = sample(face, u, v) as f64 / 255.0;
            let l = sample(lips, u, v) as f64 / 255.0;
            let mottling =
                5.0 * ((211.0 * u).sin() * (197.0 * v).cos() + (61.0 * u + 53.0 * v).sin());
            let base = [
                SKIN[0] as f64 + mottling,
                SKIN[1] as f64 + 0.75 * mottling - 6.0 * f,
                SKIN[2] as f64 + 0.5 * mottling - 4.0 * f,
            ]
            .map(|x| x.clamp(0.0, 255.0) as u8);
            img.set(i as i64, j as i64, mix(base, LIP, l));
        }
    }
    img
}

/// The procedural mouth's texture for Fig. 11 (its UVs span the patch): skin with a faint mottling, redder lips around
/// the mouth line, a darker line where the lips meet. `u` across the face, `v` up.
pub fn procedural_texture() -> Image {
    let params = sticky_lips::mesh::mouth::MouthParams::default();
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

/// A rendering of output frame `frame` of `run`, broken saliva hidden: through the skin
/// texture where there is one (the face), else skin-coloured elements with the saliva red.
pub fn picture(run: &Run, skin: Option<&Image>, frame: usize, w: u32, h: u32) -> Result<Image> {
    displaced(
        run,
        skin,
        &run.displacement(frame)?,
        &run.broken(frame)?,
        w,
        h,
    )
}

/// [`picture`] for any displacement `u` with the `hidden` elements left out.
pub fn displaced(
    run: &Run,
    skin: Option<&Image>,
    u: &[[f64; 3]],
    hidden: &[bool],
    w: u32,
    h: u32,
) -> Result<Image> {
    let cols = &run.measures.columns;
    Ok(match (skin, &run.problem.mesh.uv) {
        (Some(tex), Some(_)) => render(
            &run.problem,
            cols,
            u,
            hidden,
            Paint::Texture(tex),
            CAVITY,
            w,
            h,
        ),
        _ => {
            let colours = skin_colours(&run.problem, None);
            let paint = |e: u32| colours[e as usize];
            render(
                &run.problem,
                cols,
                u,
                hidden,
                Paint::Elements(&paint),
                CAVITY,
                w,
                h,
            )
        }
    })
}

/// `1e3 x` (m to mm).
pub fn mm(x: f64) -> f64 {
    1e3 * x
}
