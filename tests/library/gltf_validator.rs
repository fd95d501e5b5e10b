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
//! `ADAPTIVE_PM_GLTF_VALIDATOR_REPORT=target/gltf-validator.jsonl cargo test --test library gltf_validator::the_loader_follows -- --ignored`.
//! The documents that tests write at run time are held to the same rule
//! (their lists keyed by the test that wrote them):
//! `scripts/ci-gltf-validator-generated.sh`, also run by `scripts/test.sh`.

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

/// Generated documents (tests/library/gltf_doc.rs, dumped by
/// `scripts/ci-gltf-validator-generated.sh` as `TEST-RANK.gltf`) that the
/// validator calls valid and the loader refuses on purpose, by the test
/// that wrote them (a prefix of the file name), and why.
const GENERATED_VALID_BUT_REFUSED: &[(&str, &str)] = &[
    (
        "gltf_conformance__bad_gpu_instances_are_refused_by_name-1",
        "EXT_mesh_gpu_instancing attributes of two counts: the extension asks for one, and \
         the validator does not check this extension",
    ),
    (
        "gltf_conformance__bad_gpu_instances_are_refused_by_name-3",
        "an EXT_mesh_gpu_instancing attribute naming no accessor: the validator does not \
         check this extension",
    ),
    (
        "gltf_conformance__bad_gpu_instances_are_refused_by_name-5",
        "2^21 GPU instances: over the loader's bound on the node instances a scene \
         expands to",
    ),
    (
        "gltf_conformance__bad_gpu_instances_are_refused_by_name-6",
        "700 000 GPU instances of 32 triangles: over the loader's bound on the triangles \
         a scene expands to",
    ),
    (
        "gltf_textures__bad_texture_data_is_refused_by_name-5",
        "a sampler's wrapS of 1234, not a glTF wrap mode: the validator only warns \
         (VALUE_NOT_IN_LIST), and the loader will not guess a wrap mode",
    ),
    (
        "gltf_alpha_mask_refusals__bad_cutoffs_masked_emitters_and_masked_glass_are_refused_by_name-2",
        "an alphaCutoff of 1e300, finite for the validator's doubles, is infinite in f32",
    ),
    (
        "gltf_alpha_mask_refusals__bad_cutoffs_masked_emitters_and_masked_glass_are_refused_by_name-6",
        "refracting glass (a KHR_materials_volume thickness) with MASK holes: a refracting \
         mesh must be closed to have an inside",
    ),
    (
        "gltf_textures__a_webp_texture_prefers_its_png_source_and_a_broken_webp_is_refused-2",
        "a WebP image cut short: the validator reads its header, not its bitstream",
    ),
];

/// Generated documents the validator calls invalid and the loader accepts.
const GENERATED_INVALID_BUT_ACCEPTED: &[(&str, &str)] = &[];

/// A list of files (or of the tests that wrote them) with the reason each
/// is an exception.
type Exceptions<'a> = &'a [(&'a str, &'a str)];

/// The files of the report named by `var` that break the rule (module
/// docs), with `listed(file, list)` saying whether a file is on a list; and
/// how many files the report names.
fn broken_files(
    var: &str,
    (valid_but_refused, invalid_but_accepted): (Exceptions, Exceptions),
    listed: fn(&str, Exceptions) -> bool,
) -> (Vec<String>, usize) {
    let report = std::env::var(var).unwrap_or_else(|_| panic!("{var} names no report"));
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join(&report)).unwrap();
    let mut checked = 0;
    let mut broken = Vec::new();
    for line in text.lines().filter(|l| !l.trim().is_empty()) {
        let v: serde_json::Value = serde_json::from_str(line).unwrap();
        let file = v["path"].as_str().unwrap();
        let valid = v["valid"].as_bool().unwrap();
        let loaded = Scene::load(root.join(file));
        let ok = match (&loaded, valid) {
            (Ok(_), true) => true,
            (Err(e), true) => {
                e.to_string().contains("not supported") || listed(file, valid_but_refused)
            }
            (Err(_), false) => true,
            (Ok(_), false) => listed(file, invalid_but_accepted),
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
    (broken, checked)
}

fn assert_none_broken(broken: &[String]) {
    assert!(
        broken.is_empty(),
        "{} files break the rule:\n{}",
        broken.len(),
        broken.join("\n")
    );
}

#[test]
#[ignore = "needs the validator's report: scripts/ci-gltf-validator.sh, run by scripts/test.sh"]
fn the_loader_follows_the_khronos_validators_verdicts() {
    let lists = (VALID_BUT_REFUSED, INVALID_BUT_ACCEPTED);
    let by_path = |file: &str, list: Exceptions| list.iter().any(|(f, _)| *f == file);
    let (broken, checked) = broken_files("ADAPTIVE_PM_GLTF_VALIDATOR_REPORT", lists, by_path);
    assert!(checked >= 30, "the report lists only {checked} files");
    assert_none_broken(&broken);
}

#[test]
#[ignore = "needs the generated documents' report: scripts/ci-gltf-validator-generated.sh"]
fn generated_documents_follow_the_khronos_validators_verdicts() {
    let lists = (GENERATED_VALID_BUT_REFUSED, GENERATED_INVALID_BUT_ACCEPTED);
    let by_test = |file: &str, list: Exceptions| {
        let name = Path::new(file)
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or("");
        list.iter().any(|(prefix, _)| name.starts_with(prefix))
    };
    let var = "ADAPTIVE_PM_GLTF_VALIDATOR_GENERATED_REPORT";
    let (broken, checked) = broken_files(var, lists, by_test);
    assert!(checked >= 20, "the report lists only {checked} files");
    assert_none_broken(&broken);
}
