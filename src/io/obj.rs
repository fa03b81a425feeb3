//! Wavefront OBJ quad surfaces with material groups (paper section 3.1: the face was a
//! quad surface exported from Blender as OBJ, its material regions marked, then each quad
//! was extruded into a hexahedron; see [`crate::mesh::extrude`]).
//!
//! Read: `v x y z [w | r g b]`, `vt u [v [w]]` (kept: per-vertex texture coordinates),
//! `f a b c d` with the index forms `a`, `a/t`, `a//n`, `a/t/n` (1-based; negative indices
//! count back from the last element defined so far; positive indices may refer forward),
//! `g name` and `usemtl name` (either one sets the material group of the faces that follow;
//! when both appear, the later statement wins; faces before any of them are in group
//! `default`), `#` comments and `\` line continuations. Other statements (`vn`, `o`, `s`,
//! `mtllib`, `l`, `p`, ...) are ignored. Groups are numbered in the order of their first face.
//!
//! Only quads can be extruded, so a face with another vertex count is an error naming its
//! line; so are indices out of range and unparsable numbers.
//!
//! Texture coordinates are stored per vertex (an FE mesh keeps vertices shared). Where a
//! vertex is given different `vt`s by different faces (a UV seam), the first is kept and the
//! count is reported in [`QuadSurface::notes`]. If some used vertex never gets a `vt`,
//! `uv` is `None` (with a note).
//!
//! Write: [`write_obj`] writes vertices with shortest round-trip decimals (reading the file
//! back gives the same `f64`s), one `vt` per vertex when `uv` is present, and for each run
//! of quads of one group a `g name` and a `usemtl name` line, so Blender shows the groups as
//! materials (as in the paper's Fig. 2) and the quad order is kept.

use crate::error::{Error, Location, Result};
use crate::mesh::surface::{PolySurface, QuadSurface};
use std::io::Write;
use std::path::Path;

/// Reads an OBJ file (see the module docs).
pub fn read_obj(path: &Path) -> Result<QuadSurface> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    parse_obj(&text, &path.display().to_string())
}

/// One face corner as read: vertex index and optional texture index, already resolved
/// to 0-based where they were negative (`Err` keeps a positive index for later checking).
#[derive(Clone, Copy)]
struct Corner {
    v: i64,
    t: Option<i64>,
}

fn parse_index(tok: &str, count: usize, what: &str, file: &str, line: usize) -> Result<i64> {
    let i: i64 = tok.parse().map_err(|_| {
        Error::input(
            file,
            Location::Line(line),
            format!("cannot read {what} index `{tok}` (expected a non-zero integer)"),
        )
    })?;
    if i == 0 {
        return Err(Error::input(
            file,
            Location::Line(line),
            format!("{what} index 0 is invalid: OBJ indices start at 1 (negative ones count back)"),
        ));
    }
    if i < 0 {
        let r = count as i64 + i;
        if r < 0 {
            return Err(Error::input(
                file,
                Location::Line(line),
                format!(
                    "relative {what} index {i} reaches before the first {what}: only {count} are defined above this line"
                ),
            ));
        }
        Ok(r)
    } else {
        Ok(i - 1)
    }
}

fn parse_f64(tok: Option<&str>, what: &str, file: &str, line: usize) -> Result<f64> {
    let tok =
        tok.ok_or_else(|| Error::input(file, Location::Line(line), format!("missing {what}")))?;
    let x: f64 = tok.parse().map_err(|_| {
        Error::input(
            file,
            Location::Line(line),
            format!("cannot read {what} `{tok}` as a number"),
        )
    })?;
    if !x.is_finite() {
        return Err(Error::input(
            file,
            Location::Line(line),
            format!("{what} `{tok}` is not finite"),
        ));
    }
    Ok(x)
}

/// Parses OBJ text; `file` names it in errors.
pub fn parse_obj(text: &str, file: &str) -> Result<QuadSurface> {
    let p = assemble(read_statements(text, file, Faces::Quads)?, file)?;
    Ok(QuadSurface {
        vertices: p.vertices,
        uv: p.uv,
        // read_statements took only faces of four corners
        quads: p.faces.iter().map(|f| [f[0], f[1], f[2], f[3]]).collect(),
        group_of_quad: p.group_of_face,
        groups: p.groups,
        quad_lines: p.face_lines,
        notes: p.notes,
    })
}

