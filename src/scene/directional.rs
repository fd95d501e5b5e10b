//! A directional light: glTF `KHR_lights_punctual` type `directional`,
//! Blender's Sun lamp; pbrt-v4's `DistantLight`.
//!
//! Parameters:
//! - `direction`: the unit direction the light travels (a glTF light node's
//!   -Z axis in world space);
//! - `irradiance` `E` per channel: what it delivers to a surface facing it
//!   (glTF's lux, read as W/m^2 as the loader reads a point light's candela
//!   as W/sr: no photometric conversion).
//!
//! A surface at angle `theta` to it receives `E cos(theta)`, from one
//! direction: a delta in direction, so no BRDF-sampled ray ever reaches it.
//!
//! Photons leave a disc perpendicular to `direction` with the radius `r` of
//! the bounding sphere of the scene's geometry, tangent to that sphere on
//! the upstream side, all travelling along `direction`: every line of light
//! that can meet the scene crosses the disc, and the flux through it, the
//! light's power, is `E pi r^2` (pbrt-v4's `Phi`), exact. The sphere is the
//! scene's to give: [`super::Scene`] refits it ([`DirectionalLight::fit`])
//! whenever geometry or the light is added, so the disc is never stale, and
//! a light in a scene without geometry has radius 0 and no power (refused
//! by [`super::Scene::validate`]).
//!
//! For the adaptive counts: no area (`alpha_A = 1`) and `alpha_D = alpha_min`:
//! every photon leaves in the one direction, so splitting at emission gains
//! nothing.

use super::EmittedPhoton;
use crate::sampling::{concentric_disc, Frame};
use glam::Vec3;
use std::f32::consts::PI;

/// The disc's plane lies this fraction of `r` beyond the sphere, so that a
/// bounding radius rounded down by an ulp still leaves every vertex
/// downstream of the photons' origins.
const UPSTREAM_MARGIN: f32 = 1e-4;

/// Parallel light from infinitely far away.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectionalLight {
    direction: Vec3,
    irradiance: Vec3,
    /// Centre of the bounding sphere of the scene's geometry.
    centre: Vec3,
    /// Its radius; 0 until the scene has geometry.
    radius: f32,
}

impl DirectionalLight {
    /// Light travelling along `direction` (normalised here; a zero or
    /// non-finite one is kept as given, for [`super::Scene::add_light`] to
    /// refuse by its value) with irradiance `irradiance` on a surface facing
    /// it. Its photon disc is placed by the scene it is added to.
    pub fn new(direction: Vec3, irradiance: Vec3) -> Self {
        let unit = direction.normalize_or_zero();
        DirectionalLight {
            direction: if unit == Vec3::ZERO { direction } else { unit },
            irradiance,
            centre: Vec3::ZERO,
            radius: 0.0,
        }
    }

    /// Unit direction of travel.
    pub fn direction(&self) -> Vec3 {
        self.direction
    }

    /// Irradiance per channel on a surface facing the light.
    pub fn irradiance(&self) -> Vec3 {
        self.irradiance
    }

    /// Centre of the scene's bounding sphere, where the disc is aimed.
    pub fn scene_centre(&self) -> Vec3 {
        self.centre
    }

    /// Radius of the scene's bounding sphere and of the photon disc; 0 in a
    /// scene without geometry.
    pub fn scene_radius(&self) -> f32 {
        self.radius
    }

    /// Places the disc around the box `bounds` (`None`: no geometry, no
    /// disc): pbrt-v4's `Bounds3::BoundingSphere`, the box's centre and
    /// half diagonal.
    pub(super) fn fit(&mut self, bounds: Option<(Vec3, Vec3)>) {
        (self.centre, self.radius) = match bounds {
            Some((lo, hi)) => {
                let centre = 0.5 * (lo + hi);
                (centre, (hi - centre).length())
            }
            None => (Vec3::ZERO, 0.0),
        };
    }

    /// Emitted power per channel: `E pi r^2`.
    pub fn power(&self) -> Vec3 {
        self.irradiance * (PI * self.radius * self.radius)
    }

    /// A photon from the point of the disc that `u` picks (area-uniform),
    /// travelling along the light's direction, of weight 1.
    #[inline]
    pub fn sample(&self, u: [f32; 2]) -> EmittedPhoton {
        let (x, y) = concentric_disc(u);
        let across = Frame::from_normal(self.direction).world_from_local(Vec3::new(x, y, 0.0));
        let upstream = self.centre - self.direction * (self.radius * (1.0 + UPSTREAM_MARGIN));
        EmittedPhoton {
            origin: upstream + across * self.radius,
            direction: self.direction,
            normal: None,
            weight: Vec3::ONE,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn photons_leave_the_disc_upstream_of_the_sphere_along_the_direction() {
        let mut sun = DirectionalLight::new(Vec3::new(1.0, -2.0, 0.5), Vec3::ONE);
        let d = sun.direction();
        assert!((d.length() - 1.0).abs() < 1e-6);
        sun.fit(Some((Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, 1.0))));
        let r = sun.scene_radius();
        assert!((r - 2f32.sqrt()).abs() < 1e-6);
        for i in 0..64 {
            let u = [(i % 8) as f32 / 8.0 + 0.06, (i / 8) as f32 / 8.0 + 0.06];
            let e = sun.sample(u);
            assert_eq!(e.direction, d);
            let rel = e.origin - sun.scene_centre();
            // On the plane a little beyond the sphere, within the disc.
            assert!((rel.dot(d) + r * (1.0 + UPSTREAM_MARGIN)).abs() < 1e-5);
            assert!((rel - d * rel.dot(d)).length() <= r * (1.0 + 1e-5));
        }
    }

    #[test]
    fn no_geometry_means_no_disc_and_no_power() {
        let mut sun = DirectionalLight::new(-Vec3::Y, Vec3::splat(3.0));
        assert_eq!(sun.power(), Vec3::ZERO);
        sun.fit(Some((Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0))));
        assert_eq!(sun.power(), Vec3::splat(3.0 * PI));
        sun.fit(None);
        assert_eq!(sun.power(), Vec3::ZERO);
    }
}
