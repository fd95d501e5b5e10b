//! Hostile input (issue 12): every file under tests/hostile/ loads to a clear
//! `Error` naming what is wrong, never a panic, an abort, a hang, unbounded
//! memory or a read outside the scene's folder. The files are written by
//! tests/hostile/make.py; fuzzer crash inputs (`crash-*`, `fuzz-*`) are kept
//! there too and replayed here.

use adaptive_pm::error::Error;
use adaptive_pm::scene::Scene;
use std::path::{Path, PathBuf};

use crate::common;

fn dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/hostile")
}

/// Loads `name` and returns the error message (with its sources).
fn error_of(path: &Path) -> String {
    match Scene::load(path) {
        Ok(_) => panic!("{} loaded, but it is hostile", path.display()),
        Err(e) => common::chain(&e),
    }
}

fn expect(name: &str, words: &[&str]) {
    let msg = error_of(&dir().join(name));
    for w in words {
        assert!(msg.contains(w), "{name}: `{msg}` lacks `{w}`");
    }
    // No file content ever reaches a message.
    assert!(!msg.contains("root:"), "{name}: `{msg}`");
}

#[test]
fn base_scene_loads() {
    let s = Scene::load(dir().join("base.gltf")).unwrap();
    assert_eq!(s.meshes().len(), 2);
    assert_eq!(s.lights().len(), 1);
    assert!(s.camera().is_some());
}

#[test]
fn what_panicked_in_the_gltf_crate_is_an_error() {
    expect(
        "position_accessor_99.gltf",
        &["mesh 0 (`floor`) primitive 0", "index 99"],
    );
    expect(
        "index_accessor_float.gltf",
        &["accessor 1 (`idx`)", "unsigned integer"],
    );
    expect(
        "byte_stride_4_on_vec3.gltf",
        &["accessor 0 (`pos`)", "byteStride is 4"],
    );
    expect(
        "camera_perspective_without_object.gltf",
        &["camera 0", "perspective"],
    );
    expect(
        "camera_orthographic_without_object.gltf",
        &["camera 0", "orthographic"],
    );
    expect("mesh_index_out_of_range.gltf", &["node 0 (`floor`)", "7"]);
    // Found by the fuzzer: the gltf crate's reader computes `count - 1`.
    expect("fuzz-accessor-count-0.gltf", &["count 0"]);
    // Found by the fuzzer seeded with the tests' documents: a node's skin
    // index past the skins, which the gltf crate unwraps.
    expect(
        "fuzz-node-skin-out-of-range.gltf",
        &["node 0", "skin refers to index"],
    );
}

#[test]
fn what_aborted_embree_is_an_error_naming_the_node() {
    expect("vertex_at_1e20.gltf", &["node 0 (`floor`)", "beyond"]);
    expect(
        "point_light_at_1e20.gltf",
        &["node 3 (`far-light`)", "beyond"],
    );
    expect("camera_at_1e20.gltf", &["node 2 (`eye`)", "camera eye"]);
    expect(
        "spot_light_scale_0.gltf",
        &["node 3 (`spot-node`)", "unit vector"],
    );
    expect("transform_overflow.gltf", &["node 0 (`floor`)"]);
}

#[test]
fn hangs_and_unbounded_memory_are_errors() {
    expect("node_cycle_self.gltf", &["node 0 (`floor`)", "cycle"]);
    expect("node_cycle_ab.gltf", &["cycle"]);
    expect("node_dag_40_levels.gltf", &["scene 0", "node instances"]);
    expect(
        "sparse_count_2p31.gltf",
        &["accessor 0 (`sparse`)", "2147483648"],
    );
    expect(
        "accessor_count_huge.gltf",
        &["accessor 0 (`pos`)", "1099511627776 elements"],
    );
    expect(
        "buffer_byte_length_2p40.gltf",
        &["buffers declare", "limit"],
    );
    expect("buffer_uri_dev_zero.gltf", &["`/dev/zero`", "absolute"]);
}

