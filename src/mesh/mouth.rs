//! A procedural mouth: the equivalent of the paper's FaceGen model (section 3.1), built by
//! the paper's own pipeline: a quad surface of the lower front half of a face with three
//! material groups, `upper_face` and `lower_face` (soft tissue, blue and red in the paper's
//! Fig. 2) and `saliva` (a thin strip between the lips, green), then one extruded layer of
//! hexahedra ([`super::extrude`]).
//!
//! # Frame and shape (SI metres)
//!
//! `x` runs left-right (`+x` is the subject's **left**, the viewer's right in a front view),
//! `y` up, `z` forward out of the face (a front view looks along `-z`). The mouth line is
//! `y = 0` (tilted by [`MouthParams::mouth_tilt`]), centred on `x = 0`. The patch spans
//! `|x| <= face_width / 2`, from `y = -height_below` (under the chin) to `y = height_above`
//! (below the nose). The skin surface is
//!
//! `z = cyl(x) + chin(y) + lip(x, v)`:
//!
//! * `cyl(x) = sqrt(R^2 - x^2) - R`: the lower face as a cylinder section around a vertical
//!   axis (`R = face_radius`), so the mouth centre's base is at `z = 0`;
//! * `chin(y)`: a `cos^2` bump of height `chin_protrusion` centred at `y = -0.75 height_below`,
//!   half-width `0.33 height_below` (the flat stretch between it and the lower lip reads as
//!   the mentolabial sulcus);
//! * `lip(x, v) = lip_protrusion env(x) L(v)`, `v` the height above the (tilted) mouth line:
//!   `L = 1` across the saliva strip and falls as `cos^2` to 0 at the lip's thickness
//!   (`upper_lip_thickness` above, `lower_lip_thickness` below: the height of each lip), and
//!   `env(x) = cos^2(pi x / (1.2 mouth_width))`, so the lips fade out just beyond the corners.
//!
//! # Topology
//!
//! A structured grid: `nm` columns between the mouth corners `x = -+mouth_width/2`, `ns` on
//! each side beyond them; `rows_below` rows under the mouth line, one saliva row, `rows_above`
//! rows over it. Row heights grow away from the mouth (first row 0.6 of the side's mean, last
//! 1.4). The middle row is `saliva_thickness` high between the corners: the `saliva` quads.
//! Beyond the corners the same row is tissue (`upper_face`): the lips join there, and its
//! height grows over three columns to the lateral column width, so those elements are not
//! slivers. A tilted mouth line moves the rows by `tan(mouth_tilt) x` (`x` clamped to the
//! corners), blended to zero at the upper and lower edges.
//!
//! Every quad is extruded straight back (`Direction::Fixed([0, 0, -1])`) by
//! `tissue_thickness`: the surface is a height field over `x, y` with every quad a convex
//! trapezoid in projection, so **every hexahedron is valid at every resolution, tilt and
//! asymmetry** (a normal offset would invert the lips: their convex radius of curvature,
//! ~3 mm, is smaller than the tissue thickness). The same mesh comes out of
//! `extrude_with(&surface, &|_| tissue_thickness, Direction::Fixed([0, 0, -1]))` on the
//! written OBJ. Extruding along `z` keeps `x, y`, so each saliva element has the same
//! `saliva_thickness` in `y` all through its depth: it is thin across the lips, its local
//! thin axis is `+y` ([`MouthModel::saliva_across`]).
//!
//! Node numbering: surface vertex `(i, r)` (column `i` from `-x`, vertex row `r` from the
//! bottom) is node `r (ncols + 1) + i`; its offset (inner) copy is that plus
//! [`MouthModel::inner_offset`].
//!
//! # Anatomy (defaults)
//!
//! * `skull` (to be fixed): the upper edge (below the nose) and the lateral edges from the
//!   mouth line up (`y >= skull_lateral_from`), both layers.
//! * `jaw` (to follow the jaw's rotation): every node with `y <= jaw_level` (-25 mm: the
//!   chin and the lower edge, both layers; the lower lip above it is free).
//! * Jaw hinge: the temporomandibular joints' axis, horizontal left-right (`+x`) through
//!   `hinge_point = (0, 0.030, -0.080)`: 30 mm above the mouth line, 80 mm behind the mouth
//!   centre's base (85 mm behind the lips' front). A **positive** angle about `+x` opens the
//!   mouth (the chin moves down and back).
//! * Muscles (linear vector muscles, [`Muscle`]), left and right: depressor labii inferioris,
//!   depressor anguli oris, levator labii superioris, zygomaticus major. Each axis runs at
//!   mid-depth of the tissue, between anchor points given in the face's `(x, y)` (see
//!   [`muscle_anchors`]); insertions in the lips follow the tilted mouth line. The radius
//!   is `sqrt(muscle_reach^2 + (tissue_thickness/2)^2)`, so the cylinder takes the skin and
//!   inner nodes within `muscle_reach` of the axis's trace on the face. Activation 0:
//!   placeholders for the scenarios.

use super::extrude::{extrude_with, Direction};
use super::Mesh;
use crate::boundary::{Fixed, LoadCurve, LoadShape, PrescribedRotation};
use crate::error::{Error, Result};
use crate::mesh::surface::QuadSurface;
use crate::muscle::Muscle;
use std::f64::consts::FRAC_PI_2;

