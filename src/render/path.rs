//! An unbiased path tracer: the yardstick of the trade study (`bench
//! tradeoff`) and `render --integrator path`. No photon map.
//!
//! # Estimator
//! From the camera, a path is followed surface to surface:
//! - at every non-delta vertex, **next-event estimation**: one sample of
//!   every light (area lights: an area-uniform point, or by emitted power
//!   on a light with an emissive texture, and a shadow ray; point
//!   and spot lights: their intensity over `r^2`; directional lights: their
//!   irradiance `E`, the shadow ray unbounded towards them). Point, spot and
//!   directional lights are deltas that no BRDF sample can hit, so their
//!   samples take no MIS weight and nothing counts them twice;
//! - the next direction by the BRDF's own sampler; an emitter that this ray
//!   reaches adds its emission. Area-light emission is counted by both
//!   strategies, so both are weighted by **multiple importance sampling**
//!   (power heuristic, one sample of each: `w = p^2 / (p_light^2 + p_brdf^2)`,
//!   the light's pdf in solid angle `r^2 / (cos_l A)`, `r^2 p_A(y) / cos_l`
//!   on a textured light whose area pdf at `y` is `p_A(y)`); after a mirror, or
//!   from the camera, the emission counts fully (light sampling cannot find it);
//! - **Russian roulette** from the [`RR_START`]-th non-delta vertex on:
//!   survival `q = min(max(throughput), 0.95)`, the survivor divided by `q`.
//!   Unbiased; a path stops for good after [`MAX_PATH_VERTICES`] vertices, a
//!   safety cap whose bias is below `albedo^MAX_PATH_VERTICES`.
//!
//! # What is counted ([`PathPart`])
//! Call `x` the first non-delta vertex (after zero or more camera mirrors).
//! **Direct** light is the emission reaching `x` straight from a light (NEE
//! at `x`, and an emitter hit by `x`'s BRDF sample); **indirect** light is
//! everything else that leaves `x` (light after two or more scatterings,
//! caustics through mirrors included). That is exactly the split of the
//! photon renderer (direct by light sampling, indirect from the depth >= 1
//! map), so the parts compare one to one. Emitters seen from the camera
//! (through mirrors) count in [`PathPart::Full`] and [`PathPart::Direct`]
//! when `show_emitters` is set.
//!
//! Pixel sampling and determinism follow [`super::render`]: pixel `p`'s sample
//! `s` draws from `Rng::new(hash2(hash2(seed, p), s))`.

// `!(x > 0.0)` is deliberate here: it rejects NaN with the non-positive values.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::path_light::{area_light_pdf, next_event};
use super::ray_epsilon;
use crate::brdf::Transport;
use crate::error::{Error, Result};
use crate::raycast::{Hit, Ray, RayCaster};
use crate::rng::Rng;
use crate::sampling::Frame;
use crate::scene::{consistent_with_geometry, Light, PreparedScene, Scene};
use glam::Vec3;

/// Non-delta vertices before Russian roulette starts.
pub const RR_START: u32 = 3;

/// Hard cap on a path's vertices (mirrors included).
pub const MAX_PATH_VERTICES: u32 = 256;

/// Which integrator renders an image.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Integrator {
    /// Direct light by sampling + indirect from the photon map (the default).
    #[default]
    Photon,
    /// The unbiased path tracer of this module.
    Path,
}

impl std::str::FromStr for Integrator {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "photon" => Ok(Integrator::Photon),
            "path" => Ok(Integrator::Path),
            _ => Err(Error::param(
                "integrator",
                format!("expected photon or path, got `{s}`"),
            )),
        }
    }
}

/// The part of the light a path tracer estimates (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PathPart {
    /// Everything.
    Full,
    /// Emission seen from the camera and direct light at the first non-delta hit.
    Direct,
    /// Indirect light at the first non-delta hit only.
    Indirect,
    /// The caustic part of the indirect light (`L S+ x`): light that reached
    /// the first non-specular hit `x` from an emitter through mirrors and
    /// glass only. What the photon renderer reads from its caustic map.
    Caustic,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Class {
    Seen,
    Direct,
    /// Indirect, through specular surfaces only since `x`.
    Caustic,
    Indirect,
}

