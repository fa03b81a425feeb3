//! Quad-surface topology for the face pipeline: edge adjacency, edge loops, connected
//! components and sub-surfaces. Deterministic: maps are ordered (`BTreeMap`), results do not
//! depend on hashing.

use crate::mesh::surface::QuadSurface;
use std::collections::BTreeMap;

/// An undirected edge, smaller vertex first.
pub type Edge = (u32, u32);

pub fn edge(a: u32, b: u32) -> Edge {
    (a.min(b), a.max(b))
}

/// Edge adjacency of a quad surface.
#[derive(Clone, Debug)]
pub struct Adjacency {
    /// Each undirected edge with the quads that use it (one or two on a manifold surface).
    pub edge_quads: BTreeMap<Edge, Vec<u32>>,
    /// The quads around each vertex, in quad order.
    pub vertex_quads: Vec<Vec<u32>>,
}

impl Adjacency {
    pub fn new(s: &QuadSurface) -> Adjacency {
        let mut edge_quads: BTreeMap<Edge, Vec<u32>> = BTreeMap::new();
        let mut vertex_quads = vec![Vec::new(); s.vertices.len()];
        for (q, quad) in s.quads.iter().enumerate() {
            for k in 0..4 {
                edge_quads
                    .entry(edge(quad[k], quad[(k + 1) % 4]))
                    .or_default()
                    .push(q as u32);
                vertex_quads[quad[k] as usize].push(q as u32);
            }
        }
        Adjacency {
            edge_quads,
            vertex_quads,
        }
    }

    /// The vertices joined to `v` by an edge, sorted.
    pub fn neighbours(&self, s: &QuadSurface, v: u32) -> Vec<u32> {
        let mut n: Vec<u32> = Vec::new();
        for &q in &self.vertex_quads[v as usize] {
            let quad = s.quads[q as usize];
            let k = quad.iter().position(|&x| x == v).expect("quad has v");
            n.push(quad[(k + 1) % 4]);
            n.push(quad[(k + 3) % 4]);
        }
        n.sort_unstable();
        n.dedup();
        n
    }

    /// Edges used by more than two quads.
    pub fn non_manifold_edges(&self) -> Vec<Edge> {
        self.edge_quads
            .iter()
            .filter(|(_, q)| q.len() > 2)
            .map(|(e, _)| *e)
            .collect()
    }
}

/// The next vertex of the edge loop that arrives at `cur` from `prev`: at a vertex of
/// valence 4 (four quads around it, interior), the neighbour that shares no quad with the
/// edge `prev`-`cur`. `None` at other vertices (poles, boundary) or where the loop cannot
/// be continued unambiguously.
pub fn loop_step(s: &QuadSurface, adj: &Adjacency, prev: u32, cur: u32) -> Option<u32> {
    if adj.vertex_quads[cur as usize].len() != 4 {
        return None;
    }
    let on_edge = adj.edge_quads.get(&edge(prev, cur))?;
    if on_edge.len() != 2 {
        return None;
    }
    let mut used: Vec<u32> = on_edge.iter().flat_map(|&q| s.quads[q as usize]).collect();
    used.sort_unstable();
    let cand: Vec<u32> = adj
        .neighbours(s, cur)
        .into_iter()
        .filter(|n| used.binary_search(n).is_err())
        .collect();
    (cand.len() == 1).then(|| cand[0])
}

/// The edge loop through the edge `a`-`b`, as a closed vertex cycle starting `a, b, ...`;
/// `None` if it does not close within `max_len` vertices.
pub fn closed_edge_loop(
    s: &QuadSurface,
    adj: &Adjacency,
    a: u32,
    b: u32,
    max_len: usize,
) -> Option<Vec<u32>> {
    let mut l = vec![a, b];
    while l.len() <= max_len {
        let n = loop_step(s, adj, l[l.len() - 2], l[l.len() - 1])?;
        if n == a {
            // closing needs the step from the last vertex back to `a` to continue onto `b`
            return (loop_step(s, adj, l[l.len() - 1], a) == Some(b)).then_some(l);
        }
        if l.contains(&n) {
            return None;
        }
        l.push(n);
    }
    None
}

/// Edge-connected components of a subset of quads (`keep[q]`), without crossing the
/// `barrier` edges. Each component is a sorted list of quads; components are ordered by
/// their smallest quad.
pub fn components(
    s: &QuadSurface,
    adj: &Adjacency,
    keep: &[bool],
    barrier: &std::collections::BTreeSet<Edge>,
) -> Vec<Vec<u32>> {
    let mut comp = vec![usize::MAX; s.quads.len()];
    let mut out: Vec<Vec<u32>> = Vec::new();
    for start in 0..s.quads.len() {
        if !keep[start] || comp[start] != usize::MAX {
            continue;
        }
        let id = out.len();
        let mut members = vec![start as u32];
        comp[start] = id;
        let mut stack = vec![start as u32];
        while let Some(q) = stack.pop() {
            let quad = s.quads[q as usize];
            for k in 0..4 {
                let e = edge(quad[k], quad[(k + 1) % 4]);
                if barrier.contains(&e) {
                    continue;
                }
                for &r in &adj.edge_quads[&e] {
                    let r_us = r as usize;
                    if keep[r_us] && comp[r_us] == usize::MAX {
                        comp[r_us] = id;
                        members.push(r);
                        stack.push(r);
                    }
                }
            }
        }
        members.sort_unstable();
        out.push(members);
    }
    out
}

