//! What alpha masking refuses and what it does not model: `alphaMode:
//! BLEND` is traced as OPAQUE with a warning naming the material; a bad
//! `alphaCutoff`, a masked emitter or refracting glass with holes, a masked
//! texture without its coordinates, and a ray caster that does not cut
//! holes are refused with errors that name them.

use adaptive_pm::embree::{CommittedScene, Device};
use adaptive_pm::raycast::{Hit, Ray, RayCaster};
use adaptive_pm::scene::{AlphaMask, PreparedScene, TexTransform, TextureRef};
use serde_json::json;

use crate::gltf_alpha_mask::{
    checkered, cornell_with_fence, fence_scene, floor_photons, load, load_err, plane_material,
};

#[test]
fn blend_is_traced_as_opaque_with_a_warning_naming_the_material() {
    // Alpha 0 everywhere, BLEND: a wall all the same.
    let doc = fence_scene(Some(plane_material("BLEND", 0.0, false)), None);
    let scene = load(&doc);
    let w = scene.warnings().join("\n");
    assert!(
        w.contains("`fence`") && w.contains("BLEND") && w.contains("OPAQUE"),
        "{w}"
    );
    assert!(scene.alpha_mask(scene.meshes()[2].material).is_none());
    let (blocked, _, _) = floor_photons(&scene, 20_000, 3);
    assert!(
        blocked.is_empty(),
        "{} photons under a BLEND wall",
        blocked.len()
    );
    // OPAQUE ignores alpha, and MASK warns no more.
    let opaque = load(&fence_scene(
        Some(plane_material("OPAQUE", 0.0, true)),
        Some(json!({})),
    ));
    assert!(
        !opaque.has_holes() && opaque.warnings().is_empty(),
        "{:?}",
        opaque.warnings()
    );
    assert!(checkered("MASK").warnings().is_empty());
}

#[test]
fn bad_cutoffs_masked_emitters_and_masked_glass_are_refused_by_name() {
    for bad in [json!(-0.25), json!(1e39)] {
        let mut m = plane_material("MASK", 1.0, true);
        m["alphaCutoff"] = bad.clone();
        let e = load_err(&fence_scene(Some(m), Some(json!({}))));
        assert!(
            e.contains("material 2 (`fence`)") && e.contains("alphaCutoff"),
            "{bad}: {e}"
        );
    }
    // A cut-off above 1 is allowed: every point is a hole.
    let mut m = plane_material("MASK", 1.0, false);
    m["alphaCutoff"] = json!(1.5);
    assert!(load(&fence_scene(Some(m), None)).mesh_has_holes(2));
    // An emitter with holes is refused; one whose alpha never falls below
    // the cut-off is an opaque emitter.
    let mut m = plane_material("MASK", 1.0, true);
    m["emissiveFactor"] = json!([1.0, 1.0, 1.0]);
    let e = load_err(&fence_scene(Some(m.clone()), Some(json!({}))));
    assert!(
        e.contains("`fence`") && e.contains("emissive") && e.contains("MASK"),
        "{e}"
    );
    m["pbrMetallicRoughness"]
        .as_object_mut()
        .unwrap()
        .remove("baseColorTexture");
    let solid = load(&fence_scene(Some(m), None));
    assert!(!solid.has_holes() && solid.lights().len() == 2);
    // Refracting glass with holes.
    let mut glass = plane_material("MASK", 0.3, false);
    glass["extensions"] = json!({"KHR_materials_transmission": {"transmissionFactor": 1.0},
        "KHR_materials_volume": {"thicknessFactor": 0.1}});
    let mut doc = fence_scene(Some(glass), None);
    doc.extensions_used
        .extend(["KHR_materials_transmission", "KHR_materials_volume"]);
    let e = load_err(&doc);
    assert!(e.contains("`fence`") && e.contains("refracts"), "{e}");
    // A masked texture needs its coordinates.
    let mut doc = fence_scene(Some(plane_material("MASK", 1.0, true)), Some(json!({})));
    let m = doc.meshes.len() - 1;
    doc.meshes[m]["primitives"][0]["attributes"]
        .as_object_mut()
        .unwrap()
        .remove("TEXCOORD_0");
    let e = load_err(&doc);
    assert!(e.contains("TEXCOORD_0"), "{e}");
}

/// A caster of the user's that does not cut holes.
#[derive(Debug)]
struct Walls(CommittedScene);

impl RayCaster for Walls {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.0.intersect(ray)
    }
    fn occluded(&self, ray: &Ray) -> bool {
        self.0.occluded(ray)
    }
}

#[test]
fn a_caster_that_does_not_cut_holes_is_refused() {
    let scene = checkered("MASK");
    let device = Device::new().unwrap();
    let e = PreparedScene::new(
        scene.clone(),
        Walls(scene.embree_geometry(&device).unwrap()),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("fence") && e.contains("cuts_alpha_masks"), "{e}");
    // An Embree scene of another scene (no filter where the scene has holes).
    let none = load(&fence_scene(
        Some(plane_material("OPAQUE", 1.0, false)),
        None,
    ));
    let e = PreparedScene::new(scene, none.embree_geometry(&device).unwrap())
        .unwrap_err()
        .to_string();
    assert!(e.contains("filtered"), "{e}");
}
#[test]
fn the_library_api_refuses_bad_masks() {
    let mut s = cornell_with_fence();
    let m = s.meshes().last().unwrap().material;
    for (mask, what) in [
        (AlphaMask::new(f32::NAN, 1.0), "alphaCutoff NaN"),
        (AlphaMask::new(-1.0, 1.0), "alphaCutoff -1"),
        (AlphaMask::new(0.5, 1.5), "alpha factor 1.5"),
    ] {
        let e = s.set_alpha_mask(m, mask).unwrap_err().to_string();
        assert!(e.contains("`fence`") && e.contains(what), "{e}");
    }
    let bad_texture = AlphaMask::new(0.5, 1.0).with_texture(TextureRef {
        texture: 7,
        tex_coord: 0,
        transform: TexTransform::default(),
    });
    assert!(s.set_alpha_mask(m, bad_texture).is_err());
    // The Cornell light's material is emissive: a mask with holes on it.
    let light = s
        .meshes()
        .iter()
        .find(|m| m.name.contains("light"))
        .unwrap()
        .material;
    let e = s
        .set_alpha_mask(light, AlphaMask::new(0.5, 0.0))
        .unwrap_err()
        .to_string();
    assert!(e.contains("emissive"), "{e}");
    s.set_alpha_mask(light, AlphaMask::new(0.5, 1.0)).unwrap();
    assert!(s.alpha_mask(light).is_some());
}
