//! Hexahedral meshes: geometry, named sets, topology and validation.

pub mod anatomy;
pub mod budget;
pub mod extrude;
pub mod face;
pub mod generate;
pub mod mouth;
pub mod skin;
pub mod surface;
pub mod zones;

use crate::element::hex8;
use crate::error::{Error, Location, Result};
use std::collections::BTreeMap;

/// An 8-node hexahedral mesh in the reference configuration (SI units: metres).
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// Reference node positions `X` (m). Node numbering is the input's.
    pub nodes: Vec<[f64; 3]>,
    /// Element connectivity, `VTK_HEXAHEDRON` order (see [`hex8`]).
    pub elements: Vec<[u32; 8]>,
    /// Named node sets (sorted, unique node indices).
    pub node_sets: BTreeMap<String, Vec<u32>>,
    /// Named element sets (sorted, unique element indices).
    pub element_sets: BTreeMap<String, Vec<u32>>,
    /// Source line of each element, where the mesh came from a text file (for errors).
    pub element_lines: Option<Vec<usize>>,
    /// Texture coordinates of each node, where the mesh was extruded from a surface that has
    /// them (both layers take their surface vertex's); for renderings.
    pub uv: Option<Vec<[f64; 2]>>,
}

/// Mesh statistics printed by `sticky-lips check`.
#[derive(Clone, Debug, serde::Serialize)]
pub struct MeshStats {
    pub nodes: usize,
    pub elements: usize,
    pub bounding_box_min: [f64; 3],
    pub bounding_box_max: [f64; 3],
    pub total_volume: f64,
    pub min_element_volume: f64,
    pub max_element_volume: f64,
    pub min_characteristic_length: f64,
    /// Smallest ratio of minimum to maximum corner `det J` over all elements (1 for parallelepipeds).
    pub worst_jacobian_ratio: f64,
}

impl Mesh {
    pub fn element_coords(&self, e: usize) -> [[f64; 3]; 8] {
        let c = &self.elements[e];
        std::array::from_fn(|a| self.nodes[c[a] as usize])
    }

    fn location_of_element(&self, e: usize) -> Location {
        match &self.element_lines {
            Some(lines) => Location::LineField(lines[e], format!("element {e}")),
            None => Location::Field(format!("element {e}")),
        }
    }

    /// Checks the mesh: finite coordinates, node indices in range, no repeated node
    /// in an element, no inverted or degenerate element, no node outside every element.
    pub fn validate(&self, file: &str) -> Result<()> {
        if self.elements.is_empty() {
            return Err(Error::input(
                file,
                Location::None,
                "the mesh has no elements",
            ));
        }
        for (n, x) in self.nodes.iter().enumerate() {
            if !x.iter().all(|v| v.is_finite()) {
                return Err(Error::input(
                    file,
                    Location::Field(format!("node {n}")),
                    "non-finite coordinate",
                ));
            }
        }
        let nn = self.nodes.len();
        let mut used = vec![false; nn];
        for (e, conn) in self.elements.iter().enumerate() {
            for (a, &n) in conn.iter().enumerate() {
                if n as usize >= nn {
                    return Err(Error::input(
                        file,
                        self.location_of_element(e),
                        format!("node index {n} (corner {a}) is out of range: the mesh has {nn} nodes (0..{})", nn - 1),
                    ));
                }
                used[n as usize] = true;
            }
            let mut s = *conn;
            s.sort_unstable();
            if s.windows(2).any(|w| w[0] == w[1]) {
                return Err(Error::input(
                    file,
                    self.location_of_element(e),
                    format!("element repeats a node ({conn:?}): degenerate hexahedron"),
                ));
            }
            let x = self.element_coords(e);
            let (dmin, at) = hex8::min_corner_jacobian(&x);
            let v = hex8::volume(&x);
            if !(dmin > 0.0) || !(v > 0.0) {
                let what = if at < 8 {
                    format!("corner {at}")
                } else {
                    "the centre".to_string()
                };
                return Err(Error::input(
                    file,
                    self.location_of_element(e),
                    format!(
                        "inverted or degenerate hexahedron: det J = {dmin:.3e} at {what} (volume {v:.3e} m^3); \
                         node order must be VTK_HEXAHEDRON (bottom face counter-clockwise seen from the top face, then the top face)"
                    ),
                ));
            }
        }
        if let Some(n) = used.iter().position(|u| !u) {
            return Err(Error::input(
                file,
                Location::Field(format!("node {n}")),
                "node belongs to no element (it would have no mass)",
            ));
        }
        for (name, set) in &self.node_sets {
            if let Some(&n) = set.iter().find(|&&n| n as usize >= nn) {
                return Err(Error::input(
                    file,
                    Location::Field(format!("node set `{name}`")),
                    format!("node {n} out of range"),
                ));
            }
        }
        for (name, set) in &self.element_sets {
            if let Some(&e) = set.iter().find(|&&e| e as usize >= self.elements.len()) {
                return Err(Error::input(
                    file,
                    Location::Field(format!("element set `{name}`")),
                    format!("element {e} out of range"),
                ));
            }
        }
        Ok(())
    }

