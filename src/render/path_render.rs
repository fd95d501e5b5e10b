//! Images and irradiance from the path tracer ([`super::path`]), and its own
//! noise measured from two independent halves.
//!
//! **Noise of a mean of two halves.** With `A` and `B` two renders of
//! independent seeds and the same expectation, `A - B` has twice the variance
//! of one half and `(A + B) / 2` half of it, so the rms noise of the mean is
//! `rmse(A, B) / 2`. Divided by the mean's mean it is the relative noise the
//! trade study compares with the errors it judges.

use super::camera::CameraRays;
use super::film::{self, PixelEstimator, Sample};
use super::metrics::relative_rmse_masked;
use super::path::{PathPart, PathTracer};
use super::run::RenderStats;
use super::{CheckedRender, Image, RenderConfig};
use crate::error::Result;
use crate::raycast::{CheckedCaster, Ray, RayCaster};
use crate::rng::{hash2, Rng};
use crate::sampling::{cosine_hemisphere, Frame};
use crate::scene::{Material, PreparedScene, Scene, SurfacePoint};
use glam::Vec3;
use rayon::prelude::*;
use std::f32::consts::PI;

/// Renders `part` of the light of the scene of `prepared` with the path
/// tracer, on the current rayon pool, over its caster. Reads `width`,
/// `height`, `rows` (a tile), `spp`, `seed`, `camera` and `show_emitters` of
/// `cfg` (no photon-map settings).
///
/// # Errors
/// [`crate::Error::InvalidParameter`] for bad settings,
/// [`crate::Error::InvalidScene`] for a caster's hit that breaks the
/// [`RayCaster`] contract, or no camera.
pub fn render_path<C: RayCaster>(
    prepared: &PreparedScene<C>,
    cfg: &RenderConfig,
    part: PathPart,
) -> Result<Image> {
    render_path_with(prepared, cfg, part, &|_, _| {}).map(|(image, _)| image)
}

/// [`render_path`] with a progress callback, `progress(rows_done,
/// rows_total)`, called from worker threads, and the render's counts ([`RenderStats::samples`] and
/// [`RenderStats::dropped_samples`]; the photon-map fields are 0).
///
/// # Errors
/// As [`render_path`].
pub fn render_path_with<C: RayCaster>(
    prepared: &PreparedScene<C>,
    cfg: &RenderConfig,
    part: PathPart,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<(Image, RenderStats)> {
    path_image(
        prepared.scene(),
        prepared.caster(),
        &cfg.check()?,
        part,
        progress,
    )
}

fn path_image(
    scene: &Scene,
    rt: &dyn RayCaster,
    cfg: &CheckedRender,
    part: PathPart,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<(Image, RenderStats)> {
    let checked = CheckedCaster::new(scene, rt);
    let rays = CameraRays::new(&cfg.camera_for(scene)?, cfg.width, cfg.height);
    let estimator = PathEstimator {
        pt: PathTracer::over(scene, &checked),
        part,
        show_emitters: cfg.show_emitters,
    };
    let (image, dropped) = film::develop(cfg, &rays, &estimator, progress)?;
    checked.result()?;
    let stats = RenderStats {
        samples: u64::from(image.width) * u64::from(image.height) * u64::from(cfg.spp),
        dropped_samples: dropped,
        ..RenderStats::default()
    };
    Ok((image, stats))
}

/// The path tracer in the image loop: a uniformly jittered camera ray per
/// sample, from the sample's own stream.
struct PathEstimator<'a> {
    pt: PathTracer<'a>,
    part: PathPart,
    show_emitters: bool,
}

impl PixelEstimator for PathEstimator<'_> {
    type Row = ();
    type Pixel = ();

    fn row(&self) {}

    fn pixel(&self, _key: u64, _x: u32, _y: u32) {}

    fn radiance(
        &self,
        rays: &CameraRays,
        _: &(),
        sample: Sample,
        rng: &mut Rng,
        _: &mut (),
    ) -> Vec3 {
        let ray = film::camera_ray(rays, sample, rng.next_2d());
        self.pt.radiance(ray, self.part, self.show_emitters, rng)
    }

    fn row_done(&self, _: ()) {}
}

/// A path-traced image as two independent halves.
#[derive(Clone, Debug)]
pub struct PathHalves {
    /// Half A (seed `cfg.seed`).
    pub a: Image,
    /// Half B (an independent seed).
    pub b: Image,
    /// Samples of both halves left out as NaN or infinite
    /// ([`RenderStats::dropped_samples`]).
    pub dropped_samples: u64,
}

impl PathHalves {
    /// Renders both halves, each with `cfg.spp` samples per pixel.
    ///
    /// # Errors
    /// As [`render_path`].
    pub fn render<C: RayCaster>(
        prepared: &PreparedScene<C>,
        cfg: &RenderConfig,
        part: PathPart,
    ) -> Result<Self> {
        let cfg = cfg.check()?;
        let (scene, rt) = (prepared.scene(), prepared.caster());
        let (a, sa) = path_image(scene, rt, &cfg, part, &|_, _| {})?;
        let cb = cfg.with_seed(hash2(cfg.seed, 0x0B_5EED));
        let (b, sb) = path_image(scene, rt, &cb, part, &|_, _| {})?;
        Ok(PathHalves {
            a,
            b,
            dropped_samples: sa.dropped_samples + sb.dropped_samples,
        })
    }