/// Parameters of the procedural mouth (SI metres, radians). Every field has a default
/// (serde `default`): an empty TOML table gives the default mouth.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MouthParams {
    /// Distance between the mouth corners (m).
    pub mouth_width: f64,
    /// Width of the face patch (m); the lateral edges are at `+-face_width / 2`.
    pub face_width: f64,
    /// From the mouth line up to the upper edge, below the nose (m).
    pub height_above: f64,
    /// From the mouth line down to the lower edge, under the chin (m).
    pub height_below: f64,
    /// Radius of the face's curvature around a vertical axis (m).
    pub face_radius: f64,
    /// Height of the upper lip (m): the lip's bulge fades out this far above the mouth line.
    pub upper_lip_thickness: f64,
    /// Height of the lower lip (m).
    pub lower_lip_thickness: f64,
    /// How far the lips stand out from the face at the mouth line's centre (m).
    pub lip_protrusion: f64,
    /// How far the chin stands out (m).
    pub chin_protrusion: f64,
    /// Height of the saliva strip between the lips (m): the saliva elements' thickness.
    pub saliva_thickness: f64,
    /// Depth of the extruded tissue layer (m).
    pub tissue_thickness: f64,
    /// Quad columns across the face at resolution 1.
    pub columns: usize,
    /// Quad rows below the saliva row at resolution 1.
    pub rows_below: usize,
    /// Quad rows above the saliva row at resolution 1.
    pub rows_above: usize,
    /// Multiplies the number of quads (each direction by its square root). 1: close to the
    /// paper's model (3420 hexahedra, 7084 nodes); 300: about 1M hexahedra.
    pub resolution: f64,
    /// Tilt of the mouth line (rad); positive raises the subject's left corner (`+x`).
    pub mouth_tilt: f64,
    /// Lip thickness asymmetry: each lip's height is multiplied by `1 + a x / (mouth_width/2)`
    /// (clamped at the corners): positive makes the subject's left side fuller.
    pub lip_asymmetry: f64,
    /// Nodes with `y <= jaw_level` form the `jaw` set (m).
    pub jaw_level: f64,
    /// Lateral-edge nodes with `y >= skull_lateral_from` are in the `skull` set (m).
    pub skull_lateral_from: f64,
    /// A point on the jaw's hinge axis (m); the axis is `+x`.
    pub hinge_point: [f64; 3],
    /// Half-width of the strip of face nodes each muscle takes (m).
    pub muscle_reach: f64,
    /// Placeholder force of each muscle at full activation (N).
    pub muscle_strength: f64,
}

impl Default for MouthParams {
    fn default() -> Self {
        MouthParams {
            mouth_width: 0.05,
            face_width: 0.12,
            height_above: 0.020,
            height_below: 0.048,
            face_radius: 0.08,
            upper_lip_thickness: 0.009,
            lower_lip_thickness: 0.010,
            lip_protrusion: 0.005,
            chin_protrusion: 0.003,
            saliva_thickness: 0.0006,
            tissue_thickness: 0.012,
            columns: 76,
            rows_below: 30,
            rows_above: 14,
            resolution: 1.0,
            mouth_tilt: 0.0,
            lip_asymmetry: 0.0,
            jaw_level: -0.025,
            skull_lateral_from: 0.0,
            hinge_point: [0.0, 0.030, -0.080],
            muscle_reach: 0.0045,
            muscle_strength: 0.05,
        }
    }
}

/// Grid sizes after the resolution multiplier.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct MouthGrid {
    /// Quad columns between the corners (even).
    pub mouth_columns: usize,
    /// Quad columns on each side beyond the corners.
    pub side_columns: usize,
    pub rows_below: usize,
    pub rows_above: usize,
}

impl MouthGrid {
    pub fn columns(&self) -> usize {
        self.mouth_columns + 2 * self.side_columns
    }
    /// Quad rows, the saliva row included.
    pub fn rows(&self) -> usize {
        self.rows_below + self.rows_above + 1
    }
    pub fn quads(&self) -> usize {
        self.columns() * self.rows()
    }
    pub fn vertices(&self) -> usize {
        (self.columns() + 1) * (self.rows() + 1)
    }
    /// Vertex row of the lower lip's inner surface (the saliva row's lower edge).
    pub fn lower_lip_row(&self) -> usize {
        self.rows_below
    }
    /// Column of the right corner (`-x`); the left corner is `side_columns + mouth_columns`.
    pub fn right_corner(&self) -> usize {
        self.side_columns
    }
}

/// The error of field `prefix` + `field` of `file`.
fn field_error(file: &str, prefix: &str, field: &str, msg: String) -> Result<()> {
    Err(Error::field(file, format!("{prefix}{field}"), msg))
}

impl MouthParams {
    /// Checks the parameters; errors name `file` and the field, as `prefix` + its name
    /// (`mesh.mouth.` in a scenario).
    pub fn validate(&self, file: &str, prefix: &str) -> Result<()> {
        self.check_values(file, prefix)?;
        self.check_proportions(file, prefix)?;
        self.check_lips(file, prefix)?;
        self.check_levels(file, prefix)
    }

