//! Direct light by sampling the emitters (the renderer's estimator).
//!
//! - **Stratified points on the lights**: a light sample is driven by a 2D
//!   point of the pixel's (0,2)-sequence ([`super::sampler`]); the first
//!   coordinate picks the light and then the triangle (each choice rescales
//!   it back to `[0, 1)`, so the strata survive), the pair then places the
//!   point on the triangle. Over a pixel's samples the light's area is covered
//!   by strata instead of independent points.
//! - **Several shadow rays per camera sample** (`light_samples`): each uses
//!   its own point of the sequence (index `s * L + j` of `spp * L`).
//! - **Lights chosen by contribution**: one light per shadow ray, with
//!   probability proportional to an unoccluded estimate of its contribution
//!   at the shading point (power-like weight `L(theta_l) cos_l cos_x A / r^2`
//!   at the light's centre for area lights, `I cos_x / r^2` for point and spot
//!   lights, `E cos_x` for directional ones), mixed with 10 % by power so that no light that can contribute gets a zero
//!   probability (the estimate is unbiased whatever the weights).
//!
//! Area light of radiance `L0 cos^n(theta_l)` (one-sided, about the
//! triangle's geometric normal; `L0` the texel's on a textured light, whose
//! points are drawn by emitted power, [`crate::scene::AreaLight::sample_point`]:
//! the pair's first coordinate picks the piece, a second pair
//! ([`super::sampler::dim::LIGHT_POINT`]) the point in it; divided by that
//! pdf); point light `I cos(theta_x) / r^2`; spot
//! light the same times its falloff; directional light `E cos(theta_x)`,
//! its shadow ray unbounded towards the light. Point, spot and directional
//! lights are deltas: no BRDF sample finds them, so nothing else counts them.

use crate::brdf::Brdf;
use crate::raycast::{Ray, RayCaster};
use crate::rng::hash2;
use crate::sampling::{luminance, uniform_triangle, Frame};
use crate::scene::{Light, PreparedScene, Scene};
use glam::Vec3;

pub use super::quadrature::{floor_points, quadrature_irradiance, unshadowed_irradiance};

/// Shadow rays stop this fraction of their length short of either end.
pub(crate) const SHADOW_EPS: f32 = 1e-4;

/// Share of the light choice made by power alone (the rest by contribution).
const POWER_SHARE: f32 = 0.1;

/// One light's sampling data.
struct LightTable {
    /// Triangles of an area light, with their cumulative areas (normalised).
    triangles: Vec<[Vec3; 3]>,
    cdf: Vec<f32>,
    centre: Vec3,
    normal: Vec3,
    power: f32,
}

/// The lights of a scene, ready to be sampled at shading points.
#[allow(missing_debug_implementations)] // it borrows the scene and holds per-light tables: nothing useful to print
pub struct LightSampler<'a> {
    scene: &'a Scene,
    rt: &'a dyn RayCaster,
    tables: Vec<LightTable>,
    total_power: f32,
}

impl<'a> LightSampler<'a> {
    /// Tables of every light of the scene of `prepared`, whose caster traces
    /// the shadow rays.
    pub fn new<C: RayCaster>(prepared: &'a PreparedScene<C>) -> Self {
        Self::over(prepared.scene(), prepared.caster())
    }

