//! How the figures look: the camera on the mouth, the colours, the skin texture made from
//! the CC0 masks, and a rendering of a run's frame (the saliva drawn as a membrane between
//! the lips that is absent where its elements have broken, the mouth interior dark behind
//! the lips).
//!
//! What a rendering draws ([`render`]):
//!
//! - the tissue (every element but the saliva ones): its boundary at the displaced node
//!   positions, the lips' inner surfaces included (where the saliva holds them they lie
//!   inside the saliva layer and are hidden behind it);
//! - the saliva layer as a membrane ([`Membrane`]): the saliva elements' faces on the
//!   model's boundary (the row's front and back; a row's end only where it is the model's
//!   edge), never the walls between two saliva elements. Each rung of the row (the element edge across the layer, from a node on
//!   one lip to its partner on the other) is drawn at the fraction of the saliva elements
//!   sharing it that are intact, shrunk about its midpoint: 1 between two intact elements,
//!   1/2 where an intact element meets a broken one (the zip front), 0 between two broken
//!   ones. Between rungs the membrane is interpolated linearly, like a nodal field of the
//!   finite element model: the last intact element tapers from full to half height, the
//!   first broken one shows a sliver from half height to nothing (so the picture spreads
//!   the element-wise state over one element each side of the front, symmetrically). The
//!   zip front so reads as a taper whose half height sits exactly at the element boundary
//!   where the simulation has it, instead of a vertical step (the end of the last intact
//!   hexahedron and its side wall, which the renderings before showed at each element
//!   boundary of the opening). Nothing of the simulation is changed: node positions are the
//!   run's, the broken flags are the run's (`saliva_broken`);
//! - shading: smooth, from corner normals (faces within [`SMOOTH_DEGREES`] averaged, a
//!   hard crease beyond, which keeps the slab's rim sharp), but with a soft crease
//!   ([`soft_crease`], up to [`SHARP_DEGREES`]) across the edges of a lip's inner surface:
//!   the fold between a lip's front and its inner surface (35 to 115 degrees over the
//!   frames drawn for Figs. 4 and 9 from the quick runs) is then shaded alike in every column instead of smooth in
//!   some and sharp in others (the hard 60-degree crease drew notches along the lips,
//!   column by column);
//! - colours per pixel: a texture through the mesh's per-node texture coordinates
//!   (bilinear), or per-node colours interpolated (the saliva's in Fig. 9); a colour per
//!   element only where the colour is a category (Fig. 2's material groups, the previews).

use crate::element::hex8::FACES as HEX_FACES;
use crate::measures::LipColumns;
use crate::mesh::Mesh;
use crate::render::raster::{Camera, Projection, RenderOptions};
use crate::render::{
    boundary_quads_where, corner_normals_weighted, paint_triangles, rasterize, soft_crease,
    BoundaryFace, FacePaint, Image,
};
use crate::Problem;
use std::collections::HashMap;

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

