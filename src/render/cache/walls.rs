//! Cells that a wall crosses: a cell is a cube keyed by where its samples
//! lie, so a wall thinner than the cube (`door`'s 15 cm partition under a
//! coarse cell, any thin wall under a fine one) puts points of both rooms
//! in one cell. The cell's value is read on its *representative's* side
//! only:
//! - at build, a cell whose representative point sees a face inside its
//!   cube along its tangent plane, or does not see one of the members it
//!   would average, is *walled*: it averages only the members its
//!   representative sees, and keeps the representative's position
//!   (quantised in the cube, 10 bits an axis) in a second slot;
//! - a lookup that reads a walled cell casts one segment from its point to
//!   that position, and reads the cell only if nothing blocks it; else it
//!   goes on as on an empty cell (a coarser level, then the k-nearest
//!   estimate).
//!
//! A cell no wall crosses costs a lookup nothing more. What is left: a
//! wall that clips only a corner of a cube between the rays of
//! [`crossed`] is not seen, and a lookup behind it reads the cell.

use crate::raycast::{Ray, RayCaster};
use crate::sampling::Frame;
use glam::Vec3;
use std::f32::consts::TAU;

/// In-plane rays of [`crossed`].
const DIRECTIONS: u32 = 16;

/// Quantisation steps of a representative's position per axis of its cube.
const STEPS: f32 = 1024.0;

/// Whether `p` (unit normal `n`), lifted `lift` above its surface, sees a
/// face along its tangent plane before leaving the cube of corner `lo` and
/// side `side`, with surface along the plane behind it, inside the cube
/// ([`surface_below`]): 16 rays, each stopped at the cube's boundary, and behind a hit
/// [`PROBES`] short rays down through the plane. A box's outer wall, with
/// nothing behind it, does not wall a cell: no lookup comes from there.
pub(super) fn crossed(
    rt: &dyn RayCaster,
    (p, n): (Vec3, Vec3),
    lift: f32,
    lo: Vec3,
    side: f32,
) -> bool {
    let frame = Frame::from_normal(n);
    let start = p + n * lift;
    (0..DIRECTIONS).any(|j| {
        let (s, c) = (TAU * (j as f32 + 0.5) / DIRECTIONS as f32).sin_cos();
        let dir = frame.world_from_local(Vec3::new(c, s, 0.0));
        let exit = exit_distance(start, dir, lo, lo + Vec3::splat(side));
        let ray = Ray {
            tfar: exit,
            ..Ray::new(start, dir)
        };
        let Some(hit) = (exit > 0.0).then(|| rt.intersect(&ray)).flatten() else {
            return false;
        };
        (0..PROBES).any(|k| {
            let t = hit.t + (exit - hit.t) * (k as f32 + 0.5) / PROBES as f32;
            surface_below(rt, start + dir * t, n, lift)
        })
    })
}

/// Points behind a wall, inside the cube, where [`crossed`] looks for a
/// surface.
const PROBES: u32 = 3;

/// Whether a surface along the plane (its normal within 60 degrees of `n`,
/// either way) lies within `lift` of the plane under `q` (`q` at `lift`
/// above it).
fn surface_below(rt: &dyn RayCaster, q: Vec3, n: Vec3, lift: f32) -> bool {
    let ray = Ray {
        tfar: 2.0 * lift,
        ..Ray::new(q, -n)
    };
    rt.intersect(&ray).is_some_and(|h| h.ng.dot(n).abs() > 0.5)
}

/// Distance along the unit `dir` from `start` to where the ray leaves the
/// box `[lo, hi]` (0 when it starts outside it on an axis it leaves by).
fn exit_distance(start: Vec3, dir: Vec3, lo: Vec3, hi: Vec3) -> f32 {
    let axis = |s: f32, d: f32, l: f32, h: f32| {
        if d > 0.0 {
            (h - s) / d
        } else if d < 0.0 {
            (l - s) / d
        } else {
            f32::INFINITY
        }
    };
    axis(start.x, dir.x, lo.x, hi.x)
        .min(axis(start.y, dir.y, lo.y, hi.y))
        .min(axis(start.z, dir.z, lo.z, hi.z))
        .max(0.0)
}

/// Whether `x` (unit normal `n`) sees `p`, both lifted `lift` along `n`:
/// the segment between them, stopped just short of either end.
pub(super) fn sees(rt: &dyn RayCaster, x: Vec3, n: Vec3, p: Vec3, lift: f32) -> bool {
    let (a, b) = (x + n * lift, p + n * lift);
    if !(a.is_finite() && b.is_finite()) || a == b {
        return true;
    }
    !rt.occluded(&Ray::segment(a, b, 1e-4))
}

/// `p`'s position in the cube of corner `lo` and side `side`, 10 bits an
/// axis (clamped into the cube).
pub(super) fn encode(p: Vec3, lo: Vec3, side: f32) -> u32 {
    let f = (p - lo) / side * STEPS;
    let q = |v: f32| (v.clamp(0.0, STEPS - 1.0) as u32) & 1023;
    q(f.x) | (q(f.y) << 10) | (q(f.z) << 20)
}

