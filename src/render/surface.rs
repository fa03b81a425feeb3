//! The boundary surface of a hexahedral mesh: the quadrilateral faces that belong to
//! exactly one hexahedron, oriented outward, and normals for smooth shading.

use crate::element::hex8::FACES as HEX_FACES;
use crate::linalg::{add, cross, dot, normalize, scale, sub};
use std::collections::HashMap;

/// A boundary quadrilateral: its nodes counter-clockwise seen from outside the mesh, the
/// element it belongs to, and which face of that element it is (index into [`crate::element::hex8::FACES`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct BoundaryFace {
    pub nodes: [u32; 4],
    pub element: u32,
    pub local_face: u8,
}

/// The faces of `elements` that belong to exactly one of them, in element order and
/// then [`crate::element::hex8::FACES`] order (deterministic). Orientation is outward for positively
/// oriented elements (positive Jacobian, as `Mesh::validate` requires).
pub fn boundary_quads(elements: &[[u32; 8]]) -> Vec<BoundaryFace> {
    boundary_quads_where(elements, |_| true)
}

/// The boundary of the sub-mesh of the elements for which `keep(element)` holds (for
/// example without broken saliva elements); element indices stay those of `elements`.
pub fn boundary_quads_where(
    elements: &[[u32; 8]],
    keep: impl Fn(u32) -> bool,
) -> Vec<BoundaryFace> {
    let key = |f: [u32; 4]| {
        let mut k = f;
        k.sort_unstable();
        k
    };
    let face_nodes =
        |e: &[u32; 8], f: &[usize; 4]| -> [u32; 4] { std::array::from_fn(|i| e[f[i]]) };
    let kept: Vec<bool> = (0..elements.len()).map(|e| keep(e as u32)).collect();
    let mut count: HashMap<[u32; 4], u32> = HashMap::with_capacity(3 * elements.len() + 6);
    for (e, el) in elements.iter().enumerate() {
        if !kept[e] {
            continue;
        }
        for f in &HEX_FACES {
            *count.entry(key(face_nodes(el, f))).or_insert(0) += 1;
        }
    }
    let mut out = Vec::new();
    for (e, el) in elements.iter().enumerate() {
        if !kept[e] {
            continue;
        }
        for (lf, f) in HEX_FACES.iter().enumerate() {
            let nodes = face_nodes(el, f);
            if count[&key(nodes)] == 1 {
                out.push(BoundaryFace {
                    nodes,
                    element: e as u32,
                    local_face: lf as u8,
                });
            }
        }
    }
    out
}

/// The vector area of a (possibly warped) quad: half the cross product of its diagonals;
/// its direction is the right-hand normal of the node order.
pub fn quad_vector_area(positions: &[[f64; 3]], nodes: [u32; 4]) -> [f64; 3] {
    let p = |i: usize| positions[nodes[i] as usize];
    scale(&cross(&sub(&p(2), &p(0)), &sub(&p(3), &p(1))), 0.5)
}

/// Unit normal of a face (zero for a degenerate face).
pub fn face_normal(positions: &[[f64; 3]], face: &BoundaryFace) -> [f64; 3] {
    normalize(&quad_vector_area(positions, face.nodes))
}

/// The centroid of a face's four nodes.
pub fn face_centroid(positions: &[[f64; 3]], face: &BoundaryFace) -> [f64; 3] {
    let mut c = [0.0; 3];
    for &n in &face.nodes {
        c = add(&c, &positions[n as usize]);
    }
    scale(&c, 0.25)
}

/// Area-weighted unit vertex normals of the surface at the current `positions`
/// (`positions.len()` entries; zero for nodes not on any face).
pub fn vertex_normals(positions: &[[f64; 3]], faces: &[BoundaryFace]) -> Vec<[f64; 3]> {
    let mut n = vec![[0.0; 3]; positions.len()];
    for f in faces {
        let a = quad_vector_area(positions, f.nodes);
        for &v in &f.nodes {
            n[v as usize] = add(&n[v as usize], &a);
        }
    }
    n.iter().map(normalize).collect()
}

