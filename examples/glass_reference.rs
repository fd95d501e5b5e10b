//! The photon render of `cornell-glass` against a converged path-traced
//! reference of the same scene (issue: glass and caustics, "done when").
//!
//! `cargo run --release --example glass_reference -- [REF_SPP] [SIZE] [N_MAX] [SPP] [CAUSTIC]`
//! (defaults 16384, 256, and `render`'s defaults: N_MAX 1e5, `--spp auto`
//! with its noise target, a caustic pass of `auto` photons; SPP a number
//! for a fixed count, CAUSTIC a number, 0 for no pass): path-traces the
//! reference as two independent halves of REF_SPP/2 samples each (cached as
//! OpenEXR in `target/glass-reference`, keyed by the scene, size and spp,
//! since the reference takes minutes), renders the photon image as `render`
//! does (adaptive, caustic pass, gather through the cache, the other
//! settings `render`'s defaults), and
//! prints the relRMSE over the pixels that are not a light's own (its
//! noise, from the halves, taken out in quadrature), the mean per channel
//! against the reference's, and the same over the caustic's pixels (first
//! hit non-specular, caustic part at least 20 % of the reference). Emitters
//! seen from the camera are left out of both images (exact in both).

use adaptive_pm::embree::Device;
use adaptive_pm::engine::{Budget, CausticBudget, Mode, TraceConfig, Tracer};
use adaptive_pm::experiments::render_study::caustic_pixels;
use adaptive_pm::render::{
    light_pixels, mean_bias, relative_rmse_masked, render, render_path_with, render_progressive,
    Image, NoiseTarget, PathHalves, PathPart, RenderConfig,
};
use adaptive_pm::scene::Scene;
use std::path::PathBuf;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let ref_spp: u32 = args.first().map_or(Ok(16384), |s| s.parse())?;
    let size: u32 = args.get(1).map_or(Ok(256), |s| s.parse())?;
    let n_max: u64 = args.get(2).map_or(Ok(100_000), |s| s.parse())?;
    let spp: Option<u32> = match args.get(3).map(String::as_str) {
        None | Some("auto") => None,
        Some(n) => Some(n.parse()?),
    };
    let caustic = match args.get(4).map(String::as_str) {
        None | Some("auto") => CausticBudget::Auto,
        Some(n) => CausticBudget::Photons(n.parse()?),
    };
    let dir = PathBuf::from("target/glass-reference");
    std::fs::create_dir_all(&dir)?;
    let scene = Scene::open("cornell-glass")?;
    let device = Device::new()?;
    let tracer = Tracer::new(scene.commit(&device)?);
    let prepared = tracer.prepared();

    let mut base = RenderConfig::new(size, size);
    base.show_emitters = false;
    let keep: Vec<bool> = light_pixels(prepared, &base)?.iter().map(|l| !l).collect();

    // The reference's halves, from the cache or rendered now.
    let mut rc = base.clone();
    rc.spp = (ref_spp / 2).max(1);
    rc.seed = 0x5EF_E2E4CE;
    let name = |half: &str| dir.join(format!("cornell-glass-{size}-{ref_spp}-{half}.exr"));
    let (a, b) = match (Image::read_exr(name("a")), Image::read_exr(name("b"))) {
        (Ok(a), Ok(b)) => {
            eprintln!("reference: read from {}", dir.display());
            (a, b)
        }
        _ => {
            let t = Instant::now();
            let progress = |done: u64, total: u64| {
                if done % 32 == 0 {
                    eprint!("\rreference: {done}/{total} rows");
                }
            };
            let (a, _) = render_path_with(prepared, &rc, PathPart::Full, &progress)?;
            rc.seed ^= 0xB;
            let (b, _) = render_path_with(prepared, &rc, PathPart::Full, &progress)?;
            eprintln!(
                "\rreference: {ref_spp} spp in {:.1} s",
                t.elapsed().as_secs_f64()
            );
            a.write_exr(name("a"))?;
            b.write_exr(name("b"))?;
            (a, b)
        }
    };
    let halves = PathHalves {
        a,
        b,
        dropped_samples: 0,
    };
    let reference = halves.mean();
    let noise = halves.noise_rel(Some(&keep));

    let caustic_mask = caustic_pixels(prepared, &base, ref_spp / 8, &reference, &keep)?;
    let caustic_noise = halves.noise_rel(Some(&caustic_mask));

    let t = Instant::now();
    let trace_cfg = TraceConfig::new(Mode::Adaptive, Budget::NMax(n_max));
    let out = tracer.trace(&trace_cfg)?;
    let mut maps = base.build_maps(out.photons, out.frame);
    let n_caustic = caustic.photons(tracer.scene(), n_max);
    if n_caustic > 0 {
        maps = maps.with_caustic_pass(tracer.trace_caustic(&trace_cfg, n_caustic)?);
    }
    let (img, spp_used, own_noise) = match spp {
        Some(n) => {
            let mut pc = base.clone();
            pc.spp = n;
            (render(prepared, Some(&maps), &pc)?, n, None)
        }
        None => {
            let target = NoiseTarget::default();
            let (p, _) = render_progressive(
                prepared,
                Some(&maps),
                &base.check()?,
                &target,
                &|_, _| {},
                &mut |r| eprintln!("render: {} spp, noise {:.2} %", r.spp, 100.0 * r.noise),
            )?;
            (p.image, p.spp, Some(p.noise))
        }
    };
    let photon_s = t.elapsed().as_secs_f64();

    // The images, to look at (the photon render's name carries its settings).
    let tone = adaptive_pm::render::ToneMap::default();
    reference.write_png(dir.join(format!("reference-{size}-{ref_spp}.png")), tone)?;
    img.write_png(
        dir.join(format!("photon-{size}-{n_max}-{spp_used}-{n_caustic}.png")),
        tone,
    )?;
    let free = |e: f64, n: f64| (e * e - n * n).max(0.0).sqrt();
    let e = relative_rmse_masked(&img, &reference, &keep)?;
    let ec = relative_rmse_masked(&img, &reference, &caustic_mask)?;
    let bias = mean_bias(&img, &reference, &keep)?;
    let count = caustic_mask.iter().filter(|&&c| c).count();
    println!(
        "reference: {ref_spp} spp, {size}^2, relative noise {:.2} % (caustic pixels {:.2} %)",
        100.0 * noise,
        100.0 * caustic_noise
    );
    println!(
        "photon render (adaptive, N_MAX {n_max}, caustic pass {n_caustic} photons, {spp_used} spp{}): {photon_s:.2} s",
        own_noise.map_or(String::new(), |n| format!(", spp auto: own noise {:.2} %", 100.0 * n))
    );
    println!(
        "  relRMSE over the non-light pixels: {:.2} % measured, {:.2} % with the reference's noise taken out",
        100.0 * e,
        100.0 * free(e, noise)
    );
    println!(
        "  mean per channel against the reference: {:+.2} % {:+.2} % {:+.2} %",
        100.0 * bias[0],
        100.0 * bias[1],
        100.0 * bias[2]
    );
    println!(
        "  over the {count} caustic pixels: relRMSE {:.2} % measured, {:.2} % noise-free",
        100.0 * ec,
        100.0 * free(ec, caustic_noise)
    );
    Ok(())
}
