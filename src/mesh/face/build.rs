//! From a [`FaceSource`] to the hexahedral model of the paper (section 3.1): a quad surface
//! of the lower front half of the face with a single row of saliva quads between the lips,
//! extruded straight back into one layer of hexahedra.
//!
//! # The surface: a structured grid on the real face
//!
//! The quads of the source mesh are not the model's quads (at the mouth corners the lips of
//! a real head fold into each other in small, steep quads that cannot be extruded, and the
//! two lips' contours have different vertex counts). Instead the model surface is a grid laid
//! over the face seen from the front, like the procedural mouth's ([`crate::mesh::mouth`]),
//! and every grid vertex takes its depth and its data from the real skin:
//!
//! * columns at fixed `x`: `mouth_columns` equal steps between the two mouth corners (from
//!   the lip contours), `side_columns` equal steps on each side out to `half_width` from the
//!   mouth centre;
//! * in each column, one *saliva row* between the lower and the upper lip contour at that
//!   `x` (its two vertices are the contours' points there, at least `min_saliva_gap` apart:
//!   at the corners the contours meet); beyond the corners the same row is tissue (the lips
//!   are joined) and its height grows over three columns to the side columns' width;
//! * `rows_above` rows from the upper contour to `above` over the mouth centre (below the
//!   nose), `rows_below` rows from the lower contour down to the chin's outline (where the
//!   front-most skin jumps back to the neck or stops facing forward by `min_facing`, or at
//!   `below`), smoothed across the columns; row heights grow away from the mouth (first row
//!   0.6 of the mean, last 1.4);
//! * each vertex off the contours is the front-most point of the skin at its `x, y` (a ray
//!   along `-z`); its texture coordinates, jaw weight and blend-shape offsets are the skin's
//!   there (barycentric in the triangle hit); the contour vertices interpolate along the
//!   contour.
//!
//! Each grid quad is the skin over a convex quadrilateral of the `x, y` plane, so it faces
//! forward, and extruded straight back (`-z`) by `thickness` it is a valid hexahedron at
//! every resolution. Counts scale with `resolution` (each direction by its square root).
//!
//! # Sets and data
//!
//! `skull` (the top row and the lateral edges at and above the mouth line, both layers),
//! `jaw` (every node whose jaw weight is at least `jaw_weight`, both layers), the lip columns
//! (the saliva row's two vertices in every mouth column), muscles (cylinders around each
//! muscle's line at mid-depth), blend shapes at every vertex.
//!
//! # The saliva element's axis across the layer
//!
//! The upper lip's contour can lie in front of the lower one (on the MakeHuman head by 1 to
//! 6 mm), so a saliva quad is sheared: its rung runs up and forward. Extruded straight back,
//! the element is a slab whose thin direction is not the rung but the normal of the plane that
//! holds the mouth's direction along the row and the extrusion direction. That normal
//! (pointing from the lower lip to the upper) is the element's local y axis of paper eqs.
//! (8)-(10), given to the saliva rule per element ([`FaceModel::saliva_across`]).

use super::prepare::{FaceSource, MuscleLandmarks};
use crate::boundary::{Fixed, LoadCurve, LoadShape, PrescribedRotation};
use crate::error::{Error, Location, Result};
use crate::linalg::{cross, dot, sub, unit};
use crate::measures::LipColumns;
use crate::mesh::extrude::{extrude_with, Direction};
use crate::mesh::surface::QuadSurface;
use crate::mesh::Mesh;
use crate::muscle::Muscle;
use std::collections::BTreeMap;

/// The chin's outline is searched from this far below the lower lip's contour (m): the
/// lip's top, next to the slit, faces up.
const OUTLINE_START: f64 = 0.003;
/// A drop of the front-most surface by more than this within one scan step (0.25 mm) is the
/// chin's edge (the ray then hits the neck, 40-60 mm further back on the MakeHuman head;
/// the lower lip's overhang over the mentolabial sulcus drops by less than 10 mm).
const OUTLINE_JUMP: f64 = 0.015;

/// A run of samples down a column that do not face forward and is longer than this (m) ends
/// the chin; a shorter one is an overhang (the lower lip's underside).
const OUTLINE_GAP: f64 = 0.002;

/// Parameters of the face model (SI metres).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FaceParams {
    /// Multiplies the number of quads (each direction by its square root). 1: about the
    /// paper's model (3414 hexahedra).
    pub resolution: f64,
    /// The model reaches this far left and right of the mouth centre (m).
    pub half_width: f64,
    /// Its top edge is this far above the mouth centre (m): below the nose.
    pub above: f64,
    /// Its bottom edge is at most this far below the mouth centre (m), higher where the
    /// chin's outline is.
    pub below: f64,
    /// The chin's outline: where the front-most skin jumps back (to the neck), or where its
    /// normal has less than this component forward (it turns away).
    pub min_facing: f64,
    /// Quad columns across the whole width at resolution 1.
    pub columns: usize,
    /// Quad rows below the saliva row at resolution 1.
    pub rows_below: usize,
    /// Quad rows above the saliva row at resolution 1.
    pub rows_above: usize,
    /// The saliva layer's thickness across the lips (its extent along each element's axis
    /// across the layer): `"median"` (the median of the gaps between the two lip contours over
    /// the mouth, the same for every element), a number of metres (the same for every
    /// element), or `"contours"` (each column as high as the contours are apart there, at
    /// least `min_saliva_gap`: the layer the head's modeller drew, uneven).
    pub saliva_thickness: SalivaThickness,
    /// Smallest thickness of the saliva layer (m): the floor of `"median"` and of
    /// `"contours"` where the lip contours meet (the corners).
    pub min_saliva_gap: f64,
    /// The commissure (m): this length of the saliva row next to each mouth corner is tissue,
    /// so the lips are joined there through tissue, not through saliva. 0: the saliva runs
    /// to the corner points of the contours.
    pub commissure: f64,
    /// The modiolus: nodes (both layers) within this distance (m, in the front view) of a
    /// point `modiolus_lateral` beyond each mouth corner, at the corner's height, are held
    /// with the skull, except those the jaw moves. 0: none. The default (5 mm, 10 mm beyond
    /// the corners) holds the corners of the mouth where the face's muscles meet in the
    /// modiolus, a fibromuscular node lateral to each angle of the mouth (paper/README.md,
    /// "The model chosen").
    pub modiolus_radius: f64,
    /// How far beyond each mouth corner the modiolus lies (m).
    pub modiolus_lateral: f64,
    /// The lips' attachment to the bone inside the mouth (the labial vestibule, m): nodes of
    /// the inner layer further than this above the upper lip's line are held with the skull
    /// (the maxilla), further than this below the lower lip's line move with the jaw (the
    /// mandible). 0: the inner layer is free (held only where the front is).
    pub vestibule: f64,
    /// Added to the rig's (or the estimated) hinge point (m): where the jaw turns.
    pub hinge_offset: [f64; 3],
    /// Depth of the extruded tissue layer (m).
    pub thickness: f64,
    /// Nodes whose jaw skinning weight is at least this follow the jaw's rotation. 0.5: the
    /// jaw bone owns most of the vertex's motion in the rig, i.e. the skin over the mandible
    /// (chin and jaw line); the lower lip (weights below 0.3 on the MakeHuman head) is left to
    /// the tissue, so the saliva can hold it.
    pub jaw_weight: f64,
    /// Half-width of the band of skin a muscle's cylinder takes around its line (m).
    pub muscle_reach: f64,
    /// Placeholder force of each muscle at full activation (N).
    pub muscle_strength: f64,
}

/// How thick the saliva layer is ([`FaceParams::saliva_thickness`]): a rule or metres.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(untagged)]
pub enum SalivaThickness {
    /// The same thickness for every element (m).
    Metres(f64),
    Rule(ThicknessRule),
}

