//! Fuzz target for environment maps: the input is decoded as a Radiance
//! .hdr and as an .exr (`EnvironmentImage::from_bytes`). Every outcome must
//! be `Ok` or a `SceneError` naming the file; a panic, hang or abort is a
//! bug.
#![no_main]

use himal::scene::{EnvironmentDesc, EnvironmentFormat, EnvironmentImage};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    for (name, format) in [
        ("input.hdr", EnvironmentFormat::Hdr),
        ("input.exr", EnvironmentFormat::Exr),
    ] {
        let desc = EnvironmentDesc::new(name);
        if let Err(e) = EnvironmentImage::from_bytes(&desc, data, format) {
            assert!(e.to_string().contains(name), "error without the file: {e}");
        }
    }
});
