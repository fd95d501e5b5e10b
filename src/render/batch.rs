//! The photon render's samples of a pixel in batches: their camera rays,
//! shadow rays and final-gather rays each go to the ray caster as one batch
//! (Embree's packets: 1.3–1.5x the single-ray rate on incoherent rays,
//! `adaptive-pm bench rays`), where [`Ctx::radiance`] casts them one by
//! one. Every sample draws the same random numbers in the same order and
//! adds the same terms in the same order as there, so the image is bitwise
//! the same. Paths through mirrors and glass go on with single rays after
//! their batched first hit ([`Ctx::follow`]).

use super::integrator::{Ctx, GuideMemo, SampleScratch, SurfaceHit};
use super::sampler::{dim, PixelSampler};
use super::View;
use crate::raycast::{Hit, Ray};
use crate::rng::Rng;
use glam::Vec3;

/// A batch's buffers, kept by a row between batches.
#[derive(Default)]
pub(super) struct Batch {
    /// Gather rays per sample of the batch's pixel.
    gather: u32,
    /// Each sample's index among the pixel's samples.
    samples: Vec<u32>,
    /// Each sample's camera ray.
    camera: Vec<Ray>,
    /// Each sample's first non-specular hit (`None`: the sample is done).
    surfaces: Vec<Option<SurfaceHit>>,
    /// The rays of one batched step, their hits and shadow tests.
    rays: Vec<Ray>,
    hits: Vec<Option<Hit>>,
    blocked: Vec<bool>,
    /// Per ray of the step: its sample and its weight (a gather ray's) or
    /// contribution (a light sample's).
    owners: Vec<(usize, Vec3)>,
    direct: Vec<Vec3>,
    indirect: Vec<Vec3>,
    /// The last gather guide looked up.
    guide: GuideMemo,
}

impl Batch {
    /// Starts a batch of `(sample index, camera ray)` of a pixel that
    /// gathers with `gather` rays a sample.
    pub(super) fn start(&mut self, gather: u32, samples: impl Iterator<Item = (u32, Ray)>) {
        self.gather = gather;
        self.samples.clear();
        self.camera.clear();
        for (s, ray) in samples {
            self.samples.push(s);
            self.camera.push(ray);
        }
    }

    /// Casts `self.rays` as one batch into `self.hits`.
    fn intersect(&mut self, ctx: &Ctx<'_>) {
        self.hits.clear();
        self.hits.resize(self.rays.len(), None);
        ctx.rt.intersect_batch(&self.rays, &mut self.hits);
    }
}

