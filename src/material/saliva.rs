//! The saliva breaking element (paper section 3.4): moisture (eqs. 5-6), breaking point
//! (eq. 7), stretch across the layer (eqs. 8-10) and the force rule (eq. 11).
//!
//! A saliva element is an ordinary neo-Hookean hexahedron (stiffer than tissue, Table 1)
//! in the single layer between the lips. Every step, after its TLED force `f` is computed,
//! its stretch across the layer `Q` is compared with its breaking point `Z`; once `Q >= Z`
//! its force is replaced by a geometrically decaying copy of the previous step's force.
//!
//! Units: moisture is the paper's dimensionless "moisture level"; we read it as the
//! thickness of the saliva film in micrometres (the paper's Table 1 uses 100, and its text
//! gives 70-100 um films [CD87]), so an evaporation rate is in um/s. `Mc` is in the same units.

use crate::linalg::Mat3;
use crate::real::Real;

/// Boltzmann constant `k_B` (J/K), exact in SI since 2019.
pub const BOLTZMANN: f64 = 1.380_649e-23;
/// Avogadro constant `N_A` (1/mol), exact in SI since 2019.
pub const AVOGADRO: f64 = 6.022_140_76e23;

/// Paper eq. (5), Herz-Knudsen: the net molecular evaporation flux
///
/// $$ \varphi = \frac{1}{A}\frac{dN}{dt} = \frac{\alpha (p_{liq} - p_{eq})}{\sqrt{2 \pi m k_B T_{liq}}} $$
///
/// | symbol | code | unit |
/// |---|---|---|
/// | `alpha` sticking (evaporation) coefficient | `sticking` | - |
/// | `p_liq - p_eq` pressure difference | `p_liq`, `p_eq` | Pa |
/// | `m` mass of one molecule | `molecule_mass` | kg |
/// | `T_liq` liquid temperature | `temperature` | K |
/// | `phi` | return value | molecules / (m^2 s) |
///
/// Verified by `verification/saliva.rs::herz_knudsen_water_at_lip_temperature`.
pub fn herz_knudsen_flux(
    sticking: f64,
    p_liq: f64,
    p_eq: f64,
    molecule_mass: f64,
    temperature: f64,
) -> f64 {
    sticking * (p_liq - p_eq)
        / (2.0 * std::f64::consts::PI * molecule_mass * BOLTZMANN * temperature).sqrt()
}

/// Saturation vapour pressure of water over a flat liquid surface (Pa) at `celsius` (C), by
/// the Buck (1996) equation `611.21 exp((18.678 - T/234.5) (T / (257.14 + T)))`, accurate to
/// about 0.05 % between 0 and 50 C. Used for `p_liq` in eq. (5) by the `evaporation` command.
pub fn water_saturation_pressure(celsius: f64) -> f64 {
    611.21 * ((18.678 - celsius / 234.5) * (celsius / (257.14 + celsius))).exp()
}

/// Eq. (5) converted to the quantities a user of the model needs.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct EvaporationRates {
    /// Molecular flux `phi` (molecules / (m^2 s)).
    pub molecular_flux: f64,
    /// Mass flux `phi m` (kg / (m^2 s)).
    pub mass_flux: f64,
    /// Rate at which the film thins, `phi m / rho_liq` (m/s).
    pub thinning_rate: f64,
    /// The model's evaporation rate: film thinning in micrometres per second (moisture units / s).
    pub moisture_rate: f64,
}

/// Eq. (5) from physical inputs: molar mass in kg/mol, liquid density in kg/m^3.
pub fn evaporation_rates(
    sticking: f64,
    p_liq: f64,
    p_eq: f64,
    molar_mass: f64,
    temperature: f64,
    liquid_density: f64,
) -> EvaporationRates {
    let m = molar_mass / AVOGADRO;
    let phi = herz_knudsen_flux(sticking, p_liq, p_eq, m, temperature);
    let mass_flux = phi * m;
    let thinning = mass_flux / liquid_density;
    EvaporationRates {
        molecular_flux: phi,
        mass_flux,
        thinning_rate: thinning,
        moisture_rate: thinning * 1e6,
    }
}

/// A piecewise-constant evaporation rate: `rates[k]` (moisture units / s) holds from
/// `starts[k]` (s) until the next start; `starts[0] = 0`.
#[derive(Clone, Debug, PartialEq)]
pub struct EvaporationSchedule {
    pub starts: Vec<f64>,
    pub rates: Vec<f64>,
}

impl EvaporationSchedule {
    pub fn constant(rate: f64) -> Self {
        EvaporationSchedule {
            starts: vec![0.0],
            rates: vec![rate],
        }
    }
    /// `int_0^t phi(s) ds` (moisture units): how much has evaporated by time `t`.
    pub fn evaporated(&self, t: f64) -> f64 {
        let mut total = 0.0;
        for k in 0..self.starts.len() {
            let a = self.starts[k];
            if t <= a {
                break;
            }
            let b = self
                .starts
                .get(k + 1)
                .copied()
                .unwrap_or(f64::INFINITY)
                .min(t);
            total += self.rates[k] * (b - a);
        }
        total
    }
}

