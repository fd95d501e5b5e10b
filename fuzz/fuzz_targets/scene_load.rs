//! Scene loading from hostile bytes: `Scene::load` on a `.gltf`/`.glb` file
//! written into a scratch folder beside a small regular buffer file, so that
//! relative URIs, `..` escapes and absolute paths are all exercised. Any
//! panic, abort, hang or out-of-memory is a bug; an `Err` is the expected
//! answer to bad input.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::PathBuf;
use std::sync::OnceLock;

fn scratch() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("adaptive-pm-fuzz-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("scratch folder");
        // A buffer a fuzzed URI may legitimately name: one triangle.
        let tri: Vec<u8> = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
            .iter()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        std::fs::write(dir.join("tri.bin"), tri).expect("buffer file");
        dir
    })
}

fuzz_target!(|data: &[u8]| {
    let ext = if data.starts_with(b"glTF") { "glb" } else { "gltf" };
    let path = scratch().join(format!("scene.{ext}"));
    if std::fs::write(&path, data).is_ok() {
        if let Ok(scene) = adaptive_pm::scene::Scene::load(&path) {
            // A loaded scene must be traceable: its derived quantities are finite.
            let _ = scene.validate();
            let _ = scene.ray_epsilon();
            for l in scene.lights() {
                assert!(l.power().is_finite());
            }
        }
    }
});
