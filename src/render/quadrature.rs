//! Direct light by quadrature over the emitters: the oracle of the tests and
//! of the trade study, and the floor points they evaluate it at.
//!
//! Area light of radiance `L0 cos^n(theta_l)` (one-sided, about the triangle's
//! geometric normal): irradiance at `x` with normal `n_x`
//! `E(x) = integral L0 cos^n(theta_l) cos(theta_l) cos(theta_x) / r^2 V dA`.
//! Point light of intensity `I`: `I cos(theta_x) / r^2 V`; spot light: the same
//! times its falloff (the smoothstep of [`crate::scene::SpotLight`]);
//! directional light of irradiance `E`: `E cos(theta_x) V`. A textured
//! area light's `L0` is its texel's at each node (the rule then converges
//! as the grid refines, not exactly).

use super::direct::{punctual_arrival, Source};
use crate::raycast::RayCaster;
use crate::scene::{Light, PreparedScene, Scene, SurfacePoint};
use glam::Vec3;

/// Direct irradiance at `x` (normal `n`) by a midpoint rule: every area-light
/// triangle cut into `grid^2` similar sub-triangles, each sampled at its
/// centroid; point, spot and directional lights exactly. Every node traces a shadow ray with
/// the caster of `prepared`.
pub fn quadrature_irradiance<C: RayCaster>(
    prepared: &PreparedScene<C>,
    x: Vec3,
    n: Vec3,
    grid: u32,
) -> Vec3 {
    let rt: &dyn RayCaster = prepared.caster();
    quadrature(prepared.scene(), Some(rt), x, n, grid)
}

/// [`quadrature_irradiance`] with every light fully visible: no shadow rays,
/// no caster.
pub fn unshadowed_irradiance(scene: &Scene, x: Vec3, n: Vec3, grid: u32) -> Vec3 {
    quadrature(scene, None, x, n, grid)
}

fn quadrature(scene: &Scene, rt: Option<&dyn RayCaster>, x: Vec3, n: Vec3, grid: u32) -> Vec3 {
    let grid = grid.max(1);
    let eps = super::ray_epsilon(scene);
    let origin = x + n * eps;
    let visible = |source: Source| match rt {
        Some(rt) => !rt.occluded(&source.shadow_ray(origin)),
        None => true,
    };
    let mut e = Vec3::ZERO;
    for light in &scene.lights {
        match light {
            Light::Area(a) => {
                let mesh = &scene.meshes[a.mesh];
                let g = grid as f32;
                for t in 0..mesh.indices.len() {
                    let [v0, v1, v2] = mesh.triangle(t);
                    let normal = (v1 - v0).cross(v2 - v0);
                    let area = 0.5 * normal.length();
                    let n_l = normal.normalize();
                    let da = area / (g * g);
                    // Sub-triangles of the barycentric grid: (i, j) upright and inverted.
                    for i in 0..grid {
                        for j in 0..grid - i {
                            let up = Vec3::new(i as f32 + 1.0 / 3.0, j as f32 + 1.0 / 3.0, 0.0);
                            let down = Vec3::new(i as f32 + 2.0 / 3.0, j as f32 + 2.0 / 3.0, 0.0);
                            let count = if i + j + 1 < grid { 2 } else { 1 };
                            for c in [up, down].into_iter().take(count) {
                                let (b1, b2) = (c.x / g, c.y / g);
                                let p = v0 + (v1 - v0) * b1 + (v2 - v0) * b2;
                                let d = x - p;
                                let r2 = d.length_squared();
                                if r2 <= 0.0 {
                                    continue;
                                }
                                let r = r2.sqrt();
                                let cos_l = a.emission.facing(n_l.dot(d) / r);
                                let cos_x = -n.dot(d) / r;
                                if cos_l <= 0.0 || cos_x <= 0.0 || !visible(Source::At(p)) {
                                    continue;
                                }
                                let le = a.emission.profile_toward(cos_l);
                                let l0 = match a.is_textured() {
                                    true => a.radiance_at(t, b1, b2),
                                    false => a.emission.radiance,
                                };
                                e += l0 * (le * cos_l * cos_x * da / r2);
                            }
                        }
                    }
                }
            }
            Light::Point(_) | Light::Spot(_) | Light::Directional(_) => {
                if let Some((source, ig)) = punctual_arrival(light, x) {
                    let cos_x = source.direction_from(x).dot(n);
                    if cos_x > 0.0 && visible(source) {
                        e += ig * cos_x;
                    }
                }
            }
        }
    }
    e
}

