//! Linear vector muscles (paper section 3.3).
//!
//! A muscle is an origin `O`, an insertion `I` and a radius `r`: a cylinder. Every node whose
//! reference position lies inside the cylinder (its projection on the axis falls between `I`
//! and `O`, and it is at most `r` from the axis) receives a force along the axis, from the
//! insertion towards the origin (a muscle pulls its insertion towards its fixed origin), all
//! nodes in the same direction. The total force is `activation(t) * strength`; it is shared
//! equally among the selected nodes (our choice: the paper does not say; an equal share keeps
//! the total exactly `activation * strength` whatever the mesh resolution).

use crate::boundary::LoadCurve;

#[derive(Clone, Debug, PartialEq)]
pub struct Muscle {
    pub name: String,
    /// Origin `O` (m): the end attached to the skull.
    pub origin: [f64; 3],
    /// Insertion `I` (m): the end in the soft tissue that the muscle pulls.
    pub insertion: [f64; 3],
    /// Radius `r` of the cylinder (m).
    pub radius: f64,
    /// Force at full activation (N), shared by the selected nodes.
    pub strength: f64,
    /// Peak activation in `[0, 1]`.
    pub activation: f64,
    /// Activation over time: `activation * curve(t)`.
    pub curve: LoadCurve,
}

impl Muscle {
    /// Unit direction of the force, insertion -> origin.
    pub fn direction(&self) -> [f64; 3] {
        let d = [
            self.origin[0] - self.insertion[0],
            self.origin[1] - self.insertion[1],
            self.origin[2] - self.insertion[2],
        ];
        let n = crate::linalg::norm(&d);
        [d[0] / n, d[1] / n, d[2] / n]
    }

    /// Whether reference point `x` lies in the muscle's cylinder.
    pub fn contains(&self, x: &[f64; 3]) -> bool {
        let a = self.insertion;
        let d = [
            self.origin[0] - a[0],
            self.origin[1] - a[1],
            self.origin[2] - a[2],
        ];
        let len2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        let v = [x[0] - a[0], x[1] - a[1], x[2] - a[2]];
        let s = (v[0] * d[0] + v[1] * d[1] + v[2] * d[2]) / len2;
        if !(0.0..=1.0).contains(&s) {
            return false;
        }
        let p = [v[0] - s * d[0], v[1] - s * d[1], v[2] - s * d[2]];
        p[0] * p[0] + p[1] * p[1] + p[2] * p[2] <= self.radius * self.radius
    }

    /// The nodes inside the cylinder, in increasing order.
    pub fn select_nodes(&self, nodes: &[[f64; 3]]) -> Vec<u32> {
        (0..nodes.len() as u32)
            .filter(|&n| self.contains(&nodes[n as usize]))
            .collect()
    }

    /// The force on each selected node at full curve value: `(activation * strength / N) d`.
    pub fn nodal_force(&self, num_nodes: usize) -> [f64; 3] {
        let d = self.direction();
        let f = self.activation * self.strength / num_nodes as f64;
        [f * d[0], f * d[1], f * d[2]]
    }
}
