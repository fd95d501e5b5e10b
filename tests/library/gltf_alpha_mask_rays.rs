//! Rays through alpha-mask holes (`gltf_alpha_mask`'s floor, lamp and
//! plane): camera and shadow rays at every checker square, `Scene::is_hole`
//! against Embree's filter, 8- and 16-wide packets against single rays, and
//! holes that stay where the texture puts them under a mirrored node and
//! after degenerate triangles are dropped. All exact.

use adaptive_pm::embree::{BatchKernel, CommittedScene, Device};
use adaptive_pm::raycast::{Hit, Ray};
use adaptive_pm::scene::Scene;
use glam::Vec3;
use serde_json::json;

use crate::gltf_alpha_mask::{
    black, checker_clear, checkered, load, plane_material, png_rgba, CHECKS,
};
use crate::gltf_doc::{square, Doc};

#[test]
fn camera_and_shadow_rays_pass_through_the_holes_only() {
    let scene = checkered("MASK");
    let device = Device::new().unwrap();
    let prepared = scene.clone().commit(&device).unwrap();
    let rt = prepared.caster();
    let mut clear = 0;
    // Ray down from above the plane at every checker square's centre.
    for i in 0..CHECKS {
        for j in 0..CHECKS {
            let c = |k: u32| -2.0 + (k as f32 + 0.5) * 4.0 / CHECKS as f32;
            let (x, z) = (c(i), c(j));
            let ray = Ray::new(Vec3::new(x, 1.5, z), Vec3::NEG_Y);
            let hit = rt.intersect(&ray).expect("the floor or the plane");
            let open = checker_clear(x, z);
            clear += usize::from(open);
            let (want_t, want_mesh) = if open { (1.5, 0) } else { (0.5, 2) };
            assert!(
                (hit.t - want_t).abs() < 1e-4 && hit.geom_id == want_mesh,
                "({x}, {z}) clear {open}: {hit:?}"
            );
            assert!(!scene.is_hole(&hit), "a ray stopped in a hole");
            // The shadow ray from the floor up to above the plane.
            let shadow = Ray::segment(Vec3::new(x, 0.0, z), Vec3::new(x, 1.5, z), 1e-3);
            assert_eq!(rt.occluded(&shadow), !open, "({x}, {z})");
            // The hole the ray went through, as the scene sees it.
            if open {
                let at_plane = Hit {
                    t: 0.5,
                    geom_id: 2,
                    material: scene.meshes()[2].material as u32,
                    ..hit
                };
                let (prim, u, v) = barycentrics(&scene, 2, x, z);
                assert!(scene.is_hole(&Hit {
                    prim_id: prim,
                    u,
                    v,
                    ..at_plane
                }));
            }
        }
    }
    assert_eq!(clear, (CHECKS * CHECKS / 2) as usize);
}

/// The triangle of mesh `mesh` (a horizontal plane) above `(x, z)` and the
/// barycentrics of its vertices 1 and 2 there.
fn barycentrics(scene: &Scene, mesh: usize, x: f32, z: f32) -> (u32, f32, f32) {
    let m = &scene.meshes()[mesh];
    for k in 0..m.indices.len() {
        let [a, b, c] = m.triangle(k);
        let p = Vec3::new(x, a.y, z);
        let (e1, e2, d) = (b - a, c - a, p - a);
        let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let (d1, d2) = (d.dot(e1), d.dot(e2));
        let den = d11 * d22 - d12 * d12;
        let u = (d22 * d1 - d12 * d2) / den;
        let v = (d11 * d2 - d12 * d1) / den;
        if u >= 0.0 && v >= 0.0 && u + v <= 1.0 {
            return (k as u32, u, v);
        }
    }
    panic!("({x}, {z}) is not over mesh {mesh}");
}

/// Rays from above the plane in every downward-ish direction: some through
/// holes to the floor, some stopped by the plane, some missing everything;
/// occlusion segments of random lengths.
fn random_rays(n: usize, seed: u64) -> Vec<Ray> {
    let mut rng = adaptive_pm::rng::Rng::new(seed);
    (0..n)
        .map(|_| {
            let o = Vec3::new(
                rng.next_f32() * 5.0 - 2.5,
                1.0 + 0.9 * rng.next_f32(),
                rng.next_f32() * 5.0 - 2.5,
            );
            let d = Vec3::new(
                rng.next_f32() * 2.0 - 1.0,
                -rng.next_f32(),
                rng.next_f32() * 2.0 - 1.0,
            );
            Ray {
                tfar: 0.5 + 3.0 * rng.next_f32(),
                ..Ray::new(o, d)
            }
        })
        .collect()
}

