//! Figure rendering on the CPU: shaded renderings of a hexahedral mesh's boundary,
//! panels composed into figures with text labels, line plots and gap profiles, and PNG
//! encoding.
//!
//! The library computes pixels and never writes a figure by itself ("src computes"): the
//! functions here return [`Image`]s; the `sticky-lips` command calls [`save_png`] to write
//! them (atomically).
//!
//! - [`raster`]: [`Image`], [`Camera`] (perspective or orthographic, [`Camera::fit`]),
//!   [`rasterize`] (z-buffer, Lambert shading, textures and per-vertex colours sampled per
//!   pixel, supersampling).
//! - [`surface`]: [`boundary_quads`] of a hexahedral mesh and normals (hard or soft
//!   creases: [`corner_normals`], [`corner_normals_weighted`], [`soft_crease`]).
//! - triangles of a mesh's quads: [`mesh_triangles`] (a colour per face, or the texture),
//!   [`paint_triangles`] (a [`FacePaint`] per face: a colour, a colour per corner, or the
//!   texture).
//! - [`plot`]: [`plot::line_plot`], [`plot::profile_plot`], [`plot::heatmap_plot`].
//! - text: [`Image::label`], [`text_size`] with the embedded DejaVu Sans font.
//!
//! A rendering of the current configuration of a mesh:
//!
//! ```
//! use sticky_lips::render::*;
//! let mesh = sticky_lips::mesh::generate::block([0.0; 3], [2.0, 1.0, 1.0], [4, 2, 2]);
//! let faces = boundary_quads(&mesh.elements);
//! let camera = Camera::fit(&mesh.nodes, [-0.3, -1.0, -0.4], [0.0, 0.0, 1.0], 30.0,
//!                          Projection::Perspective, 4.0 / 3.0, 0.05);
//! let img = render_mesh(&mesh.nodes, &faces, &|f| if f.element % 2 == 0 { [200, 80, 80] }
//!                       else { [230, 200, 180] }, None, &camera, 320, 240);
//! assert_eq!((img.width, img.height), (320, 240));
//! let png_bytes = encode_png(&img);
//! # assert!(png_bytes.len() > 100);
//! ```

pub mod plot;
pub mod raster;
pub mod surface;
mod text;

pub use raster::{
    rasterize, Camera, CameraFrame, Image, Light, Projection, RenderOptions, Shading, Triangle,
    Wireframe, BLACK, WHITE,
};
pub use surface::{
    boundary_quads, boundary_quads_where, corner_normals, corner_normals_weighted, face_centroid,
    face_normal, soft_crease, vertex_normals, BoundaryFace,
};
pub use text::{text_size, FONT_BYTES};

use crate::error::{Error, Location, Result};
use crate::linalg::{norm, sub};
use std::path::Path;

/// Normals of faces meeting at less than this angle are averaged for smooth shading;
/// sharper edges stay sharp.
pub const DEFAULT_CREASE_DEGREES: f64 = 60.0;

/// Triangles for the boundary `faces` at the current `positions`: each quad split along
/// its shorter diagonal, coloured by `face_colour`, with crease-aware corner normals
/// ([`corner_normals`]), per-node texture coordinates `uv` (if given), and the quad edges
/// (not the diagonal) flagged for the wireframe option.
pub fn mesh_triangles(
    positions: &[[f64; 3]],
    faces: &[BoundaryFace],
    face_colour: &dyn Fn(&BoundaryFace) -> [u8; 3],
    uv: Option<&[[f64; 2]]>,
    crease_degrees: f64,
) -> Vec<Triangle> {
    let normals = corner_normals(positions, faces, crease_degrees);
    quad_triangles(positions, faces, &normals, uv, &|f| {
        (face_colour(f), None, true)
    })
}

/// How [`paint_triangles`] colours one boundary face.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FacePaint {
    /// One colour over the whole face.
    Colour([u8; 3]),
    /// A colour at each corner (in the order of the face's `nodes`), interpolated per
    /// pixel, so that the colour varies smoothly inside the face (and is continuous across
    /// faces that give a shared node the same colour).
    Corners([[u8; 3]; 4]),
    /// The texture, sampled per pixel (bilinearly) through the per-node texture
    /// coordinates; the colour where there are no texture coordinates or no texture.
    Texture([u8; 3]),
}

