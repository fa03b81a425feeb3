//! A small CPU software rasterizer: RGB images, a pinhole (or orthographic) camera, and
//! z-buffered triangles with perspective-correct interpolation, Lambert shading (flat,
//! Gouraud or per-pixel) under directional lights plus ambient, per-triangle colours,
//! per-vertex colours interpolated per pixel, or a bilinearly sampled texture, optional quad-edge wireframe, and supersampling
//! anti-aliasing (render at `s` times the size, then box-downsample).
//!
//! Conventions: pixel `(x, y)` has its centre at `(x + 0.5, y + 0.5)`, `y` grows downwards;
//! texture coordinates `(u, v)` run left to right and bottom to top (OpenGL / OBJ).
//! Rendering is deterministic: triangles are drawn in the given order and a later triangle
//! only replaces a pixel when it is strictly nearer.

use crate::linalg::{add, cross, dot, norm, normalize, scale, sub};
use rayon::prelude::*;

/// An 8-bit RGB image, rows top to bottom, `rgb.len() == 3 * width * height`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<u8>,
}

pub const WHITE: [u8; 3] = [255, 255, 255];
pub const BLACK: [u8; 3] = [0, 0, 0];

impl Image {
    /// A `width x height` image filled with `colour`.
    pub fn new(width: u32, height: u32, colour: [u8; 3]) -> Image {
        let n = width as usize * height as usize;
        let mut rgb = Vec::with_capacity(3 * n);
        for _ in 0..n {
            rgb.extend_from_slice(&colour);
        }
        Image { width, height, rgb }
    }