/// The rules of [`SalivaThickness`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ThicknessRule {
    /// The median of the gaps between the lip contours, the same for every element.
    Median,
    /// Each column as the contours have it (at least `min_saliva_gap`).
    Contours,
}

impl Default for FaceParams {
    fn default() -> Self {
        FaceParams {
            resolution: 1.0,
            half_width: 0.040,
            above: 0.017,
            below: 0.045,
            min_facing: 0.05,
            columns: 64,
            rows_below: 32,
            rows_above: 20,
            saliva_thickness: SalivaThickness::Rule(ThicknessRule::Median),
            min_saliva_gap: 0.0003,
            commissure: 0.0,
            modiolus_radius: 0.005,
            modiolus_lateral: 0.010,
            vestibule: 0.0,
            hinge_offset: [0.0; 3],
            thickness: 0.010,
            jaw_weight: 0.5,
            muscle_reach: 0.0045,
            muscle_strength: 0.05,
        }
    }
}

impl FaceParams {
    /// Checks the parameters; errors name the field as `prefix` + its name.
    pub fn validate(&self, file: &str, prefix: &str) -> Result<()> {
        let field = |k: &str| format!("{prefix}{k}");
        for (name, v) in [
            ("resolution", self.resolution),
            ("half_width", self.half_width),
            ("above", self.above),
            ("below", self.below),
            ("min_saliva_gap", self.min_saliva_gap),
            ("thickness", self.thickness),
            ("muscle_reach", self.muscle_reach),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::field(
                    file,
                    field(name),
                    format!("must be positive and finite, got {v}"),
                ));
            }
        }
        if let SalivaThickness::Metres(t) = self.saliva_thickness {
            if !(t.is_finite() && t > 0.0 && t < 0.01) {
                return Err(Error::field(
                    file,
                    field("saliva_thickness"),
                    format!("must be \"median\", \"contours\" or a thickness in metres in (0, 0.01), got {t}"),
                ));
            }
        }
        for (name, v) in [
            ("commissure", self.commissure),
            ("modiolus_radius", self.modiolus_radius),
            ("modiolus_lateral", self.modiolus_lateral),
            ("vestibule", self.vestibule),
        ] {
            if !(v.is_finite() && (0.0..0.1).contains(&v)) {
                return Err(Error::field(
                    file,
                    field(name),
                    format!("must be at least 0 and less than 0.1 m, got {v}"),
                ));
            }
        }
        if !self
            .hinge_offset
            .iter()
            .all(|v| v.is_finite() && v.abs() < 0.5)
        {
            return Err(Error::field(
                file,
                field("hinge_offset"),
                format!(
                    "each component must be finite and less than 0.5 m in size, got {:?}",
                    self.hinge_offset
                ),
            ));
        }
        if !(self.min_facing > 0.0 && self.min_facing < 1.0) {
            return Err(Error::field(
                file,
                field("min_facing"),
                format!("must be in (0, 1), got {}", self.min_facing),
            ));
        }
        if self.columns < 6 || self.rows_below < 2 || self.rows_above < 2 {
            return Err(Error::field(
                file,
                field("columns"),
                format!(
                    "need at least 6 columns and 2 rows on each side, got {} columns, {} rows below, {} above",
                    self.columns, self.rows_below, self.rows_above
                ),
            ));
        }
        let f = self.resolution.sqrt();
        let (nodes, elements) = crate::mesh::budget::extruded_grid_counts(
            self.columns as f64 * f,
            (self.rows_below + self.rows_above + 1) as f64 * f,
        );
        crate::mesh::budget::check(file, &field("resolution"), nodes, elements)?;
        crate::mesh::budget::check_face_build_with(
            file,
            &field("resolution"),
            elements,
            crate::mesh::budget::limit_bytes(),
        )?;
        if !(self.jaw_weight > 0.0 && self.jaw_weight <= 1.0) {
            return Err(Error::field(
                file,
                field("jaw_weight"),
                format!("must be in (0, 1], got {}", self.jaw_weight),
            ));
        }
        if !(self.muscle_strength.is_finite() && self.muscle_strength >= 0.0) {
            return Err(Error::field(
                file,
                field("muscle_strength"),
                format!(
                    "must be non-negative and finite, got {}",
                    self.muscle_strength
                ),
            ));
        }
        Ok(())
    }
}

/// Grid sizes after the resolution multiplier.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct FaceGrid {
    pub mouth_columns: usize,
    pub side_columns: usize,
    pub rows_below: usize,
    pub rows_above: usize,
}

impl FaceGrid {
    pub fn columns(&self) -> usize {
        self.mouth_columns + 2 * self.side_columns
    }
    /// Quad rows, the saliva row included.
    pub fn rows(&self) -> usize {
        self.rows_below + self.rows_above + 1
    }
}

/// The hexahedral face model.
#[derive(Clone, Debug)]
pub struct FaceModel {
    pub params: FaceParams,
    pub grid: FaceGrid,
    /// Where the face came from ([`super::prepare::FaceData::source`]).
    pub source: String,
    /// The model surface: groups `upper_face`, `lower_face`, `saliva`; quad `q` is element
    /// `q`; vertex `(i, r)` (column `i` from `-x`, row `r` from the bottom) is
    /// `r (columns + 1) + i`.
    pub surface: QuadSurface,
    pub mesh: Mesh,
    /// A point on the hinge axis and the unit axis.
    pub jaw_hinge: ([f64; 3], [f64; 3]),
    pub muscles: Vec<Muscle>,
    pub columns: LipColumns,
    /// Surface vertex `v` is node `v`, its copy on the inner side node `v + inner_offset`.
    pub inner_offset: u32,
    /// Unit axis across the layer of each saliva element (by element).
    pub saliva_across: BTreeMap<u32, [f64; 3]>,
    /// Jaw weight of each surface vertex.
    pub jaw_weight: Vec<f64>,
    /// Blend shapes: offset of each surface vertex (m).
    pub targets: BTreeMap<String, Vec<[f64; 3]>>,
    pub notes: Vec<String>,
}

impl FaceModel {
    /// The jaw opening: a rotation of the `jaw` set about the hinge.
    pub fn jaw_rotation(&self, angle: f64, curve: LoadCurve) -> PrescribedRotation {
        PrescribedRotation {
            nodes: self.mesh.node_sets["jaw"].clone(),
            point: self.jaw_hinge.0,
            axis: self.jaw_hinge.1,
            angle,
            curve,
        }
    }

    pub fn skull_fixed(&self) -> Fixed {
        Fixed {
            nodes: self.mesh.node_sets["skull"].clone(),
            dofs: [true; 3],
        }
    }

    /// What a scenario needs of the model ([`crate::mesh::anatomy`]).
    pub fn anatomy(&self) -> crate::mesh::anatomy::MouthAnatomy {
        crate::mesh::anatomy::MouthAnatomy {
            source: self.source.clone(),
            jaw_nodes: self.mesh.node_sets["jaw"].clone(),
            hinge: self.jaw_hinge,
            muscles: self.muscles.clone(),
            columns: self.columns.clone(),
            saliva_across: crate::material::saliva::AcrossAxis::PerElement(
                self.saliva_across.clone(),
            ),
        }
    }

    /// Displacement of every node for blend shape `name` at weight 1 (both layers move with
    /// their skin vertex), `None` if the face has no such target.
    pub fn target_displacement(&self, name: &str) -> Option<Vec<[f64; 3]>> {
        let t = self.targets.get(name)?;
        let mut u = t.clone();
        u.extend(t.iter().copied());
        Some(u)
    }
}

/// Row grading: `xi` in [0, 1] to [0, 1], first step 0.6 of the mean, last 1.4.
fn grade(xi: f64) -> f64 {
    const A: f64 = 0.6;
    xi * (A + (1.0 - A) * xi)
}

/// A point of the model surface: position and weights of the source vertices it is made of.
#[derive(Clone, Debug)]
struct Sample {
    x: [f64; 3],
    from: Vec<(u32, f64)>,
}

