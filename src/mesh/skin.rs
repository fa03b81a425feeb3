//! The skin an animation package plays: the vertices of the user's own mesh, moved by the
//! model's outer surface.
//!
//! The model's surface is not the user's mesh (a face model lays its own grid over the skin,
//! [`crate::mesh::face::build`]), so every vertex of the user's mesh is tied to the model by
//! weights computed once, at rest, in the model frame (`x` the subject's left, `y` up, `z`
//! forward, metres):
//!
//! * a vertex over the model's outer surface seen from the front (its `x, y` inside one of
//!   the surface's quads, its depth at most [`SkinParams::behind`] behind and
//!   [`SkinParams::ahead`] in front of the quad's) moves with that quad: the bilinear
//!   interpolation of the quad's four nodes' displacements at the vertex's `(s, t)` (inverse
//!   bilinear map of the quad's projection);
//! * a vertex beside the surface moves with the nearest point of its boundary, faded out over
//!   [`SkinParams::band`]: `u = f u_model + (1 - f) u_jaw` with `f = 1 - smoothstep(d / band)`,
//!   `d` the distance in `x, y` to the nearest quad;
//! * the rest follows the rig's jaw as linear blend skinning would: `u_jaw = w (R(t) (x - p) -
//!   (x - p))`, `w` the vertex's jaw weight, `R(t)` and `p` the jaw rotation the run
//!   prescribes; a vertex without jaw weight stays where it is.
//!
//! The positions are written in the user's units and axes ([`OutputFrame`]), so that the
//! user's mesh plays the point caches unchanged.
//!
//! A mesh of triangles or other polygons ([`Skin::tie_polygons`]) is tied through its quad
//! refinement ([`PolySurface::to_quads`]): the weights are computed on the refined mesh
//! (whose first vertices are the user's) and kept for the user's vertices, and the files
//! carry the user's own faces.

use crate::boundary::PrescribedRotation;
use crate::error::{Error, Result};
use crate::mesh::surface::{PolySurface, QuadSurface};

/// How vertices are tied to the model's surface (SI metres).
#[derive(Clone, Debug, PartialEq)]
pub struct SkinParams {
    /// Vertices up to this far behind the model's outer surface move with it.
    pub behind: f64,
    /// ... and up to this far in front of it.
    pub ahead: f64,
    /// Beside the surface, its motion fades out over this distance (in `x, y`).
    pub band: f64,
}

impl Default for SkinParams {
    fn default() -> Self {
        SkinParams {
            behind: 0.015,
            ahead: 0.005,
            band: 0.010,
        }
    }
}

/// From the model frame (metres) to the user's mesh's units and axes: `p_user = R^T p / scale`,
/// `R`'s rows the model's `x`, `y`, `z` axes in the user's coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OutputFrame {
    /// Metres per unit of the user's mesh.
    pub scale: f64,
    pub rows: [[f64; 3]; 3],
    /// The unit's name (`m`, `mm`, ...), for the files' metadata.
    pub unit: &'static str,
}

impl OutputFrame {
    /// The model frame itself, in metres.
    pub fn metres() -> Self {
        OutputFrame {
            scale: 1.0,
            rows: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            unit: "m",
        }
    }

    /// A point of the model frame in the user's coordinates.
    pub fn to_user(&self, p: [f64; 3]) -> [f64; 3] {
        let r = &self.rows;
        [0, 1, 2].map(|j| (r[0][j] * p[0] + r[1][j] * p[1] + r[2][j] * p[2]) / self.scale)
    }
}

/// How one vertex moves: `f` times the bilinear mix of four model nodes, plus `(1 - f)` times
/// the jaw's motion scaled by `jaw`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SkinWeight {
    pub nodes: [u32; 4],
    pub w: [f64; 4],
    pub f: f64,
    pub jaw: f64,
}

