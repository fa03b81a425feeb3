//! Quad surfaces with material groups: what the paper's pipeline starts from (section 3.1:
//! a quad surface with its material regions marked, each quad extruded into a hexahedron by
//! [`crate::mesh::extrude`]). `io::obj` reads and writes them as Wavefront OBJ; the mesh
//! generators build them in code.

use crate::error::{Error, Location, Result};

/// A quad surface with material groups.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct QuadSurface {
    /// Vertex positions (file units; the crate's are metres).
    pub vertices: Vec<[f64; 3]>,
    /// Texture coordinates, one per vertex, when every used vertex has one.
    pub uv: Option<Vec<[f64; 2]>>,
    /// Quads as 0-based vertex indices, in the file's winding: the quad's normal (right-hand
    /// rule) is its outward side.
    pub quads: Vec<[u32; 4]>,
    /// Index into `groups` of each quad.
    pub group_of_quad: Vec<u32>,
    /// Group (material) names.
    pub groups: Vec<String>,
    /// 1-based line of each quad in the file it was read from; empty for generated surfaces.
    pub quad_lines: Vec<usize>,
    /// Remarks from reading that are not errors (UV seams, missing texture coordinates).
    pub notes: Vec<String>,
}

impl QuadSurface {
    /// Where quad `q` came from, for error messages.
    pub fn quad_location(&self, q: usize) -> Location {
        match self.quad_lines.get(q) {
            Some(&l) => Location::LineField(l, format!("quad {q}")),
            None => Location::Field(format!("quad {q}")),
        }
    }

    /// A short description of quad `q` ("line 12" or "quad 7").
    pub fn quad_name(&self, q: usize) -> String {
        match self.quad_lines.get(q) {
            Some(&l) => format!("line {l}"),
            None => format!("quad {q}"),
        }
    }

    /// Index of the group called `name`.
    pub fn group_index(&self, name: &str) -> Option<usize> {
        self.groups.iter().position(|g| g == name)
    }

