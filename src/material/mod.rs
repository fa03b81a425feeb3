//! Constitutive models.
pub mod neo_hookean;
pub mod saliva;

pub use neo_hookean::NeoHookean;
