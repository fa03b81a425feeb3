//! The application layer: what a front end (the command line, the Python package, a Blender
//! add-on driving the command line) does with the library, written once.
//!
//! - [`blend`]: a blend of displacement fields written as a one-frame run;
//! - [`input`]: an input file to a [`Problem`](crate::Problem), the reader chosen by its
//!   extension, with a time step or substeps asked for; the default job's scenario;
//! - [`face`]: a user's head to a runnable model directory (`sticky-lips face`);
//! - [`look`]: how a run's frame is drawn (the camera on the mouth, the skin, the saliva);
//! - [`preview`]: a run's `preview.png` and `preview_sheet.png`;
//! - [`mesh_outputs`]: a hexahedral model's `mesh.vtu` and `model.xml`.

pub mod blend;
pub mod face;
pub mod input;
pub mod look;
pub mod mesh_outputs;
pub mod preview;
