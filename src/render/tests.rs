use super::plot::{heatmap_plot, line_plot, profile_plot, PlotSpec, ProfileSpec, Series};
use super::*;
use crate::linalg::{dot, sub};
use crate::mesh::generate::block;

const BG: [u8; 3] = [255, 255, 255];
/// Colours by local face: bottom, top, y-, x+, y+, x-.
const FACE_COLOURS: [[u8; 3]; 6] = [
    [200, 30, 30],
    [30, 200, 30],
    [30, 30, 200],
    [200, 200, 30],
    [200, 30, 200],
    [30, 200, 200],
];

fn unit_cube() -> (Vec<[f64; 3]>, Vec<BoundaryFace>) {
    let m = block([0.0; 3], [1.0; 3], [1, 1, 1]);
    let faces = boundary_quads(&m.elements);
    (m.nodes, faces)
}

fn front_camera(projection: Projection) -> Camera {
    Camera {
        eye: [0.5, -3.0, 0.5],
        target: [0.5, 0.5, 0.5],
        up: [0.0, 0.0, 1.0],
        fov_y_degrees: 40.0,
        projection,
    }
}

#[test]
fn unit_cube_front_view_shows_front_face_and_background() {
    let (nodes, faces) = unit_cube();
    assert_eq!(faces.len(), 6);
    for projection in [Projection::Perspective, Projection::Orthographic] {
        let cam = front_camera(projection);
        let img = render_mesh_with(
            &nodes,
            &faces,
            &|f| FACE_COLOURS[f.local_face as usize],
            None,
            &cam,
            &RenderOptions::unlit(64, 48),
        );
        assert_eq!(
            (img.width, img.height, img.rgb.len()),
            (64, 48, 64 * 48 * 3)
        );
        // The y- face (local face 2) faces the camera.
        assert_eq!(img.get(32, 24), FACE_COLOURS[2], "{projection:?}");
        for (x, y) in [(0, 0), (63, 0), (0, 47), (63, 47)] {
            assert_eq!(img.get(x, y), BG, "{projection:?} corner ({x}, {y})");
        }
        // Only the front face is visible head-on.
        for p in img.rgb.chunks_exact(3) {
            assert!(p == BG || p == FACE_COLOURS[2] || is_blend(p, BG, FACE_COLOURS[2]));
        }
    }
    // Lit: the front face keeps its hue (blue dominant) and is not black.
    let img = render_mesh(
        &nodes,
        &faces,
        &|f| FACE_COLOURS[f.local_face as usize],
        None,
        &front_camera(Projection::Perspective),
        64,
        48,
    );
    let c = img.get(32, 24);
    assert!(c[2] > c[0] + 60 && c[2] > c[1] + 60 && c[2] > 100, "{c:?}");
}

/// `p` lies between `a` and `b` channel-wise (an anti-aliased edge pixel).
fn is_blend(p: &[u8], a: [u8; 3], b: [u8; 3]) -> bool {
    (0..3).all(|k| p[k] >= a[k].min(b[k]) && p[k] <= a[k].max(b[k]))
}

#[test]
fn cube_seen_from_a_corner_shows_three_faces() {
    let (nodes, faces) = unit_cube();
    let cam = Camera::fit(
        &nodes,
        [-1.0, 1.0, -1.0], // from (x+, y-, z+) towards the cube
        [0.0, 0.0, 1.0],
        30.0,
        Projection::Perspective,
        1.0,
        0.1,
    );
    let img = render_mesh_with(
        &nodes,
        &faces,
        &|f| FACE_COLOURS[f.local_face as usize],
        None,
        &cam,
        &RenderOptions::unlit(96, 96),
    );
    let count = |c: [u8; 3]| img.rgb.chunks_exact(3).filter(|p| *p == c).count();
    // Visible: top (1), y- (2), x+ (3). Hidden: bottom (0), y+ (4), x- (5).
    for f in [1, 2, 3] {
        assert!(
            count(FACE_COLOURS[f]) > 300,
            "face {f}: {}",
            count(FACE_COLOURS[f])
        );
    }
    for f in [0, 4, 5] {
        assert_eq!(count(FACE_COLOURS[f]), 0, "hidden face {f} visible");
    }
    // The fit leaves the border empty.
    for i in 0..96 {
        for (x, y) in [(i, 0), (i, 95), (0, i), (95, i)] {
            assert_eq!(img.get(x, y), BG);
        }
    }
}