/// The user's mesh, tied to a model.
#[derive(Clone, Debug, PartialEq)]
pub struct Skin {
    /// Where the mesh comes from (for the files' metadata).
    pub name: String,
    /// The mesh at rest in the model frame (metres): vertices in the user's order, its faces.
    pub surface: PolySurface,
    pub weights: Vec<SkinWeight>,
    /// The model's outer surface (model frame, m; vertex `v` is node `v`), for the saliva
    /// layer's faces.
    pub model: QuadSurface,
    pub frame: OutputFrame,
    /// The jaw's prescribed rotation, for the vertices beside the model.
    pub jaw: Option<PrescribedRotation>,
    /// Vertices over the model, beside it (in the band), and elsewhere.
    pub counts: [usize; 3],
}

impl Skin {
    /// Ties `mesh` (model frame, metres; `jaw_weight` per vertex) to the model's outer surface
    /// `model` (its vertex `v` is node `v` of the mesh).
    ///
    /// `front`: the vertices that are the model's skin (the kept face); `None`: all. The
    /// others (the rest of a head, the mouth's interior behind the lip contour, which seen
    /// from the front lies over the other lip) take the weights of the nearest front vertex
    /// along the mesh's edges, faded out over [`SkinParams::band`] of that distance.
    pub fn tie(
        name: &str,
        mesh: QuadSurface,
        jaw_weight: &[f64],
        model: &QuadSurface,
        front: Option<&[bool]>,
        frame: OutputFrame,
        params: &SkinParams,
    ) -> Result<Skin> {
        let poly = PolySurface::from_quads(&mesh);
        let mut skin = Self::tie_quads(name, &mesh, jaw_weight, model, front, frame, params)?;
        skin.surface = poly;
        Ok(skin)
    }

    /// [`Skin::tie`] for a mesh of any polygons: tied through its quad refinement
    /// ([`PolySurface::to_quads`], module docs). `jaw_weight` is per vertex of `mesh`;
    /// `front`, where given, per vertex of the refined mesh (its first vertices are
    /// `mesh`'s). The skin plays `mesh`'s vertices and faces.
    pub fn tie_polygons(
        name: &str,
        mesh: &PolySurface,
        jaw_weight: &[f64],
        model: &QuadSurface,
        front: Option<&[bool]>,
        frame: OutputFrame,
        params: &SkinParams,
    ) -> Result<Skin> {
        if jaw_weight.len() != mesh.vertices.len() {
            return Err(Error::field(
                name,
                "jaw_weight",
                format!(
                    "has {} values for {} vertices",
                    jaw_weight.len(),
                    mesh.vertices.len()
                ),
            ));
        }
        let refined = mesh.to_quads();
        let jaw = refined.extend_scalar(jaw_weight);
        let mut skin = Self::tie_quads(name, &refined.surface, &jaw, model, front, frame, params)?;
        skin.weights.truncate(mesh.vertices.len());
        skin.counts = counts(&skin.weights);
        skin.surface = mesh.clone();
        Ok(skin)
    }

    /// The tie on a quad mesh (the skin's `surface` left empty for the callers to set).
    fn tie_quads(
        name: &str,
        mesh: &QuadSurface,
        jaw_weight: &[f64],
        model: &QuadSurface,
        front: Option<&[bool]>,
        frame: OutputFrame,
        params: &SkinParams,
    ) -> Result<Skin> {
        if front.is_some_and(|f| f.len() != mesh.vertices.len()) {
            return Err(Error::field(
                name,
                "front",
                format!(
                    "has a flag for {} of {} vertices",
                    front.map_or(0, |f| f.len()),
                    mesh.vertices.len()
                ),
            ));
        }
        if jaw_weight.len() != mesh.vertices.len() {
            return Err(Error::field(
                name,
                "jaw_weight",
                format!(
                    "has {} values for {} vertices",
                    jaw_weight.len(),
                    mesh.vertices.len()
                ),
            ));
        }
        let quads: Vec<[[f64; 3]; 4]> = model
            .quads
            .iter()
            .map(|q| q.map(|v| model.vertices[v as usize]))
            .collect();
        let saliva = model.group_index("saliva");
        let is_saliva: Vec<bool> = model
            .group_of_quad
            .iter()
            .map(|&g| Some(g as usize) == saliva)
            .collect();
        let is_front = |v: usize| front.is_none_or(|f| f[v]);
        let grid = QuadGrid::new(&quads, params.band);
        let mut weights: Vec<SkinWeight> = mesh
            .vertices
            .iter()
            .zip(jaw_weight)
            .enumerate()
            .map(|(v, (p, &jaw))| {
                if is_front(v) {
                    tie_vertex(p, &quads, &grid, &model.quads, &is_saliva, params, jaw)
                } else {
                    SkinWeight {
                        nodes: [0; 4],
                        w: [0.0; 4],
                        f: 0.0,
                        jaw,
                    }
                }
            })
            .collect();
        if front.is_some() {
            inherit_along_edges(mesh, &mut weights, &is_front, params.band);
        }
        Ok(Skin {
            name: name.to_string(),
            surface: PolySurface::default(),
            counts: counts(&weights),
            weights,
            model: model.clone(),
            frame,
            jaw: None,
        })
    }

