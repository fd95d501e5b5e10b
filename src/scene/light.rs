//! Lights and photon emission from them.
//!
//! - [`AreaLight`]: an emissive mesh, radiance `L0 cos^n(theta)` about each
//!   triangle's geometric normal, from the front (or both faces when
//!   two-sided). Power `sides A L0 2 pi / (n + 2)`, exact.
//! - [`PointLight`]: `KHR_lights_punctual` point, intensity `I` (W/sr), power `4 pi I`.
//! - [`SpotLight`]: `KHR_lights_punctual` spot, full intensity inside the inner
//!   cone, a smooth falloff to the outer cone; power
//!   `2 pi I (1 - (cos_inner + cos_outer) / 2)` (pbrt-v4's approximation of the
//!   smoothstep falloff, exact for a linear one).
//! - [`DirectionalLight`] (`super::directional`): `KHR_lights_punctual`
//!   directional, Blender's Sun: irradiance `E` from one direction, power
//!   `E pi r^2` through a disc of the scene's bounding radius `r`.
//!
//! Punctual lights have no area: the adaptive mode uses `alpha_A = 1` for them.
//!
//! An area light with an emissive texture ([`AreaLight::is_textured`],
//! `scene::emission_map`) has a radiance `L0(x)` that varies over its
//! surface: its power is `sides (2 pi / (n + 2)) integral L0 dA`, summed
//! over the texels, and its points are sampled by emitted power, each
//! photon weighted by its point's radiance over the pdf.

use super::emission_map::EmissionMap;
use super::{triangle_area, DirectionalLight, Emission, Mesh};

mod points;
use crate::emitter::CosN;
use crate::sampling::{spherical_direction, uniform_triangle, Frame};
use glam::Vec3;
pub use points::LightPoint;
use std::f32::consts::PI;
use std::sync::Arc;

/// One photon leaving a light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmittedPhoton {
    /// Where it starts.
    pub origin: Vec3,
    /// Unit direction of travel.
    pub direction: Vec3,
    /// The emitter's surface normal (area lights), to offset the origin.
    pub normal: Option<Vec3>,
    /// Power relative to the mean: the photon carries `weight * power / N`
    /// when N photons are emitted (exactly 1 for area and point lights).
    pub weight: Vec3,
}

/// An emissive mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct AreaLight {
    /// Index of the mesh in [`super::Scene::meshes`].
    pub mesh: usize,
    /// The emission.
    pub emission: Emission,
    /// Total area.
    pub area: f32,
    triangles: Vec<[Vec3; 3]>,
    /// Each triangle's emission frame (z = its geometric normal).
    frames: Vec<Frame>,
    cdf: Vec<f32>,
    /// Where to start looking in `cdf`: `guide[j]` is the triangle that
    /// holds the area `j / guide.len()` of the way along, so a photon's
    /// triangle is found in O(1) expected steps instead of a binary search
    /// (13 dependent, unpredictable branches for an 8k-triangle emitter).
    guide: Vec<u32>,
    /// The emissive texture, when the radiance varies over the surface.
    map: Option<Arc<EmissionMap>>,
}

impl AreaLight {
    /// Builds the light of an emissive mesh; `None` when it has no area.
    pub fn new(mesh: &Mesh, index: usize, emission: Emission) -> Option<Self> {
        let triangles: Vec<[Vec3; 3]> = (0..mesh.indices.len()).map(|i| mesh.triangle(i)).collect();
        let mut cdf = Vec::with_capacity(triangles.len());
        let mut acc = 0.0f64;
        for t in &triangles {
            acc += triangle_area(*t) as f64;
            cdf.push(acc as f32);
        }
        if acc <= 0.0 {
            return None;
        }
        let frames = triangles
            .iter()
            .map(|&[a, b, c]| Frame::from_normal((b - a).cross(c - a).normalize()))
            .collect();
        let buckets = triangles.len();
        let guide = (0..buckets)
            .map(|j| {
                let at = (acc * j as f64 / buckets as f64) as f32;
                cdf.partition_point(|&c| c < at) as u32
            })
            .collect();
        Some(AreaLight {
            mesh: index,
            emission,
            area: acc as f32,
            triangles,
            frames,
            cdf,
            guide,
            map: None,
        })
    }

    /// The triangle whose share of the area holds `target`: the first whose
    /// running area is at least `target` (the last for a larger one), as a
    /// binary search of `cdf` finds it. The guide gives a start; the walk
    /// from it is exact whatever the start, so rounding in the bucket does
    /// not matter.
    ///
    /// A NaN target lands in bucket 0, whose start is 0, and takes no step:
    /// 0, as the binary search (no `c < NaN`). An area that overflowed to
    /// infinity puts every target in bucket 0: still exact, in O(n).
    fn triangle_at(&self, target: f32) -> usize {
        let n = self.cdf.len();
        let bucket = (target / self.area * self.guide.len() as f32) as usize;
        let mut i = self.guide[bucket.min(self.guide.len() - 1)] as usize;
        while i > 0 && self.cdf[i - 1] >= target {
            i -= 1;
        }
        while i < n && self.cdf[i] < target {
            i += 1;
        }
        i.min(n - 1)
    }