/// Reads an OBJ file of any polygons (triangles, quads, more corners): a user's mesh for
/// `sticky-lips face`, which makes it quads with [`PolySurface::to_quads`].
pub fn read_polygons(path: &Path) -> Result<PolySurface> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    parse_polygons(&text, &path.display().to_string())
}

/// Parses OBJ text of any polygons of three or more corners; `file` names it in errors.
pub fn parse_polygons(text: &str, file: &str) -> Result<PolySurface> {
    assemble(read_statements(text, file, Faces::Polygons)?, file)
}

/// Which faces a reader takes.
#[derive(Clone, Copy, PartialEq)]
enum Faces {
    /// Only quads (the surfaces extruded into hexahedra).
    Quads,
    /// Any polygon of three or more corners.
    Polygons,
}

/// The statements of an OBJ file that matter here, as read: indices still unchecked against
/// the final counts (an index may refer forward).
struct Statements {
    vertices: Vec<[f64; 3]>,
    texcoords: Vec<[f64; 2]>,
    /// Each face's corners, its line and its group.
    faces: Vec<(Vec<Corner>, usize, u32)>,
    groups: Vec<String>,
}

/// Reads the `v`, `vt`, `g`/`usemtl` and `f` statements, joining continued lines and
/// dropping comments.
fn read_statements(text: &str, file: &str, take: Faces) -> Result<Statements> {
    let mut vertices: Vec<[f64; 3]> = Vec::new();
    let mut texcoords: Vec<[f64; 2]> = Vec::new();
    let mut faces: Vec<(Vec<Corner>, usize, u32)> = Vec::new();
    let mut groups: Vec<String> = Vec::new();
    let mut current: String = "default".to_string();
    let mut current_index: Option<u32> = None;

    let mut lines = text.lines().enumerate();
    let mut joined = String::new();
    while let Some((i, raw)) = lines.next() {
        let line_no = i + 1;
        // Line continuation: a trailing backslash joins the next physical line.
        let mut logical: &str = raw;
        if raw.trim_end().ends_with('\\') {
            joined.clear();
            let mut cur = raw.trim_end();
            loop {
                joined.push_str(&cur[..cur.len() - 1]);
                joined.push(' ');
                match lines.next() {
                    Some((_, next)) => {
                        if next.trim_end().ends_with('\\') {
                            cur = next.trim_end();
                        } else {
                            joined.push_str(next);
                            break;
                        }
                    }
                    None => break,
                }
            }
            logical = &joined;
        }
        let content = match logical.find('#') {
            Some(k) => &logical[..k],
            None => logical,
        };
        let mut toks = content.split_whitespace();
        let Some(kw) = toks.next() else { continue };
        match kw {
            "v" => {
                let x = parse_f64(toks.next(), "vertex x coordinate", file, line_no)?;
                let y = parse_f64(toks.next(), "vertex y coordinate", file, line_no)?;
                let z = parse_f64(toks.next(), "vertex z coordinate", file, line_no)?;
                vertices.push([x, y, z]);
            }
            "vt" => {
                let u = parse_f64(toks.next(), "texture coordinate u", file, line_no)?;
                let v = match toks.next() {
                    Some(t) => parse_f64(Some(t), "texture coordinate v", file, line_no)?,
                    None => 0.0,
                };
                texcoords.push([u, v]);
            }
            "g" | "usemtl" => {
                let name = content.trim_start()[kw.len()..].trim();
                current = if name.is_empty() {
                    "default".to_string()
                } else {
                    name.to_string()
                };
                current_index = None;
            }
            "f" => {
                let corners: Vec<&str> = toks.collect();
                if take == Faces::Polygons && corners.len() < 3 {
                    return Err(Error::input(
                        file,
                        Location::Line(line_no),
                        format!(
                            "face has {} vertices (degenerate): a face needs at least 3",
                            corners.len()
                        ),
                    ));
                }
                if take == Faces::Quads && corners.len() != 4 {
                    let what = match corners.len() {
                        3 => " (a triangle)".to_string(),
                        0..=2 => " (degenerate)".to_string(),
                        _ => " (a polygon)".to_string(),
                    };
                    return Err(Error::input(
                        file,
                        Location::Line(line_no),
                        format!(
                            "face has {} vertices{what}; only quads (4 vertices) can be extruded into hexahedra: \
                             convert the surface to quads (e.g. Blender's Tris to Quads) first",
                            corners.len()
                        ),
                    ));
                }
                let c = parse_corners(&corners, vertices.len(), texcoords.len(), file, line_no)?;
                let g = match current_index {
                    Some(g) => g,
                    None => {
                        let g = match groups.iter().position(|n| *n == current) {
                            Some(g) => g,
                            None => {
                                groups.push(current.clone());
                                groups.len() - 1
                            }
                        } as u32;
                        current_index = Some(g);
                        g
                    }
                };
                faces.push((c, line_no, g));
            }
            _ => {}
        }
    }
    Ok(Statements {
        vertices,
        texcoords,
        faces,
        groups,
    })
}