/// What colours a rendering.
pub enum Paint<'a> {
    /// A colour per element, flat over its faces (for categories: material groups).
    Elements(&'a dyn Fn(u32) -> [u8; 3]),
    /// The texture through the mesh's per-node texture coordinates, sampled per pixel, on
    /// the tissue and the saliva membrane.
    Texture(&'a Image),
    /// The texture on the tissue; on the saliva membrane a colour per saliva element
    /// (`saliva(element)`), averaged at each rung over the elements sharing it and
    /// interpolated per pixel (Fig. 9's moisture: a band's edge blends over one element).
    TextureAndSaliva(&'a Image, &'a dyn Fn(u32) -> [u8; 3]),
}

/// Faces whose normals are within this angle are averaged fully for the shading; beyond
/// it they stay sharp (a hard crease), except at a lip's inner surface.
pub const SMOOTH_DEGREES: f64 = 60.0;
/// Across the edges of a lip's inner surface (the faces the tissue shares with the saliva
/// elements) the crease is soft: the neighbour's weight falls smoothly from 1 at
/// [`SMOOTH_DEGREES`] to 0 at this angle ([`soft_crease`]).
pub const SHARP_DEGREES: f64 = 120.0;

/// The saliva layer drawn as a membrane between the lips (see the module's description):
/// one membrane node at each end of each rung of the saliva row, numbered after the
/// mesh's nodes.
pub struct Membrane {
    /// Per membrane node: its rung's node at this end and its partner at the other end.
    pub ends: Vec<(u32, u32)>,
    /// Per membrane node: the saliva elements sharing its rung (ascending).
    pub elements: Vec<Vec<u32>>,
    /// The membrane's quads: the saliva elements' boundary faces with their corners
    /// replaced by membrane nodes (`mesh nodes + index`); `element` is the saliva element.
    pub faces: Vec<BoundaryFace>,
}

/// Corner partners across each pair of opposite hexahedron faces
/// ([`crate::element::hex8::FACES`] 0-1, 2-4, 3-5).
const AXES: [((usize, usize), [usize; 8]); 3] = [
    ((0, 1), [4, 5, 6, 7, 0, 1, 2, 3]),
    ((2, 4), [3, 2, 1, 0, 7, 6, 5, 4]),
    ((3, 5), [1, 0, 3, 2, 5, 4, 7, 6]),
];

impl Membrane {
    /// The membrane of the elements flagged `saliva`. An element's axis across the layer
    /// (its rungs) joins the pair of opposite faces that both touch tissue (the two lips;
    /// at the row's ends a side face touches tissue too, but not its opposite); where no
    /// or several pairs qualify, the pair nearest each other in the reference
    /// configuration (the layer is thin across).
    pub fn new(mesh: &Mesh, saliva: &[bool]) -> Membrane {
        let els = &mesh.elements;
        let key = |e: &[u32; 8], f: usize| {
            let mut k: [u32; 4] = std::array::from_fn(|i| e[HEX_FACES[f][i]]);
            k.sort_unstable();
            k
        };
        // elements at each face
        let mut owners: HashMap<[u32; 4], Vec<u32>> = HashMap::new();
        for (e, el) in els.iter().enumerate() {
            for f in 0..6 {
                owners.entry(key(el, f)).or_default().push(e as u32);
            }
        }
        let touches_tissue = |el: &[u32; 8], f: usize| {
            owners[&key(el, f)]
                .iter()
                .any(|&o| !saliva.get(o as usize).copied().unwrap_or(false))
        };
        let x0 = &mesh.nodes;
        let centroid = |el: &[u32; 8], f: usize| {
            let mut c = [0.0; 3];
            for &i in &HEX_FACES[f] {
                for k in 0..3 {
                    c[k] += 0.25 * x0[el[i] as usize][k];
                }
            }
            c
        };
        let dist = |el: &[u32; 8], (a, b): (usize, usize)| {
            let (ca, cb) = (centroid(el, a), centroid(el, b));
            (0..3).map(|k| (ca[k] - cb[k]).powi(2)).sum::<f64>()
        };
        let mut index: HashMap<(u32, u32), u32> = HashMap::new();
        let mut m = Membrane {
            ends: Vec::new(),
            elements: Vec::new(),
            faces: Vec::new(),
        };
        let base = x0.len() as u32;
        for (e, el) in els.iter().enumerate() {
            if !saliva.get(e).copied().unwrap_or(false) {
                continue;
            }
            let both: Vec<usize> = (0..3)
                .filter(|&a| touches_tissue(el, AXES[a].0 .0) && touches_tissue(el, AXES[a].0 .1))
                .collect();
            let pool = if both.len() == 1 { both } else { vec![0, 1, 2] };
            let axis = pool
                .into_iter()
                .min_by(|&a, &b| dist(el, AXES[a].0).total_cmp(&dist(el, AXES[b].0)))
                .unwrap_or(0);
            let partner = AXES[axis].1;
            let mut node = |local: usize, m: &mut Membrane| -> u32 {
                let end = (el[local], el[partner[local]]);
                let i = *index.entry(end).or_insert_with(|| {
                    m.ends.push(end);
                    m.elements.push(Vec::new());
                    (m.ends.len() - 1) as u32
                });
                if m.elements[i as usize].last() != Some(&(e as u32)) {
                    m.elements[i as usize].push(e as u32);
                }
                base + i
            };
            // every end of every rung knows this element
            for local in 0..8 {
                node(local, &mut m);
            }
            for (lf, f) in HEX_FACES.iter().enumerate() {
                // a boundary face that holds rungs (each corner's partner in the face)
                let on_boundary = owners[&key(el, lf)].len() == 1;
                let holds_rungs = f.iter().all(|&c| f.contains(&partner[c]));
                if on_boundary && holds_rungs {
                    let nodes = f.map(|c| node(c, &mut m));
                    m.faces.push(BoundaryFace {
                        nodes,
                        element: e as u32,
                        local_face: lf as u8,
                    });
                }
            }
        }
        m
    }

    /// The fraction of intact (not `hidden`) elements sharing each membrane node's rung.
    pub fn intact(&self, hidden: &[bool]) -> Vec<f64> {
        self.elements
            .iter()
            .map(|es| {
                let ok = es
                    .iter()
                    .filter(|&&e| !hidden.get(e as usize).copied().unwrap_or(false))
                    .count();
                ok as f64 / es.len().max(1) as f64
            })
            .collect()
    }

    /// Appends the membrane nodes' values of a per-node field `v` (positions, texture
    /// coordinates): each rung shrunk about its midpoint by its intact fraction.
    pub fn extend<const N: usize>(&self, v: &[[f64; N]], intact: &[f64]) -> Vec<[f64; N]> {
        let mut out = v.to_vec();
        for (&(a, b), &f) in self.ends.iter().zip(intact) {
            let (a, b) = (v[a as usize], v[b as usize]);
            out.push(std::array::from_fn(|k| {
                let mid = 0.5 * (a[k] + b[k]);
                mid + f * (a[k] - mid)
            }));
        }
        out
    }
}

/// Renders the mesh of `p` displaced by `u`, without the `hidden` elements, on `background`
/// (3x supersampling, [`RenderOptions::new`]).
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
    let supersample = RenderOptions::new(w, h).supersample;
    let quality = Quality {
        supersample,
        cull: false,
    };
    render_with(p, cols, u, hidden, paint, background, w, h, quality)
}