/// The skin seen from the front: the source surface's quads as triangles, bucketed by `x, y`.
struct Skin<'a> {
    s: &'a QuadSurface,
    cell: f64,
    buckets: BTreeMap<(i64, i64), Vec<[u32; 3]>>,
}

impl<'a> Skin<'a> {
    fn new(s: &'a QuadSurface) -> Skin<'a> {
        let mut edge = 0.0f64;
        for q in &s.quads {
            for k in 0..4 {
                let d = sub(
                    &s.vertices[q[(k + 1) % 4] as usize],
                    &s.vertices[q[k] as usize],
                );
                edge = edge.max(d[0].hypot(d[1]));
            }
        }
        let cell = edge.max(1e-6);
        let mut buckets: BTreeMap<(i64, i64), Vec<[u32; 3]>> = BTreeMap::new();
        for q in &s.quads {
            for t in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
                let p = t.map(|v| s.vertices[v as usize]);
                let lo = |k: usize| p.iter().map(|v| v[k]).fold(f64::INFINITY, f64::min);
                let hi = |k: usize| p.iter().map(|v| v[k]).fold(f64::NEG_INFINITY, f64::max);
                for i in (lo(0) / cell).floor() as i64..=(hi(0) / cell).floor() as i64 {
                    for j in (lo(1) / cell).floor() as i64..=(hi(1) / cell).floor() as i64 {
                        buckets.entry((i, j)).or_default().push(t);
                    }
                }
            }
        }
        Skin { s, cell, buckets }
    }

    /// The front-most point of the skin at `(x, y)`, with the `z` component of its unit
    /// normal.
    fn hit(&self, x: f64, y: f64) -> Option<(Sample, f64)> {
        let key = (
            (x / self.cell).floor() as i64,
            (y / self.cell).floor() as i64,
        );
        let mut best: Option<(Sample, f64)> = None;
        for t in self.buckets.get(&key)? {
            let [a, b, c] = t.map(|v| self.s.vertices[v as usize]);
            let d = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
            if d.abs() < 1e-18 {
                continue;
            }
            let l1 = ((b[0] - x) * (c[1] - y) - (c[0] - x) * (b[1] - y)) / d;
            let l2 = ((c[0] - x) * (a[1] - y) - (a[0] - x) * (c[1] - y)) / d;
            let l3 = 1.0 - l1 - l2;
            const EPS: f64 = -1e-9;
            if l1 < EPS || l2 < EPS || l3 < EPS {
                continue;
            }
            let z = l1 * a[2] + l2 * b[2] + l3 * c[2];
            if best.as_ref().is_none_or(|(s, _)| z > s.x[2]) {
                let n = unit(&cross(&sub(&b, &a), &sub(&c, &a)));
                best = Some((
                    Sample {
                        x: [x, y, z],
                        from: vec![(t[0], l1), (t[1], l2), (t[2], l3)],
                    },
                    n[2],
                ));
            }
        }
        best
    }
}

/// A lip contour as a function of `x` (increasing along it).
struct Contour<'a> {
    s: &'a QuadSurface,
    line: &'a [u32],
}

impl Contour<'_> {
    fn at(&self, x: f64) -> Sample {
        let p = |k: usize| self.s.vertices[self.line[k] as usize];
        let n = self.line.len();
        let mut k = 0;
        while k + 2 < n && p(k + 1)[0] < x {
            k += 1;
        }
        let (a, b) = (p(k), p(k + 1));
        let t = if b[0] > a[0] {
            ((x - a[0]) / (b[0] - a[0])).clamp(0.0, 1.0)
        } else {
            0.0
        };
        Sample {
            x: [0, 1, 2].map(|i| a[i] + t * (b[i] - a[i])),
            from: vec![(self.line[k], 1.0 - t), (self.line[k + 1], t)],
        }
    }
}

/// The saliva row between the lip contours, column by column ([`saliva_layer`]).
#[derive(Clone, Debug, PartialEq)]
struct SalivaLayer {
    /// The row's middle (`y`, m): halfway between the two contours.
    middle: Vec<f64>,
    /// The row's height (`y`, m): its two vertices lie `height / 2` above and below `middle`.
    height: Vec<f64>,
    /// The thickness across the layer every element has (m); `None` for `"contours"`.
    thickness: Option<f64>,
    /// Columns whose height was raised to `min_saliva_gap` (`"contours"`).
    widened: usize,
    /// How far a lip line moved from its contour (m), the largest over the columns.
    largest_shift: f64,
}

/// The saliva row for the mouth columns at `xs` (from corner to corner) whose lower and upper
/// contours lie at `contour_y` (`(lower, upper)`).
///
/// The paper's stretch criterion (eqs. 8-10) stands for the element's strain energy "with all
/// the elements being the same thickness" (section 3.4.3). With a thickness `t` (the median
/// of the gaps across the layer, or given) each column keeps its middle between the two
/// contours and is `t / cos(theta)` high, `theta` the slope of the row's middle line there,
/// so that every element is `t` thick along its axis across the layer (the normal of the
/// row in the front view): each lip line moves straight up or down by half the difference
/// between its column's gap and that height, and nothing else of the lips changes. The gaps
/// are measured across the layer too (`(upper - lower) cos(theta)`); the two corner columns,
/// where the contours meet, do not count in the median.
fn saliva_layer(xs: &[f64], contour_y: &[(f64, f64)], p: &FaceParams) -> SalivaLayer {
    let n = xs.len();
    let middle: Vec<f64> = contour_y.iter().map(|&(lo, hi)| 0.5 * (lo + hi)).collect();
    let cos: Vec<f64> = (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
            let slope = (middle[b] - middle[a]) / (xs[b] - xs[a]);
            1.0 / (1.0 + slope * slope).sqrt()
        })
        .collect();
    let gap = p.min_saliva_gap;
    let (height, thickness, widened): (Vec<f64>, Option<f64>, usize) = match p.saliva_thickness {
        SalivaThickness::Rule(ThicknessRule::Contours) => {
            let mut widened = 0;
            let h = contour_y
                .iter()
                .map(|&(lo, hi)| {
                    if hi - lo < gap {
                        widened += 1;
                        gap
                    } else {
                        hi - lo
                    }
                })
                .collect();
            (h, None, widened)
        }
        rule => {
            let t = match rule {
                SalivaThickness::Metres(t) => t,
                _ => {
                    let mut across: Vec<f64> = (1..n.saturating_sub(1))
                        .map(|i| (contour_y[i].1 - contour_y[i].0) * cos[i])
                        .collect();
                    across.sort_by(f64::total_cmp);
                    let m = across.len();
                    let median = match m {
                        0 => gap,
                        _ if m % 2 == 1 => across[m / 2],
                        _ => 0.5 * (across[m / 2 - 1] + across[m / 2]),
                    };
                    median.max(gap)
                }
            };
            (cos.iter().map(|c| t / c).collect(), Some(t), 0)
        }
    };
    let largest_shift = contour_y
        .iter()
        .zip(&height)
        .map(|(&(lo, hi), h)| 0.5 * ((hi - lo) - h).abs())
        .fold(0.0, f64::max);
    SalivaLayer {
        middle,
        height,
        thickness,
        widened,
        largest_shift,
    }
}

/// The grid's columns in the front view ([`layout`]).
struct Layout {
    grid: FaceGrid,
    /// The columns' `x` (m), `columns + 1` of them from `-x`: the right side columns, the
    /// mouth columns from corner to corner, the left side columns.
    xs: Vec<f64>,
    /// The mouth corners: the upper contour's first point (at smaller `x`) and its last.
    corner_r: [f64; 3],
    corner_l: [f64; 3],
    /// The mouth centre's `x` and `y` (m).
    xc: f64,
    yc: f64,
    /// The narrower side column's width (m): the joined row beyond a corner grows to it.
    side_dx: f64,
}

impl Layout {
    /// The mouth's width from corner to corner (m).
    fn mouth_width(&self) -> f64 {
        self.corner_l[0] - self.corner_r[0]
    }

