//! The downstream renderer's own ray caster: every triangle tested for every
//! ray (Möller–Trumbore). Slow, obviously correct, and independent of Embree:
//! what a renderer with its own BVH plugs into the photon engine.

use adaptive_pm::raycast::{Hit, Ray, RayCaster};
use adaptive_pm::scene::Scene;
use glam::Vec3;

struct Triangle {
    v0: Vec3,
    e1: Vec3,
    e2: Vec3,
    mesh: u32,
    prim: u32,
    material: u32,
}

/// A flat list of the scene's triangles.
pub struct BruteForce {
    triangles: Vec<Triangle>,
}

impl BruteForce {
    /// Copies the triangles of `scene` (mesh index as `geom_id`, triangle
    /// index as `prim_id`, as Embree's scene does).
    pub fn new(scene: &Scene) -> Self {
        let mut triangles = Vec::new();
        for (m, mesh) in scene.meshes().iter().enumerate() {
            for (i, _) in mesh.indices.iter().enumerate() {
                let [a, b, c] = mesh.triangle(i);
                triangles.push(Triangle {
                    v0: a,
                    e1: b - a,
                    e2: c - a,
                    mesh: m as u32,
                    prim: i as u32,
                    material: mesh.material as u32,
                });
            }
        }
        BruteForce { triangles }
    }

    fn hit(t: &Triangle, ray: &Ray, tfar: f32) -> Option<Hit> {
        let p = ray.dir.cross(t.e2);
        let det = t.e1.dot(p);
        if det.abs() < 1e-12 {
            return None;
        }
        let inv = 1.0 / det;
        let s = ray.origin - t.v0;
        let u = s.dot(p) * inv;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let q = s.cross(t.e1);
        let v = ray.dir.dot(q) * inv;
        if v < 0.0 || u + v > 1.0 {
            return None;
        }
        let dist = t.e2.dot(q) * inv;
        (dist >= ray.tnear && dist <= tfar).then(|| Hit {
            t: dist,
            ng: t.e1.cross(t.e2).normalize(),
            geom_id: t.mesh,
            prim_id: t.prim,
            u,
            v,
            material: t.material,
        })
    }
}

impl RayCaster for BruteForce {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        if !(ray.origin.is_finite() && ray.dir.is_finite()) {
            return None;
        }
        let mut best: Option<Hit> = None;
        for t in &self.triangles {
            let tfar = best.map_or(ray.tfar, |h| h.t);
            if let Some(h) = Self::hit(t, ray, tfar) {
                best = Some(h);
            }
        }
        best
    }

    fn occluded(&self, ray: &Ray) -> bool {
        ray.origin.is_finite()
            && ray.dir.is_finite()
            && self
                .triangles
                .iter()
                .any(|t| Self::hit(t, ray, ray.tfar).is_some())
    }
}