/// Keeps the quads `keep` of `s` and drops the vertices no kept quad uses. Returns the
/// smaller surface and, for each of its vertices, the vertex of `s` it was.
pub fn submesh(s: &QuadSurface, keep: &[bool]) -> (QuadSurface, Vec<u32>) {
    let mut new_of = vec![u32::MAX; s.vertices.len()];
    let mut old_of = Vec::new();
    let mut quads = Vec::new();
    let mut group_of_quad = Vec::new();
    let mut quad_lines = Vec::new();
    for (q, quad) in s.quads.iter().enumerate() {
        if !keep[q] {
            continue;
        }
        for &v in quad {
            if new_of[v as usize] == u32::MAX {
                new_of[v as usize] = old_of.len() as u32;
                old_of.push(v);
            }
        }
        quads.push(quad.map(|v| new_of[v as usize]));
        group_of_quad.push(s.group_of_quad[q]);
        if let Some(&l) = s.quad_lines.get(q) {
            quad_lines.push(l);
        }
    }
    // keep the input's vertex order (stable, and readable next to the input file)
    let mut order: Vec<u32> = (0..old_of.len() as u32).collect();
    order.sort_by_key(|&i| old_of[i as usize]);
    let mut renumber = vec![0u32; old_of.len()];
    for (new, &i) in order.iter().enumerate() {
        renumber[i as usize] = new as u32;
    }
    let old_sorted: Vec<u32> = order.iter().map(|&i| old_of[i as usize]).collect();
    let quads = quads
        .iter()
        .map(|q: &[u32; 4]| q.map(|v| renumber[v as usize]))
        .collect();
    let sub = QuadSurface {
        vertices: old_sorted.iter().map(|&v| s.vertices[v as usize]).collect(),
        uv: s
            .uv
            .as_ref()
            .map(|uv| old_sorted.iter().map(|&v| uv[v as usize]).collect()),
        quads,
        group_of_quad,
        groups: s.groups.clone(),
        quad_lines,
        notes: s.notes.clone(),
    };
    (sub, old_sorted)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// An `n x m` grid of unit quads in the x-y plane, facing +z.
    pub fn grid(n: usize, m: usize) -> QuadSurface {
        let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        let mut vertices = Vec::new();
        for j in 0..=m {
            for i in 0..=n {
                vertices.push([i as f64, j as f64, 0.0]);
            }
        }
        let mut quads = Vec::new();
        for j in 0..m {
            for i in 0..n {
                quads.push([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let nq = quads.len();
        QuadSurface {
            uv: Some(vertices.iter().map(|v| [v[0], v[1]]).collect()),
            vertices,
            quads,
            group_of_quad: vec![0; nq],
            groups: vec!["g".into()],
            quad_lines: Vec::new(),
            notes: Vec::new(),
        }
    }

    #[test]
    fn submesh_keeps_the_chosen_quads_and_their_vertices_in_order() {
        let s = grid(3, 2);
        let keep: Vec<bool> = (0..6).map(|q| q % 3 != 1).collect();
        let (t, old) = submesh(&s, &keep);
        assert_eq!(t.quads.len(), 4);
        assert!(old.windows(2).all(|w| w[1] > w[0]));
        for (q, quad) in t.quads.iter().enumerate() {
            let orig = s.quads[[0, 2, 3, 5][q]];
            assert_eq!(quad.map(|v| old[v as usize]), orig);
        }
        assert_eq!(t.uv.as_ref().unwrap().len(), t.vertices.len());
        let adj = Adjacency::new(&t);
        assert!(adj.non_manifold_edges().is_empty());
        assert_eq!(adj.neighbours(&t, 0).len(), 2);
    }

    #[test]
    fn edge_loops_close_around_a_cylinder_and_stop_at_boundaries() {
        // a cylinder of 8 x 3 quads: the rings around it close, the lines along it do not
        let (n, m) = (8usize, 3usize);
        let id = |i: usize, j: usize| (j * n + i % n) as u32;
        let mut vertices = Vec::new();
        for j in 0..=m {
            for i in 0..n {
                let a = std::f64::consts::TAU * i as f64 / n as f64;
                vertices.push([a.cos(), a.sin(), j as f64]);
            }
        }
        let mut quads = Vec::new();
        for j in 0..m {
            for i in 0..n {
                quads.push([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let nq = quads.len();
        let s = QuadSurface {
            vertices,
            uv: None,
            quads,
            group_of_quad: vec![0; nq],
            groups: vec!["g".into()],
            quad_lines: Vec::new(),
            notes: Vec::new(),
        };
        let adj = Adjacency::new(&s);
        let ring = closed_edge_loop(&s, &adj, id(0, 1), id(1, 1), 100).unwrap();
        assert_eq!(ring.len(), n);
        assert!(closed_edge_loop(&s, &adj, id(0, 1), id(0, 2), 100).is_none());
        let keep = vec![true; nq];
        let barrier: std::collections::BTreeSet<Edge> =
            (0..n).map(|i| edge(id(i, 1), id(i + 1, 1))).collect();
        let c = components(&s, &adj, &keep, &barrier);
        assert_eq!(c.len(), 2);
        assert_eq!(c[0].len(), n);
        assert_eq!(c[1].len(), 2 * n);
    }
}