/// Paper eq. (6): moisture at time `t`,
///
/// $$ {}^tM = \begin{cases} {}^0M - t\varphi & {}^0M > t\varphi \\ 0 & \text{otherwise} \end{cases} $$
///
/// written with the evaporated amount `E(t) = int_0^t phi` so that a piecewise-constant rate
/// is covered (`E = t phi` for the paper's constant rate). Units: moisture (um).
/// Verified by `verification/saliva.rs::moisture_eq6`.
pub fn moisture(initial: f64, evaporated: f64) -> f64 {
    if initial > evaporated {
        initial - evaporated
    } else {
        0.0
    }
}

/// Paper eq. (7): breaking point
///
/// $$ Z = \begin{cases} 1 & {}^tM > M_c \\ 1 + K \, {}^tM / M_c & \text{otherwise} \end{cases} $$
///
/// `k_glue` is the paper's `K`, the maximum glue strength (dimensionless; not the bulk
/// modulus). `Z` is a squared stretch: the element breaks when `Q = lambda_y^2 >= Z`.
/// Verified by `verification/saliva.rs::breaking_point_eq7`.
pub fn breaking_point(moisture: f64, critical: f64, k_glue: f64) -> f64 {
    if moisture > critical {
        1.0
    } else {
        1.0 + k_glue * moisture / critical
    }
}

/// Paper eqs. (8)-(10): the stretch across the layer, `Q = y^T C y = |F y|^2`, with `y` the
/// unit vector of the element's local y axis (across the saliva layer) in the reference
/// configuration and `F = I + H` (eq. 8), `C = F^T F` (eq. 9). The paper's `C_11` (0-based)
/// is this component in the element's local frame (eq. 10); rigid rotations leave it unchanged.
///
/// Computed as `1 + (2 y.Hy + |Hy|^2)` so small stretches keep their precision in `f32`.
/// Verified by `verification/saliva.rs::stretch_eqs_8_10`.
/// GPU twin: `shaders/common/saliva.wgsl::stretch_across` (`verification/gpu.rs`).
#[inline(always)]
pub fn stretch_across<T: Real>(h: &Mat3<T>, y: &[T; 3]) -> T {
    let hy = crate::linalg::mat_vec(h, y);
    let two = T::from_f64(2.0);
    T::ONE + (two * crate::linalg::dot(y, &hy) + crate::linalg::dot(&hy, &hy))
}

/// Which reading of eq. (11) to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum BreakingRule {
    /// Eq. (11) as written: whenever `Q < Z` the unmodified force returns.
    #[default]
    Literal,
    /// As the paper's prose says: once broken, an element stays broken and its force keeps
    /// decaying; it never glues again. Our choice: compression across the layer (`Q < 1`)
    /// still gives the unmodified force, so the lips resist being pushed into each other.
    Latched,
}

/// Paper eq. (11): the force of a saliva element at this step,
///
/// $$ {}^tF = \begin{cases} {}^tf & Q < Z \\ 0.99 \, {}^{t-1}F & \text{otherwise} \end{cases} $$
///
/// `force` holds the unmodified TLED force `f` (8x3, hourglass part included) on entry and
/// the modified force `F` on return; `previous` holds `F` of the previous step on entry and
/// is updated. `decay` is the factor per step (0.99 in the paper). `broken` is the latched
/// state (only read by `Latched`). Returns whether the element is broken at this step.
/// Verified by `verification/saliva.rs::force_rule_eq11_*`.
/// GPU twin: `shaders/common/saliva.wgsl::apply_breaking_rule` (`verification/gpu.rs`).
#[inline(always)]
pub fn apply_breaking_rule<T: Real>(
    q: T,
    z: T,
    rule: BreakingRule,
    decay: T,
    broken: bool,
    force: &mut [[T; 3]; 8],
    previous: &mut [[T; 3]; 8],
) -> bool {
    let intact = match rule {
        BreakingRule::Literal => q < z,
        BreakingRule::Latched => {
            if broken {
                q < T::ONE
            } else {
                q < z
            }
        }
    };
    if !intact {
        for a in 0..8 {
            for k in 0..3 {
                force[a][k] = decay * previous[a][k];
            }
        }
    }
    *previous = *force;
    match rule {
        BreakingRule::Literal => !intact,
        BreakingRule::Latched => broken || !intact,
    }
}

/// How fast a broken element's force decays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Decay {
    /// A factor per time step (the paper: 0.99). Its physical decay time depends on `dt`.
    PerStep(f64),
    /// A decay time `tau` (s): the factor per step is `exp(-dt / tau)`, independent of `dt`.
    Time(f64),
}

impl Decay {
    pub fn factor(self, dt: f64) -> f64 {
        match self {
            Decay::PerStep(f) => f,
            Decay::Time(tau) => (-dt / tau).exp(),
        }
    }
}

