//! Run outputs: one VTU per output frame, a `.pvd` collection rewritten after every frame
//! (so it only ever lists complete frames), `final.vtu` (a copy of the last frame) and
//! `summary.json`. Every file is written atomically (temporary file, then rename), on a
//! writer thread of its own so that the time stepping does not wait for the disk.
//!
//! Point positions in the VTU files are the deformed configuration `X + u` (ParaView
//! animates the `.pvd` directly); point data `displacement` is `u` in metres; cell data
//! `material` is the material index and `volume_ratio` is `J = det F`; with saliva elements,
//! also `saliva_moisture` (um), `saliva_Z`, `saliva_Q`, `saliva_broken` (1/0, -1 for tissue)
//! and `saliva_broken_at` (s; NaN for never and for tissue elements). Node and element
//! numbering is the input's.

use crate::error::{Error, Result};
use crate::io::atomic::write_atomic;
use crate::io::vtu::{cells_xml, write_pvd, write_vtu_with_cells, DataArray, PvdEntry, VtuFrame};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{sync_channel, SyncSender};
use std::sync::Arc;
use std::thread::JoinHandle;

/// `summary.json`: what the run did (written last; an interrupted run's says where it stopped).
pub const SUMMARY: &str = "summary.json";
/// The ParaView collection listing the complete frames with their times.
pub const PVD: &str = "frames.pvd";
/// The solver's state for a restart ([`crate::io::checkpoint`]).
pub const CHECKPOINT: &str = "checkpoint.bin";
/// A copy of the last frame of a finished run.
pub const FINAL: &str = "final.vtu";

/// The file name of output frame `k`.
pub fn frame_file(k: usize) -> String {
    format!("frame_{k:06}.vtu")
}

/// The energies at each output frame: `summary.json`'s `energy`, and the part of a
/// checkpoint's history ([`crate::io::checkpoint::RunHistory`]) that a restart continues.
/// Defined here, below the driver, so that the checkpoint need not import the driver (which
/// re-exports it as `driver::EnergySeries`).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct EnergySeries {
    /// Simulated time of each frame (s).
    pub time: Vec<f64>,
    /// Kinetic energy (J).
    pub kinetic: Vec<f64>,
    /// Strain energy (J).
    pub strain: Vec<f64>,
}

/// What one frame holds, in `f64`, computed by the caller from the solver's state.
#[derive(Clone, Debug)]
pub struct Frame {
    /// Simulated time (s).
    pub time: f64,
    /// Nodal displacements (m), input node order.
    pub u: Vec<[f64; 3]>,
    /// `J = det F` per element, input element order.
    pub volume_ratio: Vec<f64>,
    /// The saliva elements' state, when the model has any.
    pub saliva: Option<SalivaFrame>,
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

/// The model's fixed data every frame file repeats.
struct Model {
    reference: Vec<[f64; 3]>,
    elements: Vec<[u32; 8]>,
    material: Vec<i32>,
    /// Element index of each saliva element, in saliva-element order.
    saliva_elements: Vec<u32>,
    /// The files' `<Cells>` element, encoded once (a third of a frame's bytes).
    cells: Vec<u8>,
}

/// Work for the writer thread, done in the order handed over.
enum Job {
    /// A frame: the file, its data, and the `.pvd` listing it.
    Frame {
        path: PathBuf,
        frame: Frame,
        pvd: Vec<PvdEntry>,
    },
    /// A checkpoint (`io::checkpoint`), written after every frame handed over before it, so
    /// that the frames it lists are on disk when it is.
    Checkpoint { path: PathBuf, bytes: Vec<u8> },
}

/// Writes the frames of one run into a directory.
///
/// The files are encoded and written on a writer thread, so that the stepping goes on while
/// a frame is written; at most one frame waits in the queue. The order of the files and
/// their bytes do not depend on this: each frame file is complete (written atomically)
/// before the `.pvd` that lists it. An error of the writer thread is reported by the next
/// [`FrameWriter::frame`] or by [`FrameWriter::finish`]; dropping the writer (e.g. when a
/// run stops with an error) waits for the frames already handed over.
pub struct FrameWriter {
    dir: PathBuf,
    model: Arc<Model>,
    entries: Vec<PvdEntry>,
    /// File name of the last frame (copied to `final.vtu` by `finish`).
    last: Option<String>,
    worker: Option<(SyncSender<Job>, JoinHandle<Result<()>>)>,
}

impl FrameWriter {
    /// Creates `dir` and removes frames left there by an earlier run. `saliva_elements` is
    /// the element index of each saliva element (empty without saliva).
    pub fn new(
        dir: &Path,
        reference: &[[f64; 3]],
        elements: &[[u32; 8]],
        material: &[u32],
        saliva_elements: &[u32],
    ) -> Result<Self> {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        remove_stale(dir, &[])?;
        Self::start(
            dir,
            reference,
            elements,
            material,
            saliva_elements,
            Vec::new(),
        )
    }

