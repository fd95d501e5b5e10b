//! The importance pass (`adaptive_pm::importance`): bitwise the same over
//! thread counts and shards, zero where no camera or gather ray reaches,
//! and the first-hit density of a camera facing a plane against the
//! pinhole's closed form.

use adaptive_pm::brdf::{Brdf, Lambert};
use adaptive_pm::embree::{thread_pool, Device};
use adaptive_pm::emitter::CosN;
use adaptive_pm::engine::Shard;
use adaptive_pm::importance::{
    importance_pass, ImportanceConfig, ImportanceSums, FIRST, GATHER, LATER,
};
use adaptive_pm::scene::{Camera, Emission, Material, Scene};
use glam::Vec3;

use crate::common;

fn grey(s: &mut Scene) -> usize {
    s.add_material(Material {
        name: "grey".into(),
        brdf: Brdf::Lambert(Lambert {
            albedo: Vec3::splat(0.5),
        }),
        emission: None,
    })
}

fn lamp(s: &mut Scene) -> usize {
    s.add_material(Material {
        name: "lamp".into(),
        brdf: Brdf::Lambert(Lambert { albedo: Vec3::ZERO }),
        emission: Some(Emission::new(Vec3::splat(5.0), CosN::new(0.0).unwrap())),
    })
}

/// The quad `a b c d` as two triangles.
fn quad(s: &mut Scene, name: &str, v: [Vec3; 4], material: usize) {
    s.add_mesh(name, v.to_vec(), vec![[0, 1, 2], [0, 2, 3]], material)
        .unwrap();
}

/// A closed cube of side `size` at `lo`.
fn cube(s: &mut Scene, name: &str, lo: Vec3, size: f32, material: usize) {
    let c: Vec<Vec3> = (0..8)
        .map(|i| lo + size * Vec3::new((i & 1) as f32, (i >> 1 & 1) as f32, (i >> 2) as f32))
        .collect();
    let faces = [
        [0, 1, 3, 2],
        [4, 6, 7, 5],
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 2, 6, 4],
        [1, 5, 7, 3],
    ];
    for (i, f) in faces.iter().enumerate() {
        quad(s, &format!("{name}{i}"), f.map(|k| c[k]), material);
    }
}

fn pass(scene: &Scene, cfg: &ImportanceConfig, threads: usize) -> ImportanceSums {
    let device = Device::new().unwrap();
    let prepared = scene.clone().commit(&device).unwrap();
    thread_pool(threads)
        .unwrap()
        .install(|| importance_pass(&prepared, cfg).unwrap())
}

fn small() -> ImportanceConfig {
    ImportanceConfig {
        width: 24,
        height: 24,
        spp: 2,
        later_bounces: 2,
        ..ImportanceConfig::default()
    }
}

#[test]
fn sums_are_bitwise_the_same_over_threads_and_shards() {
    let scene = Scene::cornell().unwrap();
    let cfg = small();
    let one = pass(&scene, &cfg, 1);
    assert!(one.cells().len() > 100, "{} cells", one.cells().len());
    for reader in [FIRST, GATHER, LATER] {
        assert!(one.total_per_sample(reader) > 0.0, "reader {reader}");
    }
    assert_eq!(one, pass(&scene, &cfg, 2));
    let shards: Vec<ImportanceSums> = (0..3)
        .map(|i| {
            let c = ImportanceConfig {
                shard: Shard::new(i, 3).unwrap(),
                ..cfg
            };
            pass(&scene, &c, 2)
        })
        .collect();
    assert_ne!(shards[0], one);
    let merged = ImportanceSums::merge(&shards).unwrap();
    assert_eq!(merged, one);
    assert_eq!(merged.freeze(), one.freeze());
    assert!(one.freeze().bytes_per_cell() <= 16);
}

/// Points on the six faces of the cube at `lo` (side `size`), each with
/// its face's outward normal.
fn face_points(lo: Vec3, size: f32) -> Vec<(Vec3, Vec3)> {
    let mut pts = Vec::new();
    for axis in 0..3 {
        for side in [0.0f32, 1.0] {
            let mut n = Vec3::ZERO;
            n[axis] = if side == 0.0 { -1.0 } else { 1.0 };
            for i in 0..7 {
                for j in 0..7 {
                    let mut p = Vec3::ZERO;
                    p[axis] = side;
                    p[(axis + 1) % 3] = (i as f32 + 0.5) / 7.0;
                    p[(axis + 2) % 3] = (j as f32 + 0.5) / 7.0;
                    pts.push((lo + p * size, n));
                }
            }
        }
    }
    pts
}