fn square(z: f64, half: f64, colour: [u8; 3]) -> [Triangle; 2] {
    let p = |x: f64, y: f64| [x, y, z];
    [
        Triangle::flat([p(-half, -half), p(half, -half), p(half, half)], colour),
        Triangle::flat([p(-half, -half), p(half, half), p(-half, half)], colour),
    ]
}

#[test]
fn nearer_triangles_occlude_farther_ones_in_any_order() {
    // Camera on +z looking down; the near square is smaller than the far one.
    let cam = Camera::perspective([0.0, 0.0, 5.0], [0.0; 3], [0.0, 1.0, 0.0], 45.0);
    let near = square(1.0, 0.5, [255, 0, 0]);
    let far = square(-1.0, 1.5, [0, 0, 255]);
    for order in [0, 1] {
        let tris: Vec<Triangle> = if order == 0 {
            near.iter().chain(far.iter()).copied().collect()
        } else {
            far.iter().chain(near.iter()).copied().collect()
        };
        let img = rasterize(&tris, None, &cam, &RenderOptions::unlit(80, 80));
        assert_eq!(img.get(40, 40), [255, 0, 0], "order {order}");
        // Outside the near square but inside the far one.
        assert_eq!(img.get(40, 20), [0, 0, 255], "order {order}");
        assert_eq!(img.get(0, 0), BG);
    }
    // Orthographic as well.
    let cam = Camera::orthographic([0.0, 0.0, 5.0], [0.0; 3], [0.0, 1.0, 0.0], 45.0);
    let tris: Vec<Triangle> = far.iter().chain(near.iter()).copied().collect();
    let img = rasterize(&tris, None, &cam, &RenderOptions::unlit(80, 80));
    assert_eq!(img.get(40, 40), [255, 0, 0]);
}

#[test]
fn no_holes_between_adjacent_triangles() {
    // A fan of many thin triangles covering a square: every pixel inside is covered.
    let cam = Camera::orthographic([0.0, 0.0, 5.0], [0.0; 3], [0.0, 1.0, 0.0], 30.0);
    let n = 44; // a multiple of 4: the corners of the square are vertices
    let mut tris = Vec::new();
    let c = [0.013, -0.021, 0.0];
    let pt = |i: usize| {
        let t = i as f64 / n as f64 * 4.0;
        let (side, s) = (t.floor() as usize % 4, t.fract());
        let v = match side {
            0 => [-1.0 + 2.0 * s, -1.0],
            1 => [1.0, -1.0 + 2.0 * s],
            2 => [1.0 - 2.0 * s, 1.0],
            _ => [-1.0, 1.0 - 2.0 * s],
        };
        [v[0], v[1], 0.0]
    };
    for i in 0..n {
        tris.push(Triangle::flat([c, pt(i), pt(i + 1)], [10, 20, 30]));
    }
    let mut opts = RenderOptions::unlit(101, 101);
    opts.supersample = 1;
    let img = rasterize(&tris, None, &cam, &opts);
    // The square spans [-1, 1]; the view half height is 5 tan(15 deg) = 1.34.
    let inside = |x: u32| (x as f64 + 0.5 - 50.5) / 50.5 * 5.0 * (15f64).to_radians().tan();
    for y in 0..101 {
        for x in 0..101 {
            let (u, v) = (inside(x), -inside(y));
            if u.abs() < 0.97 && v.abs() < 0.97 {
                assert_eq!(img.get(x, y), [10, 20, 30], "hole at ({x}, {y})");
            }
        }
    }
}

#[test]
fn boundary_of_2x2x2_block_has_24_outward_faces() {
    let m = block([0.0; 3], [2.0, 2.0, 2.0], [2, 2, 2]);
    let faces = boundary_quads(&m.elements);
    assert_eq!(faces.len(), 24);
    let centre = [1.0, 1.0, 1.0];
    for f in &faces {
        let n = face_normal(&m.nodes, f);
        let c = face_centroid(&m.nodes, f);
        assert!(dot(&n, &sub(&c, &centre)) > 0.0, "{f:?} points inwards");
        // Axis aligned, on the box surface.
        let axis = (0..3)
            .find(|&k| n[k].abs() > 0.999)
            .expect("axis-aligned normal");
        assert!((c[axis] - 1.0).abs() > 0.999, "{f:?} is not on the surface");
    }
    // Deterministic order: element order, then local face order.
    let mut sorted = faces.clone();
    sorted.sort_by_key(|f| (f.element, f.local_face));
    assert_eq!(sorted, faces);
    // No face twice.
    let mut keys: Vec<[u32; 4]> = faces
        .iter()
        .map(|f| {
            let mut k = f.nodes;
            k.sort();
            k
        })
        .collect();
    keys.sort();
    keys.dedup();
    assert_eq!(keys.len(), 24);
    // A sub-mesh: without element 0 the surface gains the three inner faces of the hole.
    let sub = boundary_quads_where(&m.elements, |e| e != 0);
    assert_eq!(sub.len(), 24 - 3 + 3);
    assert!(sub.iter().all(|f| f.element != 0));
    let elements_4x1x1 = block([0.0; 3], [4.0, 1.0, 1.0], [4, 1, 1]).elements;
    assert_eq!(boundary_quads(&elements_4x1x1).len(), 18);
}