    /// Vertex `(i, r)`: column `i` from `-x`, row `r` from the bottom.
    fn id(&self, i: usize, r: usize) -> u32 {
        (r * (self.grid.columns() + 1) + i) as u32
    }

    /// Whether the quad of column `i` in the saliva row is saliva: a mouth column, farther
    /// than `commissure` from each corner.
    fn is_saliva(&self, i: usize, commissure: f64) -> bool {
        let (ns, nm) = (self.grid.side_columns, self.grid.mouth_columns);
        let (xr, xl) = (self.corner_r[0], self.corner_l[0]);
        let xq = 0.5 * (self.xs[i] + self.xs[i + 1]);
        i >= ns && i < ns + nm && xq - xr >= commissure && xl - xq >= commissure
    }
}

/// The columns for source `src`: the mouth corners from the lip contours, the grid sizes
/// after the resolution multiplier, the columns' `x`. Fails if `half_width` leaves no face
/// beside the corners.
fn layout(src: &FaceSource, p: &FaceParams, file: &str) -> Result<Layout> {
    let d = &src.data;
    let pv = |v: u32| src.surface.vertices[v as usize];
    let corner_r = pv(d.upper_contour[0]);
    let corner_l = pv(*d.upper_contour.last().expect("contour"));
    let xc = d.mouth_center[0];
    let yc = d.mouth_center[1];
    let (xr, xl) = (corner_r[0], corner_l[0]);
    let (left_edge, right_edge) = (xc + p.half_width, xc - p.half_width);
    if !(right_edge < xr - 1e-3 && left_edge > xl + 1e-3) {
        return Err(Error::input(
            file,
            Location::Field("half_width".into()),
            format!(
                "{} mm leaves no face beside the mouth corners (at {:.1} and {:.1} mm from the centre)",
                1e3 * p.half_width,
                1e3 * (xr - xc),
                1e3 * (xl - xc)
            ),
        ));
    }
    // grid sizes
    let f = p.resolution.sqrt();
    let cols = p.columns as f64 * f;
    let mouth_w = xl - xr;
    let nm = (2.0 * (0.5 * cols * mouth_w / (2.0 * p.half_width)).round()).max(2.0) as usize;
    let ns = ((0.5 * (cols - nm as f64)).round()).max(1.0) as usize;
    let grid = FaceGrid {
        mouth_columns: nm,
        side_columns: ns,
        rows_below: ((p.rows_below as f64 * f).round() as usize).max(2),
        rows_above: ((p.rows_above as f64 * f).round() as usize).max(2),
    };
    let nc = grid.columns();
    let xs: Vec<f64> = (0..=nc)
        .map(|i| {
            if i <= ns {
                right_edge + (xr - right_edge) * i as f64 / ns as f64
            } else if i <= ns + nm {
                xr + mouth_w * (i - ns) as f64 / nm as f64
            } else {
                xl + (left_edge - xl) * (i - ns - nm) as f64 / ns as f64
            }
        })
        .collect();
    let side_dx = ((xr - right_edge) / ns as f64).min((left_edge - xl) / ns as f64);
    Ok(Layout {
        grid,
        xs,
        corner_r,
        corner_l,
        xc,
        yc,
        side_dx,
    })
}

/// The saliva row's two vertices in every column ([`saliva_row`]).
struct SalivaRow {
    /// The lower and the upper vertex in the mouth columns (the contours' points, moved up or
    /// down to the layer's height), `None` beyond the corners.
    lo: Vec<Option<Sample>>,
    hi: Vec<Option<Sample>>,
    /// The lower and the upper vertex's `y` in every column (m).
    y_lo: Vec<f64>,
    y_hi: Vec<f64>,
}

/// The saliva row: contour points in the mouth ([`saliva_layer`] sets their heights), a
/// joined row beyond the corners. Gives the row and the layer.
fn saliva_row(
    l: &Layout,
    lower: &Contour,
    upper: &Contour,
    p: &FaceParams,
) -> (SalivaRow, SalivaLayer) {
    let (ns, nm) = (l.grid.side_columns, l.grid.mouth_columns);
    let nc = l.grid.columns();
    let xs = &l.xs;
    let mouth = ns..=ns + nm;
    let mut row_lo: Vec<Option<Sample>> = Vec::with_capacity(nc + 1);
    let mut row_hi: Vec<Option<Sample>> = Vec::with_capacity(nc + 1);
    let mut y_lo = Vec::with_capacity(nc + 1);
    let mut y_hi = Vec::with_capacity(nc + 1);
    let layer = saliva_layer(
        &xs[ns..=ns + nm],
        &xs[ns..=ns + nm]
            .iter()
            .map(|&x| (lower.at(x).x[1], upper.at(x).x[1]))
            .collect::<Vec<_>>(),
        p,
    );
    let (h_r, h_l) = (layer.height[0], layer.height[nm]);
    let (m_r, m_l) = (layer.middle[0], layer.middle[nm]);
    for (i, &x) in xs.iter().enumerate() {
        if mouth.contains(&i) {
            let (mut lo, mut hi) = (lower.at(x), upper.at(x));
            let k = i - ns;
            lo.x[1] = layer.middle[k] - 0.5 * layer.height[k];
            hi.x[1] = layer.middle[k] + 0.5 * layer.height[k];
            y_lo.push(lo.x[1]);
            y_hi.push(hi.x[1]);
            row_lo.push(Some(lo));
            row_hi.push(Some(hi));
        } else {
            // beyond a corner the row is tissue: from the corner column's height it grows
            // over three columns to the side columns' width
            let (k, h0, m0) = if i < ns {
                (ns - i, h_r, m_r)
            } else {
                (i - ns - nm, h_l, m_l)
            };
            let joined = h0.max(l.side_dx);
            let t = (k as f64 / 3.0).min(1.0);
            let h = 0.5 * (h0 + (joined - h0) * t * t * (3.0 - 2.0 * t));
            y_lo.push(m0 - h);
            y_hi.push(m0 + h);
            row_lo.push(None);
            row_hi.push(None);
        }
    }
    let row = SalivaRow {
        lo: row_lo,
        hi: row_hi,
        y_lo,
        y_hi,
    };
    (row, layer)
}

/// The chin's outline in every column (`y`, m, not smoothed): scanning down each column from
/// below the lower lip (`y_lo`) while the skin faces forward and the front-most surface does
/// not jump back (to the neck). Fails where a column faces forward for less than 4 mm.
fn chin_outline(
    skin: &Skin,
    l: &Layout,
    y_lo: &[f64],
    p: &FaceParams,
    file: &str,
) -> Result<Vec<f64>> {
    let (xs, xc, yc) = (&l.xs, l.xc, l.yc);
    let y_floor = yc - p.below;
    let mut raw_bot: Vec<f64> = Vec::with_capacity(xs.len());
    for (i, &x) in xs.iter().enumerate() {
        match column_bottom(skin, x, y_lo[i] - OUTLINE_START, y_floor, p.min_facing) {
            Some(yb) if yb < y_lo[i] - 0.004 => raw_bot.push(yb),
            _ => {
                return Err(Error::input(
                    file,
                    Location::None,
                    format!(
                        "below the mouth at x = {:.1} mm the skin faces forward for less than 4 mm: the face \
                         does not reach that far out (make half_width smaller)",
                        1e3 * (x - xc)
                    ),
                ))
            }
        }
    }
    if std::env::var("STICKY_LIPS_FACE_DEBUG").is_ok() {
        for (i, (x, b)) in xs.iter().zip(&raw_bot).enumerate() {
            eprintln!(
                "outline column {i}: x {:.2} mm, bottom {:.2} mm",
                1e3 * (x - xc),
                1e3 * (b - yc)
            );
        }
    }
    Ok(raw_bot)
}

