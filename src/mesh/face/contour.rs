//! What the two lip finders share: the loop finder ([`super::prepare`]) and the finder on
//! any quad surface ([`super::lips`]) both return a [`Contour`] and measure its
//! [`opening`], count pinches beyond [`PINCH_HOPS`] edges, and read the crop's
//! [`PrepareParams`] (`pinch`, `min_mouth_width`). Here, below both, so that `prepare` uses
//! `lips` and not the other way round as well; `prepare` re-exports the public items
//! (`face::prepare::PrepareParams`, `face::PrepareParams`).

use crate::linalg::{dist, dot, sub};
use crate::mesh::surface::QuadSurface;

/// Edges a vertex must be away along the surface for its distance to count as a pinch.
pub const PINCH_HOPS: usize = 6;

/// Parameters of the crop (SI metres).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PrepareParams {
    /// Kept: quads whose centre is within this distance left and right of the mouth centre.
    pub half_width: f64,
    /// ... and at most this far below the mouth centre (the chin) ...
    pub below: f64,
    /// ... and at most this far above it (below the nose) ...
    pub above: f64,
    /// ... and at most this far behind the front of the lips (the back of the head is not
    /// the face).
    pub behind: f64,
    /// Vertices closer than this to a vertex far away along the surface are lip candidates.
    pub pinch: f64,
    /// Candidate contours narrower than this (corner to corner) are not the mouth.
    pub min_mouth_width: f64,
}

impl Default for PrepareParams {
    fn default() -> Self {
        PrepareParams {
            half_width: 0.050,
            below: 0.050,
            above: 0.025,
            behind: 0.060,
            pinch: 0.003,
            min_mouth_width: 0.025,
        }
    }
}

/// The inner lip contour of a surface: the upper and lower halves from the subject's right
/// corner to the left one (shared corners), the loop's opening (m) and how many candidate
/// loops were compared.
#[derive(Clone, Debug)]
pub struct Contour {
    pub upper: Vec<u32>,
    pub lower: Vec<u32>,
    pub opening: f64,
    pub candidates: usize,
}

/// Mean distance from the vertices of each half to the other half's polyline.
pub(crate) fn opening(s: &QuadSurface, upper: &[u32], lower: &[u32]) -> f64 {
    let p = |v: u32| s.vertices[v as usize];
    let to_polyline = |q: [f64; 3], line: &[u32]| -> f64 {
        let mut best = f64::INFINITY;
        for w in line.windows(2) {
            let (a, b) = (p(w[0]), p(w[1]));
            let ab = sub(&b, &a);
            let l2 = dot(&ab, &ab);
            let t = if l2 > 0.0 {
                (dot(&sub(&q, &a), &ab) / l2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            best = best.min(dist(
                &q,
                &[a[0] + t * ab[0], a[1] + t * ab[1], a[2] + t * ab[2]],
            ));
        }
        best
    };
    let mut sum = 0.0;
    let mut n = 0usize;
    for (h, other) in [(upper, lower), (lower, upper)] {
        for &v in &h[1..h.len() - 1] {
            sum += to_polyline(p(v), other);
            n += 1;
        }
    }
    sum / n.max(1) as f64
}
