//! The command line's values (`--threads`, `--checkpoint-every`, `--up`, `--direction`,
//! `--shape`, `--group`, the ranged numbers of `evaporation`): an error or a valid value (a
//! count >= 1, finite numbers, a number inside its range).
#![no_main]
use libfuzzer_sys::fuzz_target;
use sticky_lips::io::args;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(n) = args::count(text, "thread") {
        assert!(n >= 1);
    }
    if let Ok(v) = args::vec3(text, "--up") {
        assert!(v.iter().all(|x| x.is_finite()));
    }
    if let Ok((name, w)) = args::name_value(text, "--shape", "PATH.vtu=WEIGHT") {
        assert!(!name.is_empty() && w.is_finite());
    }
    if let Ok(h) = args::number_in(text, (0.0, true), (1.0, true), "a fraction") {
        assert!((0.0..=1.0).contains(&h));
    }
    if let Ok(t) = args::number_in(text, (-273.15, false), (1e3, true), "degrees Celsius") {
        assert!(t > -273.15 && t <= 1e3);
    }
});