/// The chin's outline in the column at `x`, scanned down from `y_start` to `y_floor` in
/// steps of 0.25 mm: the `y` of the last sample facing forward (by `min_facing`) before the
/// neck (a jump back) or before a run of samples that do not face forward longer than
/// OUTLINE_GAP (a short run is an overhang, e.g. the lower lip's underside). `None` if no
/// sample faces forward.
fn column_bottom(skin: &Skin, x: f64, y_start: f64, y_floor: f64, min_facing: f64) -> Option<f64> {
    let step = 2.5e-4;
    // samples down the column: (y, z) where the skin faces forward, None where it does not
    let mut col: Vec<(f64, Option<f64>)> = Vec::new();
    let mut y = y_start;
    while y >= y_floor {
        col.push((
            y,
            skin.hit(x, y)
                .filter(|h| h.1 >= min_facing)
                .map(|h| h.0.x[2]),
        ));
        y -= step;
    }
    let mut bottom: Option<f64> = None;
    let mut last_z: Option<f64> = None;
    let mut bad_from: Option<f64> = None;
    for &(y, z) in &col {
        match z {
            Some(z) => {
                if last_z.is_some_and(|l| l - z > OUTLINE_JUMP) {
                    break;
                }
                bad_from = None;
                bottom = Some(y);
                last_z = Some(z);
            }
            None => {
                let start = *bad_from.get_or_insert(y);
                if start - y > OUTLINE_GAP {
                    break;
                }
            }
        }
    }
    bottom
}

/// The model's bottom edge from the chin's outline `raw_bot`: the highest outline point
/// within three columns, smoothed three times (1/4, 1/2, 1/4), never below the outline.
fn smooth_outline(raw_bot: &[f64]) -> Vec<f64> {
    let n = raw_bot.len();
    let mut y_bot: Vec<f64> = (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(3), (i + 3).min(n - 1));
            raw_bot[a..=b]
                .iter()
                .copied()
                .fold(f64::NEG_INFINITY, f64::max)
        })
        .collect();
    for _ in 0..3 {
        let prev = y_bot.clone();
        for i in 0..n {
            let (a, b) = (prev[i.saturating_sub(1)], prev[(i + 1).min(n - 1)]);
            y_bot[i] = 0.25 * a + 0.5 * prev[i] + 0.25 * b;
        }
    }
    for i in 0..n {
        y_bot[i] = y_bot[i].max(raw_bot[i]);
    }
    y_bot
}

/// The grid's vertices, row by row from the bottom: the saliva row's two from `row`, the
/// others the front-most skin at their `x, y` (rows graded from the saliva row to `y_bot`
/// below and to `y_top` above). Fails where the skin does not cover a vertex.
fn grid_vertices(
    skin: &Skin,
    l: &Layout,
    row: &SalivaRow,
    y_bot: &[f64],
    y_top: f64,
    file: &str,
) -> Result<Vec<Sample>> {
    let nc = l.grid.columns();
    let (rb, ra) = (l.grid.rows_below, l.grid.rows_above);
    let nr = l.grid.rows();
    let (y_lo, y_hi) = (&row.y_lo, &row.y_hi);
    let mut samples: Vec<Sample> = Vec::with_capacity((nc + 1) * (nr + 1));
    for r in 0..=nr {
        for (i, &x) in l.xs.iter().enumerate() {
            let contour_point = if r == rb {
                row.lo[i].clone()
            } else if r == rb + 1 {
                row.hi[i].clone()
            } else {
                None
            };
            let smp = match contour_point {
                Some(s) => s,
                None => {
                    let y = if r <= rb {
                        y_lo[i] - (y_lo[i] - y_bot[i]) * grade((rb - r) as f64 / rb as f64)
                    } else {
                        y_hi[i] + (y_top - y_hi[i]) * grade((r - rb - 1) as f64 / ra as f64)
                    };
                    skin.hit(x, y).map(|h| h.0).ok_or_else(|| {
                        Error::input(
                            file,
                            Location::None,
                            format!(
                                "no skin at x = {:.2} mm, y = {:.2} mm from the mouth centre (grid vertex {i}, row {r}): \
                                 the kept face does not cover the model's area",
                                1e3 * (x - l.xc),
                                1e3 * (y - l.yc)
                            ),
                        )
                    })?
                }
            };
            samples.push(smp);
        }
    }
    Ok(samples)
}

/// The grid's quads and their groups (0 `upper_face`, 1 `lower_face`, 2 `saliva`): the
/// saliva row's mouth columns are saliva, less the commissure at each corner. Fails if the
/// commissure leaves no saliva.
fn grid_quads(l: &Layout, p: &FaceParams, file: &str) -> Result<(Vec<[u32; 4]>, Vec<u32>)> {
    let (ns, nm) = (l.grid.side_columns, l.grid.mouth_columns);
    let (nc, nr, rb) = (l.grid.columns(), l.grid.rows(), l.grid.rows_below);
    let id = |i: usize, r: usize| l.id(i, r);
    let is_saliva = |i: usize| l.is_saliva(i, p.commissure);
    if !(ns..ns + nm).any(is_saliva) {
        return Err(Error::field(
            file,
            "commissure",
            format!(
                "{} mm at each corner leaves no saliva in a mouth {:.1} mm wide",
                1e3 * p.commissure,
                1e3 * l.mouth_width()
            ),
        ));
    }
    let mut quads = Vec::with_capacity(nc * nr);
    let mut group_of_quad = Vec::with_capacity(nc * nr);
    for r in 0..nr {
        for i in 0..nc {
            quads.push([id(i, r), id(i + 1, r), id(i + 1, r + 1), id(i, r + 1)]);
            let g = if r < rb {
                1 // lower face
            } else if r > rb || !is_saliva(i) {
                0 // upper face (the joined row beyond the corners and the commissure too)
            } else {
                2 // saliva
            };
            group_of_quad.push(g);
        }
    }
    Ok((quads, group_of_quad))
}

/// Data `vals` (`dim` values at each source vertex) at every sample: the sum over the
/// source vertices it is made of, each value times its weight.
fn interpolate(samples: &[Sample], vals: &dyn Fn(u32) -> Vec<f64>, dim: usize) -> Vec<Vec<f64>> {
    samples
        .iter()
        .map(|s| {
            let mut out = vec![0.0; dim];
            for &(v, w) in &s.from {
                for (o, x) in out.iter_mut().zip(vals(v)) {
                    *o += w * x;
                }
            }
            out
        })
        .collect()
}

/// The model's node sets ([`node_sets`]).
struct NodeSets {
    skull: Vec<u32>,
    jaw: Vec<u32>,
    upper_lip: Vec<u32>,
    lower_lip: Vec<u32>,
}

/// The node sets `skull`, `jaw` and the lips' (both layers) of the grid `l` whose surface has
/// `nv` vertices at `vertices`: the skull holds the top row, the lateral edges at and above
/// the mouth line and the modiolus, the jaw moves the vertices of jaw weight at least
/// `p.jaw_weight`; the vestibule adds inner nodes to each. Fails if the jaw takes no vertex,
/// the modiolus none, or a node is in both.
fn node_sets(
    l: &Layout,
    vertices: &[[f64; 3]],
    row: &SalivaRow,
    jaw_weight: &[f64],
    cols: &LipColumns,
    p: &FaceParams,
    file: &str,
) -> Result<NodeSets> {
    let (nc, nr, rb) = (l.grid.columns(), l.grid.rows(), l.grid.rows_below);
    let nv = vertices.len() as u32;
    let mut skull: Vec<u32> = (0..=nc).map(|i| l.id(i, nr)).collect();
    for r in rb + 1..=nr {
        skull.push(l.id(0, r));
        skull.push(l.id(nc, r));
    }
    skull.sort_unstable();
    skull.dedup();
    let mut jaw: Vec<u32> = (0..nv)
        .filter(|&v| jaw_weight[v as usize] >= p.jaw_weight)
        .collect();
    if jaw.is_empty() {
        return Err(Error::input(
            file,
            Location::None,
            format!(
                "no vertex of the model has a jaw weight of at least {}: nothing would move the jaw",
                p.jaw_weight
            ),
        ));
    }
    let mut upper_lip = cols.upper.clone();
    let mut lower_lip = cols.lower.clone();
    for set in [&mut skull, &mut jaw, &mut upper_lip, &mut lower_lip] {
        both_layers(set, nv);
    }
    if p.modiolus_radius > 0.0 {
        hold_modioli(l, vertices, &jaw, &mut skull, p, file)?;
    }
    // the vestibule: the inner layer held by the maxilla above the lips, moved by the
    // mandible below them
    if p.vestibule > 0.0 {
        for r in 0..=nr {
            for i in 0..=nc {
                let v = l.id(i, r);
                let y = vertices[v as usize][1];
                if r > rb + 1 && y > row.y_hi[i] + p.vestibule {
                    skull.push(v + nv);
                } else if r < rb && y < row.y_lo[i] - p.vestibule {
                    jaw.push(v + nv);
                }
            }
        }
    }
    for set in [&mut skull, &mut jaw] {
        set.sort_unstable();
        set.dedup();
    }
    check_disjoint(&skull, &jaw, nc, nv, p, file)?;
    Ok(NodeSets {
        skull,
        jaw,
        upper_lip,
        lower_lip,
    })
}