    /// The colour of pixel `(x, y)`. Panics outside the image.
    pub fn get(&self, x: u32, y: u32) -> [u8; 3] {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) outside the image"
        );
        let i = 3 * (y as usize * self.width as usize + x as usize);
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }

    /// Sets pixel `(x, y)`; ignored outside the image.
    pub fn set(&mut self, x: i64, y: i64, colour: [u8; 3]) {
        if x < 0 || y < 0 || x >= self.width as i64 || y >= self.height as i64 {
            return;
        }
        let i = 3 * (y as usize * self.width as usize + x as usize);
        self.rgb[i..i + 3].copy_from_slice(&colour);
    }

    /// Blends `colour` over pixel `(x, y)` with opacity `alpha` in `[0, 1]`; ignored outside.
    pub fn blend(&mut self, x: i64, y: i64, colour: [u8; 3], alpha: f32) {
        if x < 0 || y < 0 || x >= self.width as i64 || y >= self.height as i64 {
            return;
        }
        let a = alpha.clamp(0.0, 1.0);
        let i = 3 * (y as usize * self.width as usize + x as usize);
        for c in 0..3 {
            let old = self.rgb[i + c] as f32;
            self.rgb[i + c] = (old + (colour[c] as f32 - old) * a).round() as u8;
        }
    }

    /// Fills the rectangle with top-left `(x, y)` (clipped to the image).
    pub fn fill_rect(&mut self, x: i64, y: i64, w: u32, h: u32, colour: [u8; 3]) {
        let x0 = x.max(0);
        let y0 = y.max(0);
        let x1 = (x + w as i64).min(self.width as i64);
        let y1 = (y + h as i64).min(self.height as i64);
        for yy in y0..y1 {
            for xx in x0..x1 {
                self.set(xx, yy, colour);
            }
        }
    }

    /// Copies `src` with its top-left corner at `(x, y)` (clipped to this image).
    pub fn blit(&mut self, src: &Image, x: i64, y: i64) {
        for sy in 0..src.height as i64 {
            let ty = y + sy;
            if ty < 0 || ty >= self.height as i64 {
                continue;
            }
            let sx0 = (-x).max(0);
            let sx1 = (self.width as i64 - x).min(src.width as i64);
            if sx1 <= sx0 {
                continue;
            }
            let s = 3 * (sy as usize * src.width as usize + sx0 as usize);
            let t = 3 * (ty as usize * self.width as usize + (x + sx0) as usize);
            let n = 3 * (sx1 - sx0) as usize;
            self.rgb[t..t + n].copy_from_slice(&src.rgb[s..s + n]);
        }
    }

    /// This image with a border of `margin` pixels of `colour` on every side.
    pub fn pad(&self, margin: u32, colour: [u8; 3]) -> Image {
        let mut out = Image::new(self.width + 2 * margin, self.height + 2 * margin, colour);
        out.blit(self, margin as i64, margin as i64);
        out
    }

    /// Box-filter downsampling by an integer `factor` (the average of each
    /// `factor x factor` block; a trailing partial block is dropped).
    pub fn downsample(&self, factor: u32) -> Image {
        if factor <= 1 {
            return self.clone();
        }
        let w = self.width / factor;
        let h = self.height / factor;
        let f = factor as usize;
        let sw = self.width as usize;
        let mut rgb = vec![0u8; 3 * w as usize * h as usize];
        // one output row: the factor a constant for the common factors (the division by
        // `f * f` then a multiplication)
        fn row_of<const F: usize>(src: &[u8], sw: usize, f: usize, y: usize, row: &mut [u8]) {
            let f = if F > 0 { F } else { f };
            let norm = (f * f) as u32;
            for (x, px) in row.chunks_exact_mut(3).enumerate() {
                let mut acc = [0u32; 3];
                for dy in 0..f {
                    let base = 3 * ((y * f + dy) * sw + x * f);
                    for dx in 0..f {
                        for c in 0..3 {
                            acc[c] += src[base + 3 * dx + c] as u32;
                        }
                    }
                }
                for c in 0..3 {
                    px[c] = ((acc[c] + norm / 2) / norm) as u8;
                }
            }
        }
        rgb.par_chunks_mut((3 * w as usize).max(1))
            .enumerate()
            .for_each(|(y, row)| match f {
                2 => row_of::<2>(&self.rgb, sw, f, y, row),
                3 => row_of::<3>(&self.rgb, sw, f, y, row),
                _ => row_of::<0>(&self.rgb, sw, f, y, row),
            });
        Image {
            width: w,
            height: h,
            rgb,
        }
    }

    /// Bilinear sample at texture coordinates `(u, v)` (`v = 0` is the bottom row),
    /// clamped to the edge; channels in `[0, 255]`. Sampling at a texel centre
    /// (`u = (i + 0.5) / width`, `v = 1 - (j + 0.5) / height`) returns that texel.
    pub fn sample_bilinear(&self, u: f64, v: f64) -> [f64; 3] {
        if self.width == 0 || self.height == 0 {
            return [0.0; 3];
        }
        let u = if u.is_finite() { u } else { 0.0 };
        let v = if v.is_finite() { v } else { 0.0 };
        let fx = (u * self.width as f64 - 0.5).clamp(0.0, (self.width - 1) as f64);
        let fy = ((1.0 - v) * self.height as f64 - 0.5).clamp(0.0, (self.height - 1) as f64);
        // (fx, fy >= 0: the conversion is their floor)
        let x0 = fx as u32;
        let y0 = fy as u32;
        let x1 = (x0 + 1).min(self.width - 1);
        let y1 = (y0 + 1).min(self.height - 1);
        let tx = fx - x0 as f64;
        let ty = fy - y0 as f64;
        // (x0, x1 and y0, y1 are within the image)
        let texel = |x: u32, y: u32| {
            let i = 3 * (y as usize * self.width as usize + x as usize);
            [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
        };
        let (a, b, c, d) = (texel(x0, y0), texel(x1, y0), texel(x0, y1), texel(x1, y1));
        std::array::from_fn(|k| {
            let top = a[k] as f64 * (1.0 - tx) + b[k] as f64 * tx;
            let bottom = c[k] as f64 * (1.0 - tx) + d[k] as f64 * tx;
            top * (1.0 - ty) + bottom * ty
        })
    }

    /// A checkerboard of `n x n` squares alternating `a` (top-left) and `b`.
    pub fn checkerboard(width: u32, height: u32, n: u32, a: [u8; 3], b: [u8; 3]) -> Image {
        let mut img = Image::new(width, height, a);
        let n = n.max(1);
        for y in 0..height {
            for x in 0..width {
                let i = x * n / width.max(1);
                let j = y * n / height.max(1);
                if (i + j) % 2 == 1 {
                    img.set(x as i64, y as i64, b);
                }
            }
        }
        img
    }

    /// Number of pixels whose colour differs from `colour`.
    pub fn count_not(&self, colour: [u8; 3]) -> usize {
        self.rgb.chunks_exact(3).filter(|p| *p != colour).count()
    }
}

// ---------------------------------------------------------------------------------------
// Camera.

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Projection {
    Perspective,
    /// Parallel projection; the visible height is that of the perspective view at the
    /// target: `2 |target - eye| tan(fov_y / 2)`.
    Orthographic,
}

/// A camera at `eye` looking at `target`, `up` giving the vertical direction of the image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub eye: [f64; 3],
    pub target: [f64; 3],
    pub up: [f64; 3],
    /// Vertical field of view (degrees), in `(0, 180)`.
    pub fov_y_degrees: f64,
    pub projection: Projection,
}

/// Camera frame: `right`, `up` (both in the image plane) and `forward` (into the scene).
#[derive(Clone, Copy, Debug)]
pub struct CameraFrame {
    pub right: [f64; 3],
    pub up: [f64; 3],
    pub forward: [f64; 3],
}

impl Camera {
    pub fn perspective(
        eye: [f64; 3],
        target: [f64; 3],
        up: [f64; 3],
        fov_y_degrees: f64,
    ) -> Camera {
        Camera {
            eye,
            target,
            up,
            fov_y_degrees,
            projection: Projection::Perspective,
        }
    }

    pub fn orthographic(
        eye: [f64; 3],
        target: [f64; 3],
        up: [f64; 3],
        fov_y_degrees: f64,
    ) -> Camera {
        Camera {
            projection: Projection::Orthographic,
            ..Camera::perspective(eye, target, up, fov_y_degrees)
        }
    }