#[test]
fn packets_agree_with_single_rays_through_holes() {
    let scene = checkered("MASK");
    let device = Device::new().unwrap();
    let committed: CommittedScene = scene.embree_geometry(&device).unwrap();
    assert_eq!(
        committed.filtered_count(),
        1,
        "only the masked plane is filtered"
    );
    let rays = random_rays(20_001, 5);
    let mut by_kernel = Vec::new();
    for kernel in [
        BatchKernel::Single,
        BatchKernel::Packet8,
        BatchKernel::Packet16,
    ] {
        let mut hits = vec![None; rays.len()];
        committed.intersect_batch_with(kernel, &rays, &mut hits);
        let mut occluded = vec![false; rays.len()];
        committed.occluded_batch_with(kernel, &rays, &mut occluded);
        by_kernel.push((kernel, hits, occluded));
    }
    let (_, hits, occluded) = &by_kernel[0];
    for (kernel, h, o) in &by_kernel[1..] {
        assert!(
            h == hits,
            "{kernel:?}: closest hits differ from single rays"
        );
        assert!(
            o == occluded,
            "{kernel:?}: occlusion differs from single rays"
        );
    }
    // Single rays agree with the scene's own view of the holes, and
    // occlusion with closest hits.
    let (mut on_plane, mut through) = (0, 0);
    for ((ray, hit), occ) in rays.iter().zip(hits).zip(occluded) {
        assert_eq!(*hit, committed.intersect(ray));
        assert_eq!(hit.is_some(), *occ, "{ray:?}");
        if let Some(h) = hit {
            assert!(!scene.is_hole(h), "a hit in a hole: {h:?}");
            match h.geom_id {
                2 => on_plane += 1,
                0 => through += usize::from(ray.origin.y > 1.0),
                _ => {}
            }
        }
    }
    assert!(
        on_plane > 3000 && through > 1000,
        "plane {on_plane}, through {through}"
    );
}

#[test]
fn a_mirrored_node_and_dropped_triangles_keep_the_holes_where_the_texture_says() {
    // A 2 x 1 texture, clear on the left (u < 1/2), CLAMP and NEAREST, on a
    // plane whose first triangle is degenerate (dropped: the kept ones are
    // renumbered), under a node mirrored in x (negative determinant: the
    // winding is reversed, which reorders Embree's vertices 1 and 2). The
    // vertex at x = -2 has u = 0 and lands at x = +2: the hole is on the
    // right.
    let half = png_rgba(2, 1, &[[9, 9, 9, 0], [9, 9, 9, 255]]);
    let mut doc = Doc::default();
    doc.texture(
        &half,
        json!({"magFilter": 9728, "wrapS": 33071, "wrapT": 33071}),
    );
    let floor_m = doc.material(black("floor"));
    let lamp = doc.material(json!({"name": "lamp", "emissiveFactor": [1.0, 1.0, 1.0]}));
    let plane_m = doc.material(plane_material("MASK", 1.0, true));
    let (p, i) = square(2.0, true);
    let f = doc.mesh(&p, &i, 4, Some(floor_m));
    doc.node(json!({ "mesh": f }));
    let (p, i) = square(0.5, false);
    let l = doc.mesh(&p, &i, 4, Some(lamp));
    doc.node(json!({"mesh": l, "translation": [0.0, 2.0, 0.0]}));
    let (p, i) = square(2.0, true);
    let with_degenerate: Vec<u32> = [0, 0, 1].into_iter().chain(i).collect();
    let pl = doc.mesh(&p, &with_degenerate, 4, Some(plane_m));
    doc.texcoords(pl, &[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
    doc.node(json!({"mesh": pl, "translation": [0.0, 1.0, 0.0], "scale": [-1.0, 1.0, 1.0]}));
    let scene = load(&doc);
    assert_eq!(scene.skipped_degenerate(), 1);
    assert_eq!(scene.source_triangle(2, 0), Some(1));
    let device = Device::new().unwrap();
    let prepared = scene.clone().commit(&device).unwrap();
    for z in [-1.5, -0.3, 0.4, 1.7] {
        for (x, clear) in [(-1.5, false), (-0.2, false), (0.2, true), (1.5, true)] {
            let ray = Ray::new(Vec3::new(x, 1.5, z), Vec3::NEG_Y);
            let hit = prepared.caster().intersect(&ray).unwrap();
            let want = if clear { 0 } else { 2 };
            assert_eq!(hit.geom_id, want, "({x}, {z}): {hit:?}");
            // The BRDF at the hit is still read where the ray stops.
            assert!(scene.surface_brdf(&hit).is_some());
        }
    }
}
