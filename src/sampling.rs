//! Shared geometry of sampling: local shading frames, hemisphere and triangle
//! warps, and their pdfs. Samplers take their random numbers as arguments
//! (`u: [f32; 2]`) so tests can drive them with fixed numbers.
//!
//! Convention: in a local frame the surface normal is +z; a direction `w` is a
//! unit vector pointing *away* from the surface.

use glam::Vec3;
use std::f32::consts::{FRAC_1_PI, PI};

/// An orthonormal frame around a normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// First tangent.
    pub s: Vec3,
    /// Second tangent.
    pub t: Vec3,
    /// The normal (local +z).
    pub n: Vec3,
}

impl Frame {
    /// A frame whose z axis is the unit vector `n` (Duff et al. 2017, branchless).
    pub fn from_normal(n: Vec3) -> Self {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Frame { s, t, n }
    }

    /// World direction to local coordinates.
    #[inline]
    pub fn local_from_world(&self, w: Vec3) -> Vec3 {
        Vec3::new(w.dot(self.s), w.dot(self.t), w.dot(self.n))
    }

    /// Local direction to world coordinates.
    #[inline]
    pub fn world_from_local(&self, l: Vec3) -> Vec3 {
        self.s * l.x + self.t * l.y + self.n * l.z
    }
}

/// Direction from spherical coordinates (theta from +z, phi from +x).
#[inline]
pub fn spherical_direction(cos_theta: f32, phi: f32) -> Vec3 {
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), cos_theta)
}

/// Azimuth of a local direction in [0, 2 pi).
#[inline]
pub fn phi_of(w: Vec3) -> f32 {
    let p = w.y.atan2(w.x);
    if p < 0.0 {
        p + 2.0 * PI
    } else {
        p
    }
}

/// Cosine-weighted hemisphere: pdf `cos(theta) / pi` (solid angle).
#[inline]
pub fn cosine_hemisphere(u: [f32; 2]) -> Vec3 {
    let cos_theta = (1.0 - u[0]).max(0.0).sqrt();
    spherical_direction(cos_theta, 2.0 * PI * u[1])
}

/// Pdf (solid angle) of [`cosine_hemisphere`].
#[inline]
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * FRAC_1_PI
}

/// Uniform hemisphere: pdf `1 / (2 pi)`.
#[inline]
pub fn uniform_hemisphere(u: [f32; 2]) -> Vec3 {
    spherical_direction(1.0 - u[0], 2.0 * PI * u[1])
}

/// Power-cosine hemisphere: pdf `(e + 1) / (2 pi) cos^e(theta)`, e >= 0.
///
/// Written with `u^(1/(e+1))`, which stays finite for any exponent: at e = 1e6
/// every sample is within a few milliradians of the axis, as it should be.
#[inline]
pub fn cos_power_hemisphere(e: f32, u: [f32; 2]) -> Vec3 {
    // 1 - u[0] is in (0, 1], so the power never sees 0 with a negative exponent.
    // e = 1 (a diffuse emitter) is a square root, which costs a fraction of
    // `powf`; every photon of a diffuse light is sampled here.
    let cos_theta = if e == 1.0 {
        (1.0 - u[0]).sqrt()
    } else {
        (1.0 - u[0]).powf(1.0 / (e + 1.0)).clamp(0.0, 1.0)
    };
    spherical_direction(cos_theta, 2.0 * PI * u[1])
}

/// Pdf (solid angle) of [`cos_power_hemisphere`].
#[inline]
pub fn cos_power_hemisphere_pdf(e: f32, cos_theta: f32) -> f32 {
    if cos_theta <= 0.0 {
        return 0.0;
    }
    (e + 1.0) * 0.5 * FRAC_1_PI * cos_theta.powf(e)
}

/// Uniform point on a triangle as barycentrics `(b0, b1)` (the third is `1 - b0 - b1`).
#[inline]
pub fn uniform_triangle(u: [f32; 2]) -> (f32, f32) {
    let su = u[0].sqrt();
    (1.0 - su, u[1] * su)
}

/// Uniform point on the unit disc, `(x, y)`, by Shirley and Chiu's
/// concentric map: it keeps strata of `u` compact on the disc, where the
/// polar map `(sqrt(u0), 2 pi u1)` stretches them into slivers.
#[inline]
pub fn concentric_disc(u: [f32; 2]) -> (f32, f32) {
    let (a, b) = (2.0 * u[0] - 1.0, 2.0 * u[1] - 1.0);
    if a == 0.0 && b == 0.0 {
        return (0.0, 0.0);
    }
    let (r, theta) = if a.abs() > b.abs() {
        (a, std::f32::consts::FRAC_PI_4 * (b / a))
    } else {
        (
            b,
            std::f32::consts::FRAC_PI_2 - std::f32::consts::FRAC_PI_4 * (a / b),
        )
    };
    (r * theta.cos(), r * theta.sin())
}