    /// The orthonormal camera frame. If `up` is parallel to the view direction another
    /// up vector is chosen.
    pub fn frame(&self) -> CameraFrame {
        frame_from(sub(&self.target, &self.eye), self.up)
    }

    fn tan_half(&self) -> f64 {
        (self.fov_y_degrees.clamp(1e-3, 179.0).to_radians() / 2.0).tan()
    }

    /// View coordinates of `p`: `(x right, y up, depth along the view direction)`.
    pub fn to_view(&self, p: [f64; 3]) -> [f64; 3] {
        let f = self.frame();
        let d = sub(&p, &self.eye);
        [dot(&d, &f.right), dot(&d, &f.up), dot(&d, &f.forward)]
    }

    /// Pixel coordinates `(x, y)` and depth of `p` in a `width x height` image, or `None`
    /// for a point behind a perspective camera.
    pub fn project(&self, p: [f64; 3], width: u32, height: u32) -> Option<(f64, f64, f64)> {
        let v = self.to_view(p);
        let (sx, sy) = self.view_to_pixel(v, width as f64, height as f64)?;
        Some((sx, sy, v[2]))
    }

    fn view_to_pixel(&self, v: [f64; 3], w: f64, h: f64) -> Option<(f64, f64)> {
        let t = self.tan_half();
        let aspect = w / h;
        let (nx, ny) = match self.projection {
            Projection::Perspective => {
                if !(v[2] > 0.0) {
                    return None;
                }
                (v[0] / (v[2] * t * aspect), v[1] / (v[2] * t))
            }
            Projection::Orthographic => {
                let half = norm(&sub(&self.target, &self.eye)) * t;
                (v[0] / (half * aspect), v[1] / half)
            }
        };
        Some(((nx + 1.0) * 0.5 * w, (1.0 - ny) * 0.5 * h))
    }

