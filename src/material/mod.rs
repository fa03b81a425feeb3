//! Constitutive models.
pub mod neo_hookean;

pub use neo_hookean::NeoHookean;
