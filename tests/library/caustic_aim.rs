//! The caustic pass's direction sampler (`engine::caustic_aim`) against
//! its pdf: the cone mixture integrates to 1, its samples over their pdf
//! measure each cone's solid angle (overlaps included), and a one-sided
//! emitter does not aim behind itself. Sigmas from the samples themselves.

use adaptive_pm::engine::caustic_aim::{CausticAim, Target};
use adaptive_pm::rng::Rng;
use glam::Vec3;
use std::f32::consts::PI;

use crate::common::{self, assert_sigmas, MeanVar};

/// The mixture over three cones (one holding the point: every direction)
/// integrates to 1 over the sphere (checked by uniform directions), and
/// its samples weighted by 1/pdf measure each cone's solid angle
/// `2 pi (1 - cos)`, overlaps included.
#[test]
fn the_cone_mixture_matches_its_pdf() {
    let targets = vec![
        Target {
            centre: Vec3::new(0.0, 0.0, 3.0),
            radius: 1.0,
            mesh: 0,
        },
        Target {
            centre: Vec3::new(0.8, 0.0, 3.0),
            radius: 0.7,
            mesh: 1,
        },
        Target {
            centre: Vec3::new(0.0, -4.0, 0.5),
            radius: 0.3,
            mesh: 2,
        },
    ];
    let x = Vec3::new(0.1, 0.2, 0.0);
    let aim = CausticAim::from_targets(targets.clone());
    let mut rng = Rng::new(common::seed(7));
    let n = 400_000;
    let mut norm = MeanVar::default();
    for _ in 0..n {
        let z = 1.0 - 2.0 * rng.next_f32();
        let w = adaptive_pm::sampling::spherical_direction(z, 2.0 * PI * rng.next_f32());
        norm.push(4.0 * PI as f64 * aim.pdf(x, None, w) as f64);
    }
    assert_sigmas(
        "pdf integrates to 1",
        norm.mean() - 1.0,
        norm.std_error(),
        4.5,
    );
    let cones: Vec<_> = targets
        .iter()
        .map(|t| t.cone_from(x, None).unwrap())
        .collect();
    let mut solid = vec![MeanVar::default(); cones.len()];
    for _ in 0..n {
        let d = aim.sample(x, None, rng.next_f32(), rng.next_2d()).unwrap();
        let pdf = aim.pdf(x, None, d.direction);
        assert!((pdf - d.pdf).abs() <= 1e-6 * pdf, "{pdf} vs {}", d.pdf);
        for (m, c) in solid.iter_mut().zip(&cones) {
            m.push(if c.contains(d.direction) {
                1.0 / d.pdf as f64
            } else {
                0.0
            });
        }
    }
    for (j, (m, t)) in solid.iter().zip(&targets).enumerate() {
        let d = (t.centre - x).length() as f64;
        let exact =
            2.0 * std::f64::consts::PI * (1.0 - (1.0 - (t.radius as f64 / d).powi(2)).sqrt());
        assert_sigmas(
            &format!("cone {j} solid angle"),
            m.mean() - exact,
            m.std_error(),
            4.5,
        );
    }
    // A one-sided emitter facing away from the third sphere (wholly below
    // its plane) does not aim at it.
    let facing = Some(Vec3::Y);
    for _ in 0..1000 {
        let d = aim
            .sample(x, facing, rng.next_f32(), rng.next_2d())
            .unwrap();
        assert!(!cones[2].contains(d.direction) || cones[0].contains(d.direction));
    }
}