    /// A camera looking along `view_direction` (from the eye into the scene) with `up`
    /// vertical, placed so that the projections of all `points` fit an image of the given
    /// `aspect` (width / height), centred, leaving `margin` (a fraction of the image size,
    /// e.g. 0.05) empty on each side.
    pub fn fit(
        points: &[[f64; 3]],
        view_direction: [f64; 3],
        up: [f64; 3],
        fov_y_degrees: f64,
        projection: Projection,
        aspect: f64,
        margin: f64,
    ) -> Camera {
        let fr = frame_from(view_direction, up);
        let finite: Vec<[f64; 3]> = points
            .iter()
            .copied()
            .filter(|p| p.iter().all(|c| c.is_finite()))
            .collect();
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in &finite {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        if finite.is_empty() {
            lo = [-1.0; 3];
            hi = [1.0; 3];
        }
        let centre = scale(&add(&lo, &hi), 0.5);
        let size = norm(&sub(&hi, &lo)).max(1e-12);
        // Coordinates relative to the box centre in the camera frame.
        let rel: Vec<[f64; 3]> = finite
            .iter()
            .map(|p| {
                let d = sub(p, &centre);
                [dot(&d, &fr.right), dot(&d, &fr.up), dot(&d, &fr.forward)]
            })
            .collect();
        let rel = if rel.is_empty() { vec![[0.0; 3]] } else { rel };
        let fov = fov_y_degrees.clamp(1e-3, 179.0);
        let ty = (fov.to_radians() / 2.0).tan();
        let aspect = if aspect > 0.0 && aspect.is_finite() {
            aspect
        } else {
            1.0
        };
        let tx = ty * aspect;
        let k = (1.0 - 2.0 * margin.clamp(0.0, 0.45)).max(0.05);
        match projection {
            Projection::Orthographic => {
                let (mut x0, mut x1, mut y0, mut y1) = (
                    f64::INFINITY,
                    f64::NEG_INFINITY,
                    f64::INFINITY,
                    f64::NEG_INFINITY,
                );
                for r in &rel {
                    x0 = x0.min(r[0]);
                    x1 = x1.max(r[0]);
                    y0 = y0.min(r[1]);
                    y1 = y1.max(r[1]);
                }
                let half = ((x1 - x0) / (2.0 * aspect * k))
                    .max((y1 - y0) / (2.0 * k))
                    .max(1e-9 * size);
                // The visible height is tied to |target - eye|; keep the eye in front of
                // the scene anyway (nothing is clipped in orthographic views).
                let target = add(
                    &centre,
                    &add(
                        &scale(&fr.right, 0.5 * (x0 + x1)),
                        &scale(&fr.up, 0.5 * (y0 + y1)),
                    ),
                );
                let eye = sub(&target, &scale(&fr.forward, half / ty));
                Camera {
                    eye,
                    target,
                    up: fr.up,
                    fov_y_degrees: fov,
                    projection,
                }
            }
            Projection::Perspective => {
                let zmin = rel.iter().map(|r| r[2]).fold(f64::INFINITY, f64::min);
                // Smallest distance from the (shifted) target at which every point fits.
                let distance = |a: f64, b: f64| {
                    let mut d = (-zmin + 1e-6 * size).max(1e-9);
                    for r in &rel {
                        let need =
                            ((r[0] - a).abs() / (tx * k)).max((r[1] - b).abs() / (ty * k)) - r[2];
                        d = d.max(need);
                    }
                    d
                };
                let (mut a, mut b) = (0.0, 0.0); // lateral shift of the target (right, up)
                for _ in 0..8 {
                    let d = distance(a, b);
                    // Centre the projected extents.
                    let (mut x0, mut x1, mut y0, mut y1) = (
                        f64::INFINITY,
                        f64::NEG_INFINITY,
                        f64::INFINITY,
                        f64::NEG_INFINITY,
                    );
                    for r in &rel {
                        let depth = d + r[2];
                        let nx = (r[0] - a) / depth;
                        let ny = (r[1] - b) / depth;
                        x0 = x0.min(nx);
                        x1 = x1.max(nx);
                        y0 = y0.min(ny);
                        y1 = y1.max(ny);
                    }
                    a += 0.5 * (x0 + x1) * d;
                    b += 0.5 * (y0 + y1) * d;
                }
                let dist = distance(a, b);
                let target = add(&centre, &add(&scale(&fr.right, a), &scale(&fr.up, b)));
                let eye = sub(&target, &scale(&fr.forward, dist));
                Camera {
                    eye,
                    target,
                    up: fr.up,
                    fov_y_degrees: fov,
                    projection,
                }
            }
        }
    }
}

fn frame_from(view_direction: [f64; 3], up: [f64; 3]) -> CameraFrame {
    let mut forward = normalize(&view_direction);
    if forward == [0.0; 3] {
        forward = [0.0, 0.0, -1.0];
    }
    let mut right = normalize(&cross(&forward, &up));
    if norm(&right) < 0.5 {
        // `up` parallel to the view direction: take any perpendicular.
        let alt = if forward[0].abs() < 0.9 {
            [1.0, 0.0, 0.0]
        } else {
            [0.0, 1.0, 0.0]
        };
        right = normalize(&cross(&forward, &alt));
    }
    let up = cross(&right, &forward);
    CameraFrame { right, up, forward }
}

// ---------------------------------------------------------------------------------------
// Triangles and shading options.

/// A directional light: `direction` points from the surface towards the light, in camera
/// coordinates (x right, y up, z towards the viewer), so lighting follows the camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    pub direction: [f64; 3],
    pub intensity: f64,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shading {
    /// One normal per triangle (the geometric one).
    Flat,
    /// Lighting evaluated at the vertices (from the vertex normals) and interpolated.
    Gouraud,
    /// Vertex normals interpolated and lighting evaluated per pixel (still Lambert).
    Smooth,
}

/// Lines drawn along the flagged edges of triangles (e.g. the quad edges of a mesh).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wireframe {
    pub colour: [u8; 3],
    /// Line width in output pixels.
    pub width_px: f64,
}

#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    pub width: u32,
    pub height: u32,
    /// Supersampling factor per axis (1 = none; 3 is a good default).
    pub supersample: u32,
    pub background: [u8; 3],
    /// Ambient light, added to the Lambert terms (a surface facing the key light at
    /// normal incidence gets `ambient + intensity`; values are clamped to 1).
    pub ambient: f64,
    pub lights: Vec<Light>,
    pub shading: Shading,
    /// Perspective-correct interpolation of texture coordinates, colours and normals
    /// (otherwise affine in screen space).
    pub perspective_correct: bool,
    pub wireframe: Option<Wireframe>,
}

impl RenderOptions {
    /// Two lights (a key light from the upper left front and a weak fill from the right),
    /// ambient 0.22, smooth shading, 3x supersampling, white background.
    pub fn new(width: u32, height: u32) -> RenderOptions {
        RenderOptions {
            width,
            height,
            supersample: 3,
            background: WHITE,
            ambient: 0.22,
            lights: vec![
                Light {
                    direction: [-0.45, 0.55, 1.0],
                    intensity: 0.68,
                },
                Light {
                    direction: [0.7, -0.1, 0.5],
                    intensity: 0.2,
                },
            ],
            shading: Shading::Smooth,
            perspective_correct: true,
            wireframe: None,
        }
    }

    /// No lights and ambient 1: every surface shows its colour (or texel) exactly.
    pub fn unlit(width: u32, height: u32) -> RenderOptions {
        RenderOptions {
            ambient: 1.0,
            lights: Vec::new(),
            shading: Shading::Flat,
            ..RenderOptions::new(width, height)
        }
    }
}

