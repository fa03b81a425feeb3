//! Files the animation packages play: point caches (PC2, MDD) and USD with time samples.
//!
//! * **PC2** (3ds Max's Point Cache 2; Blender's Mesh Cache modifier, Maya `cacheFile -pc2`):
//!   little-endian; a 32-byte header (`"POINTCACHE2\0"`, version `1` as `i32`, the point
//!   count `i32`, the first frame `f32`, the frames between samples `f32`, the sample count
//!   `i32`), then every sample's points as `f32` triples.
//! * **MDD** (LightWave's; Blender's Mesh Cache modifier): big-endian; the frame count and the
//!   point count (`i32`), every frame's time in seconds (`f32`), then every frame's points as
//!   `f32` triples.
//! * **USDA** (USD's text layer): a `Mesh` prim per surface whose `points` carry one time
//!   sample per frame, `timeCodesPerSecond` set so that the time codes are the frame numbers
//!   and the animation plays in simulated time; per-face data as `uniform` primvars with time
//!   samples.
//!
//! Floats are written in the shortest form that reads back as the same `f32`, so every reader
//! gets the positions the PC2 file holds, bit for bit.

use std::fmt::Write as _;

/// A PC2 file of `frames` (each the same number of points), one sample per frame from frame
/// `start`.
pub fn pc2_bytes(frames: &[Vec<[f32; 3]>], start: f32) -> Vec<u8> {
    let np = frames.first().map_or(0, |f| f.len());
    let mut b = Vec::with_capacity(32 + frames.len() * np * 12);
    b.extend_from_slice(b"POINTCACHE2\0");
    b.extend_from_slice(&1i32.to_le_bytes());
    b.extend_from_slice(&(np as i32).to_le_bytes());
    b.extend_from_slice(&start.to_le_bytes());
    b.extend_from_slice(&1f32.to_le_bytes());
    b.extend_from_slice(&(frames.len() as i32).to_le_bytes());
    for f in frames {
        debug_assert_eq!(f.len(), np);
        for p in f {
            for c in p {
                b.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    b
}

/// An MDD file of `frames` at `times` (s).
pub fn mdd_bytes(frames: &[Vec<[f32; 3]>], times: &[f64]) -> Vec<u8> {
    let np = frames.first().map_or(0, |f| f.len());
    let mut b = Vec::with_capacity(8 + 4 * times.len() + frames.len() * np * 12);
    b.extend_from_slice(&(frames.len() as i32).to_be_bytes());
    b.extend_from_slice(&(np as i32).to_be_bytes());
    for &t in times {
        b.extend_from_slice(&(t as f32).to_be_bytes());
    }
    for f in frames {
        for p in f {
            for c in p {
                b.extend_from_slice(&c.to_be_bytes());
            }
        }
    }
    b
}

/// A mesh prim of a USD layer: faces, rest points, the points of every frame, and per-face
/// values of every frame (`uniform` primvars).
pub struct UsdMesh<'a> {
    pub name: &'a str,
    pub faces: &'a [Vec<u32>],
    pub rest: &'a [[f32; 3]],
    pub frames: &'a [Vec<[f32; 3]>],
    /// Vertex texture coordinates (`primvars:st`), if any.
    pub uv: Option<&'a [[f32; 2]]>,
    /// `(name, values of every frame, one per face)`.
    pub face_data: Vec<(&'a str, Vec<Vec<f32>>)>,
}

/// Metadata of a USD layer.
pub struct UsdLayer<'a> {
    pub doc: &'a str,
    /// `"Y"` or `"Z"`.
    pub up_axis: &'a str,
    pub metres_per_unit: f64,
    /// Frames per simulated second (the time codes are frame numbers).
    pub frames_per_second: f64,
    pub meshes: Vec<UsdMesh<'a>>,
}

fn fmt_f32(out: &mut String, x: f32) {
    // `{:?}` of an f32 is its shortest round-trip form (`1.0`, `0.0125`, `1e-7`)
    let _ = write!(out, "{x:?}");
}

fn points_array(out: &mut String, pts: &[[f32; 3]]) {
    out.push('[');
    for (i, p) in pts.iter().enumerate() {
        if i > 0 {
            out.push_str(", ");
        }
        out.push('(');
        fmt_f32(out, p[0]);
        out.push_str(", ");
        fmt_f32(out, p[1]);
        out.push_str(", ");
        fmt_f32(out, p[2]);
        out.push(')');
    }
    out.push(']');
}

fn float_array(out: &mut String, v: &[f32]) {
    out.push('[');
    for (i, &x) in v.iter().enumerate() {
        if i > 0 {
            out.push_str(", ");
        }
        fmt_f32(out, x);
    }
    out.push(']');
}

fn quote(s: &str) -> String {
    let mut q = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => q.push_str("\\\""),
            '\\' => q.push_str("\\\\"),
            '\n' => q.push_str("\\n"),
            c if c.is_control() => {}
            c => q.push(c),
        }
    }
    q.push('"');
    q
}

