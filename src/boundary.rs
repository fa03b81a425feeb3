//! Boundary conditions and loads: fixed DOFs, prescribed displacements with load
//! shapes, a prescribed rigid rotation of a node set (the jaw), nodal forces, gravity.

use crate::linalg::rotation_matrix;

/// A load shape of relative time `tau` in `[0, 1]`: the fraction of the magnitude applied.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LoadShape {
    /// `tau`.
    Ramp,
    /// `10 tau^3 - 15 tau^4 + 6 tau^5` (zero velocity and acceleration at both ends).
    Poly345,
    /// `1` from the start.
    Step,
    /// `tau exp(cos(4 pi tau) - 1)` (NiftySim's wavy ramp).
    Hilly,
    /// `tau / 0.1` below `tau = 0.1`, then `1`.
    RampHold,
    /// `3 tau^2 - 2 tau^3` (zero velocity at both ends).
    SmoothStep,
    /// Keyframes in absolute time, interpolated linearly, held before the first and after
    /// the last ([`Keyframes`]); `start` and `duration` of the curve do not apply.
    #[serde(skip)]
    Keyed(std::sync::Arc<Keyframes>),
}

/// Keyframes `(time s, value)`, strictly increasing in time, at least one: the value at `t`
/// is the linear interpolation between the keys around it, the first key's value before it and
/// the last's after it. Animation packages export a key per frame, so linear interpolation
/// reproduces their curves at the frames.
#[derive(Clone, Debug, PartialEq)]
pub struct Keyframes {
    keys: Vec<(f64, f64)>,
}

impl Keyframes {
    /// Checks the keys: finite, at least one, times strictly increasing. The error says which
    /// key (0-based) is wrong.
    pub fn new(keys: Vec<(f64, f64)>) -> Result<Keyframes, String> {
        if keys.is_empty() {
            return Err("needs at least one key".into());
        }
        for (i, &(t, v)) in keys.iter().enumerate() {
            if !(t.is_finite() && v.is_finite()) {
                return Err(format!("key {i} ({t}, {v}) is not finite"));
            }
            if i > 0 && t <= keys[i - 1].0 {
                return Err(format!(
                    "key {i} at t = {t} s does not come after key {} at t = {} s",
                    i - 1,
                    keys[i - 1].0
                ));
            }
        }
        Ok(Keyframes { keys })
    }

    pub fn keys(&self) -> &[(f64, f64)] {
        &self.keys
    }

    /// The value at time `t` (s).
    pub fn at(&self, t: f64) -> f64 {
        let k = &self.keys;
        // the first key after t
        let i = k.partition_point(|&(tk, _)| tk <= t);
        if i == 0 {
            return k[0].1;
        }
        if i == k.len() {
            return k[k.len() - 1].1;
        }
        let ((t0, v0), (t1, v1)) = (k[i - 1], k[i]);
        v0 + (v1 - v0) * ((t - t0) / (t1 - t0))
    }
}

impl LoadShape {
    /// The shape at relative time `tau` (not clamped: NiftySim evaluates past 1).
    pub fn eval(&self, tau: f64) -> f64 {
        match self {
            LoadShape::Keyed(k) => k.at(tau),
            LoadShape::Ramp => tau,
            LoadShape::Poly345 => tau * tau * tau * (10.0 - 15.0 * tau + 6.0 * tau * tau),
            LoadShape::Step => 1.0,
            LoadShape::Hilly => tau * ((4.0 * std::f64::consts::PI * tau).cos() - 1.0).exp(),
            LoadShape::RampHold => {
                if tau < 0.1 {
                    tau / 0.1
                } else {
                    1.0
                }
            }
            LoadShape::SmoothStep => tau * tau * (3.0 - 2.0 * tau),
        }
    }

    pub fn parse(s: &str) -> Option<LoadShape> {
        Some(match s.to_ascii_uppercase().as_str() {
            "RAMP" => LoadShape::Ramp,
            "POLY345" => LoadShape::Poly345,
            "STEP" => LoadShape::Step,
            "HILLY" => LoadShape::Hilly,
            "RAMPHOLD" => LoadShape::RampHold,
            "SMOOTH_STEP" | "SMOOTHSTEP" => LoadShape::SmoothStep,
            _ => return None,
        })
    }
}

/// A load shape applied over a time window: `tau = (t - start) / duration` (keyframes: in
/// absolute time).
#[derive(Clone, Debug, PartialEq)]
pub struct LoadCurve {
    pub shape: LoadShape,
    /// When the shape starts (s).
    pub start: f64,
    /// How long it takes to reach its end value (s).
    pub duration: f64,
}

impl LoadCurve {
    /// Value at time `t` (s). With `clamp`, `tau` is held in `[0, 1]` (the shape holds its
    /// end value, and is zero before `start`; at `start` it is the shape's value at 0, so a
    /// `Step` is on from `start`); without, it is NiftySim's unclamped value.
    pub fn value(&self, t: f64, clamp: bool) -> f64 {
        if let LoadShape::Keyed(k) = &self.shape {
            return k.at(t);
        }
        let mut tau = (t - self.start) / self.duration;
        if clamp {
            if tau < 0.0 {
                return 0.0;
            }
            tau = tau.min(1.0);
        }
        self.shape.eval(tau)
    }
}

