//! The preview every mouth or face run writes beside its frames, so that the result can be
//! looked at without ParaView: `preview.png`, an animated PNG of the mouth over the run (up
//! to [`ANIMATION_FRAMES`] frames spread evenly over the run, broken saliva elements left out
//! so that the lips part), and `preview_sheet.png`, a contact sheet of [`SHEET_FRAMES`]
//! frames labelled with their times. Rendered with the paper's mouth camera
//! ([`crate::app::look`]): on the shipped MakeHuman face through the face's skin texture on
//! the dark mouth interior, as the paper's figures of the face are
//! ([`crate::app::look::face_skin`]); on other models (the procedural mouth, a face of the
//! user's, which comes without a texture) in the material groups' colours of Fig. 2.
//!
//! The sheet's frames are centred on the opening, so that the zipper is shown: the opening
//! spans from the last frame before anything opens (a saliva element broken, or a column's
//! gap above the open threshold) to the first frame at which the broken elements and the open
//! fraction have both reached their largest of the run ([`opening_span`], from the run's
//! `measures.json`, or from the frames' `saliva_broken` where the measures do not match the
//! frames). A span of fewer than [`SHEET_FRAMES`] frames is widened to that many consecutive
//! frames about its middle (within the run); a longer one is sampled evenly, its first and
//! last frame included ([`sheet_frames`]). A run in which nothing opens is sampled evenly
//! from its first frame to its last.
//!
//! Cost: the preview should cost less than the simulation it shows. The frames needed are read
//! once each (the XML parsed once), and rendered in parallel, each frame by itself, so that
//! the bytes are the same on any number of threads; without the tissue's triangles that face
//! away from the camera ([`Quality::cull`]: the same pictures); the animation's 27 frames with
//! one sample a pixel (30 ms apart on the README's first command: 0.27 and 0.30 s in the
//! zipper), the sheet's panels with 2x2 (the paper's figures take 3x3); both files compressed
//! with the `png` crate's fast setting. On the README's first command (2026-12-04, 2-core AMD
//! EPYC, medians of 7 runs) that took the preview from 2.21 s (41 frames and 8 panels at 3x3
//! samples, flat colours, the default compression, each frame file parsed twice) to 0.40 s,
//! against 0.56 s for the run itself.

use crate::app::look::{
    element_codes, face_skin, makehuman_masks, render_with, Paint, Quality, BLUE, CAVITY, GREEN,
    RED, SKIN, WHITE,
};
use crate::error::{Error, Result};
use crate::render::{encode_apng, encode_png_fast, GridLabels, Image};
use crate::Problem;
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::path::Path;

pub const ANIMATION_FRAMES: usize = 27;
pub const SHEET_FRAMES: usize = 8;
/// Samples per pixel along each axis, in the animation's frames and the sheet's panels (the
/// paper's figures take 3).
const ANIMATION_SUPERSAMPLE: u32 = 1;
const SHEET_SUPERSAMPLE: u32 = 2;

/// `n` indices spread evenly over `0..len`, first and last included.
fn spread(len: usize, n: usize) -> Vec<usize> {
    if len <= n {
        return (0..len).collect();
    }
    let mut v: Vec<usize> = (0..n).map(|i| i * (len - 1) / (n - 1)).collect();
    v.dedup();
    v
}

/// The frames over which the mouth opens, from each frame's count of broken saliva elements
/// and open fraction: from the last frame before the first at which either is above zero, to
/// the first frame at which both are at their largest of the run. `None` when nothing opens.
pub fn opening_span(broken: &[usize], open: &[f64]) -> Option<(usize, usize)> {
    let len = broken.len().min(open.len());
    let first = (0..len).find(|&k| broken[k] > 0 || open[k] > 0.0)?;
    let most_broken = broken[..len].iter().copied().max().unwrap_or(0);
    let most_open = open[..len].iter().copied().fold(0.0, f64::max);
    let done = (first..len)
        .find(|&k| broken[k] >= most_broken && open[k] >= most_open)
        .unwrap_or(len - 1);
    Some((first.saturating_sub(1), done))
}

/// The contact sheet's `n` frames of a run of `len` frames, centred on the opening `span`
/// (see the module's description).
pub fn sheet_frames(len: usize, span: Option<(usize, usize)>, n: usize) -> Vec<usize> {
    let Some((a, b)) = span.filter(|&(a, b)| a <= b && b < len) else {
        return spread(len, n);
    };
    let count = b - a + 1;
    if count >= n {
        return spread(count, n).into_iter().map(|k| a + k).collect();
    }
    let n = n.min(len);
    let lo = a.saturating_sub((n - count) / 2).min(len - n);
    (lo..lo + n).collect()
}

