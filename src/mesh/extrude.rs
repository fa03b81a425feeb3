//! Extrusion of a quad surface into one layer of hexahedra (paper section 3.1: "a python
//! script was created to extrude the quads of the mesh into hexahedra").
//!
//! Every quad becomes one hexahedron: its bottom face is the surface quad, its top face the
//! same quad offset inward, by the thickness of the quad's group. Inward is against the
//! quad's normal (right-hand rule on its vertex order: a surface exported from Blender with
//! outward normals has its quads counter-clockwise seen from outside).
//!
//! * [`Direction::Normal`]: each vertex moves along its vertex normal, the sum of the area
//!   vectors of the quads around it (area weighted), normalised. This is the general rule;
//!   it inverts elements where the surface is convex with a radius of curvature smaller than
//!   the thickness (a protruding lip, say), and says so, naming the quad.
//! * [`Direction::Fixed`]: every vertex moves along one direction (e.g. straight back into
//!   the head, `[0, 0, -1]`). Valid whenever every quad faces against that direction (the
//!   surface is a height field over the plane normal to it), however curved.
//!
//! Shared vertices stay shared. A vertex used by quads of groups with different
//! thicknesses is offset by the **mean** of the thicknesses of the quads around it
//! (each quad counts once), so thickness changes smoothly across a group boundary.
//!
//! Output numbering: the used vertices, in surface order, are nodes `0..n`; their offset
//! copies are nodes `n..2n` in the same order. When every vertex is used by some quad (the
//! normal case) node `v` is vertex `v` and node `v + n` its offset. Vertices used by no quad
//! are dropped (they would have no mass). Element `q` is quad `q`, with VTK node order
//! `[a, d, c, b, a', d', c', b']` for the quad `[a, b, c, d]` (the bottom face seen from the
//! top face is then counter-clockwise). Element sets: one per group, named after it. Node
//! sets: `surface` (the surface vertices) and `inner` (their offsets).
//! `Mesh::element_lines` holds the quads' OBJ lines, so later errors name them.
//!
//! Errors (all naming quads by their OBJ line where the surface came from a file): a quad
//! that repeats a vertex or has zero area; an edge shared by more than two quads
//! (non-manifold); an edge traversed in the same direction by two quads (inconsistent
//! orientation); a non-positive thickness; an offset that inverts a hexahedron.

use super::Mesh;
use crate::element::hex8;
use crate::error::{Error, Location, Result};
use crate::linalg::{cross, dot, norm, sub};
use crate::mesh::surface::QuadSurface;
use rayon::prelude::*;

/// How vertices are offset.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Direction {
    /// Against the area-weighted vertex normal.
    Normal,
    /// Along this direction (normalised here): the direction *into* the body.
    Fixed([f64; 3]),
}

/// Area vector of a (possibly warped) quad: half the cross product of its diagonals.
/// Its length is the area of a planar quad; its direction is the quad's normal.
pub fn quad_area_vector(x: [&[f64; 3]; 4]) -> [f64; 3] {
    let d1 = sub(x[2], x[0]);
    let d2 = sub(x[3], x[1]);
    let c = cross(&d1, &d2);
    [0.5 * c[0], 0.5 * c[1], 0.5 * c[2]]
}

/// Per-group thicknesses from a default and `(group name, thickness)` overrides, for
/// [`extrude`]'s `thickness` argument (`&|g| t[g]`). Errors: an override naming no group
/// (the message lists the groups), a group left without a thickness, a thickness that is
/// not positive and finite.
/// The diagonal of the surface's bounding box (m).
fn surface_size(s: &QuadSurface) -> f64 {
    let (lo, hi) = crate::linalg::bounding_box(&s.vertices);
    let d: f64 = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
    if d.is_finite() {
        d
    } else {
        0.0
    }
}

