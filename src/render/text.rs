//! Text in raster images, with the embedded DejaVu Sans font (assets/fonts, Bitstream
//! Vera licence) drawn through `ab_glyph`. The same font is registered with `plotters`
//! for the plots, so figures need no system fonts.

use super::raster::Image;
use ab_glyph::{point, Font, FontRef, PxScale, ScaleFont};
use std::sync::OnceLock;

/// DejaVu Sans 2.37 (see assets/fonts/LICENSE).
pub static FONT_BYTES: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

pub(crate) fn font() -> &'static FontRef<'static> {
    static FONT: OnceLock<FontRef<'static>> = OnceLock::new();
    FONT.get_or_init(|| FontRef::try_from_slice(FONT_BYTES).expect("the embedded font parses"))
}

/// Registers the embedded font with `plotters` as "sans-serif" (once).
pub(crate) fn register_plot_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let ok = plotters::style::register_font(
            "sans-serif",
            plotters::style::FontStyle::Normal,
            FONT_BYTES,
        )
        .is_ok();
        assert!(ok, "the embedded font registers with plotters");
    });
}

fn line_height(size: f64) -> f64 {
    let f = font().as_scaled(PxScale::from(size as f32));
    (f.ascent() - f.descent() + f.line_gap()) as f64
}

fn line_width(text: &str, size: f64) -> f64 {
    let f = font().as_scaled(PxScale::from(size as f32));
    let mut x = 0.0f32;
    let mut prev = None;
    for c in text.chars() {
        let id = f.glyph_id(c);
        if let Some(p) = prev {
            x += f.kern(p, id);
        }
        x += f.h_advance(id);
        prev = Some(id);
    }
    x as f64
}

/// Width and height in pixels of `text` (lines separated by `\n`) at `size` pixels
/// (the font's ascent minus descent).
pub fn text_size(text: &str, size: f64) -> (u32, u32) {
    let lines: Vec<&str> = text.split('\n').collect();
    let w = lines
        .iter()
        .map(|l| line_width(l, size))
        .fold(0.0f64, f64::max);
    let h = line_height(size) * lines.len() as f64;
    (w.ceil() as u32, h.ceil() as u32)
}

impl Image {
    /// Draws `text` (anti-aliased; lines separated by `\n`) with the top-left corner of
    /// its box at `(x, y)`, `size` pixels high (ascent minus descent), clipped to the image.
    pub fn label(&mut self, text: &str, x: i64, y: i64, size: f64, colour: [u8; 3]) {
        let scale = PxScale::from(size as f32);
        let f = font().as_scaled(scale);
        let lh = line_height(size);
        for (i, line) in text.split('\n').enumerate() {
            let baseline = y as f32 + f.ascent() + (i as f64 * lh) as f32;
            let mut caret = x as f32;
            let mut prev = None;
            for c in line.chars() {
                let id = f.glyph_id(c);
                if let Some(p) = prev {
                    caret += f.kern(p, id);
                }
                prev = Some(id);
                let glyph = id.with_scale_and_position(scale, point(caret, baseline));
                caret += f.h_advance(id);
                if let Some(og) = font().outline_glyph(glyph) {
                    let b = og.px_bounds();
                    let (bx, by) = (b.min.x as i64, b.min.y as i64);
                    og.draw(|gx, gy, cov| {
                        if cov > 0.0 {
                            self.blend(bx + gx as i64, by + gy as i64, colour, cov);
                        }
                    });
                }
            }
        }
    }

    /// Draws `text` horizontally centred on `cx`, its top at `y`.
    pub fn label_centred(&mut self, text: &str, cx: i64, y: i64, size: f64, colour: [u8; 3]) {
        let (w, _) = text_size(text, size);
        self.label(text, cx - w as i64 / 2, y, size, colour);
    }
}
