//! The per-sample estimator (see the module docs of [`super`]): each sample
//! with its own counter-based random stream and the pixel's stratified
//! points ([`super::sampler`]). The image loop is in [`super::film`].

use super::batch::Batch;
use super::cache::{Guide, IrradianceCache};
use super::direct::LightSampler;
use super::estimate::{radiance_estimate, Lookup};
use super::reads::{MapReads, RowReads};
use super::sampler::{dim, PixelSampler};
use super::{RenderMaps, View, MAX_SPECULAR};
use crate::brdf::{Brdf, Transport};
use crate::engine::albedo::AlbedoTable;
use crate::photon_map::{Neighbor, PhotonMap};
use crate::raycast::{Hit, Ray, RayCaster};
use crate::rng::Rng;
use crate::sampling::Frame;
use crate::scene::{consistent_with_geometry, Material, Scene};
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;
use std::time::Instant;

pub(super) struct Ctx<'a> {
    pub(super) scene: &'a Scene,
    pub(super) rt: &'a dyn RayCaster,
    pub(super) maps: Option<&'a RenderMaps>,
    pub(super) cache: Option<&'a IrradianceCache>,
    pub(super) lights: LightSampler<'a>,
    /// Directional albedo of each material (glossy gather hits).
    pub(super) albedo: Vec<AlbedoTable>,
    pub(super) view: View,
    pub(super) gather: u32,
    pub(super) light_samples: u32,
    pub(super) spp: u32,
    pub(super) lookup: Lookup,
    /// The caustic map's kernel.
    pub(super) caustic_lookup: Lookup,
    pub(super) eps: f32,
    pub(super) show_emitters: bool,
    /// Marks of the photons the lookups return, when asked for.
    pub(super) reads: Option<&'a MapReads<'a>>,
    /// Whether a diffuse gather draws its directions from the cache's
    /// guides ([`IrradianceCache::guide`]).
    pub(super) guided: bool,
}
#[cfg(test)]
impl<'a> Ctx<'a> {
    /// The full view of `maps` (and `cache`) for unit tests: one gather
    /// ray, one light sample, one sample a pixel, the emitters hidden, the
    /// gather guided.
    pub(super) fn for_tests(
        scene: &'a Scene,
        rt: &'a dyn RayCaster,
        maps: &'a RenderMaps,
        cache: Option<&'a IrradianceCache>,
        lookup: Lookup,
    ) -> Self {
        Ctx {
            scene,
            rt,
            maps: Some(maps),
            cache,
            lights: LightSampler::over(scene, rt),
            albedo: scene
                .materials()
                .iter()
                .map(|m| AlbedoTable::new(&m.brdf))
                .collect(),
            view: View::Full,
            gather: 1,
            light_samples: 1,
            spp: 1,
            lookup,
            caustic_lookup: lookup,
            eps: super::ray_epsilon(scene),
            show_emitters: false,
            reads: None,
            guided: true,
        }
    }
}

/// One lookup in this many is timed, its time counted this many times: a
/// clock read per lookup cost 3.5 % of a render (`__vdso_clock_gettime` in
/// the profile), for a figure that is a diagnostic. Lookups of a row are
/// alike, so the estimate's error is far below the run-to-run noise.
const LOOKUP_TIMING_STRIDE: u64 = 16;

/// Per-thread scratch and counters.
pub(super) struct SampleScratch {
    pub(super) neighbors: Vec<Neighbor>,
    pub(super) lookup_ns: u64,
    pub(super) lookups: u64,
    pub(super) hits: u64,
    pub(super) misses: u64,
    /// The row's marks (empty unless the render marks its reads).
    pub(super) reads: RowReads,
    /// The buffers of the row's batches of samples.
    pub(super) batch: Batch,
}

impl SampleScratch {
    pub(super) fn new(k: usize) -> Self {
        SampleScratch {
            neighbors: Vec::with_capacity(k),
            lookup_ns: 0,
            lookups: 0,
            hits: 0,
            misses: 0,
            reads: RowReads::default(),
            batch: Batch::default(),
        }
    }

    /// Starts a lookup: a clock when this one is timed.
    fn start_lookup(&mut self) -> Option<Instant> {
        self.lookups += 1;
        (self.lookups % LOOKUP_TIMING_STRIDE == 0).then(Instant::now)
    }

    fn end_lookup(&mut self, start: Option<Instant>) {
        if let Some(t) = start {
            let ns = (t.elapsed().as_nanos() as u64).saturating_sub(clock_overhead_ns());
            self.lookup_ns += ns * LOOKUP_TIMING_STRIDE;
        }
    }
}

