//! A face rig (`sticky-lips face HEAD.obj --rig RIG.json`) as `FaceRig::from_json` reads it,
//! and a rig that reads run through `face::prepare` on the MakeHuman face
//! (`assets/makehuman/face.obj`, 686 vertices, compiled in and read once) in the frame of
//! `sticky-lips face face.obj --units m --up 0,1,0 --forward 0,0,1` (metres, y up, z forward:
//! the face is in the model frame; `face` cannot take either from the face alone, which is
//! smaller than a head and has no nose). The repository ships no whole head; the face is the
//! head's front around the lips, and a rig's arrays are on its vertices.
//!
//! Must hold: an error or a face, never a panic, an abort or a hang. A face that is made has
//! both lip lines (two vertices or more, on the surface), one finite jaw weight in [0, 1] per
//! vertex, a finite hinge, a unit hinge axis and finite blend-shape offsets, and its
//! `face.obj` and `face.json` texts read back (`face::parse`).
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::sync::OnceLock;
use sticky_lips::mesh::face::{self, FaceRig, InputFrame};
use sticky_lips::mesh::surface::PolySurface;

const HEAD: &str = include_str!("../../assets/makehuman/face.obj");
const HEAD_NAME: &str = "fuzz/head.obj";

fn head() -> &'static (PolySurface, InputFrame) {
    static ONCE: OnceLock<(PolySurface, InputFrame)> = OnceLock::new();
    ONCE.get_or_init(|| {
        let head = sticky_lips::io::obj::parse_polygons(HEAD, "assets/makehuman/face.obj")
            .expect("the MakeHuman face reads");
        let frame = InputFrame {
            scale: 1.0,
            up: [0.0, 1.0, 0.0],
            forward: [0.0, 0.0, 1.0],
        };
        (head, frame)
    })
}

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let (head, frame) = head();
    let Ok(rig) = FaceRig::from_json(text, "fuzz/rig.json") else {
        return;
    };
    let Ok(src) = face::prepare(head, &rig, *frame, &Default::default(), HEAD_NAME) else {
        return;
    };
    let (s, d) = (&src.surface, &src.data);
    let nv = s.vertices.len();
    for line in [&d.upper_contour, &d.lower_contour] {
        assert!(
            line.len() >= 2 && line.iter().all(|&v| (v as usize) < nv),
            "{line:?}"
        );
    }
    assert_eq!(d.jaw_weight.len(), nv);
    assert!(
        d.jaw_weight.iter().all(|w| (0.0..=1.0).contains(w)),
        "jaw weights"
    );
    let finite = |p: &[f64; 3]| p.iter().all(|x| x.is_finite());
    assert!(finite(&d.hinge_point), "hinge point {:?}", d.hinge_point);
    let n = d.hinge_axis.iter().map(|x| x * x).sum::<f64>().sqrt();
    assert!((n - 1.0).abs() < 1e-9, "hinge axis {:?}", d.hinge_axis);
    for (name, t) in &d.targets {
        assert_eq!(t.len(), nv, "{name}");
        assert!(t.iter().all(finite), "target {name} not finite");
    }
    let (obj, json) = face::to_texts(&src);
    if let Err(e) = face::parse(&obj, &json, "fuzz/face.obj", "fuzz/face.json") {
        panic!("the face made does not read back: {e}");
    }
});
