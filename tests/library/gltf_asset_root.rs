//! The asset root (`LoadOptions::asset_root`): a scene in `root/scenes/`
//! whose buffer is `../buffers/geo.bin` and whose image is
//! `../textures/white.png` loads with the root set to `root` and is refused
//! without it; a URI that climbs out of the root, or a symbolic link that
//! points out of it, is refused naming the URI and the root; the scene file
//! must lie inside the root.

use crate::gltf_textures::png_rgb;
use adaptive_pm::error::Error;
use adaptive_pm::scene::{LoadOptions, Scene};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

use crate::gltf_doc::{square, Doc};

/// A floor and a lamp, their geometry in one buffer.
fn floor_and_lamp() -> Doc {
    let mut doc = Doc::default();
    let white = doc.material(json!({"name": "white", "pbrMetallicRoughness":
        {"baseColorFactor": [0.5, 0.5, 0.5, 1.0], "metallicFactor": 0.0}}));
    let lamp = doc.material(json!({"name": "lamp", "emissiveFactor": [1.0, 1.0, 1.0],
        "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0}}));
    let (p, i) = square(2.0, true);
    let floor = doc.mesh(&p, &i, 4, Some(white));
    doc.node(json!({ "mesh": floor }));
    let (p, i) = square(0.25, false);
    let light = doc.mesh(&p, &i, 4, Some(lamp));
    doc.node(json!({"mesh": light, "translation": [0.0, 1.0, 0.0]}));
    doc
}

/// A tree `root/scenes/scene.gltf` whose buffer is the file `buffer_uri`
/// names (written at `root/buffers/geo.bin`); returns the root and the scene.
fn asset_tree(dir: &Path, buffer_uri: &str) -> (PathBuf, PathBuf) {
    let root = dir.join("root");
    for sub in ["scenes", "buffers", "textures"] {
        std::fs::create_dir_all(root.join(sub)).unwrap();
    }
    let doc = floor_and_lamp();
    std::fs::write(root.join("buffers/geo.bin"), &doc.bin).unwrap();
    let scene = doc.write(&root.join("scenes"));
    edit(&scene, |v| v["buffers"][0]["uri"] = json!(buffer_uri));
    (root, scene)
}

fn edit(path: &Path, change: impl FnOnce(&mut Value)) {
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    change(&mut v);
    std::fs::write(path, v.to_string()).unwrap();
}

fn rooted(root: &Path) -> LoadOptions {
    LoadOptions::default().with_asset_root(root)
}

fn refusal(scene: &Path, options: &LoadOptions) -> String {
    match Scene::load_with(scene, options) {
        Ok(_) => panic!("{} loaded", scene.display()),
        Err(e) => e.to_string(),
    }
}

fn assert_has(msg: &str, words: &[&str]) {
    for w in words {
        assert!(msg.contains(w), "`{msg}` lacks `{w}`");
    }
}

#[test]
fn a_buffer_in_a_sibling_folder_loads_with_the_root_and_not_without() {
    let dir = tempfile::tempdir().unwrap();
    let (root, scene) = asset_tree(dir.path(), "../buffers/geo.bin");
    let loaded = Scene::load_with(&scene, &rooted(&root)).unwrap();
    assert_eq!(loaded.triangle_count(), 4);
    assert_eq!(loaded.lights().len(), 1);
    // Percent-encoded and with dot segments, the same file.
    edit(&scene, |v| {
        v["buffers"][0]["uri"] = json!("./../scenes/../%62uffers/geo.bin")
    });
    assert_eq!(
        Scene::load_with(&scene, &rooted(&root))
            .unwrap()
            .triangle_count(),
        4
    );
    // Without a root, the scene's own folder is the root.
    let folder = root.join("scenes");
    let msg = refusal(&scene, &LoadOptions::default());
    assert_has(
        &msg,
        &[
            "buffer 0 uri `./../scenes/../%62uffers/geo.bin`",
            "leaves the asset root",
            &format!("`{}` (the scene file's folder)", folder.display()),
        ],
    );
    assert_eq!(msg, Scene::load(&scene).unwrap_err().to_string());
}

#[test]
fn a_uri_that_climbs_out_of_the_root_is_refused_naming_it_and_the_root() {
    let dir = tempfile::tempdir().unwrap();
    let (root, scene) = asset_tree(dir.path(), "../../outside.bin");
    // The file exists: only the root keeps it from being read.
    std::fs::write(dir.path().join("outside.bin"), floor_and_lamp().bin).unwrap();
    let msg = refusal(&scene, &rooted(&root));
    assert_has(
        &msg,
        &[
            "buffer 0 uri `../../outside.bin`",
            "leaves the asset root",
            &format!("`{}`", root.display()),
        ],
    );
    assert!(!msg.contains("scene file's folder"), "{msg}");
    // A root one level up reads it.
    assert!(Scene::load_with(&scene, &rooted(dir.path())).is_ok());
}

#[test]
fn a_symbolic_link_out_of_the_root_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (root, scene) = asset_tree(dir.path(), "../buffers/link.bin");
    let outside = dir.path().join("outside.bin");
    std::fs::write(&outside, floor_and_lamp().bin).unwrap();
    std::os::unix::fs::symlink(&outside, root.join("buffers/link.bin")).unwrap();
    let msg = refusal(&scene, &rooted(&root));
    assert_has(
        &msg,
        &[
            "buffer 0 uri `../buffers/link.bin`",
            "resolves outside the asset root",
            &format!("`{}`", root.display()),
        ],
    );
    // A link that stays inside is followed.
    std::fs::remove_file(root.join("buffers/link.bin")).unwrap();
    std::os::unix::fs::symlink(root.join("buffers/geo.bin"), root.join("buffers/link.bin"))
        .unwrap();
    assert!(Scene::load_with(&scene, &rooted(&root)).is_ok());
    // A root reached through a link is the folder it points to.
    let alias = dir.path().join("alias");
    std::os::unix::fs::symlink(&root, &alias).unwrap();
    assert!(Scene::load_with(alias.join("scenes/scene.gltf"), &rooted(&alias)).is_ok());
}

#[test]
fn an_image_in_a_sibling_folder_is_read_inside_the_root() {
    let dir = tempfile::tempdir().unwrap();
    let (root, scene) = asset_tree(dir.path(), "../buffers/geo.bin");
    let png = png_rgb(1, 1, &[[255; 3]]);
    std::fs::write(root.join("textures/white.png"), &png).unwrap();
    let uv = [[0.0f32, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    let uv_bytes: Vec<u8> = uv.iter().flatten().flat_map(|c| c.to_le_bytes()).collect();
    std::fs::write(root.join("buffers/uv.bin"), &uv_bytes).unwrap();
    edit(&scene, |v| {
        v["buffers"]
            .as_array_mut()
            .unwrap()
            .push(json!({"uri": "../buffers/uv.bin", "byteLength": uv_bytes.len()}));
        v["bufferViews"]
            .as_array_mut()
            .unwrap()
            .push(json!({"buffer": 1, "byteLength": uv_bytes.len()}));
        let view = v["bufferViews"].as_array().unwrap().len() - 1;
        v["accessors"]
            .as_array_mut()
            .unwrap()
            .push(json!({"bufferView": view, "componentType": 5126, "count": 4, "type": "VEC2"}));
        let accessor = v["accessors"].as_array().unwrap().len() - 1;
        v["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(accessor);
        v["images"] = json!([{"uri": "../textures/white.png"}]);
        v["textures"] = json!([{"source": 0}]);
        v["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
    });
    let loaded = Scene::load_with(&scene, &rooted(&root)).unwrap();
    assert_eq!(loaded.meshes()[0].texcoords[0].len(), 4);
    edit(&scene, |v| v["images"][0]["uri"] = json!("../../white.png"));
    let msg = refusal(&scene, &rooted(&root));
    assert_has(
        &msg,
        &["image 0", "`../../white.png`", "leaves the asset root"],
    );
}

#[test]
fn the_scene_file_must_lie_inside_its_root() {
    let dir = tempfile::tempdir().unwrap();
    let (root, scene) = asset_tree(dir.path(), "../buffers/geo.bin");
    let msg = refusal(&scene, &rooted(&root.join("buffers")));
    assert_has(
        &msg,
        &["scene.gltf", "is not inside the asset root", "buffers"],
    );
    let msg = refusal(&scene, &rooted(&root.join("buffers/geo.bin")));
    assert_has(&msg, &["geo.bin", "is not a folder"]);
    let missing = root.join("nowhere");
    match Scene::load_with(&scene, &rooted(&missing)) {
        Err(Error::Io { path, .. }) => assert_eq!(path, missing),
        other => panic!("a missing root: {other:?}"),
    }
    // A built-in scene reads no file: a root given with it is a mistake.
    let e = Scene::open_with("cornell", &rooted(&root)).unwrap_err();
    assert_has(&e.to_string(), &["built-in scene `cornell`", "asset root"]);
}
