//! The preview every mouth or face run writes beside its frames, so that the result can be
//! looked at without ParaView: `preview.png`, an animated PNG of the mouth over the run (up
//! to [`ANIMATION_FRAMES`] frames, broken saliva elements left out so that the lips part),
//! and `preview_sheet.png`, a contact sheet of [`SHEET_FRAMES`] frames labelled with their
//! times. Rendered with the paper's mouth camera ([`crate::paper::look`]).

use crate::paper::look::{element_codes, render, Paint, BLUE, GREEN, RED, WHITE};
use std::path::Path;
use sticky_lips::error::{Error, Result};
use sticky_lips::render::{encode_apng, save_png, GridLabels, Image};
use sticky_lips::Problem;

pub const ANIMATION_FRAMES: usize = 41;
pub const SHEET_FRAMES: usize = 8;

/// `n` indices spread evenly over `0..len`, first and last included.
fn spread(len: usize, n: usize) -> Vec<usize> {
    if len <= n {
        return (0..len).collect();
    }
    let mut v: Vec<usize> = (0..n).map(|i| i * (len - 1) / (n - 1)).collect();
    v.dedup();
    v
}

/// Writes the preview of the run in `dir` (nothing for models without lips).
pub fn write(p: &Problem, dir: &Path) -> Result<()> {
    let Some(cols) = &p.physics.lip_columns else {
        return Ok(());
    };
    let entries = sticky_lips::export::read_pvd(dir)?;
    let codes = element_codes(p);
    let colour = |e: u32| [BLUE, RED, GREEN][codes[e as usize] as usize];
    let picture = |k: usize, w: u32, h: u32| -> Result<Image> {
        let path = dir.join(&entries[k].1);
        let (u, _, _) = sticky_lips::io::vtu::read_point_data_f64(&path, "displacement")?;
        let u: Vec<[f64; 3]> = u.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        if u.len() != p.mesh.nodes.len() {
            return Err(Error::input(
                path.display().to_string(),
                sticky_lips::error::Location::Field("displacement".into()),
                format!(
                    "{} points for a model of {} nodes",
                    u.len(),
                    p.mesh.nodes.len()
                ),
            ));
        }
        let hidden: Vec<bool> = match sticky_lips::io::vtu::read_cell_data(&path, "saliva_broken") {
            Ok((b, _, _)) => b.iter().map(|&x| x > 0.0).collect(),
            Err(_) => vec![],
        };
        Ok(render(
            p,
            cols,
            &u,
            &hidden,
            Paint::Elements(&colour),
            WHITE,
            w,
            h,
        ))
    };
    let mut anim = Vec::new();
    for k in spread(entries.len(), ANIMATION_FRAMES) {
        anim.push(picture(k, 360, 224)?);
    }
    let delay = (4000 / anim.len().max(1)).clamp(40, 500) as u16;
    let apng = encode_apng(&anim, delay).expect("frames of one size");
    let path = dir.join("preview.png");
    sticky_lips::io::atomic::write_atomic(&path, &apng).map_err(|e| Error::io(&path, e))?;
    let mut panels = Vec::new();
    for k in spread(entries.len(), SHEET_FRAMES) {
        let title = format!("t = {:.3} s", entries[k].0);
        let labels = GridLabels {
            title: Some(&title),
            text_size: 16.0,
            ..Default::default()
        };
        panels.push(Image::grid_labelled(
            &[picture(k, 420, 262)?],
            1,
            2,
            WHITE,
            &labels,
        ));
    }
    let legend = Image::legend(
        &[
            ("upper face", BLUE),
            ("lower face", RED),
            ("saliva (broken elements left out)", GREEN),
        ],
        16.0,
        WHITE,
    );
    let sheet = Image::grid(&[Image::grid(&panels, 4, 8, WHITE), legend], 1, 6, WHITE);
    save_png(&dir.join("preview_sheet.png"), &sheet)
}