/// A triangle to rasterize (world coordinates).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    pub positions: [[f64; 3]; 3],
    /// Vertex normals (any length; zero means "use the face normal"). Normals are
    /// flipped together with the face when the triangle is seen from behind (two-sided
    /// lighting).
    pub normals: [[f64; 3]; 3],
    /// Texture coordinates; the texture passed to [`rasterize`] replaces `colour` (and
    /// `colours`) where these are given.
    pub uv: Option<[[f64; 2]; 3]>,
    pub colour: [u8; 3],
    /// A colour per vertex, interpolated per pixel (perspective-correct like the texture
    /// coordinates); replaces `colour` where given (and no texture applies).
    pub colours: Option<[[u8; 3]; 3]>,
    /// Bit `i` set: the edge from vertex `i` to vertex `(i + 1) % 3` is drawn by the
    /// wireframe option.
    pub edges: u8,
}

impl Triangle {
    /// A flat-coloured triangle with no vertex normals, no texture and all edges flagged.
    pub fn flat(positions: [[f64; 3]; 3], colour: [u8; 3]) -> Triangle {
        Triangle {
            positions,
            normals: [[0.0; 3]; 3],
            uv: None,
            colour,
            colours: None,
            edges: 0b111,
        }
    }
}

// ---------------------------------------------------------------------------------------
// Rasterization.

/// A vertex after transformation: view position and attributes to interpolate.
#[derive(Clone, Copy, Debug)]
struct ClipVertex {
    view: [f64; 3],
    normal: [f64; 3], // camera frame, already flipped towards the viewer
    uv: [f64; 2],
    colour: [f64; 3], // per-vertex colour (the triangle's where it has none)
    light: f64,       // Gouraud intensity
}

impl ClipVertex {
    fn lerp(&self, o: &ClipVertex, t: f64) -> ClipVertex {
        let l3 = |a: [f64; 3], b: [f64; 3]| add(&a, &scale(&sub(&b, &a), t));
        ClipVertex {
            view: l3(self.view, o.view),
            normal: l3(self.normal, o.normal),
            uv: [
                self.uv[0] + (o.uv[0] - self.uv[0]) * t,
                self.uv[1] + (o.uv[1] - self.uv[1]) * t,
            ],
            colour: l3(self.colour, o.colour),
            light: self.light + (o.light - self.light) * t,
        }
    }
}

#[derive(Clone, Copy, Debug)]
struct ScreenVertex {
    x: f64,
    y: f64,
    /// Affine in screen space: `1 / depth` (perspective) or `-depth` (orthographic);
    /// larger is nearer.
    key: f64,
    /// Perspective weight `1 / depth` (1 for orthographic or affine interpolation).
    w: f64,
    attr: ClipVertex,
}

#[derive(Clone, Copy, Debug)]
struct ScreenTriangle {
    v: [ScreenVertex; 3],
    colour: [f64; 3],
    textured: bool,
    /// Interpolate the vertices' colours (else `colour` throughout).
    vertex_coloured: bool,
    flat_light: f64,
    edges: u8,
    ymin: i64,
    ymax: i64,
}

fn lambert(n: [f64; 3], lights: &[([f64; 3], f64)], ambient: f64) -> f64 {
    let mut s = ambient;
    for (l, i) in lights {
        s += i * dot(&n, l).max(0.0);
    }
    s
}

/// Rasterizes `triangles` seen from `camera` into an `options.width x options.height`
/// image. `texture` is sampled for the triangles that have texture coordinates.
///
/// A depth pass first finds the triangle seen at each sample (the nearest; of equally near
/// ones the first in `triangles`), then each sample is shaded once, by that triangle: the
/// image drawing the triangles in order over each other with a depth test gives, without
/// shading the samples that a nearer triangle covers later.
pub fn rasterize(
    triangles: &[Triangle],
    texture: Option<&Image>,
    camera: &Camera,
    options: &RenderOptions,
) -> Image {
    let ss = options.supersample.clamp(1, 8);
    let (w, h) = (options.width * ss, options.height * ss);
    if w == 0 || h == 0 {
        return Image::new(options.width, options.height, options.background);
    }
    let lights: Vec<([f64; 3], f64)> = options
        .lights
        .iter()
        .map(|l| (normalize(&l.direction), l.intensity))
        .filter(|(d, _)| *d != [0.0; 3])
        .collect();
    let ssf = ss as f64;

    // --- Vertex stage: transform, light, clip, project.
    let stage = VertexStage {
        camera,
        frame: camera.frame(),
        lights: &lights,
        options,
        texture,
        perspective: camera.projection == Projection::Perspective,
        near: 1e-4 * norm(&sub(&camera.target, &camera.eye)).max(1e-12),
        w,
        h,
    };
    let screen: Vec<ScreenTriangle> = triangles
        .par_iter()
        .flat_map_iter(|t| stage.screen(t))
        .collect();

    // --- Bin triangles into horizontal bands (keeping the input order within a band).
    let band_rows = (16 * ss) as usize;
    let bins = bin_bands(&screen, band_rows, (h as usize).div_ceil(band_rows));

    // --- Pixel stage, one band per task.
    let mut colour_buf = vec![0u8; 3 * w as usize * h as usize];
    let pixels = PixelStage {
        screen: &screen,
        bins: &bins,
        texture,
        lights: &lights,
        options,
        wire: options
            .wireframe
            .map(|wf| (wf.colour.map(|c| c as f64), 0.5 * wf.width_px * ssf)),
        w: w as usize,
        band_rows,
    };
    colour_buf
        .par_chunks_mut(3 * w as usize * band_rows)
        .enumerate()
        .for_each(|(band, cbuf)| pixels.draw_band(band, cbuf));
    let img = Image {
        width: w,
        height: h,
        rgb: colour_buf,
    };
    img.downsample(ss)
}

