//! Where the caustic pass aims its photons (docs/method.md, "The caustic
//! pass"): Jensen's projection map, as bounding spheres of the specular
//! meshes and the cones of directions a point of a light sees them in.
//!
//! A path `L S+ D` starts with a ray whose first hit is a specular
//! object (a mirror or glass: [`crate::brdf::Brdf::is_specular`]). That
//! object lies inside its mesh's bounding sphere, so the ray's direction
//! lies in the cone the sphere subtends from the ray's origin. Sampling
//! only those cones loses no caustic path; directions outside every cone
//! have pdf 0 and could not have started one.
//!
//! From a point `x`, sphere `j` subtends a cone of solid angle `Omega_j`
//! (the whole sphere of directions when `x` is inside it). The sampler
//! picks cone `j` with probability `Omega_j / sum_k Omega_k` and a
//! direction uniform in it, so the mixture's pdf at `w` is
//! `#{cones holding w} / sum_k Omega_k`: the sum over the cones that
//! contain `w` of `(Omega_j / sum) (1 / Omega_j)`.

use crate::sampling::Frame;
use crate::scene::Scene;
use glam::Vec3;
use std::f32::consts::PI;

/// How much a bounding sphere is grown past its farthest vertex, relative
/// to its radius: rounding in the centre or radius must never leave a
/// vertex outside (that vertex's directions would get pdf 0).
const SPHERE_MARGIN: f32 = 1e-4;

/// A bounding sphere of one specular mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Target {
    /// Centre (the mesh's bounding-box centre).
    pub centre: Vec3,
    /// Radius (its farthest vertex, grown by a margin).
    pub radius: f32,
    /// The mesh, an index into [`Scene::meshes`].
    pub mesh: usize,
}

/// The cone sphere `target` subtends from a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cone {
    /// Unit axis, from the point to the sphere's centre.
    pub axis: Vec3,
    /// `1 - cos(half angle)`, in `(0, 2]` (2: the point is inside the
    /// sphere and every direction is in the cone).
    pub one_minus_cos: f32,
}

impl Cone {
    /// The cone's solid angle, `2 pi (1 - cos)`.
    pub fn solid_angle(&self) -> f32 {
        2.0 * PI * self.one_minus_cos
    }

    /// Whether the unit direction `w` is in the cone (its boundary
    /// included, with a rim a few float roundings wide).
    pub fn contains(&self, w: Vec3) -> bool {
        // 1 - cos = |w - axis|^2 / 2 for unit vectors, without the
        // cancellation of 1 - dot near the axis. A direction `sample` draws
        // on the rim carries an error of a few ulps per component, which
        // moves |w - axis|^2 / 2 by about |w - axis| times it: the rim
        // allows 8 ulps of that, so that the cone drawn holds its own
        // sample for the mixture's pdf as it does for the sampler's.
        let omc = self.one_minus_cos;
        let rim = 8.0 * f32::EPSILON * (omc + (2.0 * omc).sqrt());
        0.5 * (w - self.axis).length_squared() <= omc + rim
    }

    /// The direction of `u` uniform in the cone's solid angle.
    pub fn sample(&self, u: [f32; 2]) -> Vec3 {
        // 1 - cos(theta) directly: for a far, small sphere cos(theta) is
        // within an ulp of 1 and 1 - cos^2 would lose every digit.
        let omc = u[0] * self.one_minus_cos;
        let sin = (omc * (2.0 - omc)).max(0.0).sqrt();
        let phi = 2.0 * PI * u[1];
        let local = Vec3::new(sin * phi.cos(), sin * phi.sin(), 1.0 - omc);
        Frame::from_normal(self.axis)
            .world_from_local(local)
            .normalize()
    }
}

impl Target {
    /// The cone this sphere subtends from `x`; `None` when the sphere is
    /// wholly behind the plane through `x` normal to `facing` (a one-sided
    /// emitter there sends nothing into it), or for a non-finite point.
    pub fn cone_from(&self, x: Vec3, facing: Option<Vec3>) -> Option<Cone> {
        let d = self.centre - x;
        if !d.is_finite() {
            return None;
        }
        if facing.is_some_and(|n| d.dot(n) <= -self.radius) {
            return None;
        }
        let dist2 = d.length_squared();
        let r2 = self.radius * self.radius;
        if dist2 <= r2 {
            // Inside: the axis is arbitrary and the cone is every direction.
            return Some(Cone {
                axis: Vec3::Z,
                one_minus_cos: 2.0,
            });
        }
        let sin2 = r2 / dist2;
        let cos = (1.0 - sin2).max(0.0).sqrt();
        Some(Cone {
            axis: d / dist2.sqrt(),
            // 1 - sqrt(1 - s) = s / (1 + sqrt(1 - s)), without cancellation.
            one_minus_cos: (sin2 / (1.0 + cos)).max(f32::MIN_POSITIVE),
        })
    }
}

/// The bounding spheres of a scene's specular meshes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CausticAim {
    targets: Vec<Target>,
}

/// A direction the sampler chose and its pdf (solid angle).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AimedDirection {
    /// Unit direction.
    pub direction: Vec3,
    /// The mixture's pdf there (sr^-1).
    pub pdf: f32,
}