/// [`mesh_triangles`] with a [`FacePaint`] per face and the corner normals given (e.g. from
/// [`corner_normals_weighted`], one entry per face).
pub fn paint_triangles(
    positions: &[[f64; 3]],
    faces: &[BoundaryFace],
    normals: &[[[f64; 3]; 4]],
    paint: &dyn Fn(&BoundaryFace) -> FacePaint,
    uv: Option<&[[f64; 2]]>,
) -> Vec<Triangle> {
    quad_triangles(positions, faces, normals, uv, &|f| match paint(f) {
        FacePaint::Colour(c) => (c, None, false),
        FacePaint::Corners(cs) => (cs[0], Some(cs), false),
        FacePaint::Texture(c) => (c, None, true),
    })
}

/// The triangles of the quads: `style(face)` gives the colour, the corner colours (if any)
/// and whether the texture coordinates apply.
#[allow(clippy::type_complexity)]
fn quad_triangles(
    positions: &[[f64; 3]],
    faces: &[BoundaryFace],
    normals: &[[[f64; 3]; 4]],
    uv: Option<&[[f64; 2]]>,
    style: &dyn Fn(&BoundaryFace) -> ([u8; 3], Option<[[u8; 3]; 4]>, bool),
) -> Vec<Triangle> {
    let mut out = Vec::with_capacity(2 * faces.len());
    for (f, n) in faces.iter().zip(normals) {
        let p = |i: usize| positions[f.nodes[i] as usize];
        let (colour, corners, textured) = style(f);
        let uv = if textured { uv } else { None };
        // Corner triples and edge masks (bit i: edge from corner i to corner i+1).
        let split: [([usize; 3], u8); 2] = if norm(&sub(&p(2), &p(0))) <= norm(&sub(&p(3), &p(1))) {
            [([0, 1, 2], 0b011), ([0, 2, 3], 0b110)]
        } else {
            [([0, 1, 3], 0b101), ([1, 2, 3], 0b011)]
        };
        for (c, edges) in split {
            out.push(Triangle {
                positions: c.map(p),
                normals: c.map(|i| n[i]),
                uv: uv.map(|uv| c.map(|i| uv[f.nodes[i] as usize])),
                colour,
                colours: corners.map(|cs| c.map(|i| cs[i])),
                edges,
            });
        }
    }
    out
}

/// Renders the boundary `faces` of a mesh at the current `positions` with the default
/// options ([`RenderOptions::new`]: two lights, smooth shading, 3x supersampling, white
/// background). `uv`: texture coordinates per node and the texture, which then replaces
/// the face colours.
pub fn render_mesh(
    positions: &[[f64; 3]],
    faces: &[BoundaryFace],
    face_colour: &dyn Fn(&BoundaryFace) -> [u8; 3],
    uv: Option<(&[[f64; 2]], &Image)>,
    camera: &Camera,
    width: u32,
    height: u32,
) -> Image {
    render_mesh_with(
        positions,
        faces,
        face_colour,
        uv,
        camera,
        &RenderOptions::new(width, height),
    )
}

/// [`render_mesh`] with explicit options (size, lights, shading, wireframe, ...).
pub fn render_mesh_with(
    positions: &[[f64; 3]],
    faces: &[BoundaryFace],
    face_colour: &dyn Fn(&BoundaryFace) -> [u8; 3],
    uv: Option<(&[[f64; 2]], &Image)>,
    camera: &Camera,
    options: &RenderOptions,
) -> Image {
    let tris = mesh_triangles(
        positions,
        faces,
        face_colour,
        uv.map(|(u, _)| u),
        DEFAULT_CREASE_DEGREES,
    );
    rasterize(&tris, uv.map(|(_, t)| t), camera, options)
}

