//! Glass from glTF: the built-in `cornell-glass` (a mirror and a glass sphere
//! in the empty box), and `KHR_materials_transmission`, `KHR_materials_ior`
//! and `KHR_materials_volume` read from a small file, good values and bad.

use adaptive_pm::brdf::Brdf;
use adaptive_pm::scene::{Mesh, Scene, BUILTIN_CORNELL_EMPTY, BUILTIN_CORNELL_GLASS};
use glam::Vec3;
use std::path::Path;

const RADIUS: f32 = 100.0;
const MIRROR_CENTRE: Vec3 = Vec3::new(370.0, 100.0, 350.0);
const GLASS_CENTRE: Vec3 = Vec3::new(185.0, 100.0, 170.0);

fn mesh<'a>(s: &'a Scene, prefix: &str) -> &'a Mesh {
    let found: Vec<&Mesh> = s
        .meshes()
        .iter()
        .filter(|m| m.name.starts_with(prefix))
        .collect();
    assert_eq!(found.len(), 1, "one mesh `{prefix}`");
    found[0]
}

/// Every vertex on the sphere, a shading normal per vertex that points
/// out, and every triangle wound counter-clockwise seen from outside.
fn assert_outward_sphere(m: &Mesh, centre: Vec3) {
    assert!(m.indices.len() >= 8192, "{}: {}", m.name, m.indices.len());
    assert_eq!(m.normals.len(), m.positions.len(), "{}", m.name);
    for (p, n) in m.positions.iter().zip(&m.normals) {
        let r = *p - centre;
        assert!((r.length() - RADIUS).abs() < 1e-3, "{}: {p}", m.name);
        assert!(n.dot(r.normalize()) > 1.0 - 1e-5, "{}: {n} at {p}", m.name);
    }
    for i in 0..m.indices.len() {
        let [a, b, c] = m.triangle(i);
        let winding = (b - a).cross(c - a);
        let centroid = (a + b + c) / 3.0;
        assert!(
            winding.dot(centroid - centre) > 0.0,
            "{} triangle {i} faces in",
            m.name
        );
    }
}

#[test]
fn cornell_glass_has_a_mirror_and_a_glass_sphere_in_the_empty_box() {
    let s = Scene::open(BUILTIN_CORNELL_GLASS).unwrap();
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/cornell_glass.gltf");
    assert_eq!(s.meshes(), Scene::load(file).unwrap().meshes());
    let empty = Scene::open(BUILTIN_CORNELL_EMPTY).unwrap();
    for m in empty.meshes() {
        assert_eq!(Some(m), s.meshes().iter().find(|g| g.name == m.name));
    }
    assert_eq!(s.meshes().len(), empty.meshes().len() + 2);
    assert_eq!(s.lights(), empty.lights());
    assert_eq!(s.camera(), empty.camera());

    let mirror = mesh(&s, "mirror_sphere");
    let glass = mesh(&s, "glass_sphere");
    assert_outward_sphere(mirror, MIRROR_CENTRE);
    assert_outward_sphere(glass, GLASS_CENTRE);
    // Standing on the floor (y = 0), not through it.
    for m in [mirror, glass] {
        let low = m
            .positions
            .iter()
            .map(|p| p.y)
            .fold(f32::INFINITY, f32::min);
        assert!((0.0..1e-3).contains(&low), "{}: {low}", m.name);
    }

    let Brdf::Mirror(r) = s.materials()[mirror.material].brdf else {
        panic!("metallic 1, roughness 0 is a mirror")
    };
    assert_eq!(r.reflectance(), Vec3::splat(0.9));
    let Brdf::Dielectric(d) = s.materials()[glass.material].brdf else {
        panic!("transmission 1, roughness 0 is a smooth dielectric")
    };
    assert_eq!(d.ior(), 1.5);
    assert!(!d.thin(), "thicknessFactor 200: a refracting volume");
    assert_eq!(d.attenuation(), Vec3::ZERO, "no attenuationDistance");
    assert_eq!(d.tint(), Vec3::ONE);
}