pub fn group_thickness(
    surface: &QuadSurface,
    default: Option<f64>,
    per_group: &[(String, f64)],
    file: &str,
) -> Result<Vec<f64>> {
    let mut t = vec![default; surface.groups.len()];
    for (name, value) in per_group {
        match surface.group_index(name) {
            Some(g) => t[g] = Some(*value),
            None => {
                return Err(Error::input(
                    file,
                    Location::Field(format!("thickness of group {name}")),
                    format!(
                        "no group `{name}` in the surface; its groups are: {}",
                        surface.groups.join(", ")
                    ),
                ))
            }
        }
    }
    // a layer far thicker than the surface is large is a unit mistake, not a model
    let size = surface_size(surface);
    let most = 1e3 * size;
    surface
        .groups
        .iter()
        .zip(t)
        .map(|(name, v)| match v {
            Some(v) if v.is_finite() && v > 0.0 && v > most && size > 0.0 => Err(Error::input(
                file,
                Location::Field(format!("thickness of group {name}")),
                format!(
                    "thickness {v:e} m is more than 1000 times the surface's size ({size:.3e} m, its bounding box diagonal): check the unit"
                ),
            )),
            Some(v) if v.is_finite() && v > 0.0 => Ok(v),
            Some(v) => Err(Error::input(
                file,
                Location::Field(format!("thickness of group {name}")),
                format!("thickness {v} must be positive and finite (m)"),
            )),
            None => Err(Error::input(
                file,
                Location::Field(format!("thickness of group {name}")),
                "no thickness given for this group and no default thickness",
            )),
        })
        .collect()
}

/// Extrudes against the vertex normals ([`Direction::Normal`]); `thickness(g)` is the
/// thickness (m) of group `g`.
pub fn extrude(
    surface: &QuadSurface,
    thickness: &dyn Fn(usize) -> f64,
    file: &str,
) -> Result<Mesh> {
    extrude_with(surface, thickness, Direction::Normal, file)
}

/// Checks the surface's topology: no repeated vertex in a quad, no zero-area quad, every
/// edge shared by at most two quads, traversed in opposite directions by the two.
pub fn check_topology(surface: &QuadSurface, file: &str) -> Result<()> {
    let v = &surface.vertices;
    for (q, quad) in surface.quads.iter().enumerate() {
        for a in 0..4 {
            for b in a + 1..4 {
                if quad[a] == quad[b] {
                    return Err(Error::input(
                        file,
                        surface.quad_location(q),
                        format!(
                            "quad repeats vertex {} (vertices {:?}, 1-based): it is degenerate",
                            quad[a] + 1,
                            quad.map(|i| i + 1)
                        ),
                    ));
                }
            }
        }
        let x = quad.map(|i| &v[i as usize]);
        let area = norm(&quad_area_vector(x));
        let mut l2 = 0.0f64;
        for k in 0..4 {
            let e = sub(x[(k + 1) % 4], x[k]);
            l2 = l2.max(dot(&e, &e));
        }
        if !(area > 1e-12 * l2) {
            return Err(Error::input(
                file,
                surface.quad_location(q),
                format!(
                    "quad {:?} (1-based vertices) has zero area ({area:.3e}; longest edge {:.3e}): \
                     it is collapsed or folded over itself",
                    quad.map(|i| i + 1),
                    l2.sqrt()
                ),
            ));
        }
    }
    // Every directed edge, keyed by its undirected vertex pair; sorted, each key must appear
    // at most twice, in opposite directions.
    let mut edges: Vec<(u64, u32)> = Vec::with_capacity(4 * surface.quads.len());
    for (q, quad) in surface.quads.iter().enumerate() {
        for k in 0..4 {
            let (a, b) = (quad[k], quad[(k + 1) % 4]);
            let key = ((a.min(b) as u64) << 32) | a.max(b) as u64;
            edges.push((key, ((q as u32) << 1) | (a < b) as u32));
        }
    }
    edges.par_sort_unstable();
    let mut i = 0;
    while i < edges.len() {
        let mut j = i + 1;
        while j < edges.len() && edges[j].0 == edges[i].0 {
            j += 1;
        }
        let key = edges[i].0;
        let (lo, hi) = ((key >> 32) + 1, (key & 0xffff_ffff) + 1);
        if j - i > 2 {
            let names: Vec<String> = edges[i..j]
                .iter()
                .map(|e| surface.quad_name((e.1 >> 1) as usize))
                .collect();
            return Err(Error::input(
                file,
                surface.quad_location((edges[i].1 >> 1) as usize),
                format!(
                    "non-manifold surface: the edge between vertices {lo} and {hi} belongs to {} quads ({}); \
                     an extruded surface needs at most two quads per edge",
                    j - i,
                    names.join(", ")
                ),
            ));
        }
        if j - i == 2 && (edges[i].1 & 1) == (edges[i + 1].1 & 1) {
            let (q1, q2) = ((edges[i].1 >> 1) as usize, (edges[i + 1].1 >> 1) as usize);
            let (from, to) = if edges[i].1 & 1 == 1 {
                (lo, hi)
            } else {
                (hi, lo)
            };
            return Err(Error::input(
                file,
                surface.quad_location(q2),
                format!(
                    "inconsistent orientation: the quads at {} and {} both traverse the edge from vertex {from} \
                     to vertex {to} in the same direction, so one of them faces the other way \
                     (reverse its vertex order; in Blender: Mesh > Normals > Recalculate Outside)",
                    surface.quad_name(q1.min(q2)),
                    surface.quad_name(q1.max(q2)),
                ),
            ));
        }
        i = j;
    }
    Ok(())
}