    /// Goes on with the frames of a run restarted from a checkpoint: `frames` (those the
    /// checkpoint lists) must be in `dir` and stay; every other output of ours (frames
    /// written after the checkpoint, `final.vtu`, `summary.json`, temporary files) is
    /// removed, and `frames.pvd` lists `frames` again. The checkpoint itself stays until a
    /// newer one replaces it.
    pub fn resume(
        dir: &Path,
        reference: &[[f64; 3]],
        elements: &[[u32; 8]],
        material: &[u32],
        saliva_elements: &[u32],
        frames: Vec<PvdEntry>,
    ) -> Result<Self> {
        let keep: Vec<&str> = frames.iter().map(|e| e.file.as_str()).collect();
        for f in &keep {
            let p = dir.join(f);
            if !p.is_file() {
                return Err(Error::io(
                    &p,
                    std::io::Error::other(
                        "a frame the checkpoint lists is missing; the run cannot be continued",
                    ),
                ));
            }
        }
        let mut keep_all = keep.clone();
        keep_all.push(CHECKPOINT);
        remove_stale(dir, &keep_all)?;
        let pvd = dir.join(PVD);
        if frames.is_empty() {
            let _ = std::fs::remove_file(&pvd);
        } else {
            write_pvd(&pvd, &frames).map_err(|e| Error::io(&pvd, e))?;
        }
        Self::start(dir, reference, elements, material, saliva_elements, frames)
    }

    fn start(
        dir: &Path,
        reference: &[[f64; 3]],
        elements: &[[u32; 8]],
        material: &[u32],
        saliva_elements: &[u32],
        entries: Vec<PvdEntry>,
    ) -> Result<Self> {
        let model = Arc::new(Model {
            reference: reference.to_vec(),
            elements: elements.to_vec(),
            material: material.iter().map(|&m| m as i32).collect(),
            saliva_elements: saliva_elements.to_vec(),
            cells: cells_xml(elements).map_err(|e| Error::io(dir, e))?,
        });
        let (tx, rx) = sync_channel::<Job>(1);
        let m = Arc::clone(&model);
        let handle = std::thread::Builder::new()
            .name("frame-writer".into())
            .spawn(move || -> Result<()> {
                for job in rx {
                    match job {
                        Job::Frame { path, frame, pvd } => {
                            write_frame_file(&m, &path, &frame)?;
                            let p = path.with_file_name(PVD);
                            write_pvd(&p, &pvd).map_err(|e| Error::io(&p, e))?;
                        }
                        Job::Checkpoint { path, bytes } => {
                            write_atomic(&path, &bytes).map_err(|e| Error::io(&path, e))?;
                        }
                    }
                }
                Ok(())
            })
            .map_err(|e| Error::io(dir, e))?;
        Ok(FrameWriter {
            dir: dir.to_path_buf(),
            model,
            last: entries.last().map(|e| e.file.clone()),
            entries,
            worker: Some((tx, handle)),
        })
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }
    pub fn frames_written(&self) -> usize {
        self.entries.len()
    }