/// A floor quad of material `probe` (its `pbrMetallicRoughness` and
/// `extensions` given as JSON text) under an emitting quad, with the same
/// embedded buffer as tests/hostile/base.gltf; `top` goes first in the
/// root object (`extensionsRequired`, say).
fn probe_gltf(pbr: &str, extensions: &str, top: &str) -> String {
    format!(
        r#"{{{top}"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,1]}}],
"extensionsUsed":["KHR_materials_transmission","KHR_materials_ior","KHR_materials_volume"],
"nodes":[{{"name":"floor","mesh":0}},{{"name":"lamp","mesh":1,"translation":[0,1,1],"rotation":[1,0,0,0]}}],
"meshes":[{{"name":"floor","primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"material":0}}]}},
{{"name":"lamp","primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"material":1}}]}}],
"materials":[{{"name":"probe","pbrMetallicRoughness":{pbr},"extensions":{extensions}}},
{{"name":"light","emissiveFactor":[1,1,1],"pbrMetallicRoughness":{{"metallicFactor":0,"roughnessFactor":1}}}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,0,1]}},
{{"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":12}}],
"buffers":[{{"byteLength":62,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAACAPwAAAAAAAIA/AAAAAAAAAAAAAIA/AAACAAEAAAADAAIAAAA="}}]}}"#
    )
}

const SMOOTH: &str =
    r#"{"baseColorFactor":[0.9,0.8,0.7,1],"metallicFactor":0,"roughnessFactor":0}"#;
const ROUGH: &str = r#"{"metallicFactor":0,"roughnessFactor":0.5}"#;
const FULL: &str = r#""KHR_materials_transmission":{"transmissionFactor":1}"#;

fn load(pbr: &str, extensions: &str) -> adaptive_pm::Result<Scene> {
    load_with(pbr, extensions, "")
}

fn load_with(pbr: &str, extensions: &str, top: &str) -> adaptive_pm::Result<Scene> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("probe.gltf");
    std::fs::write(&path, probe_gltf(pbr, extensions, top)).unwrap();
    Scene::load(&path)
}

fn probe(pbr: &str, extensions: &str) -> Brdf {
    let s = load(pbr, extensions).unwrap();
    let m = s.materials().iter().find(|m| m.name == "probe").unwrap();
    m.brdf
}

#[test]
fn transmission_ior_and_volume_are_read() {
    // Transmission alone: smooth glass of IOR 1.5, tinted, a thin wall.
    let Brdf::Dielectric(d) = probe(SMOOTH, &format!("{{{FULL}}}")) else {
        panic!("smooth glass")
    };
    assert_eq!((d.ior(), d.thin()), (1.5, true));
    assert_eq!(d.tint(), Vec3::new(0.9, 0.8, 0.7));
    assert_eq!(d.attenuation(), Vec3::ZERO);

    // With an IOR and roughness 0.5: GGX alpha 0.25.
    let Brdf::RoughDielectric(r) = probe(
        ROUGH,
        &format!(r#"{{{FULL},"KHR_materials_ior":{{"ior":1.33}}}}"#),
    ) else {
        panic!("rough glass")
    };
    assert_eq!((r.alpha(), r.ior(), r.thin()), (0.25, 1.33, true));

    // A volume: thickness > 0 refracts and absorbs -ln(c) / d per channel.
    let volume = r#""KHR_materials_volume":{"thicknessFactor":0.5,"attenuationDistance":2,"attenuationColor":[0.5,0.25,1]}"#;
    let Brdf::Dielectric(d) = probe(SMOOTH, &format!("{{{FULL},{volume}}}")) else {
        panic!("a volume of glass")
    };
    assert!(!d.thin());
    let expect = Vec3::new(2f32.ln() / 2.0, 4f32.ln() / 2.0, 0.0);
    assert!(
        (d.attenuation() - expect).abs().max_element() < 1e-6,
        "{}",
        d.attenuation()
    );

    // Thickness 0: a thin wall, which has no interior to absorb in.
    let thin = r#""KHR_materials_volume":{"thicknessFactor":0,"attenuationDistance":2,"attenuationColor":[0.5,0.5,0.5]}"#;
    let Brdf::Dielectric(d) = probe(SMOOTH, &format!("{{{FULL},{thin}}}")) else {
        panic!("a thin wall of glass")
    };
    assert!(d.thin());
    assert_eq!(d.attenuation(), Vec3::ZERO);

    // The IOR of an opaque dielectric sets its Fresnel f0: ((2-1)/(2+1))^2.
    let Brdf::GltfPbr(c) = probe(ROUGH, r#"{"KHR_materials_ior":{"ior":2}}"#) else {
        panic!("an opaque dielectric")
    };
    assert!((c.f0() - Vec3::splat(1.0 / 9.0)).abs().max_element() < 1e-6);

    // A file may require the three extensions.
    let required = r#""extensionsRequired":["KHR_materials_transmission","KHR_materials_ior","KHR_materials_volume"],"#;
    load_with(SMOOTH, &format!("{{{FULL}}}"), required).unwrap();
}

#[test]
fn partial_transmission_is_the_opaque_part_and_a_glass_part() {
    let partial = r#"{"KHR_materials_transmission":{"transmissionFactor":0.25}}"#;
    let s = load(ROUGH, partial).unwrap();
    let (i, probe) = s
        .materials()
        .iter()
        .enumerate()
        .find(|(_, m)| m.name == "probe")
        .unwrap();
    // The mesh keeps the material, whose BRDF is the opaque part.
    let Brdf::GltfPbr(opaque) = probe.brdf else {
        panic!("the opaque part of a rough dielectric: {:?}", probe.brdf)
    };
    assert_eq!(opaque.f0(), Vec3::splat(0.04));
    let mix = s.transmission_mix(i as u32).expect("a transmitted part");
    assert_eq!(mix.weight, 0.25);
    let glass = &s.materials()[mix.glass];
    assert_eq!(glass.name, "probe (transmitted part)");
    let Brdf::RoughDielectric(r) = glass.brdf else {
        panic!("the glass part of roughness 0.5 is rough glass")
    };
    assert_eq!((r.alpha(), r.ior(), r.thin()), (0.25, 1.5, true));
    // Whole transmission on a half metal, smooth: half glass, half mirror.
    let metal = r#"{"metallicFactor":0.5,"roughnessFactor":0}"#;
    let s = load(metal, &format!("{{{FULL}}}")).unwrap();
    let i = s
        .materials()
        .iter()
        .position(|m| m.name == "probe")
        .unwrap();
    assert!(matches!(s.materials()[i].brdf, Brdf::Mirror(_)));
    let mix = s.transmission_mix(i as u32).unwrap();
    assert_eq!(mix.weight, 0.5);
    assert!(matches!(s.materials()[mix.glass].brdf, Brdf::Dielectric(_)));
    // With a volume, the glass part refracts.
    let volume = r#"{"KHR_materials_transmission":{"transmissionFactor":0.5},"KHR_materials_volume":{"thicknessFactor":1}}"#;
    let s = load(SMOOTH, volume).unwrap();
    let i = s
        .materials()
        .iter()
        .position(|m| m.name == "probe")
        .unwrap();
    let mix = s.transmission_mix(i as u32).unwrap();
    let Brdf::Dielectric(d) = s.materials()[mix.glass].brdf else {
        panic!("smooth glass")
    };
    assert!(!d.thin());
    // Whole glass has no mix.
    let whole = load(SMOOTH, &format!("{{{FULL}}}")).unwrap();
    let i = whole
        .materials()
        .iter()
        .position(|m| m.name == "probe")
        .unwrap();
    assert_eq!(whole.transmission_mix(i as u32), None);
}

#[test]
fn bad_transmission_ior_and_volume_values_are_refused_by_name() {
    let volume = |v: &str| format!(r#"{{{FULL},"KHR_materials_volume":{{{v}}}}}"#);
    let cases = [
        (
            r#"{"KHR_materials_transmission":{"transmissionFactor":1.5}}"#.to_string(),
            "`gltf transmissionFactor`: must be in [0, 1], got 1.5",
        ),
        (
            format!(r#"{{{FULL},"KHR_materials_ior":{{"ior":0.5}}}}"#),
            "`gltf ior`: must be in [1, 4], or 0",
        ),
        (
            format!(r#"{{{FULL},"KHR_materials_ior":{{"ior":-1}}}}"#),
            "got -1",
        ),
        (
            volume(r#""thicknessFactor":-1"#),
            "`gltf thicknessFactor`: must be a finite number >= 0, got -1",
        ),
        (
            volume(r#""thicknessFactor":1,"attenuationDistance":0"#),
            "`gltf attenuationDistance`: must be > 0",
        ),
        (
            volume(r#""thicknessFactor":1,"attenuationColor":[2,1,1]"#),
            "`gltf attenuationColor`: every channel must be in [0, 1]",
        ),
    ];
    for (extensions, words) in cases {
        let msg = match load(SMOOTH, &extensions) {
            Ok(_) => panic!("{extensions} loaded"),
            Err(e) => crate::common::chain(&e),
        };
        assert!(
            msg.contains("material 0 (`probe`)") && msg.contains(words),
            "{extensions}: {msg}"
        );
    }
}
