//! The gather's rays spread by variance against the uniform gather
//! (docs/rendering.md, "Gather rays where the variance is"): one photon map
//! per scene, two renders of other seeds per allocation, and each
//! allocation's noise, `rmse(A, B) / sqrt(2) / mean` (one image's relative
//! rms noise, the emitters hidden), with the renders' times. Prints a
//! Markdown table.
//!
//! `cargo run --release --example gather_allocation -- N_MAX SIDE SPP SCENE...`
//! (for example `100000 256 32 cornell cornell-glass`)

use adaptive_pm::embree::Device;
use adaptive_pm::engine::{Budget, Mode, TraceConfig, Tracer};
use adaptive_pm::render::{render_with, rmse, GatherAllocation, Image, RenderConfig};
use adaptive_pm::scene::Scene;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [n_max, side, spp, scenes @ ..] = args.as_slice() else {
        return Err("usage: gather_allocation N_MAX SIDE SPP SCENE...".into());
    };
    let (n_max, side, spp): (u64, u32, u32) = (n_max.parse()?, side.parse()?, spp.parse()?);
    println!("| scene | N_MAX | pixels | spp | allocation | noise | variance / uniform | render s (two) | pilot s | mean gather |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for name in scenes {
        let tracer = Tracer::new(Scene::open(name)?.commit(&Device::new()?)?);
        let mut t = TraceConfig::new(Mode::Adaptive, Budget::NMax(n_max));
        t.seed = 1;
        let out = tracer.trace(&t)?;
        let maps = RenderConfig::new(side, side).build_maps(out.photons, out.frame);
        let mut uniform_variance = None;
        for allocation in [GatherAllocation::Uniform, GatherAllocation::Variance] {
            let mut cfg = RenderConfig::new(side, side);
            cfg.spp = spp;
            cfg.gather_allocation = allocation;
            cfg.show_emitters = false;
            let start = Instant::now();
            let mut images = Vec::new();
            let mut stats = Vec::new();
            for seed in [11, 12] {
                cfg.seed = seed;
                let (img, s) = render_with(tracer.prepared(), Some(&maps), None, &cfg, &|_, _| {})?;
                images.push(img);
                stats.push(s);
            }
            let seconds = start.elapsed().as_secs_f64();
            let noise = noise(&images[0], &images[1])?;
            let ratio = match uniform_variance {
                None => {
                    uniform_variance = Some(noise * noise);
                    1.0
                }
                Some(u) => noise * noise / u,
            };
            println!(
                "| {name} | {n_max} | {side}² | {spp} | {} | {:.3} % | {ratio:.3} | {seconds:.2} | {:.3} | {:.3} |",
                allocation.name(),
                100.0 * noise,
                stats[0].gather_plan_s,
                stats[0].mean_gather,
            );
        }
    }
    Ok(())
}

/// One image's relative rms noise from two independent renders: the rms of
/// their difference over `sqrt(2)`, over their mean.
fn noise(a: &Image, b: &Image) -> Result<f64, adaptive_pm::Error> {
    let mean = (a.mean() + b.mean()).as_dvec3().element_sum() / 6.0;
    Ok(rmse(a, b)? / std::f64::consts::SQRT_2 / mean)
}
