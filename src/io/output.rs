//! Run outputs: one VTU per output frame, a `.pvd` collection rewritten after every frame
//! (so it only ever lists complete frames), `final.vtu` and `summary.json`. Every file is
//! written atomically (temporary file, then rename).
//!
//! Point positions in the VTU files are the deformed configuration `X + u` (ParaView
//! animates the `.pvd` directly); point data `displacement` is `u` in metres; cell data
//! `material` is the material index and `volume_ratio` is `J = det F`. Node and element
//! numbering is the input's.

use crate::error::{Error, Result};
use crate::io::atomic::write_atomic;
use crate::io::vtu::{write_pvd, write_vtu, DataArray, PvdEntry, VtuFrame};
use crate::tled::precompute::Discretisation;
use crate::tled::solver::displacement_gradient;
use std::path::{Path, PathBuf};

/// Writes the frames of one run into a directory.
pub struct FrameWriter {
    dir: PathBuf,
    reference: Vec<[f64; 3]>,
    elements: Vec<[u32; 8]>,
    material: Vec<i32>,
    entries: Vec<PvdEntry>,
    last: Option<(f64, Vec<[f64; 3]>)>,
}

impl FrameWriter {
    /// Creates `dir` and removes frames left there by an earlier run.
    pub fn new(
        dir: &Path,
        reference: &[[f64; 3]],
        elements: &[[u32; 8]],
        material: &[u32],
    ) -> Result<Self> {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        for entry in std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
            let entry = entry.map_err(|e| Error::io(dir, e))?;
            let name = entry.file_name().to_string_lossy().to_string();
            let stale = (name.starts_with("frame_") && name.ends_with(".vtu"))
                || name == "frames.pvd"
                || name == "final.vtu"
                || name == "summary.json";
            if stale {
                std::fs::remove_file(entry.path()).map_err(|e| Error::io(entry.path(), e))?;
            }
        }
        Ok(FrameWriter {
            dir: dir.to_path_buf(),
            reference: reference.to_vec(),
            elements: elements.to_vec(),
            material: material.iter().map(|&m| m as i32).collect(),
            entries: Vec::new(),
            last: None,
        })
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }
    pub fn frames_written(&self) -> usize {
        self.entries.len()
    }

    fn write_file(
        &self,
        path: &Path,
        time: f64,
        u: &[[f64; 3]],
        disc: &Discretisation,
    ) -> Result<()> {
        let points: Vec<[f64; 3]> = self
            .reference
            .iter()
            .zip(u)
            .map(|(x, d)| [x[0] + d[0], x[1] + d[1], x[2] + d[2]])
            .collect();
        let disp: Vec<f64> = u.iter().flatten().copied().collect();
        let j: Vec<f64> = (0..disc.num_elements())
            .map(|e| {
                1.0 + crate::linalg::det_identity_plus_minus_one(&displacement_gradient(disc, u, e))
            })
            .collect();
        let frame = VtuFrame {
            points: &points,
            hexahedra: &self.elements,
            point_data: vec![DataArray::F64 {
                name: "displacement",
                components: 3,
                data: &disp,
            }],
            cell_data: vec![
                DataArray::I32 {
                    name: "material",
                    components: 1,
                    data: &self.material,
                },
                DataArray::F64 {
                    name: "volume_ratio",
                    components: 1,
                    data: &j,
                },
            ],
            time: Some(time),
        };
        write_vtu(path, &frame).map_err(|e| Error::io(path, e))
    }

    /// Writes `frame_NNNNNN.vtu` for displacement `u` at `time`, then the updated `.pvd`.
    pub fn frame(&mut self, time: f64, u: &[[f64; 3]], disc: &Discretisation) -> Result<()> {
        let name = format!("frame_{:06}.vtu", self.entries.len());
        self.write_file(&self.dir.join(&name), time, u, disc)?;
        self.entries.push(PvdEntry { time, file: name });
        let pvd = self.dir.join("frames.pvd");
        write_pvd(&pvd, &self.entries).map_err(|e| Error::io(&pvd, e))?;
        self.last = Some((time, u.to_vec()));
        Ok(())
    }

    /// Writes `final.vtu` (the last frame) and `summary.json`.
    pub fn finish<S: serde::Serialize>(&self, disc: &Discretisation, summary: &S) -> Result<()> {
        if let Some((t, u)) = &self.last {
            self.write_file(&self.dir.join("final.vtu"), *t, u, disc)?;
        }
        let path = self.dir.join("summary.json");
        let json = serde_json::to_vec_pretty(summary).expect("summary serialises");
        write_atomic(&path, &json).map_err(|e| Error::io(&path, e))
    }
}