    /// Checks that every value is finite, the sizes positive, the protrusions and the muscles'
    /// strength not negative.
    fn check_values(&self, file: &str, prefix: &str) -> Result<()> {
        let err = |field: &str, msg: String| field_error(file, prefix, field, msg);
        let positive = [
            ("mouth_width", self.mouth_width),
            ("face_width", self.face_width),
            ("height_above", self.height_above),
            ("height_below", self.height_below),
            ("face_radius", self.face_radius),
            ("upper_lip_thickness", self.upper_lip_thickness),
            ("lower_lip_thickness", self.lower_lip_thickness),
            ("saliva_thickness", self.saliva_thickness),
            ("tissue_thickness", self.tissue_thickness),
            ("resolution", self.resolution),
            ("muscle_reach", self.muscle_reach),
        ];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return err(name, format!("must be positive and finite, got {v}"));
            }
        }
        for (name, v) in [
            ("lip_protrusion", self.lip_protrusion),
            ("chin_protrusion", self.chin_protrusion),
            ("muscle_strength", self.muscle_strength),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return err(name, format!("must be non-negative and finite, got {v}"));
            }
        }
        for (name, v) in [
            ("mouth_tilt", self.mouth_tilt),
            ("lip_asymmetry", self.lip_asymmetry),
            ("jaw_level", self.jaw_level),
            ("skull_lateral_from", self.skull_lateral_from),
        ] {
            if !v.is_finite() {
                return err(name, format!("must be finite, got {v}"));
            }
        }
        if !self.hinge_point.iter().all(|v| v.is_finite()) {
            return err(
                "hinge_point",
                format!("must be finite, got {:?}", self.hinge_point),
            );
        }
        Ok(())
    }

    /// Checks the mouth's width and the face's radius against the face's width, the grid's
    /// least sizes, and the model's size against the memory.
    fn check_proportions(&self, file: &str, prefix: &str) -> Result<()> {
        let err = |field: &str, msg: String| field_error(file, prefix, field, msg);
        if self.mouth_width >= 0.9 * self.face_width {
            return err(
                "mouth_width",
                format!(
                    "{} leaves no tissue beside the corners: it must be below 0.9 face_width ({})",
                    self.mouth_width, self.face_width
                ),
            );
        }
        if self.face_radius <= 0.55 * self.face_width {
            return err(
                "face_radius",
                format!(
                    "{} is too small for face_width {}: it must exceed 0.55 face_width (the patch would wrap past the sides)",
                    self.face_radius, self.face_width
                ),
            );
        }
        if self.columns < 4 || self.rows_below < 1 || self.rows_above < 1 {
            return err(
                "columns",
                format!(
                    "need at least 4 columns and 1 row on each side, got {} columns, {} rows below, {} above",
                    self.columns, self.rows_below, self.rows_above
                ),
            );
        }
        // the model's size, in floats (no cast can saturate) and against the memory
        let f = self.resolution.sqrt();
        let (nodes, elements) = super::budget::extruded_grid_counts(
            self.columns as f64 * f,
            (self.rows_below + self.rows_above + 1) as f64 * f,
        );
        super::budget::check(file, &format!("{prefix}resolution"), nodes, elements)?;
        Ok(())
    }

    /// Checks the lips' asymmetry, and that each lip, thinned or thickened by it, is thicker
    /// than twice the saliva layer and fits in its side of the face.
    fn check_lips(&self, file: &str, prefix: &str) -> Result<()> {
        let err = |field: &str, msg: String| field_error(file, prefix, field, msg);
        if !(self.lip_asymmetry.abs() < 0.8) {
            return err(
                "lip_asymmetry",
                format!("{} must be within (-0.8, 0.8)", self.lip_asymmetry),
            );
        }
        let thin = 1.0 - self.lip_asymmetry.abs();
        for (name, t, room) in [
            (
                "upper_lip_thickness",
                self.upper_lip_thickness,
                self.height_above,
            ),
            (
                "lower_lip_thickness",
                self.lower_lip_thickness,
                0.42 * self.height_below,
            ),
        ] {
            if t * thin <= 2.0 * self.saliva_thickness {
                return err(
                    name,
                    format!(
                        "{t} (x {thin} with the asymmetry) must exceed twice the saliva thickness {}",
                        self.saliva_thickness
                    ),
                );
            }
            if t * (1.0 + self.lip_asymmetry.abs()) >= room {
                return err(
                    name,
                    format!("{t} (with the asymmetry) does not fit: it must stay below {room}"),
                );
            }
        }
        Ok(())
    }

    /// Checks the mouth's tilt, and that the jaw's level and the skull's lateral hold lie
    /// between the lips and the face's edges.
    fn check_levels(&self, file: &str, prefix: &str) -> Result<()> {
        let err = |field: &str, msg: String| field_error(file, prefix, field, msg);
        // The tilted mouth line must leave the rows in order: w tan|tilt| < 0.8 height_above.
        if !(self.mouth_tilt.abs() < 0.5)
            || self.mouth_width * self.mouth_tilt.abs().tan()
                >= 0.8 * self.height_above.min(self.height_below)
        {
            return err(
                "mouth_tilt",
                format!(
                    "{} rad is too steep: |tan(tilt)| mouth_width must stay below 0.8 height_above",
                    self.mouth_tilt
                ),
            );
        }
        let corner_drop = 0.5 * self.mouth_width * self.mouth_tilt.abs().tan();
        if !(self.jaw_level > -self.height_below
            && self.jaw_level
                < -(self.lower_lip_thickness * (1.0 + self.lip_asymmetry.abs()) + corner_drop))
        {
            return err(
                "jaw_level",
                format!(
                    "{} must lie between the lower edge ({}) and the bottom of the lower lip",
                    self.jaw_level, -self.height_below
                ),
            );
        }
        if !(self.skull_lateral_from > self.jaw_level
            && self.skull_lateral_from < self.height_above)
        {
            return err(
                "skull_lateral_from",
                format!(
                    "{} must lie between jaw_level ({}) and the upper edge ({})",
                    self.skull_lateral_from, self.jaw_level, self.height_above
                ),
            );
        }
        Ok(())
    }

    /// Grid sizes after the resolution multiplier.
    pub fn grid(&self) -> MouthGrid {
        let f = self.resolution.max(0.0).sqrt();
        let cols = self.columns as f64 * f;
        let mouth_columns =
            (2.0 * (0.5 * cols * self.mouth_width / self.face_width).round()).max(2.0) as usize;
        let side_columns = ((0.5 * (cols - mouth_columns as f64)).round()).max(1.0) as usize;
        MouthGrid {
            mouth_columns,
            side_columns,
            rows_below: ((self.rows_below as f64 * f).round() as usize).max(1),
            rows_above: ((self.rows_above as f64 * f).round() as usize).max(1),
        }
    }

    /// The resolution multiplier that gives about `hexahedra` elements.
    pub fn resolution_for(&self, hexahedra: usize) -> f64 {
        let c = self.columns as f64;
        let r = (self.rows_below + self.rows_above) as f64;
        // c f (r f + 1) = n
        let f = (-c + (c * c + 4.0 * c * r * hexahedra as f64).sqrt()) / (2.0 * c * r);
        f * f
    }
}

