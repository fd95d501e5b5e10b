//! The path-traced reference of the trade study, its noise, and its cache
//! (keyed by the scene's content and the settings, see [`super`]).

use super::{Run, TradeoffConfig, NOISE_RATIO};
use crate::error::{Error, Result};
use crate::raycast::RayCaster;
use crate::render::{
    indirect_irradiance, light_pixels, quadrature_irradiance, Image, PathHalves, PathPart,
};
use crate::scene::{Light, PreparedScene, Scene, SurfacePoint};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// Bumped when the reference's computation changes, so old caches are redone
/// (4: pixels summed in f64, and a reference is cached only without dropped
/// samples; 5: no points on mirrors and glass, and the path tracer shades
/// every BRDF about the shading normal).
const REFERENCE_VERSION: u64 = 5;

/// Seed of the reference (the runs use seeds 1, 2, ...).
const REFERENCE_SEED: u64 = 0x5EF_0000;

/// What the output says about the reference.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ReferenceInfo {
    /// Always `path`.
    pub integrator: String,
    /// Samples per pixel of the whole reference (both halves) of each part.
    pub spp: u32,
    /// Relative noise of the indirect image (error (a)'s yardstick).
    pub noise: f64,
    /// Relative noise of the full image (error (b)).
    pub image_noise: f64,
    /// Relative noise of the points' irradiance (error (c)).
    pub points_noise: f64,
    /// Path-traced rays per point (both halves).
    pub point_samples: u32,
    /// The content hash the cache is keyed by (hex).
    pub key: String,
    /// Seconds it took to compute (when it was computed).
    pub seconds: f64,
    /// True when it was read from the cache.
    pub cached: bool,
}

/// The reference images and point values.
#[allow(missing_debug_implementations)] // large images and borrowed scenes: nothing useful to print
pub struct Reference {
    /// What the output says.
    pub info: ReferenceInfo,
    /// Indirect light (mean of the halves).
    pub indirect: Image,
    /// Direct + indirect (mean of the halves).
    pub full: Image,
    /// Pixels that are not a light.
    pub keep: Vec<bool>,
    /// The fixed points of error (c).
    pub points: Vec<SurfacePoint>,
    /// Reference irradiance at each point (mean over RGB).
    pub irradiance: Vec<f64>,
}

#[derive(Serialize, Deserialize)]
struct Cached {
    info: ReferenceInfo,
    direct_e: Vec<f64>,
    indirect_a: Vec<f64>,
    indirect_b: Vec<f64>,
}

/// FNV-1a, 64 bits: stable across runs and Rust versions (the cache key).
fn fnv(bytes: &[u8], mut h: u64) -> u64 {
    for b in bytes {
        h ^= *b as u64;
        h = h.wrapping_mul(0x100_0000_01b3);
    }
    h
}

/// A hash of what the scene *is*: geometry, materials (with their
/// transmitted parts' shares), textures (emissive ones too), lights and camera
/// (their exact float values through `Debug`), not where it came from.
pub fn scene_hash(scene: &Scene) -> u64 {
    let text = format!(
        "{:?}{:?}{:?}{:?}{:?}",
        scene.materials, scene.meshes, scene.lights, scene.camera, scene.material_maps
    );
    let mut h = fnv(text.as_bytes(), 0xcbf2_9ce4_8422_2325);
    // Only when there are any: the keys of scenes without stay as they were.
    if scene.emission_textures.iter().any(Option::is_some) {
        h = fnv(format!("{:?}", scene.emission_textures).as_bytes(), h);
    }
    if scene.alpha_masks.iter().any(Option::is_some) {
        h = fnv(format!("{:?}", scene.alpha_masks).as_bytes(), h);
    }
    // A partly transmitting material's share is not in its materials.
    if scene.transmission_mixes.iter().any(Option::is_some) {
        h = fnv(format!("{:?}", scene.transmission_mixes).as_bytes(), h);
    }
    for t in &scene.textures {
        let head = format!("{}x{} {:?}", t.width(), t.height(), t.sampler);
        h = fnv(head.as_bytes(), h);
        h = fnv(t.texels().as_flattened(), h);
    }
    h
}