/// Adds to the surface vertices in `set` their copies on the inner side (`+ nv`), sorted.
fn both_layers(set: &mut Vec<u32>, nv: u32) {
    let n = set.len();
    for k in 0..n {
        set.push(set[k] + nv);
    }
    set.sort_unstable();
    set.dedup();
}

/// The modiolus beyond each corner, held with the skull (both layers): adds to `skull` the
/// vertices not in `jaw` within `modiolus_radius` of either point. Fails if it takes none.
fn hold_modioli(
    l: &Layout,
    vertices: &[[f64; 3]],
    jaw: &[u32],
    skull: &mut Vec<u32>,
    p: &FaceParams,
    file: &str,
) -> Result<()> {
    let nv = vertices.len() as u32;
    let (xr, xl) = (l.corner_r[0], l.corner_l[0]);
    let centres = [
        [xr - p.modiolus_lateral, l.corner_r[1]],
        [xl + p.modiolus_lateral, l.corner_l[1]],
    ];
    let mut held = 0;
    for v in 0..nv {
        let x = vertices[v as usize];
        if jaw.binary_search(&v).is_err()
            && centres
                .iter()
                .any(|c| (x[0] - c[0]).hypot(x[1] - c[1]) <= p.modiolus_radius)
        {
            skull.extend([v, v + nv]);
            held += 1;
        }
    }
    if held == 0 {
        return Err(Error::field(
            file,
            "modiolus_radius",
            format!(
                "{} mm around the points {} mm beyond the corners takes no vertex of the model",
                1e3 * p.modiolus_radius,
                1e3 * p.modiolus_lateral
            ),
        ));
    }
    Ok(())
}

/// Fails, naming the first such node by its column and row, if a node is in both `skull`
/// and `jaw` (both sorted).
fn check_disjoint(
    skull: &[u32],
    jaw: &[u32],
    nc: usize,
    nv: u32,
    p: &FaceParams,
    file: &str,
) -> Result<()> {
    if let Some(v) = jaw.iter().find(|v| skull.binary_search(v).is_ok()) {
        let s = *v % nv;
        return Err(Error::input(
            file,
            Location::None,
            format!(
                "node {v} (column {}, row {}{}) is both held by the skull{} and moved by the jaw",
                s as usize % (nc + 1),
                s as usize / (nc + 1),
                if *v >= nv { ", inner layer" } else { "" },
                if p.modiolus_radius > 0.0 {
                    " (or the modiolus: make modiolus_radius smaller)"
                } else {
                    ""
                }
            ),
        ));
    }
    Ok(())
}

/// The unit axis across the layer of each saliva element (by element, module docs): the
/// normal of the plane of the mouth's direction along the row and the extrusion direction,
/// pointing from the lower lip to the upper.
fn saliva_axes(l: &Layout, vertices: &[[f64; 3]], commissure: f64) -> BTreeMap<u32, [f64; 3]> {
    let (ns, nm) = (l.grid.side_columns, l.grid.mouth_columns);
    let (nc, rb) = (l.grid.columns(), l.grid.rows_below);
    let id = |i: usize, r: usize| l.id(i, r);
    let back = [0.0, 0.0, -1.0];
    let mut across = BTreeMap::new();
    for i in (ns..ns + nm).filter(|&i| l.is_saliva(i, commissure)) {
        let q = (rb * nc + i) as u32;
        let x = |v: u32| vertices[v as usize];
        let along = sub(&x(id(i + 1, rb)), &x(id(i, rb)));
        let along2 = sub(&x(id(i + 1, rb + 1)), &x(id(i, rb + 1)));
        let a = unit(&[0, 1, 2].map(|k| along[k] + along2[k]));
        let mut nrm = unit(&cross(&a, &back));
        let rung = sub(&x(id(i, rb + 1)), &x(id(i, rb)));
        if dot(&nrm, &rung) < 0.0 {
            nrm = nrm.map(|v| -v);
        }
        across.insert(q, nrm);
    }
    across
}

/// The element sets `tissue_upper`, `tissue_lower` (the groups' sets) and `tissue` (both).
fn add_tissue_sets(es: &mut BTreeMap<String, Vec<u32>>) {
    let up = es.get("upper_face").cloned().unwrap_or_default();
    let low = es.get("lower_face").cloned().unwrap_or_default();
    let mut tissue: Vec<u32> = up.iter().chain(low.iter()).copied().collect();
    tissue.sort_unstable();
    es.insert("tissue_upper".into(), up);
    es.insert("tissue_lower".into(), low);
    es.insert("tissue".into(), tissue);
}

/// The muscles from their landmarks: each line at mid-depth of the layer, its cylinder
/// reaching `muscle_reach` around it in the skin (and the half depth across), inactive.
fn face_muscles(landmarks: &[MuscleLandmarks], p: &FaceParams) -> Vec<Muscle> {
    let depth = 0.5 * p.thickness;
    let radius = (p.muscle_reach.powi(2) + depth * depth).sqrt();
    landmarks
        .iter()
        .map(|m: &MuscleLandmarks| Muscle {
            name: m.name.clone(),
            origin: [m.origin[0], m.origin[1], m.origin[2] - depth],
            insertion: [m.insertion[0], m.insertion[1], m.insertion[2] - depth],
            radius,
            strength: p.muscle_strength,
            activation: 0.0,
            curve: LoadCurve {
                shape: LoadShape::SmoothStep,
                start: 0.0,
                duration: 0.1,
            },
        })
        .collect()
}

/// The model's notes: its sizes, and the saliva layer's thickness or widening.
fn model_notes(
    p: &FaceParams,
    grid: &FaceGrid,
    mesh: &Mesh,
    lip_columns: usize,
    layer: &SalivaLayer,
) -> Vec<String> {
    let mut notes = vec![format!(
        "resolution {}: {} columns ({} between the corners), {} rows ({} below the saliva row, {} above); \
         {} hexahedra, {} nodes; {} lip columns",
        p.resolution,
        grid.columns(),
        grid.mouth_columns,
        grid.rows(),
        grid.rows_below,
        grid.rows_above,
        mesh.elements.len(),
        mesh.nodes.len(),
        lip_columns
    )];
    match layer.thickness {
        Some(t) => notes.push(format!(
            "every saliva element is {:.3} mm thick across the layer; the lip lines moved up or down by at most {:.3} mm from the contours",
            1e3 * t,
            1e3 * layer.largest_shift
        )),
        None if layer.widened > 0 => notes.push(format!(
            "the saliva row was widened to {} mm at {} columns where the lip contours are closer (the corners)",
            1e3 * p.min_saliva_gap,
            layer.widened
        )),
        None => {}
    }
    notes
}