/// What an empty timed interval reads on this machine (the median of 255),
/// taken off each timed lookup: on a VM the clock's two reads are a
/// sizeable part of a cache lookup's timed interval, and `lookup_s` would
/// count them as the lookups' time.
fn clock_overhead_ns() -> u64 {
    static OVERHEAD: std::sync::OnceLock<u64> = std::sync::OnceLock::new();
    *OVERHEAD.get_or_init(|| {
        let mut empty: Vec<u64> = (0..255)
            .map(|_| {
                let t = Instant::now();
                t.elapsed().as_nanos() as u64
            })
            .collect();
        empty.sort_unstable();
        empty[empty.len() / 2]
    })
}

/// The last guide looked up, with its cell's key and the bits of the
/// normals it was made for ([`Ctx::guide_reusing`]).
#[derive(Default)]
pub(super) struct GuideMemo(Option<(u64, [[u32; 3]; 2], Option<Guide>)>);

/// A non-delta hit reached through zero or more mirrors.
pub(super) struct SurfaceHit {
    pub(super) position: Vec3,
    /// Geometric normal flipped to the side the ray came from.
    pub(super) normal: Vec3,
    /// Shading normal (interpolated vertex normals when the mesh has them),
    /// on the same side as `normal`.
    pub(super) shading: Vec3,
    /// Unit direction back along the ray.
    pub(super) wo: Vec3,
    material_index: usize,
    /// The BRDF at this point (a textured material's, from its texels).
    pub(super) brdf: Brdf,
    /// Product of the mirror weights on the way.
    pub(super) throughput: Vec3,
}

impl<'a> Ctx<'a> {
    /// Emission at `h` towards `wo` (its texel's, for an emissive texture).
    fn emitted(&self, material: &Material, h: &Hit, wo: Vec3) -> Vec3 {
        match material.emission {
            Some(_) => self.scene.emitted_radiance(h, wo),
            None => Vec3::ZERO,
        }
    }

    /// Follows `ray` through mirrors and glass to its first non-specular
    /// hit (camera paths carry radiance: [`Transport::Radiance`]). Emission
    /// seen at hit `first_emission` (0 = the first hit) and later is added
    /// to `emitted`.
    pub(super) fn trace(
        &self,
        ray: Ray,
        first_emission: u32,
        rng: &mut Rng,
        emitted: &mut Vec3,
    ) -> Option<SurfaceHit> {
        let first = self.rt.intersect(&ray);
        self.follow(ray, first, first_emission, rng, emitted)
    }

    /// [`Self::trace`] of `ray` whose closest hit, `first`, is already
    /// known (from a batch of rays): the same result, the same random
    /// numbers drawn.
    #[inline(always)]
    pub(super) fn follow(
        &self,
        mut ray: Ray,
        first: Option<Hit>,
        first_emission: u32,
        rng: &mut Rng,
        emitted: &mut Vec3,
    ) -> Option<SurfaceHit> {
        let mut throughput = Vec3::ONE;
        let mut hit = first;
        for bounce in 0..=MAX_SPECULAR {
            let h = hit?;
            let material = self.scene.materials.get(h.material as usize)?;
            let dir = ray.dir.normalize();
            let wo = -dir;
            let position = ray.at(h.t);
            let from_inside = h.ng.dot(dir) > 0.0;
            if from_inside {
                // The segment just travelled lay inside this (closed) object.
                if let Some(sigma) = self.scene.interior_attenuation(h.material) {
                    throughput *= (-sigma * h.t * ray.dir.length()).exp();
                }
            }
            let normal = h.facing(dir);
            if bounce >= first_emission {
                *emitted += throughput * self.emitted(material, &h, wo);
            }
            // A partly transmitting surface scatters by one of its parts.
            let scattering = self
                .scene
                .scattering_material(h.material, || rng.next_f32());
            let material = &self.scene.materials[scattering as usize];
            if !material.brdf.is_specular() {
                return Some(SurfaceHit {
                    position,
                    normal,
                    shading: self.scene.shading_side(&h, normal, wo),
                    wo,
                    material_index: h.material as usize,
                    brdf: self.scene.surface_brdf(&h)?,
                    throughput,
                });
            }
            let n = self
                .scene
                .scattering_normal(&material.brdf, &h, from_inside);
            let frame = Frame::from_normal(n);
            let wo_l = frame.local_from_world(wo);
            let bs = material
                .brdf
                .sample_in(wo_l, rng.next_2d(), Transport::Radiance)?;
            throughput *= bs.weight;
            let out = frame.world_from_local(bs.wo);
            let transmitted = bs.wo.z * wo_l.z < 0.0;
            let alive = throughput.max_element() > 0.0; // false for NaN too
            if !alive || !consistent_with_geometry(h.ng, wo, out, transmitted) {
                return None;
            }
            let side = h.facing(-out);
            ray = Ray::new(position + side * self.eps, out);
            if bounce == MAX_SPECULAR {
                break;
            }
            hit = self.rt.intersect(&ray);
        }
        None
    }