/// Initial moisture of the saliva elements as a function of where they are.
#[derive(Clone, Debug, PartialEq)]
pub enum MoistureMap {
    Constant(f64),
    /// Linear from `values.0` at coordinate `positions.0` to `values.1` at `positions.1`
    /// along `axis` (clamped outside), evaluated at the element centroid.
    Gradient {
        axis: [f64; 3],
        positions: (f64, f64),
        values: (f64, f64),
    },
    /// Piecewise constant along `axis`: `values[k]` between `edges[k-1]` and `edges[k]`
    /// (`values.len() = edges.len() + 1`).
    Bands {
        axis: [f64; 3],
        edges: Vec<f64>,
        values: Vec<f64>,
    },
    /// `left` where the centroid's coordinate along `axis` is below `center`, else `right`.
    LeftRight {
        axis: [f64; 3],
        center: f64,
        left: f64,
        right: f64,
    },
    /// One value per saliva element, in element order (read from a file).
    PerElement(Vec<f64>),
}

impl MoistureMap {
    /// Value at an element centroid `c`; `k` is the element's index among the saliva elements.
    pub fn value(&self, c: &[f64; 3], k: usize) -> f64 {
        let along = |axis: &[f64; 3]| c[0] * axis[0] + c[1] * axis[1] + c[2] * axis[2];
        match self {
            MoistureMap::Constant(m) => *m,
            MoistureMap::Gradient {
                axis,
                positions,
                values,
            } => {
                let s = ((along(axis) - positions.0) / (positions.1 - positions.0)).clamp(0.0, 1.0);
                values.0 + s * (values.1 - values.0)
            }
            MoistureMap::Bands {
                axis,
                edges,
                values,
            } => {
                let x = along(axis);
                let k = edges.iter().take_while(|&&e| x >= e).count();
                values[k]
            }
            MoistureMap::LeftRight {
                axis,
                center,
                left,
                right,
            } => {
                if along(axis) < *center {
                    *left
                } else {
                    *right
                }
            }
            MoistureMap::PerElement(v) => v[k],
        }
    }
}

/// Parameters of a saliva material (on top of its neo-Hookean moduli).
#[derive(Clone, Debug, PartialEq)]
pub struct SalivaParams {
    /// Critical moisture `M_c` (um).
    pub critical_moisture: f64,
    /// Maximum glue strength `K` of eq. (7) (dimensionless).
    pub k_glue: f64,
    /// Initial moisture `0M` (um).
    pub initial_moisture: MoistureMap,
    /// Evaporation rate `phi` (um/s).
    pub evaporation: EvaporationSchedule,
    pub rule: BreakingRule,
    pub decay: Decay,
    /// The local y axis (across the layer); `None` = found from each element's reference
    /// geometry ([`across_direction`]).
    pub across: Option<AcrossAxis>,
}

/// The local y axis of the saliva elements (across the layer), in the reference
/// configuration: the direction whose stretch `Q` eqs. (8)-(10) measure.
#[derive(Clone, Debug, PartialEq)]
pub enum AcrossAxis {
    /// One direction for every element of the set (normalised where used).
    Uniform([f64; 3]),
    /// A unit direction per element, by element index (a model that knows its lips, e.g. a
    /// face whose strip is sheared: [`crate::mesh::face::FaceModel::saliva_across`]).
    PerElement(std::collections::BTreeMap<u32, [f64; 3]>),
}

impl SalivaParams {
    /// The first moisture value of the map that is negative or not finite, if any.
    pub fn initial_moisture_values_invalid(&self) -> Option<f64> {
        let bad = |v: &f64| !(v.is_finite() && *v >= 0.0);
        match &self.initial_moisture {
            MoistureMap::Constant(m) => bad(m).then_some(*m),
            MoistureMap::Gradient { values, .. } => {
                [values.0, values.1].into_iter().find(|v| bad(v))
            }
            MoistureMap::Bands { values, .. } => values.iter().copied().find(|v| bad(v)),
            MoistureMap::LeftRight { left, right, .. } => {
                [*left, *right].into_iter().find(|v| bad(v))
            }
            MoistureMap::PerElement(v) => v.iter().copied().find(|v| bad(v)),
        }
    }
}

/// The direction across a flat element: of the three lines joining opposite face centres
/// (the centre columns of the Jacobian `dX/dxi`, `dX/deta`, `dX/dzeta`), the shortest,
/// normalised. For an element of a thin layer this is the layer's normal, whatever the
/// node numbering. Ties (a cube) pick the first.
pub fn across_direction(x: &[[f64; 3]; 8]) -> [f64; 3] {
    let j = crate::element::hex8::jacobian(x, [0.0; 3]);
    let mut best = (f64::INFINITY, [0.0; 3]);
    for c in 0..3 {
        let v = [j[0][c], j[1][c], j[2][c]];
        let n = crate::linalg::norm(&v);
        if n < best.0 * (1.0 - 1e-12) {
            best = (n, [v[0] / n, v[1] / n, v[2] / n]);
        }
    }
    best.1
}
