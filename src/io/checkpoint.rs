//! Checkpoints of a CPU run (`run --checkpoint-every N`, `run --restart DIR`).
//!
//! A checkpoint holds everything a run needs to go on as if it had never stopped: the
//! solver's state at one step ([`SolverState`]: the displacements at that step and the one
//! before, the saliva elements' previous forces, broken flags and last values), the driver's
//! history (energies, broken counts, lip measures, the frames listed so far) and what it must
//! match (the scenario's hash, the precision, the sizes). Frames written after a checkpoint
//! are written again by the restarted run, with the same bytes.
//!
//! File layout (`checkpoint.bin`, little-endian):
//!
//! | bytes | content |
//! |---|---|
//! | 16 | magic `STICKYLIPS-CKPT1` |
//! | 8 | length `h` of the header (u64) |
//! | h | header, JSON ([`Header`]) |
//! | 8 x n | the solver state's numbers as `f64` bits, in [`SolverState::numbers`] order |
//! | s | one byte (0/1) per saliva element: broken |
//! | 32 | SHA-256 of every byte before it |
//!
//! An `f32` run's values are stored as `f64`, which is exact both ways. The file is written
//! atomically (`io::atomic`), so a run killed at any moment leaves the previous checkpoint
//! or the new one, never a mixture; the checksum catches a file damaged afterwards.

use crate::error::{Error, Location, Result};
use crate::io::output::EnergySeries;
use crate::io::vtu::PvdEntry;
use crate::measures::RunMeasures;
use crate::problem::Problem;
pub use crate::tled::solver::SolverState;
use sha2::{Digest, Sha256};
use std::path::Path;

/// The checkpoint's file name in a run's output directory (the frame writer's, which keeps
/// it through a restart).
pub use crate::io::output::CHECKPOINT as FILE_NAME;
const MAGIC: &[u8; 16] = b"STICKYLIPS-CKPT1";
/// Version of the layout above and of [`Header`]; a file of another version is refused.
pub const FORMAT: u32 = 1;

/// What the driver has recorded up to the checkpoint's step.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RunHistory {
    pub energy: EnergySeries,
    pub broken_saliva: Vec<usize>,
    pub measures: Option<RunMeasures>,
    /// The frames listed in `frames.pvd` so far: (time, file name).
    pub frames: Vec<(f64, String)>,
    /// Seconds spent stepping before the checkpoint (for the summary's rates).
    pub stepping_time: f64,
    /// [`displacement_hash`] of the last frame listed: a restart checks it against that
    /// frame's file, so that a checkpoint moved into another run's directory is refused
    /// instead of continuing its own run among the other's frames (absent in checkpoints
    /// written before it was added: not checked; not written when absent, so that such a
    /// checkpoint re-encodes to its own bytes).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub last_frame_hash: Option<String>,
}

/// SHA-256 (hex) of the bits of a frame's displacements, as written to its `displacement`
/// array (`f64`).
pub fn displacement_hash(u: &[f64]) -> String {
    let mut h = Sha256::new();
    for x in u {
        h.update(x.to_bits().to_le_bytes());
    }
    hex(&h.finalize())
}

/// Refuses a checkpoint whose history's last frame is not the file of that name in `dir`
/// (the directory's own run wrote other displacements there).
pub fn check_frames(path: &Path, header: &Header, dir: &Path) -> Result<()> {
    let (Some(want), Some((_, file))) = (
        &header.history.last_frame_hash,
        header.history.frames.last(),
    ) else {
        return Ok(());
    };
    let frame = dir.join(file);
    let (u, _, _) = crate::io::vtu::read_point_data_f64(&frame, "displacement")?;
    if displacement_hash(&u) != *want {
        return Err(bad(
            path,
            format!(
                "belongs to another run: the last frame it lists, {}, holds other displacements \
                 than the checkpoint's run wrote (was the checkpoint copied from another run's \
                 directory?); restart that run in its own directory, or remove {FILE_NAME} and \
                 run from the start",
                frame.display()
            ),
        ));
    }
    Ok(())
}

impl RunHistory {
    pub fn pvd_entries(&self) -> Vec<PvdEntry> {
        self.frames
            .iter()
            .map(|(time, file)| PvdEntry {
                time: *time,
                file: file.clone(),
            })
            .collect()
    }
}

