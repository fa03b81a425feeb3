//! The verification suite: one `cargo test` target, one module per claim family.
//! The catalogue (claim, paper equation, tolerance and why) is `verification/README.md`.

mod common;
mod determinism;
mod element;
#[cfg(feature = "gpu")]
mod gpu;
mod inputs;
mod muscle_jaw_blend;
mod niftysim;
mod paper_claims;
mod patch;
mod precision;
mod restick;
mod saliva;
mod skfem;
mod subcycling;
mod time_integration;
mod time_step;
