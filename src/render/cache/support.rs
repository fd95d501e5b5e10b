//! The part of a kernel's disc that lies on a surface photons can reach.
//!
//! A k-nearest estimate divides the photons' power by the disc's area. Where
//! the disc runs past the surface (a floor's end at a wall, a block's top
//! edge, a sphere curving away from its tangent plane), no photon the
//! estimate admits can lie in the part beyond, so the estimate reads low:
//! about `r / L` of the light of a surface of size `L`, which is the
//! image's mean bias that shrinks only as `r` does. This module measures,
//! by casting rays, the share of the cone filter's weight that falls where
//! such a photon could lie, so that the estimate divides by that part of
//! the disc only.
//!
//! Along each of [`DIRECTIONS`] directions in the tangent plane (evenly
//! spaced, turned by a hash per estimate), the disc reaches as far as a
//! surface lies within the plane tolerance of the plane: a short ray down
//! through the plane must hit there, the same test that admits a photon
//! into the estimate. Where it does not at the disc's rim, the edge is
//! found by bisection.
//!
//! The share does not ask whether the part is in sight of the disc's
//! centre. The estimate does not either: a floor that runs on under a wall
//! or a block lends its photons from the far side (`door`'s partition) and
//! its empty part under a block alike, and a share that left those parts
//! out read `door`'s dark room 2-5 % too bright, multiplying the leak
//! instead of the area. The foot of a wall standing on a floor keeps its
//! old bias.
//!
//! The cone's weight out to that reach is integrated exactly along each
//! direction (`int_0^s (1 - rho) rho d rho`), so a straight edge is read to
//! within the angular sampling and the bisection.

use crate::raycast::{Ray, RayCaster};
use crate::sampling::Frame;
use glam::Vec3;
use std::f32::consts::TAU;

/// Directions per disc: 16 rays where the disc lies whole on the surface.
pub const DIRECTIONS: u32 = 16;

/// Bisection steps towards an edge: the edge found to `1 / 64` of the
/// radius.
const BISECTIONS: u32 = 6;

/// The smallest share used: a disc reaching a surface over less than this
/// is read as this much, so a sliver never multiplies an estimate by more
/// than 10.
pub const LEAST_SHARE: f32 = 0.1;

/// The share, in `[LEAST_SHARE, 1]`, of the cone filter `w(d) = 1 - d / r`
/// over the disc of radius `r` about `x` (unit normal `n`) that lies on a
/// surface within `tolerance` of the disc's plane. `rotation` in `[0, 1)`
/// turns the directions.
pub fn kernel_share(
    rt: &dyn RayCaster,
    x: Vec3,
    n: Vec3,
    r: f32,
    tolerance: f32,
    rotation: f32,
) -> f32 {
    if !(r > 0.0 && r.is_finite() && tolerance > 0.0 && x.is_finite() && n.is_finite()) {
        return 1.0;
    }
    let frame = Frame::from_normal(n);
    let lift = n * tolerance;
    let mass: f32 = (0..DIRECTIONS)
        .map(|j| {
            let (s, c) = (TAU * (j as f32 + rotation) / DIRECTIONS as f32).sin_cos();
            let dir = frame.world_from_local(Vec3::new(c, s, 0.0));
            cone_mass(reach(rt, x + lift, dir, r, lift) / r)
        })
        .sum();
    (mass / (DIRECTIONS as f32 * cone_mass(1.0))).clamp(LEAST_SHARE, 1.0)
}

/// The cone filter's weight per unit angle out to `s` of the unit disc:
/// `int_0^s (1 - rho) rho d rho`.
fn cone_mass(s: f32) -> f32 {
    s * s * (0.5 - s / 3.0)
}

