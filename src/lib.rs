//! # sticky-lips
//!
//! A verification-first implementation of "Physically-based Sticky Lips" (Leach &
//! Maddock): a total Lagrangian explicit dynamics (TLED) finite element model of the
//! mouth. This crate computes; the `sticky-lips` binary and `scripts/` produce files
//! and figures. See `ARCHITECTURE.md` for the data flow of one time step and
//! `paper/equations.md` for where each equation of the paper lives.

pub mod driver;
pub mod element;
pub mod error;
pub mod io;
pub mod linalg;
pub mod material;
pub mod mesh;
pub mod problem;
pub mod real;
pub mod static_solve;
pub mod tled;

pub use error::{Error, Result};
pub use problem::Problem;
pub use real::{Precision, Real};
