//! Step 4: the solid angle of a peak from the extreme spherical coordinates
//! of its samples (paper §2.1.4; docs/method.md, "Step 4: solid angles of the
//! peaks"):
//! `omega = arc(phi) * (cos theta_min - cos theta_max)`.
//!
//! `arc(phi)` is the shortest arc covering the azimuths, `2 pi` minus their
//! largest circular gap; when that gap is under pi the samples surround the
//! normal and the arc is `2 pi`. The theta range always comes from the
//! samples. `1 - cos theta` is computed as `(x^2 + y^2) / (1 + z)`, exact for
//! the tiny lobes of exponents near 1e6 where `z` itself has lost its digits
//! (and as `1 - z` below the horizon, for a transmission lobe).

use crate::sampling::phi_of;
use glam::Vec3;
use std::f32::consts::PI;

/// The shortest arc covering a set of azimuths in [0, 2 pi), 2 pi when the
/// largest gap is under pi; 0 for fewer than two azimuths.
pub fn azimuth_arc(phis: &mut [f32]) -> f32 {
    if phis.len() < 2 {
        return 0.0;
    }
    // Unstable is the same order: values equal under `total_cmp` have the
    // same bits. It sorts without the stable sort's scratch allocation.
    phis.sort_unstable_by(f32::total_cmp);
    let mut gap = phis[0] + 2.0 * PI - phis[phis.len() - 1];
    for w in phis.windows(2) {
        gap = gap.max(w[1] - w[0]);
    }
    if gap < PI {
        2.0 * PI
    } else {
        (2.0 * PI - gap).max(0.0)
    }
}

/// Solid angle (sr) of the box of extreme spherical coordinates of `dirs`.
pub fn solid_angle(dirs: &[Vec3]) -> f32 {
    let mut phis: Vec<f32> = dirs.iter().map(|&d| phi_of(d)).collect();
    solid_angle_at(dirs, &mut phis)
}

/// [`solid_angle`] with the azimuths `phis[i] = phi_of(dirs[i])` given
/// (reordered: they are sorted in place).
pub fn solid_angle_at(dirs: &[Vec3], phis: &mut [f32]) -> f32 {
    if dirs.is_empty() {
        return 0.0;
    }
    let mut vmin = f32::INFINITY;
    let mut vmax = 0.0f32;
    for d in dirs {
        // Below the horizon (a transmission lobe) 1 - z loses nothing.
        let versine = if d.z >= 0.0 {
            (d.x * d.x + d.y * d.y) / (1.0 + d.z)
        } else {
            1.0 - d.z
        };
        vmin = vmin.min(versine);
        vmax = vmax.max(versine);
    }
    azimuth_arc(phis) * (vmax - vmin).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::spherical_direction;

    #[test]
    fn arc_rules() {
        assert_eq!(azimuth_arc(&mut [1.0]), 0.0);
        assert!((azimuth_arc(&mut [0.1, 0.5]) - 0.4).abs() < 1e-6);
        // across the 0 / 2 pi seam: shortest arc is 0.3
        assert!((azimuth_arc(&mut [6.2, 0.2]) - (0.2 + 2.0 * PI - 6.2)).abs() < 1e-5);
        // surrounding the normal: every gap < pi
        assert_eq!(azimuth_arc(&mut [0.0, 2.0, 4.0]), 2.0 * PI);
    }

    #[test]
    fn cap_around_normal() {
        // a full ring of samples at theta = 0.3 plus the pole: a cap of
        // 2 pi (1 - cos 0.3)
        let mut d: Vec<Vec3> = (0..12)
            .map(|k| spherical_direction(0.3f32.cos(), k as f32 * 0.5))
            .collect();
        d.push(Vec3::Z);
        let want = 2.0 * PI * (1.0 - 0.3f32.cos());
        assert!((solid_angle(&d) - want).abs() < 1e-4 * want.max(1.0));
    }
}
