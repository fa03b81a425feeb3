pub mod args;
pub mod atomic;
pub mod checkpoint;
pub mod niftysim;
pub mod obj;
pub mod output;
pub mod scenario;
pub mod vtu;