/// Row-spacing law on `[0, 1]`: first interval `A` times the mean, last `2 - A`.
fn grade(xi: f64) -> f64 {
    const A: f64 = 0.6;
    xi * (A + (1.0 - A) * xi)
}

fn cos2_bump(u: f64) -> f64 {
    if u.abs() >= 1.0 {
        0.0
    } else {
        let c = (FRAC_PI_2 * u).cos();
        c * c
    }
}

/// The analytic face (see the module docs).
struct Shape<'a> {
    p: &'a MouthParams,
}

impl Shape<'_> {
    /// Height of the mouth line at `x`.
    fn mouth_line(&self, x: f64) -> f64 {
        let h = 0.5 * self.p.mouth_width;
        self.p.mouth_tilt.tan() * x.clamp(-h, h)
    }
    /// Weight of the mouth line's tilt at height `v` above it: 1 in the middle, 0 at the edges.
    fn tilt_weight(&self, v: f64) -> f64 {
        let (a, b) = (self.p.height_above, self.p.height_below);
        if v > 0.5 * a {
            (2.0 * (a - v) / a).clamp(0.0, 1.0)
        } else if v < -0.5 * b {
            (2.0 * (b + v) / b).clamp(0.0, 1.0)
        } else {
            1.0
        }
    }
    fn y(&self, x: f64, v: f64) -> f64 {
        v + self.mouth_line(x) * self.tilt_weight(v)
    }
    fn lip_height(&self, x: f64, upper: bool) -> f64 {
        let h = 0.5 * self.p.mouth_width;
        let t = if upper {
            self.p.upper_lip_thickness
        } else {
            self.p.lower_lip_thickness
        };
        t * (1.0 + self.p.lip_asymmetry * (x / h).clamp(-1.0, 1.0))
    }
    fn z(&self, x: f64, y: f64, v: f64) -> f64 {
        let p = self.p;
        let r = p.face_radius;
        let cyl = (r * r - x * x).max(0.0).sqrt() - r;
        let yc = -0.75 * p.height_below;
        let hc = 0.33 * p.height_below;
        let chin = p.chin_protrusion * cos2_bump((y - yc) / hc);
        let env = cos2_bump(x / (0.6 * p.mouth_width));
        let s2 = 0.5 * p.saliva_thickness;
        let t = self.lip_height(x, v >= 0.0);
        let u = ((v.abs() - s2) / (t - s2)).clamp(0.0, 1.0);
        cyl + chin + p.lip_protrusion * env * cos2_bump(u)
    }
    /// The skin point at face coordinates `(x, y)` (`y` absolute).
    fn skin(&self, x: f64, y: f64) -> [f64; 3] {
        let v = y - self.mouth_line(x);
        [x, y, self.z(x, y, v)]
    }
}

/// The generated model.
#[derive(Clone, Debug)]
pub struct MouthModel {
    pub params: MouthParams,
    pub grid: MouthGrid,
    /// The hexahedral mesh; element sets `upper_face`, `lower_face`, `saliva` (the
    /// surface's groups), `tissue_upper`, `tissue_lower` (the same as the first two), `tissue`
    /// (both); node sets `surface`, `inner`, `skull`, `jaw`, `upper_lip_inner`,
    /// `lower_lip_inner`, `upper_edge`, `lower_edge`, `lateral_edges`.
    pub mesh: Mesh,
    /// The quad surface it was extruded from (write it with `io::obj::write_obj`).
    pub surface: QuadSurface,
    /// The jaw's hinge: a point on the axis and the axis (unit, `+x`; a positive rotation
    /// opens the mouth).
    pub jaw_hinge: ([f64; 3], [f64; 3]),
    pub muscles: Vec<Muscle>,
    /// Per vertex column of the saliva strip, corners included, from the right corner (`-x`)
    /// to the left: `(x, upper lip node, lower lip node)`, the skin (surface) nodes facing
    /// each other across the strip. Add [`MouthModel::inner_offset`] for the inner nodes.
    pub saliva_columns: Vec<(f64, u32, u32)>,
    /// Node `n` of the surface has its inner copy at `n + inner_offset`.
    pub inner_offset: u32,
    /// The saliva elements' local y axis (across the strip, reference configuration): `+y`.
    /// The geometric detection (`material::saliva::across_direction`) finds it too while a
    /// column is wider than the strip is thick (resolution below about 6.8 with the
    /// defaults); above that, give this vector to the saliva material explicitly.
    pub saliva_across: [f64; 3],
}

impl MouthModel {
    /// The jaw's opening: a rotation of the `jaw` set about the hinge by `angle` (rad,
    /// positive opens) times `curve`.
    pub fn jaw_rotation(&self, angle: f64, curve: LoadCurve) -> PrescribedRotation {
        PrescribedRotation {
            nodes: self.mesh.node_sets["jaw"].clone(),
            point: self.jaw_hinge.0,
            axis: self.jaw_hinge.1,
            angle,
            curve,
        }
    }

    /// The `skull` set fixed in all three directions.
    pub fn skull_fixed(&self) -> Fixed {
        Fixed {
            nodes: self.mesh.node_sets["skull"].clone(),
            dofs: [true; 3],
        }
    }