/// The centre of the step [`encode`] put a position in.
pub(super) fn decode(code: u32, lo: Vec3, side: f32) -> Vec3 {
    let c = |s: u32| (((code >> s) & 1023) as f32 + 0.5) / STEPS;
    lo + Vec3::new(c(0), c(10), c(20)) * side
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::embree::{CommittedScene, Device};
    use crate::scene::{PreparedScene, Scene, BUILTIN_DOOR};

    /// `name` committed, and its plane tolerance.
    fn prepared(name: &str) -> (PreparedScene<CommittedScene>, f32) {
        let scene = Scene::open(name).unwrap();
        let (lo, hi) = scene.bounds();
        let lift = super::super::PLANE_TOLERANCE * (hi - lo).length();
        (scene.commit(&Device::new().unwrap()).unwrap(), lift)
    }

    /// `door`'s floor runs on under its 15 cm partition (x 400 to 415): a
    /// cube across it is walled from either room, and a point sees its own
    /// room's floor but not the next room's.
    #[test]
    fn a_partition_walls_the_cells_across_it() {
        let (door, lift) = prepared(BUILTIN_DOOR);
        let rt = door.caster();
        let (a, b) = (Vec3::new(390.0, 0.0, 60.0), Vec3::new(425.0, 0.0, 70.0));
        let lo = Vec3::new(380.0, -20.0, 40.0);
        for p in [a, b] {
            assert!(crossed(rt, (p, Vec3::Y), lift, lo, 60.0), "from {p}");
        }
        // A cube inside room A, away from the partition.
        let inside = Vec3::new(300.0, -20.0, 40.0);
        assert!(!crossed(
            rt,
            (Vec3::new(330.0, 0.0, 70.0), Vec3::Y),
            lift,
            inside,
            60.0
        ));
        assert!(!sees(rt, a, Vec3::Y, b, lift));
        assert!(sees(rt, a, Vec3::Y, Vec3::new(310.0, 0.0, 90.0), lift));
    }

    /// The Cornell box's floor ends at its walls: a cell at a wall, its
    /// cube running past the wall into the void, is not walled, and nor is
    /// one in the open floor; one across a block's corner is, the floor
    /// running on under the block.
    #[test]
    fn an_outer_wall_does_not_wall_a_cell_and_a_block_does() {
        let (empty, lift) = prepared("cornell-empty");
        let rt = empty.caster();
        let at_wall = Vec3::new(5.0, 0.0, 300.0);
        assert!(!crossed(
            rt,
            (at_wall, Vec3::Y),
            lift,
            Vec3::new(-20.0, -20.0, 280.0),
            50.0
        ));
        let open = Vec3::new(280.0, 0.0, 280.0);
        assert!(!crossed(
            rt,
            (open, Vec3::Y),
            lift,
            Vec3::new(260.0, -20.0, 260.0),
            50.0
        ));
        let (cornell, lift) = prepared("cornell");
        let rt = cornell.caster();
        // The short block's corner nearest the open side is at (130, 65);
        // its sides run to (290, 114) and (82, 225).
        let cube = Vec3::new(105.0, -20.0, 40.0);
        for p in [Vec3::new(115.0, 0.0, 45.0), Vec3::new(145.0, 0.0, 45.0)] {
            assert!(crossed(rt, (p, Vec3::Y), lift, cube, 50.0), "from {p}");
        }
    }

    #[test]
    fn a_position_comes_back_within_half_a_step() {
        let mut r = crate::rng::Rng::new(3);
        let (lo, side) = (Vec3::new(-3.0, 10.0, 250.0), 7.5);
        for _ in 0..10_000 {
            let u = Vec3::new(r.next_f32(), r.next_f32(), r.next_f32());
            let p = lo + u * side;
            let back = decode(encode(p, lo, side), lo, side);
            let err = (back - p).abs().max_element();
            assert!(err <= 0.5 * side / STEPS * 1.001, "{p} -> {back}");
        }
        // Outside the cube: clamped to its boundary steps.
        let far = decode(encode(lo + Vec3::splat(2.0 * side), lo, side), lo, side);
        assert!((far - (lo + Vec3::splat(side))).abs().max_element() < side / STEPS);
    }

    #[test]
    fn the_exit_is_where_the_ray_leaves_the_box() {
        let (lo, hi) = (Vec3::ZERO, Vec3::splat(2.0));
        let start = Vec3::new(0.5, 1.0, 1.0);
        assert!((exit_distance(start, Vec3::X, lo, hi) - 1.5).abs() < 1e-6);
        assert!((exit_distance(start, -Vec3::X, lo, hi) - 0.5).abs() < 1e-6);
        let d = Vec3::new(1.0, 1.0, 0.0).normalize();
        assert!((exit_distance(start, d, lo, hi) - 2f32.sqrt()).abs() < 1e-5);
        assert_eq!(exit_distance(Vec3::splat(3.0), Vec3::X, lo, hi), 0.0);
    }
}
