//! Mesh generators for verification: boxes of hexahedra and randomly distorted patches.

use super::Mesh;

/// A deterministic 64-bit generator (SplitMix64), so generated meshes are identical
/// everywhere without depending on a random-number crate's version.
#[derive(Clone, Debug)]
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in `[-1, 1)`.
    pub fn symmetric(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

/// A box `[origin, origin + size]` split into `cells` hexahedra.
///
/// Node `(i, j, k)` has index `i + (nx + 1) (j + (ny + 1) k)`. Node sets `x_min`, `x_max`,
/// `y_min`, `y_max`, `z_min`, `z_max` (the faces), `boundary`, `interior`; element set `all`.
pub fn block(origin: [f64; 3], size: [f64; 3], cells: [usize; 3]) -> Mesh {
    let [nx, ny, nz] = cells;
    let idx = |i: usize, j: usize, k: usize| (i + (nx + 1) * (j + (ny + 1) * k)) as u32;
    let mut nodes = Vec::with_capacity((nx + 1) * (ny + 1) * (nz + 1));
    for k in 0..=nz {
        for j in 0..=ny {
            for i in 0..=nx {
                nodes.push([
                    origin[0] + size[0] * i as f64 / nx as f64,
                    origin[1] + size[1] * j as f64 / ny as f64,
                    origin[2] + size[2] * k as f64 / nz as f64,
                ]);
            }
        }
    }
    let mut elements = Vec::with_capacity(nx * ny * nz);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                elements.push([
                    idx(i, j, k),
                    idx(i + 1, j, k),
                    idx(i + 1, j + 1, k),
                    idx(i, j + 1, k),
                    idx(i, j, k + 1),
                    idx(i + 1, j, k + 1),
                    idx(i + 1, j + 1, k + 1),
                    idx(i, j + 1, k + 1),
                ]);
            }
        }
    }
    let mut mesh = Mesh {
        nodes,
        elements,
        ..Default::default()
    };
    let mut sets: [Vec<u32>; 8] = Default::default();
    for k in 0..=nz {
        for j in 0..=ny {
            for i in 0..=nx {
                let n = idx(i, j, k);
                let flags = [i == 0, i == nx, j == 0, j == ny, k == 0, k == nz];
                for (s, f) in flags.iter().enumerate() {
                    if *f {
                        sets[s].push(n);
                    }
                }
                if flags.iter().any(|f| *f) {
                    sets[6].push(n);
                } else {
                    sets[7].push(n);
                }
            }
        }
    }
    let names = [
        "x_min", "x_max", "y_min", "y_max", "z_min", "z_max", "boundary", "interior",
    ];
    for (name, set) in names.iter().zip(sets) {
        mesh.node_sets.insert(name.to_string(), set);
    }
    mesh.element_sets
        .insert("all".into(), (0..mesh.elements.len() as u32).collect());
    mesh
}

/// A block whose interior nodes are moved by up to `fraction` of the local cell size in
/// each coordinate, uniformly at random from `seed` (faces stay planar). With
/// `fraction = 0.25` the elements are far from parallelepipeds, which is what the patch
/// test needs.
pub fn distorted_block(
    origin: [f64; 3],
    size: [f64; 3],
    cells: [usize; 3],
    fraction: f64,
    seed: u64,
) -> Mesh {
    let mut mesh = block(origin, size, cells);
    let h = [
        size[0] / cells[0] as f64,
        size[1] / cells[1] as f64,
        size[2] / cells[2] as f64,
    ];
    let mut rng = SplitMix64(seed);
    let interior = mesh.node_sets["interior"].clone();
    for n in interior {
        for (i, hi) in h.iter().enumerate() {
            mesh.nodes[n as usize][i] += fraction * hi * rng.symmetric();
        }
    }
    mesh
}

/// One layer of a [`layered_block`]: its thickness along z (m), its number of cells
/// through the thickness, and the name of its element set.
#[derive(Clone, Debug, PartialEq, serde::Deserialize)]
pub struct Layer {
    pub name: String,
    pub thickness: f64,
    pub cells: usize,
}

/// A block stacked from layers along z (bottom first), each its own element set, e.g. two
/// tissue slabs joined by a thin saliva layer. `size_xy`/`cells_xy` give the footprint.
/// Node sets as for [`block`] (`z_min` is the bottom of the first layer, `z_max` the top of
/// the last), plus `LAYER_bottom` and `LAYER_top` for each layer's bounding planes.
pub fn layered_block(
    origin: [f64; 3],
    size_xy: [f64; 2],
    cells_xy: [usize; 2],
    layers: &[Layer],
) -> Mesh {
    let nz: usize = layers.iter().map(|l| l.cells).sum();
    let total: f64 = layers.iter().map(|l| l.thickness).sum();
    let mut mesh = block(
        origin,
        [size_xy[0], size_xy[1], total],
        [cells_xy[0], cells_xy[1], nz],
    );
    // move node planes to the layer boundaries
    let mut z_planes = Vec::with_capacity(nz + 1);
    let mut z = origin[2];
    z_planes.push(z);
    for l in layers {
        for _ in 0..l.cells {
            z += l.thickness / l.cells as f64;
            z_planes.push(z);
        }
    }
    let per_plane = (cells_xy[0] + 1) * (cells_xy[1] + 1);
    for (n, x) in mesh.nodes.iter_mut().enumerate() {
        x[2] = z_planes[n / per_plane];
    }
    let per_layer_cells = cells_xy[0] * cells_xy[1];
    let mut k0 = 0;
    for l in layers {
        let first = k0 * per_layer_cells;
        let last = (k0 + l.cells) * per_layer_cells;
        mesh.element_sets
            .insert(l.name.clone(), (first as u32..last as u32).collect());
        mesh.node_sets.insert(
            format!("{}_bottom", l.name),
            (k0 * per_plane..(k0 + 1) * per_plane)
                .map(|n| n as u32)
                .collect(),
        );
        mesh.node_sets.insert(
            format!("{}_top", l.name),
            ((k0 + l.cells) * per_plane..(k0 + l.cells + 1) * per_plane)
                .map(|n| n as u32)
                .collect(),
        );
        k0 += l.cells;
    }
    mesh
}