/// The JSON header of a checkpoint.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Header {
    pub format: u32,
    /// `f32` or `f64`.
    pub precision: String,
    /// [`problem_hash`] of the problem the run solves.
    pub problem_hash: String,
    /// The input file of the run (as given), for messages and for `run --restart` without one.
    pub input: String,
    pub step: usize,
    pub num_nodes: usize,
    pub num_saliva: usize,
    pub history: RunHistory,
}

/// SHA-256 (hex) of the problem a run solves: its mesh, materials, boundary conditions,
/// loads, time settings, numerics and physics, everything but the input's file name (so a
/// scenario moved to another directory still matches). Two problems with the same hash give
/// the same steps.
pub fn problem_hash(problem: &Problem) -> String {
    let mut p = problem.clone();
    p.source.clear();
    // `Debug` prints every f64 as its shortest round-trip decimal: equal text, equal bits
    let text = format!("format {FORMAT}\n{p:?}");
    hex(&Sha256::digest(text.as_bytes()))
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// Encodes a checkpoint (see the module's table).
pub fn encode(header: &Header, state: &SolverState) -> Vec<u8> {
    let json = serde_json::to_vec(header).expect("checkpoint header serialises");
    let mut out = Vec::with_capacity(64 + json.len() + 8 * (6 * state.u.len()));
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&(json.len() as u64).to_le_bytes());
    out.extend_from_slice(&json);
    for x in state.numbers() {
        out.extend_from_slice(&x.to_bits().to_le_bytes());
    }
    out.extend(state.broken.iter().map(|&b| b as u8));
    let sum = Sha256::digest(&out);
    out.extend_from_slice(&sum);
    out
}

fn bad(path: &Path, message: impl Into<String>) -> Error {
    Error::input(path.display().to_string(), Location::None, message)
}

/// Reads and checks a checkpoint file: magic, checksum, header, sizes.
pub fn read(path: &Path) -> Result<(Header, SolverState)> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    decode(&bytes).map_err(|m| bad(path, m))
}

/// Decodes the bytes of a checkpoint file (see the module's table); the message says what is wrong.
pub fn decode(bytes: &[u8]) -> std::result::Result<(Header, SolverState), String> {
    if bytes.len() < MAGIC.len() + 8 + 32 || &bytes[..MAGIC.len()] != MAGIC {
        return Err("not a sticky-lips checkpoint (no STICKYLIPS-CKPT1 at its start)".into());
    }
    let (body, sum) = bytes.split_at(bytes.len() - 32);
    if Sha256::digest(body).as_slice() != sum {
        return Err("checkpoint damaged: its SHA-256 does not match its contents".into());
    }
    let mut at = MAGIC.len();
    let h = u64::from_le_bytes(body[at..at + 8].try_into().expect("8 bytes")) as usize;
    at += 8;
    let json = body
        .get(at..at.saturating_add(h))
        .ok_or("checkpoint header longer than the file")?;
    at += h;
    let header: Header = serde_json::from_slice(json).map_err(|e| format!("header: {e}"))?;
    if header.format != FORMAT {
        return Err(format!(
            "checkpoint format {} (this build reads format {FORMAT})",
            header.format
        ));
    }
    let (nn, ns) = (header.num_nodes, header.num_saliva);
    let count = nn
        .checked_mul(6)
        .and_then(|a| ns.checked_mul(24 + 4).map(|b| (a, b)))
        .and_then(|(a, b)| a.checked_add(b))
        .ok_or("checkpoint sizes overflow")?;
    let expected = count
        .checked_mul(8)
        .and_then(|n| n.checked_add(ns))
        .ok_or("checkpoint sizes overflow")?;
    let rest = &body[at..];
    if rest.len() != expected {
        return Err(format!(
            "checkpoint state is {} bytes, its header ({nn} nodes, {ns} saliva elements) says {expected}",
            rest.len()
        ));
    }
    let (numbers, flags) = rest.split_at(8 * count);
    let mut it = numbers
        .chunks_exact(8)
        .map(|c| f64::from_bits(u64::from_le_bytes(c.try_into().expect("8 bytes"))));
    let mut vec3 = |n: usize| -> Vec<[f64; 3]> {
        (0..n)
            .map(|_| [0; 3].map(|_| it.next().expect("counted")))
            .collect()
    };
    let u = vec3(nn);
    let u_prev = vec3(nn);
    let previous: Vec<[f64; 3]> = vec3(8 * ns);
    let saliva_previous = previous
        .chunks_exact(8)
        .map(|c| std::array::from_fn(|a| c[a]))
        .collect();
    let rest: Vec<f64> = it.collect();
    let (broken_at, rest) = rest.split_at(ns);
    let (moisture, rest) = rest.split_at(ns);
    let (z, q) = rest.split_at(ns);
    let broken = flags
        .iter()
        .map(|&b| match b {
            0 => Ok(false),
            1 => Ok(true),
            _ => Err(format!("broken flag {b} (0 or 1)")),
        })
        .collect::<std::result::Result<_, _>>()?;
    if u.iter().chain(&u_prev).flatten().any(|x| !x.is_finite()) {
        return Err("checkpoint holds a non-finite displacement".into());
    }
    let state = SolverState {
        step: header.step,
        u,
        u_prev,
        saliva_previous,
        broken,
        broken_at: broken_at.to_vec(),
        moisture: moisture.to_vec(),
        z: z.to_vec(),
        q: q.to_vec(),
    };
    Ok((header, state))
}

