//! The part of a kernel's disc that its centre sees on its surface.
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
//! spaced, turned by a hash per estimate), the disc reaches
//! - as far as its centre sees along the plane ([`Sight`]: one ray per
//!   direction, lifted off the surface by the plane tolerance; between two
//!   rays, the nearer of the faces they hit, each taken as a line), and
//! - as far as a surface lies within the plane tolerance of the plane: a
//!   short ray down through the plane must hit there, the same test that
//!   admits a photon into the estimate. Where it does not at the disc's
//!   rim, the edge is found by bisection.
//!
//! The estimate admits a photon only within sight ([`Sight::admits`]), so
//! the share and the estimate cut the same disc. Without the sight, a floor
//! that runs on under a wall or a block lent its photons from the far
//! side: `door`'s lit room through the 15 cm partition into the camera's
//! room, and the empty floor under a block at the block's foot (-13 %
//! there). The sight ray runs at the plane tolerance's height, so on a
//! concave surface it stops about where the surface leaves the tolerance,
//! as the plane test does.
//!
//! The cone's weight is integrated exactly along each of [`SUB_ANGLES`]
//! angles per direction (`int_0^s (1 - rho) rho d rho`), so a straight
//! edge is read to within the angular sampling and the bisection.

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

/// How far a disc's centre sees along its tangent plane: a ray along each
/// of [`DIRECTIONS`] directions (the `j`-th at the angle
/// `TAU (j + rotation) / DIRECTIONS`), and between two neighbouring rays
/// the nearer of the faces they hit, each taken as a line. A straight wall
/// is then seen where it is across the whole wedge, not only along the
/// rays. Read at one ray's hit across its sector, a slanted wall's near
/// half took in an empty stretch past the wall (a floor under a
/// partition: the estimate read -4 %) or the next room's photons; read at
/// the least of neighbouring hits, a disc beside a wall lost a quarter of
/// its photons.
#[derive(Clone, Debug)]
pub struct Sight {
    frame: Frame,
    rotation: f32,
    /// Each ray's hit distance, infinite where it hit nothing in range.
    reach: [f32; DIRECTIONS as usize],
    /// The line of each ray's hit face in the tangent plane: its unit
    /// normal `(nx, ny)` facing the centre and the hit's offset along it
    /// (negative), so the line is `p . (nx, ny) = offset`; a zero normal
    /// where the ray hit nothing or the face lies flat.
    face: [(f32, f32, f32); DIRECTIONS as usize],
    /// Whether any ray hit: if none did, every photon within the range is
    /// in sight.
    blocked: bool,
    /// A distance within which every point of the plane is in sight: the
    /// nearest face's line (or hit) less a margin for rounding, 0 when a
    /// face is degenerate. Most of an estimate's photons lie within it,
    /// and [`Sight::admits`] takes them without an angle.
    clear: f32,
}

/// The sub-angles a sector's share integrates over (midpoints).
const SUB_ANGLES: u32 = 4;

impl Sight {
    /// What `x` (unit normal `n`) sees along its tangent plane out to
    /// `range`, from `tolerance` above the surface; `rotation` in `[0, 1)`
    /// turns the directions. Bad input gives an unobstructed sight.
    pub fn cast(
        rt: &dyn RayCaster,
        x: Vec3,
        n: Vec3,
        tolerance: f32,
        rotation: f32,
        range: f32,
    ) -> Self {
        let mut sight = Sight {
            rotation,
            ..Self::unobstructed(n)
        };
        let valid = tolerance > 0.0 && range > 0.0 && x.is_finite() && n.is_finite();
        if !valid || !tolerance.is_finite() {
            return sight;
        }
        let start = x + n * tolerance;
        for j in 0..DIRECTIONS {
            let ray = Ray {
                tfar: range,
                ..Ray::new(start, sight.direction(j))
            };
            if let Some(h) = rt.intersect(&ray) {
                // The face's normal in the plane, facing the centre.
                let facing = if h.ng.dot(ray.dir) > 0.0 { -h.ng } else { h.ng };
                let local = sight.frame.local_from_world(facing);
                let flat = local.x.hypot(local.y);
                sight.reach[j as usize] = h.t;
                sight.face[j as usize] = if flat > 0.0 {
                    let (nx, ny) = (local.x / flat, local.y / flat);
                    let (s, c) = sight.angle(j as f32).sin_cos();
                    (nx, ny, h.t * (c * nx + s * ny))
                } else {
                    (0.0, 0.0, 0.0)
                };
                sight.blocked = true;
            }
        }
        sight.clear = sight.clear_distance();
        sight
    }