#[test]
fn a_fifo_or_a_device_inside_the_folder_is_not_read() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = tmp.path().join("scene.gltf");
    std::fs::copy(dir().join("buffer_uri_fifo.gltf"), &scene).unwrap();
    let fifo = tmp.path().join("fifo.bin");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    // SAFETY: mkfifo reads a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let msg = error_of(&scene);
    assert!(
        msg.contains("`fifo.bin`") && msg.contains("not a regular file"),
        "{msg}"
    );
    // A symbolic link to a device, inside the folder, resolves outside it.
    std::fs::remove_file(&fifo).unwrap();
    std::os::unix::fs::symlink("/dev/zero", &fifo).unwrap();
    let msg = error_of(&scene);
    assert!(
        msg.contains("`fifo.bin`") && msg.contains("outside"),
        "{msg}"
    );
}

#[test]
fn no_file_outside_the_scene_folder_is_read() {
    for name in [
        "buffer_uri_dotdot_passwd.gltf",
        "buffer_uri_absolute_passwd.gltf",
        "buffer_uri_file_scheme.gltf",
        "buffer_uri_proc_environ.gltf",
        "buffer_uri_percent_dotdot.gltf",
    ] {
        let msg = error_of(&dir().join(name));
        assert!(msg.contains("buffer 0 uri `"), "{name}: {msg}");
        // Never the size or the bytes of the file it named (`root:x:0:0`
        // of /etc/passwd; the message names the asset root, a folder).
        assert!(
            !msg.contains("root:") && !msg.contains("bytes"),
            "{name}: {msg}"
        );
    }
}

#[test]
fn messages_say_what_is_wrong() {
    let msg = error_of(&dir().join("accessor_past_buffer.gltf"));
    assert!(
        msg.contains("accessor 0 (`pos`)") && !msg.contains("no POSITION"),
        "{msg}"
    );
    expect(
        "degenerate_only_mesh.gltf",
        &["mesh `floor#0`", "degenerate"],
    );
    expect(
        "spot_cone_0.gltf",
        &["light 0 (`spot`)", "outerConeAngle 0"],
    );
    expect("camera_yfov_0.gltf", &["camera 0", "yfov 0"]);
}

/// Every other file kept here (fuzzer finds) loads to an error or a valid
/// scene, without panicking.
#[test]
fn glb_length_under_its_header_is_a_clear_error() {
    // Found by the fuzzer: the gltf crate subtracted 12 from it unchecked.
    let copy = tempfile::tempdir().unwrap();
    let target = copy.path().join("scene.glb");
    std::fs::copy(dir().join("fuzz-glb-length-under-header.glb"), &target).unwrap();
    let e = Scene::load(&target).unwrap_err();
    assert!(matches!(e, Error::Load { .. }), "{e}");
    let cause = std::error::Error::source(&e).map(|s| s.to_string());
    assert!(
        cause
            .as_deref()
            .unwrap_or("")
            .contains("GLB header declares"),
        "{e}: {cause:?}"
    );
}

#[test]
fn fuzzer_finds_replay_without_panic() {
    for entry in std::fs::read_dir(dir()).unwrap() {
        let p = entry.unwrap().path();
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        if name.starts_with("crash-") || name.starts_with("fuzz-") {
            let copy = tempfile::tempdir().unwrap();
            let ext = if std::fs::read(&p).unwrap().starts_with(b"glTF") {
                "glb"
            } else {
                "gltf"
            };
            let target = copy.path().join(format!("scene.{ext}"));
            std::fs::copy(&p, &target).unwrap();
            if let Ok(s) = Scene::load(&target) {
                assert!(s.lights().iter().all(|l| l.power().is_finite()), "{name}");
            }
        }
    }
}