    /// The vertices' positions (user's units and axes) for model displacements `u` (per
    /// node, m) at time `t`.
    pub fn positions(&self, u: &[[f64; 3]], t: f64) -> Vec<[f64; 3]> {
        let r = self.jaw.as_ref().map(|j| j.matrix(t, true));
        self.surface
            .vertices
            .iter()
            .zip(&self.weights)
            .map(|(x, w)| {
                let mut d = [0.0; 3];
                if w.f > 0.0 {
                    for (n, wn) in w.nodes.iter().zip(w.w) {
                        let un = u[*n as usize];
                        for k in 0..3 {
                            d[k] += w.f * wn * un[k];
                        }
                    }
                }
                if let (Some(j), Some(r)) = (&self.jaw, &r) {
                    let g = (1.0 - w.f) * w.jaw;
                    if g > 0.0 {
                        let dj = j.displacement_by(r, x);
                        for k in 0..3 {
                            d[k] += g * dj[k];
                        }
                    }
                }
                self.frame.to_user([x[0] + d[0], x[1] + d[1], x[2] + d[2]])
            })
            .collect()
    }

    /// The largest node index the weights use (a check against the model's node count).
    pub fn max_node(&self) -> Option<u32> {
        self.weights
            .iter()
            .filter(|w| w.f > 0.0)
            .flat_map(|w| w.nodes)
            .max()
    }
}

/// Vertices over the model, beside it, and elsewhere.
fn counts(weights: &[SkinWeight]) -> [usize; 3] {
    let mut counts = [0usize; 3];
    for w in weights {
        counts[if w.f == 1.0 {
            0
        } else if w.f > 0.0 {
            1
        } else {
            2
        }] += 1;
    }
    counts
}

/// Vertices off the front take the model weights of the nearest front vertex that has any
/// (Dijkstra over the mesh's edges, lengths in metres, ties to the smaller vertex index),
/// scaled by `1 - smoothstep(distance / band)`; their own jaw weight stays.
fn inherit_along_edges(
    mesh: &QuadSurface,
    weights: &mut [SkinWeight],
    is_front: &dyn Fn(usize) -> bool,
    band: f64,
) {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;
    let nv = mesh.vertices.len();
    let mut nbrs: Vec<Vec<u32>> = vec![Vec::new(); nv];
    for q in &mesh.quads {
        for i in 0..4 {
            let (a, b) = (q[i] as usize, q[(i + 1) % 4] as usize);
            nbrs[a].push(b as u32);
            nbrs[b].push(a as u32);
        }
    }
    for n in nbrs.iter_mut() {
        n.sort_unstable();
        n.dedup();
    }
    // (distance bits, vertex): non-negative f64s order like their bits
    let mut dist = vec![f64::INFINITY; nv];
    let mut source = vec![usize::MAX; nv];
    let mut heap = BinaryHeap::new();
    for v in 0..nv {
        if is_front(v) && weights[v].f > 0.0 {
            dist[v] = 0.0;
            source[v] = v;
            heap.push(Reverse((0u64, v)));
        }
    }
    while let Some(Reverse((d, v))) = heap.pop() {
        let d = f64::from_bits(d);
        if d > dist[v] || d >= band {
            continue;
        }
        let x = mesh.vertices[v];
        for &n in &nbrs[v] {
            let n = n as usize;
            if is_front(n) {
                continue;
            }
            let y = mesh.vertices[n];
            let nd =
                d + ((x[0] - y[0]).powi(2) + (x[1] - y[1]).powi(2) + (x[2] - y[2]).powi(2)).sqrt();
            if nd < dist[n] || (nd == dist[n] && source[v] < source[n]) {
                dist[n] = nd;
                source[n] = source[v];
                heap.push(Reverse((nd.to_bits(), n)));
            }
        }
    }
    for v in 0..nv {
        if !is_front(v) && source[v] != usize::MAX && dist[v] < band {
            let s = weights[source[v]];
            weights[v] = SkinWeight {
                f: s.f * (1.0 - smoothstep(dist[v] / band)),
                jaw: weights[v].jaw,
                ..s
            };
        }
    }
}

