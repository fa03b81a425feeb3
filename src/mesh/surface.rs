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