/// How finely [`render_with`] renders.
#[derive(Clone, Copy, Debug)]
pub struct Quality {
    /// `supersample x supersample` samples per pixel.
    pub supersample: u32,
    /// Leave out the tissue's triangles that face away from the camera. The tissue's
    /// boundary is closed and oriented outward, so that these lie behind its front: the
    /// picture is the same but where a sample falls on a silhouette edge to within rounding.
    /// The saliva membrane is two-sided and always drawn.
    pub cull: bool,
}

/// [`render`] with the [`Quality`] given (the run's preview takes less, for its cost).
#[allow(clippy::too_many_arguments)]
pub fn render_with(
    p: &Problem,
    cols: &LipColumns,
    u: &[[f64; 3]],
    hidden: &[bool],
    paint: Paint,
    background: [u8; 3],
    w: u32,
    h: u32,
    quality: Quality,
) -> Image {
    let x: Vec<[f64; 3]> = p
        .mesh
        .nodes
        .iter()
        .zip(u)
        .map(|(a, b)| [a[0] + b[0], a[1] + b[1], a[2] + b[2]])
        .collect();
    let codes = element_codes(p);
    let saliva: Vec<bool> = codes.iter().map(|&c| c == 2).collect();
    let is_hidden = |e: u32| hidden.get(e as usize).copied().unwrap_or(false);
    let mut faces =
        boundary_quads_where(&p.mesh.elements, |e| !saliva[e as usize] && !is_hidden(e));
    let membrane = Membrane::new(&p.mesh, &saliva);
    let intact = membrane.intact(hidden);
    faces.extend(membrane.faces.iter().copied());
    let x = membrane.extend(&x, &intact);
    let uv = p.mesh.uv.as_ref().map(|uv| membrane.extend(uv, &intact));
    // the lips' inner surfaces: tissue faces that a saliva element shares
    let mut saliva_faces = std::collections::HashSet::new();
    for (e, el) in p.mesh.elements.iter().enumerate() {
        if saliva[e] {
            for f in &HEX_FACES {
                let mut k: [u32; 4] = std::array::from_fn(|i| el[f[i]]);
                k.sort_unstable();
                saliva_faces.insert(k);
            }
        }
    }
    let inner: Vec<bool> = faces
        .iter()
        .map(|f| {
            let mut k = f.nodes;
            k.sort_unstable();
            !saliva[f.element as usize] && saliva_faces.contains(&k)
        })
        .collect();
    let normals = corner_normals_weighted(&x, &faces, &|a, b, cos| {
        let sharp = if inner[a] || inner[b] {
            SHARP_DEGREES
        } else {
            SMOOTH_DEGREES
        };
        soft_crease(cos, SMOOTH_DEGREES, sharp)
    });
    // per membrane node, the mean of the saliva colours of the elements at its rung
    let rung_colour = |c: &dyn Fn(u32) -> [u8; 3], i: usize| -> [u8; 3] {
        let es = &membrane.elements[i];
        let mut s = [0.0; 3];
        for &e in es {
            let ce = c(e);
            for k in 0..3 {
                s[k] += ce[k] as f64 / es.len().max(1) as f64;
            }
        }
        s.map(|v| v.round().clamp(0.0, 255.0) as u8)
    };
    let n_mesh = p.mesh.nodes.len();
    let saliva_colours: Option<Vec<[u8; 3]>> = match &paint {
        Paint::TextureAndSaliva(_, c) => Some(
            (0..membrane.ends.len())
                .map(|i| rung_colour(*c, i))
                .collect(),
        ),
        _ => None,
    };
    let face_paint = |f: &BoundaryFace| -> FacePaint {
        match &paint {
            Paint::Elements(c) => FacePaint::Colour(c(f.element)),
            Paint::Texture(_) => FacePaint::Texture(SKIN),
            Paint::TextureAndSaliva(_, _) => match &saliva_colours {
                Some(sc) if saliva[f.element as usize] => FacePaint::Corners(
                    f.nodes
                        .map(|n| sc[(n as usize).saturating_sub(n_mesh).min(sc.len() - 1)]),
                ),
                _ => FacePaint::Texture(SKIN),
            },
        }
    };
    let texture = match &paint {
        Paint::Elements(_) => None,
        Paint::Texture(t) | Paint::TextureAndSaliva(t, _) => Some(*t),
    };
    let mut tris = paint_triangles(&x, &faces, &normals, &face_paint, uv.as_deref());
    let cam = mouth_camera(p, cols, w as f64 / h as f64);
    if quality.cull {
        // two triangles a face, the tissue's faces first
        let tissue = 2 * (faces.len() - membrane.faces.len());
        let mut k = 0;
        tris.retain(|t| {
            k += 1;
            let [a, b, c] = t.positions;
            let d = |p: [f64; 3], q: [f64; 3]| [0, 1, 2].map(|i| p[i] - q[i]);
            let (e1, e2, v) = (d(b, a), d(c, a), d(cam.eye, a));
            let n = [
                e1[1] * e2[2] - e1[2] * e2[1],
                e1[2] * e2[0] - e1[0] * e2[2],
                e1[0] * e2[1] - e1[1] * e2[0],
            ];
            k > tissue || n[0] * v[0] + n[1] * v[1] + n[2] * v[2] >= 0.0
        });
    }
    let mut o = RenderOptions::new(w, h);
    o.background = background;
    o.supersample = quality.supersample;
    rasterize(&tris, texture, &cam, &o)
}

