//! The command line as a user meets it: `--json` prints one object with the
//! documented keys, bad input exits non-zero with a message naming the
//! problem, and nothing panics.

use serde_json::Value;
use std::process::Command;

fn run(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_adaptive-pm"))
        .args(args)
        .output()
        .expect("the binary runs");
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(!stderr.contains("panicked"), "{args:?} panicked: {stderr}");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).to_string(),
        stderr,
    )
}

fn json(args: &[&str]) -> Value {
    let (code, out, err) = run(args);
    assert_eq!(code, 0, "{args:?}: {err}");
    // exactly one JSON object on stdout
    serde_json::from_str(out.trim()).unwrap_or_else(|e| panic!("{args:?}: {e}: {out}"))
}

#[test]
fn scene_json_lists_triangles_and_lights() {
    let v = json(&["scene", "cornell", "--json"]);
    assert_eq!(v["triangles"], 32);
    let l = &v["lights"][0];
    assert!((l["area"].as_f64().unwrap() - 13650.0).abs() < 0.1);
    assert_eq!(l["power"].as_array().unwrap().len(), 3);
}

#[test]
fn scene_names_a_materials_transmitted_part() {
    let file = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/blender_frosted.glb");
    let v = json(&["scene", file, "--json"]);
    let materials = v["materials"].as_array().unwrap();
    let frosted = materials.iter().find(|m| m["name"] == "frosted").unwrap();
    assert_eq!(frosted["transmitted"]["weight"], 0.5);
    let glass = &materials[frosted["transmitted"]["material"].as_u64().unwrap() as usize];
    assert_eq!(glass["name"], "frosted (transmitted part)");
    assert!(glass["brdf"]
        .as_str()
        .unwrap()
        .starts_with("rough-dielectric"));
    let floor = materials.iter().find(|m| m["name"] == "floor").unwrap();
    assert_eq!(floor["transmitted"], Value::Null);
    let (code, text, err) = run(&["scene", file]);
    assert_eq!(code, 0, "{err}");
    assert!(
        text.contains("transmits 0.5: `frosted (transmitted part)`"),
        "{text}"
    );
}

#[test]
fn scene_json_shows_a_directional_light() {
    let file = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/scenes/sun_floor.gltf");
    let v = json(&["scene", file, "--json"]);
    let sun = &v["lights"][0];
    assert_eq!(sun["kind"], "directional");
    let d: Vec<f64> = serde_json::from_value(sun["direction"].clone()).unwrap();
    let t = 30f64.to_radians();
    let want = [0.0, -t.cos(), -t.sin()];
    assert!(
        d.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-6),
        "{d:?}"
    );
    assert_eq!(sun["irradiance"].as_array().unwrap().len(), 3);
    let r = sun["disc_radius"].as_f64().unwrap();
    assert!((r - 2.5625f64.sqrt()).abs() < 1e-5, "{r}");
    assert_eq!(sun["area"], Value::Null);
    let (code, text, err) = run(&["scene", file]);
    assert_eq!(code, 0, "{err}");
    assert!(
        text.contains("directional") && text.contains("disc radius 1.6008"),
        "{text}"
    );
}

#[test]
fn trace_json_has_every_documented_key() {
    let v = json(&[
        "trace", "cornell", "--mode", "adaptive", "--n-max", "3000", "--cosn", "20", "--json",
    ]);
    for key in [
        "emitted",
        "emitted_per_light",
        "stored",
        "stored_primary",
        "reemitted_first_hit",
        "split_rate_by_depth",
        "max_density",
        "mean_density",
        "sigma_density",
        "max_density_primary",
        "mean_density_primary",
        "sigma_density_primary",
        "trace_s",
        // tools/trace_readme.py and tools/trace_rounds.py read these two.
        "rays",
        "rays_per_s",
        "build_s",
        "bytes_per_photon",
        "budget_bound",
        "stored_power",
        "checksum",
    ] {
        assert!(!v[key].is_null(), "missing {key}");
    }
    assert!(
        v["emitted"].as_u64().unwrap() < 3000,
        "a cos^20 light emits fewer photons"
    );
    let again = json(&[
        "trace",
        "cornell",
        "--mode",
        "adaptive",
        "--n-max",
        "3000",
        "--cosn",
        "20",
        "--json",
        "--threads",
        "1",
    ]);
    assert_eq!(
        v["checksum"], again["checksum"],
        "1 and 2 threads give the same map"
    );
}