impl Ctx<'_> {
    /// Whether [`Self::radiance_batch`] serves this render: the full view
    /// with a final gather (the default). Other views take one sample at a
    /// time.
    pub(super) fn batches(&self) -> bool {
        self.view == View::Full && self.maps.is_some() && self.gather > 0
    }

    /// [`Self::radiance`] of every sample of `batch` (begun with
    /// [`Batch::start`]) of the pixel `px`, sample `k` drawing from
    /// `rngs[k]`, into `out[k]`. Only when [`Self::batches`].
    pub(super) fn radiance_batch(
        &self,
        px: &PixelSampler,
        rngs: &mut [Rng],
        sc: &mut SampleScratch,
        b: &mut Batch,
        out: &mut [Vec3],
    ) {
        let Some(maps) = self.maps else {
            return;
        };
        let first_emission = if self.show_emitters { 0 } else { u32::MAX };
        // First hits: the camera rays in one batch.
        std::mem::swap(&mut b.rays, &mut b.camera);
        b.intersect(self);
        b.surfaces.clear();
        for (k, rng) in rngs.iter_mut().enumerate() {
            let mut seen = Vec3::ZERO;
            let s = self.follow(b.rays[k], b.hits[k], first_emission, rng, &mut seen);
            out[k] = seen;
            b.surfaces.push(s);
        }
        std::mem::swap(&mut b.rays, &mut b.camera);
        self.gather_batch(maps, px, rngs, sc, b);
        self.direct_batch(px, b);
        for (k, s) in b.surfaces.iter().enumerate() {
            if let Some(s) = s {
                let caustic = self.estimate_with(&maps.caustic, self.caustic_lookup, s, sc);
                let local = b.direct[k] + caustic + b.indirect[k];
                out[k] += s.throughput * local;
            }
        }
    }

    /// The final gather of every sample with a surface, `b.gather` rays
    /// each, into `b.indirect`:
    /// [`Ctx::gather`]'s rays in one batch.
    fn gather_batch(
        &self,
        maps: &super::RenderMaps,
        px: &PixelSampler,
        rngs: &mut [Rng],
        sc: &mut SampleScratch,
        b: &mut Batch,
    ) {
        let g = b.gather;
        let n = self.spp * g;
        b.rays.clear();
        b.owners.clear();
        for (k, s) in b.surfaces.iter().enumerate() {
            let Some(s) = s else { continue };
            let guide = self.guide_reusing(s, &mut b.guide);
            for j in 0..g {
                let u = px.get_2d(dim::GATHER, b.samples[k] * g + j, n);
                if let Some((weight, ray)) = self.gather_ray_with(s, u, guide) {
                    b.rays.push(ray);
                    b.owners.push((k, weight));
                }
            }
        }
        b.intersect(self);
        b.indirect.clear();
        b.indirect.resize(b.surfaces.len(), Vec3::ZERO);
        for (i, &(k, weight)) in b.owners.iter().enumerate() {
            // Emission straight from a light was counted by light sampling,
            // and through mirrors and glass by the caustic map.
            let mut emitted = Vec3::ZERO;
            let rng = &mut rngs[k];
            if let Some(y) = self.follow(b.rays[i], b.hits[i], u32::MAX, rng, &mut emitted) {
                b.indirect[k] += weight * y.throughput * self.cached_radiance(maps, &y, rng, sc);
            }
        }
        for v in &mut b.indirect {
            *v /= g as f32;
        }
    }

    /// The direct light of every sample with a surface, into `b.direct`:
    /// [`Ctx::direct`]'s shadow rays in one batch.
    fn direct_batch(&self, px: &PixelSampler, b: &mut Batch) {
        let l = self.light_samples;
        b.rays.clear();
        b.owners.clear();
        for (k, s) in b.surfaces.iter().enumerate() {
            let Some(s) = s else { continue };
            for j in 0..l {
                let (i, n) = (b.samples[k] * l + j, self.spp * l);
                let arrival = self.lights.unshadowed_with(
                    &s.brdf,
                    [s.position, s.normal, s.shading, s.wo],
                    self.eps,
                    px.get_2d(dim::LIGHT, i, n),
                    || px.get_2d(dim::LIGHT_POINT, i, n),
                );
                if let Some((ray, light)) = arrival {
                    b.rays.push(ray);
                    b.owners.push((k, light));
                }
            }
        }
        b.blocked.clear();
        b.blocked.resize(b.rays.len(), false);
        self.rt.occluded_batch(&b.rays, &mut b.blocked);
        b.direct.clear();
        b.direct.resize(b.surfaces.len(), Vec3::ZERO);
        for (&(k, light), &blocked) in b.owners.iter().zip(&b.blocked) {
            if !blocked {
                b.direct[k] += light;
            }
        }
        for v in &mut b.direct {
            *v /= l as f32;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::embree::Device;
    use crate::engine::{Budget, Mode, TraceConfig, Tracer};
    use crate::render::cache::{CacheConfig, IrradianceCache};
    use crate::render::estimate::Lookup;
    use crate::render::{default_max_radius, RenderMaps};
    use crate::rng::hash2;
    use crate::scene::Scene;

    /// Through glass and a mirror, with the emitters seen or not, two light
    /// samples and 1 to 3 gather rays a sample, a batch of samples gives each sample's radiance to
    /// the bit, as one [`Ctx::radiance`] per sample does (with the cache
    /// and without, when the gather reads the k nearest photons).
    #[test]
    fn a_batch_gives_each_samples_radiance_to_the_bit() {
        let scene = Scene::open("cornell-glass").unwrap();
        let tracer = Tracer::new(scene.clone().commit(&Device::new().unwrap()).unwrap());
        let prepared = tracer.prepared();
        let mut tc = TraceConfig::new(Mode::Adaptive, Budget::NMax(20_000));
        tc.seed = 3;
        let maps = RenderMaps::build(&tracer.trace(&tc).unwrap().records());
        let lookup = Lookup {
            k: 50,
            max_radius: default_max_radius(&scene),
        };
        let cache =
            IrradianceCache::build(&maps.full, prepared, &CacheConfig { stride: 8, lookup })
                .unwrap();
        let rt: &dyn crate::raycast::RayCaster = prepared.caster();
        let (lo, hi) = scene.bounds();
        let (spp, width) = (20u32, 12u32);
        for (show_emitters, with_cache) in [(false, true), (true, true), (true, false)] {
            let ctx = Ctx {
                gather: 2,
                light_samples: 2,
                spp,
                show_emitters,
                ..Ctx::for_tests(&scene, rt, &maps, with_cache.then_some(&cache), lookup)
            };
            assert!(ctx.batches());
            let mut sc = SampleScratch::new(lookup.k);
            let mut batch = Batch::default();
            let mut lit = 0;
            // Rays from the box's open front towards points spread over it.
            let eye = Vec3::new(
                0.5 * (lo.x + hi.x),
                0.5 * (lo.y + hi.y),
                lo.z - (hi.z - lo.z),
            );
            for pixel in 0..width * width {
                let px = PixelSampler::new(hash2(5, u64::from(pixel)));
                // Pixels gather with their own counts, as a plan makes them.
                let g = 1 + pixel % 3;
                let target = lo
                    + (hi - lo)
                        * Vec3::new(
                            ((pixel % width) as f32 + 0.5) / width as f32,
                            ((pixel / width) as f32 + 0.5) / width as f32,
                            1.0,
                        );
                let ray = |s: u32| {
                    let [jx, jy] = px.get_2d(dim::PIXEL, s, spp);
                    Ray::new(eye, target + Vec3::new(jx, jy, 0.0) * 20.0 - eye)
                };
                let stream = |s: u32| Rng::new(hash2(u64::from(pixel), u64::from(s)));
                let one_by_one: Vec<Vec3> = (0..spp)
                    .map(|s| ctx.radiance(ray(s), (&px, s), g, &mut stream(s), &mut sc))
                    .collect();
                let mut rngs: Vec<Rng> = (0..spp).map(stream).collect();
                let mut out = vec![Vec3::ZERO; spp as usize];
                batch.start(g, (0..spp).map(|s| (s, ray(s))));
                ctx.radiance_batch(&px, &mut rngs, &mut sc, &mut batch, &mut out);
                for (a, b) in one_by_one.iter().zip(&out) {
                    assert_eq!(
                        a.to_array().map(f32::to_bits),
                        b.to_array().map(f32::to_bits)
                    );
                }
                lit += out.iter().filter(|l| l.max_element() > 0.0).count();
            }
            // Nearly every sample sees light: the comparison is not of zeros.
            assert!(lit * 10 > 9 * (spp * width * width) as usize, "{lit} lit");
        }
    }
}