    pub(super) fn over(scene: &'a Scene, rt: &'a dyn RayCaster) -> Self {
        let tables: Vec<LightTable> = scene
            .lights
            .iter()
            .map(|l| {
                let power = luminance(l.power()).max(0.0);
                match l {
                    Light::Area(a) => {
                        let mesh = &scene.meshes[a.mesh];
                        let triangles: Vec<[Vec3; 3]> =
                            (0..mesh.indices.len()).map(|i| mesh.triangle(i)).collect();
                        let mut acc = 0.0f64;
                        let mut cdf = Vec::with_capacity(triangles.len());
                        let (mut centre, mut normal) = (Vec3::ZERO, Vec3::ZERO);
                        for t in &triangles {
                            let c = (t[1] - t[0]).cross(t[2] - t[0]);
                            acc += 0.5 * c.length() as f64;
                            cdf.push(acc as f32);
                            centre += (t[0] + t[1] + t[2]) * (0.5 * c.length() / 3.0);
                            normal += c;
                        }
                        let total = acc.max(f64::MIN_POSITIVE) as f32;
                        cdf.iter_mut().for_each(|c| *c /= total);
                        LightTable {
                            triangles,
                            cdf,
                            centre: centre / total,
                            normal: normal.normalize_or_zero(),
                            power,
                        }
                    }
                    _ => LightTable {
                        triangles: Vec::new(),
                        cdf: Vec::new(),
                        centre: l.position().unwrap_or(Vec3::ZERO),
                        normal: Vec3::ZERO,
                        power,
                    },
                }
            })
            .collect();
        let total_power = tables.iter().map(|t| t.power).sum();
        LightSampler {
            scene,
            rt,
            tables,
            total_power,
        }
    }

    /// Unoccluded contribution estimate of light `i` at `x` (normal `n`).
    fn weight(&self, i: usize, x: Vec3, n: Vec3) -> f32 {
        let t = &self.tables[i];
        // Towards the light's centre: the unit direction, the squared
        // distance and cos(theta_x). A light straddling the tangent plane
        // still counts: the cosines are floored, this is only a sampling weight.
        let toward_centre = || {
            let d = t.centre - x;
            let r2 = d.length_squared().max(1e-12);
            let wi = d / r2.sqrt();
            (wi, r2, wi.dot(n).max(0.05))
        };
        match &self.scene.lights[i] {
            Light::Area(a) => {
                let (wi, r2, cos_x) = toward_centre();
                let cos_l = a.emission.facing((-wi).dot(t.normal)).max(0.05);
                let le = luminance(a.mean_radiance()) * a.emission.profile_toward(cos_l);
                le * cos_l * cos_x * a.area / r2.max(a.area)
            }
            Light::Point(p) => {
                let (_, r2, cos_x) = toward_centre();
                luminance(p.intensity) * cos_x / r2
            }
            Light::Spot(s) => {
                let (wi, r2, cos_x) = toward_centre();
                luminance(s.intensity) * s.falloff(s.direction.dot(-wi)).max(0.05) * cos_x / r2
            }
            Light::Directional(d) => luminance(d.irradiance()) * (-d.direction()).dot(n).max(0.05),
        }
    }

    /// Picks a light for `x` with `u` in `[0, 1)`: its index, its probability,
    /// and `u` rescaled to `[0, 1)` within the choice.
    fn pick(&self, x: Vec3, n: Vec3, u: f32) -> Option<(usize, f32, f32)> {
        let count = self.tables.len();
        if count == 1 {
            return Some((0, 1.0, u));
        }
        // Lights are few in the scenes we render; weights are recomputed per call.
        let mut w: Vec<f32> = (0..count).map(|i| self.weight(i, x, n)).collect();
        let sum: f32 = w.iter().sum();
        for (i, wi) in w.iter_mut().enumerate() {
            let by_power = self.tables[i].power / self.total_power.max(1e-30);
            let by_contrib = if sum > 0.0 { *wi / sum } else { by_power };
            *wi = POWER_SHARE * by_power + (1.0 - POWER_SHARE) * by_contrib;
        }
        let mut acc = 0.0;
        for (i, &p) in w.iter().enumerate() {
            if p > 0.0 && (u < acc + p || i == count - 1) {
                return Some((i, p, ((u - acc) / p).clamp(0.0, 0.999_999_9)));
            }
            acc += p;
        }
        None
    }

