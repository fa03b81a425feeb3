//! The zones of a mouth model: the left, centre and right thirds of the lips' width.
//!
//! `[[wet]]` picks its saliva by zone, and a mouth model (generators `mouth` and `face`) has
//! one element set per zone, `saliva_left`, `saliva_centre` and `saliva_right`, so that a
//! scenario can give each third its own saliva material (its own `k_glue` and moisture in a
//! `[[saliva]]` table of its own), as the Blender add-on's stickiness per zone does.
//!
//! A zone is decided by the element's centroid `x` (m, the model frame: `+x` is the
//! subject's left) against the lip columns: with `c` the mouth's centre line and `w` the
//! columns' span, left is `x >= c + w/6`, right is `x <= c - w/6`, centre is in between.
//! The three zones cover every element once.

use crate::measures::LipColumns;
use crate::mesh::Mesh;

/// A zone of the mouth, by the subject's sides.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Zone {
    Left,
    Centre,
    Right,
    /// The whole mouth.
    All,
}

impl Zone {
    /// The three thirds, in the order of the element sets' names.
    pub const THIRDS: [Zone; 3] = [Zone::Left, Zone::Centre, Zone::Right];

    /// The zone named `name` (`left`, `centre` or `center`, `right`, `all`).
    pub fn from_name(name: &str) -> Option<Zone> {
        match name {
            "left" => Some(Zone::Left),
            "centre" | "center" => Some(Zone::Centre),
            "right" => Some(Zone::Right),
            "all" => Some(Zone::All),
            _ => None,
        }
    }

    /// The name a scenario uses.
    pub fn name(self) -> &'static str {
        match self {
            Zone::Left => "left",
            Zone::Centre => "centre",
            Zone::Right => "right",
            Zone::All => "all",
        }
    }

    /// Whether a point at `x` (m, model frame) lies in this zone of the mouth of `cols`.
    pub fn contains(self, cols: &LipColumns, x: f64) -> bool {
        let (lo, hi) = cols
            .x
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        let third = (hi - lo) / 6.0;
        let c = cols.center;
        match self {
            Zone::Left => x >= c + third,
            Zone::Right => x <= c - third,
            Zone::Centre => (x - c).abs() < third,
            Zone::All => true,
        }
    }
}

/// The elements of `candidates` whose centroid lies in `zone`.
pub fn elements(mesh: &Mesh, candidates: &[u32], cols: &LipColumns, zone: Zone) -> Vec<u32> {
    candidates
        .iter()
        .copied()
        .filter(|&e| {
            let x = mesh.element_coords(e as usize);
            zone.contains(cols, x.iter().map(|p| p[0]).sum::<f64>() / 8.0)
        })
        .collect()
}

/// Adds the element sets `saliva_left`, `saliva_centre` and `saliva_right` (the element set
/// `saliva` split by zone) to a mouth model's mesh; nothing where it has no `saliva` set.
pub fn add_saliva_sets(mesh: &mut Mesh, cols: &LipColumns) {
    let Some(saliva) = mesh.element_sets.get("saliva").cloned() else {
        return;
    };
    for zone in Zone::THIRDS {
        let set = elements(mesh, &saliva, cols, zone);
        mesh.element_sets
            .insert(format!("saliva_{}", zone.name()), set);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The three zone sets of the procedural mouth split its saliva: each element in exactly
    /// one, none empty, left ones at larger x than centre ones, centre ones than right ones.
    #[test]
    fn the_zone_sets_split_the_saliva() {
        let model = crate::mesh::mouth::generate(&Default::default()).unwrap();
        let cols = model.anatomy().columns;
        let mut mesh = model.mesh;
        add_saliva_sets(&mut mesh, &cols);
        let saliva = mesh.element_sets["saliva"].clone();
        let sets: Vec<&Vec<u32>> = Zone::THIRDS
            .iter()
            .map(|z| &mesh.element_sets[&format!("saliva_{}", z.name())])
            .collect();
        let mut all: Vec<u32> = sets.iter().flat_map(|s| s.iter().copied()).collect();
        all.sort_unstable();
        assert_eq!(all, saliva, "every saliva element in exactly one zone");
        let x = |e: u32| {
            mesh.element_coords(e as usize)
                .iter()
                .map(|p| p[0])
                .sum::<f64>()
                / 8.0
        };
        let range = |s: &Vec<u32>| {
            assert!(!s.is_empty());
            s.iter()
                .map(|&e| x(e))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                    (a.min(v), b.max(v))
                })
        };
        let (l, c, r) = (range(sets[0]), range(sets[1]), range(sets[2]));
        assert!(
            l.0 > c.1 && c.0 > r.1,
            "left {l:?} centre {c:?} right {r:?}"
        );
    }

    /// A scenario on the procedural mouth gives each third its own saliva material and
    /// `[[saliva]]` table: every element of `saliva_ZONE` gets that zone's material, whose
    /// saliva set carries its `k_glue`; no saliva element is left with the tissue.
    #[test]
    fn a_scenario_gives_each_zone_its_own_glue() {
        let mut text = String::from(
            "[mesh]\ngenerator = \"mouth\"\n\
             [[materials]]\nname = \"tissue\"\nmu = 800.0\nK = 7000.0\ndensity = 1050.0\n",
        );
        let glue = [0.05, 0.1, 0.2];
        for (z, k) in Zone::THIRDS.iter().zip(glue) {
            let n = z.name();
            text += &format!(
                "[[materials]]\nname = \"saliva_{n}\"\nelements = \"saliva_{n}\"\nmu = 7700.0\n\
                 K = 191000.0\ndensity = 1050.0\n\
                 [[saliva]]\nmaterial = \"saliva_{n}\"\ncritical_moisture = 100.0\n\
                 initial_moisture = 90.0\nk_glue = {k}\n"
            );
        }
        text += "[[fix]]\nnodes = \"skull\"\n[time]\ndt = 1e-5\ntotal = 1e-4\n";
        let p = crate::io::scenario::parse(&text, std::path::Path::new("zones.toml"))
            .unwrap()
            .problem;
        assert_eq!(p.physics.saliva.len(), 3);
        for (i, (z, k)) in Zone::THIRDS.iter().zip(glue).enumerate() {
            let set = &p.mesh.element_sets[&format!("saliva_{}", z.name())];
            let m = p.physics.saliva[i].material;
            assert_eq!(p.materials[m as usize].name, format!("saliva_{}", z.name()));
            assert!(set.iter().all(|&e| p.element_material[e as usize] == m));
            assert_eq!(p.physics.saliva[i].params.k_glue, k);
        }
        let tissue = 0;
        assert!(p.mesh.element_sets["saliva"]
            .iter()
            .all(|&e| p.element_material[e as usize] != tissue));
    }

    #[test]
    fn zone_names_round_trip() {
        for z in [Zone::Left, Zone::Centre, Zone::Right, Zone::All] {
            assert_eq!(Zone::from_name(z.name()), Some(z));
        }
        assert_eq!(Zone::from_name("center"), Some(Zone::Centre));
        assert_eq!(Zone::from_name("middle"), None);
    }
}
