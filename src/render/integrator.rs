//! The per-pixel estimator (see the module docs of [`super`]): rows of pixels
//! in parallel, each sample with its own counter-based random stream.

use super::camera::CameraRays;
use super::direct::direct_radiance;
use super::estimate::{radiance_estimate, Lookup};
use super::{default_max_radius, ray_epsilon, Image, RenderConfig, RenderMaps, View, MAX_SPECULAR};
use crate::embree::{CommittedScene, Hit, Ray};
use crate::error::{Error, Result};
use crate::photon_map::{Neighbor, PhotonMap};
use crate::rng::{hash2, Rng};
use crate::sampling::Frame;
use crate::scene::{Material, Scene};
use glam::Vec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

struct Ctx<'a> {
    scene: &'a Scene,
    rt: &'a CommittedScene,
    maps: Option<&'a RenderMaps>,
    view: View,
    gather: u32,
    lookup: Lookup,
    eps: f32,
    show_emitters: bool,
}

/// A non-delta hit reached through zero or more mirrors.
struct SurfaceHit<'a> {
    position: Vec3,
    /// Geometric normal flipped to the side the ray came from.
    normal: Vec3,
    /// Unit direction back along the ray.
    wo: Vec3,
    material: &'a Material,
    /// Product of the mirror weights on the way.
    throughput: Vec3,
}

impl<'a> Ctx<'a> {
    fn emitted(material: &Material, h: &Hit, wo: Vec3) -> Vec3 {
        match material.emission {
            Some(e) => {
                let cos = h.ng.dot(wo);
                if cos > 0.0 {
                    e.radiance * e.profile.eval(Vec3::new(0.0, 0.0, cos))
                } else {
                    Vec3::ZERO
                }
            }
            None => Vec3::ZERO,
        }
    }

    /// Follows `ray` through mirrors to its first non-delta hit. Emission seen
    /// at hit `first_emission` (0 = the first hit) and later is added to `emitted`.
    fn trace(
        &self,
        mut ray: Ray,
        first_emission: u32,
        rng: &mut Rng,
        emitted: &mut Vec3,
    ) -> Option<SurfaceHit<'a>> {
        let mut throughput = Vec3::ONE;
        for bounce in 0..=MAX_SPECULAR {
            let h = self.rt.intersect(&ray)?;
            let material = self.scene.materials.get(h.material as usize)?;
            let dir = ray.dir.normalize();
            let wo = -dir;
            let position = ray.at(h.t);
            let normal = if h.ng.dot(dir) > 0.0 { -h.ng } else { h.ng };
            if bounce >= first_emission {
                *emitted += throughput * Self::emitted(material, &h, wo);
            }
            if !material.brdf.is_delta() {
                return Some(SurfaceHit {
                    position,
                    normal,
                    wo,
                    material,
                    throughput,
                });
            }
            let frame = Frame::from_normal(normal);
            let bs = material
                .brdf
                .sample(frame.local_from_world(wo), rng.next_2d())?;
            throughput *= bs.weight;
            if throughput.max_element() <= 0.0 {
                return None;
            }
            ray = Ray::new(position + normal * self.eps, frame.world_from_local(bs.wo));
        }
        None
    }

    fn estimate(&self, map: &PhotonMap, s: &SurfaceHit, scratch: &mut Vec<Neighbor>) -> Vec3 {
        radiance_estimate(
            map,
            &s.material.brdf,
            s.position,
            s.normal,
            s.wo,
            self.lookup,
            scratch,
        )
        .value
    }

    /// Final gather from `s`: BRDF-sampled rays, the full map at their hits.
    fn gather(
        &self,
        maps: &RenderMaps,
        s: &SurfaceHit,
        rng: &mut Rng,
        scratch: &mut Vec<Neighbor>,
    ) -> Vec3 {
        let frame = Frame::from_normal(s.normal);
        let wo_l = frame.local_from_world(s.wo);
        let mut sum = Vec3::ZERO;
        for _ in 0..self.gather {
            let Some(bs) = s.material.brdf.sample(wo_l, rng.next_2d()) else {
                continue;
            };
            let ray = Ray::new(
                s.position + s.normal * self.eps,
                frame.world_from_local(bs.wo),
            );
            // Emission straight from a light was counted by light sampling;
            // after a mirror it is a caustic only the gather finds.
            let mut emitted = Vec3::ZERO;
            if let Some(y) = self.trace(ray, 1, rng, &mut emitted) {
                sum += bs.weight * y.throughput * self.estimate(&maps.full, &y, scratch);
            }
            sum += bs.weight * emitted;
        }
        sum / self.gather as f32
    }

    fn radiance(&self, ray: Ray, rng: &mut Rng, scratch: &mut Vec<Neighbor>) -> Vec3 {
        let mut l = Vec3::ZERO;
        let first = if self.show_emitters { 0 } else { u32::MAX };
        let Some(s) = self.trace(ray, first, rng, &mut l) else {
            return l;
        };
        let direct = |rng: &mut Rng| {
            direct_radiance(
                self.scene,
                self.rt,
                &s.material.brdf,
                [s.position, s.normal, s.wo],
                self.eps,
                rng,
            )
        };
        let local = match (self.view, self.maps) {
            (View::DirectOnly, _) => direct(rng),
            (View::Map { primary_only }, Some(m)) => {
                let map = if primary_only { &m.primary } else { &m.full };
                self.estimate(map, &s, scratch)
            }
            (View::Full, Some(m)) => {
                let indirect = if self.gather > 0 {
                    self.gather(m, &s, rng, scratch)
                } else {
                    self.estimate(&m.indirect, &s, scratch)
                };
                direct(rng) + indirect
            }
            (_, None) => Vec3::ZERO,
        };
        l + s.throughput * local
    }
}

