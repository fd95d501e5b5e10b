//! Helpers shared by the test binaries (each binary compiles its own copy
//! and uses part of it).
#![allow(dead_code)]

/// An error's message followed by its sources', `: `-separated.
pub fn chain(e: &dyn std::error::Error) -> String {
    let mut msg = e.to_string();
    let mut src = e.source();
    while let Some(s) = src {
        msg += &format!(": {s}");
        src = s.source();
    }
    msg
}

/// Overwrites the four i32 of the box2i attribute `name` in EXR `bytes`.
pub fn set_exr_box(bytes: &mut [u8], name: &str, b: [i32; 4]) {
    let key = format!("{name}\0box2i\0");
    let at = bytes
        .windows(key.len())
        .position(|w| w == key.as_bytes())
        .unwrap()
        + key.len()
        + 4;
    for (i, v) in b.iter().enumerate() {
        bytes[at + 4 * i..at + 4 * i + 4].copy_from_slice(&v.to_le_bytes());
    }
}

/// Makes a 1 KB EXR file (a copy of `bytes`) claim `side` x `side` pixels
/// in 64 x 64 blocks, the count its decoder checks against the size.
pub fn claim_exr_size(bytes: &mut [u8], side: i32) {
    let b = [0, 0, side - 1, side - 1];
    set_exr_box(bytes, "displayWindow", b);
    set_exr_box(bytes, "dataWindow", b);
    let blocks = ((side + 63) / 64).pow(2);
    let key = b"chunkCount\0int\0";
    let at = bytes.windows(key.len()).position(|w| w == key).unwrap() + key.len() + 4;
    bytes[at..at + 4].copy_from_slice(&blocks.to_le_bytes());
}