/// What the vertex stage of [`rasterize`] works with ([`VertexStage::screen`]).
struct VertexStage<'a> {
    camera: &'a Camera,
    frame: CameraFrame,
    /// The lights: unit directions and intensities.
    lights: &'a [([f64; 3], f64)],
    options: &'a RenderOptions,
    texture: Option<&'a Image>,
    perspective: bool,
    /// The near plane's distance from the eye (perspective).
    near: f64,
    /// The supersampled image's size.
    w: u32,
    h: u32,
}

impl VertexStage<'_> {
    /// Camera coordinates with z towards the viewer.
    fn to_cam(&self, n: [f64; 3]) -> [f64; 3] {
        [
            dot(&n, &self.frame.right),
            dot(&n, &self.frame.up),
            -dot(&n, &self.frame.forward),
        ]
    }

    /// Triangle `t` transformed, lit (its normals flipped towards the viewer), clipped
    /// against the near plane and projected: the screen triangles it becomes, none where it
    /// is not finite, degenerate or off the image's projection; a clipped one is a fan with no
    /// wireframe edges.
    fn screen(&self, t: &Triangle) -> Vec<ScreenTriangle> {
        let (camera, options) = (self.camera, self.options);
        let mut out: Vec<ScreenTriangle> = Vec::new();
        let p = t.positions;
        if !p.iter().flatten().all(|c| c.is_finite()) {
            return out;
        }
        let face_n = normalize(&cross(&sub(&p[1], &p[0]), &sub(&p[2], &p[0])));
        if face_n == [0.0; 3] {
            return out; // degenerate
        }
        let centroid = scale(&add(&add(&p[0], &p[1]), &p[2]), 1.0 / 3.0);
        let to_viewer = if self.perspective {
            sub(&camera.eye, &centroid)
        } else {
            scale(&self.frame.forward, -1.0)
        };
        let flip = if dot(&face_n, &to_viewer) < 0.0 {
            -1.0
        } else {
            1.0
        };
        let face_cam = self.to_cam(scale(&face_n, flip));
        let flat_light = lambert(face_cam, self.lights, options.ambient);
        let verts: [ClipVertex; 3] = std::array::from_fn(|i| {
            let vn = normalize(&t.normals[i]);
            let n = if vn == [0.0; 3] {
                face_cam
            } else {
                self.to_cam(scale(&vn, flip))
            };
            let light = match options.shading {
                Shading::Flat => flat_light,
                _ => lambert(n, self.lights, options.ambient),
            };
            ClipVertex {
                view: camera.to_view(p[i]),
                normal: n,
                uv: t.uv.map(|uv| uv[i]).unwrap_or([0.0; 2]),
                colour: t
                    .colours
                    .map(|c| c[i])
                    .unwrap_or(t.colour)
                    .map(|c| c as f64),
                light,
            }
        });
        // Near-plane clipping (perspective only).
        let mut poly: Vec<ClipVertex> = verts.to_vec();
        let mut clipped = false;
        if self.perspective && verts.iter().any(|v| v.view[2] < self.near) {
            clipped = true;
            poly = clip_near(&poly, self.near);
        }
        if poly.len() < 3 {
            return out;
        }
        let colour = t.colour.map(|c| c as f64);
        let textured = t.uv.is_some() && self.texture.is_some();
        let vertex_coloured = !textured && t.colours.is_some();
        let sv: Option<Vec<ScreenVertex>> = poly.iter().map(|v| self.project(v)).collect();
        let Some(sv) = sv else { return out };
        for i in 1..sv.len() - 1 {
            let v = [sv[0], sv[i], sv[i + 1]];
            let ymin = v.iter().map(|q| q.y).fold(f64::INFINITY, f64::min);
            let ymax = v.iter().map(|q| q.y).fold(f64::NEG_INFINITY, f64::max);
            if !(ymin.is_finite() && ymax.is_finite()) {
                continue;
            }
            out.push(ScreenTriangle {
                v,
                colour,
                textured,
                vertex_coloured,
                flat_light,
                edges: if clipped { 0 } else { t.edges },
                ymin: (ymin - 0.5).floor().max(0.0) as i64,
                ymax: ((ymax - 0.5).ceil() as i64).min(self.h as i64 - 1),
            });
        }
        out
    }

    /// Vertex `v` on the supersampled image, with its depth key and perspective weight;
    /// `None` where the camera cannot project it.
    fn project(&self, v: &ClipVertex) -> Option<ScreenVertex> {
        let (x, y) = self
            .camera
            .view_to_pixel(v.view, self.w as f64, self.h as f64)?;
        let (key, pw) = if self.perspective {
            (1.0 / v.view[2], 1.0 / v.view[2])
        } else {
            (-v.view[2], 1.0)
        };
        Some(ScreenVertex {
            x,
            y,
            key,
            w: if self.options.perspective_correct {
                pw
            } else {
                1.0
            },
            attr: *v,
        })
    }
}

