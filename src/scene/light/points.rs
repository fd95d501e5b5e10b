//! Points on an area light for light sampling at a surface, and what a
//! textured light (`scene::emission_map`) adds: its radiance and
//! area pdf at any point, its power's integral.

use super::super::emission_map::{EmissionMap, MapSample};
use super::AreaLight;
use crate::sampling::uniform_triangle;
use glam::Vec3;
use std::sync::Arc;

/// A point sampled on an area light, for light sampling at a surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightPoint {
    /// Where.
    pub position: Vec3,
    /// The front face's unit geometric normal.
    pub normal: Vec3,
    /// The triangle (index in the light's mesh).
    pub triangle: usize,
    /// Radiance `L0` along the normal there (the texel's, when textured).
    pub radiance: Vec3,
    /// Area pdf of the point (`1 / area` for an untextured light).
    pub pdf_area: f32,
}

impl AreaLight {
    /// The light with its radiance read from an emissive texture
    /// (`scene::emission_map`); `None` when no texel it covers emits.
    pub(crate) fn with_map(
        mut self,
        build: impl FnOnce(&[[Vec3; 3]]) -> Option<EmissionMap>,
    ) -> Option<Self> {
        self.map = Some(Arc::new(build(&self.triangles)?));
        Some(self)
    }

    /// The light emitting nothing (its texture covers only black texels).
    pub(crate) fn dark(mut self) -> Self {
        self.map = None;
        self.emission.radiance = Vec3::ZERO;
        self
    }

    /// Whether an emissive texture sets the radiance.
    pub fn is_textured(&self) -> bool {
        self.map.is_some()
    }

    /// Whether [`Self::power`] is exact: always for an untextured light; for
    /// a textured one, when every triangle was cut along the texels
    /// (`scene::emission_map`).
    pub fn power_is_exact(&self) -> bool {
        self.map.as_ref().is_none_or(|m| m.is_exact())
    }

    /// The pieces a textured light is sampled by (0 untextured).
    pub fn piece_count(&self) -> usize {
        self.map.as_ref().map_or(0, |m| m.piece_count())
    }

    /// `integral L0 dA` per channel over the light (one face).
    pub fn radiance_integral(&self) -> Vec3 {
        match &self.map {
            Some(m) => m.integral(),
            None => self.emission.radiance * self.area,
        }
    }

    /// The mean radiance over the surface (the radiance, untextured).
    pub fn mean_radiance(&self) -> Vec3 {
        match &self.map {
            Some(m) if self.area > 0.0 => m.integral() / self.area,
            Some(_) => Vec3::ZERO,
            None => self.emission.radiance,
        }
    }

    /// Radiance `L0` along the normal at barycentrics `(u, v)` of triangle `t`.
    pub fn radiance_at(&self, t: usize, u: f32, v: f32) -> Vec3 {
        match &self.map {
            Some(m) if t < self.triangles.len() => m.radiance(t, (u, v)),
            Some(_) => Vec3::ZERO,
            None => self.emission.radiance,
        }
    }

    /// The area pdf of [`Self::sample_point`] at barycentrics `(u, v)` of triangle `t`.
    pub fn pdf_area_at(&self, t: usize, u: f32, v: f32) -> f32 {
        match &self.map {
            Some(m) => m.pdf_area(t, (u, v)),
            None => 1.0 / self.area,
        }
    }

    /// A point on the light: area-uniform (untextured; `u_tri` picks the
    /// triangle), or by emitted power (textured; `u_tri` picks the piece,
    /// `u_pos` the point in it).
    pub fn sample_point(&self, u_tri: f32, u_pos: [f32; 2]) -> LightPoint {
        match &self.map {
            Some(m) => self.map_point(m, m.sample_in(m.pick(u_tri), u_pos)),
            None => {
                let i = self.triangle_at(u_tri * self.area);
                let [a, b, c] = self.triangles[i];
                let (b0, b1) = uniform_triangle(u_pos);
                LightPoint {
                    // As `sample` places it, to the bit.
                    position: a * b0 + b * b1 + c * (1.0 - b0 - b1),
                    normal: self.frames[i].n,
                    triangle: i,
                    radiance: self.emission.radiance,
                    pdf_area: 1.0 / self.area,
                }
            }
        }
    }

    fn map_point(&self, m: &EmissionMap, s: MapSample) -> LightPoint {
        let [a, b, c] = self.triangles[s.triangle];
        let (b1, b2) = s.bary;
        LightPoint {
            position: a * (1.0 - b1 - b2) + b * b1 + c * b2,
            normal: self.frames[s.triangle].n,
            triangle: s.triangle,
            radiance: s.radiance.unwrap_or_else(|| m.radiance(s.triangle, s.bary)),
            pdf_area: s.pdf_area,
        }
    }
}