/// `count` area-uniform points on the surfaces that neither emit nor are
/// specular: a photon map stores nothing on a mirror or on glass, so its
/// irradiance there is no estimate of anything.
pub(super) fn study_points(scene: &Scene, count: usize) -> Vec<SurfacePoint> {
    let read_from_the_map = |p: &SurfacePoint| {
        scene
            .materials
            .get(scene.meshes[p.mesh].material)
            .is_some_and(|m| m.emission.is_none() && !m.brdf.is_specular())
    };
    let mut pts: Vec<SurfacePoint> = scene
        .surface_sampler()
        .points(count * 4, 0x7124_DE0F)
        .into_iter()
        .filter(read_from_the_map)
        .collect();
    pts.truncate(count);
    pts
}

fn luminance_mean(v: glam::Vec3) -> f64 {
    (v.x as f64 + v.y as f64 + v.z as f64) / 3.0
}

impl Reference {
    /// The reference of `scene` for `cfg`: from the cache when it holds one
    /// for this content and these settings, else path-traced (and cached).
    ///
    /// # Errors
    /// Render errors, or an unreadable or unwritable cache file.
    pub fn get<C: RayCaster>(prepared: &PreparedScene<C>, cfg: &TradeoffConfig) -> Result<Self> {
        let scene = prepared.scene();
        // The kernel set is in the key: another set's reference is as good
        // a reference, but not the one a fresh run would make.
        let isa = prepared.caster().kernels().map_or("-".into(), |k| {
            format!("{} {}", k.isa, crate::isa::version_name(k.version_code()))
        });
        let math = crate::isa::MathVariant::host().map_or("-", |m| m.name());
        let settings = format!(
            "v{REFERENCE_VERSION} {}x{} spp {} points {} x {} isa {isa} math {math}",
            cfg.width, cfg.height, cfg.reference_spp, cfg.points, cfg.point_samples
        );
        let key = format!("{:016x}", fnv(settings.as_bytes(), scene_hash(scene)));
        let points = study_points(scene, cfg.points);
        let keep: Vec<bool> = light_pixels(prepared, &cfg.render_config(1, 0))?
            .iter()
            .map(|l| !l)
            .collect();
        let files = cfg.cache_dir.as_ref().map(|d| {
            let f = |s: &str| d.join(format!("reference-{key}{s}"));
            [".json", "-ia.exr", "-ib.exr", "-da.exr", "-db.exr"].map(f)
        });
        if let Some(f) = &files {
            if let Some(r) = Self::read(f, &points, &keep) {
                return Ok(r);
            }
        }
        let t = std::time::Instant::now();
        let rc = cfg.render_config(cfg.reference_spp, REFERENCE_SEED);
        let ind = PathHalves::render(prepared, &rc, PathPart::Indirect)?;
        let dir = PathHalves::render(prepared, &rc, PathPart::Direct)?;
        // Every error of the study is measured against this image.
        ind.require_complete()?;
        dir.require_complete()?;
        let grid = quadrature_grid(scene);
        let direct_e: Vec<f64> = points
            .iter()
            .map(|p| luminance_mean(quadrature_irradiance(prepared, p.position, p.normal, grid)))
            .collect();
        let half = |seed| {
            indirect_irradiance(prepared, &points, cfg.point_samples, seed)
                .into_iter()
                .map(luminance_mean)
                .collect::<Vec<f64>>()
        };
        let (indirect_a, indirect_b) = (half(REFERENCE_SEED), half(REFERENCE_SEED + 1));
        let info = ReferenceInfo {
            integrator: "path".into(),
            spp: 2 * cfg.reference_spp,
            noise: 0.0,
            image_noise: 0.0,
            points_noise: 0.0,
            point_samples: 2 * cfg.point_samples,
            key,
            seconds: t.elapsed().as_secs_f64(),
            cached: false,
        };
        let cached = Cached {
            info,
            direct_e,
            indirect_a,
            indirect_b,
        };
        let images = [ind.a, ind.b, dir.a, dir.b];
        if let Some(f) = &files {
            for (img, path) in images.iter().zip(&f[1..]) {
                img.write_exr(path)?;
            }
            let text =
                serde_json::to_string(&cached).map_err(|e| Error::param("cache", e.to_string()))?;
            std::fs::write(&f[0], text)
                .map_err(|e| Error::param("cache", format!("{}: {e}", f[0].display())))?;
        }
        Ok(Self::assemble(cached, images, points, keep))
    }

