//! Using adaptive-pm as a library: trace the built-in Cornell box in the
//! adaptive mode, build the photon map, and look up the photon density.
//!
//! `cargo run --release --example trace_cornell`

use adaptive_pm::embree::{thread_pool, Device};
use adaptive_pm::emitter::CosN;
use adaptive_pm::engine::measure::{DENSITY_POINTS, DENSITY_POINTS_SEED};
use adaptive_pm::engine::{map_metrics, Budget, Maps, Mode, TraceConfig, Tracer};
use adaptive_pm::scene::Scene;

fn main() -> Result<(), adaptive_pm::Error> {
    // A scene: the built-in box, or Scene::load("my_scene.glb").
    let mut scene = Scene::cornell()?;
    // Make the ceiling light directional: radiance cos^20(theta).
    scene.set_cosn(CosN::new(20.0)?);

    // Embree: a device, then the scene and its geometry owned together
    // (Send + Sync and 'static: a tracer can be stored and shared).
    let device = Device::new()?;
    let tracer = Tracer::new(scene.commit(&device)?);
    let scene = tracer.scene();

    // Tracing threads need flush-to-zero for Embree: use its thread pool.
    let pool = thread_pool(0)?;
    let config = TraceConfig::new(Mode::Adaptive, Budget::NMax(100_000));
    let run = pool.install(|| tracer.trace(&config))?;

    for (i, plan) in run.plans.iter().enumerate() {
        println!(
            "light {i}: {} photons (alpha_E {:.2}, alpha_A {:.2}, alpha_D {:.4})",
            plan.photons, plan.alpha_e, plan.alpha_a, plan.alpha_d
        );
    }
    println!(
        "stored {} photons, {} at their first hit; split rate by depth {:?}",
        run.report.stored, run.report.stored_primary, run.report.split_rate_by_depth
    );

    // The balanced kd-trees (all photons, primary only) and their densities.
    let maps = pool.install(|| Maps::from_photons(run.photons.clone(), run.frame));
    let mut nearest = Vec::new();
    let p = glam::Vec3::new(278.0, 0.0, 279.5); // middle of the floor
    maps.full.nearest_k(p, 50, f32::INFINITY, &mut nearest);
    println!(
        "50 nearest photons to the floor's centre within r = {:.2}",
        nearest.last().map_or(0.0, |n| n.dist2.sqrt())
    );
    let points = scene
        .surface_sampler()
        .points(DENSITY_POINTS, DENSITY_POINTS_SEED);
    let metrics = pool.install(|| map_metrics(&maps, &points));
    println!(
        "density: max {:.3e}, mean {:.3e}, sigma/mean {:.3}",
        metrics.full.max, metrics.full.mean, metrics.full.sigma_over_mean
    );
    Ok(())
}
