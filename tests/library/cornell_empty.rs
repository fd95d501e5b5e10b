//! The built-in `cornell-empty` (the paper's scene, SPEC §4): the five walls
//! and the light of `cornell`, same albedos, light and camera, no blocks.

use adaptive_pm::scene::{builtin_names, Light, Scene, BUILTIN_CORNELL, BUILTIN_CORNELL_EMPTY};

#[test]
fn empty_box_is_the_classic_box_without_its_blocks() {
    let empty = Scene::open(BUILTIN_CORNELL_EMPTY).unwrap();
    let full = Scene::open(BUILTIN_CORNELL).unwrap();
    assert_eq!(empty.triangle_count(), 12, "5 walls + the light, 2 each");
    assert_eq!(empty.lights().len(), 1);
    assert!(matches!(empty.lights()[0], Light::Area(_)));
    assert_eq!(empty.camera(), full.camera());
    assert!(empty.camera().is_some());
    assert_eq!(
        empty.materials(),
        full.materials(),
        "same albedos and light"
    );
    // every mesh of the empty box is the same mesh in the full box
    for m in empty.meshes() {
        let twin = full.meshes().iter().find(|f| f.name == m.name).unwrap();
        assert_eq!(m, twin, "{}", m.name);
    }
    let names: Vec<&str> = full.meshes().iter().map(|m| m.name.as_str()).collect();
    // Mesh names carry their primitive index (`tall_block#0`).
    assert!(names.iter().any(|n| n.starts_with("tall_block")));
    assert!(names.iter().any(|n| n.starts_with("short_block")));
    assert!(empty.meshes().iter().all(|m| !m.name.contains("block")));
    match (&empty.lights()[0], &full.lights()[0]) {
        (Light::Area(a), Light::Area(b)) => {
            assert_eq!(a.area, b.area);
            assert_eq!(a.emission, b.emission);
        }
        _ => unreachable!("checked above"),
    }
}

#[test]
fn a_bad_name_lists_the_built_in_scenes() {
    let e = Scene::open("cornell-emtpy").unwrap_err().to_string();
    for n in builtin_names() {
        assert!(e.contains(n), "{e}");
    }
    assert!(e.contains("cornell-emtpy"), "{e}");
}