/// The corners `v[/t[/n]]` of an `f` statement (`nv` vertices and `nt` texture
/// coordinates defined so far, for negative indices).
fn parse_corners(
    corners: &[&str],
    nv: usize,
    nt: usize,
    file: &str,
    line_no: usize,
) -> Result<Vec<Corner>> {
    let mut c = vec![Corner { v: 0, t: None }; corners.len()];
    for (k, tok) in corners.iter().enumerate() {
        let mut parts = tok.split('/');
        let vi = parts.next().unwrap_or("");
        let v = parse_index(vi, nv, "vertex", file, line_no)?;
        let t = match parts.next() {
            Some(ti) if !ti.is_empty() => {
                Some(parse_index(ti, nt, "texture coordinate", file, line_no)?)
            }
            _ => None,
        };
        c[k] = Corner { v, t };
    }
    Ok(c)
}

/// The surface: every index checked, texture coordinates per vertex (the first of a seam
/// kept, with a note), groups in order of their first face.
fn assemble(st: Statements, file: &str) -> Result<PolySurface> {
    let Statements {
        vertices,
        texcoords,
        faces,
        groups,
    } = st;
    let nv = vertices.len();
    let nt = texcoords.len();
    let mut quads = Vec::with_capacity(faces.len());
    let mut group_of_quad = Vec::with_capacity(faces.len());
    let mut quad_lines = Vec::with_capacity(faces.len());
    let mut uv: Vec<[f64; 2]> = vec![[0.0; 2]; nv];
    let mut has_uv = vec![false; nv];
    let mut used = vec![false; nv];
    let mut seams = 0usize;
    let mut any_uv = false;
    for (c, line, g) in &faces {
        let mut q = vec![0u32; c.len()];
        for (k, corner) in c.iter().enumerate() {
            if corner.v as usize >= nv {
                return Err(Error::input(
                    file,
                    Location::Line(*line),
                    format!(
                        "vertex index {} is out of range: the file defines {nv} vertices",
                        corner.v + 1
                    ),
                ));
            }
            q[k] = corner.v as u32;
            used[corner.v as usize] = true;
            if let Some(t) = corner.t {
                if t as usize >= nt {
                    return Err(Error::input(
                        file,
                        Location::Line(*line),
                        format!(
                            "texture coordinate index {} is out of range: the file defines {nt} texture coordinates",
                            t + 1
                        ),
                    ));
                }
                any_uv = true;
                let v = corner.v as usize;
                let val = texcoords[t as usize];
                if !has_uv[v] {
                    has_uv[v] = true;
                    uv[v] = val;
                } else if uv[v] != val {
                    seams += 1;
                }
            }
        }
        quads.push(q);
        group_of_quad.push(*g);
        quad_lines.push(*line);
    }
    let mut notes = Vec::new();
    let uv = if !any_uv {
        None
    } else {
        let missing = (0..nv).filter(|&v| used[v] && !has_uv[v]).count();
        if missing > 0 {
            notes.push(format!(
                "{missing} used vertices have no texture coordinate: texture coordinates dropped"
            ));
            None
        } else {
            if seams > 0 {
                notes.push(format!(
                    "{seams} face corners give a vertex a different texture coordinate than an earlier face \
                     (UV seams); each vertex keeps its first one"
                ));
            }
            Some(uv)
        }
    };
    Ok(PolySurface {
        vertices,
        uv,
        faces: quads,
        group_of_face: group_of_quad,
        groups,
        face_lines: quad_lines,
        notes,
    })
}

/// Writes `s` as OBJ text into `w`.
pub fn write_obj_to(w: &mut dyn Write, s: &QuadSurface) -> std::io::Result<()> {
    writeln!(
        w,
        "# sticky-lips quad surface: {} vertices, {} quads, {} groups",
        s.vertices.len(),
        s.quads.len(),
        s.groups.len()
    )?;
    let faces = s.quads.iter().map(|q| &q[..]).zip(&s.group_of_quad);
    write_body(w, &s.vertices, s.uv.as_deref(), faces, &s.groups)
}