impl CausticAim {
    /// A sphere about every mesh whose material may scatter specularly
    /// (mirror, glass, or partly glass) and that has a vertex; none in a
    /// scene without one.
    pub fn new(scene: &Scene) -> Self {
        let targets = scene
            .meshes()
            .iter()
            .enumerate()
            .filter(|(_, m)| scene.may_scatter_specularly(m.material))
            .filter_map(|(i, m)| bounding_sphere(&m.positions).map(|(c, r)| (i, c, r)))
            .map(|(mesh, centre, radius)| Target {
                centre,
                radius,
                mesh,
            })
            .collect();
        CausticAim { targets }
    }

    /// Aim at these spheres (tests, or a caller's own bounds).
    pub fn from_targets(targets: Vec<Target>) -> Self {
        CausticAim { targets }
    }

    /// The spheres.
    pub fn targets(&self) -> &[Target] {
        &self.targets
    }

    /// True when the scene has no specular mesh: no caustic path exists.
    pub fn is_empty(&self) -> bool {
        self.targets.is_empty()
    }

    fn cones(&self, x: Vec3, facing: Option<Vec3>) -> impl Iterator<Item = Cone> + '_ {
        self.targets
            .iter()
            .filter_map(move |t| t.cone_from(x, facing))
    }

    /// A direction from `x` into one of the cones (`u_sel` picks the cone,
    /// `u` the direction in it) and the mixture's pdf there; `None` when
    /// `x` sees no sphere (every one behind `facing`'s plane).
    pub fn sample(
        &self,
        x: Vec3,
        facing: Option<Vec3>,
        u_sel: f32,
        u: [f32; 2],
    ) -> Option<AimedDirection> {
        let total: f32 = self.cones(x, facing).map(|c| c.solid_angle()).sum();
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let goal = u_sel * total;
        let (mut acc, mut picked, mut chosen) = (0.0f32, None, 0);
        for (j, cone) in self.cones(x, facing).enumerate() {
            acc += cone.solid_angle();
            picked = Some(cone);
            chosen = j;
            if goal < acc {
                break;
            }
        }
        let direction = picked?.sample(u);
        // The chosen cone holds its own sample whatever the rounding of
        // `contains` at its rim; the others are tested.
        let others = self
            .cones(x, facing)
            .enumerate()
            .filter(|&(j, c)| j != chosen && c.contains(direction))
            .count();
        Some(AimedDirection {
            direction,
            pdf: (1 + others) as f32 / total,
        })
    }

    /// The mixture's pdf of the unit direction `w` from `x` (0 outside
    /// every cone).
    pub fn pdf(&self, x: Vec3, facing: Option<Vec3>, w: Vec3) -> f32 {
        let (mut total, mut holding) = (0.0f32, 0u32);
        for c in self.cones(x, facing) {
            total += c.solid_angle();
            holding += u32::from(c.contains(w));
        }
        if total > 0.0 {
            holding as f32 / total
        } else {
            0.0
        }
    }
}

/// The centre of the box of `positions` and the distance to the farthest
/// one, grown by [`SPHERE_MARGIN`]; `None` without a finite vertex.
fn bounding_sphere(positions: &[Vec3]) -> Option<(Vec3, f32)> {
    let finite = || positions.iter().filter(|p| p.is_finite());
    let lo = finite().fold(Vec3::splat(f32::INFINITY), |a, &p| a.min(p));
    let hi = finite().fold(Vec3::splat(f32::NEG_INFINITY), |a, &p| a.max(p));
    if !lo.cmple(hi).all() {
        return None;
    }
    let centre = 0.5 * (lo + hi);
    let r = finite()
        .map(|&p| (p - centre).length())
        .fold(0.0f32, f32::max);
    // An absolute floor too: a point-like mesh still gets a cone.
    let grown = r * (1.0 + SPHERE_MARGIN) + (hi - lo).max_element().max(r) * 1e-6 + 1e-6;
    Some((centre, grown))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sphere_holds_every_vertex() {
        let pts = [
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(-4.0, 0.5, 2.0),
            Vec3::new(0.0, -1.0, 9.0),
        ];
        let (c, r) = bounding_sphere(&pts).unwrap();
        assert!(pts.iter().all(|p| (*p - c).length() < r));
        assert_eq!(bounding_sphere(&[]), None);
        assert_eq!(bounding_sphere(&[Vec3::NAN]), None);
    }

    #[test]
    fn a_far_small_sphere_keeps_its_cone() {
        let t = Target {
            centre: Vec3::new(0.0, 0.0, 1e4),
            radius: 1e-3,
            mesh: 0,
        };
        let cone = t.cone_from(Vec3::ZERO, None).unwrap();
        // (r/d)^2 / 2 = 5e-15: cos alone would round to 1.
        assert!((cone.one_minus_cos / 5e-15 - 1.0).abs() < 1e-3);
        let w = cone.sample([0.999, 0.3]);
        assert!(0.5 * (w - cone.axis).length_squared() < 1e-13, "{w}");
        // Behind a one-sided emitter facing away: no cone.
        assert_eq!(t.cone_from(Vec3::ZERO, Some(-Vec3::Z)), None);
        assert!(t.cone_from(Vec3::ZERO, Some(Vec3::Z)).is_some());
    }
}
