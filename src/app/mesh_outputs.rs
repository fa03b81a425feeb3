//! A hexahedral model's files for other software: `mesh.vtu` (the mesh with a `material`
//! cell array, one code per group in the order given) and `model.xml` (a NiftySim model
//! with Table 1's materials and timing), written by `face`, `mouth` and `extrude`.

use crate::io::niftysim;
use std::path::Path;

/// Writes `out/mesh.vtu` and `out/model.xml` for `mesh`, its elements grouped as `groups`
/// (a group named `saliva` gets Table 1's saliva, the others its tissue).
pub fn write(
    out: &Path,
    mesh: &crate::mesh::Mesh,
    groups: &[(String, Vec<u32>)],
) -> crate::Result<()> {
    use crate::error::Error;
    use crate::io::vtu::{write_vtu, DataArray, VtuFrame};
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    let mut material = vec![0i32; mesh.elements.len()];
    for (g, (_, els)) in groups.iter().enumerate() {
        for &e in els {
            material[e as usize] = g as i32;
        }
    }
    let zero = vec![0.0; 3 * mesh.nodes.len()];
    let frame = VtuFrame {
        points: &mesh.nodes,
        hexahedra: &mesh.elements,
        point_data: vec![DataArray::F64 {
            name: "displacement",
            components: 3,
            data: &zero,
        }],
        cell_data: vec![DataArray::I32 {
            name: "material",
            components: 1,
            data: &material,
        }],
        time: None,
    };
    let vtu = out.join("mesh.vtu");
    write_vtu(&vtu, &frame).map_err(|e| Error::io(&vtu, e))?;
    let sets: Vec<niftysim::SetMaterial> = groups
        .iter()
        .map(|(name, els)| {
            // meshes written without a scenario get Table 1's materials
            let m = if name == "saliva" {
                crate::problem::table1::SALIVA
            } else {
                crate::problem::table1::TISSUE
            };
            niftysim::SetMaterial {
                elements: els,
                mu: m.mu,
                bulk: m.bulk,
                density: m.density,
            }
        })
        .collect();
    use crate::problem::table1;
    niftysim::write_model(
        &out.join("model.xml"),
        mesh,
        &sets,
        table1::TIME_STEP,
        table1::TOTAL_TIME,
        table1::DAMPING,
        table1::HOURGLASS_KAPPA,
    )
}
