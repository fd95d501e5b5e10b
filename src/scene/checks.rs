//! The invariants [`super::Scene`]'s constructors enforce, so that a scene
//! built in code or loaded from a file never panics or aborts later: every
//! coordinate finite and within [`MAX_COORDINATE`] (Embree aborts on a ray
//! beyond [`crate::raycast::EMBREE_LARGE`]), every derived quantity (areas,
//! powers, directions) finite.

use super::{AreaLight, Camera, DirectionalLight, Emission, Light, Material, Mesh};
use crate::error::{Error, Result};
use crate::raycast::EMBREE_LARGE;
use crate::sampling::luminance;
use glam::Vec3;

/// The largest coordinate a vertex, light or camera may have. Rays start at
/// scene points plus small offsets; 1/16 of Embree's limit leaves room for
/// them and for differences of two points.
pub const MAX_COORDINATE: f32 = EMBREE_LARGE / 16.0;

fn bad(msg: String) -> Error {
    Error::InvalidScene(msg)
}

fn in_range(p: Vec3) -> bool {
    p.abs().cmple(Vec3::splat(MAX_COORDINATE)).all()
}

pub(super) fn check_positions(name: &str, positions: &[Vec3]) -> Result<()> {
    match positions.iter().position(|&p| !in_range(p)) {
        None => Ok(()),
        Some(i) => Err(bad(format!(
            "mesh `{name}` has vertex {i} at {}: non-finite or beyond {MAX_COORDINATE:e}",
            positions[i]
        ))),
    }
}

pub(super) fn check_material(m: &Material) -> Result<()> {
    let albedo = m.brdf.albedo(Vec3::Z);
    if !albedo.is_finite() || albedo.min_element() < 0.0 {
        return Err(bad(format!(
            "material `{}` has a non-finite or negative albedo {albedo}",
            m.name
        )));
    }
    if let Some(e) = &m.emission {
        if !e.radiance.is_finite() || e.radiance.min_element() < 0.0 {
            return Err(bad(format!(
                "material `{}` has an invalid emission {}",
                m.name, e.radiance
            )));
        }
        if e.radiance.max_element() > MAX_RADIANCE {
            return Err(bad(format!(
                "material `{}` emits a radiance {} above {MAX_RADIANCE:e}",
                m.name,
                sci(e.radiance)
            )));
        }
    }
    Ok(())
}

/// Triangles kept, and when some were dropped, the source index of each.
pub(super) struct Kept {
    pub kept: Vec<u32>,
    pub len_dropped: usize,
}

pub(super) fn drop_degenerate(
    positions: &[Vec3],
    indices: Vec<[u32; 3]>,
) -> (Vec<[u32; 3]>, Option<Kept>) {
    let good = |t: &[u32; 3]| {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let n = (b - a).cross(c - a);
        n.length_squared() > 0.0 && n.is_finite()
    };
    if indices.iter().all(good) {
        return (indices, None);
    }
    let before = indices.len();
    let (mut out, mut kept) = (Vec::new(), Vec::new());
    for (i, t) in indices.into_iter().enumerate() {
        if good(&t) {
            out.push(t);
            kept.push(i as u32);
        }
    }
    let len_dropped = before - out.len();
    (out, Some(Kept { kept, len_dropped }))
}

/// The largest power (W, any channel) a light may have, and the largest
/// total over a scene's lights ([`super::Scene::validate`]). Photon powers,
/// the map's quantiser (which keeps 256x headroom), density estimates and
/// pixel sums are f32: 1e30 leaves eight orders of magnitude below f32's
/// 3.4e38 for them (the Sun, 3.8e26 W, fits). Above it, sums overflowed
/// and whole renders came out null or zero.
pub const MAX_LIGHT_POWER: f32 = 1e30;

/// The smallest non-zero power (luminance, W) a light may have: a photon of
/// it split a trillion ways is still a normal f32. Below it, flush-to-zero
/// (on in every tracing thread) made the light emit nothing.
pub const MIN_LIGHT_POWER: f32 = 1e-20;

/// The largest emitted radiance (any channel): what a camera sees of an
/// emitter, and what pixel sums add up.
pub const MAX_RADIANCE: f32 = 1e30;

/// `[1e38, 1e38, 1e38]`: huge and tiny values in a readable form.
fn sci(v: Vec3) -> String {
    format!("[{:e}, {:e}, {:e}]", v.x, v.y, v.z)
}