/// A prim name: letters, digits and `_`, not starting with a digit.
pub fn prim_name(s: &str) -> String {
    let mut n: String = s
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if n.is_empty() || n.starts_with(|c: char| c.is_ascii_digit()) {
        n.insert(0, '_');
    }
    n
}

/// The text of a USDA layer: a root `Xform` named `sticky_lips` (the default prim) holding
/// the meshes.
pub fn usda_text(layer: &UsdLayer) -> String {
    let nf = layer
        .meshes
        .iter()
        .map(|m| m.frames.len())
        .max()
        .unwrap_or(0);
    let mut o = String::new();
    o.push_str("#usda 1.0\n(\n");
    let _ = writeln!(o, "    defaultPrim = \"sticky_lips\"");
    let _ = writeln!(o, "    doc = {}", quote(layer.doc));
    let _ = writeln!(o, "    endTimeCode = {}", nf.saturating_sub(1));
    let _ = writeln!(o, "    framesPerSecond = {:?}", layer.frames_per_second);
    let _ = writeln!(o, "    metersPerUnit = {:?}", layer.metres_per_unit);
    let _ = writeln!(o, "    startTimeCode = 0");
    let _ = writeln!(o, "    timeCodesPerSecond = {:?}", layer.frames_per_second);
    let _ = writeln!(o, "    upAxis = \"{}\"", layer.up_axis);
    o.push_str(")\n\ndef Xform \"sticky_lips\"\n{\n");
    for m in &layer.meshes {
        let _ = writeln!(o, "    def Mesh \"{}\"\n    {{", prim_name(m.name));
        o.push_str("        int[] faceVertexCounts = [");
        for (i, f) in m.faces.iter().enumerate() {
            if i > 0 {
                o.push_str(", ");
            }
            let _ = write!(o, "{}", f.len());
        }
        o.push_str("]\n        int[] faceVertexIndices = [");
        let mut first = true;
        for f in m.faces {
            for v in f {
                if !first {
                    o.push_str(", ");
                }
                first = false;
                let _ = write!(o, "{v}");
            }
        }
        o.push_str("]\n        uniform token orientation = \"rightHanded\"\n");
        o.push_str("        point3f[] points = ");
        points_array(&mut o, m.rest);
        o.push_str("\n        point3f[] points.timeSamples = {\n");
        for (k, f) in m.frames.iter().enumerate() {
            let _ = write!(o, "            {k}: ");
            points_array(&mut o, f);
            o.push_str(",\n");
        }
        o.push_str("        }\n");
        for (name, frames) in &m.face_data {
            let _ = writeln!(
                o,
                "        float[] primvars:{} (\n            interpolation = \"uniform\"\n        )",
                prim_name(name)
            );
            let _ = writeln!(
                o,
                "        float[] primvars:{}.timeSamples = {{",
                prim_name(name)
            );
            for (k, v) in frames.iter().enumerate() {
                let _ = write!(o, "            {k}: ");
                float_array(&mut o, v);
                o.push_str(",\n");
            }
            o.push_str("        }\n");
        }
        if let Some(uv) = m.uv {
            o.push_str("        texCoord2f[] primvars:st = [");
            for (i, t) in uv.iter().enumerate() {
                if i > 0 {
                    o.push_str(", ");
                }
                o.push('(');
                fmt_f32(&mut o, t[0]);
                o.push_str(", ");
                fmt_f32(&mut o, t[1]);
                o.push(')');
            }
            o.push_str("] (\n            interpolation = \"vertex\"\n        )\n");
        }
        o.push_str("        uniform token subdivisionScheme = \"none\"\n    }\n");
    }
    o.push_str("}\n");
    o
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frames() -> Vec<Vec<[f32; 3]>> {
        vec![
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.25]],
            vec![[0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.35]],
        ]
    }

    #[test]
    fn pc2_has_its_header_and_little_endian_samples() {
        let b = pc2_bytes(&frames(), 0.0);
        assert_eq!(b.len(), 32 + 2 * 3 * 12);
        assert_eq!(&b[..12], b"POINTCACHE2\0");
        let i32_at = |o: usize| i32::from_le_bytes(b[o..o + 4].try_into().unwrap());
        let f32_at = |o: usize| f32::from_le_bytes(b[o..o + 4].try_into().unwrap());
        assert_eq!((i32_at(12), i32_at(16), i32_at(28)), (1, 3, 2));
        assert_eq!((f32_at(20), f32_at(24)), (0.0, 1.0));
        // second sample, third point, z
        assert_eq!(f32_at(32 + 3 * 12 + 2 * 12 + 8), 0.35);
    }

    #[test]
    fn mdd_is_big_endian_with_the_frame_times() {
        let b = mdd_bytes(&frames(), &[0.0, 0.5]);
        assert_eq!(b.len(), 8 + 2 * 4 + 2 * 3 * 12);
        let i32_at = |o: usize| i32::from_be_bytes(b[o..o + 4].try_into().unwrap());
        let f32_at = |o: usize| f32::from_be_bytes(b[o..o + 4].try_into().unwrap());
        assert_eq!((i32_at(0), i32_at(4)), (2, 3));
        assert_eq!((f32_at(8), f32_at(12)), (0.0, 0.5));
        assert_eq!(f32_at(16 + 3 * 12 + 2 * 12 + 8), 0.35);
    }

    #[test]
    fn usda_lists_faces_time_samples_and_face_primvars() {
        let f = frames();
        let faces = vec![vec![0u32, 1, 2]];
        let layer = UsdLayer {
            doc: "a \"test\"",
            up_axis: "Y",
            metres_per_unit: 0.001,
            frames_per_second: 100.0,
            meshes: vec![UsdMesh {
                name: "skin 1",
                faces: &faces,
                rest: &f[0],
                frames: &f,
                uv: None,
                face_data: vec![("broken", vec![vec![0.0], vec![1.0]])],
            }],
        };
        let t = usda_text(&layer);
        assert!(t.starts_with("#usda 1.0\n"));
        for want in [
            "doc = \"a \\\"test\\\"\"",
            "endTimeCode = 1",
            "metersPerUnit = 0.001",
            "timeCodesPerSecond = 100.0",
            "def Mesh \"skin_1\"",
            "int[] faceVertexCounts = [3]",
            "int[] faceVertexIndices = [0, 1, 2]",
            "1: [(0.0, 0.0, 0.1), (1.0, 0.0, 0.1), (0.0, 1.0, 0.35)],",
            "float[] primvars:broken.timeSamples = {",
            "1: [1.0],",
        ] {
            assert!(t.contains(want), "{want:?} missing from\n{t}");
        }
        assert_eq!(prim_name("9lives"), "_9lives");
    }
}