    /// The lip gap at each saliva column for current node positions `x` (all nodes): the
    /// distance between the facing skin nodes minus its reference value (m). Zero at rest,
    /// positive where the lips have parted.
    /// What a scenario needs of the model ([`super::anatomy`]).
    pub fn anatomy(&self) -> super::anatomy::MouthAnatomy {
        super::anatomy::MouthAnatomy {
            source: "procedural mouth".into(),
            jaw_nodes: self.mesh.node_sets["jaw"].clone(),
            hinge: self.jaw_hinge,
            muscles: self.muscles.clone(),
            columns: crate::measures::LipColumns {
                x: self.saliva_columns.iter().map(|c| c.0).collect(),
                upper: self.saliva_columns.iter().map(|c| c.1).collect(),
                lower: self.saliva_columns.iter().map(|c| c.2).collect(),
                center: 0.0,
            },
            saliva_across: crate::material::saliva::AcrossAxis::Uniform(self.saliva_across),
        }
    }

    pub fn lip_gaps(&self, x: &[[f64; 3]]) -> Vec<f64> {
        let d = |a: &[f64; 3], b: &[f64; 3]| {
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
        };
        self.saliva_columns
            .iter()
            .map(|&(_, u, l)| {
                let (u, l) = (u as usize, l as usize);
                d(&x[u], &x[l]) - d(&self.mesh.nodes[u], &self.mesh.nodes[l])
            })
            .collect()
    }
}