    fn read(files: &[PathBuf; 5], points: &[SurfacePoint], keep: &[bool]) -> Option<Self> {
        // A regular file of bounded size (points and their sums: far below
        // 256 MiB); anything else is no cache, and the reference is redone.
        let text = crate::input::read_regular_file(&files[0], 256 << 20).ok()?;
        let mut cached: Cached = serde_json::from_slice(&text).ok()?;
        let n = points.len();
        if [&cached.direct_e, &cached.indirect_a, &cached.indirect_b]
            .iter()
            .any(|v| v.len() != n)
        {
            return None;
        }
        let images = [0, 1, 2, 3].map(|i| Image::read_exr(&files[i + 1]).ok());
        let [Some(ia), Some(ib), Some(da), Some(db)] = images else {
            return None;
        };
        if ia.pixels.len() != keep.len() {
            return None;
        }
        cached.info.cached = true;
        Some(Self::assemble(
            cached,
            [ia, ib, da, db],
            points.to_vec(),
            keep.to_vec(),
        ))
    }

    fn assemble(
        c: Cached,
        [ia, ib, da, db]: [Image; 4],
        points: Vec<SurfacePoint>,
        keep: Vec<bool>,
    ) -> Self {
        // Rendered without a dropped sample: checked before it was cached
        // (since REFERENCE_VERSION 4, which the cache key holds).
        let ind = PathHalves {
            a: ia,
            b: ib,
            dropped_samples: 0,
        };
        let sum = |x: &Image, y: &Image| {
            let mut s = x.clone();
            for (p, q) in s.pixels.iter_mut().zip(&y.pixels) {
                *p += *q;
            }
            s
        };
        let full = PathHalves {
            a: sum(&ind.a, &da),
            b: sum(&ind.b, &db),
            dropped_samples: 0,
        };
        let irradiance: Vec<f64> = (0..points.len())
            .map(|i| c.direct_e[i] + 0.5 * (c.indirect_a[i] + c.indirect_b[i]))
            .collect();
        let diff: Vec<f64> = c
            .indirect_a
            .iter()
            .zip(&c.indirect_b)
            .map(|(a, b)| a - b)
            .collect();
        let mean_e = irradiance.iter().sum::<f64>() / irradiance.len().max(1) as f64;
        let rms = (diff.iter().map(|d| d * d).sum::<f64>() / diff.len().max(1) as f64).sqrt();
        let mut info = c.info;
        info.noise = ind.noise_rel(Some(&keep));
        info.image_noise = full.noise_rel(Some(&keep));
        info.points_noise = if mean_e > 0.0 {
            rms / 2.0 / mean_e
        } else {
            0.0
        };
        Reference {
            info,
            indirect: ind.mean(),
            full: full.mean(),
            keep,
            points,
            irradiance,
        }
    }

    /// Fails when the reference's noise is not below [`NOISE_RATIO`] of the
    /// smallest error of its kind among `runs`, naming the `spp` to ask for.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] as above.
    pub fn check_noise(&self, runs: &[Run]) -> Result<()> {
        let min = |f: fn(&Run) -> f64| runs.iter().map(f).fold(f64::INFINITY, f64::min);
        let checks = [
            (
                "indirect",
                self.info.noise,
                min(|r| r.indirect_rel_rmse),
                "reference spp",
            ),
            (
                "image",
                self.info.image_noise,
                min(|r| r.image_rel_rmse),
                "reference spp",
            ),
            (
                "points",
                self.info.points_noise,
                min(|r| r.points_rel_err),
                "point samples",
            ),
        ];
        for (what, noise, smallest, knob) in checks {
            if smallest.is_finite() && noise >= NOISE_RATIO * smallest {
                let factor = (noise / (NOISE_RATIO * smallest)).powi(2) * 1.2;
                return Err(Error::param(
                    knob,
                    format!(
                        "the reference's {what} noise {:.4} is not below 1/3 of the smallest \
                         {what} error {:.4}: the study stops; raise the {knob} about {:.1}x",
                        noise, smallest, factor
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// Midpoint grid per light triangle: about 1024 nodes per area light.
fn quadrature_grid(scene: &Scene) -> u32 {
    let most = scene
        .lights
        .iter()
        .filter_map(|l| match l {
            Light::Area(a) => Some(scene.meshes[a.mesh].indices.len()),
            _ => None,
        })
        .max()
        .unwrap_or(1)
        .max(1);
    ((512.0 / most as f64).sqrt() as u32).clamp(1, 16)
}