/// Writes a polygon surface as OBJ text into `w` (as [`write_obj_to`], faces of any size).
pub fn write_polygons_to(w: &mut dyn Write, s: &PolySurface) -> std::io::Result<()> {
    writeln!(
        w,
        "# sticky-lips surface: {} vertices, {} faces, {} groups",
        s.vertices.len(),
        s.faces.len(),
        s.groups.len()
    )?;
    let faces = s.faces.iter().map(|f| &f[..]).zip(&s.group_of_face);
    write_body(w, &s.vertices, s.uv.as_deref(), faces, &s.groups)
}

/// Vertices, texture coordinates and faces with a `g`/`usemtl` pair at each change of group.
fn write_body<'a>(
    w: &mut dyn Write,
    vertices: &[[f64; 3]],
    uv: Option<&[[f64; 2]]>,
    faces: impl Iterator<Item = (&'a [u32], &'a u32)>,
    groups: &[String],
) -> std::io::Result<()> {
    for x in vertices {
        writeln!(w, "v {} {} {}", x[0], x[1], x[2])?;
    }
    if let Some(uv) = uv {
        for t in uv {
            writeln!(w, "vt {} {}", t[0], t[1])?;
        }
    }
    let mut last: Option<u32> = None;
    for (face, &g) in faces {
        if last != Some(g) {
            let name = groups
                .get(g as usize)
                .map(String::as_str)
                .unwrap_or("default");
            writeln!(w, "g {name}")?;
            writeln!(w, "usemtl {name}")?;
            last = Some(g);
        }
        write!(w, "f")?;
        for &i in face {
            if uv.is_some() {
                write!(w, " {}/{}", i + 1, i + 1)?;
            } else {
                write!(w, " {}", i + 1)?;
            }
        }
        writeln!(w)?;
    }
    Ok(())
}

