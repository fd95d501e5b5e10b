//! Area-uniform points on a scene's surfaces: the fixed evaluation points of the
//! density statistics (docs/method.md, "Density measurements") and the ray
//! origins of `bench rays`; and the frame a hit scatters in.

use super::{triangle_area, Scene};
use crate::brdf::Brdf;
use crate::raycast::Hit;
use crate::rng::{hash2, Rng};
use glam::Vec3;

/// A point on a surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// Position.
    pub position: Vec3,
    /// Unit geometric normal (winding side).
    pub normal: Vec3,
    /// Mesh index.
    pub mesh: usize,
}

/// Samples points uniformly by area over every triangle of a scene, the
/// holes of alpha masks left out ([`Scene::is_hole`]).
#[derive(Clone, Debug)]
pub struct SurfaceSampler {
    /// Each triangle, its mesh and its index there.
    triangles: Vec<([Vec3; 3], usize, u32)>,
    cdf: Vec<f64>,
    total: f64,
    /// Per mesh, its holes.
    cutouts: Vec<Option<super::Cutout>>,
}

impl SurfaceSampler {
    /// Builds the area table.
    pub fn new(scene: &Scene) -> Self {
        let mut triangles = Vec::new();
        let mut cdf = Vec::new();
        let mut acc = 0.0f64;
        for (mi, m) in scene.meshes.iter().enumerate() {
            for i in 0..m.indices.len() {
                let t = m.triangle(i);
                acc += triangle_area(t) as f64;
                triangles.push((t, mi, i as u32));
                cdf.push(acc);
            }
        }
        SurfaceSampler {
            triangles,
            cdf,
            total: acc,
            cutouts: (0..scene.meshes.len()).map(|m| scene.cutout(m)).collect(),
        }
    }

    /// Total area of the triangles, holes included.
    pub fn total_area(&self) -> f64 {
        self.total
    }

    /// One point from three uniforms; `None` when it falls in a hole (or
    /// the scene has no area).
    pub fn sample(&self, u_sel: f64, u: [f32; 2]) -> Option<SurfacePoint> {
        if self.triangles.is_empty() || self.total <= 0.0 {
            return None;
        }
        let target = u_sel * self.total;
        let i = self
            .cdf
            .partition_point(|&c| c < target)
            .min(self.triangles.len() - 1);
        let ([a, b, c], mesh, prim) = self.triangles[i];
        let (b0, b1) = crate::sampling::uniform_triangle(u);
        // Barycentrics of vertices 1 and 2, as a hit reports them.
        let in_hole = self.cutouts[mesh]
            .as_ref()
            .is_some_and(|h| h.is_hole(prim, b1, 1.0 - b0 - b1));
        if in_hole {
            return None;
        }
        Some(SurfacePoint {
            position: a * b0 + b * b1 + c * (1.0 - b0 - b1),
            normal: (b - a).cross(c - a).normalize(),
            mesh,
        })
    }

    /// `count` points fixed by `seed` (point `i` depends only on `seed` and
    /// `i`), less those that fall in holes.
    pub fn points(&self, count: usize, seed: u64) -> Vec<SurfacePoint> {
        (0..count)
            .filter_map(|i| {
                let mut rng = Rng::new(hash2(seed ^ 0x5EED_5A4F, i as u64));
                self.sample(rng.next_f64(), rng.next_2d())
            })
            .collect()
    }
}

impl SurfaceSampler {
    /// Incoherent rays for throughput measurements: origins area-uniform on the
    /// surfaces (offset by `epsilon` along the normal), directions
    /// cosine-distributed about the normal, on the side the normal faces.
    pub fn incoherent_rays(
        &self,
        count: usize,
        seed: u64,
        epsilon: f32,
    ) -> Vec<crate::raycast::Ray> {
        (0..count)
            .filter_map(|i| {
                let mut rng = Rng::new(hash2(seed ^ 0x4A75, i as u64));
                let p = self.sample(rng.next_f64(), rng.next_2d())?;
                let local = crate::sampling::cosine_hemisphere(rng.next_2d());
                let dir = crate::sampling::Frame::from_normal(p.normal).world_from_local(local);
                Some(crate::raycast::Ray::new(
                    p.position + p.normal * epsilon,
                    dir,
                ))
            })
            .collect()
    }
}

