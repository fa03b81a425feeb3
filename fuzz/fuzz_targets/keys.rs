//! A keys file (a load curve's `keys_file`), CSV or JSON, as `io::keys::parse_keys` reads it,
//! then made into the curve a scenario keeps (`Keyframes::new`). The text chooses the format
//! (JSON when its first character is `[` or `{`, as in `parse_keys`), so one target feeds
//! both; the input's first byte chooses `keys_fps` (byte % 8: none, 24, 30, 1e-3, 1e6, and
//! the refused 0, NaN and 2e6), the rest is the file.
//!
//! Must hold: an error or keys, never a panic, an abort or a hang; keys that are returned are
//! finite and not none; a curve made of them has its times strictly increasing (the order is
//! checked there, not by the reader, which keeps the file's order).
#![no_main]
use libfuzzer_sys::fuzz_target;
use sticky_lips::boundary::Keyframes;
use sticky_lips::io::keys::parse_keys;

const FPS: [Option<f64>; 8] = [
    None,
    Some(24.0),
    Some(30.0),
    Some(1e-3),
    Some(1e6),
    Some(0.0),
    Some(f64::NAN),
    Some(2e6),
];

fuzz_target!(|data: &[u8]| {
    let Some((&choice, rest)) = data.split_first() else {
        return;
    };
    let Ok(text) = std::str::from_utf8(rest) else {
        return;
    };
    let fps = FPS[choice as usize % FPS.len()];
    let Ok(keys) = parse_keys(text, "fuzz/keys.csv", fps) else {
        return;
    };
    assert!(!keys.is_empty());
    assert!(
        keys.iter().all(|(t, v)| t.is_finite() && v.is_finite()),
        "keys not finite at {fps:?} fps: {keys:?}"
    );
    if let Ok(k) = Keyframes::new(keys) {
        assert!(k.keys().windows(2).all(|w| w[0].0 < w[1].0));
        assert!(k.keys().iter().all(|(t, v)| t.is_finite() && v.is_finite()));
    }
});