/// Bilinear point of a quad's projection on `x, y` and its inverse by Newton's method:
/// `(s, t)` with `P(s, t) = (x, y)`, `None` when the iteration does not settle.
fn inverse_bilinear(q: &[[f64; 3]; 4], x: f64, y: f64) -> Option<(f64, f64)> {
    let (mut s, mut t) = (0.5, 0.5);
    for _ in 0..30 {
        let p = bilinear(q, s, t);
        let (rx, ry) = (p[0] - x, p[1] - y);
        // dP/ds and dP/dt
        let ds = [0, 1].map(|k| (1.0 - t) * (q[1][k] - q[0][k]) + t * (q[2][k] - q[3][k]));
        let dt = [0, 1].map(|k| (1.0 - s) * (q[3][k] - q[0][k]) + s * (q[2][k] - q[1][k]));
        let det = ds[0] * dt[1] - ds[1] * dt[0];
        if det.abs() < 1e-300 {
            return None;
        }
        let step_s = (rx * dt[1] - ry * dt[0]) / det;
        let step_t = (ds[0] * ry - ds[1] * rx) / det;
        s -= step_s;
        t -= step_t;
        if !(s.is_finite() && t.is_finite()) || s.abs() > 10.0 || t.abs() > 10.0 {
            return None;
        }
        if step_s.abs() < 1e-13 && step_t.abs() < 1e-13 {
            return Some((s, t));
        }
    }
    None
}

fn bilinear(q: &[[f64; 3]; 4], s: f64, t: f64) -> [f64; 3] {
    let w = bilinear_weights(s, t);
    [0, 1, 2].map(|k| w[0] * q[0][k] + w[1] * q[1][k] + w[2] * q[2][k] + w[3] * q[3][k])
}

fn bilinear_weights(s: f64, t: f64) -> [f64; 4] {
    [(1.0 - s) * (1.0 - t), s * (1.0 - t), s * t, (1.0 - s) * t]
}

/// `3 x^2 - 2 x^3` of `x` clamped to `[0, 1]`.
pub(crate) fn smoothstep(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// The model's quads bucketed by their `x, y` box grown by `reach`, on a uniform grid: a
/// vertex's cell lists, in increasing order, every quad within `reach` of it in `x, y`, so
/// that tying a vertex visits those only and finds what a scan of all quads would.
struct QuadGrid {
    lo: [f64; 2],
    cell: f64,
    nx: usize,
    ny: usize,
    cells: Vec<Vec<u32>>,
}

impl QuadGrid {
    fn new(quads: &[[[f64; 3]; 4]], reach: f64) -> QuadGrid {
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for q in quads {
            let (a, b) = bbox(q);
            for k in 0..2 {
                lo[k] = lo[k].min(a[k] - reach);
                hi[k] = hi[k].max(b[k] + reach);
            }
        }
        let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-9);
        let side = (quads.len() as f64).sqrt().clamp(1.0, 1024.0);
        // cells no smaller than half the reach: a quad then lands in a bounded number of cells
        // (at most about 5 x 5 beyond its own box), where cells much smaller than the reach made
        // the lists grow with the square of the quad count (3 GB for 120 000 hexahedra)
        let cell = (extent / side).max(0.5 * reach);
        let n = |k: usize| (((hi[k] - lo[k]) / cell).ceil() as usize).clamp(1, 1024);
        let (nx, ny) = (n(0), n(1));
        let mut g = QuadGrid {
            lo,
            cell,
            nx,
            ny,
            cells: vec![Vec::new(); nx * ny],
        };
        for (k, q) in quads.iter().enumerate() {
            let (a, b) = bbox(q);
            let (i0, j0) = g.index(a[0] - reach, a[1] - reach);
            let (i1, j1) = g.index(b[0] + reach, b[1] + reach);
            for j in j0..=j1 {
                for i in i0..=i1 {
                    g.cells[j * nx + i].push(k as u32);
                }
            }
        }
        g
    }

    fn index(&self, x: f64, y: f64) -> (usize, usize) {
        let c = |v: f64, lo: f64, n: usize| {
            (((v - lo) / self.cell).floor().max(0.0) as usize).min(n - 1)
        };
        (c(x, self.lo[0], self.nx), c(y, self.lo[1], self.ny))
    }

    /// The quads within reach of `(x, y)` (none outside the grid).
    fn near(&self, x: f64, y: f64) -> &[u32] {
        let inside = |v: f64, lo: f64, n: usize| v >= lo && v <= lo + self.cell * n as f64;
        if !(inside(x, self.lo[0], self.nx) && inside(y, self.lo[1], self.ny)) {
            return &[];
        }
        let (i, j) = self.index(x, y);
        &self.cells[j * self.nx + i]
    }
}