    /// Where light `i` lights `x` from, by `u`, and what arrives: a point
    /// and `L G / pdf_area` (area lights), or what [`punctual_arrival`]
    /// gives, before the BRDF, `cos(theta_x)` and visibility.
    fn sample_light(
        &self,
        i: usize,
        x: Vec3,
        u: [f32; 2],
        u_point: impl FnOnce() -> [f32; 2],
    ) -> Option<(Source, Vec3)> {
        match &self.scene.lights[i] {
            Light::Area(a) if a.is_textured() => {
                // By emitted power: `u[0]` picks the piece, `u_point` the
                // point in it; the point's texel over its area pdf.
                let p = a.sample_point(u[0], u_point());
                let d = x - p.position;
                let r2 = d.length_squared();
                let cos_l = a.emission.facing(p.normal.dot(d) / r2.sqrt());
                if !(r2 > 0.0 && cos_l > 0.0 && p.pdf_area > 0.0) {
                    return None;
                }
                let le = p.radiance * a.emission.profile_toward(cos_l);
                Some((Source::At(p.position), le * cos_l / (p.pdf_area * r2)))
            }
            Light::Area(a) => {
                let t = &self.tables[i];
                let k = t.cdf.partition_point(|&c| c <= u[0]).min(t.cdf.len() - 1);
                let lo = if k == 0 { 0.0 } else { t.cdf[k - 1] };
                let u0 = ((u[0] - lo) / (t.cdf[k] - lo).max(1e-30)).clamp(0.0, 0.999_999_9);
                let [v0, v1, v2] = t.triangles[k];
                let (b0, b1) = uniform_triangle([u0, u[1]]);
                let p = v0 * b0 + v1 * b1 + v2 * (1.0 - b0 - b1);
                let n_l = (v1 - v0).cross(v2 - v0).normalize_or_zero();
                let d = x - p;
                let r2 = d.length_squared();
                if r2 <= 0.0 {
                    return None;
                }
                let cos_l = a.emission.facing(n_l.dot(d) / r2.sqrt());
                if cos_l <= 0.0 {
                    return None;
                }
                let le = a.emission.radiance_toward(cos_l);
                Some((Source::At(p), le * cos_l * a.area / r2))
            }
            light => punctual_arrival(light, x),
        }
    }

    /// One light sample of the direct radiance leaving `x` towards `wo`
    /// (world, unit) on the side of the unit geometric normal `ng`, shaded
    /// with the unit normal `n`: a light picked by contribution, a point on
    /// it from `u`, a shadow ray from `x + eps ng`.
    ///
    /// On a textured light the point inside the piece `u` picks comes from
    /// a hash of `u` ([`Self::sample_with`] takes a stratified one).
    pub fn sample(&self, brdf: &Brdf, pts: [Vec3; 4], eps: f32, u: [f32; 2]) -> Vec3 {
        let hashed = || {
            let h = hash2(u64::from(u[0].to_bits()), u64::from(u[1].to_bits()));
            let unit = |b: u64| (b >> 40) as f32 * (1.0 / 16_777_216.0);
            [unit(h), unit(h << 24)]
        };
        self.sample_with(brdf, pts, eps, u, hashed)
    }

    /// [`Self::sample`] with `u_point`, called only for a textured light,
    /// placing the point inside the piece of the light that `u` picks.
    pub fn sample_with(
        &self,
        brdf: &Brdf,
        pts: [Vec3; 4],
        eps: f32,
        u: [f32; 2],
        u_point: impl FnOnce() -> [f32; 2],
    ) -> Vec3 {
        match self.unshadowed_with(brdf, pts, eps, u, u_point) {
            Some((ray, l)) if !self.rt.occluded(&ray) => l,
            _ => Vec3::ZERO,
        }
    }