/// The material groups at rest (Fig. 2's picture): upper face blue, lower face red, saliva
/// green.
pub fn groups_picture(p: &Problem, cols: &LipColumns, w: u32, h: u32) -> Image {
    let codes = element_codes(p);
    let colour = |e: u32| [BLUE, RED, GREEN][codes[e as usize] as usize];
    let zero = vec![[0.0; 3]; p.mesh.nodes.len()];
    render(p, cols, &zero, &[], Paint::Elements(&colour), WHITE, w, h)
}

/// The saliva's colour where the figures show it without a texture (the procedural mouth).
pub const SALIVA: [u8; 3] = [150, 70, 78];

/// Skin and lips from the CC0 lips mask alone, at the mask's resolution: lip colour where
/// the mask is white, skin where it is black, blended between (Fig. 9's tissue, sampled per
/// pixel through the mesh's texture coordinates).
pub fn lips_texture(mask: &Image) -> Image {
    let mut img = Image::new(mask.width, mask.height, SKIN);
    for j in 0..mask.height {
        for i in 0..mask.width {
            let t = mask.get(i, j)[0] as f64 / 255.0;
            img.set(i as i64, j as i64, mix(SKIN, LIP, t));
        }
    }
    img
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

/// The MakeHuman head's CC0 masks compiled into the binary (MPFB's face and lips masks,
/// greyscale in the body's UV layout), decoded: `(face, lips)`, `None` where one does not
/// decode.
pub fn makehuman_masks() -> (Option<Image>, Option<Image>) {
    let decode = |bytes: &[u8]| crate::render::decode_jpeg(bytes).ok();
    (
        decode(crate::mesh::face::MAKEHUMAN_FACE_TEXTURE),
        decode(crate::mesh::face::MAKEHUMAN_LIPS_TEXTURE),
    )
}

/// The face's skin texture, as the figures of the face and the previews of its runs use it:
/// [`skin_texture`] of the masks, 1024 pixels square.
pub fn face_skin(face: &Image, lips: &Image) -> Image {
    skin_texture(face, lips, 1024)
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
    let params = crate::mesh::mouth::MouthParams::default();
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_membrane_tapers_to_half_height_at_a_broken_element_and_has_no_inner_walls() {
        // 3 x 3 x 1 cells: the middle row (elements 3, 4, 5) is the saliva between the two
        // lips (rows 0 and 2); element 4 has broken.
        let mesh = crate::mesh::generate::block([0.0; 3], [3.0, 3.0, 1.0], [3, 3, 1]);
        let saliva: Vec<bool> = (0..9).map(|e| (3..6).contains(&e)).collect();
        let m = Membrane::new(&mesh, &saliva);
        // the front and back faces of the three elements (local faces 0 and 1) and the
        // row's two ends (on the model's edge here), no wall between saliva elements; the
        // rungs run across the layer (along y)
        assert_eq!(m.faces.len(), 8);
        assert!(m.faces.iter().all(|f| saliva[f.element as usize]));
        assert_eq!(m.faces.iter().filter(|f| f.local_face <= 1).count(), 6);
        for f in m.faces.iter().filter(|f| f.local_face > 1) {
            let xs = f.nodes.map(|n| {
                let (a, _) = m.ends[n as usize - mesh.nodes.len()];
                mesh.nodes[a as usize][0]
            });
            assert!(
                xs.iter().all(|&x| x == 0.0) || xs.iter().all(|&x| x == 3.0),
                "{xs:?}"
            );
        }
        for &(a, b) in &m.ends {
            let (pa, pb) = (mesh.nodes[a as usize], mesh.nodes[b as usize]);
            assert_eq!((pa[0], pa[2]), (pb[0], pb[2]));
            assert_eq!((pa[1] - pb[1]).abs(), 1.0);
        }
        let hidden: Vec<bool> = (0..9).map(|e| e == 4).collect();
        let intact = m.intact(&hidden);
        let x = m.extend(&mesh.nodes, &intact);
        assert_eq!(x.len(), mesh.nodes.len() + m.ends.len());
        for (i, &(a, _)) in m.ends.iter().enumerate() {
            let p = mesh.nodes[a as usize];
            // rungs at x = 0 and 3: one intact element; at x = 1 and 2: an intact and the
            // broken one
            let want = if p[0] == 0.0 || p[0] == 3.0 { 1.0 } else { 0.5 };
            assert_eq!(intact[i], want, "rung at {p:?}");
            // shrunk about the rung's midpoint (y = 1.5)
            let y = x[mesh.nodes.len() + i][1];
            assert!(
                (y - (1.5 + want * (p[1] - 1.5))).abs() < 1e-12,
                "{y} at {p:?}"
            );
        }
        // nothing broken: the membrane is the saliva's faces exactly
        let full = m.extend(&mesh.nodes, &m.intact(&[]));
        for (i, &(a, _)) in m.ends.iter().enumerate() {
            assert_eq!(full[mesh.nodes.len() + i], mesh.nodes[a as usize]);
        }
    }
}
