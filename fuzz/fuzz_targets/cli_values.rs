//! The command line's values (`--threads`, `--checkpoint-every`, `--up`, `--direction`,
//! `--shape`, `--group`): an error or a valid value (a count >= 1, finite numbers).
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
});