/// Titles around a grid of panels (see [`Image::grid_labelled`]).
#[derive(Clone, Debug)]
pub struct GridLabels<'a> {
    /// Centred above everything.
    pub title: Option<&'a str>,
    /// Centred above each column (missing entries: none).
    pub column_titles: &'a [&'a str],
    /// Left of each row, vertically centred (missing entries: none).
    pub row_titles: &'a [&'a str],
    pub text_size: f64,
    pub text_colour: [u8; 3],
}

impl Default for GridLabels<'_> {
    fn default() -> Self {
        GridLabels {
            title: None,
            column_titles: &[],
            row_titles: &[],
            text_size: 20.0,
            text_colour: BLACK,
        }
    }
}

impl Image {
    /// Panels laid out row by row in `cols` columns, each centred in a cell the size of
    /// the largest panel, `spacing` pixels between cells and around the border.
    pub fn grid(images: &[Image], cols: usize, spacing: u32, background: [u8; 3]) -> Image {
        Image::grid_labelled(images, cols, spacing, background, &GridLabels::default())
    }

    /// [`Image::grid`] with a title, column titles and row titles (e.g. Fig. 4: columns
    /// "without stickiness" / "with stickiness", rows "t = 0.04 s", ...).
    pub fn grid_labelled(
        images: &[Image],
        cols: usize,
        spacing: u32,
        background: [u8; 3],
        labels: &GridLabels,
    ) -> Image {
        let cols = cols.max(1);
        let rows = images.len().div_ceil(cols).max(1);
        // each column as wide as its widest image, each row as tall as its tallest (a legend
        // beside or below a rendering takes only the room it needs)
        let col_w: Vec<u32> = (0..cols)
            .map(|c| {
                images
                    .iter()
                    .skip(c)
                    .step_by(cols)
                    .map(|i| i.width)
                    .max()
                    .unwrap_or(0)
            })
            .collect();
        let row_h: Vec<u32> = (0..rows)
            .map(|r| {
                images
                    .iter()
                    .skip(r * cols)
                    .take(cols)
                    .map(|i| i.height)
                    .max()
                    .unwrap_or(0)
            })
            .collect();
        let col_x: Vec<u32> = col_w
            .iter()
            .scan(0, |x, &w| {
                let x0 = *x;
                *x += w + spacing;
                Some(x0)
            })
            .collect();
        let row_y: Vec<u32> = row_h
            .iter()
            .scan(0, |y, &h| {
                let y0 = *y;
                *y += h + spacing;
                Some(y0)
            })
            .collect();
        let ts = labels.text_size;
        let nonempty = |v: &[&str]| v.iter().any(|s| !s.is_empty());
        let title_h = match labels.title {
            Some(t) if !t.is_empty() => text_size(t, ts * 1.15).1 + spacing,
            _ => 0,
        };
        let col_h = if nonempty(labels.column_titles) {
            labels
                .column_titles
                .iter()
                .map(|t| text_size(t, ts).1)
                .max()
                .unwrap_or(0)
                + spacing / 2
        } else {
            0
        };
        let row_w = if nonempty(labels.row_titles) {
            labels
                .row_titles
                .iter()
                .map(|t| text_size(t, ts).0)
                .max()
                .unwrap_or(0)
                + spacing
        } else {
            0
        };
        let width = 2 * spacing + row_w + col_w.iter().sum::<u32>() + (cols as u32 - 1) * spacing;
        let height =
            2 * spacing + title_h + col_h + row_h.iter().sum::<u32>() + (rows as u32 - 1) * spacing;
        let mut out = Image::new(width, height, background);
        let x_of = |c: usize| (spacing + row_w + col_x[c]) as i64;
        let y_of = |r: usize| (spacing + title_h + col_h + row_y[r]) as i64;
        if let Some(t) = labels.title {
            out.label_centred(
                t,
                width as i64 / 2,
                spacing as i64,
                ts * 1.15,
                labels.text_colour,
            );
        }
        for (c, t) in labels.column_titles.iter().enumerate().take(cols) {
            out.label_centred(
                t,
                x_of(c) + col_w[c] as i64 / 2,
                (spacing + title_h) as i64,
                ts,
                labels.text_colour,
            );
        }
        for (r, t) in labels.row_titles.iter().enumerate().take(rows) {
            let th = text_size(t, ts).1 as i64;
            out.label(
                t,
                spacing as i64,
                y_of(r) + (row_h[r] as i64 - th) / 2,
                ts,
                labels.text_colour,
            );
        }
        for (i, img) in images.iter().enumerate() {
            let (r, c) = (i / cols, i % cols);
            let x = x_of(c) + (col_w[c] - img.width) as i64 / 2;
            let y = y_of(r) + (row_h[r] - img.height) as i64 / 2;
            out.blit(img, x, y);
        }
        out
    }