/// The opening's span from the run's `measures.json` where it has a frame for each of the
/// run's frames at the same times; `None` where it has not (an interrupted run).
fn span_from_measures(dir: &Path, times: &[f64]) -> Option<Option<(usize, usize)>> {
    let m = crate::run_dir::RunDir::new(dir).measures().ok()?;
    let matches = m.frames.len() == times.len()
        && m.frames
            .iter()
            .zip(times)
            .all(|(f, t)| (f.time - t).abs() <= 1e-9 * t.abs().max(1.0));
    if !matches {
        return None;
    }
    let broken: Vec<usize> = m.frames.iter().map(|f| f.broken).collect();
    let open: Vec<f64> = m.frames.iter().map(|f| f.open_fraction).collect();
    Some(opening_span(&broken, &open))
}

/// One frame's displacement and broken saliva elements (none where the frame has no
/// `saliva_broken`), each frame file read once.
type Frame = (Vec<[f64; 3]>, Vec<bool>);

fn read_frame(p: &Problem, path: &Path) -> Result<Frame> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let name = path.display().to_string();
    let mut arrays = crate::io::vtu::parse_arrays(
        &text,
        &name,
        &[("PointData", "displacement"), ("CellData", "saliva_broken")],
    )?;
    let broken = arrays.pop().expect("two arrays");
    let (u, _, _) = arrays.pop().expect("two arrays")?;
    let u: Vec<[f64; 3]> = u.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    if u.len() != p.mesh.nodes.len() {
        return Err(Error::input(
            name,
            crate::error::Location::Field("displacement".into()),
            format!(
                "{} points for a model of {} nodes",
                u.len(),
                p.mesh.nodes.len()
            ),
        ));
    }
    let hidden = match broken {
        Ok((b, _, _)) => b.iter().map(|&x| x > 0.0).collect(),
        Err(_) => vec![],
    };
    Ok((u, hidden))
}

/// `f` of every item, in parallel, in order; the first error in order where there is one (so
/// that the message does not depend on the threads).
fn par_map<T: Sync, U: Send>(
    items: &[T],
    f: impl Fn(&T) -> Result<U> + Sync + Send,
) -> Result<Vec<U>> {
    items
        .par_iter()
        .map(f)
        .collect::<Vec<Result<U>>>()
        .into_iter()
        .collect()
}