#[test]
fn bench_rays_json() {
    let v = json(&["bench", "rays", "cornell", "--rays", "20000", "--json"]);
    for key in [
        "raw_mrays_per_s",
        "single_mrays_per_s",
        "batch_mrays_per_s",
        "threads",
    ] {
        assert!(v[key].as_f64().unwrap() > 0.0, "{key}");
    }
}

#[test]
fn analyze_scene_json() {
    let v = json(&["analyze", "cornell", "--json"]);
    let f = v["functions"].as_array().unwrap();
    assert!(f.iter().any(|x| x["kind"] == "cosn" && x["alpha_d"] == 1.0));
    assert!(f
        .iter()
        .any(|x| x["kind"] == "lambert" && x["alpha_d_by_theta_in"].is_array()));
}

#[test]
fn quality_zero_is_an_empty_run_and_bad_input_is_a_clear_error() {
    let v = json(&["trace", "cornell", "--quality", "0", "--json"]);
    assert_eq!(v["emitted"], 0);
    assert_eq!(v["stored"], 0);
    for (args, needle) in [
        (vec!["trace", "cornell", "--quality", "1"], "--budget-mb"),
        (vec!["trace", "cornell", "--quality", "1.5"], "quality"),
        (vec!["trace", "cornell", "--cosn", "-1"], "cosn"),
        (vec!["trace", "cornell", "--cosn", "NaN"], "cosn"),
        (vec!["scene", "/no/such/scene.gltf"], "/no/such/scene.gltf"),
        (vec!["trace", "/no/such/scene.glb"], "/no/such/scene.glb"),
        (vec!["bench", "cornell", "--n-sweep", "1..x"], "A..B"),
    ] {
        let (code, _, err) = run(&args);
        assert_ne!(code, 0, "{args:?}");
        assert!(err.contains(needle), "{args:?}: {err}");
    }
}

/// `assets/cornell_empty.gltf` rewritten as `root/scenes/box.gltf` whose
/// buffer is `../buffers/box.bin`; returns the root and the scene.
fn box_with_a_sibling_buffer(dir: &std::path::Path) -> (std::path::PathBuf, std::path::PathBuf) {
    let asset = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/cornell_empty.gltf");
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(asset).unwrap()).unwrap();
    let uri = v["buffers"][0]["uri"].as_str().unwrap().to_string();
    let (_, payload) = uri.split_once(";base64,").unwrap();
    let root = dir.join("root");
    std::fs::create_dir_all(root.join("scenes")).unwrap();
    std::fs::create_dir_all(root.join("buffers")).unwrap();
    std::fs::write(
        root.join("buffers/box.bin"),
        base64::decode(payload).unwrap(),
    )
    .unwrap();
    v["buffers"][0]["uri"] = Value::from("../buffers/box.bin");
    let scene = root.join("scenes/box.gltf");
    std::fs::write(&scene, v.to_string()).unwrap();
    (root, scene)
}

#[test]
fn asset_root_lets_a_scene_read_a_sibling_folder() {
    let dir = tempfile::tempdir().unwrap();
    let (root, scene) = box_with_a_sibling_buffer(dir.path());
    let (scene, root) = (scene.to_str().unwrap(), root.to_str().unwrap());
    let v = json(&["scene", scene, "--asset-root", root, "--json"]);
    assert_eq!(v["triangles"], 12);
    let v = json(&[
        "trace",
        scene,
        "--asset-root",
        root,
        "--n-max",
        "2000",
        "--json",
    ]);
    assert!(v["stored"].as_u64().unwrap() > 0, "{v}");
    let (code, _, err) = run(&["scene", scene, "--json"]);
    assert_ne!(code, 0);
    assert!(
        err.contains("`../buffers/box.bin`") && err.contains("leaves the asset root"),
        "{err}"
    );
    let (code, _, err) = run(&["scene", "cornell", "--asset-root", root]);
    assert_ne!(code, 0);
    assert!(err.contains("does not apply"), "{err}");
}