#[test]
fn scenes_built_in_code_refuse_what_would_panic_later() {
    use adaptive_pm::brdf::{Brdf, Lambert};
    use adaptive_pm::scene::{Camera, Light, Material, PointLight, SpotLight};
    use glam::Vec3;
    let mut s = Scene::new();
    let white = s.add_material(Material {
        name: "white".into(),
        brdf: Brdf::Lambert(Lambert {
            albedo: Vec3::splat(0.5),
        }),
        emission: None,
    });
    let tri = vec![Vec3::ZERO, Vec3::X, Vec3::Y];
    let bad = |r: Result<usize, Error>| matches!(r, Err(Error::InvalidScene(_)));
    assert!(bad(s.add_mesh("m", tri.clone(), vec![[0, 1, 2]], 7)));
    assert!(bad(s.add_mesh(
        "m",
        vec![Vec3::NAN, Vec3::X, Vec3::Y],
        vec![[0, 1, 2]],
        white
    )));
    assert!(bad(s.add_mesh(
        "m",
        vec![Vec3::splat(1e20), Vec3::X, Vec3::Y],
        vec![[0, 1, 2]],
        white
    )));
    assert!(bad(s.add_mesh("m", tri.clone(), vec![[0, 1, 3]], white)));
    assert!(bad(s.add_mesh("m", tri.clone(), vec![[0, 1, 1]], white)));
    let nan_albedo = s.add_material(Material {
        name: "nan".into(),
        brdf: Brdf::Lambert(Lambert { albedo: Vec3::NAN }),
        emission: None,
    });
    assert!(bad(s.add_mesh(
        "m",
        tri.clone(),
        vec![[0, 1, 2]],
        nan_albedo
    )));
    assert!(bad(s.add_light(Light::Point(PointLight {
        position: Vec3::splat(1e20),
        intensity: Vec3::ONE
    }))));
    assert!(bad(s.add_light(Light::Point(PointLight {
        position: Vec3::ZERO,
        intensity: Vec3::splat(f32::MAX)
    }))));
    let spot = SpotLight {
        position: Vec3::ZERO,
        direction: Vec3::NAN,
        intensity: Vec3::ONE,
        cos_inner: 0.9,
        cos_outer: 0.8,
    };
    assert!(bad(s.add_light(Light::Spot(spot))));
    let mut cam = Camera::cornell();
    cam.vfov_deg = f32::NAN;
    assert!(s.set_camera(cam).is_err());
    assert!(s.meshes().is_empty() && s.lights().is_empty() && s.camera().is_none());
    // A dropped degenerate triangle: hits map back to the caller's index.
    let m = s
        .add_mesh(
            "two",
            vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::ONE],
            vec![[0, 0, 1], [0, 1, 2]],
            white,
        )
        .unwrap();
    assert_eq!(s.skipped_degenerate(), 1);
    assert_eq!(s.source_triangle(m as u32, 0), Some(1));
    assert_eq!(s.source_triangle(m as u32, 1), None);
    assert!(s.ray_epsilon() > 0.0 && s.ray_epsilon().is_finite());
}

/// Photon counts from any `N_MAX` over two lights: the sum over the lights is
/// checked (it overflowed u64 and panicked with "capacity overflow").
#[test]
fn any_n_max_over_two_lights_traces_or_is_refused() {
    use adaptive_pm::embree::Device;
    use adaptive_pm::engine::{Budget, Mode, TraceConfig, Tracer};
    use adaptive_pm::scene::{Light, PointLight};
    use glam::Vec3;
    use proptest::prelude::*;
    let mut scene = Scene::load(dir().join("base.gltf")).unwrap();
    for (x, i) in [(0.2, 1.0), (0.8, 1e6)] {
        let light = Light::Point(PointLight {
            position: Vec3::new(x, 0.5, 0.5),
            intensity: Vec3::splat(i),
        });
        scene.add_light(light).unwrap();
    }
    let device = Device::new().unwrap();
    let tracer = Tracer::new(scene.commit(&device).unwrap());
    let mut runner =
        proptest::test_runner::TestRunner::new(proptest::test_runner::Config::with_cases(32));
    let n_max = prop_oneof![0u64..2000, any::<u64>(), (u64::MAX - 8)..=u64::MAX];
    runner
        .run(&(n_max, 0usize..3), |(n, m)| {
            let mode = [Mode::Classic, Mode::Density, Mode::Adaptive][m];
            let mut cfg = TraceConfig::new(mode, Budget::NMax(n));
            cfg.memory_budget = Some(64 << 20);
            let result = tracer.trace(&cfg);
            match result {
                Ok(out) => prop_assert!(out.report.emitted <= n.saturating_mul(2).max(3)),
                Err(e) => prop_assert!(matches!(e, Error::Budget { .. }), "{e}"),
            }
            Ok(())
        })
        .unwrap();
}