    /// A legend: one colour swatch and name per line (e.g. the materials of Fig. 2).
    pub fn legend(entries: &[(&str, [u8; 3])], text_size_px: f64, background: [u8; 3]) -> Image {
        let line = text_size("Hg", text_size_px).1.max(1);
        let sw = line * 3 / 4;
        let pad = line / 2;
        let tw = entries
            .iter()
            .map(|(t, _)| text_size(t, text_size_px).0)
            .max()
            .unwrap_or(0);
        let n = entries.len() as u32;
        let mut out = Image::new(
            2 * pad + sw + pad + tw,
            2 * pad + n * line + n.saturating_sub(1) * pad / 2,
            background,
        );
        for (i, (t, c)) in entries.iter().enumerate() {
            let y = (pad + i as u32 * (line + pad / 2)) as i64;
            let sy = y + (line - sw) as i64 / 2;
            out.fill_rect(pad as i64, sy, sw, sw, BLACK);
            out.fill_rect(
                pad as i64 + 1,
                sy + 1,
                sw.saturating_sub(2),
                sw.saturating_sub(2),
                *c,
            );
            out.label(t, (pad + sw + pad) as i64, y, text_size_px, BLACK);
        }
        out
    }
}

/// The image as an 8-bit RGB PNG. Panics if the image is empty or `rgb` has the wrong length.
pub fn encode_png(image: &Image) -> Vec<u8> {
    encode_png_with(image, None)
}

/// [`encode_png`] compressed with the `png` crate's fast setting (fdeflate: a fraction of the
/// time, a somewhat larger file), for the run's preview.
pub fn encode_png_fast(image: &Image) -> Vec<u8> {
    encode_png_with(image, Some(png::Compression::Fast))
}

/// The PNG with the `png` crate's default compression, or `compression`.
fn encode_png_with(image: &Image, compression: Option<png::Compression>) -> Vec<u8> {
    assert!(
        image.width > 0 && image.height > 0,
        "encode_png: empty image ({} x {})",
        image.width,
        image.height
    );
    assert_eq!(
        image.rgb.len(),
        3 * image.width as usize * image.height as usize,
        "encode_png: buffer length does not match the size"
    );
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, image.width, image.height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        if let Some(c) = compression {
            enc.set_compression(c);
        }
        let mut w = enc.write_header().expect("PNG header into memory");
        w.write_image_data(&image.rgb)
            .expect("PNG data into memory");
        w.finish().expect("PNG end into memory");
    }
    out
}

/// Encodes frames of one size as an animated PNG (APNG: every PNG reader shows the first
/// frame, browsers and most viewers play them), each shown `delay_ms`, looping forever.
/// Compressed with the `png` crate's fast setting (fdeflate: a fraction of the default's
/// time, for a larger file).
/// `None` when `frames` is empty or the sizes differ.
pub fn encode_apng(frames: &[Image], delay_ms: u16) -> Option<Vec<u8>> {
    let first = frames.first()?;
    let (w, h) = (first.width, first.height);
    if w == 0 || h == 0 || frames.iter().any(|f| f.width != w || f.height != h) {
        return None;
    }
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(png::Compression::Fast);
        enc.set_animated(frames.len() as u32, 0).ok()?;
        enc.set_frame_delay(delay_ms, 1000).ok()?;
        let mut wr = enc.write_header().ok()?;
        for f in frames {
            wr.write_image_data(&f.rgb).ok()?;
        }
        wr.finish().ok()?;
    }
    Some(out)
}

