//! The per-pixel estimator (see the module docs of [`super`]): rows of pixels
//! in parallel, each sample with its own counter-based random stream and the
//! pixel's stratified points ([`super::sampler`]).

use super::cache::{CacheConfig, IrradianceCache};
use super::camera::CameraRays;
use super::direct::LightSampler;
use super::estimate::{radiance_estimate, Lookup};
use super::sampler::{dim, PixelSampler};
use super::{default_max_radius, ray_epsilon, Image, RenderConfig, RenderMaps, View, MAX_SPECULAR};
use crate::brdf::Brdf;
use crate::embree::{CommittedScene, Hit, Ray};
use crate::error::{Error, Result};
use crate::photon_map::{Neighbor, PhotonMap};
use crate::rng::{hash2, Rng};
use crate::sampling::Frame;
use crate::scene::{Material, Scene};
use glam::Vec3;
use rayon::prelude::*;
use std::f32::consts::FRAC_1_PI;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// What a render measured besides its image.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RenderStats {
    /// Camera samples taken.
    pub samples: u64,
    /// Seconds spent in photon-map and cache lookups, summed over threads.
    pub lookup_s: f64,
    /// Lookups answered by the cache.
    pub cache_hits: u64,
    /// Lookups that fell back to the k-nearest estimate.
    pub cache_misses: u64,
    /// Seconds to build the irradiance cache (0 when none was built here).
    pub cache_build_s: f64,
    /// Entries of the cache read (0 without one).
    pub cache_entries: usize,
    /// Bytes per cache entry (0 without one).
    pub cache_bytes_per_entry: usize,
}

struct Ctx<'a> {
    scene: &'a Scene,
    rt: &'a CommittedScene,
    maps: Option<&'a RenderMaps>,
    cache: Option<&'a IrradianceCache>,
    lights: LightSampler<'a>,
    view: View,
    gather: u32,
    light_samples: u32,
    spp: u32,
    lookup: Lookup,
    eps: f32,
    show_emitters: bool,
}

/// Per-thread scratch and counters.
struct Scratch {
    neighbors: Vec<Neighbor>,
    lookup_ns: u64,
    hits: u64,
    misses: u64,
}

