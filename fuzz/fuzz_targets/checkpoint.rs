//! A checkpoint file as `run --restart` reads it: decoded, and an accepted one re-encoded to
//! the same bytes.
#![no_main]
use libfuzzer_sys::fuzz_target;
use sticky_lips::io::checkpoint;

fuzz_target!(|data: &[u8]| {
    if let Ok((header, state)) = checkpoint::decode(data) {
        assert_eq!(checkpoint::encode(&header, &state), data);
    }
});