    /// [`Sight::clear`]: no direction sees less than the least of the rays'
    /// bounds. A face's line at signed offset `at_hit < 0` is `|at_hit|`
    /// away at its nearest, and [`Sight::to_face`] divides by a cosine of at
    /// most 1 (a rounding above 1 is what the margin is for); a ray without a
    /// face line reads its hit distance. A face with `at_hit >= 0` (or
    /// NaN) can read less than any bound: then nothing is clear.
    fn clear_distance(&self) -> f32 {
        let mut clear = f32::INFINITY;
        for (&d, &(nx, ny, at_hit)) in self.reach.iter().zip(&self.face) {
            if !d.is_finite() {
                continue;
            }
            let bound = if nx == 0.0 && ny == 0.0 {
                d
            } else if at_hit < 0.0 {
                -at_hit
            } else {
                return 0.0;
            };
            clear = clear.min(bound);
        }
        clear * (1.0 - 1e-4)
    }

    /// A sight that nothing blocks, about the normal `n`.
    pub fn unobstructed(n: Vec3) -> Self {
        Sight {
            frame: Frame::from_normal(n),
            rotation: 0.0,
            reach: [f32::INFINITY; DIRECTIONS as usize],
            face: [(0.0, 0.0, 0.0); DIRECTIONS as usize],
            blocked: false,
            clear: f32::INFINITY,
        }
    }

    /// The angle of ray `j` in the tangent plane.
    fn angle(&self, j: f32) -> f32 {
        TAU * (j + self.rotation) / DIRECTIONS as f32
    }

    /// The unit direction of ray `j` in world space.
    fn direction(&self, j: u32) -> Vec3 {
        let (s, c) = self.angle(j as f32).sin_cos();
        self.frame.world_from_local(Vec3::new(c, s, 0.0))
    }

    /// How far the centre sees at the angle `phi` in the tangent plane:
    /// the nearest of the planes that the two rays around `phi` hit,
    /// each hit face taken as a line across the wedge. A straight wall is
    /// then exact across the wedge, and so is a room's corner (the nearer
    /// of its two walls); past a block's corner the side's line runs on and
    /// hides some floor that is in sight (a smaller disc, not a wrong one).
    /// Infinite where neither ray hit.
    fn seen_at(&self, phi: f32) -> f32 {
        let steps = (phi / TAU * DIRECTIONS as f32 - self.rotation).rem_euclid(DIRECTIONS as f32);
        let a = (steps.floor() as usize).min(DIRECTIONS as usize - 1);
        let b = (a + 1) % DIRECTIONS as usize;
        self.to_face(a, phi).min(self.to_face(b, phi))
    }

    /// The distance at the angle `phi` to the line of the face that ray
    /// `j` hit: infinite where it hit nothing or `phi` runs away from the
    /// face, its hit distance where the face's normal lies off the plane.
    fn to_face(&self, j: usize, phi: f32) -> f32 {
        let d = self.reach[j];
        let (nx, ny, at_hit) = self.face[j];
        if !d.is_finite() || (nx == 0.0 && ny == 0.0) {
            return d;
        }
        let (s, c) = phi.sin_cos();
        let toward = c * nx + s * ny;
        if toward < -1e-6 {
            at_hit / toward
        } else {
            f32::INFINITY
        }
    }

    /// Whether a photon at `offset` from the centre lies within sight
    /// (measured in the tangent plane).
    pub fn admits(&self, offset: Vec3) -> bool {
        if !self.blocked {
            return true;
        }
        let local = self.frame.local_from_world(offset);
        // Strictly within the clear distance (squared, so without the
        // hypot: the margin covers its rounding), in sight at any angle.
        if local.x * local.x + local.y * local.y < self.clear * self.clear {
            return true;
        }
        self.admits_by_angle(local)
    }