/// Polygon `poly` clipped against the plane `view z = near`: the part in front of it (fewer
/// than three vertices where none is).
fn clip_near(poly: &[ClipVertex], near: f64) -> Vec<ClipVertex> {
    let mut res = Vec::with_capacity(4);
    for i in 0..poly.len() {
        let a = poly[i];
        let b = poly[(i + 1) % poly.len()];
        let (ina, inb) = (a.view[2] >= near, b.view[2] >= near);
        if ina {
            res.push(a);
        }
        if ina != inb {
            let s = (near - a.view[2]) / (b.view[2] - a.view[2]);
            res.push(a.lerp(&b, s));
        }
    }
    res
}

/// The indices of the triangles of `screen` in each of `n_bands` horizontal bands of
/// `band_rows` rows that they reach, in the input order within a band.
fn bin_bands(screen: &[ScreenTriangle], band_rows: usize, n_bands: usize) -> Vec<Vec<u32>> {
    let mut bins: Vec<Vec<u32>> = vec![Vec::new(); n_bands];
    for (i, t) in screen.iter().enumerate() {
        if t.ymax < t.ymin || t.ymax < 0 {
            continue;
        }
        let b0 = (t.ymin as usize) / band_rows;
        let b1 = (t.ymax as usize / band_rows).min(n_bands - 1);
        for bin in bins.iter_mut().take(b1 + 1).skip(b0) {
            bin.push(i as u32);
        }
    }
    bins
}

/// What the pixel stage of [`rasterize`] works with ([`PixelStage::draw_band`]).
struct PixelStage<'a> {
    screen: &'a [ScreenTriangle],
    /// The triangles of each band ([`bin_bands`]).
    bins: &'a [Vec<u32>],
    texture: Option<&'a Image>,
    lights: &'a [([f64; 3], f64)],
    options: &'a RenderOptions,
    /// The wireframe's colour and half width (samples).
    wire: Option<([f64; 3], f64)>,
    /// The supersampled image's width and a band's rows.
    w: usize,
    band_rows: usize,
}

impl PixelStage<'_> {
    /// Draws band `band` into `cbuf`, its rows of RGB samples.
    fn draw_band(&self, band: usize, cbuf: &mut [u8]) {
        let w = self.w;
        let rows = cbuf.len() / (3 * w);
        let y0 = band * self.band_rows;
        // the depth pass: the triangle seen at each sample (the first in order of those
        // nearest), then each sample shaded once, by that triangle (the same colour as
        // drawing the triangles in order over each other, without shading the hidden ones)
        let mut depth = vec![f64::NEG_INFINITY; rows * w];
        let mut seen = vec![u32::MAX; rows * w];
        for &ti in &self.bins[band] {
            cover_triangle(
                &self.screen[ti as usize],
                ti,
                w,
                y0,
                rows,
                &mut depth,
                &mut seen,
            );
        }
        for (r, (row, seen)) in cbuf
            .chunks_exact_mut(3 * w)
            .zip(seen.chunks_exact(w))
            .enumerate()
        {
            for (x, (px, &ti)) in row.chunks_exact_mut(3).zip(seen).enumerate() {
                px.copy_from_slice(&match self.screen.get(ti as usize) {
                    Some(t) => shade_sample(
                        t,
                        self.texture,
                        self.lights,
                        self.options,
                        self.wire,
                        x,
                        y0 + r,
                    ),
                    None => self.options.background,
                });
            }
        }
    }
}

/// The triangle's signed double area in pixels and its barycentric weights at the centre of
/// sample `(x, y)` (normalised edge functions).
fn barycentric(t: &ScreenTriangle, x: usize, y: usize) -> (f64, [f64; 3]) {
    let [a, b, c] = t.v;
    let area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    let inv_area = 1.0 / area;
    let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
    let l0 = ((b.x - px) * (c.y - py) - (b.y - py) * (c.x - px)) * inv_area;
    let l1 = ((c.x - px) * (a.y - py) - (c.y - py) * (a.x - px)) * inv_area;
    (area, [l0, l1, 1.0 - l0 - l1])
}