/// Atomically writes `s` to `path` as OBJ (see the module docs).
pub fn write_obj(path: &Path, s: &QuadSurface) -> Result<()> {
    s.validate(&path.display().to_string())?;
    crate::io::atomic::write_atomic_with(path, |w| write_obj_to(w, s))
        .map_err(|e| Error::io(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn msg(e: Error) -> String {
        e.to_string()
    }

    const SQUARE: &str = "\
# two quads, two materials
v 0 0 0
v 1 0 0
v 2 0 0
v 0 1 0
v 1 1 0
v 2 1 0
vt 0 0
vt 0.5 0
vt 1 0
vt 0 1
vt 0.5 1
vt 1 1
o Face
usemtl skin
f 1/1/1 2/2/1 5/5/1 4/4/1
g saliva
f -5/-5 -4/-4 -1/-1 -2/-2
";

    #[test]
    fn parses_groups_uv_and_index_forms() {
        let s = parse_obj(SQUARE, "sq.obj").unwrap();
        assert_eq!(s.vertices.len(), 6);
        assert_eq!(s.quads, vec![[0, 1, 4, 3], [1, 2, 5, 4]]);
        assert_eq!(s.groups, vec!["skin".to_string(), "saliva".to_string()]);
        assert_eq!(s.group_of_quad, vec![0, 1]);
        assert_eq!(s.quad_lines, vec![16, 18]);
        let uv = s.uv.as_ref().unwrap();
        assert_eq!(uv[4], [0.5, 1.0]);
        assert!(s.notes.is_empty());
    }

    #[test]
    fn round_trip_is_exact() {
        let mut s = parse_obj(SQUARE, "sq.obj").unwrap();
        s.vertices[4] = [0.1 + 0.2, 1.0 / 3.0, -7.25e-9];
        let dir = std::env::temp_dir().join(format!("sticky-lips-obj-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("rt.obj");
        write_obj(&path, &s).unwrap();
        let r = read_obj(&path).unwrap();
        assert_eq!(r.vertices, s.vertices);
        assert_eq!(r.uv, s.uv);
        assert_eq!(r.quads, s.quads);
        assert_eq!(r.group_of_quad, s.group_of_quad);
        assert_eq!(r.groups, s.groups);
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn non_quad_face_names_its_line() {
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\nf 1 2 3\n";
        let e = msg(parse_obj(text, "tri.obj").unwrap_err());
        assert!(e.starts_with("tri.obj:6:"), "{e}");
        assert!(e.contains("3 vertices") && e.contains("triangle"), "{e}");
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 2 0\nf 1 2 3 4 5\n";
        let e = msg(parse_obj(text, "pent.obj").unwrap_err());
        assert!(
            e.starts_with("pent.obj:6:") && e.contains("5 vertices"),
            "{e}"
        );
    }

    #[test]
    fn bad_indices_and_numbers_are_errors() {
        let e = msg(parse_obj("v 0 0 0\nf 1 2 3 4\n", "a.obj").unwrap_err());
        assert!(
            e.starts_with("a.obj:2:") && e.contains("out of range"),
            "{e}"
        );
        let e = msg(parse_obj("v 0 0 0\nf 1 1 1 -2\n", "b.obj").unwrap_err());
        assert!(e.starts_with("b.obj:2:") && e.contains("-2"), "{e}");
        let e = msg(parse_obj("v 0 0 0\nf 0 1 1 1\n", "c.obj").unwrap_err());
        assert!(e.starts_with("c.obj:2:") && e.contains("index 0"), "{e}");
        let e = msg(parse_obj("v 0 0x 0\n", "d.obj").unwrap_err());
        assert!(e.starts_with("d.obj:1:") && e.contains("`0x`"), "{e}");
        let e = msg(parse_obj("v 0 0\n", "e.obj").unwrap_err());
        assert!(e.starts_with("e.obj:1:") && e.contains("missing"), "{e}");
        let e = msg(parse_obj("v 0 0 0\nvt 0 0\nf 1/2 1/1 1/1 1/1\n", "f.obj").unwrap_err());
        assert!(e.starts_with("f.obj:3:") && e.contains("texture"), "{e}");
    }

    #[test]
    fn continuation_comments_and_forward_references() {
        let text =
            "f 1 2 \\\n 3 4 # a quad before its vertices\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";
        let s = parse_obj(text, "c.obj").unwrap();
        assert_eq!(s.quads, vec![[0, 1, 2, 3]]);
        assert_eq!(s.quad_lines, vec![1]);
        assert_eq!(s.groups, vec!["default".to_string()]);
        assert!(s.uv.is_none());
    }

    #[test]
    fn uv_seams_are_noted() {
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 9 9\n\
                    f 1/1 2/2 3/3 4/4\nf 2/5 5/1 6/1 3/3\n";
        let s = parse_obj(text, "s.obj").unwrap();
        assert_eq!(s.uv.as_ref().unwrap()[1], [1.0, 0.0]);
        assert_eq!(s.notes.len(), 1, "{:?}", s.notes);
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\nvt 0 0\n\
                    f 1/1 2/1 3/1 4/1\nf 2 5 6 3\n";
        let s = parse_obj(text, "m.obj").unwrap();
        assert!(s.uv.is_none());
        assert_eq!(s.notes.len(), 1);
    }

    #[test]
    fn polygons_are_read_and_written_back_as_they_are() {
        let text = "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nv 1 1 0\nv 2 1 0\nv 3 0.5 0\n\
                    f 1 2 5 4\ng tri\nf 2 3 6\nf 2 6 5\nf 3 7 6 # a fan\nf 1 2 3 7 6 5 4\n";
        let p = parse_polygons(text, "p.obj").unwrap();
        assert_eq!(p.faces.len(), 5);
        assert_eq!(p.faces[1], vec![1, 2, 5]);
        assert_eq!(p.faces[4].len(), 7);
        assert_eq!(p.face_lines, vec![8, 10, 11, 12, 13]);
        assert_eq!(p.groups, vec!["default", "tri"]);
        let mut out = Vec::new();
        write_polygons_to(&mut out, &p).unwrap();
        let back = parse_polygons(std::str::from_utf8(&out).unwrap(), "back.obj").unwrap();
        assert_eq!(back.vertices, p.vertices);
        assert_eq!(back.faces, p.faces);
        assert_eq!(back.group_of_face, p.group_of_face);
        // the quad reader still refuses the triangles, naming the first one's line
        let e = parse_obj(text, "p.obj").unwrap_err().to_string();
        assert!(e.contains("p.obj:10") && e.contains("triangle"), "{e}");
        // and a two-corner face is refused by both
        let e = parse_polygons("v 0 0 0\nv 1 0 0\nf 1 2\n", "d.obj")
            .unwrap_err()
            .to_string();
        assert!(e.contains("d.obj:3") && e.contains("degenerate"), "{e}");
    }
}