    /// Refuses halves that left samples out: as a reference they would bias
    /// every error measured against them.
    ///
    /// # Errors
    /// [`crate::Error::InvalidScene`] naming the count.
    pub fn require_complete(&self) -> Result<()> {
        if self.dropped_samples > 0 {
            return Err(crate::Error::InvalidScene(format!(
                "the path-traced reference left out {} NaN or infinite samples \
                 (degenerate geometry, or radiance beyond f32)",
                self.dropped_samples
            )));
        }
        Ok(())
    }

    /// The mean of the halves.
    pub fn mean(&self) -> Image {
        let mut m = self.a.clone();
        for (p, q) in m.pixels.iter_mut().zip(&self.b.pixels) {
            *p = (*p + *q) * 0.5;
        }
        m
    }

    /// Relative rms noise of [`PathHalves::mean`] over the pixels where
    /// `keep` is true (all when `None`): `rmse(A, B) / 2 / mean`, which is
    /// the relative RMSE of `A` against the mean (`A - (A + B) / 2 = (A - B) / 2`).
    pub fn noise_rel(&self, keep: Option<&[bool]>) -> f64 {
        let all;
        let keep = match keep {
            Some(k) => k,
            None => {
                all = vec![true; self.a.pixels.len()];
                &all
            }
        };
        relative_rmse_masked(&self.a, &self.mean(), keep).unwrap_or(0.0)
    }
}

/// For each pixel, whether the ray through its centre first hits an emitter
/// (a light's own pixel, excluded from the trade study's image errors).
///
/// # Errors
/// [`crate::Error::InvalidScene`] when neither `cfg` nor the scene has a camera.
pub fn light_pixels<C: RayCaster>(
    prepared: &PreparedScene<C>,
    cfg: &RenderConfig,
) -> Result<Vec<bool>> {
    first_hit_mask(prepared, cfg, |m| m.emission.is_some())
}

/// For each pixel, whether the ray through its centre first hits a specular
/// surface (a mirror or glass): not a caustic's pixel, whatever the image
/// shows there.
///
/// # Errors
/// [`crate::Error::InvalidScene`] when neither `cfg` nor the scene has a camera.
pub fn specular_pixels<C: RayCaster>(
    prepared: &PreparedScene<C>,
    cfg: &RenderConfig,
) -> Result<Vec<bool>> {
    first_hit_mask(prepared, cfg, |m| m.brdf.is_specular())
}

/// For each pixel, whether the ray through its centre first hits a material
/// for which `is` holds.
fn first_hit_mask<C: RayCaster>(
    prepared: &PreparedScene<C>,
    cfg: &RenderConfig,
    is: impl Fn(&Material) -> bool,
) -> Result<Vec<bool>> {
    let scene = prepared.scene();
    let rays = CameraRays::new(&cfg.camera_for(scene)?, cfg.width, cfg.height);
    let w = cfg.width as usize;
    Ok((0..w * cfg.height as usize)
        .map(|i| {
            let ray = rays.ray((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
            prepared
                .caster()
                .intersect(&ray)
                .is_some_and(|h| scene.materials.get(h.material as usize).is_some_and(&is))
        })
        .collect())
}

/// Irradiance arriving at each point (on the side of its normal) that is
/// *not* direct light: light that left some surface (caustics included), by
/// `samples` cosine-distributed path-traced rays per point. `E_indirect =
/// pi * mean(L)` for cosine-weighted directions. Adding the direct light's
/// quadrature ([`super::quadrature_irradiance`]) gives the full irradiance.
/// Point `i` draws from `hash2(seed, i)`; points run in parallel.
pub fn indirect_irradiance<C: RayCaster>(
    prepared: &PreparedScene<C>,
    points: &[SurfacePoint],
    samples: u32,
    seed: u64,
) -> Vec<Vec3> {
    let pt = PathTracer::new(prepared);
    let samples = samples.max(1);
    points
        .par_iter()
        .enumerate()
        .map(|(i, p)| {
            let frame = Frame::from_normal(p.normal);
            let origin = p.position + p.normal * pt.eps;
            let key = hash2(seed, i as u64);
            let mut sum = Vec3::ZERO;
            for s in 0..samples {
                let mut rng = Rng::new(hash2(key, s as u64));
                let dir = frame.world_from_local(cosine_hemisphere(rng.next_2d()));
                let l = pt.radiance_after_first_bounce(Ray::new(origin, dir), &mut rng);
                if l.is_finite() {
                    sum += l;
                }
            }
            sum * (PI / samples as f32)
        })
        .collect()
}