/// A non-delta hit reached through zero or more mirrors.
struct SurfaceHit<'a> {
    position: Vec3,
    /// Geometric normal flipped to the side the ray came from.
    normal: Vec3,
    /// Shading normal (interpolated vertex normals when the mesh has them),
    /// on the same side as `normal`.
    shading: Vec3,
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

    /// The shading normal at `h`, on the side of `normal` (the flipped
    /// geometric normal), and facing `wo` (else the geometric one is used).
    fn shading_normal(&self, h: &Hit, normal: Vec3, wo: Vec3) -> Vec3 {
        let Some(mesh) = self.scene.meshes.get(h.geom_id as usize) else {
            return normal;
        };
        let Some(ns) = mesh.shading_normal(h.prim_id as usize, h.u, h.v) else {
            return normal;
        };
        let ns = if ns.dot(normal) < 0.0 { -ns } else { ns };
        if ns.dot(wo) > 0.0 {
            ns
        } else {
            normal
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
            let shading = self.shading_normal(&h, normal, wo);
            if !material.brdf.is_delta() {
                return Some(SurfaceHit {
                    position,
                    normal,
                    shading,
                    wo,
                    material,
                    throughput,
                });
            }
            let frame = Frame::from_normal(shading);
            let bs = material
                .brdf
                .sample(frame.local_from_world(wo), rng.next_2d())?;
            throughput *= bs.weight;
            let out = frame.world_from_local(bs.wo);
            if throughput.max_element() <= 0.0 || out.dot(normal) <= 0.0 {
                return None;
            }
            ray = Ray::new(position + normal * self.eps, out);
        }
        None
    }

    fn estimate(&self, map: &PhotonMap, s: &SurfaceHit, sc: &mut Scratch) -> Vec3 {
        let t = Instant::now();
        let v = radiance_estimate(
            map,
            &s.material.brdf,
            s.position,
            s.normal,
            s.wo,
            self.lookup,
            &mut sc.neighbors,
        )
        .value;
        sc.lookup_ns += t.elapsed().as_nanos() as u64;
        v
    }

    /// Radiance leaving a gather hit `y`: the cache's irradiance times
    /// `albedo / pi` on a diffuse surface, else the full map's estimate.
    fn cached_radiance(
        &self,
        maps: &RenderMaps,
        y: &SurfaceHit,
        rng: &mut Rng,
        sc: &mut Scratch,
    ) -> Vec3 {
        if let (Some(cache), Brdf::Lambert(l)) = (self.cache, &y.material.brdf) {
            let t = Instant::now();
            let [u0, u1] = rng.next_2d();
            let e = cache.irradiance(y.position, y.normal, [u0, u1, rng.next_f32()]);
            sc.lookup_ns += t.elapsed().as_nanos() as u64;
            if let Some(e) = e {
                sc.hits += 1;
                return l.albedo * FRAC_1_PI * e;
            }
            sc.misses += 1;
        }
        self.estimate(&maps.full, y, sc)
    }

    /// Final gather from `s`: BRDF-sampled rays (stratified over the pixel's
    /// samples), the cache (or the full map) at their hits.
    fn gather(
        &self,
        maps: &RenderMaps,
        s: &SurfaceHit,
        (px, sample): (&PixelSampler, u32),
        rng: &mut Rng,
        sc: &mut Scratch,
    ) -> Vec3 {
        let frame = Frame::from_normal(s.shading);
        let wo_l = frame.local_from_world(s.wo);
        let mut sum = Vec3::ZERO;
        let n = self.spp * self.gather;
        for j in 0..self.gather {
            let u = px.get_2d(dim::GATHER, sample * self.gather + j, n);
            let Some(bs) = s.material.brdf.sample(wo_l, u) else {
                continue;
            };
            let dir = frame.world_from_local(bs.wo);
            if dir.dot(s.normal) <= 0.0 {
                continue;
            }
            let ray = Ray::new(s.position + s.normal * self.eps, dir);
            // Emission straight from a light was counted by light sampling;
            // after a mirror it is a caustic only the gather finds.
            let mut emitted = Vec3::ZERO;
            if let Some(y) = self.trace(ray, 1, rng, &mut emitted) {
                sum += bs.weight * y.throughput * self.cached_radiance(maps, &y, rng, sc);
            }
            sum += bs.weight * emitted;
        }
        sum / self.gather as f32
    }

    /// Direct light at `s`: `light_samples` stratified light samples.
    fn direct(&self, s: &SurfaceHit, (px, sample): (&PixelSampler, u32)) -> Vec3 {
        let l = self.light_samples;
        let mut sum = Vec3::ZERO;
        for j in 0..l {
            let u = px.get_2d(dim::LIGHT, sample * l + j, self.spp * l);
            sum += self.lights.sample(
                self.rt,
                &s.material.brdf,
                [s.position, s.normal, s.shading, s.wo],
                self.eps,
                u,
            );
        }
        sum / l as f32
    }

    fn radiance(
        &self,
        ray: Ray,
        px: (&PixelSampler, u32),
        rng: &mut Rng,
        sc: &mut Scratch,
    ) -> Vec3 {
        let mut l = Vec3::ZERO;
        let first = if self.show_emitters { 0 } else { u32::MAX };
        let Some(s) = self.trace(ray, first, rng, &mut l) else {
            return l;
        };
        let local = match (self.view, self.maps) {
            (View::DirectOnly, _) => self.direct(&s, px),
            (View::Map { primary_only }, Some(m)) => {
                let map = if primary_only { &m.primary } else { &m.full };
                self.estimate(map, &s, sc)
            }
            (View::Full, Some(m)) => {
                let indirect = if self.gather > 0 {
                    self.gather(m, &s, px, rng, sc)
                } else {
                    self.estimate(&m.indirect, &s, sc)
                };
                self.direct(&s, px) + indirect
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
/// map when `maps` is `None`.
pub fn render(
    scene: &Scene,
    rt: &CommittedScene,
    maps: Option<&RenderMaps>,
    cfg: &RenderConfig,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<Image> {
    render_with(scene, rt, maps, None, cfg, progress).map(|(image, _)| image)
}

/// [`render`] returning the render's [`RenderStats`]. The gather reads its
/// hits from `cache` when given; else, when the settings ask for a cache
/// (`cache_stride > 0`, a gather, the full view), one is built from
/// `maps.full` first (its time is in [`RenderStats::cache_build_s`]).
///
/// # Errors
/// As [`render`].
pub fn render_with(
    scene: &Scene,
    rt: &CommittedScene,
    maps: Option<&RenderMaps>,
    cache: Option<&IrradianceCache>,
    cfg: &RenderConfig,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<(Image, RenderStats)> {
    cfg.validate()?;
    if maps.is_none() && cfg.view != View::DirectOnly {
        return Err(Error::param(
            "photon map",
            "this view reads the photon map; pass one or use the direct-only view",
        ));
    }
    let mut image = Image::new(cfg.width, cfg.height)?;
    let max_radius = cfg.max_radius.unwrap_or_else(|| default_max_radius(scene));
    let lookup = Lookup {
        k: cfg.k,
        max_radius,
    };
    let built = match (cache, maps) {
        (None, Some(m))
            if cfg.cache_stride > 0 && cfg.final_gather > 0 && cfg.view == View::Full =>
        {
            let (lo, hi) = scene.bounds();
            let c = CacheConfig {
                stride: cfg.cache_stride,
                lookup,
            };
            Some(IrradianceCache::build(&m.full, rt, (hi - lo).length(), &c)?)
        }
        _ => None,
    };
    let cache = cache.or(built.as_ref());
    let camera = cfg.camera_for(scene);
    let rays = CameraRays::new(&camera, cfg.width, cfg.height);
    let ctx = Ctx {
        scene,
        rt,
        maps,
        cache,
        lights: LightSampler::new(scene),
        view: cfg.view,
        gather: cfg.final_gather,
        light_samples: cfg.light_samples,
        spp: cfg.spp,
        lookup,
        eps: ray_epsilon(scene),
        show_emitters: cfg.show_emitters,
    };
    let width = cfg.width as usize;
    let rows = cfg.height as u64;
    let done = AtomicU64::new(0);
    let (lookup_ns, hits, misses) = (AtomicU64::new(0), AtomicU64::new(0), AtomicU64::new(0));
    let inv_spp = 1.0 / cfg.spp as f32;
    image
        .pixels
        .par_chunks_mut(width)
        .enumerate()
        .for_each(|(y, row)| {
            let mut sc = Scratch {
                neighbors: Vec::with_capacity(cfg.k),
                lookup_ns: 0,
                hits: 0,
                misses: 0,
            };
            for (x, px) in row.iter_mut().enumerate() {
                let pixel = (y * width + x) as u64;
                let key = hash2(cfg.seed, pixel);
                let sampler = PixelSampler::new(key);
                let mut sum = Vec3::ZERO;
                for s in 0..cfg.spp {
                    let mut rng = Rng::new(hash2(key, s as u64));
                    let [jx, jy] = sampler.get_2d(dim::PIXEL, s, cfg.spp);
                    let ray = rays.ray(x as f32 + jx, y as f32 + jy);
                    let l = ctx.radiance(ray, (&sampler, s), &mut rng, &mut sc);
                    // A NaN or infinite sample (degenerate geometry) is dropped, not spread.
                    if l.is_finite() {
                        sum += l;
                    }
                }
                *px = sum * inv_spp;
            }
            lookup_ns.fetch_add(sc.lookup_ns, Ordering::Relaxed);
            hits.fetch_add(sc.hits, Ordering::Relaxed);
            misses.fetch_add(sc.misses, Ordering::Relaxed);
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, rows);
        });
    let stats = RenderStats {
        samples: cfg.width as u64 * cfg.height as u64 * cfg.spp as u64,
        lookup_s: lookup_ns.into_inner() as f64 * 1e-9,
        cache_hits: hits.into_inner(),
        cache_misses: misses.into_inner(),
        cache_build_s: built.as_ref().map_or(0.0, |c| c.build_s),
        cache_entries: cache.map_or(0, |c| c.len()),
        cache_bytes_per_entry: cache.map_or(0, |c| c.bytes_per_entry()),
    };
    Ok((image, stats))
}