/// Each group's thickness (m); fails where a group with quads has one that is not positive
/// and finite.
fn group_thicknesses(
    surface: &QuadSurface,
    thickness: &dyn Fn(usize) -> f64,
    file: &str,
) -> Result<Vec<f64>> {
    let ng = surface.groups.len();
    let mut has_quads = vec![false; ng];
    for &g in &surface.group_of_quad {
        has_quads[g as usize] = true;
    }
    let tg: Vec<f64> = (0..ng).map(thickness).collect();
    for g in 0..ng {
        if has_quads[g] && !(tg[g].is_finite() && tg[g] > 0.0) {
            return Err(Error::input(
                file,
                Location::Field(format!("thickness of group {}", surface.groups[g])),
                format!("thickness {} must be positive and finite (m)", tg[g]),
            ));
        }
    }
    Ok(tg)
}

/// The fixed direction's unit vector (`None` for [`Direction::Normal`]); fails for a
/// direction that is zero or not finite.
fn unit_direction(direction: Direction, file: &str) -> Result<Option<[f64; 3]>> {
    Ok(match direction {
        Direction::Normal => None,
        Direction::Fixed(d) => {
            let n = norm(&d);
            if !(n.is_finite() && n > 0.0) {
                return Err(Error::input(
                    file,
                    Location::Field("extrusion direction".into()),
                    format!("direction {d:?} must be a finite non-zero vector"),
                ));
            }
            Some([d[0] / n, d[1] / n, d[2] / n])
        }
    })
}

/// Per vertex of a surface: the sum of its quads' area vectors, and of their thicknesses,
/// and their count ([`vertex_sums`]).
struct VertexSums {
    normal: Vec<[f64; 3]>,
    tsum: Vec<f64>,
    count: Vec<u32>,
}

impl VertexSums {
    /// Vertex `i`'s offset: the mean thickness of its quads.
    fn offset(&self, i: usize) -> f64 {
        self.tsum[i] / self.count[i] as f64
    }
}

/// Area-weighted normals and mean thickness (group thicknesses `tg`), per vertex.
fn vertex_sums(surface: &QuadSurface, tg: &[f64]) -> VertexSums {
    let nv = surface.vertices.len();
    let v = &surface.vertices;
    let mut normal = vec![[0.0f64; 3]; nv];
    let mut tsum = vec![0.0f64; nv];
    let mut count = vec![0u32; nv];
    for (q, quad) in surface.quads.iter().enumerate() {
        let a = quad_area_vector(quad.map(|i| &v[i as usize]));
        let t = tg[surface.group_of_quad[q] as usize];
        for &i in quad {
            let n = &mut normal[i as usize];
            n[0] += a[0];
            n[1] += a[1];
            n[2] += a[2];
            tsum[i as usize] += t;
            count[i as usize] += 1;
        }
    }
    VertexSums {
        normal,
        tsum,
        count,
    }
}

/// The nodes: the used vertices (`used`, in order), then each offset by its mean thickness
/// along `fixed`, or against its area-weighted normal. Fails where a vertex has no normal.
fn extruded_nodes(
    surface: &QuadSurface,
    sums: &VertexSums,
    used: &[u32],
    fixed: Option<[f64; 3]>,
    file: &str,
) -> Result<Vec<[f64; 3]>> {
    let v = &surface.vertices;
    let mut nodes = Vec::with_capacity(2 * used.len());
    nodes.extend(used.iter().map(|&i| v[i as usize]));
    for &i in used {
        let i = i as usize;
        let t = sums.offset(i);
        let d = match fixed {
            Some(d) => d,
            None => {
                let n = sums.normal[i];
                let l = norm(&n);
                if !(l > 0.0) || !l.is_finite() {
                    let q = surface
                        .quads
                        .iter()
                        .position(|quad| quad.contains(&(i as u32)))
                        .unwrap_or(0);
                    return Err(Error::input(
                        file,
                        surface.quad_location(q),
                        format!(
                            "vertex {} has no defined normal: the quads around it cancel out",
                            i + 1
                        ),
                    ));
                }
                [-n[0] / l, -n[1] / l, -n[2] / l]
            }
        };
        let x = v[i];
        nodes.push([x[0] + t * d[0], x[1] + t * d[1], x[2] + t * d[2]]);
    }
    Ok(nodes)
}

