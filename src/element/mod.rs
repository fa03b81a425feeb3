//! Element geometry, computed once in the reference configuration.
pub mod hex8;