fn tie_vertex(
    p: &[f64; 3],
    quads: &[[[f64; 3]; 4]],
    grid: &QuadGrid,
    index: &[[u32; 4]],
    is_saliva: &[bool],
    params: &SkinParams,
    jaw: f64,
) -> SkinWeight {
    let none = SkinWeight {
        nodes: [0; 4],
        w: [0.0; 4],
        f: 0.0,
        jaw,
    };
    // the nearest quad in x, y among those the vertex lies at the right depth of
    let reach = params.band;
    let mut best: Option<(f64, usize, f64, f64)> = None;
    for &k in grid.near(p[0], p[1]) {
        let k = k as usize;
        let q = &quads[k];
        let (lo, hi) = bbox(q);
        let gap = (lo[0] - p[0])
            .max(p[0] - hi[0])
            .max(lo[1] - p[1])
            .max(p[1] - hi[1]);
        if gap > reach || best.is_some_and(|b| gap > b.0) {
            continue;
        }
        let Some((s, t)) = inverse_bilinear(q, p[0], p[1]) else {
            continue;
        };
        let (sc, tc) = (s.clamp(0.0, 1.0), t.clamp(0.0, 1.0));
        let c = bilinear(q, sc, tc);
        let depth = p[2] - c[2];
        if depth < -params.behind || depth > params.ahead {
            continue;
        }
        let d = ((c[0] - p[0]).powi(2) + (c[1] - p[1]).powi(2)).sqrt();
        if d <= reach && best.is_none_or(|b| d < b.0) {
            best = Some((d, k, sc, tc));
            if d == 0.0 {
                break;
            }
        }
    }
    match best {
        None => none,
        Some((d, k, s, t)) => {
            // over the saliva layer a vertex belongs to the lip on its side of the slit's
            // middle: never a mix of both lips, which part there
            let (s, t) = if is_saliva.get(k).copied().unwrap_or(false) {
                snap_across(&quads[k], s, t)
            } else {
                (s, t)
            };
            SkinWeight {
                nodes: index[k],
                w: bilinear_weights(s, t),
                f: if d == 0.0 {
                    1.0
                } else {
                    1.0 - smoothstep(d / params.band)
                },
                jaw,
            }
        }
    }
}

/// The parameter across a (long, thin) quad snapped to the nearer long edge.
fn snap_across(q: &[[f64; 3]; 4], s: f64, t: f64) -> (f64, f64) {
    let len = |a: [f64; 3], b: [f64; 3]| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
    let along_t = len(bilinear(q, 0.5, 1.0), bilinear(q, 0.5, 0.0));
    let along_s = len(bilinear(q, 1.0, 0.5), bilinear(q, 0.0, 0.5));
    let snap = |x: f64| if x < 0.5 { 0.0 } else { 1.0 };
    if along_t <= along_s {
        (s, snap(t))
    } else {
        (snap(s), t)
    }
}