/// The error of quad `q`, whose hexahedron (`conn`) is inverted: where and why.
#[allow(clippy::too_many_arguments)]
fn inverted_error(
    surface: &QuadSurface,
    q: usize,
    conn: &[u32; 8],
    nodes: &[[f64; 3]],
    sums: &VertexSums,
    tg: &[f64],
    fixed: Option<[f64; 3]>,
    file: &str,
) -> Error {
    let v = &surface.vertices;
    let x: [[f64; 3]; 8] = std::array::from_fn(|k| nodes[conn[k] as usize]);
    let (dmin, at) = hex8::min_corner_jacobian(&x);
    let g = surface.group_of_quad[q] as usize;
    let quad = surface.quads[q];
    let ts: Vec<String> = quad
        .iter()
        .map(|&i| format!("{:.4e}", sums.offset(i as usize)))
        .collect();
    let why = match fixed {
        Some(d) => {
            let a = quad_area_vector(quad.map(|i| &v[i as usize]));
            if dot(&a, &d) >= 0.0 {
                format!(
                    "the quad faces along the extrusion direction {d:?} (its outward normal must point against it)"
                )
            } else {
                "the quad is too warped for this thickness".to_string()
            }
        }
        None => "the thickness exceeds the local radius of curvature of the surface (a convex bump \
                 thinner than the thickness), or the quad is strongly warped; use a smaller thickness \
                 or a fixed extrusion direction"
            .to_string(),
    };
    Error::input(
        file,
        surface.quad_location(q),
        format!(
            "extruding this quad (group `{}`, thickness {:.4e} m; offsets at its vertices {}) inverts its \
             hexahedron: det J = {dmin:.3e} at {}: {why}",
            surface.groups[g],
            tg[g],
            ts.join(", "),
            if at < 8 { format!("corner {at}") } else { "the centre".into() },
        ),
    )
}

/// The mesh of `nodes` and `elements` (the surface's `used` vertices, then their offsets):
/// the surface's texture coordinates on both layers, its quad lines, an element set per
/// group, node sets `surface` and `inner`.
fn extruded_mesh(
    surface: &QuadSurface,
    nodes: Vec<[f64; 3]>,
    elements: Vec<[u32; 8]>,
    used: &[u32],
) -> Mesh {
    let nu = used.len();
    let uv = surface.uv.as_ref().map(|uv| {
        let top: Vec<[f64; 2]> = used.iter().map(|&i| uv[i as usize]).collect();
        let mut all = top.clone();
        all.extend(top);
        all
    });
    let mut mesh = Mesh {
        nodes,
        elements,
        element_lines: if surface.quad_lines.is_empty() {
            None
        } else {
            Some(surface.quad_lines.clone())
        },
        uv,
        ..Default::default()
    };
    let mut sets: Vec<Vec<u32>> = vec![Vec::new(); surface.groups.len()];
    for (q, &g) in surface.group_of_quad.iter().enumerate() {
        sets[g as usize].push(q as u32);
    }
    for (name, set) in surface.groups.iter().zip(sets) {
        mesh.element_sets.insert(name.clone(), set);
    }
    mesh.node_sets
        .insert("surface".into(), (0..nu as u32).collect());
    mesh.node_sets
        .insert("inner".into(), (nu as u32..2 * nu as u32).collect());
    mesh
}

