//! Table 1 of the paper ("the parameters used to generate the results shown in Figures 1, 4
//! and 7-11"), once, in SI units. Every default of the code that is a Table 1 value takes it
//! from here; `paper/scenarios/table1.toml` (the base scenario of `sticky-lips paper`) holds
//! the same numbers, and a test in `crate::paper` checks that the two agree.
//!
//! The extracted table has its labels and values shifted by one cell; these are the values
//! read back into place. Its K_glue cell reads 0 (lost: 0 would switch stickiness off);
//! `crate::paper` holds the value chosen for the figures instead.

/// A neo-Hookean material of Table 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Table1Material {
    /// Shear modulus `mu` (Pa).
    pub mu: f64,
    /// Bulk modulus `K` (Pa).
    pub bulk: f64,
    /// Mass density `rho` (kg/m^3).
    pub density: f64,
}

impl Table1Material {
    /// As a [`crate::problem::MaterialSpec`] called `name`.
    pub fn spec(&self, name: &str) -> crate::problem::MaterialSpec {
        crate::problem::MaterialSpec {
            name: name.into(),
            law: crate::material::NeoHookean {
                mu: self.mu,
                bulk: self.bulk,
            },
            density: self.density,
        }
    }
}

/// Soft tissue: neo-Hookean, `mu` = 800 Pa, `K` = 7000 Pa, `rho` = 1050 kg/m^3.
pub const TISSUE: Table1Material = Table1Material {
    mu: 800.0,
    bulk: 7000.0,
    density: 1050.0,
};

/// Saliva: the breaking neo-Hookean material, `mu` = 7700 Pa, `K` = 191000 Pa,
/// `rho` = 1050 kg/m^3.
pub const SALIVA: Table1Material = Table1Material {
    mu: 7700.0,
    bulk: 191000.0,
    density: 1050.0,
};

/// Time step `dt` (s).
pub const TIME_STEP: f64 = 1e-5;

/// Total time simulated (s).
pub const TOTAL_TIME: f64 = 1.0;

/// Hourglass control coefficient `kappa` (dimensionless).
pub const HOURGLASS_KAPPA: f64 = 0.075;

/// Mass-proportional damping coefficient `alpha` (1/s): damping matrix `alpha M`.
pub const DAMPING: f64 = 80.0;

/// Initial moisture `0M` of the saliva (the paper's moisture level; read here as a film
/// thickness in micrometres, see `material::saliva`).
pub const INITIAL_MOISTURE: f64 = 100.0;

/// Critical moisture `Mc` (same unit as the moisture).
pub const CRITICAL_MOISTURE: f64 = 100.0;

/// Evaporation rate `phi` (um/s): 0, "as all the animations produced are short" (section 4).
pub const EVAPORATION_RATE: f64 = 0.0;

/// Eq. (11)'s force decay of a broken saliva element: 0.99 per time step.
pub const DECAY_PER_STEP: f64 = 0.99;

/// Frames are recorded every this many steps (section 4: "vertex displacements are recorded
/// every 100 steps").
pub const OUTPUT_EVERY: usize = 100;