    /// Consistency of the arrays (for surfaces built in code): lengths, index ranges,
    /// finite coordinates.
    pub fn validate(&self, file: &str) -> Result<()> {
        let nv = self.vertices.len();
        if self.group_of_quad.len() != self.quads.len() {
            return Err(Error::input(
                file,
                Location::None,
                format!(
                    "{} quads but {} group indices",
                    self.quads.len(),
                    self.group_of_quad.len()
                ),
            ));
        }
        if !self.quad_lines.is_empty() && self.quad_lines.len() != self.quads.len() {
            return Err(Error::input(
                file,
                Location::None,
                format!(
                    "{} quads but {} quad lines",
                    self.quads.len(),
                    self.quad_lines.len()
                ),
            ));
        }
        if let Some(uv) = &self.uv {
            if uv.len() != nv {
                return Err(Error::input(
                    file,
                    Location::None,
                    format!("{nv} vertices but {} texture coordinates", uv.len()),
                ));
            }
        }
        for (v, x) in self.vertices.iter().enumerate() {
            if !x.iter().all(|c| c.is_finite()) {
                return Err(Error::input(
                    file,
                    Location::Field(format!("vertex {}", v + 1)),
                    format!("non-finite coordinate {x:?}"),
                ));
            }
        }
        for (q, quad) in self.quads.iter().enumerate() {
            if let Some(&i) = quad.iter().find(|&&i| i as usize >= nv) {
                return Err(Error::input(
                    file,
                    self.quad_location(q),
                    format!(
                        "vertex index {} is out of range: there are {nv} vertices",
                        i + 1
                    ),
                ));
            }
            let g = self.group_of_quad[q] as usize;
            if g >= self.groups.len() {
                return Err(Error::input(
                    file,
                    self.quad_location(q),
                    format!(
                        "group index {g} is out of range: there are {} groups",
                        self.groups.len()
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// A surface of polygons (triangles, quads or more corners) as a user's mesh comes: what
/// `sticky-lips face` reads before it makes the surface all quads ([`PolySurface::to_quads`]),
/// and what the point caches play back (the user's own faces and vertex order).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PolySurface {
    /// Vertex positions (file units; the crate's are metres).
    pub vertices: Vec<[f64; 3]>,
    /// Texture coordinates, one per vertex, when every used vertex has one.
    pub uv: Option<Vec<[f64; 2]>>,
    /// Faces as 0-based vertex indices (at least 3), in the file's winding.
    pub faces: Vec<Vec<u32>>,
    /// Index into `groups` of each face.
    pub group_of_face: Vec<u32>,
    pub groups: Vec<String>,
    /// 1-based line of each face in the file it was read from; empty for generated ones.
    pub face_lines: Vec<usize>,
    /// Remarks from reading that are not errors.
    pub notes: Vec<String>,
}

/// A [`PolySurface`] made of quads: the surface itself where every face is a quad, else one
/// split of every face (below). Its first `input_vertices` vertices are the input's, in
/// order; each later vertex is the mean of the input vertices `parents[v - input_vertices]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Refined {
    pub surface: QuadSurface,
    pub input_vertices: usize,
    pub parents: Vec<Vec<u32>>,
}

impl Refined {
    /// A per-vertex quantity of the input carried onto every vertex of the refined surface:
    /// a new vertex gets the mean of its parents' values (each component).
    pub fn extend<const N: usize>(&self, values: &[[f64; N]]) -> Vec<[f64; N]> {
        let mut out = values.to_vec();
        for p in &self.parents {
            let mut m = [0.0; N];
            for &v in p {
                for k in 0..N {
                    m[k] += values[v as usize][k];
                }
            }
            let n = p.len() as f64;
            out.push(m.map(|x| x / n));
        }
        out
    }

    /// [`Refined::extend`] for one number per vertex.
    pub fn extend_scalar(&self, values: &[f64]) -> Vec<f64> {
        let v: Vec<[f64; 1]> = values.iter().map(|&x| [x]).collect();
        self.extend(&v).into_iter().map(|x| x[0]).collect()
    }
}

impl PolySurface {
    /// Consistency of the arrays: lengths, faces of three or more corners, index ranges,
    /// finite coordinates.
    pub fn validate(&self, file: &str) -> Result<()> {
        let nv = self.vertices.len();
        let at = |f: usize| match self.face_lines.get(f) {
            Some(&l) => Location::LineField(l, format!("face {f}")),
            None => Location::Field(format!("face {f}")),
        };
        if self.group_of_face.len() != self.faces.len() {
            return Err(Error::input(
                file,
                Location::None,
                format!(
                    "{} faces but {} group indices",
                    self.faces.len(),
                    self.group_of_face.len()
                ),
            ));
        }
        if let Some(uv) = &self.uv {
            if uv.len() != nv {
                return Err(Error::input(
                    file,
                    Location::None,
                    format!("{nv} vertices but {} texture coordinates", uv.len()),
                ));
            }
        }
        if let Some(v) = self
            .vertices
            .iter()
            .position(|x| !x.iter().all(|c| c.is_finite()))
        {
            return Err(Error::input(
                file,
                Location::Field(format!("vertex {}", v + 1)),
                format!("non-finite coordinate {:?}", self.vertices[v]),
            ));
        }
        for (k, f) in self.faces.iter().enumerate() {
            if f.len() < 3 {
                return Err(Error::input(
                    file,
                    at(k),
                    format!("a face needs at least 3 vertices, this one has {}", f.len()),
                ));
            }
            if let Some(&i) = f.iter().find(|&&i| i as usize >= nv) {
                return Err(Error::input(
                    file,
                    at(k),
                    format!(
                        "vertex index {} is out of range: there are {nv} vertices",
                        i + 1
                    ),
                ));
            }
            if self.group_of_face[k] as usize >= self.groups.len() {
                return Err(Error::input(
                    file,
                    at(k),
                    format!(
                        "group index {} is out of range: there are {} groups",
                        self.group_of_face[k],
                        self.groups.len()
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Every face a quad.
    pub fn is_quads(&self) -> bool {
        self.faces.iter().all(|f| f.len() == 4)
    }

    /// The quad surface as a polygon surface (same vertices, faces and groups).
    pub fn from_quads(s: &QuadSurface) -> PolySurface {
        PolySurface {
            vertices: s.vertices.clone(),
            uv: s.uv.clone(),
            faces: s.quads.iter().map(|q| q.to_vec()).collect(),
            group_of_face: s.group_of_quad.clone(),
            groups: s.groups.clone(),
            face_lines: s.quad_lines.clone(),
            notes: s.notes.clone(),
        }
    }

    /// The surface made of quads. Where every face is a quad, the surface as it is (no
    /// parents). Otherwise every face of `n` corners becomes `n` quads, one at each corner
    /// `c`: `c`, the midpoint of the edge after it, the face's centre (the mean of its
    /// corners) and the midpoint of the edge before it, in the face's winding, so a
    /// triangle becomes three quads and a quad four, and neighbouring faces still share
    /// their edges' midpoints (no T-junctions). This is one step of Catmull-Clark
    /// subdivision's topology without its smoothing: the surface's shape does not change.
    /// New vertices are numbered after the input's: the edge midpoints in the order their
    /// edges are first met (face by face, corner by corner), then the face centres in face
    /// order. Each new quad keeps its face's group and file line.
    pub fn to_quads(&self) -> Refined {
        let nv = self.vertices.len();
        if self.is_quads() {
            return Refined {
                surface: QuadSurface {
                    vertices: self.vertices.clone(),
                    uv: self.uv.clone(),
                    quads: self
                        .faces
                        .iter()
                        .map(|f| [f[0], f[1], f[2], f[3]])
                        .collect(),
                    group_of_quad: self.group_of_face.clone(),
                    groups: self.groups.clone(),
                    quad_lines: self.face_lines.clone(),
                    notes: self.notes.clone(),
                },
                input_vertices: nv,
                parents: Vec::new(),
            };
        }
        self.subdivided()
    }

    /// One split of every face (as [`PolySurface::to_quads`] does where a face is not a
    /// quad), also where all are quads: a quad becomes four.
    pub fn subdivided(&self) -> Refined {
        let nv = self.vertices.len();
        let mut parents: Vec<Vec<u32>> = Vec::new();
        let mut mid: std::collections::BTreeMap<(u32, u32), u32> = Default::default();
        for f in &self.faces {
            for i in 0..f.len() {
                let (a, b) = (f[i], f[(i + 1) % f.len()]);
                let key = (a.min(b), a.max(b));
                if let std::collections::btree_map::Entry::Vacant(e) = mid.entry(key) {
                    e.insert((nv + parents.len()) as u32);
                    parents.push(vec![key.0, key.1]);
                }
            }
        }
        let first_centre = nv + parents.len();
        parents.extend(self.faces.iter().cloned());
        let mut quads = Vec::new();
        let mut group_of_quad = Vec::new();
        let mut quad_lines = Vec::new();
        for (k, f) in self.faces.iter().enumerate() {
            let n = f.len();
            let centre = (first_centre + k) as u32;
            let m = |a: u32, b: u32| mid[&(a.min(b), a.max(b))];
            for i in 0..n {
                let c = f[i];
                quads.push([c, m(c, f[(i + 1) % n]), centre, m(f[(i + n - 1) % n], c)]);
                group_of_quad.push(self.group_of_face[k]);
                if let Some(&l) = self.face_lines.get(k) {
                    quad_lines.push(l);
                }
            }
        }
        let mean3 = |p: &Vec<u32>| {
            let mut s = [0.0; 3];
            for &v in p {
                for k in 0..3 {
                    s[k] += self.vertices[v as usize][k];
                }
            }
            s.map(|x| x / p.len() as f64)
        };
        let mut vertices = self.vertices.clone();
        vertices.extend(parents.iter().map(mean3));
        let refined = Refined {
            surface: QuadSurface {
                vertices,
                uv: None,
                quads,
                group_of_quad,
                groups: self.groups.clone(),
                quad_lines,
                notes: self.notes.clone(),
            },
            input_vertices: nv,
            parents,
        };
        let uv = self.uv.as_ref().map(|uv| refined.extend(uv));
        Refined {
            surface: QuadSurface {
                uv,
                ..refined.surface
            },
            ..refined
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area_vector(s: &QuadSurface) -> [f64; 3] {
        let mut a = [0.0; 3];
        for q in &s.quads {
            let n = crate::mesh::extrude::quad_area_vector(q.map(|v| &s.vertices[v as usize]));
            for k in 0..3 {
                a[k] += n[k];
            }
        }
        a
    }

    /// A unit square made of a quad and, beside it, two triangles (a square split along its
    /// diagonal), all facing +z.
    fn mixed() -> PolySurface {
        PolySurface {
            vertices: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [2.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [1.0, 1.0, 0.0],
                [2.0, 1.0, 0.0],
            ],
            uv: Some((0..6).map(|i| [i as f64, 0.5]).collect()),
            faces: vec![vec![0, 1, 4, 3], vec![1, 2, 5], vec![1, 5, 4]],
            group_of_face: vec![0, 1, 1],
            groups: vec!["a".into(), "b".into()],
            face_lines: vec![7, 8, 9],
            notes: vec![],
        }
    }

    #[test]
    fn a_surface_of_quads_is_its_own_refinement() {
        let mut p = mixed();
        p.faces = vec![vec![0, 1, 4, 3], vec![1, 2, 5, 4]];
        p.group_of_face = vec![0, 1];
        p.face_lines = vec![7, 8];
        let r = p.to_quads();
        assert!(r.parents.is_empty());
        assert_eq!(r.surface.quads, vec![[0, 1, 4, 3], [1, 2, 5, 4]]);
        assert_eq!(r.surface.vertices, p.vertices);
        assert_eq!(PolySurface::from_quads(&r.surface), p);
    }

    #[test]
    fn triangles_become_three_quads_that_share_the_edges_midpoints() {
        let p = mixed();
        p.validate("mixed").unwrap();
        let r = p.to_quads();
        let s = &r.surface;
        s.validate("refined").unwrap();
        // 4 + 3 + 3 quads; 8 edges' midpoints and 3 centres added
        assert_eq!(s.quads.len(), 10);
        assert_eq!(r.input_vertices, 6);
        assert_eq!(s.vertices.len(), 6 + 8 + 3);
        assert_eq!(&s.vertices[..6], &p.vertices[..]);
        // the shape is unchanged: the same area, all facing +z
        let a = area_vector(s);
        assert!((a[2] - 2.0).abs() < 1e-12 && a[0].abs() < 1e-12 && a[1].abs() < 1e-12);
        for q in &s.quads {
            let n = crate::mesh::extrude::quad_area_vector(q.map(|v| &s.vertices[v as usize]));
            assert!(n[2] > 0.0, "{q:?}");
        }
        // conforming: every edge of the refined surface in one or two quads, and the
        // interior edges (the shared edge 1-4 and the diagonal 1-5 included) in exactly two
        let mut uses: std::collections::BTreeMap<(u32, u32), usize> = Default::default();
        for q in &s.quads {
            for i in 0..4 {
                let (a, b) = (q[i], q[(i + 1) % 4]);
                *uses.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        assert!(uses.values().all(|&n| n == 1 || n == 2));
        let boundary = uses.values().filter(|&&n| n == 1).count();
        // the square's outline: 6 input edges, each in two halves
        assert_eq!(boundary, 12);
        // groups and file lines carried; the per-vertex data as the parents' mean
        assert_eq!(s.group_of_quad, vec![0, 0, 0, 0, 1, 1, 1, 1, 1, 1]);
        assert_eq!(s.quad_lines, vec![7, 7, 7, 7, 8, 8, 8, 9, 9, 9]);
        for (k, par) in r.parents.iter().enumerate() {
            let v = 6 + k;
            let mean =
                par.iter().map(|&i| p.vertices[i as usize][0]).sum::<f64>() / par.len() as f64;
            assert_eq!(s.vertices[v][0], mean);
            let mean_u = par.iter().map(|&i| i as f64).sum::<f64>() / par.len() as f64;
            assert_eq!(s.uv.as_ref().unwrap()[v][0], mean_u);
        }
        assert_eq!(r.parents.len(), 11);
    }

    #[test]
    fn a_polygon_surface_with_bad_arrays_is_refused() {
        let mut p = mixed();
        p.faces[1] = vec![1, 2];
        let e = p.validate("m.obj").unwrap_err().to_string();
        assert!(e.contains("m.obj:8") && e.contains("at least 3"), "{e}");
        let mut p = mixed();
        p.faces[2][0] = 60;
        let e = p.validate("m.obj").unwrap_err().to_string();
        assert!(e.contains("m.obj:9") && e.contains("61"), "{e}");
    }
}
