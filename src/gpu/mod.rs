//! The wgpu backend (cargo feature `gpu`, on by default): the TLED step and the saliva
//! breaking rule as WGSL compute kernels (`shaders/`), mirroring the CPU stages of
//! [`crate::tled`] under the same names.
//!
//! | CPU stage | WGSL kernel |
//! |---|---|
//! | `tled::element_forces::element_forces` | `shaders/element_forces.wgsl::element_forces` |
//! | `tled::saliva_forces::saliva_forces` | `shaders/element_forces.wgsl::saliva_forces` (called by the `element_forces` kernel for each saliva element) |
//! | `tled::node_update::node_update` + `tled::solver::apply_constraints` | `shaders/node_update.wgsl::node_update` |
//!
//! - [`context`]: instance from the environment, adapter, device with the adapter's limits;
//! - [`layout`]: the `#[repr(C)]` Pod structs and constants shared with WGSL;
//! - [`shaders`]: assembly of the WGSL sources;
//! - [`sim`]: [`GpuSimulation`], the same step contract as [`crate::tled::Simulation`]
//!   (packing, buffers, bindings derived from the WGSL declarations, stepping).

pub mod context;
pub mod layout;
pub mod shaders;
pub mod sim;

pub use context::{adapter_available, GpuContext};
pub use sim::{GpuReal, GpuSimulation};
