//! Next-event estimation of the path tracer: one sample of every light from
//! a surface point, area lights weighted against BRDF sampling by the power
//! heuristic (see [`super::path`]). Point, spot and directional lights are
//! deltas that no BRDF sample reaches: their samples count fully.

// `!(x > 0.0)` is deliberate here: it rejects NaN with the non-positive values.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::direct::{punctual_arrival, Source};
use super::path::{power_heuristic, PathTracer};
use crate::brdf::Brdf;
use crate::rng::Rng;
use crate::sampling::Frame;
use crate::scene::Light;
use glam::Vec3;

/// Solid-angle pdf, seen from `from`, of a sample at `at` on an area light
/// whose cosine towards `from` is `cos_l`, drawn with the area pdf `1 / area`
/// (`area`: the light's area when it is sampled uniformly, else the
/// reciprocal of the point's area pdf).
pub(super) fn area_light_pdf(from: Vec3, at: Vec3, cos_l: f32, area: f32) -> f32 {
    let d2 = (at - from).length_squared();
    if cos_l > 0.0 && area > 0.0 {
        d2 / (cos_l * area)
    } else {
        f32::INFINITY
    }
}

/// Radiance reflected at `x` towards `wo` by one sample of each light,
/// shadow rays included: `ng` is the geometric normal on the ray's side,
/// `n` the shading normal the BRDF is evaluated about
/// ([`crate::scene::Scene::shading_side`]).
// Always inlined into its one caller: whether LLVM inlined it turned on
// unrelated changes elsewhere in the crate, and out of line (its points
// passed through the stack) the path tracer ran 5 % slower.
#[inline(always)]
pub(super) fn next_event(
    pt: &PathTracer,
    brdf: &Brdf,
    [x, ng, n, wo]: [Vec3; 4],
    rng: &mut Rng,
) -> Vec3 {
    let frame = Frame::from_normal(n);
    let wo_l = frame.local_from_world(wo);
    let origin = x + ng * pt.eps;
    let mut sum = Vec3::ZERO;
    for light in &pt.scene.lights {
        // (where the light comes from, incoming radiance or intensity / r^2
        // over the pdf, MIS weight input)
        let (source, li, pdf_l) = match light {
            Light::Area(a) => {
                // By emitted power on a textured light, else area-uniform.
                let p = a.sample_point(rng.next_f32(), rng.next_2d());
                let d = x - p.position;
                let r2 = d.length_squared();
                if !(r2 > 0.0) {
                    continue;
                }
                let cos_l = a.emission.facing(p.normal.dot(d) / r2.sqrt());
                if cos_l <= 0.0 {
                    continue;
                }
                let le = p.radiance * a.emission.profile_toward(cos_l);
                let area = if a.is_textured() {
                    1.0 / p.pdf_area
                } else {
                    a.area
                };
                let pdf = area_light_pdf(x, p.position, cos_l, area);
                (Source::At(p.position), le / pdf, Some(pdf))
            }
            delta => match punctual_arrival(delta, x) {
                Some((source, li)) => (source, li, None),
                None => continue,
            },
        };
        let wi = source.direction_from(x);
        let cos_x = wi.dot(n);
        if cos_x <= 0.0 || wi.dot(ng) <= 0.0 || !(li.max_element() > 0.0) {
            continue;
        }
        let wi_l = frame.local_from_world(wi);
        let f = brdf.eval(wi_l, wo_l);
        if !(f.max_element() > 0.0) {
            continue;
        }
        if pt.rt.occluded(&source.shadow_ray(origin)) {
            continue;
        }
        let w = match pdf_l {
            Some(pdf_l) => power_heuristic(pdf_l, brdf.pdf(wo_l, wi_l)),
            None => 1.0,
        };
        sum += f * li * (cos_x * w);
    }
    sum
}
