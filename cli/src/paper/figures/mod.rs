//! One producer per figure, listed in [`TABLE`] with the runs each needs.

mod choices;
mod dt;
mod fig1;
mod fig10;
mod fig11;
mod fig2;
mod fig4;
mod fig6;
mod fig7;
mod fig8;
mod fig9;
mod load;
mod plots;
mod restick;
mod study;
mod sweep;
mod zip;

use super::runs::{self, Model};
use super::{Context, Output};
use sticky_lips::error::Result;

pub struct Figure {
    /// Its name for `--only`.
    pub name: &'static str,
    /// What it shows, in a few words.
    pub what: &'static str,
    /// The runs it needs (see [`runs::all`]).
    pub runs: fn(Model, bool) -> Vec<String>,
    pub produce: fn(&Context) -> Result<Output>,
}

fn names(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| s.to_string()).collect()
}

fn sweep_runs(_: Model, quick: bool) -> Vec<String> {
    let (ks, angles) = runs::sweep_grid(quick);
    let mut v = Vec::new();
    for &a in &angles {
        for &k in &ks {
            v.push(runs::sweep_name(k, a));
        }
    }
    v
}

pub const TABLE: &[Figure] = &[
    Figure {
        name: "fig2",
        what: "material regions",
        runs: |_, _| names(&["fig4_sticky"]),
        produce: fig2::produce,
    },
    Figure {
        name: "fig4",
        what: "the opening over time, rows 0.04 s apart",
        runs: |_, _| names(&["fig4_dry", "fig4_sticky"]),
        produce: fig4::produce,
    },
    Figure {
        name: "fig1",
        what: "the mouth opening with sticky lips",
        runs: |_, _| names(&["fig4_sticky"]),
        produce: fig1::produce,
    },
    Figure {
        name: "fig6",
        what: "the blend-shape baseline at the slight opening",
        runs: |_, _| names(&["fig7_dry", "fig4_dry"]),
        produce: fig6::produce,
    },
    Figure {
        name: "fig7",
        what: "a slight opening at equilibrium",
        runs: |_, _| names(&["fig7_dry", "fig7_sticky", "fig4_dry"]),
        produce: fig7::produce,
    },
    Figure {
        name: "fig8",
        what: "a wide opening at equilibrium",
        runs: |_, _| names(&["fig4_dry", "fig4_sticky"]),
        produce: fig8::produce,
    },
    Figure {
        name: "fig9",
        what: "moisture varying along the lips",
        runs: |_, _| names(&["fig9_bands"]),
        produce: fig9::produce,
    },
    Figure {
        name: "fig10",
        what: "asymmetric opening (one side's depressors)",
        runs: |_, _| names(&["fig10_asym"]),
        produce: fig10::produce,
    },
    Figure {
        name: "fig11",
        what: "texture-mapped",
        runs: |_, _| names(&["fig4_sticky"]),
        produce: fig11::produce,
    },
    Figure {
        name: "load",
        what: "the load on the saliva along the mouth, breaking off",
        runs: |_, _| names(&["load_profile"]),
        produce: load::produce,
    },
    Figure {
        name: "zip",
        what: "the zip front: when each lip column opens",
        runs: |_, _| names(&["fig4_dry", "fig4_sticky", "fig7_sticky"]),
        produce: zip::produce,
    },
    Figure {
        name: "sweep",
        what: "K_glue x jaw angle: equilibrium open fraction and where the opening starts",
        runs: sweep_runs,
        produce: sweep::produce,
    },
    Figure {
        name: "study",
        what: "what sets the zip front's speed",
        runs: |_, quick| study::names(quick),
        produce: study::produce,
    },
    Figure {
        name: "dt",
        what: "convergence in the time step: the wide opening at six steps",
        runs: |_, _| dt::names(),
        produce: dt::produce,
    },
    Figure {
        name: "choices",
        what: "the modelling choices the paper leaves open, one at a time: load and equilibrium opening",
        runs: choices::names,
        produce: choices::produce,
    },
    Figure {
        name: "restick",
        what: "lips that stick again: open, close, open",
        // the face only: on the procedural mouth the run diverges as the lips close again
        runs: |model, _| match model {
            Model::Face => names(&["plosive"]),
            Model::Procedural => Vec::new(),
        },
        produce: restick::produce,
    },
    Figure {
        name: "plots",
        what: "the measures over time",
        runs: |_, _| names(&["fig4_dry", "fig4_sticky", "fig10_asym"]),
        produce: plots::produce,
    },
];
