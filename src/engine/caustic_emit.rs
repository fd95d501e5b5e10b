//! A caustic photon leaving a light toward the specular objects
//! ([`CausticAim`]): the light's own position sampling, a direction from
//! the cones, and a weight that keeps the pass unbiased.
//!
//! The main trace emits photon `i` of a light with the light's position
//! density `p_A`, direction density `p_L(w | x)` and weight `w_L` (1 for
//! area and point lights), and carries `w_L P / N`. The caustic pass keeps
//! `p_A` and the position weight, draws `w` from the cones with density
//! `p_C(w | x)` instead, and carries `w_L p_L / p_C P / N_C`: both have the
//! same expected flux `L_e cos / N` per unit area and solid angle wherever
//! `p_C > 0`, and `p_C > 0` wherever a caustic path can start. For a
//! directional light the roles swap: its direction is fixed and the
//! position is drawn on the discs the spheres cast on its photon disc.

use super::caustic_aim::CausticAim;
use crate::rng::Rng;
use crate::sampling::{concentric_disc, Frame};
use crate::scene::{AreaLight, DirectionalLight, EmittedPhoton, Light, SpotLight};
use glam::Vec3;
use std::f32::consts::PI;

/// A photon of `light` aimed at `aim`'s spheres, its weight relative to
/// the light's mean photon (`power / N`); `None` when the sample can start
/// no caustic path (no sphere seen, zero emission that way).
pub fn aimed_photon(light: &Light, aim: &CausticAim, rng: &mut Rng) -> Option<EmittedPhoton> {
    let e = match light {
        Light::Area(a) => area(a, aim, rng),
        Light::Point(p) => {
            let d = aim.sample(p.position, None, rng.next_f32(), rng.next_2d())?;
            Some(EmittedPhoton {
                origin: p.position,
                direction: d.direction,
                normal: None,
                weight: Vec3::splat(1.0 / (4.0 * PI * d.pdf)),
            })
        }
        Light::Spot(s) => spot(s, light.power(), aim, rng),
        Light::Directional(d) => directional(d, aim, rng),
    }?;
    let live = e.weight.is_finite() && e.weight.max_element() > 0.0;
    live.then_some(e)
}

/// An area light: the point as the main trace draws it (its triangle, its
/// position weight), the direction from the cones, weighted by the
/// profile's pdf over the cones' (half of it per face when two-sided).
fn area(a: &AreaLight, aim: &CausticAim, rng: &mut Rng) -> Option<EmittedPhoton> {
    // A first u_dir below 1/2 takes the front face of a two-sided light
    // (AreaLight::sample): the origin, its weight and the front normal,
    // whatever direction the cones then give.
    let front = a.sample(rng.next_f32(), rng.next_2d(), [0.25, 0.5]);
    let n = front.normal?;
    let two_sided = a.emission.two_sided;
    let facing = (!two_sided).then_some(n);
    let d = aim.sample(front.origin, facing, rng.next_f32(), rng.next_2d())?;
    let cos = d.direction.dot(n);
    let profile_pdf = a
        .emission
        .profile
        .emission_pdf(Vec3::new(0.0, 0.0, cos.abs()));
    let (p_light, normal) = match (two_sided, cos > 0.0) {
        (false, true) => (profile_pdf, n),
        (false, false) => return None,
        (true, front_face) => (0.5 * profile_pdf, if front_face { n } else { -n }),
    };
    Some(EmittedPhoton {
        origin: front.origin,
        direction: d.direction,
        normal: Some(normal),
        weight: front.weight * (p_light / d.pdf),
    })
}

/// A spot light: the main trace's photon carries `I falloff / (p P)`
/// for its uniform-cone pdf `p`; here the cones' pdf takes `p`'s place.
fn spot(s: &SpotLight, power: Vec3, aim: &CausticAim, rng: &mut Rng) -> Option<EmittedPhoton> {
    let d = aim.sample(s.position, None, rng.next_f32(), rng.next_2d())?;
    let flux = s.intensity * s.falloff(d.direction.dot(s.direction)) / d.pdf;
    let per = |f: f32, p: f32| if p > 0.0 { f / p } else { 0.0 };
    Some(EmittedPhoton {
        origin: s.position,
        direction: d.direction,
        normal: None,
        weight: Vec3::new(
            per(flux.x, power.x),
            per(flux.y, power.y),
            per(flux.z, power.z),
        ),
    })
}

/// A directional light: a point on the disc one sphere casts on the
/// light's photon disc (picked by its area), weighted by the main trace's
/// density `1 / (pi r^2)` over the mixture's, `#{discs holding it} /
/// sum_k pi R_k^2`; a point off the light's disc is not emitted.
fn directional(d: &DirectionalLight, aim: &CausticAim, rng: &mut Rng) -> Option<EmittedPhoton> {
    let r = d.scene_radius();
    let dir = d.direction();
    // The disc's centre: the point its uniform sampler maps the square's
    // centre to (concentric_disc((1/2, 1/2)) = 0).
    let upstream = d.sample([0.5, 0.5]).origin;
    let frame = Frame::from_normal(dir);
    let across = |p: Vec3| {
        let q = frame.local_from_world(p - d.scene_centre());
        glam::Vec2::new(q.x, q.y)
    };
    let discs = aim.targets().iter().map(|t| (across(t.centre), t.radius));
    let total: f32 = discs.clone().map(|(_, rad)| rad * rad).sum();
    if !(total > 0.0 && total.is_finite() && r > 0.0) {
        return None;
    }
    let goal = rng.next_f32() * total;
    let (mut acc, mut chosen) = (0.0f32, None);
    for (centre, rad) in discs.clone() {
        acc += rad * rad;
        chosen = Some((centre, rad));
        if goal < acc {
            break;
        }
    }
    let (centre, rad) = chosen?;
    let (x, y) = concentric_disc(rng.next_2d());
    let at = centre + glam::Vec2::new(x, y) * rad;
    if at.length() > r {
        return None;
    }
    let holding = discs
        .filter(|&(c, rr)| (at - c).length_squared() <= rr * rr)
        .count()
        .max(1);
    Some(EmittedPhoton {
        origin: upstream + frame.world_from_local(Vec3::new(at.x, at.y, 0.0)),
        direction: dir,
        normal: None,
        weight: Vec3::splat(total / (r * r * holding as f32)),
    })
}
