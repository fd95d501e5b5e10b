//! `adaptive-pm render <SCENE> --mode M (--quality Q | --n-max N) --out image.exr`:
//! trace photons, build the maps, render an image (see `adaptive_pm::render`).

use super::common::{
    open_scene, progress_bar, EmbreeArgs, SceneFileArgs, ThreadArgs, TraceConfigArgs,
};
use super::render_spp::{first_spp, noise_target, photon_image, Spp, SppOutcome};
use adaptive_pm::embree::EmbreeScene;
use adaptive_pm::engine::caustic::BYTES_PER_CAUSTIC_PHOTON;
use adaptive_pm::engine::tracer::BYTES_PER_STORED_PHOTON;
use adaptive_pm::engine::{CausticBudget, CausticReport, Mode, TraceConfig, Tracer};
use adaptive_pm::output::refuse_overwrite;
use adaptive_pm::photon_file::read_render_maps;
use adaptive_pm::render::{
    cache::DEFAULT_STRIDE, check_output_path, tile_rows, CheckedRender, GatherAllocation,
    GatherDirections, Image, Integrator, RenderConfig, RenderMaps, RenderStats, ToneMap, View,
    DEFAULT_GATHER, DEFAULT_K,
};
use adaptive_pm::scene::Scene;
use anyhow::Context;
use serde_json::json;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// Arguments of `render`.
#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// A glTF file (.gltf or .glb), or a built-in scene: `cornell` (the Cornell
    /// box), `cornell-empty` (without its blocks), `cornell-glass` (with a mirror
    /// and a glass sphere instead), `door` (two rooms, a door ajar, the light in
    /// the room the camera does not see).
    pub scene: String,
    #[command(flatten)]
    pub assets: SceneFileArgs,
    /// classic (Markov chains), density (density control) or adaptive (the paper).
    #[arg(long, default_value = "adaptive")]
    pub mode: Mode,
    /// photon (direct light + photon map) or path (unbiased path tracer, no photons).
    #[arg(long, default_value = "photon")]
    pub integrator: Integrator,
    #[command(flatten)]
    pub budget: TraceConfigArgs,
    #[command(flatten)]
    pub threads: ThreadArgs,
    #[command(flatten)]
    pub embree: EmbreeArgs,
    /// Samples per pixel, or `auto`: rounds of two independent half images
    /// until their estimated relative noise (rms over the pixels that are
    /// not a light's, of the mean) is at most --noise, or --max-spp. The
    /// noise seen is the render's own: the photon map's error is not in it.
    #[arg(long, default_value = "auto")]
    pub spp: Spp,
    /// With --spp auto: the relative noise to stop at (default 0.02, 2 %).
    #[arg(long)]
    pub noise: Option<f64>,
    /// With --spp auto: the most samples per pixel (default 1024).
    #[arg(long)]
    pub max_spp: Option<u32>,
    /// Image width in pixels.
    #[arg(long, default_value_t = 256)]
    pub width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = 256)]
    pub height: u32,
    /// Final-gather rays per camera sample, on average with --gather-allocation variance
    /// (0: read the indirect map at the first hit).
    #[arg(long, default_value_t = DEFAULT_GATHER)]
    pub final_gather: u32,
    /// How the gather's rays are spread: variance (that many per sample on
    /// average, more where a pilot measured more gather noise) or uniform.
    #[arg(long, default_value = "variance")]
    pub gather_allocation: GatherAllocation,
    /// Where the gather's directions come from at a diffuse surface: guided
    /// (the irradiance cache's histogram of where the indirect photons came
    /// from, half and half with the cosine) or brdf (the cosine alone).
    #[arg(long, default_value = "guided")]
    pub gather_directions: GatherDirections,
    /// Light samples (shadow rays) per camera sample.
    #[arg(long, default_value_t = 1)]
    pub light_samples: u32,
    /// Photons per irradiance-cache sample, 2 or more (0: the gather reads the k nearest photons).
    #[arg(long, default_value_t = DEFAULT_STRIDE)]
    pub cache_stride: u32,
    /// Photons per radiance estimate.
    #[arg(long, default_value_t = DEFAULT_K)]
    pub k: usize,
    /// Caustic photons per caustic estimate (the caustic map's own kernel).
    #[arg(long, default_value_t = adaptive_pm::render::DEFAULT_CAUSTIC_K)]
    pub caustic_k: usize,
    /// Largest caustic kernel radius in scene units (default: a quarter of
    /// the other estimates' largest radius).
    #[arg(long)]
    pub caustic_radius: Option<f32>,
    /// Caustic photons of the caustic pass, aimed at mirrors and glass
    /// (Jensen's projection map); the caustic map is then the pass's, not
    /// the main trace's caustic photons. 0 turns the pass off. Default:
    /// N_MAX (the main trace's budget) when the scene has a mirror or glass
    /// mesh and a light, else 0 (`auto`, which shrinks to what the main
    /// map leaves of --budget-mb); 0 with --map.
    #[arg(long)]
    pub caustic_photons: Option<CausticBudget>,
    /// Linear radiance, OpenEXR.
    #[arg(long)]
    pub out: PathBuf,
    /// Also a tone-mapped sRGB preview (exposure, then Reinhard).
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Exposure of the PNG preview in stops.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true,
          value_parser = super::common::parse_exposure)]
    pub exposure: f32,
    /// Direct light only: no photons are traced.
    #[arg(long, conflicts_with = "visualize_map")]
    pub direct_only: bool,
    /// Show the map's radiance estimate at the first hit (no light sampling, no gather).
    #[arg(long)]
    pub visualize_map: bool,
    /// With --visualize-map: depth-0 photons only (the paper's primary map).
    #[arg(long, requires = "visualize_map")]
    pub primary_only: bool,
    /// Render from this photon map file (`trace --out` or `merge`) instead of tracing.
    #[arg(long, conflicts_with = "direct_only")]
    pub map: Option<PathBuf>,
    /// Render only tile I of N (bands of rows), for `assemble`.
    #[arg(long)]
    pub tile: Option<adaptive_pm::engine::Shard>,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: RenderArgs) -> anyhow::Result<()> {
    let scene = open_scene(&args.scene, &args.assets, args.budget.cosn)?;
    let mut trace_cfg = args.budget.config(args.mode)?;
    let cfg = render_config(&args)?;
    if let Some(imp) = trace_cfg.importance.as_mut() {
        imp.match_render(&cfg);
    }
    let target = noise_target(&args)?;
    check_outputs(&args)?;
    let pool = args.threads.pool()?;
    let device = args.embree.device()?;
    let prepared = Arc::new(scene.commit(&device)?);
    if args.integrator == Integrator::Path {
        return super::render_path::run_path(&args, &prepared, &cfg, target.as_ref(), &pool);
    }
    let bar = progress_bar(!args.json);
    let (maps, trace_s, photons, caustic) = if cfg.view == View::DirectOnly {
        (None, 0.0, 0, None)
    } else {
        let (maps, trace_s, photons) =
            photon_maps(&args, &prepared, &trace_cfg, &cfg, &pool, &bar)?;
        let (maps, caustic) = caustic_pass(&args, &prepared, &trace_cfg, &cfg, &pool, maps)?;
        let caustic_s = caustic.as_ref().map_or(0.0, |c| c.trace_s);
        (Some(maps), trace_s + caustic_s, photons, caustic)
    };
    bar.set_position(0);
    bar.set_length(args.height as u64);
    bar.set_message("render");
    let t = Instant::now();
    let (image, stats, spp) = pool.install(|| {
        photon_image(
            &prepared,
            maps.as_ref(),
            &cfg,
            target.as_ref(),
            &|done, _| bar.set_position(done),
        )
    })?;
    let render_s = t.elapsed().as_secs_f64();
    bar.finish_and_clear();
    warn_dropped(stats.dropped_samples, stats.samples);
    write_image(&image, &cfg, &args)?;
    if let Some(p) = &args.png {
        image.write_png(
            p,
            ToneMap {
                exposure: args.exposure,
            },
        )?;
    }
    let times = Times {
        trace_s,
        map_build_s: maps.as_ref().map_or(0.0, |m| m.build_total_s()),
        render_s,
    };
    let run = RunReport {
        stats: &stats,
        spp,
        photons,
        times: &times,
        caustic: caustic.as_ref(),
    };
    report(&args, &cfg, &image, &run);
    Ok(())
}