impl PathPart {
    fn counts(self, class: Class, show_emitters: bool) -> bool {
        match (self, class) {
            (_, Class::Seen) => show_emitters && self != PathPart::Indirect,
            (PathPart::Full, _) => true,
            (PathPart::Direct, c) => c == Class::Direct,
            (PathPart::Indirect, c) => matches!(c, Class::Indirect | Class::Caustic),
            (PathPart::Caustic, c) => c == Class::Caustic,
        }
    }
}

/// Where a path stands: non-delta vertices passed, and whether a mirror
/// was crossed since the first of them.
#[derive(Clone, Copy)]
struct State {
    non_delta: u32,
    delta_since_x: bool,
}

/// The path tracer over one prepared scene, through its caster.
#[allow(missing_debug_implementations)] // large images and borrowed scenes: nothing useful to print
pub struct PathTracer<'a> {
    pub(super) scene: &'a Scene,
    pub(super) rt: &'a dyn RayCaster,
    pub(super) eps: f32,
    /// Light index of each mesh that is an area light.
    light_of_mesh: Vec<Option<usize>>,
}

impl<'a> PathTracer<'a> {
    /// A path tracer of the scene of `prepared`, tracing with its caster.
    pub fn new<C: RayCaster>(prepared: &'a PreparedScene<C>) -> Self {
        Self::over(prepared.scene(), prepared.caster())
    }

    pub(super) fn over(scene: &'a Scene, rt: &'a dyn RayCaster) -> Self {
        let mut light_of_mesh = vec![None; scene.meshes.len()];
        for (i, l) in scene.lights.iter().enumerate() {
            if let Light::Area(a) = l {
                if let Some(slot) = light_of_mesh.get_mut(a.mesh) {
                    *slot = Some(i);
                }
            }
        }
        PathTracer {
            scene,
            rt,
            eps: ray_epsilon(scene),
            light_of_mesh,
        }
    }

    /// One sample of the radiance arriving along `ray` (from the camera).
    pub fn radiance(&self, ray: Ray, part: PathPart, show_emitters: bool, rng: &mut Rng) -> Vec3 {
        let start = State {
            non_delta: 0,
            delta_since_x: false,
        };
        self.trace(ray, start, part, show_emitters, rng)
    }

    /// One sample of the radiance arriving at a surface point along `ray`
    /// (leaving the point), *without* the emission of a light reached
    /// straight away: what the photon map's full irradiance adds to the
    /// direct light (the ray's origin plays the first non-delta vertex).
    pub fn radiance_after_first_bounce(&self, ray: Ray, rng: &mut Rng) -> Vec3 {
        let start = State {
            non_delta: 1,
            delta_since_x: false,
        };
        self.trace(ray, start, PathPart::Indirect, false, rng)
    }