    pub fn stats(&self) -> MeshStats {
        let (bmin, bmax) = crate::linalg::bounding_box(&self.nodes);
        let (mut vt, mut vmin, mut vmax, mut lmin, mut jr) =
            (0.0, f64::INFINITY, 0.0f64, f64::INFINITY, 1.0f64);
        for e in 0..self.elements.len() {
            let x = self.element_coords(e);
            let v = hex8::volume(&x);
            vt += v;
            vmin = vmin.min(v);
            vmax = vmax.max(v);
            lmin = lmin.min(hex8::characteristic_length(&x));
            let dets: Vec<f64> = hex8::NATURAL
                .iter()
                .map(|p| crate::linalg::det(&hex8::jacobian(&x, *p)))
                .collect();
            let (a, b) = dets
                .iter()
                .fold((f64::INFINITY, 0.0f64), |(a, b), &d| (a.min(d), b.max(d)));
            jr = jr.min(a / b);
        }
        MeshStats {
            nodes: self.nodes.len(),
            elements: self.elements.len(),
            bounding_box_min: bmin,
            bounding_box_max: bmax,
            total_volume: vt,
            min_element_volume: vmin,
            max_element_volume: vmax,
            min_characteristic_length: lmin,
            worst_jacobian_ratio: jr,
        }
    }
}

/// For each node, the `(element, corner)` slots that touch it, as `8 * element + corner`,
/// in increasing order (compressed rows). Summing element forces through this list
/// gives every node its force in a fixed order, whatever the thread count.
#[derive(Clone, Debug)]
pub struct NodeGather {
    pub offsets: Vec<u32>,
    pub slots: Vec<u32>,
}

impl NodeGather {
    pub fn new(num_nodes: usize, elements: &[[u32; 8]]) -> Self {
        let mut counts = vec![0u32; num_nodes + 1];
        for conn in elements {
            for &n in conn {
                counts[n as usize + 1] += 1;
            }
        }
        for i in 0..num_nodes {
            counts[i + 1] += counts[i];
        }
        let offsets = counts.clone();
        let mut fill = counts;
        let mut slots = vec![0u32; 8 * elements.len()];
        for (e, conn) in elements.iter().enumerate() {
            for (a, &n) in conn.iter().enumerate() {
                let k = &mut fill[n as usize];
                slots[*k as usize] = (8 * e + a) as u32;
                *k += 1;
            }
        }
        NodeGather { offsets, slots }
    }

    #[inline(always)]
    pub fn of(&self, node: usize) -> &[u32] {
        &self.slots[self.offsets[node] as usize..self.offsets[node + 1] as usize]
    }
}