/// Builds the model (module docs). `file` names the source in errors.
pub fn build(src: &FaceSource, p: &FaceParams, file: &str) -> Result<FaceModel> {
    p.validate(file, "")?;
    let d = &src.data;
    let skin_s = &src.surface;
    let skin = Skin::new(skin_s);
    let upper = Contour {
        s: skin_s,
        line: &d.upper_contour,
    };
    let lower = Contour {
        s: skin_s,
        line: &d.lower_contour,
    };
    let l = layout(src, p, file)?;
    let grid = l.grid;
    let (ns, nm, rb) = (grid.side_columns, grid.mouth_columns, grid.rows_below);
    let (row, layer) = saliva_row(&l, &lower, &upper, p);
    let raw_bot = chin_outline(&skin, &l, &row.y_lo, p, file)?;
    let y_bot = smooth_outline(&raw_bot);
    let y_top = l.yc + p.above;
    let samples = grid_vertices(&skin, &l, &row, &y_bot, y_top, file)?;
    let (quads, group_of_quad) = grid_quads(&l, p, file)?;
    let interp = |vals: &dyn Fn(u32) -> Vec<f64>, dim: usize| interpolate(&samples, vals, dim);
    let uv = skin_s.uv.as_ref().map(|uv| {
        interp(&|v| uv[v as usize].to_vec(), 2)
            .into_iter()
            .map(|u| [u[0], u[1]])
            .collect::<Vec<[f64; 2]>>()
    });
    let surface = QuadSurface {
        vertices: samples.iter().map(|s| s.x).collect(),
        uv,
        quads,
        group_of_quad,
        groups: vec!["upper_face".into(), "lower_face".into(), "saliva".into()],
        quad_lines: Vec::new(),
        notes: Vec::new(),
    };
    let mut mesh = extrude_with(
        &surface,
        &|_| p.thickness,
        Direction::Fixed([0.0, 0.0, -1.0]),
        file,
    )?;
    let nv = surface.vertices.len() as u32;
    let jaw_weight: Vec<f64> = interp(&|v| vec![d.jaw_weight[v as usize]], 1)
        .into_iter()
        .map(|w| w[0])
        .collect();
    let cols = LipColumns {
        x: (ns..=ns + nm).map(|i| l.xs[i]).collect(),
        upper: (ns..=ns + nm).map(|i| l.id(i, rb + 1)).collect(),
        lower: (ns..=ns + nm).map(|i| l.id(i, rb)).collect(),
        center: l.xc,
    };
    let sets = node_sets(&l, &surface.vertices, &row, &jaw_weight, &cols, p, file)?;
    let across = saliva_axes(&l, &surface.vertices, p.commissure);
    let node_sets = &mut mesh.node_sets;
    node_sets.insert("skull".into(), sets.skull);
    node_sets.insert("jaw".into(), sets.jaw);
    node_sets.insert("upper_lip_inner".into(), sets.upper_lip);
    node_sets.insert("lower_lip_inner".into(), sets.lower_lip);
    add_tissue_sets(&mut mesh.element_sets);
    let muscles = face_muscles(&d.muscles, p);
    let targets = d
        .targets
        .iter()
        .map(|(k, t)| {
            let v = interp(&|v| t[v as usize].to_vec(), 3)
                .into_iter()
                .map(|u| [u[0], u[1], u[2]])
                .collect();
            (k.clone(), v)
        })
        .collect();
    let notes = model_notes(p, &grid, &mesh, cols.x.len(), &layer);
    Ok(FaceModel {
        params: p.clone(),
        grid,
        source: d.source.clone(),
        surface,
        mesh,
        jaw_hinge: (
            [0, 1, 2].map(|k| d.hinge_point[k] + p.hinge_offset[k]),
            d.hinge_axis,
        ),
        muscles,
        columns: cols,
        inner_offset: nv,
        saliva_across: across,
        jaw_weight,
        targets,
        notes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::hex8;

    fn model_with(resolution: f64, f: impl Fn(&mut FaceParams)) -> FaceModel {
        let src = super::super::makehuman().unwrap();
        let mut p = FaceParams {
            resolution,
            ..Default::default()
        };
        f(&mut p);
        build(&src, &p, "makehuman").unwrap()
    }

    fn model(resolution: f64) -> FaceModel {
        let src = super::super::makehuman().unwrap();
        build(
            &src,
            &FaceParams {
                resolution,
                ..Default::default()
            },
            "makehuman",
        )
        .unwrap()
    }

    #[test]
    fn the_makehuman_face_is_a_valid_mirror_symmetric_model_about_the_papers_size() {
        for res in [0.25, 1.0] {
            let m = model(res);
            m.mesh.validate("face").unwrap();
            let (ne, nn) = (m.mesh.elements.len(), m.mesh.nodes.len());
            if res == 1.0 {
                // the paper: 3414 hexahedra, 6982 nodes
                assert!((ne as f64 / 3414.0 - 1.0).abs() < 0.05, "{ne} hexahedra");
                assert!((nn as f64 / 6982.0 - 1.0).abs() < 0.05, "{nn} nodes");
            }
            for e in 0..ne {
                let (dmin, _) = hex8::min_corner_jacobian(&m.mesh.element_coords(e));
                assert!(dmin > 0.0, "element {e} inverted");
            }
            // every node has a mirror image (x -> 2 xc - x) up to round-off
            let xc = m.columns.center;
            let mut pts: Vec<[i64; 3]> = m
                .mesh
                .nodes
                .iter()
                .map(|p| {
                    [
                        ((p[0] - xc) * 1e8).round() as i64,
                        (p[1] * 1e8).round() as i64,
                        (p[2] * 1e8).round() as i64,
                    ]
                })
                .collect();
            let mut mirrored: Vec<[i64; 3]> = pts.iter().map(|p| [-p[0], p[1], p[2]]).collect();
            pts.sort_unstable();
            mirrored.sort_unstable();
            let off = pts
                .iter()
                .zip(&mirrored)
                .map(|(a, b)| (0..3).map(|k| (a[k] - b[k]).abs()).max().unwrap())
                .max()
                .unwrap();
            assert!(off <= 2, "not mirror symmetric: {off} x 1e-8 m");
        }
    }

    #[test]
    fn one_row_of_saliva_from_corner_to_corner_with_its_axis_across() {
        let m = model(1.0);
        let sal = &m.mesh.element_sets["saliva"];
        assert_eq!(sal.len(), m.grid.mouth_columns);
        assert_eq!(m.columns.x.len(), m.grid.mouth_columns + 1);
        assert!(m.columns.x.windows(2).all(|w| w[1] > w[0]));
        // the columns run between the mouth corners, the upper vertex above the lower one
        let width = m.columns.x.last().unwrap() - m.columns.x[0];
        assert!((width - 0.0488).abs() < 0.001, "mouth width {width}");
        for (k, (&u, &l)) in m.columns.upper.iter().zip(&m.columns.lower).enumerate() {
            let (pu, pl) = (m.mesh.nodes[u as usize], m.mesh.nodes[l as usize]);
            assert!(
                pu[1] - pl[1] >= m.params.min_saliva_gap - 1e-12,
                "column {k}"
            );
        }
        for &e in sal {
            let a = m.saliva_across[&e];
            assert!(a[2].abs() < 1e-12, "the axis lies in the x-y plane: {a:?}");
            assert!(
                a[1] > 0.9,
                "across points up, from the lower lip to the upper: {a:?}"
            );
            // the element's extent along the axis is the saliva row's height: thin
            let x = m.mesh.element_coords(e as usize);
            let along: Vec<f64> = x.iter().map(|p| dot(p, &a)).collect();
            let thick = along.iter().copied().fold(f64::NEG_INFINITY, f64::max)
                - along.iter().copied().fold(f64::INFINITY, f64::min);
            assert!(thick < 0.003, "saliva element {e}: {thick} m across");
        }
        // groups: every quad is tissue or saliva; the saliva quads are the element set
        let g = m.surface.group_index("saliva").unwrap() as u32;
        let n = m.surface.group_of_quad.iter().filter(|&&q| q == g).count();
        assert_eq!(n, sal.len());
    }

    /// Each saliva element's extent along its axis across the layer (m), by element.
    fn thicknesses(m: &FaceModel) -> Vec<f64> {
        m.mesh.element_sets["saliva"]
            .iter()
            .map(|&e| {
                let a = m.saliva_across[&e];
                let x = m.mesh.element_coords(e as usize);
                let along: Vec<f64> = x.iter().map(|p| dot(p, &a)).collect();
                along.iter().copied().fold(f64::NEG_INFINITY, f64::max)
                    - along.iter().copied().fold(f64::INFINITY, f64::min)
            })
            .collect()
    }

    /// Paper section 3.4.3: the stretch criterion assumes "all the elements being the same
    /// thickness". By default every saliva element is the median gap thick; with
    /// `"contours"` the layer is as uneven as the head's lips are apart.
    #[test]
    fn the_saliva_layer_is_equally_thick_by_default() {
        for res in [0.25, 1.0] {
            let m = model(res);
            let t = thicknesses(&m);
            let (lo, hi) = (
                t.iter().copied().fold(f64::INFINITY, f64::min),
                t.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            );
            eprintln!(
                "resolution {res}: saliva {:.4} .. {:.4} mm",
                1e3 * lo,
                1e3 * hi
            );
            let uneven = model_with(res, |p| {
                p.saliva_thickness = SalivaThickness::Rule(ThicknessRule::Contours)
            });
            let tu = thicknesses(&uneven);
            let (ulo, uhi) = (
                tu.iter().copied().fold(f64::INFINITY, f64::min),
                tu.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            );
            eprintln!("contours: {:.4} .. {:.4} mm", 1e3 * ulo, 1e3 * uhi);
            assert!(hi / lo < 1.01, "{lo} .. {hi}");
            assert!(uhi / ulo > 1.3, "{ulo} .. {uhi}");
        }
    }

    /// The modelling choices of the study: each changes what it says and nothing else.
    #[test]
    fn commissure_modiolus_vestibule_and_hinge_offset_change_what_they_say() {
        let base = model_with(0.25, |p| p.modiolus_radius = 0.0);
        let count = |m: &FaceModel, set: &str| m.mesh.node_sets[set].len();
        let sal = |m: &FaceModel| m.mesh.element_sets["saliva"].len();
        // commissure: the saliva quads within 3 mm of a corner become tissue
        let c = model_with(0.25, |p| {
            p.modiolus_radius = 0.0;
            p.commissure = 0.003;
        });
        let (xr, xl) = (base.columns.x[0], *base.columns.x.last().unwrap());
        let near = base.mesh.element_sets["saliva"]
            .iter()
            .filter(|&&e| {
                let x = base.mesh.element_coords(e as usize);
                let xq = x[..4].iter().map(|p| p[0]).sum::<f64>() / 4.0;
                xq - xr < 0.003 || xl - xq < 0.003
            })
            .count();
        assert!(near >= 2, "{near}");
        assert_eq!(sal(&c), sal(&base) - near);
        assert_eq!(c.mesh.nodes, base.mesh.nodes);
        assert_eq!(c.saliva_across.len(), sal(&c));
        // modiolus: more nodes held, none of them in the jaw set, the rest unchanged
        let m = model_with(0.25, |p| p.modiolus_radius = 0.005);
        assert!(count(&m, "skull") > count(&base, "skull"));
        assert_eq!(m.mesh.node_sets["jaw"], base.mesh.node_sets["jaw"]);
        assert!(base.mesh.node_sets["skull"]
            .iter()
            .all(|n| m.mesh.node_sets["skull"].binary_search(n).is_ok()));
        // vestibule: inner-layer nodes only join the skull and the jaw
        let v = model_with(0.25, |p| {
            p.modiolus_radius = 0.0;
            p.vestibule = 0.008;
        });
        let nv = v.inner_offset;
        for set in ["skull", "jaw"] {
            let extra: Vec<u32> = v.mesh.node_sets[set]
                .iter()
                .copied()
                .filter(|n| base.mesh.node_sets[set].binary_search(n).is_err())
                .collect();
            assert!(!extra.is_empty(), "{set}");
            assert!(extra.iter().all(|&n| n >= nv), "{set}: a front node added");
        }
        // hinge offset
        let h = model_with(0.25, |p| {
            p.modiolus_radius = 0.0;
            p.hinge_offset = [0.0, -0.015, 0.0];
        });
        assert!((h.jaw_hinge.0[1] - (base.jaw_hinge.0[1] - 0.015)).abs() < 1e-15);
        // refusals name the field
        let src = super::super::makehuman().unwrap();
        for (p, field) in [
            (
                FaceParams {
                    commissure: 0.03,
                    resolution: 0.25,
                    ..Default::default()
                },
                "commissure",
            ),
            (
                FaceParams {
                    saliva_thickness: SalivaThickness::Metres(-1.0),
                    ..Default::default()
                },
                "saliva_thickness",
            ),
            (
                FaceParams {
                    hinge_offset: [0.0, 1e300, 0.0],
                    ..Default::default()
                },
                "hinge_offset",
            ),
            (
                FaceParams {
                    modiolus_radius: 0.001,
                    modiolus_lateral: 0.09,
                    resolution: 0.25,
                    ..Default::default()
                },
                "modiolus_radius",
            ),
        ] {
            let e = build(&src, &p, "face.json").unwrap_err().to_string();
            assert!(e.contains(field), "{field}: {e}");
        }
    }

    #[test]
    fn skull_and_jaw_are_apart_and_the_hinge_opens_the_mouth() {
        let m = model(0.25);
        let skull = &m.mesh.node_sets["skull"];
        let jaw = &m.mesh.node_sets["jaw"];
        assert!(skull.iter().all(|n| jaw.binary_search(n).is_err()));
        let yc = m.jaw_hinge.0[1];
        // the jaw set lies below the lower lip: no node of the lower lip's columns is in it
        for &l in &m.columns.lower {
            assert!(jaw.binary_search(&l).is_err());
        }
        let lip_y = m
            .columns
            .lower
            .iter()
            .map(|&l| m.mesh.nodes[l as usize][1])
            .fold(f64::INFINITY, f64::min);
        let top = jaw
            .iter()
            .map(|&n| m.mesh.nodes[n as usize][1])
            .fold(f64::NEG_INFINITY, f64::max);
        assert!(
            top < lip_y - 0.005,
            "jaw set reaches {top}, the lower lip {lip_y}"
        );
        // the hinge lies behind and above the mouth; a positive angle moves the chin down
        let mouth_y = m.mesh.nodes[m.columns.upper[m.columns.upper.len() / 2] as usize][1];
        let front = m
            .mesh
            .nodes
            .iter()
            .map(|p| p[2])
            .fold(f64::NEG_INFINITY, f64::max);
        assert!(
            yc > mouth_y && m.jaw_hinge.0[2] < front - 0.05,
            "hinge {:?}",
            m.jaw_hinge.0
        );
        let rot = m.jaw_rotation(
            0.1,
            LoadCurve {
                shape: LoadShape::Step,
                start: 0.0,
                duration: 1.0,
            },
        );
        let low = *jaw
            .iter()
            .min_by(|&&a, &&b| m.mesh.nodes[a as usize][1].total_cmp(&m.mesh.nodes[b as usize][1]))
            .unwrap();
        let u = rot.displacement(&m.mesh.nodes[low as usize], 1.0, true);
        assert!(u[1] < -0.003, "{u:?}");
        for mu in &m.muscles {
            let k = mu.select_nodes(&m.mesh.nodes).len();
            assert!(k >= 6, "muscle {} takes {k} nodes", mu.name);
        }
    }
}
