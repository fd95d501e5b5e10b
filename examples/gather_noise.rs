//! The gather's noise at equal samples under two settings: its rays spread
//! by variance against the uniform gather (docs/rendering.md, "Gather rays
//! where the variance is"), or its directions drawn from the cache's guide
//! against the BRDF's ("The gather's guide"). One photon map per scene, two
//! renders of other seeds per setting, and each setting's noise,
//! `rmse(A, B) / sqrt(2) / mean` (one image's relative rms noise, the
//! emitters hidden), with the renders' times. Prints a Markdown table.
//!
//! `cargo run --release --example gather_noise -- allocation|directions N_MAX SIDE SPP SCENE...`
//! (for example `directions 100000 256 32 cornell cornell-glass`)

use adaptive_pm::embree::Device;
use adaptive_pm::engine::{Budget, Mode, TraceConfig, Tracer};
use adaptive_pm::render::{
    render_with, rmse, GatherAllocation, GatherDirections, Image, RenderConfig,
};
use adaptive_pm::scene::Scene;
use std::time::Instant;

/// A setting: its name and what it changes.
type Setting = (&'static str, fn(&mut RenderConfig));

fn settings(compared: &str) -> Option<[Setting; 2]> {
    match compared {
        "allocation" => Some([
            ("uniform", |c| {
                c.gather_allocation = GatherAllocation::Uniform
            }),
            ("variance", |c| {
                c.gather_allocation = GatherAllocation::Variance
            }),
        ]),
        "directions" => Some([
            ("brdf", |c| c.gather_directions = GatherDirections::Brdf),
            ("guided", |c| c.gather_directions = GatherDirections::Guided),
        ]),
        _ => None,
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: gather_noise allocation|directions N_MAX SIDE SPP SCENE...";
    let [compared, n_max, side, spp, scenes @ ..] = args.as_slice() else {
        return Err(usage.into());
    };
    let settings = settings(compared).ok_or(usage)?;
    let (n_max, side, spp): (u64, u32, u32) = (n_max.parse()?, side.parse()?, spp.parse()?);
    println!("| scene | N_MAX | pixels | spp | {compared} | noise | variance / {} | render s (two) | pilot s | mean gather |", settings[0].0);
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for name in scenes {
        let tracer = Tracer::new(Scene::open(name)?.commit(&Device::new()?)?);
        let mut t = TraceConfig::new(Mode::Adaptive, Budget::NMax(n_max));
        t.seed = 1;
        let out = tracer.trace(&t)?;
        let maps = RenderConfig::new(side, side).build_maps(out.photons, out.frame);
        let mut first_variance = None;
        for (setting, apply) in settings {
            let mut cfg = RenderConfig::new(side, side);
            cfg.spp = spp;
            apply(&mut cfg);
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
            let ratio = match first_variance {
                None => {
                    first_variance = Some(noise * noise);
                    1.0
                }
                Some(u) => noise * noise / u,
            };
            println!(
                "| {name} | {n_max} | {side}² | {spp} | {setting} | {:.3} % | {ratio:.3} | {seconds:.2} | {:.3} | {:.3} |",
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
