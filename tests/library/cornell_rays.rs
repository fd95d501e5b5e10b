//! Rays with known answers in the built-in Cornell box, through the safe wrapper.

use adaptive_pm::embree::{Device, Ray};
use adaptive_pm::rng::Rng;
use adaptive_pm::sampling::uniform_hemisphere;
use adaptive_pm::scene::Scene;
use glam::Vec3;

#[test]
fn a_ray_down_from_the_light_centre_hits_the_floor_below() {
    let scene = Scene::cornell().unwrap();
    let device = Device::new().unwrap();
    let rt = scene.embree_geometry(&device).unwrap();
    let centre = Vec3::new(278.0, 548.0, 279.5);
    let hit = rt
        .intersect(&Ray::new(centre, -Vec3::Y))
        .expect("the floor is below");
    let p = centre - Vec3::Y * hit.t;
    assert!((p - Vec3::new(278.0, 0.0, 279.5)).length() < 1e-3, "{p}");
    assert!((hit.t - 548.0).abs() < 1e-3);
    assert!(hit.ng.y.abs() > 0.9999);
    let floor = scene
        .meshes()
        .iter()
        .position(|m| m.name.starts_with("floor"))
        .unwrap();
    assert_eq!(hit.geom_id as usize, floor);
    assert_eq!(hit.material as usize, scene.meshes()[floor].material);
    // upwards from the floor, the first thing is the light (0.1 below the ceiling)
    let up = rt
        .intersect(&Ray::new(Vec3::new(278.0, 1.0, 279.5), Vec3::Y))
        .unwrap();
    assert!((up.t - 547.7).abs() < 1e-3, "{}", up.t);
    assert!(scene.materials()[up.material as usize].emission.is_some());
}

#[test]
fn the_box_closed_by_a_front_wall_traps_every_ray() {
    // The Cornell box is open at the front (z = 0), where the camera looks in.
    // With a front wall added, 1e5 random rays from inside must all hit something.
    let mut scene = Scene::cornell().unwrap();
    let white = scene
        .materials()
        .iter()
        .position(|m| m.name == "white")
        .unwrap();
    let front = vec![
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(560.0, -1.0, 0.0),
        Vec3::new(560.0, 550.0, 0.0),
        Vec3::new(-1.0, 550.0, 0.0),
    ];
    scene
        .add_mesh("front", front, vec![[0, 1, 2], [0, 2, 3]], white)
        .unwrap();
    let device = Device::new().unwrap();
    let rt = scene.embree_geometry(&device).unwrap();
    let mut rng = Rng::new(crate::common::seed(11));
    let mut escaped_open = 0;
    let open_rt = Scene::cornell().unwrap().embree_geometry(&device).unwrap();
    for _ in 0..100_000 {
        // a point inside the box, above the blocks' tops where it could be inside a block
        let o = Vec3::new(
            10.0 + 530.0 * rng.next_f32(),
            340.0 + 200.0 * rng.next_f32(),
            10.0 + 540.0 * rng.next_f32(),
        );
        let d = {
            let w = uniform_hemisphere(rng.next_2d());
            if rng.next_f32() < 0.5 {
                w
            } else {
                -w
            }
        };
        let hit = rt.intersect(&Ray::new(o, d));
        let h = hit.expect("a closed box has no way out");
        assert!(h.t > 0.0 && h.t.is_finite());
        // occlusion agrees with closest hit, at the hit distance and short of it
        assert!(rt.occluded(&Ray {
            origin: o,
            dir: d,
            tnear: 0.0,
            tfar: h.t * 1.0001
        }));
        assert!(!rt.occluded(&Ray {
            origin: o,
            dir: d,
            tnear: 0.0,
            tfar: h.t * 0.999
        }));
        if open_rt.intersect(&Ray::new(o, d)).is_none() {
            escaped_open += 1;
        }
    }
    // Without the front wall, rays towards -z do get out: a sanity bound,
    // not a statistical one (~15 % of 1e5 rays escape, binomial sd ~110, so
    // 1000 is ~130 sd below).
    eprintln!("{escaped_open} of 100000 rays left the open box");
    assert!(escaped_open > 1000, "{escaped_open}");
}
