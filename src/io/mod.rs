pub mod atomic;
pub mod vtu;
pub mod niftysim;