/// A structure-aware mutation run (no libFuzzer needed): numbers of the
/// regression files replaced by hostile values, spans deleted or duplicated.
/// Every mutant loads or fails with an error; a panic fails the test and
/// prints the mutant. `HOSTILE_MUTANTS` sets the count (default 2000).
#[test]
#[ignore = "long: run with --ignored (the fuzz target in fuzz/ is the main tool)"]
fn mutants_of_the_regression_files_never_panic() {
    use adaptive_pm::rng::Rng;
    let count: usize = std::env::var("HOSTILE_MUTANTS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2000);
    let seeds: Vec<String> = std::fs::read_dir(dir())
        .unwrap()
        .filter_map(|e| {
            let p = e.unwrap().path();
            (p.extension()? == "gltf").then(|| std::fs::read_to_string(p).unwrap())
        })
        .collect();
    let hostile = [
        "0",
        "-1",
        "1e39",
        "-1e39",
        "4294967295",
        "2147483648",
        "99",
        "1e20",
        "3",
        "5126",
        "5121",
        "0.0",
        "[]",
        "{}",
        "\"x\"",
        "null",
    ];
    let tmp = tempfile::tempdir().unwrap();
    let target = tmp.path().join("m.gltf");
    let mut rng = Rng::new(12);
    std::panic::set_hook(Box::new(|_| {}));
    for i in 0..count {
        let mut s = seeds[i % seeds.len()].clone().into_bytes();
        for _ in 0..1 + (rng.next_f32() * 3.0) as usize {
            let at = (rng.next_f32() * s.len() as f32) as usize % s.len().max(1);
            match (rng.next_f32() * 3.0) as usize {
                0 => {
                    // Replace the number starting at or after `at`.
                    if let Some(start) = s[at..]
                        .iter()
                        .position(|c| c.is_ascii_digit())
                        .map(|k| k + at)
                    {
                        let end = s[start..]
                            .iter()
                            .position(|c| !(c.is_ascii_digit() || b".eE+-".contains(c)))
                            .map_or(s.len(), |k| k + start);
                        let v = hostile
                            [(rng.next_f32() * hostile.len() as f32) as usize % hostile.len()];
                        s.splice(start..end, v.bytes());
                    }
                }
                1 => {
                    let end = (at + (rng.next_f32() * 40.0) as usize).min(s.len());
                    s.drain(at..end);
                }
                _ => {
                    let end = (at + (rng.next_f32() * 40.0) as usize).min(s.len());
                    let dup: Vec<u8> = s[at..end].to_vec();
                    s.splice(at..at, dup);
                }
            }
        }
        std::fs::write(&target, &s).unwrap();
        let r = std::panic::catch_unwind(|| {
            if let Ok(scene) = Scene::load(&target) {
                assert!(scene.lights().iter().all(|l| l.power().is_finite()));
                let _ = scene.ray_epsilon();
            }
        });
        if r.is_err() {
            let keep = std::env::temp_dir().join(format!("hostile-mutant-{i}.gltf"));
            std::fs::write(&keep, &s).unwrap();
            let _ = std::panic::take_hook();
            panic!("mutant {i} panicked; kept as {}", keep.display());
        }
    }
    let _ = std::panic::take_hook();
}