/// The caustic pass's photon count: `--caustic-photons`, else the default
/// for a traced run (`auto`: `engine::default_caustic_photons`) and 0
/// with `--map`.
fn caustic_count(args: &RenderArgs, scene: &Scene, trace_cfg: &TraceConfig) -> anyhow::Result<u64> {
    let n_max = trace_cfg.budget.n_max()?;
    Ok(match (args.caustic_photons, &args.map) {
        (Some(c), _) => c.photons(scene, n_max),
        (None, Some(_)) => 0,
        (None, None) => CausticBudget::Auto.photons(scene, n_max),
    })
}

/// Runs the caustic pass when the render reads the caustic map (the full
/// view) and the count is not 0, its map replacing the main trace's
/// caustic map.
fn caustic_pass(
    args: &RenderArgs,
    prepared: &Arc<EmbreeScene>,
    trace_cfg: &TraceConfig,
    cfg: &RenderConfig,
    pool: &rayon::ThreadPool,
    maps: RenderMaps,
) -> anyhow::Result<(RenderMaps, Option<CausticReport>)> {
    let n = caustic_count(args, prepared.scene(), trace_cfg)?;
    if n == 0 || cfg.view != View::Full {
        return Ok((maps, None));
    }
    // The pass gets what the main map left of the budget; `auto` shrinks
    // to fit it, a count asked for is refused when it does not.
    let used = maps.full.len() as u64 * BYTES_PER_STORED_PHOTON;
    let left = trace_cfg.check()?.memory_budget().saturating_sub(used);
    let n = match args.caustic_photons {
        None | Some(CausticBudget::Auto) => n.min(left / BYTES_PER_CAUSTIC_PHOTON),
        Some(CausticBudget::Photons(_)) => n,
    };
    if n == 0 {
        return Ok((maps, None));
    }
    let mut pass_cfg = trace_cfg.clone();
    pass_cfg.memory_budget = Some(left);
    let tracer = Tracer::new(Arc::clone(prepared));
    let pass = pool.install(|| tracer.trace_caustic(&pass_cfg, n))?;
    let report = pass.report.clone();
    Ok((pool.install(|| maps.with_caustic_pass(pass)), Some(report)))
}