/// Checks that a checkpoint belongs to this problem and precision; the message names the
/// checkpoint file and what differs.
pub fn check_matches(
    path: &Path,
    header: &Header,
    problem: &Problem,
    precision: &str,
) -> Result<()> {
    if header.precision != precision {
        return Err(bad(
            path,
            format!(
                "the checkpoint is of an {} run, this run is {precision} (give --precision {})",
                header.precision, header.precision
            ),
        ));
    }
    if header.problem_hash != problem_hash(problem) {
        return Err(bad(
            path,
            format!(
                "the checkpoint was written for a different problem than {} (checkpoint of {}; the mesh, materials, loads, time or numerics differ)",
                problem.source, header.input
            ),
        ));
    }
    let steps = problem.num_steps();
    if header.step > steps || header.num_nodes != problem.mesh.nodes.len() {
        return Err(bad(path, "the checkpoint does not fit the problem's sizes"));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> (Header, SolverState) {
        let state = SolverState {
            step: 7,
            u: vec![[1.0, -2.5e-3, f64::MIN_POSITIVE], [0.0, -0.0, 3.0]],
            u_prev: vec![[0.5, 0.25, 0.125], [1e-300, 2.0, 4.0]],
            saliva_previous: vec![[[0.1, 0.2, 0.3]; 8]],
            broken: vec![true],
            broken_at: vec![f64::NAN],
            moisture: vec![100.0],
            z: vec![1.05],
            q: vec![1.0125],
        };
        let header = Header {
            format: FORMAT,
            precision: "f64".into(),
            problem_hash: "abc".into(),
            input: "case.toml".into(),
            step: 7,
            num_nodes: 2,
            num_saliva: 1,
            history: RunHistory {
                energy: EnergySeries {
                    time: vec![0.0, 0.1],
                    kinetic: vec![0.0, 1e-9],
                    strain: vec![0.0, 2e-7],
                },
                broken_saliva: vec![0, 1],
                measures: None,
                frames: vec![(0.0, "frame_000000.vtu".into())],
                stepping_time: 0.5,
                last_frame_hash: Some(displacement_hash(&[0.0, 1e-3])),
            },
        };
        (header, state)
    }

    #[test]
    fn a_checkpoint_reads_back_bit_for_bit() {
        let (h, s) = sample();
        let bytes = encode(&h, &s);
        let (h2, s2) = decode(&bytes).unwrap();
        assert_eq!(h, h2);
        let bits = |s: &SolverState| s.numbers().map(f64::to_bits).collect::<Vec<_>>();
        assert_eq!(bits(&s), bits(&s2));
        assert_eq!(s.broken, s2.broken);
        assert_eq!(s2.step, 7);
    }

    #[test]
    fn damaged_or_foreign_files_are_refused() {
        let (h, s) = sample();
        let bytes = encode(&h, &s);
        // every single-byte change is caught (by the magic or the checksum)
        for i in [0, 20, bytes.len() / 2, bytes.len() - 40, bytes.len() - 1] {
            let mut b = bytes.clone();
            b[i] ^= 0x10;
            assert!(decode(&b).is_err(), "byte {i}");
        }
        assert!(decode(&bytes[..bytes.len() - 1])
            .unwrap_err()
            .contains("not match"));
        assert!(decode(b"hello")
            .unwrap_err()
            .contains("not a sticky-lips checkpoint"));
        assert!(decode(&[]).is_err());
        // a header that claims more state than the file holds, with a valid checksum
        let mut h2 = h.clone();
        h2.num_nodes = 3;
        let b = encode(&h2, &s);
        assert!(decode(&b).unwrap_err().contains("says"), "size mismatch");
    }
}
