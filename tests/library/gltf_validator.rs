//! The loader against the Khronos glTF-Validator, file by file: every
//! `.gltf` and `.glb` in the repository, with the verdicts that
//! `scripts/ci-gltf-validator.sh` wrote (one JSON line per file).
//!
//! The rule: a file the validator calls valid loads, or is refused with an
//! error that names an unsupported feature, or is on [`VALID_BUT_REFUSED`]
//! with the reason; a file it calls invalid is refused, or is on
//! [`INVALID_BUT_ACCEPTED`] with the reason.
//!
//! `scripts/test.sh` runs the validator, then this test:
//! `ADAPTIVE_PM_GLTF_VALIDATOR_REPORT=target/gltf-validator.jsonl cargo test --test library gltf_validator -- --ignored`.

use adaptive_pm::scene::Scene;
use std::path::Path;

/// Valid glTF that the loader refuses on purpose, and why.
const VALID_BUT_REFUSED: &[(&str, &str)] = &[
    (
        "tests/hostile/camera_at_1e20.gltf",
        "a coordinate beyond MAX_COORDINATE: Embree aborts on rays that far out",
    ),
    (
        "tests/hostile/vertex_at_1e20.gltf",
        "a coordinate beyond MAX_COORDINATE: Embree aborts on rays that far out",
    ),
    (
        "tests/hostile/point_light_at_1e20.gltf",
        "a coordinate beyond MAX_COORDINATE: Embree aborts on rays that far out",
    ),
    (
        "tests/hostile/transform_overflow.gltf",
        "the world transform overflows f32 to infinity",
    ),
    (
        "tests/hostile/degenerate_only_mesh.gltf",
        "a mesh of zero-area triangles only: nothing to trace",
    ),
    (
        "tests/hostile/spot_light_scale_0.gltf",
        "a zero scale leaves the spot light without an axis",
    ),
];

/// Invalid glTF that the loader accepts, and why (none today).
const INVALID_BUT_ACCEPTED: &[(&str, &str)] = &[];

#[test]
#[ignore = "needs the validator's report: scripts/ci-gltf-validator.sh, run by scripts/test.sh"]
fn the_loader_follows_the_khronos_validators_verdicts() {
    let var = "ADAPTIVE_PM_GLTF_VALIDATOR_REPORT";
    let report = std::env::var(var).unwrap_or_else(|_| panic!("{var} names no report"));
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join(&report)).unwrap();
    let mut checked = 0;
    let mut broken = Vec::new();
    for line in text.lines().filter(|l| !l.trim().is_empty()) {
        let v: serde_json::Value = serde_json::from_str(line).unwrap();
        let file = v["path"].as_str().unwrap();
        let valid = v["valid"].as_bool().unwrap();
        let listed = |list: &[(&str, &str)]| list.iter().any(|(f, _)| *f == file);
        let loaded = Scene::load(root.join(file));
        let ok = match (&loaded, valid) {
            (Ok(_), true) => true,
            (Err(e), true) => e.to_string().contains("not supported") || listed(VALID_BUT_REFUSED),
            (Err(_), false) => true,
            (Ok(_), false) => listed(INVALID_BUT_ACCEPTED),
        };
        if !ok {
            let outcome = match loaded {
                Ok(_) => "loaded".to_string(),
                Err(e) => format!("refused: {e}"),
            };
            broken.push(format!(
                "{file}: validator valid={valid} {}, loader {outcome}",
                v["codes"]
            ));
        }
        checked += 1;
    }
    assert!(checked >= 30, "the report lists only {checked} files");
    assert!(
        broken.is_empty(),
        "{} files break the rule:\n{}",
        broken.len(),
        broken.join("\n")
    );
}
