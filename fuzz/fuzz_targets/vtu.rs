//! A VTU frame as `blend` reads it: a point-data and a cell-data array.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    use sticky_lips::io::vtu::parse_array;
    if let Ok((v, comps, n)) = parse_array(text, "fuzz.vtu", "PointData", "displacement") {
        assert_eq!(v.len(), comps * n);
    }
    if let Ok((v, comps, n)) = parse_array(text, "fuzz.vtu", "CellData", "material") {
        assert_eq!(v.len(), comps * n);
    }
});