#[test]
fn a_scene_in_the_working_folder_reads_its_buffer() {
    let dir = tempfile::tempdir().unwrap();
    let (root, _) = box_with_a_sibling_buffer(dir.path());
    let out = Command::new(env!("CARGO_BIN_EXE_adaptive-pm"))
        .args(["scene", "box.gltf", "--asset-root", "..", "--json"])
        .current_dir(root.join("scenes"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
}

/// `--spp auto` (the default) reports the spp it reached and its noise; its
/// options are refused where they cannot apply.
#[test]
fn render_spp_auto_reports_its_noise_and_refuses_what_cannot_apply() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("a.exr");
    let out = out.to_str().unwrap();
    let small = ["--width", "16", "--height", "16", "--n-max", "2000"];
    let args = [
        &[
            "render", "cornell", "--json", "--noise", "0.2", "--out", out,
        ][..],
        &small,
    ]
    .concat();
    let v = json(&args);
    let spp = v["spp"].as_u64().unwrap();
    assert!((8..=1024).contains(&spp), "{v}");
    let noise = v["noise_estimate"].as_f64().unwrap();
    assert_eq!(v["noise_target_reached"], noise <= 0.2, "{v}");
    let fixed = [
        &["render", "cornell", "--json", "--spp", "3", "--out", out][..],
        &small,
    ]
    .concat();
    let v = json(&fixed);
    assert_eq!(v["spp"], 3);
    assert!(v["noise_estimate"].is_null());
    for (extra, needle) in [
        (vec!["--spp", "0"], "--spp"),
        (vec!["--spp", "many"], "auto"),
        (vec!["--noise", "1.5"], "noise target"),
        (vec!["--noise", "0"], "noise target"),
        (vec!["--max-spp", "4"], "max spp"),
        (vec!["--spp", "8", "--noise", "0.1"], "--spp auto"),
        (vec!["--tile", "0/2"], "--tile needs a fixed --spp"),
    ] {
        let args = [&["render", "cornell", "--out", out][..], &small, &extra].concat();
        let (code, _, err) = run(&args);
        assert_ne!(code, 0, "{args:?}");
        assert!(err.contains(needle), "{args:?}: {err}");
    }
}

/// `assets/cornell_empty.gltf` without its light and its camera, as most
/// glTF models come.
fn bare_model(dir: &std::path::Path) -> String {
    let asset = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/cornell_empty.gltf");
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(asset).unwrap()).unwrap();
    for m in v["materials"].as_array_mut().unwrap() {
        m.as_object_mut().unwrap().remove("emissiveFactor");
    }
    v.as_object_mut().unwrap().remove("cameras");
    for n in v["nodes"].as_array_mut().unwrap() {
        n.as_object_mut().unwrap().remove("camera");
    }
    let path = dir.join("bare.gltf");
    std::fs::write(&path, v.to_string()).unwrap();
    path.to_str().unwrap().to_string()
}

#[test]
fn a_model_without_light_or_camera_is_lit_and_framed_from_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let model = bare_model(dir.path());
    // Described, with the light it lacks as a warning.
    let v = json(&["scene", &model, "--json"]);
    assert_eq!(v["lights"].as_array().unwrap().len(), 0);
    assert!(v["warnings"].to_string().contains("--point-light"), "{v}");
    // Traced: refused, naming a light that would do.
    let (code, _, err) = run(&["trace", &model, "-n", "1000"]);
    assert_eq!(code, 1);
    assert!(
        err.contains("has no light") && err.contains("--point-light "),
        "{err}"
    );
    let light = ["--point-light", "278,500,279,2e6"];
    let v = json(&[&["trace", &model, "-n", "2000", "--json"][..], &light].concat());
    assert!(v["stored"].as_u64().unwrap() > 0, "{v}");
    // Rendered without a camera: framed whole, and said so.
    let out = dir.path().join("bare.exr");
    let args = [
        &[
            "render", &model, "-n", "2000", "--spp", "1", "--width", "16", "--height", "16",
        ][..],
        &["--out", out.to_str().unwrap(), "--json"],
        &light,
    ]
    .concat();
    let (code, _, err) = run(&args);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("has no camera") && err.contains("--camera "),
        "{err}"
    );
    let camera = ["--camera", "278,273,-800,278,273,0,39.3"];
    let (code, _, err) = run(&[&args[..], &camera].concat());
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("has no camera"), "{err}");
    // Bad values are refused by name.
    for (flag, value, needle) in [
        ("--point-light", "1,2,3", "four numbers"),
        ("--point-light", "1,2,3,nan", "finite"),
        ("--point-light", "1,2,3,0", "above 0 W"),
        ("--point-light", "1e30,0,0,1", "--point-light"),
        ("--camera", "0,0,0,0,0,0", "differ"),
        ("--camera", "0,0,0,1,0,0,180", "field of view"),
        ("--camera", "0,0,0,1", "six or seven"),
    ] {
        let (code, _, err) = run(&["trace", &model, "-n", "1000", flag, value]);
        assert!(code == 1 || code == 2, "{flag} {value}: {err}");
        assert!(err.contains(needle), "{flag} {value}: {err}");
    }
}
