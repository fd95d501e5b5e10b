//! The camera's side of the importance pass ([`crate::importance`]): one
//! camera sample walked with the renderer's own estimator, its pixel
//! sampler, random stream and gather sampling ([`super::integrator`]), the
//! points where the render would read photons handed to a callback with the
//! path's throughput.
//!
//! - **First hit**: the camera ray through mirrors and glass to its first
//!   non-specular hit `x` ([`Ctx::trace`]), where the caustic map (and,
//!   without a gather, the indirect map) is read.
//! - **Gather hits**: the gather's BRDF-sampled rays from `x`
//!   ([`Ctx::gather_ray`], the pixel's stratified [`dim::GATHER`] points),
//!   through mirrors and glass to `y`, where the gather reads the
//!   irradiance cache or the full map; weight `T_x * f cos / pdf * T_y / G`.
//! - **Continuation**: from `y`, further BRDF-sampled bounces (the sample's
//!   own random stream), each hit `z` weighted by the product so far. Nothing
//!   reads photons at `z`; its deposit estimates the adjoint there: what a
//!   photon at `z` may still bring to the image by its later bounces.

use super::camera::CameraRays;
use super::direct::LightSampler;
use super::estimate::Lookup;
use super::film::{camera_ray, Sample};
use super::integrator::{Ctx, SurfaceHit};
use super::sampler::{dim, PixelSampler};
use super::{ray_epsilon, View};
use crate::raycast::RayCaster;
use crate::rng::{hash2, Rng};
use crate::scene::{Camera, Scene};
use glam::Vec3;

/// Which reader a deposit is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Reader {
    /// The first non-specular hit of a camera ray.
    First = 0,
    /// A gather ray's hit.
    Gather = 1,
    /// A later bounce of the camera path: read by nobody, adjoint only.
    Later = 2,
}

/// How many camera samples and rays the walk takes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct WalkSettings {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub gather: u32,
    /// Bounces after the gather hit.
    pub later_bounces: u32,
    pub seed: u64,
}

/// The renderer's estimator, set up to walk camera samples.
pub(crate) struct CameraWalk<'a> {
    ctx: Ctx<'a>,
    rays: CameraRays,
    settings: WalkSettings,
}

impl<'a> CameraWalk<'a> {
    /// A walk over `scene` through `rt` seen by `camera`.
    pub(crate) fn new(
        scene: &'a Scene,
        rt: &'a dyn RayCaster,
        camera: &Camera,
        settings: WalkSettings,
    ) -> Self {
        // No maps and no cache: the walk only follows rays.
        let lookup = Lookup {
            k: 1,
            max_radius: 1.0,
        };
        let ctx = Ctx {
            scene,
            rt,
            maps: None,
            cache: None,
            lights: LightSampler::over(scene, rt),
            albedo: Vec::new(),
            view: View::Full,
            gather: settings.gather,
            light_samples: 1,
            spp: settings.spp,
            lookup,
            caustic_lookup: lookup,
            eps: ray_epsilon(scene),
            show_emitters: false,
            reads: None,
            guided: false,
        };
        CameraWalk {
            ctx,
            rays: CameraRays::new(camera, settings.width, settings.height),
            settings,
        }
    }

    /// Camera samples of the whole walk: pixels times samples per pixel.
    pub(crate) fn samples(&self) -> u64 {
        let s = &self.settings;
        u64::from(s.width) * u64::from(s.height) * u64::from(s.spp)
    }

    /// Walks camera sample `index` (`pixel * spp + s`, pixels row by row, as
    /// the film numbers them) and calls `deposit(reader, hit, weight)` at
    /// every point the render would read photons at, and at the later
    /// bounces, with the luminance of the path's throughput.
    pub(crate) fn walk(&self, index: u64, deposit: &mut impl FnMut(Reader, &Hit, f32)) {
        let st = &self.settings;
        let spp = u64::from(st.spp);
        let (pixel, s) = (index / spp, (index % spp) as u32);
        let width = u64::from(st.width);
        let sample = Sample {
            x: (pixel % width) as u32,
            y: (pixel / width) as u32,
            s,
        };
        // The film's keys: this sample is the render's sample.
        let key = hash2(st.seed, pixel);
        let px = PixelSampler::new(key);
        let mut rng = Rng::new(hash2(key, u64::from(s)));
        let ray = camera_ray(&self.rays, sample, px.get_2d(dim::PIXEL, s, st.spp));
        let mut ignored = Vec3::ZERO;
        let Some(x) = self.ctx.trace(ray, u32::MAX, &mut rng, &mut ignored) else {
            return;
        };
        deposit(Reader::First, &Hit::of(&x), lum(x.throughput));
        let n = st.spp * st.gather;
        for j in 0..st.gather {
            let u = px.get_2d(dim::GATHER, s * st.gather + j, n);
            let Some((weight, ray)) = self.ctx.gather_ray(&x, u) else {
                continue;
            };
            let Some(y) = self.ctx.trace(ray, u32::MAX, &mut rng, &mut ignored) else {
                continue;
            };
            let t = x.throughput * weight * y.throughput / st.gather as f32;
            deposit(Reader::Gather, &Hit::of(&y), lum(t));
            self.later(y, t, &mut rng, deposit);
        }
    }

    /// The bounces after a gather hit `y` reached with throughput `t`.
    fn later(
        &self,
        mut y: SurfaceHit,
        mut t: Vec3,
        rng: &mut Rng,
        deposit: &mut impl FnMut(Reader, &Hit, f32),
    ) {
        let mut ignored = Vec3::ZERO;
        for _ in 0..self.settings.later_bounces {
            let Some((weight, ray)) = self.ctx.gather_ray(&y, rng.next_2d()) else {
                return;
            };
            let Some(z) = self.ctx.trace(ray, u32::MAX, rng, &mut ignored) else {
                return;
            };
            t *= weight * z.throughput;
            let alive = t.max_element() > 0.0; // false for NaN too
            if !alive {
                return;
            }
            deposit(Reader::Later, &Hit::of(&z), lum(t));
            y = z;
        }
    }
}

/// Where a deposit lands: a point and the geometric normal on the side the
/// ray arrived from (the side whose photons the render reads).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Hit {
    pub position: Vec3,
    pub normal: Vec3,
}

impl Hit {
    fn of(s: &SurfaceHit) -> Self {
        Hit {
            position: s.position,
            normal: s.normal,
        }
    }
}

fn lum(v: Vec3) -> f32 {
    crate::sampling::luminance(v)
}