    fn trace(
        &self,
        mut ray: Ray,
        mut st: State,
        part: PathPart,
        show_emitters: bool,
        rng: &mut Rng,
    ) -> Vec3 {
        let mut l = Vec3::ZERO;
        let mut beta = Vec3::ONE;
        // Position and solid-angle pdf of the last non-delta BRDF sample.
        let mut prev: Option<(Vec3, f32)> = None;
        for _ in 0..MAX_PATH_VERTICES {
            let Some(h) = self.rt.intersect(&ray) else {
                break;
            };
            let Some(mat) = self.scene.materials.get(h.material as usize) else {
                break;
            };
            let dir = ray.dir.normalize();
            let wo = -dir;
            let pos = ray.at(h.t);
            let from_inside = h.ng.dot(dir) > 0.0;
            let normal = h.facing(dir);
            if from_inside {
                // The segment just travelled lay inside this (closed) object.
                if let Some(sigma) = self.scene.interior_attenuation(h.material) {
                    beta *= (-sigma * h.t * ray.dir.length()).exp();
                }
            }
            if let Some(e) = mat.emission {
                let cos_l = e.facing(h.ng.dot(wo));
                let class = match st {
                    State { non_delta: 0, .. } => Class::Seen,
                    State {
                        non_delta: 1,
                        delta_since_x: false,
                    } => Class::Direct,
                    State { non_delta: 1, .. } => Class::Caustic,
                    _ => Class::Indirect,
                };
                if cos_l > 0.0 && part.counts(class, show_emitters) {
                    let le = e.radiance_toward(cos_l) * self.scene.emission_texel(&h);
                    let w = match (prev, self.light_area(&h)) {
                        (Some((p, pdf_b)), Some(area)) => {
                            let pdf_l = area_light_pdf(p, pos, cos_l, area);
                            power_heuristic(pdf_b, pdf_l)
                        }
                        _ => 1.0,
                    };
                    l += beta * le * w;
                }
            }
            // A partly transmitting surface scatters by one of its parts.
            let scattering = self
                .scene
                .scattering_material(h.material, || rng.next_f32());
            let mat = &self.scene.materials[scattering as usize];
            if mat.brdf.is_specular() {
                // Mirrors and glass (rough glass too: sampled, not lit by
                // next-event estimation, whose shadow rays it blocks).
                st.delta_since_x |= st.non_delta >= 1;
                let n = self.scene.scattering_normal(&mat.brdf, &h, from_inside);
                let frame = Frame::from_normal(n);
                let wo_l = frame.local_from_world(wo);
                let Some(bs) = mat.brdf.sample_in(wo_l, rng.next_2d(), Transport::Radiance) else {
                    break;
                };
                beta *= bs.weight;
                let out = frame.world_from_local(bs.wo);
                let transmitted = bs.wo.z * wo_l.z < 0.0;
                if !(beta.max_element() > 0.0)
                    || !beta.is_finite()
                    || !consistent_with_geometry(h.ng, wo, out, transmitted)
                {
                    break;
                }
                prev = None;
                let side = h.facing(-out);
                ray = Ray::new(pos + side * self.eps, out);
                continue;
            }
            // A textured material scatters by its texels at this point.
            let Some(brdf) = self.scene.surface_brdf(&h) else {
                break;
            };
            let shading = self.scene.shading_side(&h, normal, wo);
            let frame = Frame::from_normal(shading);
            let wo_l = frame.local_from_world(wo);
            st.non_delta += 1;
            // Past the first non-delta vertex there is no direct light left.
            if part == PathPart::Direct && st.non_delta > 1 {
                break;
            }
            let nee_class = if st.non_delta == 1 {
                Class::Direct
            } else {
                Class::Indirect
            };
            if part.counts(nee_class, show_emitters) {
                l += beta * next_event(self, &brdf, [pos, normal, shading, wo], rng);
            }
            let Some(bs) = brdf.sample(wo_l, rng.next_2d()) else {
                break;
            };
            beta *= bs.weight;
            if st.non_delta >= RR_START {
                let q = beta.max_element().min(0.95);
                if !(q > 0.0) || rng.next_f32() >= q {
                    break;
                }
                beta /= q;
            }
            if !(beta.max_element() > 0.0) || !beta.is_finite() {
                break;
            }
            let out = frame.world_from_local(bs.wo);
            // A shading normal can send a sample under the surface: dropped.
            if out.dot(normal) <= 0.0 {
                break;
            }
            prev = (!bs.specular).then_some((pos, bs.pdf));
            ray = Ray::new(pos + normal * self.eps, out);
        }
        l
    }

    /// The area light sampling's "area" at hit `h` on an area light: the
    /// light's area when it is sampled uniformly, the reciprocal of its
    /// area pdf at the point when textured (sampled by power).
    fn light_area(&self, h: &Hit) -> Option<f32> {
        let i = (*self.light_of_mesh.get(h.geom_id as usize)?)?;
        match self.scene.lights.get(i)? {
            Light::Area(a) if a.is_textured() => {
                Some(1.0 / a.pdf_area_at(h.prim_id as usize, h.u, h.v))
            }
            l => l.area(),
        }
    }
}

/// The power heuristic for one sample of each strategy: `a^2 / (a^2 + b^2)`.
pub(super) fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2.is_infinite() {
        return 1.0;
    }
    if a2 + b2 > 0.0 {
        a2 / (a2 + b2)
    } else {
        0.0
    }
}
