//! What a model of a given size needs in memory, checked before it is built: a mesh
//! generator asked for more than the machine can hold refuses with the field and the
//! numbers instead of aborting on its first allocation.
//!
//! The estimate is the peak resident memory of a `run` in `f64` (mesh, discretisation, the
//! stepping arrays, the stability analysis, the frame writer), measured on blocks of
//! 64 000 and 216 000 hexahedra (150 MB and 512 MB, 2026-12-01) and fitted per element and
//! per node. Indices are 32-bit, so no model may have 2^32 nodes or elements or more.

use crate::error::{Error, Result};

/// Bytes a run holds per hexahedron (fitted, see the module documentation).
pub const BYTES_PER_ELEMENT: u128 = 1600;
/// Bytes a run holds per node.
pub const BYTES_PER_NODE: u128 = 700;

/// The memory the operating system says is available to a new allocation, if known: through
/// the `sysinfo` crate, on Linux (`MemAvailable`, and the free part of the process's cgroup
/// limit where that is smaller), macOS (`host_statistics64`) and Windows
/// (`GlobalMemoryStatusEx`). `None` where the platform reports nothing.
pub fn available_bytes() -> Option<u128> {
    let mut sys = sysinfo::System::new().ok()?;
    sys.refresh_memory_specifics(sysinfo::MemoryRefreshKind::nothing().with_ram());
    let mut have = sys.available_memory();
    if let Some(cg) = sys.cgroup_limits() {
        have = have.min(cg.free_memory);
    }
    (have > 0).then_some(have as u128)
}

/// The estimate for `nodes` nodes and `elements` hexahedra (bytes).
pub fn estimate(nodes: u128, elements: u128) -> u128 {
    nodes
        .saturating_mul(BYTES_PER_NODE)
        .saturating_add(elements.saturating_mul(BYTES_PER_ELEMENT))
}

fn gib(b: u128) -> String {
    format!("{:.2} GiB", b as f64 / (1u128 << 30) as f64)
}

/// Refuses a model of `nodes` nodes and `elements` hexahedra (counts computed without
/// overflow by the caller) that 32-bit indices cannot number or that would not fit in
/// `available` bytes (`None`: not known, only the index limit is checked). `field` names
/// what the user set (e.g. `mesh.cells`).
pub fn check_with(
    file: &str,
    field: &str,
    nodes: u128,
    elements: u128,
    available: Option<u128>,
) -> Result<()> {
    let limit = u32::MAX as u128;
    if nodes >= limit || elements >= limit {
        return Err(Error::field(
            file,
            field,
            format!(
                "gives {elements} hexahedra and {nodes} nodes; a model may have fewer than 2^32 of each"
            ),
        ));
    }
    let need = estimate(nodes, elements);
    if let Some(have) = available {
        if need > have {
            return Err(Error::field(
                file,
                field,
                format!(
                    "gives {elements} hexahedra and {nodes} nodes, which need about {} to run; {} are available (the machine's free memory, or {LIMIT_VARIABLE} where set)",
                    gib(need),
                    gib(have)
                ),
            ));
        }
    }
    Ok(())
}

/// The environment variable that lowers the memory a model may use below what the machine
/// has available (MiB): for a job on a shared node (a Slurm allocation, a container) and for
/// the fuzz targets.
pub const LIMIT_VARIABLE: &str = "STICKY_LIPS_MEMORY_MB";

/// The memory a model may use: the machine's available memory, or [`LIMIT_VARIABLE`] where
/// that is set and smaller. An unreadable value of the variable is ignored (the machine's).
pub fn limit_bytes() -> Option<u128> {
    let cap = std::env::var(LIMIT_VARIABLE)
        .ok()
        .and_then(|v| v.trim().parse::<u64>().ok())
        .map(|mb| mb as u128 * (1 << 20));
    match (available_bytes(), cap) {
        (Some(a), Some(c)) => Some(a.min(c)),
        (a, c) => a.or(c),
    }
}