    /// Hands `frame_NNNNNN.vtu` and the updated `.pvd` to the writer thread.
    pub fn frame(&mut self, frame: Frame) -> Result<()> {
        self.check_lengths(&frame)?;
        let name = frame_file(self.entries.len());
        self.entries.push(PvdEntry {
            time: frame.time,
            file: name.clone(),
        });
        let job = Job::Frame {
            path: self.dir.join(&name),
            frame,
            pvd: self.entries.clone(),
        };
        self.send(job)?;
        self.last = Some(name);
        Ok(())
    }

    /// The frames listed so far (time, file name), in order.
    pub fn entries(&self) -> &[PvdEntry] {
        &self.entries
    }

    /// Hands a checkpoint's bytes to the writer thread: written atomically as
    /// `checkpoint.bin` once the frames handed over before it are on disk.
    pub fn checkpoint(&mut self, bytes: Vec<u8>) -> Result<()> {
        let path = self.dir.join(CHECKPOINT);
        self.send(Job::Checkpoint { path, bytes })
    }

    fn send(&mut self, job: Job) -> Result<()> {
        let sent = match &self.worker {
            Some((tx, _)) => tx.send(job).is_ok(),
            None => false,
        };
        if !sent {
            // The writer thread stopped: its error says why.
            self.join()?;
            return Err(Error::io(
                &self.dir,
                std::io::Error::other("the frame writer thread has stopped"),
            ));
        }
        Ok(())
    }

    fn check_lengths(&self, f: &Frame) -> Result<()> {
        let m = &self.model;
        let ok = f.u.len() == m.reference.len()
            && f.volume_ratio.len() == m.elements.len()
            && f.saliva.as_ref().is_none_or(|s| {
                let n = m.saliva_elements.len();
                [
                    s.moisture.len(),
                    s.z.len(),
                    s.q.len(),
                    s.broken.len(),
                    s.broken_at.len(),
                ]
                .iter()
                .all(|&l| l == n)
            });
        if ok {
            Ok(())
        } else {
            Err(Error::io(
                &self.dir,
                std::io::Error::other(
                    "frame data does not match the model (nodes, elements or saliva elements)",
                ),
            ))
        }
    }

    /// Waits for every frame handed over to be on disk (no more frames can be written after).
    pub fn flush(&mut self) -> Result<()> {
        self.join()
    }

    /// Waits for the writer thread to write every frame handed over; its error, if any.
    fn join(&mut self) -> Result<()> {
        match self.worker.take() {
            Some((tx, handle)) => {
                drop(tx);
                match handle.join() {
                    Ok(r) => r,
                    Err(_) => Err(Error::io(
                        &self.dir,
                        std::io::Error::other("the frame writer thread panicked"),
                    )),
                }
            }
            None => Ok(()),
        }
    }

    /// Waits for the frames, then writes `final.vtu` (a copy of the last frame) and
    /// `summary.json`.
    pub fn finish<S: serde::Serialize>(mut self, summary: &S) -> Result<()> {
        self.join()?;
        if let Some(name) = &self.last {
            let from = self.dir.join(name);
            let bytes = std::fs::read(&from).map_err(|e| Error::io(&from, e))?;
            let to = self.dir.join(FINAL);
            write_atomic(&to, &bytes).map_err(|e| Error::io(&to, e))?;
        }
        let path = self.dir.join(SUMMARY);
        let json = serde_json::to_vec_pretty(summary).expect("summary serialises");
        write_atomic(&path, &json).map_err(|e| Error::io(&path, e))
    }
}

impl FrameWriter {
    /// Waits for the frames handed over, then writes `summary.json` only: an interrupted run
    /// has no final state, so no `final.vtu`.
    pub fn finish_interrupted<S: serde::Serialize>(mut self, summary: &S) -> Result<()> {
        self.join()?;
        let path = self.dir.join(SUMMARY);
        let json = serde_json::to_vec_pretty(summary).expect("summary serialises");
        write_atomic(&path, &json).map_err(|e| Error::io(&path, e))
    }
}

impl Drop for FrameWriter {
    fn drop(&mut self) {
        // The frames handed over are written; an error is reported by frame() or finish().
        let _ = self.join();
    }
}

/// Removes the outputs of an earlier run from `dir` (ours and our temporary files), except
/// the files named in `keep`.
fn remove_stale(dir: &Path, keep: &[&str]) -> Result<()> {
    for entry in std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
        let entry = entry.map_err(|e| Error::io(dir, e))?;
        let name = entry.file_name().to_string_lossy().to_string();
        let stale = is_ours(&name) || is_our_temporary(&name);
        if stale && !keep.contains(&name.as_str()) {
            std::fs::remove_file(entry.path()).map_err(|e| Error::io(entry.path(), e))?;
        }
    }
    Ok(())
}

