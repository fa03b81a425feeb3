//! # sticky-lips
//!
//! A verification-first implementation of "Physically-based Sticky Lips" (Leach &
//! Maddock): a total Lagrangian explicit dynamics (TLED) finite element model of the
//! mouth. This crate computes; the `sticky-lips` binary and `scripts/` produce files
//! and figures. See `ARCHITECTURE.md` for the data flow of one time step and
//! `paper/equations.md` for where each equation of the paper lives.

// Index loops mirror the tensor notation of the equations (`H_ij = sum_a u_a,i D_a,j`);
// iterator chains would hide it.
#![allow(clippy::needless_range_loop)]
// `!(x > 0.0)` is deliberate throughout input validation: unlike `x <= 0.0` it also
// rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod app;
pub mod blend;
pub mod boundary;
pub mod claims;
pub mod control;
pub mod driver;
pub mod element;
pub mod error;
pub mod export;
#[cfg(feature = "gpu")]
pub mod gpu;
pub mod io;
pub mod lanes;
pub mod linalg;
pub mod material;
pub mod measures;
pub mod mesh;
pub mod muscle;
pub mod paper;
pub mod problem;
pub mod real;
pub mod render;
pub mod run_dir;
#[cfg(feature = "equilibrium")]
pub mod static_solve;
pub mod sweep;
pub mod tled;

pub use error::{Error, Result};
pub use problem::Problem;
pub use real::{Precision, Real};