/// `None` when a light's power is usable, else what is wrong with it.
pub(super) fn power_problem(p: Vec3) -> Option<String> {
    let y = luminance(p);
    if !p.is_finite() || !y.is_finite() || p.min_element() < 0.0 {
        return Some(format!("its power {} is negative or overflows", sci(p)));
    }
    if p.max_element() > MAX_LIGHT_POWER {
        return Some(format!(
            "its power {} W is above {MAX_LIGHT_POWER:e} W (scale the scene's lights down)",
            sci(p)
        ));
    }
    if y > 0.0 && y < MIN_LIGHT_POWER {
        return Some(format!(
            "its power {y:e} W is below {MIN_LIGHT_POWER:e} W (too small to carry photons)"
        ));
    }
    None
}

pub(super) fn area_light(mesh: &Mesh, index: usize, e: Emission) -> Result<AreaLight> {
    let light = AreaLight::new(mesh, index, e)
        .ok_or_else(|| bad(format!("emissive mesh `{}` has no area", mesh.name)))?;
    if !light.area.is_finite() {
        return Err(bad(format!(
            "emissive mesh `{}`: its area overflows",
            mesh.name
        )));
    }
    if let Some(why) = power_problem(light.power()) {
        return Err(bad(format!("emissive mesh `{}`: {why}", mesh.name)));
    }
    Ok(light)
}

pub(super) fn check_punctual(light: &Light) -> Result<()> {
    let (position, intensity) = match light {
        Light::Area(a) => {
            return Err(bad(format!(
                "an area light (mesh {}) is added by add_mesh with an emissive material",
                a.mesh
            )))
        }
        Light::Directional(d) => return check_directional(d),
        Light::Point(p) => (p.position, p.intensity),
        Light::Spot(s) => {
            let unit = s.direction.is_finite() && (s.direction.length() - 1.0).abs() < 1e-3;
            if !unit {
                return Err(bad(format!(
                    "spot light axis {} is not a unit vector (a zero scale on its node?)",
                    s.direction
                )));
            }
            let ordered = (-1.0..1.0).contains(&s.cos_outer)
                && s.cos_outer < s.cos_inner
                && s.cos_inner <= 1.0;
            if !ordered {
                return Err(bad(format!(
                    "spot light cone cosines inner {} outer {} are not -1 <= outer < inner <= 1",
                    s.cos_inner, s.cos_outer
                )));
            }
            (s.position, s.intensity)
        }
    };
    if !in_range(position) {
        return Err(bad(format!(
            "{} light position {position} is not finite or beyond {MAX_COORDINATE:e}",
            light.kind()
        )));
    }
    if !intensity.is_finite() || intensity.min_element() < 0.0 {
        return Err(bad(format!(
            "{} light intensity {intensity} is negative or not finite",
            light.kind()
        )));
    }
    if let Some(why) = power_problem(light.power()) {
        return Err(bad(format!(
            "{} light of intensity {}: {why}",
            light.kind(),
            sci(intensity)
        )));
    }
    Ok(())
}

/// A directional light's own values. Its power depends on the scene's
/// bounds, which may still grow: [`check_directional_powers`] checks it
/// once the scene is complete.
fn check_directional(d: &DirectionalLight) -> Result<()> {
    let dir = d.direction();
    if !(dir.is_finite() && (dir.length() - 1.0).abs() < 1e-3) {
        return Err(bad(format!(
            "directional light direction {dir} is not finite and non-zero (a zero scale on its node?)"
        )));
    }
    let e = d.irradiance();
    if !e.is_finite() || e.min_element() < 0.0 {
        return Err(bad(format!(
            "directional light irradiance {e} is negative or not finite"
        )));
    }
    Ok(())
}

/// Every directional light's power `E pi r^2` for the scene's final bounds.
pub(super) fn check_directional_powers(lights: &[Light]) -> Result<()> {
    for (i, l) in lights.iter().enumerate() {
        let Light::Directional(d) = l else { continue };
        if let Some(why) = power_problem(d.power()) {
            return Err(bad(format!(
                "directional light {i} of irradiance {} over the scene's bounding radius {:e}: {why}",
                sci(d.irradiance()),
                d.scene_radius()
            )));
        }
    }
    Ok(())
}

pub(super) fn check_camera(c: &Camera) -> Result<()> {
    let unit = |v: Vec3| v.is_finite() && (v.length() - 1.0).abs() < 1e-3;
    if !in_range(c.eye) {
        return Err(bad(format!(
            "camera eye {} is not finite or beyond {MAX_COORDINATE:e}",
            c.eye
        )));
    }
    if !unit(c.forward) || !unit(c.up) || c.forward.dot(c.up).abs() > 1e-3 {
        return Err(bad(format!(
            "camera axes forward {} and up {} are not orthogonal unit vectors (a zero scale on its node?)",
            c.forward, c.up
        )));
    }
    if !(c.vfov_deg > 0.0 && c.vfov_deg < 180.0) {
        return Err(bad(format!(
            "camera field of view {} degrees is outside (0, 180)",
            c.vfov_deg
        )));
    }
    Ok(())
}