    fn estimate(&self, map: &PhotonMap, s: &SurfaceHit, sc: &mut SampleScratch) -> Vec3 {
        self.estimate_with(map, self.lookup, s, sc)
    }

    pub(super) fn estimate_with(
        &self,
        map: &PhotonMap,
        lookup: Lookup,
        s: &SurfaceHit,
        sc: &mut SampleScratch,
    ) -> Vec3 {
        if map.is_empty() {
            return Vec3::ZERO;
        }
        let t = sc.start_lookup();
        let v = radiance_estimate(
            map,
            &s.brdf,
            s.position,
            s.normal,
            s.wo,
            lookup,
            &mut sc.neighbors,
        )
        .value;
        sc.end_lookup(t);
        if let Some(reads) = self.reads {
            sc.reads.mark(reads, map, &sc.neighbors);
        }
        v
    }

    /// Radiance leaving a gather hit `y`: the cache's irradiance times
    /// `albedo / pi` (a glossy surface is read as a diffuse one of its
    /// directional albedo towards the gather ray: biased there, but without
    /// the fireflies of a glossy k-nearest estimate), else, on a cache miss
    /// or without a cache, the full map's estimate.
    pub(super) fn cached_radiance(
        &self,
        maps: &RenderMaps,
        y: &SurfaceHit,
        rng: &mut Rng,
        sc: &mut SampleScratch,
    ) -> Vec3 {
        if let Some(cache) = self.cache {
            let t = sc.start_lookup();
            let [u0, u1] = rng.next_2d();
            let e = cache.irradiance(y.position, y.normal, [u0, u1, rng.next_f32()], self.rt);
            sc.end_lookup(t);
            if let Some(e) = e {
                sc.hits += 1;
                let albedo = match &y.brdf {
                    Brdf::Lambert(l) => l.albedo,
                    _ => self.albedo[y.material_index].at(y.wo.dot(y.shading)),
                };
                return albedo * FRAC_1_PI * e;
            }
            sc.misses += 1;
        }
        self.estimate(&maps.full, y, sc)
    }

    /// Final gather from `s`: `g` BRDF-sampled rays (stratified over the
    /// pixel's samples), the cache (or the full map) at their hits.
    fn gather(
        &self,
        maps: &RenderMaps,
        s: &SurfaceHit,
        (px, sample): (&PixelSampler, u32),
        g: u32,
        rng: &mut Rng,
        sc: &mut SampleScratch,
    ) -> Vec3 {
        let mut sum = Vec3::ZERO;
        let n = self.spp * g;
        let guide = self.guide_at(s);
        for j in 0..g {
            let u = px.get_2d(dim::GATHER, sample * g + j, n);
            let Some((weight, ray)) = self.gather_ray_with(s, u, guide.as_ref()) else {
                continue;
            };
            // Emission straight from a light was counted by light sampling,
            // and through mirrors and glass by the caustic map.
            let mut emitted = Vec3::ZERO;
            if let Some(y) = self.trace(ray, u32::MAX, rng, &mut emitted) {
                sum += weight * y.throughput * self.cached_radiance(maps, &y, rng, sc);
            }
        }
        sum / g as f32
    }

    /// A BRDF-sampled ray leaving `s` from the point `u` in `[0, 1)^2`, and
    /// its weight (BRDF times cosine over pdf): the gather's sampling, also
    /// the importance pass's ([`super::importance_walk`]). `None` for no
    /// sample or one below the surface.
    #[inline(always)]
    pub(super) fn gather_ray(&self, s: &SurfaceHit, u: [f32; 2]) -> Option<(Vec3, Ray)> {
        let frame = Frame::from_normal(s.shading);
        let bs = s.brdf.sample(frame.local_from_world(s.wo), u)?;
        let dir = frame.world_from_local(bs.wo);
        if dir.dot(s.normal) <= 0.0 {
            return None;
        }
        Some((bs.weight, Ray::new(s.position + s.normal * self.eps, dir)))
    }

    /// The guide a gather from `s` draws its directions from: the cache's
    /// at a diffuse surface, when the render is guided.
    #[inline]
    pub(super) fn guide_at(&self, s: &SurfaceHit) -> Option<Guide> {
        self.guide_reusing(s, &mut GuideMemo::default()).copied()
    }