/// Which of the three DOFs of a node a constraint acts on.
pub type DofMask = [bool; 3];

#[derive(Clone, Debug, PartialEq)]
pub struct Fixed {
    pub nodes: Vec<u32>,
    pub dofs: DofMask,
}

/// `u_dof(t) = value * curve(t)` at each node.
#[derive(Clone, Debug, PartialEq)]
pub struct PrescribedDisplacement {
    pub nodes: Vec<u32>,
    pub dof: usize,
    /// One value per node (m).
    pub values: Vec<f64>,
    pub curve: LoadCurve,
}

/// A rigid rotation of a node set about the axis through `point` along `axis` (unit),
/// by the angle `angle * curve(t)` (rad): `u = R (X - p) + p - X`. It drives the jaw.
#[derive(Clone, Debug, PartialEq)]
pub struct PrescribedRotation {
    pub nodes: Vec<u32>,
    pub point: [f64; 3],
    pub axis: [f64; 3],
    pub angle: f64,
    pub curve: LoadCurve,
}

impl PrescribedRotation {
    /// Displacement of reference point `x` at time `t`.
    pub fn displacement(&self, x: &[f64; 3], t: f64, clamp: bool) -> [f64; 3] {
        self.displacement_by(&self.matrix(t, clamp), x)
    }

    /// The rotation matrix at time `t` (one per step, shared by all of the set's nodes).
    pub fn matrix(&self, t: f64, clamp: bool) -> [[f64; 3]; 3] {
        rotation_matrix(&self.axis, self.angle * self.curve.value(t, clamp))
    }

    /// Displacement of reference point `x` under the rotation `r` (from [`Self::matrix`]):
    /// `R (x - p) - (x - p)`.
    pub fn displacement_by(&self, r: &[[f64; 3]; 3], x: &[f64; 3]) -> [f64; 3] {
        let d = [
            x[0] - self.point[0],
            x[1] - self.point[1],
            x[2] - self.point[2],
        ];
        let rd = crate::linalg::mat_vec(r, &d);
        [rd[0] - d[0], rd[1] - d[1], rd[2] - d[2]]
    }
}

/// `f_dof(t) = value * curve(t)` at each node (N).
#[derive(Clone, Debug, PartialEq)]
pub struct NodalForce {
    pub nodes: Vec<u32>,
    pub dof: usize,
    pub values: Vec<f64>,
    pub curve: LoadCurve,
}

/// Body force `m_n g(t)` on the nodes (all nodes when `nodes` is `None`),
/// `g(t) = acceleration * curve(t)` (m/s^2), `m_n` the lumped mass.
#[derive(Clone, Debug, PartialEq)]
pub struct Gravity {
    pub nodes: Option<Vec<u32>>,
    pub acceleration: [f64; 3],
    pub curve: LoadCurve,
}

/// Everything imposed on the model.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BoundaryConditions {
    pub fixed: Vec<Fixed>,
    pub displacements: Vec<PrescribedDisplacement>,
    pub rotations: Vec<PrescribedRotation>,
    pub forces: Vec<NodalForce>,
    pub gravity: Vec<Gravity>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keyframes_interpolate_linearly_and_hold_at_the_ends() {
        let k = Keyframes::new(vec![(0.1, 1.0), (0.3, 3.0), (0.4, -1.0)]).unwrap();
        for (t, v) in [
            (-5.0, 1.0),
            (0.1, 1.0),
            (0.2, 2.0),
            (0.3, 3.0),
            (0.35, 1.0),
            (0.4, -1.0),
            (9.0, -1.0),
        ] {
            assert!((k.at(t) - v).abs() < 1e-14, "at {t}: {} not {v}", k.at(t));
        }
        // a curve of keys takes absolute time, whatever its start and duration say
        let c = LoadCurve {
            shape: LoadShape::Keyed(std::sync::Arc::new(k)),
            start: 5.0,
            duration: 0.01,
        };
        assert!((c.value(0.2, true) - 2.0).abs() < 1e-14);
        assert_eq!(Keyframes::new(vec![(0.0, 7.0)]).unwrap().at(1.0), 7.0);
    }

    #[test]
    fn keyframes_must_be_finite_and_increasing() {
        assert!(Keyframes::new(vec![]).unwrap_err().contains("at least one"));
        let e = Keyframes::new(vec![(0.0, 0.0), (0.0, 1.0)]).unwrap_err();
        assert!(e.contains("key 1"), "{e}");
        let e = Keyframes::new(vec![(0.0, f64::NAN)]).unwrap_err();
        assert!(e.contains("key 0") && e.contains("finite"), "{e}");
    }
}