/// A file of a run's output that a new run into the same directory replaces.
fn is_ours(name: &str) -> bool {
    (name.starts_with("frame_") && name.ends_with(".vtu"))
        || ["frames.pvd", "final.vtu", "summary.json", CHECKPOINT].contains(&name)
        || crate::export::FILES.contains(&name)
}

/// A temporary file of `io::atomic` (`.NAME.tmp-PID`) for one of our outputs, left behind by
/// a run that was killed while writing it.
fn is_our_temporary(name: &str) -> bool {
    let Some(rest) = name.strip_prefix('.') else {
        return false;
    };
    let Some((base, pid)) = rest.rsplit_once(".tmp-") else {
        return false;
    };
    let ours = is_ours(base)
        || ["measures.json", "gap.csv", "series.csv", "scenario.toml"].contains(&base);
    ours && !pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit())
}

/// Encodes one frame as a VTU file at `path` (atomically).
fn write_frame_file(m: &Model, path: &Path, f: &Frame) -> Result<()> {
    let points: Vec<[f64; 3]> = m
        .reference
        .iter()
        .zip(&f.u)
        .map(|(x, d)| [x[0] + d[0], x[1] + d[1], x[2] + d[2]])
        .collect();
    let disp: Vec<f64> = f.u.iter().flatten().copied().collect();
    let ne = m.elements.len();
    let spread = |v: &[f64]| {
        let mut out = vec![f64::NAN; ne];
        for (k, &e) in m.saliva_elements.iter().enumerate() {
            out[e as usize] = v[k];
        }
        out
    };
    let (moisture, z, q, broken_at, broken) = match &f.saliva {
        Some(s) => {
            let mut b = vec![-1i32; ne];
            for (k, &e) in m.saliva_elements.iter().enumerate() {
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
            data: &m.material,
        },
        f64_cell("volume_ratio", &f.volume_ratio),
    ];
    if f.saliva.is_some() {
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
        hexahedra: &m.elements,
        point_data: vec![DataArray::F64 {
            name: "displacement",
            components: 3,
            data: &disp,
        }],
        cell_data,
        time: Some(f.time),
    };
    write_vtu_with_cells(path, &frame, &m.cells).map_err(|e| Error::io(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(tag: &str) -> PathBuf {
        let d =
            std::env::temp_dir().join(format!("sticky_lips_output_{tag}_{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        d
    }

    /// One hexahedron, the unit cube.
    fn cube() -> (Vec<[f64; 3]>, Vec<[u32; 8]>) {
        let x: Vec<[f64; 3]> = (0..8)
            .map(|k| [(k & 1) as f64, ((k >> 1) & 1) as f64, ((k >> 2) & 1) as f64])
            .collect();
        (x, vec![[0, 1, 3, 2, 4, 5, 7, 6]])
    }

    fn frame(t: f64) -> Frame {
        Frame {
            time: t,
            u: vec![[t, 0.0, 0.0]; 8],
            volume_ratio: vec![1.0],
            saliva: None,
        }
    }

    fn names(d: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn frames_in_order_and_final_is_the_last() {
        let d = scratch("order");
        let (x, el) = cube();
        let mut w = FrameWriter::new(&d, &x, &el, &[0], &[]).unwrap();
        for k in 0..5 {
            w.frame(frame(k as f64 * 0.1)).unwrap();
        }
        assert_eq!(w.frames_written(), 5);
        w.finish(&serde_json::json!({"ok": true})).unwrap();
        let expected: Vec<PvdEntry> = (0..5)
            .map(|k| PvdEntry {
                time: k as f64 * 0.1,
                file: format!("frame_{k:06}.vtu"),
            })
            .collect();
        let pvd = std::fs::read_to_string(d.join("frames.pvd")).unwrap();
        assert_eq!(pvd, crate::io::vtu::pvd_string(&expected).unwrap());
        assert_eq!(
            std::fs::read(d.join("final.vtu")).unwrap(),
            std::fs::read(d.join("frame_000004.vtu")).unwrap()
        );
        assert!(names(&d).iter().all(|n| !n.contains(".tmp-")));
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn dropping_the_writer_leaves_every_frame_handed_over() {
        let d = scratch("drop");
        let (x, el) = cube();
        let mut w = FrameWriter::new(&d, &x, &el, &[0], &[]).unwrap();
        for k in 0..3 {
            w.frame(frame(k as f64)).unwrap();
        }
        drop(w); // as when a run stops with an error
        assert_eq!(
            names(&d),
            [
                "frame_000000.vtu",
                "frame_000001.vtu",
                "frame_000002.vtu",
                "frames.pvd"
            ]
        );
        let pvd = std::fs::read_to_string(d.join("frames.pvd")).unwrap();
        assert_eq!(pvd.matches("<DataSet").count(), 3, "{pvd}");
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn a_write_error_names_the_file() {
        let d = scratch("error");
        let (x, el) = cube();
        let mut w = FrameWriter::new(&d, &x, &el, &[0], &[]).unwrap();
        std::fs::remove_dir_all(&d).unwrap(); // the directory goes away under the run
        let mut err = None;
        for k in 0..3 {
            if let Err(e) = w.frame(frame(k as f64)) {
                err = Some(e);
                break;
            }
        }
        let e = match err {
            Some(e) => e,
            None => w.finish(&serde_json::json!({})).unwrap_err(),
        };
        let text = e.to_string();
        assert!(text.contains("frame_00000"), "{text}");
    }

    #[test]
    fn stale_temporaries_of_ours_are_recognised() {
        for n in [
            ".frame_000003.vtu.tmp-4242",
            ".frames.pvd.tmp-7",
            ".summary.json.tmp-1",
        ] {
            assert!(is_our_temporary(n), "{n}");
        }
        for n in [
            ".frame_000003.vtu.tmp-",
            ".notes.txt.tmp-12",
            "frame_000003.vtu.tmp-1",
            ".frames.pvd.tmp-x1",
        ] {
            assert!(!is_our_temporary(n), "{n}");
        }
        let d = scratch("stale");
        std::fs::create_dir_all(&d).unwrap();
        for n in [
            ".frame_000009.vtu.tmp-99999",
            ".frames.pvd.tmp-99999",
            "notes.txt",
        ] {
            std::fs::write(d.join(n), b"x").unwrap();
        }
        let (x, el) = cube();
        let w = FrameWriter::new(&d, &x, &el, &[0], &[]).unwrap();
        drop(w);
        assert_eq!(names(&d), ["notes.txt"]);
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn data_that_does_not_fit_the_model_is_refused() {
        let d = scratch("lengths");
        let (x, el) = cube();
        let mut w = FrameWriter::new(&d, &x, &el, &[0], &[]).unwrap();
        let mut f = frame(0.0);
        f.u.pop();
        assert!(w.frame(f).is_err());
        let mut f = frame(0.0);
        f.volume_ratio.push(1.0);
        assert!(w.frame(f).is_err());
        assert_eq!(w.frames_written(), 0);
        drop(w);
        std::fs::remove_dir_all(&d).unwrap();
    }
}