#[test]
fn normals_of_a_cube_keep_creases() {
    let (nodes, faces) = unit_cube();
    let corner = corner_normals(&nodes, &faces, 60.0);
    for (f, cn) in faces.iter().zip(&corner) {
        let n = face_normal(&nodes, f);
        for c in cn {
            assert!(dot(c, &n) > 1.0 - 1e-12);
        }
    }
    // Fully smooth: corner normals along the diagonals.
    let vn = vertex_normals(&nodes, &faces);
    let s = 1.0 / 3f64.sqrt();
    assert!((dot(&vn[0], &[-s, -s, -s]) - 1.0).abs() < 1e-12);
    assert!((dot(&vn[7], &[s, s, s]) - 1.0).abs() < 1e-12);
}

#[test]
fn texture_sampling_returns_texels() {
    let mut tex = Image::new(2, 2, BLACK);
    let c = [[255, 0, 0], [0, 255, 0], [0, 0, 255], [250, 250, 10]];
    tex.set(0, 0, c[0]); // top left
    tex.set(1, 0, c[1]);
    tex.set(0, 1, c[2]); // bottom left
    tex.set(1, 1, c[3]);
    let at = |u: f64, v: f64| tex.sample_bilinear(u, v).map(|x| x.round() as u8);
    assert_eq!(at(0.25, 0.75), c[0]);
    assert_eq!(at(0.75, 0.75), c[1]);
    assert_eq!(at(0.25, 0.25), c[2]);
    assert_eq!(at(0.75, 0.25), c[3]);
    assert_eq!(at(-3.0, 9.0), c[0]); // clamped
    let mid = tex.sample_bilinear(0.5, 0.5);
    for k in 0..3 {
        let mean = c.iter().map(|p| p[k] as f64).sum::<f64>() / 4.0;
        assert!((mid[k] - mean).abs() < 1e-9);
    }
    // A textured, unlit quad filling most of the view shows the texels in the right places.
    let cam = Camera::orthographic([0.0, 0.0, 5.0], [0.0; 3], [0.0, 1.0, 0.0], 30.0);
    let (p, uv) = (
        [
            [-1.0, -1.0, 0.0],
            [1.0, -1.0, 0.0],
            [1.0, 1.0, 0.0],
            [-1.0, 1.0, 0.0],
        ],
        [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
    );
    let tris: Vec<Triangle> = [[0, 1, 2], [0, 2, 3]]
        .iter()
        .map(|t| Triangle {
            positions: t.map(|i| p[i]),
            normals: [[0.0; 3]; 3],
            uv: Some(t.map(|i| uv[i])),
            colour: [1, 2, 3],
            colours: None,
            edges: 0,
        })
        .collect();
    let img = rasterize(&tris, Some(&tex), &cam, &RenderOptions::unlit(100, 100));
    // Square spans pixels ~13..87; near the quadrant centres the texels show (up to
    // the bilinear blend across the supersamples).
    let close = |x: u32, y: u32, c: [u8; 3]| {
        let p = img.get(x, y);
        assert!(
            (0..3).all(|k| (p[k] as i32 - c[k] as i32).abs() <= 8),
            "({x}, {y}): {p:?} vs {c:?}"
        );
    };
    close(31, 31, c[0]);
    close(68, 31, c[1]);
    close(31, 68, c[2]);
    close(68, 68, c[3]);
}

#[test]
fn camera_fit_keeps_points_inside_the_margin() {
    let m = block([3.0, -2.0, 1.0], [10.0, 2.0, 1.0], [5, 2, 2]);
    for projection in [Projection::Perspective, Projection::Orthographic] {
        let cam = Camera::fit(
            &m.nodes,
            [0.3, 1.0, -0.5],
            [0.0, 0.0, 1.0],
            35.0,
            projection,
            1.5,
            0.1,
        );
        let (w, h) = (300, 200);
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for p in &m.nodes {
            let (x, y, d) = cam.project(*p, w, h).unwrap();
            assert!(d > 0.0);
            x0 = x0.min(x);
            x1 = x1.max(x);
            y0 = y0.min(y);
            y1 = y1.max(y);
        }
        assert!(
            x0 >= 0.1 * w as f64 - 1e-6 && x1 <= 0.9 * w as f64 + 1e-6,
            "{projection:?} x {x0} {x1}"
        );
        assert!(
            y0 >= 0.1 * h as f64 - 1e-6 && y1 <= 0.9 * h as f64 + 1e-6,
            "{projection:?} y {y0} {y1}"
        );
        // Tight in one direction and roughly centred.
        let fill = ((x1 - x0) / (0.8 * w as f64)).max((y1 - y0) / (0.8 * h as f64));
        assert!(fill > 0.97, "{projection:?} fill {fill}");
        assert!(((x0 + x1) / 2.0 - w as f64 / 2.0).abs() < 0.03 * w as f64);
        assert!(((y0 + y1) / 2.0 - h as f64 / 2.0).abs() < 0.03 * h as f64);
    }
}

#[test]
fn geometry_behind_the_camera_is_clipped() {
    let cam = Camera::perspective([0.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0], 60.0);
    // A large floor passing under and behind the eye.
    let tri = Triangle::flat(
        [[-5.0, -1.0, 3.0], [5.0, -1.0, 3.0], [0.0, -1.0, -20.0]],
        [100, 100, 100],
    );
    let img = rasterize(&[tri], None, &cam, &RenderOptions::unlit(40, 40));
    assert_eq!(img.get(20, 39), [100, 100, 100]); // the floor below the horizon
    assert_eq!(img.get(20, 2), BG); // the sky
}

#[test]
fn wireframe_draws_quad_edges_not_diagonals() {
    let cam = Camera::orthographic([0.0, 0.0, 5.0], [0.0; 3], [0.0, 1.0, 0.0], 30.0);
    // Two elements side by side: top faces [-1, 0] x [-1, 1] and [0, 1] x [-1, 1] at z = 0.
    let m = block([-1.0, -1.0, -1.0], [2.0, 2.0, 1.0], [2, 1, 1]);
    let faces = boundary_quads(&m.elements);
    let mut opts = RenderOptions::unlit(100, 100);
    opts.wireframe = Some(Wireframe {
        colour: [0, 0, 0],
        width_px: 2.0,
    });
    let img = render_mesh_with(&m.nodes, &faces, &|_| [200, 200, 200], None, &cam, &opts);
    // Each top face's diagonal passes through its centre (x = -0.5 or 0.5, y = 0): not drawn.
    let px = |x: f64| (50.0 + x / (5.0 * 15f64.to_radians().tan()) * 50.0) as u32;
    assert_eq!(img.get(px(-0.5), 50), [200, 200, 200]);
    assert_eq!(img.get(px(0.5), 50), [200, 200, 200]);
    // The shared edge x = 0 is drawn, two pixels wide.
    let dark = (45..56).filter(|&x| img.get(x, 30)[0] < 60).count();
    assert!((1..=3).contains(&dark), "{dark}");
    // The outline x = 1 too (half of the line lies outside the face).
    assert!((80..95).any(|x| img.get(x, 30)[0] < 120));
}

#[test]
fn labels_and_grids() {
    let mut img = Image::new(120, 40, BG);
    img.label("Hello 0.04 s", 4, 4, 18.0, BLACK);
    assert!(img.count_not(BG) > 50);
    let (tw, th) = text_size("Hello 0.04 s", 18.0);
    assert!(tw > 60 && tw < 120 && (18..30).contains(&th), "{tw} x {th}");
    let a = Image::new(30, 20, [255, 0, 0]);
    let b = Image::new(20, 10, [0, 0, 255]);
    let g = Image::grid(&[a.clone(), b.clone(), a.clone()], 2, 5, BG);
    // columns as wide as their widest image (30, 20), rows as tall as their tallest (20, 20)
    assert_eq!(
        (g.width, g.height),
        (5 + 30 + 5 + 20 + 5, 5 + 20 + 5 + 20 + 5)
    );
    assert_eq!(g.get(5, 5), [255, 0, 0]);
    assert_eq!(g.get(40 + 10, 5 + 5 + 5), [0, 0, 255]); // b centred vertically in its row
    assert_eq!(g.get(40 + 1, 5 + 1), BG);
    // a legend-like short image below a tall one takes only its own height
    let s = Image::grid(&[a.clone(), b.clone()], 1, 5, BG);
    assert_eq!((s.width, s.height), (5 + 30 + 5, 5 + 20 + 5 + 10 + 5));
    assert_eq!(s.get(5 + 5 + 10, 5 + 20 + 5 + 5), [0, 0, 255]);
    let labels = GridLabels {
        title: Some("Figure"),
        column_titles: &["without", "with"],
        row_titles: &["t = 0", "t = 0.04 s"],
        ..Default::default()
    };
    let gl = Image::grid_labelled(&[a.clone(), a.clone(), a.clone(), a], 2, 6, BG, &labels);
    assert!(gl.width > g.width && gl.height > g.height);
    let legend = Image::legend(
        &[("skin", [230, 180, 160]), ("saliva", [90, 140, 230])],
        16.0,
        BG,
    );
    assert!(legend.count_not(BG) > 100);
}

fn demo_plot() -> PlotSpec {
    let mut spec = PlotSpec::new(
        "Open fraction of the mouth width",
        "time (s)",
        "open fraction",
    );
    let t: Vec<f64> = (0..=60).map(|i| i as f64 * 0.005).collect();
    spec.series.push(Series::new(
        "without stickiness",
        t.iter()
            .map(|&t| {
                (
                    t,
                    (1.0 - (-(t / 0.01)).exp()).min(1.0) * (t > 0.02) as u8 as f64,
                )
            })
            .collect(),
    ));
    spec.series.push(
        Series::new(
            "with stickiness",
            t.iter()
                .map(|&t| (t, (1.0 - (-(t - 0.02).max(0.0) / 0.12).exp())))
                .collect(),
        )
        .markers(),
    );
    spec.series
        .push(Series::new("K_glue x 2", t.iter().map(|&t| (t, 0.5 * t)).collect()).dashed());
    spec
}

#[test]
fn plots_render_and_are_not_blank() {
    let spec = demo_plot();
    let img = line_plot(&spec);
    assert_eq!((img.width, img.height), (800, 500));
    assert!(img.count_not(BG) > 10_000, "{}", img.count_not(BG));
    // Series colours appear (anti-aliased lines: allow a tolerance).
    let near = |c: [u8; 3]| {
        img.rgb
            .chunks_exact(3)
            .filter(|p| (0..3).all(|k| (p[k] as i32 - c[k] as i32).abs() < 30))
            .count()
    };
    assert!(near(plot::PALETTE[0]) > 200);
    assert!(near(plot::PALETTE[1]) > 200);
    // Log axis with zeros and NaNs in the data.
    let mut log = spec.clone();
    log.log_y = true;
    log.series.push(Series::new(
        "gaps",
        vec![(0.0, 0.0), (0.1, f64::NAN), (0.2, 1e-3), (0.3, 1e-1)],
    ));
    let img = line_plot(&log);
    assert!(img.count_not(BG) > 10_000);
    // Empty plot.
    let img = line_plot(&PlotSpec::new("empty", "x", "y"));
    assert!(img.count_not(BG) > 1000);
    // Profiles and heat map.
    let mut prof = ProfileSpec::new(
        "Lip gap",
        "position across the mouth (mm)",
        "gap (mm)",
        "time (s)",
    );
    prof.x = (0..=40).map(|i| -25.0 + 50.0 * i as f64 / 40.0).collect();
    for k in 0..8 {
        let t = 0.04 * k as f64;
        let half = 3.0 * k as f64;
        prof.profiles.push((
            t,
            prof.x
                .iter()
                .map(|&x: &f64| (0.4 * k as f64 * (1.0 - (x / half.max(1e-9)).powi(2))).max(0.0))
                .collect(),
        ));
    }
    let img = profile_plot(&prof);
    assert_eq!((img.width, img.height), (800, 500));
    assert!(img.count_not(BG) > 10_000);
    let img = heatmap_plot(&prof);
    assert!(img.count_not(BG) > 100_000);
}

#[test]
fn png_round_trip() {
    let mut img = Image::checkerboard(37, 23, 5, [10, 200, 30], [250, 1, 128]);
    img.label("x", 2, 2, 12.0, [0, 0, 0]);
    let bytes = encode_png(&img);
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    assert_eq!(decode_png(&bytes).unwrap(), img);
    let dir = std::env::temp_dir().join(format!("sticky-lips-render-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("x.png");
    save_png(&path, &img).unwrap();
    assert_eq!(load_png(&path).unwrap(), img);
    assert!(save_png(&path, &Image::new(0, 0, BG)).is_err());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Writes /tmp/render_demo.png, /tmp/render_demo_grid.png and /tmp/plot_demo.png to look
/// at: `cargo test --lib render::tests::demo_images -- --ignored`.
#[test]
#[ignore]
fn demo_images() {
    let m = block([0.0, 0.0, 0.0], [10.0, 2.0, 2.0], [20, 4, 4]);
    // Bend the bar into an arc about the y axis (radius 6, centre above), with a twist.
    let r = 6.0;
    let bent: Vec<[f64; 3]> = m
        .nodes
        .iter()
        .map(|p| {
            let th = (p[0] - 5.0) / r;
            let rr = r - (p[2] - 1.0);
            let tw = 0.08 * (p[0] - 5.0);
            let (y, z) = (p[1] - 1.0, p[2] - 1.0);
            let (y, _z) = (y * tw.cos() - z * tw.sin(), y * tw.sin() + z * tw.cos());
            [5.0 + rr * th.sin(), 1.0 + y, 1.0 + r - rr * th.cos()]
        })
        .collect();
    let faces = boundary_quads(&m.elements);
    let colour = |f: &BoundaryFace| {
        if f.element % 2 == 0 {
            [196, 84, 84]
        } else {
            [236, 196, 170]
        }
    };
    let (w, h) = (800, 500);
    let cam = Camera::fit(
        &bent,
        [0.45, 1.0, -0.55],
        [0.0, 0.0, 1.0],
        35.0,
        Projection::Perspective,
        w as f64 / h as f64,
        0.05,
    );
    let img = render_mesh(&bent, &faces, &colour, None, &cam, w, h);
    save_png(std::path::Path::new("/tmp/render_demo.png"), &img).unwrap();

    let (pw, ph) = (400, 260);
    let cam = Camera::fit(
        &bent,
        [0.45, 1.0, -0.55],
        [0.0, 0.0, 1.0],
        35.0,
        Projection::Perspective,
        pw as f64 / ph as f64,
        0.05,
    );
    let mut wire = RenderOptions::new(pw, ph);
    wire.wireframe = Some(Wireframe {
        colour: [40, 40, 40],
        width_px: 1.0,
    });
    wire.shading = Shading::Flat;
    let uv: Vec<[f64; 2]> = m
        .nodes
        .iter()
        .map(|p| [p[0] / 10.0, (p[1] + p[2]) / 4.0])
        .collect();
    let tex = Image::checkerboard(256, 256, 8, [240, 240, 240], [60, 90, 160]);
    let ortho = Camera::fit(
        &bent,
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        35.0,
        Projection::Orthographic,
        pw as f64 / ph as f64,
        0.05,
    );
    let panels = vec![
        render_mesh(&bent, &faces, &colour, None, &cam, pw, ph),
        render_mesh_with(&bent, &faces, &colour, None, &cam, &wire),
        render_mesh(&bent, &faces, &colour, Some((&uv, &tex)), &cam, pw, ph),
        render_mesh(&bent, &faces, &colour, None, &ortho, pw, ph),
    ];
    let labels = GridLabels {
        title: Some("A bent 20 x 4 x 4 block"),
        column_titles: &["smooth shading", "flat + wireframe"],
        row_titles: &["", "textured / ortho"],
        ..Default::default()
    };
    let grid = Image::grid_labelled(&panels, 2, 12, BG, &labels);
    save_png(std::path::Path::new("/tmp/render_demo_grid.png"), &grid).unwrap();

    let mut prof = ProfileSpec::new(
        "Lip gap along the mouth",
        "position across the mouth (mm)",
        "gap (mm)",
        "time (s)",
    );
    prof.x = (0..=60).map(|i| -25.0 + 50.0 * i as f64 / 60.0).collect();
    for k in 0..10 {
        let t = 0.02 * k as f64;
        let half = 2.5 * k as f64;
        prof.profiles.push((
            t,
            prof.x
                .iter()
                .map(|&x: &f64| (0.5 * k as f64 * (1.0 - (x / half.max(1e-9)).powi(2))).max(0.0))
                .collect(),
        ));
    }
    let mut log = demo_plot();
    log.title = "Broken saliva elements (log y)".into();
    log.log_y = true;
    log.legend = plot::LegendPosition::LowerRight;
    let plots = vec![
        line_plot(&demo_plot()),
        line_plot(&log),
        profile_plot(&prof),
        heatmap_plot(&prof),
    ];
    let grid = Image::grid(&plots, 2, 10, BG);
    save_png(std::path::Path::new("/tmp/plot_demo.png"), &grid).unwrap();
}

#[test]
fn the_makehuman_masks_decode_as_jpeg() {
    let img = super::decode_jpeg(crate::mesh::face::MAKEHUMAN_LIPS_TEXTURE).unwrap();
    assert_eq!((img.width, img.height), (2048, 2048));
    // a greyscale mask: mostly black, white where the lips are
    let white = img.rgb.chunks_exact(3).filter(|p| p[0] > 200).count();
    assert!(
        white > 100 && white < img.rgb.len() / 30,
        "{white} white pixels"
    );
    assert!(img
        .rgb
        .chunks_exact(3)
        .all(|p| p[0] == p[1] && p[1] == p[2]));
    assert!(super::decode_jpeg(b"not a jpeg").is_err());
}

/// The unit cube seen head-on through its y- face (local face 2), unlit, with the pixels
/// of that face's interior (a margin in from its edges).
fn front_face_pixels(img: &Image) -> Vec<[u8; 3]> {
    let mut out = Vec::new();
    for y in 0..img.height {
        for x in 0..img.width {
            let p = img.get(x, y);
            if p != BG {
                out.push(p);
            }
        }
    }
    out
}

#[test]
fn a_texture_varies_inside_one_quad_of_a_mesh() {
    // One hexahedron; its front face (y-) maps the left half of the texture (red) to its
    // left half and the right half (blue) to its right: both show inside the one quad, so
    // the texture is sampled per pixel, not once per face.
    let (nodes, faces) = unit_cube();
    let uv: Vec<[f64; 2]> = nodes.iter().map(|p| [p[0], p[2]]).collect();
    let (red, blue) = ([220, 20, 20], [20, 20, 220]);
    let mut tex = Image::new(2, 1, red);
    tex.set(1, 0, blue);
    let normals = corner_normals(&nodes, &faces, DEFAULT_CREASE_DEGREES);
    let front = |f: &BoundaryFace| {
        if f.local_face == 2 {
            FacePaint::Texture([0, 0, 0])
        } else {
            FacePaint::Colour([0, 0, 0])
        }
    };
    let tris = paint_triangles(&nodes, &faces, &normals, &front, Some(&uv));
    let cam = front_camera(Projection::Orthographic);
    let img = rasterize(&tris, Some(&tex), &cam, &RenderOptions::unlit(128, 96));
    let px = front_face_pixels(&img);
    let near = |p: &[u8; 3], c: [u8; 3]| (0..3).all(|k| (p[k] as i32 - c[k] as i32).abs() <= 6);
    let n_red = px.iter().filter(|p| near(p, red)).count();
    let n_blue = px.iter().filter(|p| near(p, blue)).count();
    assert!(n_red > 100 && n_blue > 100, "red {n_red}, blue {n_blue}");
    // left of the centre red, right blue (the texture's u runs with x)
    assert!(near(&img.get(50, 48), red), "{:?}", img.get(50, 48));
    assert!(near(&img.get(78, 48), blue), "{:?}", img.get(78, 48));
    // and a blend between (bilinear), not a step only
    assert!(px.iter().any(|p| p[0] > 60 && p[2] > 60));
    // a face colour per quad (the old way) gives one colour over the face
    let flat = |f: &BoundaryFace| FacePaint::Colour(if f.local_face == 2 { red } else { BG });
    let tris = paint_triangles(&nodes, &faces, &normals, &flat, Some(&uv));
    let img = rasterize(&tris, Some(&tex), &cam, &RenderOptions::unlit(128, 96));
    assert!(front_face_pixels(&img)
        .iter()
        .all(|p| is_blend(p, BG, red) || *p == red));
}

#[test]
fn corner_colours_are_interpolated_per_pixel() {
    // Red at the front face's left corners, blue at its right: the colour runs smoothly
    // from red to blue across the one quad (many shades, monotone in x).
    let (nodes, faces) = unit_cube();
    let (red, blue) = ([240u8, 0, 0], [0u8, 0, 240]);
    let normals = corner_normals(&nodes, &faces, DEFAULT_CREASE_DEGREES);
    let paint = |f: &BoundaryFace| {
        FacePaint::Corners(f.nodes.map(|n| {
            if nodes[n as usize][0] < 0.5 {
                red
            } else {
                blue
            }
        }))
    };
    let tris = paint_triangles(&nodes, &faces, &normals, &paint, None);
    let cam = front_camera(Projection::Orthographic);
    let img = rasterize(&tris, None, &cam, &RenderOptions::unlit(128, 96));
    let row: Vec<[u8; 3]> = (0..128).map(|x| img.get(x, 48)).collect();
    let inside: Vec<[u8; 3]> = row.into_iter().filter(|p| *p != BG).collect();
    assert!(inside.len() > 20, "{}", inside.len());
    // away from the anti-aliased edges: red falls, blue rises, pixel by pixel
    let core = &inside[2..inside.len() - 2];
    for w in core.windows(2) {
        assert!(w[1][0] <= w[0][0] && w[1][2] >= w[0][2], "{w:?}");
    }
    let mut shades: Vec<[u8; 3]> = core.to_vec();
    shades.dedup();
    assert!(shades.len() > 10, "{} shades", shades.len());
    assert!(core[0][0] > 200 && core[core.len() - 1][2] > 200);
    // the same bits with one worker thread and with four
    let render_with = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| rasterize(&tris, None, &cam, &RenderOptions::new(128, 96)))
    };
    assert_eq!(render_with(1), render_with(4));
}

#[test]
fn a_soft_crease_is_continuous_in_the_angle_and_a_hard_one_is_the_old_rule() {
    let w = |deg: f64| soft_crease(deg.to_radians().cos(), 60.0, 120.0);
    assert_eq!(w(10.0), 1.0);
    assert_eq!(w(60.0), 1.0);
    assert_eq!(w(130.0), 0.0);
    assert!((w(90.0) - 0.5).abs() < 1e-12);
    // no jump anywhere: 0.1 degree apart, the weights differ by little
    for i in 0..1800 {
        let a = i as f64 * 0.1;
        assert!((w(a + 0.1) - w(a)).abs() < 0.01, "at {a} degrees");
    }
    // hard: 1 within, 0 beyond
    assert_eq!(soft_crease(59f64.to_radians().cos(), 60.0, 60.0), 1.0);
    assert_eq!(soft_crease(61f64.to_radians().cos(), 60.0, 60.0), 0.0);
    // corner_normals is the hard crease of corner_normals_weighted, bit for bit
    let m = block([0.0; 3], [2.0, 1.0, 1.0], [2, 2, 1]);
    let faces = boundary_quads(&m.elements);
    for c in [0.0, 30.0, 60.0, 89.0, 91.0, 180.0] {
        let hard = corner_normals_weighted(&m.nodes, &faces, &|_, _, cos| soft_crease(cos, c, c));
        assert_eq!(corner_normals(&m.nodes, &faces, c), hard, "{c}");
    }
    // a box's 90-degree edges: sharp with a hard 60-degree crease, half-blended with a soft
    // one to 120 degrees
    let soft =
        corner_normals_weighted(&m.nodes, &faces, &|_, _, cos| soft_crease(cos, 60.0, 120.0));
    let hard = corner_normals(&m.nodes, &faces, 60.0);
    let f = faces.iter().position(|f| f.local_face == 2).unwrap();
    let n = face_normal(&m.nodes, &faces[f]);
    assert!(hard[f].iter().all(|c| dot(c, &n) > 1.0 - 1e-12));
    assert!(soft[f].iter().any(|c| dot(c, &n) < 0.99));
}

#[test]
fn round_half_away_is_f64_round() {
    use super::raster::round_half_away;
    let mut xs = vec![
        0.0,
        0.5,
        1.5,
        2.5,
        254.5,
        255.49999999999997,
        0.49999999999999994,
        -0.5,
        -1.5,
        -2.4999999999999996,
        4503599627370495.5,
        4503599627370497.0,
        1e300,
        -1e300,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    let mut s = 0x2545f4914f6cdd1d_u64;
    for _ in 0..100_000 {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        xs.push((s >> 11) as f64 / (1u64 << 53) as f64 * 600.0 - 300.0);
        xs.push(f64::from_bits(s));
    }
    for x in xs {
        let (a, b) = (round_half_away(x), x.round());
        assert!(
            a == b || (a.is_nan() && b.is_nan()),
            "{x:e}: {a} against {b}"
        );
    }
}
