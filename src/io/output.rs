//! Run outputs: one VTU per output frame, a `.pvd` collection rewritten after every frame
//! (so it only ever lists complete frames), `final.vtu` and `summary.json`. Every file is
//! written atomically (temporary file, then rename).
//!
//! Point positions in the VTU files are the deformed configuration `X + u` (ParaView
//! animates the `.pvd` directly); point data `displacement` is `u` in metres; cell data
//! `material` is the material index and `volume_ratio` is `J = det F`; with saliva elements,
//! also `saliva_moisture` (um), `saliva_Z`, `saliva_Q`, `saliva_broken` (1/0, -1 for tissue)
//! and `saliva_broken_at` (s; NaN for never and for tissue elements). Node and element
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
    last: Option<(f64, Vec<[f64; 3]>, Option<SalivaFrame>)>,
}

/// The saliva elements' state at a frame, in saliva-element order (see `SalivaPlan`).
#[derive(Clone, Debug)]
pub struct SalivaFrame {
    pub moisture: Vec<f64>,
    pub z: Vec<f64>,
    pub q: Vec<f64>,
    pub broken: Vec<bool>,
    pub broken_at: Vec<f64>,
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
        saliva: Option<&SalivaFrame>,
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
        let ne = disc.num_elements();
        let spread = |v: &[f64]| {
            let mut out = vec![f64::NAN; ne];
            for (k, &e) in disc.saliva.elements.iter().enumerate() {
                out[e as usize] = v[k];
            }
            out
        };
        let (moisture, z, q, broken_at, broken) = match saliva {
            Some(s) => {
                let mut b = vec![-1i32; ne];
                for (k, &e) in disc.saliva.elements.iter().enumerate() {
                    b[e as usize] = s.broken[k] as i32;
                }
                (
                    spread(&s.moisture),
                    spread(&s.z),
                    spread(&s.q),
                    spread(&s.broken_at),
                    b,
                )
            }
            None => Default::default(),
        };
        let f64_cell = |name, data| DataArray::F64 {
            name,
            components: 1,
            data,
        };
        let mut cell_data = vec![
            DataArray::I32 {
                name: "material",
                components: 1,
                data: &self.material,
            },
            f64_cell("volume_ratio", &j),
        ];
        if saliva.is_some() {
            cell_data.extend([
                f64_cell("saliva_moisture", &moisture),
                f64_cell("saliva_Z", &z),
                f64_cell("saliva_Q", &q),
                DataArray::I32 {
                    name: "saliva_broken",
                    components: 1,
                    data: &broken,
                },
                f64_cell("saliva_broken_at", &broken_at),
            ]);
        }
        let frame = VtuFrame {
            points: &points,
            hexahedra: &self.elements,
            point_data: vec![DataArray::F64 {
                name: "displacement",
                components: 3,
                data: &disp,
            }],
            cell_data,
            time: Some(time),
        };
        write_vtu(path, &frame).map_err(|e| Error::io(path, e))
    }

    /// Writes `frame_NNNNNN.vtu` for displacement `u` at `time`, then the updated `.pvd`.
    pub fn frame(
        &mut self,
        time: f64,
        u: &[[f64; 3]],
        disc: &Discretisation,
        saliva: Option<SalivaFrame>,
    ) -> Result<()> {
        let name = format!("frame_{:06}.vtu", self.entries.len());
        self.write_file(&self.dir.join(&name), time, u, disc, saliva.as_ref())?;
        self.entries.push(PvdEntry { time, file: name });
        let pvd = self.dir.join("frames.pvd");
        write_pvd(&pvd, &self.entries).map_err(|e| Error::io(&pvd, e))?;
        self.last = Some((time, u.to_vec(), saliva));
        Ok(())
    }

    /// Writes `final.vtu` (the last frame) and `summary.json`.
    pub fn finish<S: serde::Serialize>(&self, disc: &Discretisation, summary: &S) -> Result<()> {
        if let Some((t, u, s)) = &self.last {
            self.write_file(&self.dir.join("final.vtu"), *t, u, disc, s.as_ref())?;
        }
        let path = self.dir.join("summary.json");
        let json = serde_json::to_vec_pretty(summary).expect("summary serialises");
        write_atomic(&path, &json).map_err(|e| Error::io(&path, e))
    }
}
