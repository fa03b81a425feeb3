//! The face's lip finder on small meshes made from the input: `face::prepare` (the whole
//! first half of `sticky-lips face`: checks, the lip contour found, the crop) with a fixed
//! frame (millimetres, y up, z forward) and no rig, and `face::lips::detect_axes` (what
//! `face` does without `--up` and `--forward`).
//!
//! The mesh is a template of a few dozen vertices, a flat grid of quads or a small mouth (a
//! flange around a slit that goes back into a tube, as the unit tests' synthetic head, with
//! or without a nose), changed by the input's bytes: the template and its size, a scale, an
//! offset size, all vertices made one point, then per face one operation (kept, dropped
//! leaving a hole, split into triangles, turned over, a corner replaced by any vertex:
//! degenerate, repeated or non-manifold), then per vertex an offset, then faces of any
//! vertices from the bytes left.
//!
//! Must hold: an error or a value, never a panic, an abort or a hang; detected axes are two
//! perpendicular unit vectors; a face that is made has lip lines of two or more vertices on
//! its surface and a finite jaw weight in [0, 1] per vertex.
#![no_main]
use libfuzzer_sys::fuzz_target;
use sticky_lips::mesh::face::{self, FaceRig, InputFrame, PrepareParams};
use sticky_lips::mesh::surface::PolySurface;

/// The input's bytes in order; zeros once they run out.
struct Bytes<'a>(&'a [u8]);

impl Bytes<'_> {
    fn next(&mut self) -> u8 {
        match self.0.split_first() {
            Some((&b, rest)) => {
                self.0 = rest;
                b
            }
            None => 0,
        }
    }
    fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

/// A flat grid of `nx` x `ny` vertices 5 mm apart, quads facing +z.
fn grid(nx: usize, ny: usize) -> (Vec<[f64; 3]>, Vec<Vec<u32>>) {
    let mut v = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            v.push([5.0 * i as f64, 5.0 * j as f64, 0.0]);
        }
    }
    let id = |i: usize, j: usize| (j * nx + i) as u32;
    let mut f = Vec::new();
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            f.push(vec![id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (v, f)
}

/// A small mouth (mm): `nu` vertices around each of `flange` rings of the face narrowing to
/// the lips (an elliptic slit 50 mm wide, 1.2 mm open; ring `k` out from the lips 10 k mm
/// wider and 4 k^2 mm behind them, curved back like a head's), then `tube` rings going back
/// into the mouth; quads, the flange facing +z. With `nose`, the outer ring's top vertex
/// (above the mouth's middle where `nu` is a multiple of 4) lies 10 mm in front of the lips.
fn mouth(nu: usize, flange: usize, tube: usize, nose: bool) -> (Vec<[f64; 3]>, Vec<Vec<u32>>) {
    let rings = flange + tube + 1;
    let mut v = Vec::new();
    for r in 0..rings {
        let (a, b, z) = if r <= flange {
            let k = (flange - r) as f64;
            (25.0 + 10.0 * k, 0.6 + 10.0 * k, -4.0 * k * k)
        } else {
            let k = (r - flange) as f64;
            (25.0, 0.6 + 2.0 * k, -3.0 * k)
        };
        for i in 0..nu {
            let t = std::f64::consts::TAU * i as f64 / nu as f64;
            v.push([a * t.cos(), b * t.sin(), z]);
        }
    }
    if nose {
        v[nu / 4][2] = 10.0;
    }
    let id = |i: usize, r: usize| (r * nu + i % nu) as u32;
    let mut f = Vec::new();
    for r in 0..rings - 1 {
        for i in 0..nu {
            // outer ring to inner ring, counter-clockwise seen from +z: the normal is +z
            f.push(vec![id(i, r), id(i + 1, r), id(i + 1, r + 1), id(i, r + 1)]);
        }
    }
    (v, f)
}

fn surface(data: &[u8]) -> PolySurface {
    let mut b = Bytes(data);
    let shape = b.next();
    let (mut vertices, template) = if shape & 1 == 0 {
        grid(2 + (shape as usize >> 1) % 6, 2 + (shape as usize >> 4) % 6)
    } else {
        mouth(
            [8, 10, 12, 16][(shape as usize >> 1) % 4],
            2 + (shape as usize >> 3) % 2,
            1 + (shape as usize >> 4) % 2,
            shape & 32 != 0,
        )
    };
    let flags = b.next();
    let scale = [1.0, 1e-3, 1e3, 1e100][(flags & 3) as usize];
    let amplitude = [0.0, 0.05, 0.5, 5.0][((flags >> 2) & 3) as usize];
    let nv = vertices.len() as u32;
    let mut faces = Vec::new();
    for f in template {
        let op = b.next();
        match op % 8 {
            4 => {}
            5 => {
                faces.push(vec![f[0], f[1], f[2]]);
                faces.push(vec![f[0], f[2], f[3]]);
            }
            6 => faces.push(f.into_iter().rev().collect()),
            7 => {
                let mut f = f;
                f[(op as usize >> 3) % 4] = b.next() as u32 % nv;
                faces.push(f);
            }
            _ => faces.push(f),
        }
    }
    for v in vertices.iter_mut() {
        for c in v.iter_mut() {
            *c += amplitude * (b.next() as f64 - 128.0) / 128.0;
        }
    }
    if flags >> 4 == 5 {
        let p = vertices[0];
        vertices.iter_mut().for_each(|v| *v = p);
    }
    for v in vertices.iter_mut() {
        *v = v.map(|c| c * scale);
    }
    // faces of any vertices: a count of corners, then the corners
    while flags & 128 != 0 && !b.is_empty() && faces.len() < 400 {
        let n = 3 + b.next() as usize % 4;
        faces.push((0..n).map(|_| b.next() as u32 % nv).collect());
    }
    PolySurface {
        vertices,
        uv: None,
        group_of_face: vec![0; faces.len()],
        faces,
        groups: vec!["head".into()],
        face_lines: Vec::new(),
        notes: Vec::new(),
    }
}

fuzz_target!(|data: &[u8]| {
    let head = surface(data);
    let params = PrepareParams::default();
    if let Ok(a) =
        face::lips::detect_axes(&head, 1e-3, &params, "fuzz/head.obj", &Default::default())
    {
        let dot = |p: [f64; 3], q: [f64; 3]| p[0] * q[0] + p[1] * q[1] + p[2] * q[2];
        assert!((dot(a.up, a.up) - 1.0).abs() < 1e-9, "{a:?}");
        assert!((dot(a.forward, a.forward) - 1.0).abs() < 1e-9, "{a:?}");
        assert!(dot(a.up, a.forward).abs() < 1e-9, "{a:?}");
    }
    let frame = InputFrame {
        scale: 1e-3,
        up: [0.0, 1.0, 0.0],
        forward: [0.0, 0.0, 1.0],
    };
    let rig = FaceRig::default();
    if let Ok(src) = face::prepare(&head, &rig, frame, &params, "fuzz/head.obj") {
        let nv = src.surface.vertices.len();
        for line in [&src.data.upper_contour, &src.data.lower_contour] {
            assert!(
                line.len() >= 2 && line.iter().all(|&v| (v as usize) < nv),
                "{line:?}"
            );
        }
        assert_eq!(src.data.jaw_weight.len(), nv);
        assert!(src.data.jaw_weight.iter().all(|w| (0.0..=1.0).contains(w)));
    }
});