    /// [`Self::sample_with`] but for its shadow ray: the ray, and what
    /// arrives when nothing blocks it (`None` when nothing would), so that
    /// a caller can test many shadow rays in one batch.
    pub(crate) fn unshadowed_with(
        &self,
        brdf: &Brdf,
        [x, ng, n, wo]: [Vec3; 4],
        eps: f32,
        u: [f32; 2],
        u_point: impl FnOnce() -> [f32; 2],
    ) -> Option<(Ray, Vec3)> {
        let (i, prob, u0) = self.pick(x, n, u[0])?;
        let (source, le_g) = self.sample_light(i, x, [u0, u[1]], u_point)?;
        let wi = source.direction_from(x);
        let cos_x = wi.dot(n);
        if cos_x <= 0.0 || wi.dot(ng) <= 0.0 || le_g.max_element() <= 0.0 {
            return None;
        }
        let frame = Frame::from_normal(n);
        let f = brdf.eval(frame.local_from_world(wi), frame.local_from_world(wo));
        if f.max_element() <= 0.0 {
            return None;
        }
        Some((source.shadow_ray(x + ng * eps), f * le_g * (cos_x / prob)))
    }
}

/// Where a light sample's light comes from, seen from a shading point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Source {
    /// A point: on an area light, or a point or spot light's position.
    At(Vec3),
    /// Infinitely far along this unit direction: a directional light.
    Along(Vec3),
}

impl Source {
    /// Unit direction from `x` towards the light (zero when `x` is the point).
    pub(crate) fn direction_from(self, x: Vec3) -> Vec3 {
        match self {
            Source::At(p) => (p - x).normalize_or_zero(),
            Source::Along(w) => w,
        }
    }

    /// The shadow ray from `origin` (already off the surface) to the light:
    /// a segment stopping short of a point, unbounded towards a direction
    /// (the light lies beyond all geometry).
    pub(crate) fn shadow_ray(self, origin: Vec3) -> Ray {
        match self {
            Source::At(p) => Ray::segment(origin, p, SHADOW_EPS),
            Source::Along(w) => Ray::new(origin, w),
        }
    }
}

/// Where a point, spot or directional light lights `x` from, and what
/// arrives there before `cos(theta_x)` and visibility: `I / r^2` (times a
/// spot's falloff), or a directional light's irradiance `E`; `None` for an
/// area light, a point at the light, or outside a spot's cone.
pub(crate) fn punctual_arrival(light: &Light, x: Vec3) -> Option<(Source, Vec3)> {
    match light {
        Light::Area(_) => None,
        Light::Directional(d) => Some((Source::Along(-d.direction()), d.irradiance())),
        Light::Point(p) => {
            let r2 = (x - p.position).length_squared();
            (r2 > 0.0).then(|| (Source::At(p.position), p.intensity / r2))
        }
        Light::Spot(s) => {
            let d = x - s.position;
            let r2 = d.length_squared();
            if r2 <= 0.0 {
                return None;
            }
            let f = s.falloff(s.direction.dot(d) / r2.sqrt());
            (f > 0.0).then(|| (Source::At(s.position), s.intensity * f / r2))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::brdf::Lambert;
    use crate::embree::Device;
    use crate::render::sampler::{dim, PixelSampler};
    use crate::scene::Scene;
    use std::f32::consts::PI;

    /// Over 256 stratified samples, the direct radiance at the floor's centre
    /// equals the quadrature irradiance times albedo / pi within 1 %.
    #[test]
    fn stratified_light_samples_match_the_quadrature() {
        let scene = Scene::cornell().unwrap();
        let device = Device::new().unwrap();
        let prepared = scene.commit(&device).unwrap();
        let lights = LightSampler::new(&prepared);
        let x = Vec3::new(278.0, 0.0, 279.0);
        let brdf: Brdf = Lambert::new(Vec3::splat(0.5)).unwrap().into();
        let s = PixelSampler::new(3);
        let n = 256;
        let mut sum = Vec3::ZERO;
        for i in 0..n {
            let u = s.get_2d(dim::LIGHT, i, n);
            sum += lights.sample(&brdf, [x, Vec3::Y, Vec3::Y, Vec3::Y], 1e-3, u);
        }
        let got = sum.x / n as f32;
        let e = quadrature_irradiance(&prepared, x, Vec3::Y, 32);
        let want = e.x * 0.5 / PI;
        assert!((got / want - 1.0).abs() < 0.01, "{got} vs {want}");
    }
}