/// The depth pass of one triangle over the band of `rows` rows from `y0`: where it covers a
/// sample and is nearer than what is there, its depth key and index `ti` go to `depth` and
/// `seen`.
fn cover_triangle(
    t: &ScreenTriangle,
    ti: u32,
    w: usize,
    y0: usize,
    rows: usize,
    depth: &mut [f64],
    seen: &mut [u32],
) {
    let [a, b, c] = t.v;
    let area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    if !(area.abs() > 1e-12) {
        return;
    }
    // Inclusive edge test with a tolerance relative to the triangle, so that pixel
    // centres on a shared edge are covered by at least one of the two triangles.
    let eps = -1e-9;
    let xmin = a.x.min(b.x).min(c.x);
    let xmax = a.x.max(b.x).max(c.x);
    let x_lo = ((xmin - 0.5).floor().max(0.0)) as usize;
    let x_hi = ((xmax - 0.5).ceil()).min(w as f64 - 1.0);
    if x_hi < 0.0 {
        return;
    }
    let x_hi = x_hi as usize;
    let ry0 = (t.ymin.max(y0 as i64)) as usize;
    let ry1 = (t.ymax.min((y0 + rows) as i64 - 1)).max(-1);
    if ry1 < ry0 as i64 {
        return;
    }
    let ry1 = ry1 as usize;
    for y in ry0..=ry1 {
        for x in x_lo..=x_hi {
            let (_, [l0, l1, l2]) = barycentric(t, x, y);
            if l0 < eps || l1 < eps || l2 < eps {
                continue;
            }
            let key = l0 * a.key + l1 * b.key + l2 * c.key;
            let di = (y - y0) * w + x;
            if !(key > depth[di]) {
                continue;
            }
            depth[di] = key;
            seen[di] = ti;
        }
    }
}

/// The colour of sample `(x, y)` of a triangle that covers it.
#[allow(clippy::too_many_arguments)]
fn shade_sample(
    t: &ScreenTriangle,
    texture: Option<&Image>,
    lights: &[([f64; 3], f64)],
    options: &RenderOptions,
    wire: Option<([f64; 3], f64)>,
    x: usize,
    y: usize,
) -> [u8; 3] {
    let [a, b, c] = t.v;
    let (area, [l0, l1, l2]) = barycentric(t, x, y);
    // Perspective-correct weights.
    let q0 = l0 * a.w;
    let q1 = l1 * b.w;
    let q2 = l2 * c.w;
    let qs = q0 + q1 + q2;
    let (q0, q1, q2) = (q0 / qs, q1 / qs, q2 / qs);
    let albedo = if t.textured {
        let u = q0 * a.attr.uv[0] + q1 * b.attr.uv[0] + q2 * c.attr.uv[0];
        let v = q0 * a.attr.uv[1] + q1 * b.attr.uv[1] + q2 * c.attr.uv[1];
        texture
            .map(|tex| tex.sample_bilinear(u, v))
            .unwrap_or(t.colour)
    } else if t.vertex_coloured {
        std::array::from_fn(|k| {
            q0 * a.attr.colour[k] + q1 * b.attr.colour[k] + q2 * c.attr.colour[k]
        })
    } else {
        t.colour
    };
    let light = match options.shading {
        Shading::Flat => t.flat_light,
        Shading::Gouraud => q0 * a.attr.light + q1 * b.attr.light + q2 * c.attr.light,
        Shading::Smooth => {
            let n = normalize(&add(
                &add(&scale(&a.attr.normal, q0), &scale(&b.attr.normal, q1)),
                &scale(&c.attr.normal, q2),
            ));
            lambert(n, lights, options.ambient)
        }
    }
    .clamp(0.0, 1.0);
    let mut col = albedo.map(|c| c * light);
    if let Some((wc, half)) = wire {
        if t.edges != 0 {
            // Edge lengths (edge i: vertex i -> i+1, opposite vertex i+2).
            let pts = [(a.x, a.y), (b.x, b.y), (c.x, c.y)];
            let l = [l2, l0, l1]; // weight of the vertex opposite edge i
            for i in 0..3 {
                if t.edges & (1 << i) != 0 {
                    let (p, q) = (pts[i], pts[(i + 1) % 3]);
                    let edge_len = ((q.0 - p.0).powi(2) + (q.1 - p.1).powi(2)).sqrt();
                    // distance = barycentric * 2 area / edge length
                    let dist = l[i] * area.abs() / edge_len.max(1e-12);
                    if dist <= half {
                        col = wc;
                    }
                }
            }
        }
    }
    col.map(|c| round_half_away(c).clamp(0.0, 255.0) as u8)
}

/// `x.round()` (half away from zero; but +0 for -0.5 < x < 0), without the call to the C
/// library's `round` that `f64::round` is on the baseline x86-64 target: the truncation is
/// exact below 2^52 and so is the fraction `x - trunc(x)`; NaN and larger magnitudes are
/// returned as they are (whole numbers there).
#[inline]
pub(crate) fn round_half_away(x: f64) -> f64 {
    if !(x.abs() < 4_503_599_627_370_496.0) {
        return x;
    }
    let t = x as i64 as f64;
    let frac = x - t;
    if frac >= 0.5 {
        t + 1.0
    } else if frac <= -0.5 {
        t - 1.0
    } else {
        t
    }
}