#[test]
fn no_importance_where_no_camera_or_gather_ray_reaches() {
    let mut s = Scene::new();
    let (g, l) = (grey(&mut s), lamp(&mut s));
    cube(&mut s, "room", Vec3::ZERO, 1.0, g);
    // A closed cube outside the room: no ray of the camera's enters it.
    cube(&mut s, "shut", Vec3::new(2.0, 0.0, 0.0), 0.5, g);
    // Low enough that the lamp's top is not in the ceiling's cells.
    let y = 0.85;
    let light = [(0.3, 0.3), (0.3, 0.7), (0.7, 0.7), (0.7, 0.3)].map(|(x, z)| Vec3::new(x, y, z));
    quad(&mut s, "lamp", light, l);
    let eye = Vec3::new(0.5, 0.5, 0.05);
    s.set_camera(Camera::look_at(eye, Vec3::new(0.5, 0.4, 1.0), Vec3::Y, 70.0).unwrap())
        .unwrap();
    let cfg = ImportanceConfig {
        later_bounces: 4,
        ..small()
    };
    let grid = pass(&s, &cfg, 2).freeze();
    let mut inside_seen = 0;
    for (p, n) in face_points(Vec3::ZERO, 1.0) {
        // The room's outer faces, seen from outside (normal outward).
        // (Photons there may still be stored: a kernel at an inner point
        // reaches the render's radius, on surfaces of any side.)
        let what = (grid.read(p, n), grid.adjoint(p, n));
        assert_eq!(what, (0.0, 0.0), "outside of the room at {p}");
        inside_seen += usize::from(grid.adjoint(p, -n) > 0.0);
    }
    // The gather and later bounces reach every wall from inside.
    assert!(inside_seen > 200, "{inside_seen} of 294 inner points");
    for (p, n) in face_points(Vec3::new(2.0, 0.0, 0.0), 0.5) {
        for n in [n, -n] {
            assert_eq!(grid.adjoint(p, n), 0.0, "shut cube at {p}");
            assert!(!grid.within_reach(p), "shut cube at {p}");
        }
    }
}

#[test]
fn first_hits_on_a_facing_plane_match_the_pinhole_closed_form() {
    let mut s = Scene::new();
    let (g, l) = (grey(&mut s), lamp(&mut s));
    let (z, big) = (2.0f32, 10.0f32);
    let plane =
        [(-1., -1.), (1., -1.), (1., 1.), (-1., 1.)].map(|(x, y)| Vec3::new(x * big, y * big, z));
    quad(&mut s, "wall", plane, g);
    // A light out of view (sets the bounds' near side at z = 1).
    let light = [(9.0, 9.0), (9.5, 9.0), (9.5, 9.5), (9.0, 9.5)].map(|(x, y)| Vec3::new(x, y, 1.0));
    quad(&mut s, "lamp", light, l);
    let vfov = 40.0f32;
    s.set_camera(Camera::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y, vfov).unwrap())
        .unwrap();
    let cfg = ImportanceConfig {
        width: 64,
        height: 64,
        spp: 4,
        gather: 0,
        cell_fraction: 1.0 / 512.0,
        seed: common::seed(1),
        ..ImportanceConfig::default()
    };
    let sums = pass(&s, &cfg, 2);
    // Every camera ray hits the plane with throughput 1: one per sample,
    // to the fixed point's rounding.
    assert!((sums.total_per_sample(FIRST) - 1.0).abs() < 1e-6);
    assert_eq!(sums.total_per_sample(GATHER), 0.0);
    let h = sums.grid().cell_size();
    let (lo, _) = s.bounds();
    let layer = (z - lo.z) / h;
    assert!(
        (0.05..0.95).contains(&layer.fract()),
        "the plane lies on a cell face"
    );
    // A pinhole's samples, uniform over the image, are uniform over the
    // plane's footprint (a central projection onto a parallel plane is
    // affine): importance per area is 1 / footprint area everywhere in it.
    let half = z * (vfov.to_radians() / 2.0).tan();
    let want = 1.0 / (2.0 * half).powi(2) as f64;
    let grid = sums.freeze();
    // Cell centres on the plane; the cells wholly in view.
    let centres = |o: f32| {
        let k = |v: f32| ((v - o) / h).floor() as i64;
        (k(-half)..=k(half)).map(move |k| o + (k as f32 + 0.5) * h)
    };
    let mut ratio = common::MeanVar::default();
    for x in centres(lo.x) {
        for y in centres(lo.y) {
            if x.abs() + h / 2.0 < half && y.abs() + h / 2.0 < half {
                let p = Vec3::new(x, y, z);
                ratio.push(grid.read(p, -Vec3::Z) as f64 / want);
            }
        }
    }
    assert!(ratio.count() > 400, "{} cells in view", ratio.count());
    let sigma = ratio.std_error();
    common::assert_sigmas(
        "first-hit density / closed form",
        ratio.mean() - 1.0,
        sigma,
        4.0,
    );
    assert!(sigma < 0.02, "sigma {sigma}");
}