/// Renders `scene` (whose Embree geometry is `rt`) with `maps`, on the current
/// rayon pool. `progress(rows_done, rows_total)` is called from worker threads.
///
/// # Errors
/// [`Error::InvalidParameter`] for bad settings or a view that needs a photon
/// map when `maps` is `None`; [`Error::InvalidScene`] when neither `cfg` nor
/// the scene has a camera.
pub fn render(
    scene: &Scene,
    rt: &CommittedScene,
    maps: Option<&RenderMaps>,
    cfg: &RenderConfig,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<Image> {
    cfg.validate()?;
    if maps.is_none() && cfg.view != View::DirectOnly {
        return Err(Error::param(
            "photon map",
            "this view reads the photon map; pass one or use the direct-only view",
        ));
    }
    // A tile (`cfg.rows`) is an image of its rows only; pixels keep their
    // whole-image index, so their samples are the whole image's.
    let (y0, y1) = cfg.rows.unwrap_or((0, cfg.height));
    let mut image = Image::new(cfg.width, y1 - y0)?;
    let camera = cfg.camera_for(scene)?;
    let rays = CameraRays::new(&camera, cfg.width, cfg.height);
    let ctx = Ctx {
        scene,
        rt,
        maps,
        view: cfg.view,
        gather: cfg.final_gather,
        lookup: Lookup {
            k: cfg.k,
            max_radius: cfg.max_radius.unwrap_or_else(|| default_max_radius(scene)),
        },
        eps: ray_epsilon(scene),
        show_emitters: cfg.show_emitters,
    };
    let width = cfg.width as usize;
    let rows = (y1 - y0) as u64;
    let done = AtomicU64::new(0);
    let inv_spp = 1.0 / cfg.spp as f32;
    image
        .pixels
        .par_chunks_mut(width)
        .enumerate()
        .for_each(|(y, row)| {
            let y = y + y0 as usize;
            let mut scratch = Vec::with_capacity(cfg.k);
            for (x, px) in row.iter_mut().enumerate() {
                let pixel = (y * width + x) as u64;
                let key = hash2(cfg.seed, pixel);
                let mut sum = Vec3::ZERO;
                for s in 0..cfg.spp {
                    let mut rng = Rng::new(hash2(key, s as u64));
                    let [jx, jy] = rng.next_2d();
                    let ray = rays.ray(x as f32 + jx, y as f32 + jy);
                    let l = ctx.radiance(ray, &mut rng, &mut scratch);
                    // A NaN or infinite sample (degenerate geometry) is dropped, not spread.
                    if l.is_finite() {
                        sum += l;
                    }
                }
                *px = sum * inv_spp;
            }
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, rows);
        });
    Ok(image)
}