/// Muscle anchor points on the face, for the subject's left side (`+x`; the right side is
/// mirrored): `(name, origin (x, y), insertion (x, y))`, `y` from the untilted mouth line.
/// Insertions (in the lips) follow the tilted mouth line; origins (on bone) do not. The
/// third coordinate is mid-depth of the tissue under that point.
pub fn muscle_anchors() -> [(&'static str, [f64; 2], [f64; 2]); 4] {
    [
        // From the mandible beside the chin to the lower lip: pulls the lower lip down.
        (
            "depressor_labii_inferioris",
            [0.017, -0.040],
            [0.009, -0.005],
        ),
        // From the mandible's lower edge to the corner of the mouth: pulls the corner down.
        ("depressor_anguli_oris", [0.036, -0.044], [0.025, -0.002]),
        // From the maxilla below the orbit (above the patch) to the upper lip: raises it.
        ("levator_labii_superioris", [0.017, 0.040], [0.010, 0.005]),
        // From the zygomatic bone to the corner: pulls the corner up and out (a smile).
        ("zygomaticus_major", [0.058, 0.036], [0.026, 0.002]),
    ]
}

/// The quad surface of the mouth (groups `upper_face`, `lower_face`, `saliva`), with
/// texture coordinates `u = (x + W/2) / W`, `v = (y + height_below) / (height_above + height_below)`.
pub fn generate_surface(p: &MouthParams) -> Result<QuadSurface> {
    const FILE: &str = "mouth parameters";
    p.validate(FILE, "")?;
    let g = p.grid();
    let shape = Shape { p };
    let (nm, ns, rb, ra) = (g.mouth_columns, g.side_columns, g.rows_below, g.rows_above);
    let nc = g.columns();
    let nr = g.rows(); // quad rows; vertex rows 0..=nr
    let half_w = 0.5 * p.face_width;
    let half_m = 0.5 * p.mouth_width;
    let side_dx = (half_w - half_m) / ns as f64;
    let xs: Vec<f64> = (0..=nc)
        .map(|i| {
            if i <= ns {
                -half_w + side_dx * i as f64
            } else if i <= ns + nm {
                -half_m + p.mouth_width * (i - ns) as f64 / nm as f64
            } else {
                half_m + side_dx * (i - ns - nm) as f64
            }
        })
        .collect();
    // Half-height of the saliva row per column: s/2 between the corners, growing to half the
    // lateral column width (at least s/2) over three columns beyond them.
    let s = p.saliva_thickness;
    let joined = s.max(side_dx);
    let half_row: Vec<f64> = (0..=nc)
        .map(|i| {
            let k = if i < ns {
                ns - i
            } else if i > ns + nm {
                i - ns - nm
            } else {
                0
            };
            let t = (k as f64 / 3.0).min(1.0);
            0.5 * (s + (joined - s) * t * t * (3.0 - 2.0 * t))
        })
        .collect();
    let nv = (nc + 1) * (nr + 1);
    let mut vertices = Vec::with_capacity(nv);
    let mut uv = Vec::with_capacity(nv);
    let (a, b) = (p.height_above, p.height_below);
    for r in 0..=nr {
        for i in 0..=nc {
            let (x, h) = (xs[i], half_row[i]);
            let v = if r <= rb {
                -(h + (b - h) * grade((rb - r) as f64 / rb as f64))
            } else {
                h + (a - h) * grade((r - rb - 1) as f64 / ra as f64)
            };
            let y = shape.y(x, v);
            vertices.push([x, y, shape.z(x, y, v)]);
            uv.push([(x + half_w) / p.face_width, (y + b) / (a + b)]);
        }
    }
    let id = |i: usize, r: usize| (r * (nc + 1) + i) as u32;
    let mut quads = Vec::with_capacity(g.quads());
    let mut group_of_quad = Vec::with_capacity(g.quads());
    for r in 0..nr {
        for i in 0..nc {
            quads.push([id(i, r), id(i + 1, r), id(i + 1, r + 1), id(i, r + 1)]);
            // Group indices in order of first appearance (lower_face, upper_face, saliva), so
            // the OBJ read back numbers them the same.
            let group = if r < rb {
                0
            } else if r > rb || i < ns || i >= ns + nm {
                1
            } else {
                2
            };
            group_of_quad.push(group);
        }
    }
    Ok(QuadSurface {
        vertices,
        uv: Some(uv),
        quads,
        group_of_quad,
        groups: vec!["lower_face".into(), "upper_face".into(), "saliva".into()],
        quad_lines: Vec::new(),
        notes: Vec::new(),
    })
}

/// The mouth model: the surface, extruded, with its node sets, jaw hinge and muscles.
pub fn generate(p: &MouthParams) -> Result<MouthModel> {
    const FILE: &str = "mouth parameters";
    let surface = generate_surface(p)?;
    let g = p.grid();
    let mut mesh = extrude_with(
        &surface,
        &|_| p.tissue_thickness,
        Direction::Fixed([0.0, 0.0, -1.0]),
        FILE,
    )?;
    let nc = g.columns();
    let nr = g.rows();
    let nv = surface.vertices.len() as u32;
    debug_assert_eq!(mesh.nodes.len(), 2 * nv as usize);
    let id = |i: usize, r: usize| (r * (nc + 1) + i) as u32;
    let both = |set: &mut Vec<u32>| {
        let n = set.len();
        for k in 0..n {
            set.push(set[k] + nv);
        }
        set.sort_unstable();
    };

    let mut upper_edge: Vec<u32> = (0..=nc).map(|i| id(i, nr)).collect();
    let mut lower_edge: Vec<u32> = (0..=nc).map(|i| id(i, 0)).collect();
    let mut lateral: Vec<u32> = (0..=nr).flat_map(|r| [id(0, r), id(nc, r)]).collect();
    let y = |n: u32| surface.vertices[n as usize][1];
    let mut skull: Vec<u32> = upper_edge
        .iter()
        .copied()
        .chain(
            lateral
                .iter()
                .copied()
                .filter(|&n| y(n) >= p.skull_lateral_from),
        )
        .collect();
    skull.sort_unstable();
    skull.dedup();
    let mut jaw: Vec<u32> = (0..nv).filter(|&n| y(n) <= p.jaw_level).collect();
    let (c0, c1) = (g.right_corner(), g.right_corner() + g.mouth_columns);
    let lo = g.lower_lip_row();
    let mut upper_lip: Vec<u32> = (c0..=c1).map(|i| id(i, lo + 1)).collect();
    let mut lower_lip: Vec<u32> = (c0..=c1).map(|i| id(i, lo)).collect();
    let saliva_columns: Vec<(f64, u32, u32)> = (c0..=c1)
        .map(|i| {
            (
                surface.vertices[id(i, lo) as usize][0],
                id(i, lo + 1),
                id(i, lo),
            )
        })
        .collect();
    for set in [
        &mut upper_edge,
        &mut lower_edge,
        &mut lateral,
        &mut skull,
        &mut jaw,
        &mut upper_lip,
        &mut lower_lip,
    ] {
        both(set);
    }
    let ns = &mut mesh.node_sets;
    ns.insert("upper_edge".into(), upper_edge);
    ns.insert("lower_edge".into(), lower_edge);
    ns.insert("lateral_edges".into(), lateral);
    ns.insert("skull".into(), skull);
    ns.insert("jaw".into(), jaw);
    ns.insert("upper_lip_inner".into(), upper_lip);
    ns.insert("lower_lip_inner".into(), lower_lip);
    let es = &mut mesh.element_sets;
    let up = es["upper_face"].clone();
    let low = es["lower_face"].clone();
    let mut tissue: Vec<u32> = up.iter().chain(low.iter()).copied().collect();
    tissue.sort_unstable();
    es.insert("tissue_upper".into(), up);
    es.insert("tissue_lower".into(), low);
    es.insert("tissue".into(), tissue);

    let shape = Shape { p };
    let depth = 0.5 * p.tissue_thickness;
    let radius = (p.muscle_reach.powi(2) + depth * depth).sqrt();
    let mut muscles = Vec::new();
    for (name, o, ins) in muscle_anchors() {
        for (side, sign) in [("l", 1.0), ("r", -1.0)] {
            let at = |x: f64, y: f64| {
                let s = shape.skin(x, y);
                [s[0], s[1], s[2] - depth]
            };
            let xi = sign * ins[0];
            muscles.push(Muscle {
                name: format!("{name}_{side}"),
                origin: at(sign * o[0], o[1]),
                insertion: at(xi, ins[1] + shape.mouth_line(xi)),
                radius,
                strength: p.muscle_strength,
                activation: 0.0,
                curve: LoadCurve {
                    shape: LoadShape::SmoothStep,
                    start: 0.0,
                    duration: 0.1,
                },
            });
        }
    }
    Ok(MouthModel {
        params: p.clone(),
        grid: g,
        mesh,
        surface,
        jaw_hinge: (p.hinge_point, [1.0, 0.0, 0.0]),
        muscles,
        saliva_columns,
        inner_offset: nv,
        saliva_across: [0.0, 1.0, 0.0],
    })
}

/// Per-element material code for output, by group name: 0 `upper_face`, 1 `lower_face`,
/// 2 `saliva` (the paper's Fig. 2 colours blue, red, green), 3 any other group.
pub fn material_codes(surface: &QuadSurface) -> Vec<i32> {
    let code: Vec<i32> = surface
        .groups
        .iter()
        .map(|g| match g.as_str() {
            "upper_face" => 0,
            "lower_face" => 1,
            "saliva" => 2,
            _ => 3,
        })
        .collect();
    surface
        .group_of_quad
        .iter()
        .map(|&g| code[g as usize])
        .collect()
}

/// [`material_codes`] of the model's surface (element `e` is quad `e`).
pub fn material_of_elements(model: &MouthModel) -> Vec<i32> {
    material_codes(&model.surface)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::hex8;
    use crate::material::saliva::across_direction;

    fn check_model(m: &MouthModel) {
        m.mesh.validate("mouth").unwrap();
        let sal = &m.mesh.element_sets["saliva"];
        assert_eq!(sal.len(), m.grid.mouth_columns);
        let s = m.params.saliva_thickness;
        for &e in sal {
            let x = m.mesh.element_coords(e as usize);
            let (dmin, _) = hex8::min_corner_jacobian(&x);
            assert!(dmin > 0.0);
            // Thin across the lips: the y extent is the saliva thickness at every edge.
            for (a, b) in [(0, 1), (3, 2), (4, 5), (7, 6)] {
                let d = [x[b][0] - x[a][0], x[b][1] - x[a][1], x[b][2] - x[a][2]];
                let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                assert!(
                    (len - s).abs() < 1e-6 * s + 0.02 * s,
                    "saliva edge {len} vs {s}"
                );
                assert!(d[1].abs() > 0.99 * len);
            }
        }
        let skull = &m.mesh.node_sets["skull"];
        let jaw = &m.mesh.node_sets["jaw"];
        assert!(!skull.is_empty() && !jaw.is_empty());
        assert!(
            skull.iter().all(|n| jaw.binary_search(n).is_err()),
            "skull and jaw overlap"
        );
        for mu in &m.muscles {
            let n = mu.select_nodes(&m.mesh.nodes).len();
            assert!(n >= 6, "muscle {} selects {n} nodes", mu.name);
        }
    }

    #[test]
    fn default_mouth_matches_the_paper_counts_and_is_valid() {
        let p = MouthParams::default();
        let m = generate(&p).unwrap();
        let (ne, nn) = (m.mesh.elements.len() as f64, m.mesh.nodes.len() as f64);
        assert!((ne / 3414.0 - 1.0).abs() < 0.15, "{ne} hexahedra");
        assert!((nn / 6982.0 - 1.0).abs() < 0.15, "{nn} nodes");
        assert_eq!(ne as usize, 3420);
        assert_eq!(nn as usize, 7084);
        check_model(&m);
        // Geometric detection of the thin axis agrees with saliva_across.
        for &e in &m.mesh.element_sets["saliva"] {
            let a = across_direction(&m.mesh.element_coords(e as usize));
            assert!(a[1].abs() > 0.999, "{a:?}");
        }
        // The saliva columns span the mouth from corner to corner.
        let c = &m.saliva_columns;
        assert_eq!(c.len(), m.grid.mouth_columns + 1);
        assert!((c[0].0 + 0.025).abs() < 1e-12 && (c[c.len() - 1].0 - 0.025).abs() < 1e-12);
        assert!(c.windows(2).all(|w| w[1].0 > w[0].0));
        for &(_, u, l) in c {
            let (xu, xl) = (m.mesh.nodes[u as usize], m.mesh.nodes[l as usize]);
            assert!((xu[1] - xl[1] - p.saliva_thickness).abs() < 1e-12);
            assert!(m.mesh.node_sets["upper_lip_inner"]
                .binary_search(&u)
                .is_ok());
            assert!(m.mesh.node_sets["lower_lip_inner"]
                .binary_search(&l)
                .is_ok());
        }
        assert!(m.lip_gaps(&m.mesh.nodes).iter().all(|g| g.abs() < 1e-15));
        // Material sets partition the elements.
        let es = &m.mesh.element_sets;
        assert_eq!(
            es["tissue"].len() + es["saliva"].len(),
            m.mesh.elements.len()
        );
        assert_eq!(es["tissue_upper"], es["upper_face"]);
        // The jaw opens with a positive angle: the chin moves down.
        let rot = m.jaw_rotation(
            0.1,
            LoadCurve {
                shape: LoadShape::Step,
                start: 0.0,
                duration: 1.0,
            },
        );
        // The skin node of the jaw set nearest the chin's front (0, -0.035).
        let chin = *rot
            .nodes
            .iter()
            .filter(|&&n| n < m.inner_offset)
            .min_by(|&&a, &&b| {
                let d = |n: u32| {
                    let x = m.mesh.nodes[n as usize];
                    x[0].powi(2) + (x[1] + 0.035).powi(2)
                };
                d(a).total_cmp(&d(b))
            })
            .unwrap();
        let u = rot.displacement(&m.mesh.nodes[chin as usize], 1.0, true);
        assert!(u[1] < -0.007 && u[2] < -0.005, "{u:?}");
        assert_eq!(m.muscles.len(), 8);
        // The surface written by the generator extrudes to the same mesh.
        let again = super::super::extrude::extrude_with(
            &m.surface,
            &|_| p.tissue_thickness,
            Direction::Fixed([0.0, 0.0, -1.0]),
            "again",
        )
        .unwrap();
        assert_eq!(again.nodes, m.mesh.nodes);
        assert_eq!(again.elements, m.mesh.elements);
    }

    /// Table 1's time step is stable on the default mouth with Table 1's materials, damping
    /// and hourglass coefficient, skull fixed and jaw prescribed.
    #[test]
    fn table_1_time_step_is_stable() {
        use crate::boundary::BoundaryConditions;
        use crate::problem::{table1, Numerics, Physics, Problem, TimeSettings};
        use crate::tled::precompute::Discretisation;
        use crate::tled::stability::analyse;
        let m = generate(&MouthParams::default()).unwrap();
        let element_material: Vec<u32> = m
            .surface
            .group_of_quad
            .iter()
            .map(|&g| if g == 2 { 1 } else { 0 })
            .collect();
        let bc = BoundaryConditions {
            fixed: vec![m.skull_fixed()],
            rotations: vec![m.jaw_rotation(
                0.1,
                LoadCurve {
                    shape: LoadShape::SmoothStep,
                    start: 0.0,
                    duration: 0.5,
                },
            )],
            ..Default::default()
        };
        let p = Problem {
            source: "mouth".into(),
            mesh: m.mesh.clone(),
            materials: vec![table1::TISSUE.spec("tissue"), table1::SALIVA.spec("saliva")],
            element_material,
            bc,
            time: TimeSettings {
                dt: table1::TIME_STEP,
                total_time: table1::TOTAL_TIME,
                output_every: table1::OUTPUT_EVERY,
            },
            numerics: Numerics {
                damping: table1::DAMPING,
                ..Default::default()
            },
            additive_constraints: false,
            physics: Physics::default(),
        };
        p.validate().unwrap();
        let d = Discretisation::new(&p);
        let r = analyse(&p, &d);
        eprintln!(
            "critical dt {:.3e} s (element estimate {:.3e} s at element {})",
            r.critical_time_step, r.element_estimate, r.limiting_element
        );
        assert!(r.critical_time_step > table1::TIME_STEP);
    }

    #[test]
    fn asymmetric_and_coarse_and_fine_mouths_are_valid() {
        for (res, tilt, asym) in [
            (0.25, 0.0, 0.0),
            (1.0, 0.15, 0.3),
            (1.0, -0.2, -0.5),
            (4.0, 0.1, 0.2),
            (0.1, 0.1, 0.0),
        ] {
            let p = MouthParams {
                resolution: res,
                mouth_tilt: tilt,
                lip_asymmetry: asym,
                ..Default::default()
            };
            let m = generate(&p).unwrap_or_else(|e| panic!("{res} {tilt} {asym}: {e}"));
            check_model(&m);
        }
    }

    #[test]
    fn bad_parameters_name_the_field() {
        let p = MouthParams {
            saliva_thickness: -1.0,
            ..Default::default()
        };
        let e = generate(&p).unwrap_err().to_string();
        assert!(e.contains("saliva_thickness"), "{e}");
        let p = MouthParams {
            mouth_tilt: 0.45,
            ..Default::default()
        };
        assert!(generate(&p).unwrap_err().to_string().contains("mouth_tilt"));
        let p = MouthParams {
            jaw_level: 0.01,
            ..Default::default()
        };
        assert!(generate(&p).unwrap_err().to_string().contains("jaw_level"));
        let p: MouthParams = toml::from_str("mouth_width = 0.045\n").unwrap();
        assert_eq!(p.mouth_width, 0.045);
        assert_eq!(p.columns, 76);
        assert!(toml::from_str::<MouthParams>("mouth_wdth = 0.045\n").is_err());
    }

    #[test]
    fn writes_obj_and_vtu_for_the_lead() {
        use crate::io::vtu::{write_vtu, DataArray, VtuFrame};
        let m = generate(&MouthParams::default()).unwrap();
        let dir = std::env::temp_dir();
        crate::io::obj::write_obj(&dir.join("mouth.obj"), &m.surface).unwrap();
        let back = crate::io::obj::read_obj(&dir.join("mouth.obj")).unwrap();
        assert_eq!(back.vertices, m.surface.vertices);
        assert_eq!(back.uv, m.surface.uv);
        assert_eq!(back.groups, m.surface.groups);
        assert_eq!(back.group_of_quad, m.surface.group_of_quad);
        // `sticky-lips extrude mouth.obj` (straight back by the tissue thickness) gives the
        // generator's mesh.
        let again = super::super::extrude::extrude_with(
            &back,
            &|_| 0.012,
            Direction::Fixed([0.0, 0.0, -1.0]),
            "mouth.obj",
        )
        .unwrap();
        assert_eq!(again.nodes, m.mesh.nodes);
        assert_eq!(again.elements, m.mesh.elements);
        for g in ["upper_face", "lower_face", "saliva"] {
            assert_eq!(again.element_sets[g], m.mesh.element_sets[g]);
        }
        // Along the normals instead, the lips' curvature (radius ~3 mm) inverts elements.
        let e = super::super::extrude::extrude(&back, &|_| 0.012, "mouth.obj")
            .unwrap_err()
            .to_string();
        assert!(e.contains("inverts"), "{e}");

        let mat = material_of_elements(&m);
        let mut marks = vec![0i32; m.mesh.nodes.len()];
        for &n in &m.mesh.node_sets["skull"] {
            marks[n as usize] = 1;
        }
        for &n in &m.mesh.node_sets["jaw"] {
            marks[n as usize] = 2;
        }
        for &n in m.mesh.node_sets["upper_lip_inner"]
            .iter()
            .chain(&m.mesh.node_sets["lower_lip_inner"])
        {
            marks[n as usize] = 3;
        }
        let frame = VtuFrame {
            points: &m.mesh.nodes,
            hexahedra: &m.mesh.elements,
            point_data: vec![DataArray::I32 {
                name: "boundary",
                components: 1,
                data: &marks,
            }],
            cell_data: vec![DataArray::I32 {
                name: "material",
                components: 1,
                data: &mat,
            }],
            time: None,
        };
        write_vtu(&dir.join("mouth.vtu"), &frame).unwrap();
    }

    #[test]
    fn resolution_for_a_million() {
        let p = MouthParams::default();
        let r = p.resolution_for(1_000_000);
        let q = MouthParams { resolution: r, ..p }.grid().quads();
        assert!((q as f64 / 1e6 - 1.0).abs() < 0.01, "{r} -> {q}");
    }

    /// About 1.4 s in the test profile on 2 cores (0.7 s to generate, 0.6 s to validate).
    #[test]
    fn a_million_hexahedra() {
        let p = MouthParams {
            resolution: 300.0,
            ..Default::default()
        };
        let t = std::time::Instant::now();
        let m = generate(&p).unwrap();
        let dt = t.elapsed().as_secs_f64();
        eprintln!(
            "generated {} hexahedra, {} nodes in {dt:.2} s",
            m.mesh.elements.len(),
            m.mesh.nodes.len()
        );
        assert!(m.mesh.elements.len() >= 1_000_000);
        let t = std::time::Instant::now();
        m.mesh.validate("mouth").unwrap();
        eprintln!("validated in {:.2} s", t.elapsed().as_secs_f64());
        for mu in &m.muscles {
            assert!(!mu.select_nodes(&m.mesh.nodes).is_empty());
        }
    }
}