/// The caustic pass's line of the text report.
fn print_caustic(caustic: Option<&CausticReport>) {
    if let Some(c) = caustic {
        println!(
            "caustic pass: {} photons emitted ({} aimed at {} specular meshes), {} stored, {:.3} s",
            c.emitted, c.aimed, c.targets, c.stored, c.trace_s
        );
    }
}

/// The render settings the arguments ask for, checked (once: the render
/// runs on them as they are).
fn render_config(args: &RenderArgs) -> anyhow::Result<CheckedRender> {
    let mut cfg = RenderConfig::new(args.width, args.height);
    cfg.spp = first_spp(args.spp);
    cfg.final_gather = args.final_gather;
    cfg.gather_allocation = args.gather_allocation;
    cfg.gather_directions = args.gather_directions;
    cfg.light_samples = args.light_samples;
    cfg.cache_stride = args.cache_stride;
    cfg.k = args.k;
    cfg.caustic_k = args.caustic_k;
    cfg.caustic_max_radius = args.caustic_radius;
    cfg.view = if args.direct_only {
        View::DirectOnly
    } else if args.visualize_map {
        View::Map {
            primary_only: args.primary_only,
        }
    } else {
        View::Full
    };
    cfg.seed = args.budget.seed;
    cfg.rows = args.tile.map(|t| tile_rows(t, args.height));
    // Fail before any work: bad sizes.
    Ok(cfg.check()?)
}

/// Fails before any work on a missing folder, an unwritable path, or an
/// output that would replace an input or the other output, however spelled
/// (a built-in scene's name is no file).
fn check_outputs(args: &RenderArgs) -> anyhow::Result<()> {
    check_output_path(&args.out)?;
    if let Some(p) = &args.png {
        check_output_path(p)?;
    }
    let scene_path = Path::new(&args.scene);
    let mut inputs: Vec<&Path> = Vec::new();
    inputs.extend(Some(scene_path).filter(|p| p.exists()));
    inputs.extend(args.map.as_deref());
    refuse_overwrite(&args.out, &inputs).context("--out")?;
    if let Some(p) = &args.png {
        inputs.push(&args.out);
        refuse_overwrite(p, &inputs).context("--png")?;
    }
    Ok(())
}

/// The maps to render from, read from `--map` or traced now, with the
/// seconds that took and the photons stored.
fn photon_maps(
    args: &RenderArgs,
    prepared: &Arc<EmbreeScene>,
    trace_cfg: &TraceConfig,
    cfg: &RenderConfig,
    pool: &rayon::ThreadPool,
    bar: &indicatif::ProgressBar,
) -> anyhow::Result<(RenderMaps, f64, usize)> {
    let t = Instant::now();
    if let Some(path) = &args.map {
        let (h, maps) = pool.install(|| read_render_maps(path, prepared.scene()))?;
        return Ok((maps, t.elapsed().as_secs_f64(), h.photons as usize));
    }
    let tracer = Tracer::new(Arc::clone(prepared));
    let out = pool.install(|| {
        tracer.trace_with_progress(trace_cfg, &|p| {
            bar.set_length(p.total);
            bar.set_position(p.done);
            bar.set_message(format!("depth {}", p.depth));
        })
    })?;
    let stored = out.photons.len();
    let maps = pool.install(|| cfg.build_maps(out.photons, out.frame));
    Ok((maps, t.elapsed().as_secs_f64(), stored))
}