    /// [`Self::guide_at`], the same value, reusing `memo`'s guide when `s`
    /// is in its cell with its normals (a pixel's samples mostly are):
    /// making a guide for every sample was 30 M of the 140 M instructions
    /// the guide added to a 96² render of 32 spp (callgrind).
    #[inline]
    pub(super) fn guide_reusing<'m>(
        &self,
        s: &SurfaceHit,
        memo: &'m mut GuideMemo,
    ) -> Option<&'m Guide> {
        let (Brdf::Lambert(_), Some(c), true) = (&s.brdf, self.cache, self.guided) else {
            return None;
        };
        let key = c.guide_key(s.position, s.normal)?;
        let normals = [s.normal, s.shading].map(|v| v.to_array().map(f32::to_bits));
        if !matches!(&memo.0, Some((k, n, _)) if *k == key && *n == normals) {
            memo.0 = Some((key, normals, c.guide_of(key, s.normal, s.shading)));
        }
        memo.0.as_ref().and_then(|(_, _, g)| g.as_ref())
    }

    /// [`Self::gather_ray`], its direction drawn from `guide` when there is
    /// one (a diffuse `s`): the weight is the albedo over the guide's
    /// density relative to the cosine's ([`Guide::sample`]).
    // Always inlined: returned through the stack, its ray was written by the
    // callee and read back by wider loads (a store-forwarding stall, 5 % of
    // `radiance_batch` in `perf annotate`).
    #[inline(always)]
    pub(super) fn gather_ray_with(
        &self,
        s: &SurfaceHit,
        u: [f32; 2],
        guide: Option<&Guide>,
    ) -> Option<(Vec3, Ray)> {
        let (Some(g), Brdf::Lambert(l)) = (guide, &s.brdf) else {
            return self.gather_ray(s, u);
        };
        let (dir, inverse) = g.sample(u);
        if dir.dot(s.normal) <= 0.0 || s.wo.dot(s.shading) <= 0.0 {
            return None;
        }
        Some((
            l.albedo * inverse,
            Ray::new(s.position + s.normal * self.eps, dir),
        ))
    }

    /// Direct light at `s`: `light_samples` stratified light samples.
    fn direct(&self, s: &SurfaceHit, (px, sample): (&PixelSampler, u32)) -> Vec3 {
        let l = self.light_samples;
        let mut sum = Vec3::ZERO;
        for j in 0..l {
            let (i, n) = (sample * l + j, self.spp * l);
            sum += self.lights.sample_with(
                &s.brdf,
                [s.position, s.normal, s.shading, s.wo],
                self.eps,
                px.get_2d(dim::LIGHT, i, n),
                || px.get_2d(dim::LIGHT_POINT, i, n),
            );
        }
        sum / l as f32
    }

    /// The radiance one camera sample brings along `ray`: sample `px.1` of
    /// the pixel whose points `px.0` draws, gathering with `g` rays.
    pub(super) fn radiance(
        &self,
        ray: Ray,
        px: (&PixelSampler, u32),
        g: u32,
        rng: &mut Rng,
        sc: &mut SampleScratch,
    ) -> Vec3 {
        let mut l = Vec3::ZERO;
        let first = if self.show_emitters || self.view == View::Emitters {
            0
        } else {
            u32::MAX
        };
        let Some(s) = self.trace(ray, first, rng, &mut l) else {
            return l;
        };
        let local = match (self.view, self.maps) {
            (View::Emitters, _) => Vec3::ZERO,
            (View::DirectOnly, _) => self.direct(&s, px),
            (View::Map { primary_only }, Some(m)) => {
                let map = if primary_only { &m.primary } else { &m.full };
                self.estimate(map, &s, sc)
            }
            (View::Full, Some(m)) => {
                let indirect = if self.gather > 0 {
                    self.gather(m, &s, px, g, rng, sc)
                } else {
                    self.estimate(&m.indirect, &s, sc)
                };
                let caustic = self.estimate_with(&m.caustic, self.caustic_lookup, &s, sc);
                self.direct(&s, px) + caustic + indirect
            }
            (_, None) => Vec3::ZERO,
        };
        l + s.throughput * local
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The clock's overhead is measured once and is a plausible time: a
    /// lookup's time is then its own, less the same figure in every row.
    #[test]
    fn the_clocks_overhead_is_measured_once() {
        let overhead = clock_overhead_ns();
        assert!(overhead < 1_000_000, "{overhead} ns");
        assert_eq!(clock_overhead_ns(), overhead);
    }
}