/// Decodes a PNG (any colour type and bit depth; alpha is dropped, grey expanded) to RGB.
pub fn decode_png(bytes: &[u8]) -> std::result::Result<Image, String> {
    let mut dec = png::Decoder::new(std::io::Cursor::new(bytes));
    dec.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = dec.read_info().map_err(|e| e.to_string())?;
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| "PNG too large".to_string())?;
    let mut buf = vec![0u8; size];
    let info = reader.next_frame(&mut buf).map_err(|e| e.to_string())?;
    let (w, h) = (info.width, info.height);
    let channels = match info.color_type {
        png::ColorType::Grayscale => 1,
        png::ColorType::GrayscaleAlpha => 2,
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        png::ColorType::Indexed => return Err("indexed PNG was not expanded".into()),
    };
    let mut rgb = Vec::with_capacity(3 * w as usize * h as usize);
    for y in 0..h as usize {
        let row = &buf[y * info.line_size..y * info.line_size + channels * w as usize];
        for px in row.chunks_exact(channels) {
            match channels {
                1 | 2 => rgb.extend_from_slice(&[px[0]; 3]),
                _ => rgb.extend_from_slice(&px[..3]),
            }
        }
    }
    Ok(Image {
        width: w,
        height: h,
        rgb,
    })
}

/// Decodes a baseline or progressive JPEG (greyscale, RGB, YCbCr or CMYK) to RGB, with the
/// `zune-jpeg` crate (the MakeHuman textures are JPEG).
pub fn decode_jpeg(bytes: &[u8]) -> std::result::Result<Image, String> {
    use zune_jpeg::zune_core::bytestream::ZCursor;
    use zune_jpeg::zune_core::colorspace::ColorSpace;
    use zune_jpeg::zune_core::options::DecoderOptions;
    // greyscale stays one channel (expanded below); everything else is converted to RGB
    let mut probe = zune_jpeg::JpegDecoder::new(ZCursor::new(bytes));
    probe.decode_headers().map_err(|e| e.to_string())?;
    let grey = probe.input_colorspace() == Some(ColorSpace::Luma);
    let out = if grey {
        ColorSpace::Luma
    } else {
        ColorSpace::RGB
    };
    let opts = DecoderOptions::default().jpeg_set_out_colorspace(out);
    let mut dec = zune_jpeg::JpegDecoder::new_with_options(ZCursor::new(bytes), opts);
    let pixels = dec.decode().map_err(|e| e.to_string())?;
    let (w, h) = dec
        .dimensions()
        .ok_or_else(|| "JPEG without a frame header".to_string())?;
    let (w, h) = (w as u32, h as u32);
    let n = w as usize * h as usize;
    let rgb: Vec<u8> = match dec.output_colorspace() {
        Some(ColorSpace::Luma) => pixels.iter().flat_map(|&g| [g, g, g]).collect(),
        Some(ColorSpace::RGB) => pixels,
        other => {
            return Err(format!(
                "JPEG decoded to an unexpected colour space {other:?}"
            ))
        }
    };
    if rgb.len() != 3 * n {
        return Err(format!(
            "JPEG decoded to {} bytes for {w} x {h} pixels",
            rgb.len()
        ));
    }
    Ok(Image {
        width: w,
        height: h,
        rgb,
    })
}

/// Reads a PNG file (e.g. a texture) as RGB.
pub fn load_png(path: &Path) -> Result<Image> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    decode_png(&bytes).map_err(|m| Error::input(path.display().to_string(), Location::None, m))
}

/// Writes the image as a PNG file, atomically (a reader never sees a partial file).
pub fn save_png(path: &Path, image: &Image) -> Result<()> {
    if image.width == 0 || image.height == 0 {
        return Err(Error::input(
            path.display().to_string(),
            Location::None,
            "cannot write an empty image",
        ));
    }
    crate::io::atomic::write_atomic(path, &encode_png(image)).map_err(|e| Error::io(path, e))
}

#[cfg(test)]
mod tests;