/// Extrudes with the given offset [`Direction`] (see the module docs).
pub fn extrude_with(
    surface: &QuadSurface,
    thickness: &dyn Fn(usize) -> f64,
    direction: Direction,
    file: &str,
) -> Result<Mesh> {
    surface.validate(file)?;
    if surface.quads.is_empty() {
        return Err(Error::input(
            file,
            Location::None,
            "the surface has no quads",
        ));
    }
    check_topology(surface, file)?;
    let tg = group_thicknesses(surface, thickness, file)?;
    let fixed = unit_direction(direction, file)?;

    let nv = surface.vertices.len();
    // Area-weighted normals and mean thickness, per vertex.
    let sums = vertex_sums(surface, &tg);
    // Renumber the used vertices.
    let mut node_of = vec![u32::MAX; nv];
    let mut used: Vec<u32> = Vec::with_capacity(nv);
    for i in 0..nv {
        if sums.count[i] > 0 {
            node_of[i] = used.len() as u32;
            used.push(i as u32);
        }
    }
    let nu = used.len();
    let nodes = extruded_nodes(surface, &sums, &used, fixed, file)?;
    let elements: Vec<[u32; 8]> = surface
        .quads
        .iter()
        .map(|q| {
            let [a, b, c, d] = q.map(|i| node_of[i as usize]);
            let o = nu as u32;
            [a, d, c, b, a + o, d + o, c + o, b + o]
        })
        .collect();
    let bad = elements.par_iter().position_first(|conn| {
        let x: [[f64; 3]; 8] = std::array::from_fn(|k| nodes[conn[k] as usize]);
        !(hex8::min_corner_jacobian(&x).0 > 0.0)
    });
    if let Some(q) = bad {
        return Err(inverted_error(
            surface,
            q,
            &elements[q],
            &nodes,
            &sums,
            &tg,
            fixed,
            file,
        ));
    }
    Ok(extruded_mesh(surface, nodes, elements, &used))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::obj::parse_obj;

    /// An `n x m` grid of unit quads in the plane z = 0, normals +z.
    fn patch(n: usize, m: usize, h: f64) -> QuadSurface {
        let mut s = QuadSurface::default();
        for j in 0..=m {
            for i in 0..=n {
                s.vertices.push([i as f64 * h, j as f64 * h, 0.0]);
            }
        }
        let id = |i: usize, j: usize| (i + (n + 1) * j) as u32;
        for j in 0..m {
            for i in 0..n {
                s.quads
                    .push([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
                s.group_of_quad.push(if i < n / 2 { 0 } else { 1 });
            }
        }
        s.groups = vec!["skin".into(), "saliva".into()];
        s
    }

    #[test]
    fn flat_patch_gives_prisms_of_area_times_thickness() {
        let s = patch(4, 3, 0.01);
        let mesh = extrude(&s, &|_| 0.002, "patch").unwrap();
        mesh.validate("patch").unwrap();
        assert_eq!(mesh.nodes.len(), 2 * 20);
        assert_eq!(mesh.elements.len(), 12);
        for e in 0..12 {
            let x = mesh.element_coords(e);
            let v = hex8::volume(&x);
            assert!((v - 0.01 * 0.01 * 0.002).abs() < 1e-18, "{v}");
            // Bottom face = the surface quad (z = 0); top face offset inward (-z).
            for a in 0..4 {
                assert_eq!(x[a][2], 0.0);
                assert!((x[a + 4][2] + 0.002).abs() < 1e-15);
            }
        }
        assert_eq!(mesh.node_sets["surface"], (0..20).collect::<Vec<u32>>());
        assert_eq!(mesh.node_sets["inner"], (20..40).collect::<Vec<u32>>());
        assert_eq!(mesh.element_sets["skin"].len(), 6);
        assert_eq!(mesh.element_sets["saliva"].len(), 6);
        let total: f64 = (0..12).map(|e| hex8::volume(&mesh.element_coords(e))).sum();
        assert!((total - 0.04 * 0.03 * 0.002).abs() < 1e-15);
    }

    #[test]
    fn shared_vertices_take_the_mean_thickness() {
        let s = patch(2, 1, 1.0);
        let t = [1.0, 3.0];
        let mesh = extrude(&s, &|g| t[g], "patch").unwrap();
        // Vertex (1, 0) is shared by a quad of each group: mean 2.
        assert!((mesh.nodes[6 + 1][2] + 2.0).abs() < 1e-12);
        assert!((mesh.nodes[6][2] + 1.0).abs() < 1e-12);
        assert!((mesh.nodes[6 + 2][2] + 3.0).abs() < 1e-12);
    }

    #[test]
    fn fixed_direction_and_unused_vertices() {
        let mut s = patch(2, 2, 1.0);
        s.vertices.push([9.0, 9.0, 9.0]); // used by no quad: dropped
        let mesh = extrude_with(&s, &|_| 0.5, Direction::Fixed([0.0, 0.0, -2.0]), "p").unwrap();
        mesh.validate("p").unwrap();
        assert_eq!(mesh.nodes.len(), 18);
        let s2 = patch(2, 2, 1.0);
        let e = extrude_with(&s2, &|_| 0.5, Direction::Fixed([0.0, 0.0, 1.0]), "p")
            .unwrap_err()
            .to_string();
        assert!(e.contains("faces along the extrusion direction"), "{e}");
    }

    #[test]
    fn inconsistent_orientation_names_both_lines() {
        let text = "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nv 1 1 0\nv 2 1 0\n\
                    f 1 2 5 4\nf 2 5 6 3\n";
        let s = parse_obj(text, "flip.obj").unwrap();
        let e = extrude(&s, &|_| 0.1, "flip.obj").unwrap_err().to_string();
        assert!(e.contains("inconsistent orientation"), "{e}");
        assert!(e.contains("line 7") && e.contains("line 8"), "{e}");
        assert!(e.starts_with("flip.obj:8:"), "{e}");
    }

    #[test]
    fn non_manifold_zero_area_and_bad_thickness() {
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 1 0 1\nv 0 0 1\nv 1 0 -1\nv 0 0 -1\n\
                    f 1 2 3 4\nf 2 1 6 5\nf 2 1 8 7\n";
        let s = parse_obj(text, "nm.obj").unwrap();
        let e = extrude(&s, &|_| 0.1, "nm.obj").unwrap_err().to_string();
        assert!(e.contains("non-manifold") && e.contains("3 quads"), "{e}");
        let text = "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nf 1 2 3 4\n";
        let s = parse_obj(text, "z.obj").unwrap();
        let e = extrude(&s, &|_| 0.1, "z.obj").unwrap_err().to_string();
        assert!(e.starts_with("z.obj:5:") && e.contains("zero area"), "{e}");
        let s = patch(2, 1, 1.0);
        let e = extrude(&s, &|g| if g == 1 { -1.0 } else { 1.0 }, "t")
            .unwrap_err()
            .to_string();
        assert!(e.contains("saliva") && e.contains("positive"), "{e}");
        let e = group_thickness(&s, None, &[("skin".into(), 1.0)], "t")
            .unwrap_err()
            .to_string();
        assert!(e.contains("saliva"), "{e}");
        let e = group_thickness(&s, Some(1.0), &[("lips".into(), 1.0)], "t")
            .unwrap_err()
            .to_string();
        assert!(e.contains("skin, saliva"), "{e}");
        assert_eq!(
            group_thickness(&s, Some(1.0), &[("saliva".into(), 2.0)], "t").unwrap(),
            vec![1.0, 2.0]
        );
    }

    #[test]
    fn thickness_beyond_curvature_radius_is_named() {
        // A half cylinder of radius 1 (axis y), normals outward; thickness 1.5 > radius.
        let (n, m) = (12usize, 2usize);
        let mut s = QuadSurface::default();
        for j in 0..=m {
            for i in 0..=n {
                let a = std::f64::consts::PI * i as f64 / n as f64;
                s.vertices.push([a.cos(), j as f64 * 0.3, a.sin()]);
            }
        }
        let id = |i: usize, j: usize| (i + (n + 1) * j) as u32;
        for j in 0..m {
            for i in 0..n {
                // Outward normal: counter-clockwise seen from outside.
                s.quads
                    .push([id(i, j), id(i, j + 1), id(i + 1, j + 1), id(i + 1, j)]);
                s.group_of_quad.push(0);
            }
        }
        s.groups = vec!["shell".into()];
        let ok = extrude(&s, &|_| 0.5, "cyl").unwrap();
        ok.validate("cyl").unwrap();
        // Inner radius 0.5 (up to the normals' discretisation): volume of the half shell.
        let v: f64 = (0..ok.elements.len())
            .map(|e| hex8::volume(&ok.element_coords(e)))
            .sum();
        let exact = 0.5 * std::f64::consts::PI * (1.0 - 0.25) * 0.6;
        assert!((v - exact).abs() < 0.02 * exact, "{v} vs {exact}");
        let e = extrude(&s, &|_| 1.5, "cyl").unwrap_err().to_string();
        assert!(
            e.contains("inverts") && e.contains("shell") && e.contains("radius of curvature"),
            "{e}"
        );
    }
}