    /// Changes the `cos^n` profile.
    pub fn set_profile(&mut self, profile: CosN) {
        self.emission.profile = profile;
    }

    /// Emitted power per channel: `sides (2 pi / (n + 2)) integral L0 dA`,
    /// the texels' sum for a textured light ([`Self::power_is_exact`]).
    ///
    /// Used for: the share of photons each light emits (`engine::counts`:
    /// `N_MAX P_l / sum P`, and the adaptive mode's `alpha_E`), each
    /// photon's power (`power / N` times the sample's weight), the
    /// renderer's light choice (its share by power), and the scene's checks
    /// ([`super::Scene::validate`]). Only the photon powers need it exact for
    /// the map to be unbiased; a textured light's weights use its true
    /// radiance over the true pdf, so even an approximate power cancels.
    pub fn power(&self) -> Vec3 {
        self.radiance_integral()
            * self.emission.profile.projected_integral()
            * self.emission.sides()
    }

    /// Samples a photon: position area-uniform, direction `~ cos^(n+1)`.
    /// `u_tri` picks the triangle. A two-sided light picks the face with
    /// the first half of `u_dir[0]` (front below 1/2, rescaled), so a
    /// one-sided light's photons are unchanged by the option existing.
    ///
    /// A textured light places the point by emitted power
    /// ([`Self::sample_point`]) and weights the photon by its flux over the
    /// mean: `L0(x) sides (2 pi / (n + 2)) / pdf_area(x) / power`.
    #[inline]
    pub fn sample(&self, u_tri: f32, u_pos: [f32; 2], u_dir: [f32; 2]) -> EmittedPhoton {
        let (i, origin, weight) = match &self.map {
            None => {
                let i = self.triangle_at(u_tri * self.area);
                let [a, b, c] = self.triangles[i];
                let (b0, b1) = uniform_triangle(u_pos);
                (i, a * b0 + b * b1 + c * (1.0 - b0 - b1), Vec3::ONE)
            }
            Some(_) => {
                let p = self.sample_point(u_tri, u_pos);
                let per_area = self.emission.profile.projected_integral() * self.emission.sides();
                let flux = p.radiance * per_area / p.pdf_area;
                let power = self.power();
                let w = Vec3::new(
                    ratio(flux.x, power.x),
                    ratio(flux.y, power.y),
                    ratio(flux.z, power.z),
                );
                (
                    p.triangle,
                    p.position,
                    if w.is_finite() { w } else { Vec3::ZERO },
                )
            }
        };
        let frame = &self.frames[i];
        let (u_dir, back) = match self.emission.two_sided {
            false => (u_dir, false),
            true if u_dir[0] < 0.5 => ([2.0 * u_dir[0], u_dir[1]], false),
            true => ([2.0 * u_dir[0] - 1.0, u_dir[1]], true),
        };
        let local = self.emission.profile.sample_emission(u_dir);
        let (direction, normal) = (frame.world_from_local(local), frame.n);
        let (direction, normal) = if back {
            (-direction, -normal)
        } else {
            (direction, normal)
        };
        EmittedPhoton {
            origin,
            direction,
            normal: Some(normal),
            weight,
        }
    }
}

/// An isotropic point light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLight {
    /// Position.
    pub position: Vec3,
    /// Radiant intensity per channel (W/sr).
    pub intensity: Vec3,
}

/// A spot light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpotLight {
    /// Position.
    pub position: Vec3,
    /// Unit axis.
    pub direction: Vec3,
    /// Radiant intensity on the axis (W/sr).
    pub intensity: Vec3,
    /// Cosine of the inner cone angle.
    pub cos_inner: f32,
    /// Cosine of the outer cone angle.
    pub cos_outer: f32,
}

impl SpotLight {
    /// Intensity relative to the axis at `cos_theta` from it: 1 inside the
    /// inner cone, 0 outside the outer one, a smoothstep between.
    pub fn falloff(&self, cos_theta: f32) -> f32 {
        if cos_theta >= self.cos_inner {
            1.0
        } else if cos_theta <= self.cos_outer {
            0.0
        } else {
            let t = (cos_theta - self.cos_outer) / (self.cos_inner - self.cos_outer).max(1e-8);
            t * t * (3.0 - 2.0 * t)
        }
    }
}

/// Any light of a scene.
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// An emissive mesh.
    Area(AreaLight),
    /// A point light.
    Point(PointLight),
    /// A spot light.
    Spot(SpotLight),
    /// A directional light (the Sun).
    Directional(DirectionalLight),
}

impl Light {
    /// Emitted power per channel.
    pub fn power(&self) -> Vec3 {
        match self {
            Light::Area(a) => a.power(),
            Light::Point(p) => p.intensity * 4.0 * PI,
            Light::Spot(s) => s.intensity * 2.0 * PI * (1.0 - 0.5 * (s.cos_inner + s.cos_outer)),
            Light::Directional(d) => d.power(),
        }
    }

    /// Emitting area; `None` for punctual lights.
    pub fn area(&self) -> Option<f32> {
        match self {
            Light::Area(a) => Some(a.area),
            _ => None,
        }
    }