/// Seconds spent in each stage of a render.
struct Times {
    trace_s: f64,
    map_build_s: f64,
    render_s: f64,
}

/// What a render did besides its image.
struct RunReport<'a> {
    stats: &'a RenderStats,
    spp: SppOutcome,
    photons: usize,
    times: &'a Times,
    caustic: Option<&'a CausticReport>,
}

/// Prints what the render did: one JSON object, or lines of text.
fn report(args: &RenderArgs, cfg: &RenderConfig, image: &Image, run: &RunReport) {
    let RunReport {
        stats,
        spp,
        photons,
        times,
        caustic,
    } = *run;
    let mean = image.mean();
    let samples_per_s = stats.samples as f64 / times.render_s.max(1e-9);
    if args.json {
        println!(
            "{}",
            json!({
                "scene": args.scene,
                "mode": args.mode.name(),
                "view": format!("{:?}", cfg.view),
                "width": args.width,
                "height": args.height,
                "spp": spp.spp,
                "noise_estimate": spp.noise.map(|n| n.0),
                "noise_target_reached": spp.noise.map(|n| n.1),
                "final_gather": args.final_gather,
                "gather_allocation": args.gather_allocation.name(),
                "gather_directions": args.gather_directions.name(),
                "mean_gather": stats.mean_gather,
                "gather_plan_s": stats.gather_plan_s,
                "light_samples": args.light_samples,
                "cache_stride": args.cache_stride,
                "k": args.k,
                "photons": photons,
                "trace_s": times.trace_s,
                "map_build_s": times.map_build_s,
                "render_s": times.render_s,
                "samples_per_s": samples_per_s,
                "lookup_s": stats.lookup_s,
                "cache_build_s": stats.cache_build_s,
                "cache_entries": stats.cache_entries,
                "cache_bytes_per_entry": stats.cache_bytes_per_entry,
                "cache_walled": stats.cache_walled,
                "cache_guides": stats.cache_guides.0,
                "cache_guide_bytes": stats.cache_guides.1,
                "cache_misses": stats.cache_misses,
                "dropped_samples": stats.dropped_samples,
                "mean_rgb": [mean.x, mean.y, mean.z],
                "caustic_pass": caustic,
                "out": args.out,
            })
        );
        return;
    }
    println!(
        "{} on {}: {} photons, trace + kd-trees {:.3} s, render {:.3} s ({}x{}, {} spp, gather {})",
        args.mode.name(),
        args.scene,
        photons,
        times.trace_s,
        times.render_s,
        args.width,
        args.height,
        spp.spp,
        args.final_gather
    );
    print_noise(&spp);
    let (cache_n, cache_s) = (stats.cache_entries, stats.cache_build_s);
    println!(
        "{samples_per_s:.0} samples/s, lookups {:.3} s (thread sum), cache {cache_n} cells ({} walled) built in {cache_s:.3} s",
        stats.lookup_s, stats.cache_walled
    );
    print_caustic(caustic);
    println!("mean RGB {:.4} {:.4} {:.4}", mean.x, mean.y, mean.z);
    println!("wrote {}", args.out.display());
    if let Some(p) = &args.png {
        println!("wrote {}", p.display());
    }
}

/// The `--spp auto` line of the text report.
pub fn print_noise(spp: &SppOutcome) {
    match spp.noise {
        Some((n, true)) => println!(
            "noise {:.2} % after {} spp (target reached)",
            100.0 * n,
            spp.spp
        ),
        Some((n, false)) => println!(
            "noise {:.2} % after {} spp: --max-spp stopped it before --noise",
            100.0 * n,
            spp.spp
        ),
        None => {}
    }
}

/// Writes the EXR: a tile of the whole image (`--tile`) or the whole image.
pub fn write_image(image: &Image, cfg: &RenderConfig, args: &RenderArgs) -> anyhow::Result<()> {
    match (args.tile, cfg.rows) {
        (Some(_), Some((y0, _))) => image.write_exr_tile(y0, args.height, &args.out)?,
        _ => image.write_exr(&args.out)?,
    }
    Ok(())
}

/// Says on stderr that samples were left out (the image is biased there).
pub fn warn_dropped(dropped: u64, samples: u64) {
    if dropped > 0 {
        eprintln!(
            "warning: {dropped} of {samples} samples were NaN or infinite and were left out \
             (degenerate geometry, or radiance beyond f32): the image is biased where they fell"
        );
    }
}