/// Rec. 709 luminance weights of linear RGB: the one copy, for
/// [`luminance`] and [`luminance_f64`].
pub const LUMINANCE_WEIGHTS: [f64; 3] = [0.2126, 0.7152, 0.0722];

/// Rec. 709 luminance of linear RGB.
#[inline]
pub fn luminance(rgb: Vec3) -> f32 {
    // Each weight rounded to f32 is the f32 nearest its decimal: the same
    // constants as written in f32.
    const W: [f32; 3] = [
        LUMINANCE_WEIGHTS[0] as f32,
        LUMINANCE_WEIGHTS[1] as f32,
        LUMINANCE_WEIGHTS[2] as f32,
    ];
    W[0] * rgb.x + W[1] * rgb.y + W[2] * rgb.z
}

/// [`luminance`] in f64, for sums of power kept in f64.
#[inline]
pub fn luminance_f64(rgb: [f64; 3]) -> f64 {
    let w = LUMINANCE_WEIGHTS;
    w[0] * rgb[0] + w[1] * rgb[1] + w[2] * rgb[2]
}

/// Perfect mirror of `w` about +z in a local frame.
#[inline]
pub fn reflect_z(w: Vec3) -> Vec3 {
    Vec3::new(-w.x, -w.y, w.z)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_is_orthonormal_for_any_normal() {
        for n in [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(0.3, -0.4, 0.866).normalize(),
            Vec3::new(1e-8, 0.0, -1.0).normalize(),
        ] {
            let f = Frame::from_normal(n);
            assert!((f.s.length() - 1.0).abs() < 1e-5);
            assert!((f.t.length() - 1.0).abs() < 1e-5);
            assert!(
                f.s.dot(f.t).abs() < 1e-5 && f.s.dot(n).abs() < 1e-5 && f.t.dot(n).abs() < 1e-5
            );
            let w = Vec3::new(0.2, 0.5, 0.3).normalize();
            assert!((f.local_from_world(f.world_from_local(w)) - w).length() < 1e-5);
        }
    }

    #[test]
    fn the_concentric_disc_map_is_uniform_and_stays_inside() {
        // A stratified grid: every quarter of the disc, by radius and by
        // angle, gets its share of the points to within the grid's step.
        let m = 200;
        let (mut inner, mut upper, mut right) = (0, 0, 0);
        for i in 0..m {
            for j in 0..m {
                let u = [(i as f32 + 0.5) / m as f32, (j as f32 + 0.5) / m as f32];
                let (x, y) = concentric_disc(u);
                let r2 = x * x + y * y;
                assert!(r2 <= 1.0 + 1e-6, "{u:?} -> ({x}, {y})");
                inner += usize::from(r2 < 0.5);
                upper += usize::from(y > 0.0);
                right += usize::from(x > 0.0);
            }
        }
        for (what, count) in [("r^2 < 1/2", inner), ("y > 0", upper), ("x > 0", right)] {
            let share = count as f64 / (m * m) as f64;
            assert!((share - 0.5).abs() < 0.01, "{what}: {share}");
        }
        assert_eq!(concentric_disc([0.5, 0.5]), (0.0, 0.0));
    }

    #[test]
    fn luminance_weights_are_the_rec709_decimals_in_both_precisions() {
        assert_eq!(luminance(Vec3::X), 0.2126f32);
        assert_eq!(luminance(Vec3::Y), 0.7152f32);
        assert_eq!(luminance(Vec3::Z), 0.0722f32);
        assert_eq!(luminance_f64([1.0, 1.0, 1.0]), 0.2126 + 0.7152 + 0.0722);
    }

    #[test]
    fn cos_power_is_finite_at_huge_exponents() {
        for e in [0.0, 1.0, 1e4, 1e6] {
            for u in [[0.0, 0.0], [0.999_999, 0.5], [0.5, 0.999]] {
                let w = cos_power_hemisphere(e, u);
                assert!(w.is_finite() && w.z >= 0.0 && (w.length() - 1.0).abs() < 1e-4);
            }
        }
    }
}