/// Per-corner normals that keep creases sharp: the normal at corner `i` of a face is the
/// area-weighted average of the normals of the faces at that node whose normal is within
/// `crease_degrees` of this face's normal (so a smooth surface is shaded smoothly and a box
/// keeps its edges). `crease_degrees >= 180` gives [`vertex_normals`]; `0` gives flat faces.
pub fn corner_normals(
    positions: &[[f64; 3]],
    faces: &[BoundaryFace],
    crease_degrees: f64,
) -> Vec<[[f64; 3]; 4]> {
    corner_normals_weighted(positions, faces, &|_, _, cos| {
        soft_crease(cos, crease_degrees, crease_degrees)
    })
}

/// A soft crease: the weight of a neighbouring face whose normal makes an angle with
/// cosine `cos` with this face's: 1 within `smooth_degrees`, 0 beyond `sharp_degrees`, and
/// in between falling smoothly (a smoothstep in the angle), so that the shading is a
/// continuous function of the geometry: two neighbouring columns of a mesh whose fold angles
/// straddle a hard threshold (one at 58 degrees, one at 62) are then shaded alike instead of
/// one smooth and one sharp. `sharp_degrees <= smooth_degrees` is a hard crease.
pub fn soft_crease(cos: f64, smooth_degrees: f64, sharp_degrees: f64) -> f64 {
    let smooth = smooth_degrees.clamp(0.0, 180.0);
    let sharp = sharp_degrees.clamp(0.0, 180.0);
    if cos >= smooth.to_radians().cos() - 1e-12 {
        return 1.0;
    }
    if sharp <= smooth {
        return 0.0;
    }
    let deg = cos.clamp(-1.0, 1.0).acos().to_degrees();
    let t = ((sharp - deg) / (sharp - smooth)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// [`corner_normals`] with the neighbours weighted by `weight(face, neighbour, cos)` in
/// `[0, 1]` (`face`, `neighbour`: indices into `faces`; `cos`: the cosine of the angle
/// between their normals): the normal at a corner is the area-weighted average of the
/// normals of the faces at that node, each also weighted by `weight` (the face itself by
/// 1). A hard crease is a weight of 1 or 0; [`soft_crease`] falls smoothly between.
pub fn corner_normals_weighted(
    positions: &[[f64; 3]],
    faces: &[BoundaryFace],
    weight: &dyn Fn(usize, usize, f64) -> f64,
) -> Vec<[[f64; 3]; 4]> {
    let areas: Vec<[f64; 3]> = faces
        .iter()
        .map(|f| quad_vector_area(positions, f.nodes))
        .collect();
    let units: Vec<[f64; 3]> = areas.iter().map(normalize).collect();
    // Faces around each node (CSR).
    let mut start = vec![0usize; positions.len() + 1];
    for f in faces {
        for &v in &f.nodes {
            start[v as usize + 1] += 1;
        }
    }
    for i in 0..positions.len() {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut adj = vec![0u32; start[positions.len()]];
    for (fi, f) in faces.iter().enumerate() {
        for &v in &f.nodes {
            adj[fill[v as usize]] = fi as u32;
            fill[v as usize] += 1;
        }
    }
    faces
        .iter()
        .enumerate()
        .map(|(fi, f)| {
            std::array::from_fn(|c| {
                let v = f.nodes[c] as usize;
                let mut s = [0.0; 3];
                for &g in &adj[start[v]..start[v + 1]] {
                    let g = g as usize;
                    let w = if g == fi {
                        1.0
                    } else {
                        weight(fi, g, dot(&units[g], &units[fi]))
                    };
                    if w == 1.0 {
                        s = add(&s, &areas[g]);
                    } else if w > 0.0 {
                        s = add(&s, &scale(&areas[g], w));
                    }
                }
                let n = normalize(&s);
                if n == [0.0; 3] {
                    units[fi]
                } else {
                    n
                }
            })
        })
        .collect()
}