/// The quad's box in `x, y`.
fn bbox(q: &[[f64; 3]; 4]) -> ([f64; 2], [f64; 2]) {
    let (lo, hi) = crate::linalg::bounding_box(q);
    ([lo[0], lo[1]], [hi[0], hi[1]])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::boundary::{LoadCurve, LoadShape};

    /// A flat model surface: 4 x 2 unit quads of 10 mm at z = 0, vertex `i + 5 j` at
    /// `(10 i, 10 j)` mm.
    fn model() -> QuadSurface {
        let mut vertices = Vec::new();
        for j in 0..3 {
            for i in 0..5 {
                vertices.push([0.01 * i as f64, 0.01 * j as f64, 0.0]);
            }
        }
        let mut quads = Vec::new();
        for j in 0..2u32 {
            for i in 0..4u32 {
                let v = i + 5 * j;
                quads.push([v, v + 1, v + 6, v + 5]);
            }
        }
        QuadSurface {
            vertices,
            uv: None,
            group_of_quad: vec![0; quads.len()],
            quads,
            groups: vec!["face".into()],
            quad_lines: vec![],
            notes: vec![],
        }
    }

    fn mesh(points: &[[f64; 3]]) -> QuadSurface {
        QuadSurface {
            vertices: points.to_vec(),
            uv: None,
            quads: vec![],
            group_of_quad: vec![],
            groups: vec![],
            quad_lines: vec![],
            notes: vec![],
        }
    }

    #[test]
    fn a_vertex_over_the_surface_takes_the_bilinear_mix_of_its_quad() {
        let m = model();
        // inside quad (1, 0) at s = 0.3, t = 0.6, 2 mm in front of it
        let p = [0.013, 0.006, 0.002];
        let skin = Skin::tie(
            "t",
            mesh(&[p]),
            &[0.0],
            &m,
            None,
            OutputFrame::metres(),
            &SkinParams::default(),
        )
        .unwrap();
        let w = skin.weights[0];
        assert_eq!(w.f, 1.0);
        assert_eq!(w.nodes, [1, 2, 7, 6]);
        for (a, b) in w.w.iter().zip([0.7 * 0.4, 0.3 * 0.4, 0.3 * 0.6, 0.7 * 0.6]) {
            assert!((a - b).abs() < 1e-12, "{:?}", w.w);
        }
        // a displacement linear in x and y is reproduced exactly
        let u: Vec<[f64; 3]> = m
            .vertices
            .iter()
            .map(|x| [2.0 * x[0], -x[1], x[0] + 3.0 * x[1]])
            .collect();
        let got = skin.positions(&u, 0.0)[0];
        let want = [p[0] + 2.0 * p[0], p[1] - p[1], p[2] + p[0] + 3.0 * p[1]];
        for k in 0..3 {
            assert!((got[k] - want[k]).abs() < 1e-15, "{got:?} {want:?}");
        }
        assert_eq!(skin.counts, [1, 0, 0]);
    }

    #[test]
    fn beside_the_surface_the_motion_fades_and_far_away_the_jaw_takes_over() {
        let m = model();
        let params = SkinParams::default();
        let pts = [
            [0.045, 0.01, 0.0],  // 5 mm right of the edge: half the band
            [0.07, 0.01, 0.0],   // 30 mm away
            [0.02, 0.01, -0.05], // over the surface but 50 mm behind it (the back of a head)
        ];
        let mut skin = Skin::tie(
            "t",
            mesh(&pts),
            &[0.0, 1.0, 0.5],
            &m,
            None,
            OutputFrame::metres(),
            &params,
        )
        .unwrap();
        assert_eq!(skin.counts, [0, 1, 2]);
        assert!((skin.weights[0].f - 0.5).abs() < 1e-12);
        assert_eq!(skin.weights[1].f, 0.0);
        assert_eq!(skin.weights[2].f, 0.0);
        // a uniform model displacement: half of it at the first vertex, none at the others
        let u = vec![[0.0, 0.001, 0.0]; m.vertices.len()];
        let p = skin.positions(&u, 1.0);
        assert!((p[0][1] - (0.01 + 0.0005)).abs() < 1e-15);
        assert_eq!(p[1], pts[1]);
        // with a jaw rotation of 0.1 rad about z through the origin at t = 1: the far vertex
        // moves by its full weight, the one behind by half
        skin.jaw = Some(PrescribedRotation {
            nodes: vec![],
            point: [0.0; 3],
            axis: [0.0, 0.0, 1.0],
            angle: 0.1,
            curve: LoadCurve {
                shape: LoadShape::Ramp,
                start: 0.0,
                duration: 1.0,
            },
        });
        let p = skin.positions(&u, 1.0);
        let (c, s) = (0.1f64.cos(), 0.1f64.sin());
        let rot = |x: [f64; 3]| [c * x[0] - s * x[1], s * x[0] + c * x[1], x[2]];
        let r1 = rot(pts[1]);
        for k in 0..3 {
            assert!((p[1][k] - r1[k]).abs() < 1e-15);
        }
        let r2 = rot(pts[2]);
        for k in 0..3 {
            assert!((p[2][k] - (pts[2][k] + 0.5 * (r2[k] - pts[2][k]))).abs() < 1e-15);
        }
    }

    #[test]
    fn positions_are_written_in_the_users_units_and_axes() {
        // the user's mesh in millimetres, z up, -y forward (Blender's): model x = user x,
        // model y (up) = user z, model z (forward) = user -y
        let frame = OutputFrame {
            scale: 1e-3,
            rows: [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]],
            unit: "mm",
        };
        assert_eq!(frame.to_user([0.001, 0.002, 0.003]), [1.0, -3.0, 2.0]);
    }

    #[test]
    fn over_the_saliva_layer_a_vertex_goes_with_the_lip_on_its_side() {
        // one saliva quad 10 mm long, 2 mm across, between the lips
        let m = QuadSurface {
            vertices: vec![
                [0.0, 0.0, 0.0],
                [0.01, 0.0, 0.0],
                [0.01, 0.002, 0.0],
                [0.0, 0.002, 0.0],
            ],
            uv: None,
            quads: vec![[0, 1, 2, 3]],
            group_of_quad: vec![0],
            groups: vec!["saliva".into()],
            quad_lines: vec![],
            notes: vec![],
        };
        let pts = [[0.003, 0.0005, 0.0], [0.003, 0.0015, 0.0]];
        let skin = Skin::tie(
            "t",
            mesh(&pts),
            &[0.0, 0.0],
            &m,
            None,
            OutputFrame::metres(),
            &SkinParams::default(),
        )
        .unwrap();
        let close = |a: [f64; 4], b: [f64; 4]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12);
        assert!(
            close(skin.weights[0].w, [0.7, 0.3, 0.0, 0.0]),
            "{:?}",
            skin.weights[0]
        );
        assert!(
            close(skin.weights[1].w, [0.0, 0.0, 0.3, 0.7]),
            "{:?}",
            skin.weights[1]
        );
        // the same quad in another group mixes both edges
        let mut tissue = m.clone();
        tissue.groups = vec!["upper_face".into()];
        let skin = Skin::tie(
            "t",
            mesh(&pts[..1]),
            &[0.0],
            &tissue,
            None,
            OutputFrame::metres(),
            &SkinParams::default(),
        )
        .unwrap();
        assert!(
            close(skin.weights[0].w, [0.525, 0.225, 0.075, 0.175]),
            "{:?}",
            skin.weights[0]
        );
    }

    #[test]
    fn vertices_off_the_front_inherit_along_the_edges_and_fade() {
        let m = model();
        // a strip of quads along x at y = 5 mm, z = 0 (over the model up to x = 40 mm) whose
        // vertices from x = 20 mm on are not the front (a head's interior, say)
        let xs = [0.0, 0.01, 0.02, 0.025, 0.03, 0.04];
        let mut pts = Vec::new();
        for &x in &xs {
            pts.push([x, 0.004, 0.0]);
            pts.push([x, 0.006, 0.0]);
        }
        let mut strip = mesh(&pts);
        for i in 0..xs.len() as u32 - 1 {
            strip.quads.push([2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1]);
            strip.group_of_quad.push(0);
        }
        strip.groups = vec!["head".into()];
        let front: Vec<bool> = (0..pts.len()).map(|v| xs[v / 2] < 0.015).collect();
        let skin = Skin::tie(
            "t",
            strip,
            &vec![0.0; pts.len()],
            &m,
            Some(&front),
            OutputFrame::metres(),
            &SkinParams::default(),
        )
        .unwrap();
        let w = &skin.weights;
        // x = 10 mm is the nearest front vertex: x = 20 mm is 10 mm away along the edges, the
        // whole band, so nothing; the front ones are tied as usual
        assert_eq!(w[2].f, 1.0);
        assert_eq!(w[4].f, 0.0);
        assert_eq!(w[6].f, 0.0);
        assert_eq!(skin.counts, [4, 0, 8]);
        // with a 20 mm band: x = 20 mm (10 mm) fades to one half, x = 25 mm to 0.156, and it
        // moves with x = 10 mm's quad corner, not with the quad it lies over
        let mut strip = mesh(&pts);
        strip.quads = (0..xs.len() as u32 - 1)
            .map(|i| [2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1])
            .collect();
        strip.group_of_quad = vec![0; strip.quads.len()];
        strip.groups = vec!["head".into()];
        let params = SkinParams {
            band: 0.02,
            ..Default::default()
        };
        let skin = Skin::tie(
            "t",
            strip,
            &vec![0.0; pts.len()],
            &m,
            Some(&front),
            OutputFrame::metres(),
            &params,
        )
        .unwrap();
        let w = &skin.weights;
        assert!((w[4].f - 0.5).abs() < 1e-12, "{:?}", w[4]);
        assert!(
            (w[6].f - (1.0 - (0.75f64.powi(2) * (3.0 - 1.5)))).abs() < 1e-12,
            "{:?}",
            w[6]
        );
        assert_eq!((w[4].nodes, w[4].w), (w[2].nodes, w[2].w));
    }

    #[test]
    fn a_jaw_weight_per_vertex_is_required() {
        let e = Skin::tie(
            "head.json",
            mesh(&[[0.0; 3]]),
            &[],
            &model(),
            None,
            OutputFrame::metres(),
            &SkinParams::default(),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("head.json") && e.contains("jaw_weight"), "{e}");
    }

    #[test]
    fn a_mesh_of_triangles_plays_its_own_vertices_and_faces() {
        // two triangles over quad (1, 0), split along a diagonal, plus a vertex off the model
        let m = model();
        let tri = PolySurface {
            vertices: vec![
                [0.012, 0.002, 0.0],
                [0.018, 0.002, 0.0],
                [0.018, 0.008, 0.0],
                [0.012, 0.008, 0.0],
            ],
            uv: None,
            faces: vec![vec![0, 1, 2], vec![0, 2, 3]],
            group_of_face: vec![0, 0],
            groups: vec!["skin".into()],
            face_lines: vec![],
            notes: vec![],
        };
        let skin = Skin::tie_polygons(
            "t",
            &tri,
            &[0.0; 4],
            &m,
            None,
            OutputFrame::metres(),
            &SkinParams::default(),
        )
        .unwrap();
        // the user's vertices and faces, each tied as it would be alone
        assert_eq!(skin.surface, tri);
        assert_eq!(skin.weights.len(), 4);
        assert_eq!(skin.counts, [4, 0, 0]);
        for (k, p) in tri.vertices.iter().enumerate() {
            let alone = Skin::tie(
                "t",
                mesh(&[*p]),
                &[0.0],
                &m,
                None,
                OutputFrame::metres(),
                &SkinParams::default(),
            )
            .unwrap();
            assert_eq!(skin.weights[k], alone.weights[0]);
        }
        // the front flags are per vertex of the refined mesh (4 + 5 edges + 2 centres)
        let e = Skin::tie_polygons(
            "t",
            &tri,
            &[0.0; 4],
            &m,
            Some(&[true; 4]),
            OutputFrame::metres(),
            &SkinParams::default(),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("4 of 11"), "{e}");
    }
}