impl Scene {
    /// The normal of the scattering frame at hit `h` (`from_inside`: the ray
    /// arrived on the side opposite the winding normal). For a transmitting
    /// model it is the outside of the object (the winding side); for a
    /// reflecting one the side the ray arrives from (surfaces are
    /// two-sided). Specular models (mirrors, glass) use the shading normal
    /// ([`Scene::shading_normal`]) when the mesh has one, so that a smooth sphere
    /// reflects and refracts as a sphere, not as its facets; the others the
    /// geometric normal. Photons and camera paths use the same frame.
    pub fn scattering_normal(&self, brdf: &Brdf, h: &Hit, from_inside: bool) -> Vec3 {
        let side = if from_inside && !brdf.is_transmissive() {
            -h.ng
        } else {
            h.ng
        };
        if !brdf.is_specular() {
            return side;
        }
        self.shading_normal(h)
            .map(|ns| if ns.dot(side) < 0.0 { -ns } else { ns })
            .unwrap_or(side)
    }

    /// The normal a non-specular BRDF is evaluated and sampled about at hit
    /// `h`, seen along `toward` (the direction back to the camera, or back
    /// to where a photon came from): the shading normal turned to face
    /// `toward`, or `side` (the geometric normal on that side) on a mesh
    /// without one. The renderer, the path tracer and the photon tracer
    /// share it, and each drops the directions below `side`'s surface, so
    /// that the BRDF they see is one reciprocal function: the model in the
    /// shading frame, for two directions on the same side of the shading
    /// normal and of the geometric one. (Turning to `side` instead, or
    /// falling back to `side` where the shading normal faces away, would
    /// make the frame depend on which end a path starts from, and photons
    /// and camera paths would solve different equations.)
    pub fn shading_side(&self, h: &Hit, side: Vec3, toward: Vec3) -> Vec3 {
        match self.shading_normal(h) {
            Some(ns) if ns.dot(toward) < 0.0 => -ns,
            Some(ns) => ns,
            None => side,
        }
    }
}

/// The factor that makes photon (flux) transport through a shading normal
/// the adjoint of camera transport (Veach 1997, §5.3; pbrt's
/// `CorrectShadingNormal`): a photon arriving from `back` (unit, pointing
/// back along its path) and leaving along `out`, sampled about the
/// shading normal `ns` by a sampler whose weight carries `|out.ns|`, is
/// multiplied by `|back.ns| |out.ng| / (|back.ng| |out.ns|)`. Camera paths
/// need no factor: their cosine is the shading one. 0 where a cosine is 0.
pub fn photon_shading_factor(ng: Vec3, ns: Vec3, back: Vec3, out: Vec3) -> f32 {
    let denominator = back.dot(ng).abs() * out.dot(ns).abs();
    if denominator.is_nan() || denominator <= 0.0 {
        return 0.0;
    }
    back.dot(ns).abs() * out.dot(ng).abs() / denominator
}

/// Whether a specular sample in a shading frame is consistent with the
/// geometry: a reflection leaves on the side it arrived from and a
/// transmission crosses over. A shading normal can break this near the
/// silhouette; such samples are dropped, the same way by photons and
/// camera paths. `back` points back along the arriving ray, `out` is the
/// sampled direction, `transmitted` whether the sample crossed the frame's
/// plane.
pub fn consistent_with_geometry(ng: Vec3, back: Vec3, out: Vec3, transmitted: bool) -> bool {
    (out.dot(ng) * back.dot(ng) < 0.0) == transmitted
}