/// How far from `start` (lifted off the surface by `lift`) along the unit
/// `dir` the surface reaches, at most `r`.
fn reach(rt: &dyn RayCaster, start: Vec3, dir: Vec3, r: f32, lift: Vec3) -> f32 {
    let on_surface = |t: f32| {
        let down = Ray {
            tfar: 2.0,
            ..Ray::new(start + dir * t, -lift)
        };
        rt.occluded(&down)
    };
    if on_surface(r) {
        return r;
    }
    let (mut lo, mut hi) = (0.0, r);
    for _ in 0..BISECTIONS {
        let mid = 0.5 * (lo + hi);
        if on_surface(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::embree::Device;
    use crate::scene::Scene;

    /// The cone filter's share of the part of a unit disc where `kept(x, y)`
    /// holds, by midpoint quadrature on a polar grid.
    fn share_where(kept: impl Fn(f64, f64) -> bool) -> f64 {
        let (nr, na) = (1000, 1000);
        let mut sum = 0.0;
        for i in 0..nr {
            let rho = (i as f64 + 0.5) / nr as f64;
            for j in 0..na {
                let phi = std::f64::consts::TAU * (j as f64 + 0.5) / na as f64;
                if kept(rho * phi.cos(), rho * phi.sin()) {
                    sum += (1.0 - rho) * rho;
                }
            }
        }
        let cell = std::f64::consts::TAU / (nr * na) as f64;
        sum * cell / (std::f64::consts::PI / 3.0)
    }

    /// The empty Cornell box, the floor's tolerance, and the floor's centre.
    fn empty_box() -> (
        crate::scene::PreparedScene<crate::embree::CommittedScene>,
        f32,
        Vec3,
    ) {
        let scene = Scene::open("cornell-empty").unwrap();
        let (lo, hi) = scene.bounds();
        let tolerance = super::super::PLANE_TOLERANCE * (hi - lo).length();
        let prepared = scene.commit(&Device::new().unwrap()).unwrap();
        let centre = Vec3::new(0.5 * (lo.x + hi.x), lo.y, 0.5 * (lo.z + hi.z));
        (prepared, tolerance, centre)
    }

    /// The distance from `x` (on the floor) to the wall along `dir`.
    fn to_wall(rt: &dyn RayCaster, x: Vec3, dir: Vec3, lift: f32) -> f32 {
        rt.intersect(&Ray::new(x + Vec3::Y * lift, dir)).unwrap().t
    }

    /// The share at `x` on the floor (normal +Y) for 16 rotations: each
    /// within `each` of `want`, their mean within `mean`.
    fn assert_share_over_rotations(
        rt: &dyn RayCaster,
        x: Vec3,
        r: f32,
        tol: f32,
        want: f32,
        (each, mean): (f32, f32),
        a: f32,
    ) {
        let shares: Vec<f32> = (0..16)
            .map(|k| kernel_share(rt, x, Vec3::Y, r, tol, k as f32 / 16.0))
            .collect();
        for s in &shares {
            assert!((s - want).abs() < each, "a {a}: {s} vs {want}");
        }
        let m = shares.iter().sum::<f32>() / 16.0;
        assert!((m - want).abs() < mean, "a {a}: mean {m} vs {want}");
    }

    #[test]
    fn a_disc_inside_the_floor_lies_on_it_whole() {
        let (prepared, tol, centre) = empty_box();
        for rotation in [0.0, 0.3, 0.9] {
            let s = kernel_share(prepared.caster(), centre, Vec3::Y, 50.0, tol, rotation);
            assert_eq!(s, 1.0);
        }
    }

    /// Beside a wall the share matches the quadrature within 0.04 for each
    /// rotation, and within 0.01 over 16 rotations.
    #[test]
    fn beside_a_wall_the_share_is_the_cut_discs() {
        let (prepared, tol, centre) = empty_box();
        let rt = prepared.caster();
        let r = 60.0;
        let wall = to_wall(rt, centre, -Vec3::X, tol);
        for a in [0.0f32, 0.2, 0.5, 0.8] {
            // Just inside the floor at a = 0 (the plane tolerance off the wall).
            let d = (a * r).max(2.0 * tol);
            let x = centre - Vec3::X * (wall - d);
            let want = share_where(|x, _| x > -(d / r) as f64) as f32;
            assert_share_over_rotations(rt, x, r, tol, want, (0.04, 0.01), a);
        }
    }

    /// Beside the floor's open front edge (z = 0 in the empty box: no wall,
    /// the floor just ends), where only the rays down through the plane
    /// see the edge and bisection finds it: the same cut disc, within
    /// 0.05 for each rotation and 0.015 over 16.
    #[test]
    fn beside_an_open_edge_the_bisection_finds_the_cut() {
        let (prepared, tol, centre) = empty_box();
        let rt = prepared.caster();
        let r = 60.0;
        for a in [0.1f32, 0.3, 0.6] {
            let x = Vec3::new(centre.x, centre.y, a * r);
            let want = share_where(|x, _| x > -f64::from(a)) as f32;
            assert_share_over_rotations(rt, x, r, tol, want, (0.05, 0.015), a);
        }
    }

    /// At a block's foot the floor runs on under the block, and the
    /// estimate admits photons there: the share keeps that part (a share
    /// that left it out multiplied `door`'s leak through its partition).
    #[test]
    fn a_floor_running_under_a_block_is_kept() {
        let scene = Scene::cornell().unwrap();
        let (lo, hi) = scene.bounds();
        let tol = super::super::PLANE_TOLERANCE * (hi - lo).length();
        let prepared = scene.commit(&Device::new().unwrap()).unwrap();
        let rt = prepared.caster();
        let mut feet = 0;
        for i in 0..16 {
            let a = i as f32 * std::f32::consts::PI / 8.0;
            let dir = Vec3::new(a.cos(), 0.0, a.sin());
            let from = Vec3::new(0.5 * (lo.x + hi.x), lo.y, 0.5 * (lo.z + hi.z));
            let Some(h) = rt.intersect(&Ray::new(from + Vec3::Y * tol, dir)) else {
                continue;
            };
            // A block's side, not a wall: nearer the centre than the walls
            // (about 278 away), and its top, not the ceiling, over the floor
            // beyond it.
            if h.t > 0.4 * (hi.x - lo.x) {
                continue;
            }
            let x = from + dir * (h.t - 2.0 * tol);
            let up = rt.intersect(&Ray::new(x + dir * 4.0 * tol + Vec3::Y * tol, Vec3::Y));
            if up.is_some_and(|u| u.t < 0.9 * (hi.y - lo.y)) {
                feet += 1;
                let s = kernel_share(rt, x, Vec3::Y, 40.0, tol, 0.0);
                assert_eq!(s, 1.0, "at a foot {x}");
            }
        }
        assert!(feet > 0, "no block's foot found");
    }

    /// In a corner, a little more than a quarter of the disc.
    #[test]
    fn a_corner_keeps_its_quadrant() {
        let (prepared, tol, centre) = empty_box();
        let rt = prepared.caster();
        let (wx, wz) = (
            to_wall(rt, centre, -Vec3::X, tol),
            to_wall(rt, centre, Vec3::Z, tol),
        );
        let (r, d) = (60.0, 2.0 * tol);
        let corner = centre + Vec3::new(d - wx, 0.0, wz - d);
        let mean = (0..16)
            .map(|k| kernel_share(rt, corner, Vec3::Y, r, tol, k as f32 / 16.0))
            .sum::<f32>()
            / 16.0;
        let a = f64::from(d / r);
        let want = share_where(|x, y| x > -a && y > -a) as f32;
        assert!((mean - want).abs() < 0.01, "corner: {mean} vs {want}");
    }
}
