//! An OBJ surface: read as polygons (what `face` reads), made quads and validated; read as a
//! quad surface (what `extrude` reads), extruded into hexahedra and validated.
#![no_main]
use libfuzzer_sys::fuzz_target;
#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    let Some(text) = common::text(data) else {
        return;
    };
    if let Ok(p) = sticky_lips::io::obj::parse_polygons(text, "fuzz.obj") {
        if p.validate("fuzz.obj").is_ok() {
            let _ = p.to_quads().surface.validate("fuzz.obj");
        }
    }
    let Ok(s) = sticky_lips::io::obj::parse_obj(text, "fuzz.obj") else {
        return;
    };
    use sticky_lips::mesh::extrude;
    let Ok(t) = extrude::group_thickness(&s, Some(0.001), &[], "fuzz.obj") else {
        return;
    };
    if let Ok(mesh) = extrude::extrude_with(&s, &|g| t[g], extrude::Direction::Normal, "fuzz.obj") {
        let _ = mesh.validate("fuzz.obj");
    }
});