/// A `nx x nz` grid of points on the meshes whose name starts with `prefix`
/// (the floor: `floor`), inset by `margin` (a fraction of the extent) from the
/// bounding box, keeping points inside a triangle. Normals face up (+y when
/// the winding says otherwise they are flipped towards +y).
pub fn floor_points(
    scene: &Scene,
    prefix: &str,
    nx: u32,
    nz: u32,
    margin: f32,
) -> Vec<SurfacePoint> {
    let mut out = Vec::new();
    for (mi, mesh) in scene.meshes.iter().enumerate() {
        if !mesh.name.starts_with(prefix) {
            continue;
        }
        let tris: Vec<[Vec3; 3]> = (0..mesh.indices.len()).map(|i| mesh.triangle(i)).collect();
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for t in &tris {
            for v in t {
                lo = lo.min(*v);
                hi = hi.max(*v);
            }
        }
        let ext = hi - lo;
        for iz in 0..nz {
            for ix in 0..nx {
                let fx = margin + (1.0 - 2.0 * margin) * (ix as f32 + 0.5) / nx as f32;
                let fz = margin + (1.0 - 2.0 * margin) * (iz as f32 + 0.5) / nz as f32;
                let (px, pz) = (lo.x + ext.x * fx, lo.z + ext.z * fz);
                // Drop the point straight down/up onto the triangle below it.
                for t in &tris {
                    if let Some(p) = vertical_hit(t, px, pz) {
                        let mut nrm = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
                        if nrm.y < 0.0 {
                            nrm = -nrm;
                        }
                        out.push(SurfacePoint {
                            position: p,
                            normal: nrm,
                            mesh: mi,
                        });
                        break;
                    }
                }
            }
        }
    }
    out
}

/// Where the vertical line through `(x, z)` meets triangle `t`, if it does.
fn vertical_hit(t: &[Vec3; 3], x: f32, z: f32) -> Option<Vec3> {
    let [a, b, c] = *t;
    let det = (b.x - a.x) * (c.z - a.z) - (c.x - a.x) * (b.z - a.z);
    if det.abs() < 1e-12 {
        return None;
    }
    let u = ((x - a.x) * (c.z - a.z) - (c.x - a.x) * (z - a.z)) / det;
    let v = ((b.x - a.x) * (z - a.z) - (x - a.x) * (b.z - a.z)) / det;
    if u < 0.0 || v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some(a + (b - a) * u + (c - a) * v)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::brdf::Lambert;
    use crate::emitter::CosN;
    use crate::scene::{Emission, Material};
    use std::f32::consts::PI;

    /// A unit-radiance diffuse square of side s at height h over the point
    /// below its centre: E = 4 L * (s/2)/sqrt(h^2+(s/2)^2) atan((s/2)/sqrt(...))
    /// summed over the 4 triangles of the square; the closed form of a
    /// square source on axis (view factor).
    #[test]
    fn quadrature_matches_the_view_factor_of_a_square() {
        let mut scene = Scene::new();
        let white = scene.add_material(Material {
            name: "w".into(),
            brdf: Lambert::new(Vec3::splat(0.5)).unwrap().into(),
            emission: Some(Emission::new(Vec3::ONE, CosN::new(0.0).unwrap())),
        });
        let (a, h) = (1.0f32, 2.0f32);
        let quad = vec![
            Vec3::new(-a, h, -a),
            Vec3::new(a, h, -a),
            Vec3::new(a, h, a),
            Vec3::new(-a, h, a),
        ];
        // Winding facing down (-y).
        scene
            .add_mesh("light", quad, vec![[0, 1, 2], [0, 2, 3]], white)
            .unwrap();
        let e = unshadowed_irradiance(&scene, Vec3::ZERO, Vec3::Y, 64);
        // Square of half-side a at distance h, on axis: E = 4 L [a/sqrt(a^2+h^2) atan(a/sqrt(a^2+h^2))]
        let q = (a * a + h * h).sqrt();
        let exact = 4.0 * (a / q) * (a / q).atan();
        assert!((e.x / exact - 1.0).abs() < 1e-3, "{} vs {exact}", e.x);
        // Facing up instead: nothing.
        assert!(unshadowed_irradiance(&scene, Vec3::ZERO, -Vec3::Y, 8).x == 0.0);
        let _ = PI;
    }
}