    /// [`Sight::admits`] of the offset whose tangent-plane coordinates are
    /// `local`, by its angle.
    fn admits_by_angle(&self, local: Vec3) -> bool {
        let along = local.x.hypot(local.y);
        along <= self.seen_at(local.y.atan2(local.x))
    }
}

/// The share, in `[LEAST_SHARE, 1]`, of the cone filter `w(d) = 1 - d / r`
/// over the disc of radius `r` about the centre `x` of `sight` that the
/// centre sees and that lies on a surface within `tolerance` of the disc's
/// plane. Each ray's sector is integrated over [`SUB_ANGLES`] sub-angles,
/// each read to what the centre sees there; where the surface ends short
/// of the sight along the ray, to that end.
pub fn kernel_share(rt: &dyn RayCaster, x: Vec3, sight: &Sight, r: f32, tolerance: f32) -> f32 {
    let n = sight.frame.n;
    if !(r > 0.0 && r.is_finite() && tolerance > 0.0 && x.is_finite() && n.is_finite()) {
        return 1.0;
    }
    let lift = n * tolerance;
    let mass: f32 = (0..DIRECTIONS)
        .map(|j| {
            let seen = r.min(sight.seen_at(sight.angle(j as f32)));
            let surface = reach(rt, x + lift, sight.direction(j), seen, lift);
            let ends = surface < seen;
            (0..SUB_ANGLES)
                .map(|q| {
                    let off = (q as f32 + 0.5) / SUB_ANGLES as f32 - 0.5;
                    let there = r.min(sight.seen_at(sight.angle(j as f32 + off)));
                    let out = if ends { there.min(surface) } else { there };
                    cone_mass(out / r)
                })
                .sum::<f32>()
                / SUB_ANGLES as f32
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
    /// holds (`x` along world X, `y` along world Z), by midpoint quadrature
    /// on a polar grid of `n` by `n`.
    fn share_where(n: usize, kept: impl Fn(f64, f64) -> bool) -> f64 {
        let mut sum = 0.0;
        for i in 0..n {
            let rho = (i as f64 + 0.5) / n as f64;
            for j in 0..n {
                let phi = std::f64::consts::TAU * (j as f64 + 0.5) / n as f64;
                if kept(rho * phi.cos(), rho * phi.sin()) {
                    sum += (1.0 - rho) * rho;
                }
            }
        }
        let cell = std::f64::consts::TAU / (n * n) as f64;
        sum * cell / (std::f64::consts::PI / 3.0)
    }

    /// The share at `x` with the sight cast out to `r`, and the sight.
    fn share(rt: &dyn RayCaster, x: Vec3, r: f32, tol: f32, rotation: f32) -> (f32, Sight) {
        let sight = Sight::cast(rt, x, Vec3::Y, tol, rotation, r);
        (kernel_share(rt, x, &sight, r, tol), sight)
    }

    /// Whether `sight` admits the point `(u, v)` of the unit disc of radius
    /// `r` on the floor.
    fn admits(sight: &Sight, r: f32, u: f64, v: f64) -> bool {
        sight.admits(Vec3::new(u as f32 * r, 0.0, v as f32 * r))
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

    /// At `x` on the floor, for 16 rotations of the directions, against the
    /// part of the disc where `kept` (the floor the centre sees, in unit
    /// disc coordinates):
    /// - the share is the cone's weight over what the estimate admits
    ///   there (the sight's sectors on the floor), within `each`: the two
    ///   cut the same disc;
    /// - where `walled` (the edge is a wall, not the floor's end), the
    ///   sight admits no part of the disc outside `kept` (under 0.005 of
    ///   the weight): no photon from past a wall;
    /// - it admits at least `least` of `kept`'s weight.
    fn assert_share_over_rotations(
        rt: &dyn RayCaster,
        x: Vec3,
        (r, tol, past_at_most): (f32, f32, f64),
        kept: impl Fn(f64, f64) -> bool,
        (each, least): (f64, f64),
    ) {
        let want = share_where(400, &kept);
        for k in 0..16 {
            let (s, sight) = share(rt, x, r, tol, k as f32 / 16.0);
            let admitted = share_where(400, |u, v| kept(u, v) && admits(&sight, r, u, v));
            let past = share_where(400, |u, v| !kept(u, v) && admits(&sight, r, u, v));
            let at = format!("at {x} rotation {k}: share {s}, admitted {admitted}");
            assert!((f64::from(s) - admitted).abs() < each, "{at}");
            assert!(past <= past_at_most, "{at}, past the wall {past}");
            assert!(admitted > least * want, "{at}, of {want}");
        }
    }

    /// The clear distance's shortcut admits what the angle does: sights
    /// cast from points of `door` and the Cornell box (beside walls,
    /// blocks, corners and the doorway), offsets at random and just inside
    /// and outside the clear distance.
    #[test]
    fn the_clear_distance_admits_what_the_angle_does() {
        let device = Device::new().unwrap();
        let mut rng = crate::rng::Rng::new(23);
        let mut shortcuts = 0;
        for name in ["door", "cornell"] {
            let scene = Scene::open(name).unwrap();
            let prepared = scene.clone().commit(&device).unwrap();
            let rt = prepared.caster();
            let (lo, hi) = scene.bounds();
            let tol = crate::render::cache::PLANE_TOLERANCE * (hi - lo).length();
            let range = crate::render::default_max_radius(&scene);
            for _ in 0..300 {
                // A point on the floor (y = lo.y), anywhere over it.
                let [u, v] = rng.next_2d();
                let x = Vec3::new(lo.x + u * (hi.x - lo.x), lo.y, lo.z + v * (hi.z - lo.z));
                let sight = Sight::cast(rt, x, Vec3::Y, tol, rng.next_f32(), range);
                if !sight.blocked {
                    continue;
                }
                for i in 0..400 {
                    let [a, b] = rng.next_2d();
                    let phi = TAU * a;
                    let rho = match i % 4 {
                        0 => range * b,
                        1 => sight.clear * (1.0 - 1e-6 * b),
                        2 => sight.clear * (1.0 + 1e-6 * b),
                        _ => sight.clear * 2.0 * b,
                    };
                    let local = Vec3::new(rho * phi.cos(), rho * phi.sin(), 0.0);
                    let offset = sight.frame.world_from_local(local);
                    let l = sight.frame.local_from_world(offset);
                    let slow = sight.admits_by_angle(l);
                    assert_eq!(sight.admits(offset), slow, "{name} at {x}, offset {offset}");
                    shortcuts += usize::from(l.x * l.x + l.y * l.y < sight.clear * sight.clear);
                }
            }
        }
        // The shortcut was taken, so the comparison is not of the slow path alone.
        assert!(shortcuts > 10_000, "{shortcuts} shortcuts");
    }

    #[test]
    fn a_disc_inside_the_floor_lies_on_it_whole() {
        let (prepared, tol, centre) = empty_box();
        for rotation in [0.0, 0.3, 0.9] {
            let (s, _) = share(prepared.caster(), centre, 50.0, tol, rotation);
            assert_eq!(s, 1.0);
        }
    }

    /// Beside a wall, at 0 to 0.8 radii from it: the share is what the
    /// sight admits (within 0.03), none of it past the wall, and at least
    /// 0.99 of the cut disc.
    #[test]
    fn beside_a_wall_the_share_is_the_admitted_part_of_the_cut_disc() {
        let (prepared, tol, centre) = empty_box();
        let rt = prepared.caster();
        let r = 60.0;
        let wall = to_wall(rt, centre, -Vec3::X, tol);
        for a in [0.0f32, 0.2, 0.5, 0.8] {
            // Just inside the floor at a = 0 (the plane tolerance off the wall).
            let d = (a * r).max(2.0 * tol);
            let x = centre - Vec3::X * (wall - d);
            let cut = f64::from(d / r);
            assert_share_over_rotations(rt, x, (r, tol, 0.005), |u, _| u > -cut, (0.03, 0.99));
        }
    }

    /// Beside the floor's open front edge (z = 0 in the empty box: no wall,
    /// the floor just ends), where only the rays down through the plane
    /// see the edge and bisection finds it: the share is the cut disc
    /// within 0.05 (its bisection runs along each sector's centre line).
    #[test]
    fn beside_an_open_edge_the_bisection_finds_the_cut() {
        let (prepared, tol, centre) = empty_box();
        let rt = prepared.caster();
        let r = 60.0;
        for a in [0.1f32, 0.3, 0.6] {
            let x = Vec3::new(centre.x, centre.y, a * r);
            let cut = f64::from(a);
            assert_share_over_rotations(rt, x, (r, tol, 1.0), |_, v| v > -cut, (0.05, 0.98));
        }
    }

    /// At a block's foot the floor runs on under the block, but the
    /// disc's centre does not see it, and the estimate admits no photon
    /// there: the block's side cuts the disc as a wall does. At 2
    /// tolerances from a side (a disc of radius 40, under the blocks'
    /// 165-wide faces), the share is what the sight admits on the open side
    /// of the side's plane (within 0.03), at least 0.95 of that side. Up to
    /// 0.03 of the weight may be admitted past the plane: where the face's
    /// end lies within the disc, the floor runs on round the block, in
    /// sight.
    #[test]
    fn a_blocks_side_cuts_the_disc_at_its_foot() {
        let scene = Scene::cornell().unwrap();
        let (lo, hi) = scene.bounds();
        let tol = super::super::PLANE_TOLERANCE * (hi - lo).length();
        let prepared = scene.commit(&Device::new().unwrap()).unwrap();
        let rt = prepared.caster();
        let r = 40.0;
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
            let facing = h.ng.dot(dir).abs();
            let x = from + dir * (h.t - 2.0 * tol / facing);
            let up = rt.intersect(&Ray::new(x + dir * 4.0 * tol + Vec3::Y * tol, Vec3::Y));
            if up.is_some_and(|u| u.t < 0.9 * (hi.y - lo.y)) {
                feet += 1;
                // The open side of the side's plane, in unit disc coordinates.
                let out = if h.ng.dot(dir) < 0.0 { h.ng } else { -h.ng };
                let (ox, oz) = (f64::from(out.x), f64::from(out.z));
                let cut = f64::from(2.0 * tol / r);
                let open = move |u: f64, v: f64| u * ox + v * oz > -cut;
                assert_share_over_rotations(rt, x, (r, tol, 0.03), open, (0.03, 0.95));
            }
        }
        assert!(feet > 0, "no block's foot found");
    }

    /// In a corner: the share is what the sight admits, none of it past
    /// either wall, and at least 0.99 of the quadrant's weight.
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
        let a = f64::from(d / r);
        let quadrant = |u: f64, v: f64| u > -a && v < a;
        assert_share_over_rotations(rt, corner, (r, tol, 0.005), quadrant, (0.03, 0.99));
    }

    /// Beside a wall, the sight at every angle within 60 degrees of the
    /// wall's normal is the wall's distance (the line through two rays' hits
    /// on it), within 1e-3 of it; away from it, at the box's far walls.
    #[test]
    fn the_sight_follows_a_straight_wall_between_rays() {
        let (prepared, tol, centre) = empty_box();
        let rt = prepared.caster();
        let wall = to_wall(rt, centre, -Vec3::X, tol);
        let d = 10.0;
        let x = centre - Vec3::X * (wall - d);
        for rotation in [0.0, 0.37] {
            let sight = Sight::cast(rt, x, Vec3::Y, tol, rotation, 1000.0);
            for k in 0..360 {
                let phi = (k as f32 + 0.5).to_radians();
                // The frame's local axes in world space, to find the angle's
                // world direction.
                let (s, c) = phi.sin_cos();
                let w = sight.frame.world_from_local(Vec3::new(c, s, 0.0));
                let toward = -w.x;
                let seen = sight.seen_at(phi);
                if toward > 0.5 {
                    let want = d / toward;
                    assert!((seen / want - 1.0).abs() < 1e-3, "{phi}: {seen} vs {want}");
                } else if toward < -0.5 {
                    assert!(seen > 200.0, "{phi}: {seen}");
                }
            }
        }
    }
}