    /// Position of a point or spot light (area and directional lights have none).
    pub fn position(&self) -> Option<Vec3> {
        match self {
            Light::Area(_) | Light::Directional(_) => None,
            Light::Point(p) => Some(p.position),
            Light::Spot(s) => Some(s.position),
        }
    }

    /// A short name for reports.
    pub fn kind(&self) -> &'static str {
        match self {
            Light::Area(_) => "area",
            Light::Point(_) => "point",
            Light::Spot(_) => "spot",
            Light::Directional(_) => "directional",
        }
    }

    /// Samples an emitted photon: `u_sel` picks the triangle of an area light,
    /// `u_pos` the point on it (on a directional light's disc), `u_dir` the
    /// direction.
    #[inline]
    pub fn sample(&self, u_sel: f32, u_pos: [f32; 2], u_dir: [f32; 2]) -> EmittedPhoton {
        match self {
            Light::Area(a) => a.sample(u_sel, u_pos, u_dir),
            Light::Point(p) => EmittedPhoton {
                origin: p.position,
                direction: {
                    let z = 1.0 - 2.0 * u_dir[0];
                    spherical_direction(z, 2.0 * PI * u_dir[1])
                },
                normal: None,
                weight: Vec3::ONE,
            },
            Light::Directional(d) => d.sample(u_pos),
            Light::Spot(s) => {
                // Uniform in the outer cone, weighted by the falloff.
                let cos_t = 1.0 - u_dir[0] * (1.0 - s.cos_outer);
                let local = spherical_direction(cos_t, 2.0 * PI * u_dir[1]);
                let pdf = 1.0 / (2.0 * PI * (1.0 - s.cos_outer).max(1e-12));
                let power = self.power();
                let flux = s.intensity * s.falloff(cos_t) / pdf;
                let weight = Vec3::new(
                    ratio(flux.x, power.x),
                    ratio(flux.y, power.y),
                    ratio(flux.z, power.z),
                );
                EmittedPhoton {
                    origin: s.position,
                    direction: Frame::from_normal(s.direction).world_from_local(local),
                    normal: None,
                    weight,
                }
            }
        }
    }
}

fn ratio(a: f32, b: f32) -> f32 {
    if b > 0.0 {
        a / b
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// A strip of `areas.len()` triangles with those areas (0 for a
    /// degenerate one) along x.
    fn strip(areas: &[f32]) -> Mesh {
        let mut positions = Vec::new();
        let mut indices = Vec::new();
        for (k, &a) in areas.iter().enumerate() {
            let x = k as f32 * 3.0;
            let base = positions.len() as u32;
            positions.extend([
                Vec3::new(x, 0.0, 0.0),
                Vec3::new(x + 1.0, 0.0, 0.0),
                Vec3::new(x, 2.0 * a, 0.0),
            ]);
            indices.push([base, base + 1, base + 2]);
        }
        Mesh {
            name: "strip".into(),
            positions,
            indices,
            material: 0,
            normals: Vec::new(),
            texcoords: Vec::new(),
            colors: Vec::new(),
            tangents: Vec::new(),
        }
    }

    #[test]
    fn the_guide_finds_the_triangle_the_binary_search_finds() {
        let emission = Emission::new(Vec3::ONE, CosN::new(1.0).unwrap());
        let mut rng = Rng::new(7);
        let uneven: Vec<f32> = (0..1000)
            .map(|i| match i % 7 {
                0 => 0.0,
                1 => 1e-6,
                2 => 50.0,
                _ => rng.next_f32(),
            })
            .collect();
        // The first running area one float below the guide's first bucket
        // boundary: the guide starts past it and must step back.
        let step_back = [0x40c6_29f8, 0x3fa4_92ad, 0x3fe7_c147].map(f32::from_bits);
        for areas in [
            vec![1.0],
            vec![0.0, 1.0, 0.0],
            vec![1.0; 64],
            step_back.to_vec(),
            uneven,
        ] {
            let light = AreaLight::new(&strip(&areas), 0, emission).unwrap();
            let binary = |t: f32| {
                light
                    .cdf
                    .partition_point(|&c| c < t)
                    .min(light.cdf.len() - 1)
            };
            // Every running area exactly, its neighbours, the ends, and
            // random targets.
            let mut targets: Vec<f32> = vec![
                0.0,
                -0.0,
                -1.0,
                f32::from_bits(1), // the smallest subnormal
                light.area,
                2.0 * light.area,
                f32::INFINITY,
                f32::NEG_INFINITY,
                f32::NAN,
            ];
            for &c in light.cdf.iter().filter(|&&c| c > 0.0) {
                // The floats either side of a positive `c`.
                let (below, above) = (c.to_bits() - 1, c.to_bits() + 1);
                targets.extend([c, f32::from_bits(below), f32::from_bits(above)]);
            }
            targets.extend((0..10_000).map(|_| rng.next_f32() * light.area));
            for t in targets {
                assert_eq!(
                    light.triangle_at(t),
                    binary(t),
                    "target {t} of {}",
                    light.area
                );
            }
        }
    }
}