/// Writes the preview of the run in `dir` (nothing for models without lips).
pub fn write(p: &Problem, dir: &Path) -> Result<()> {
    let Some(cols) = &p.physics.lip_columns else {
        return Ok(());
    };
    let entries = crate::run_dir::RunDir::new(dir).frames()?;
    let times: Vec<f64> = entries.iter().map(|e| e.0).collect();
    let read = |k: &usize| read_frame(p, &dir.join(&entries[*k].1));
    let anim_frames = spread(entries.len(), ANIMATION_FRAMES);
    // the sheet's frames: from the measures, else from every frame's broken elements
    let span = match span_from_measures(dir, &times) {
        Some(span) => span,
        None => {
            let all: Vec<usize> = (0..entries.len()).collect();
            let broken: Vec<usize> = par_map(&all, |k| {
                let path = dir.join(&entries[*k].1);
                Ok(
                    match crate::io::vtu::read_cell_data(&path, "saliva_broken") {
                        Ok((b, _, _)) => b.iter().filter(|&&x| x > 0.0).count(),
                        Err(_) => 0,
                    },
                )
            })?;
            opening_span(&broken, &vec![0.0; broken.len()])
        }
    };
    let sheet = sheet_frames(entries.len(), span, SHEET_FRAMES);
    // each frame needed read once (the texture made meanwhile)
    let needed: Vec<usize> = anim_frames
        .iter()
        .chain(&sheet)
        .copied()
        .collect::<std::collections::BTreeSet<_>>()
        .into_iter()
        .collect();
    let textured =
        p.mesh.uv.is_some() && p.physics.model.as_deref() == Some(crate::mesh::face::MAKEHUMAN);
    let (frames, skin) = rayon::join(
        || par_map(&needed, read),
        || {
            let (face, lips) = if textured {
                makehuman_masks()
            } else {
                (None, None)
            };
            Some(face_skin(&face?, &lips?))
        },
    );
    let frames: BTreeMap<usize, Frame> = needed.iter().copied().zip(frames?).collect();
    let codes = element_codes(p);
    let colour = |e: u32| [BLUE, RED, GREEN][codes[e as usize] as usize];
    let picture = |k: usize, w: u32, h: u32, ss: u32| -> Image {
        let (u, hidden) = &frames[&k];
        let (paint, background) = match &skin {
            Some(tex) => (Paint::Texture(tex), CAVITY),
            None => (Paint::Elements(&colour), WHITE),
        };
        let quality = Quality {
            supersample: ss,
            cull: true,
        };
        render_with(p, cols, u, hidden, paint, background, w, h, quality)
    };
    let (anim, panels) = rayon::join(
        || {
            anim_frames
                .par_iter()
                .map(|&k| picture(k, 360, 224, ANIMATION_SUPERSAMPLE))
                .collect::<Vec<Image>>()
        },
        || {
            sheet
                .par_iter()
                .map(|&k| {
                    let title = format!("t = {:.3} s", entries[k].0);
                    let labels = GridLabels {
                        title: Some(&title),
                        text_size: 16.0,
                        ..Default::default()
                    };
                    Image::grid_labelled(
                        &[picture(k, 420, 262, SHEET_SUPERSAMPLE)],
                        1,
                        2,
                        WHITE,
                        &labels,
                    )
                })
                .collect::<Vec<Image>>()
        },
    );
    let legend = match skin {
        Some(_) => Image::legend(
            &[
                ("skin and lips (the face's texture)", SKIN),
                ("behind the lips (broken saliva elements left out)", CAVITY),
            ],
            16.0,
            WHITE,
        ),
        None => Image::legend(
            &[
                ("upper face", BLUE),
                ("lower face", RED),
                ("saliva (broken elements left out)", GREEN),
            ],
            16.0,
            WHITE,
        ),
    };
    let sheet = Image::grid(&[Image::grid(&panels, 4, 8, WHITE), legend], 1, 6, WHITE);
    let delay = (4000 / anim.len().max(1)).clamp(40, 500) as u16;
    let (apng, sheet) = rayon::join(
        || encode_apng(&anim, delay).expect("frames of one size"),
        || encode_png_fast(&sheet),
    );
    for (name, bytes) in [("preview_sheet.png", sheet), ("preview.png", apng)] {
        let path = dir.join(name);
        crate::io::atomic::write_atomic(&path, &bytes).map_err(|e| Error::io(&path, e))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sheet_is_centred_on_the_opening() {
        // the README's first command: 81 frames, the first element broken at frame 27, all 20
        // at frame 30, every column open from frame 31
        let mut broken = vec![0usize; 81];
        let mut open = vec![0.0; 81];
        for (k, (b, o)) in [(6, 0.0), (12, 0.45), (16, 0.65), (20, 0.95)]
            .iter()
            .enumerate()
        {
            broken[27 + k] = *b;
            open[27 + k] = *o;
        }
        for k in 31..81 {
            broken[k] = 20;
            open[k] = 1.0;
        }
        let span = opening_span(&broken, &open);
        assert_eq!(span, Some((26, 31)));
        // six frames widened to eight about their middle: one before, one after
        assert_eq!(sheet_frames(81, span, 8), (25..33).collect::<Vec<usize>>());
        // near the run's start or end the eight stay within the run
        assert_eq!(
            sheet_frames(81, Some((0, 2)), 8),
            (0..8).collect::<Vec<_>>()
        );
        assert_eq!(
            sheet_frames(81, Some((78, 80)), 8),
            (73..81).collect::<Vec<_>>()
        );
        assert_eq!(sheet_frames(5, Some((1, 2)), 8), (0..5).collect::<Vec<_>>());
        // a long opening is sampled evenly, its ends included
        assert_eq!(
            sheet_frames(401, Some((100, 240)), 8),
            vec![100, 120, 140, 160, 180, 200, 220, 240]
        );
        // nothing opens: evenly over the run, as before
        assert_eq!(opening_span(&[0; 81], &[0.0; 81]), None);
        assert_eq!(
            sheet_frames(81, None, 8),
            vec![0, 11, 22, 34, 45, 57, 68, 80]
        );
        // broken elements only (no measures): the span ends when the last one breaks
        assert_eq!(opening_span(&broken, &vec![0.0; 81]), Some((26, 30)));
        // a mouth that never opens fully ends its span at its widest
        let partial: Vec<f64> = open.iter().map(|o| o * 0.5).collect();
        assert_eq!(opening_span(&broken, &partial), Some((26, 31)));
    }
}
