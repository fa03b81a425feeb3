//! Total Lagrangian explicit dynamics (paper section 3.2): precompute, the three stages of
//! a step (`element_forces`, `saliva_forces` on the saliva elements' own blocks,
//! `node_update` with the constraints), stability.
pub mod element_forces;
pub mod node_update;
pub mod precompute;
pub mod saliva_forces;
pub mod simd;
pub mod solver;
pub mod stability;
pub mod subcycle;

pub use solver::Simulation;