/// Bytes the `face` command holds per hexahedron while it builds a model (peak resident
/// memory of `sticky-lips face` on the MakeHuman head at `--resolution` 16 and 36: 266 MB
/// for 53 504 hexahedra and 593 MB for 120 192, 2026-12-04, after the skin's quad grid
/// stopped growing with the square of the count): more than a run of the same model needs.
pub const FACE_BUILD_BYTES_PER_ELEMENT: u128 = 5000;

/// Refuses a face model of `elements` hexahedra whose build would not fit in `available`
/// bytes (the run's own need is checked by [`check_with`]).
pub fn check_face_build_with(
    file: &str,
    field: &str,
    elements: u128,
    available: Option<u128>,
) -> Result<()> {
    let need = elements.saturating_mul(FACE_BUILD_BYTES_PER_ELEMENT);
    match available {
        Some(have) if need > have => Err(Error::field(
            file,
            field,
            format!(
                "gives about {elements} hexahedra, whose build needs about {}; {} are available (the machine's free memory, or {LIMIT_VARIABLE} where set)",
                gib(need),
                gib(have)
            ),
        )),
        _ => Ok(()),
    }
}

/// [`check_with`] against [`limit_bytes`].
pub fn check(file: &str, field: &str, nodes: u128, elements: u128) -> Result<()> {
    check_with(file, field, nodes, elements, limit_bytes())
}

/// Nodes and hexahedra of a block of `cells`, without overflow.
pub fn block_counts(cells: [usize; 3]) -> (u128, u128) {
    let [x, y, z] = cells.map(|c| c as u128);
    (
        (x + 1).saturating_mul(y + 1).saturating_mul(z + 1),
        x.saturating_mul(y).saturating_mul(z),
    )
}

/// Nodes and hexahedra of a quad surface of `quads` quads on a grid of `columns` x `rows`
/// quads, extruded into one layer (two layers of nodes).
pub fn extruded_grid_counts(columns: f64, rows: f64) -> (u128, u128) {
    let q = |x: f64| x.clamp(0.0, 1e30) as u128;
    let (c, r) = (q(columns), q(rows));
    (
        2u128.saturating_mul((c + 1).saturating_mul(r + 1)),
        c.saturating_mul(r),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_do_not_overflow() {
        let (n, e) = block_counts([usize::MAX, 2, 2]);
        assert!(n > u32::MAX as u128 && e > u32::MAX as u128);
        assert_eq!(block_counts([2, 3, 4]), (60, 24));
        assert_eq!(extruded_grid_counts(4.0, 2.0), (30, 8));
    }

    #[test]
    fn refuses_what_does_not_fit_and_says_so() {
        let have = Some(1u128 << 30);
        check_with("f.toml", "mesh.cells", 1000, 1000, have).unwrap();
        let e = check_with("f.toml", "mesh.cells", 1 << 20, 1 << 20, have)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("field `mesh.cells`") && e.contains("1.00 GiB are available"),
            "{e}"
        );
        let e = check_with("f.toml", "mesh.cells", 1 << 33, 1, None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("fewer than 2^32"), "{e}");
        // the index limit holds even where the available memory is not known
        check_with("f.toml", "mesh.cells", 1 << 31, 1, None).unwrap();
    }

    #[test]
    fn a_face_build_needs_more_than_its_run() {
        let have = Some(800u128 << 20);
        // 60 000 hexahedra: about 180 MB to run, about 300 MB to build: both fit
        check_with("c", "--resolution", 120_000, 60_000, have).unwrap();
        check_face_build_with("c", "--resolution", 60_000, have).unwrap();
        // 200 000: about 0.6 GB to run fits, about 1 GB to build does not
        check_with("c", "--resolution", 400_000, 200_000, have).unwrap();
        let e = check_face_build_with("c", "--resolution", 200_000, have)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("`--resolution`") && e.contains("build needs"),
            "{e}"
        );
        check_face_build_with("c", "--resolution", u128::MAX, None).unwrap();
    }
}
