//! `adaptive-pm bench tradeoff <SCENE>`: the speed/accuracy trade (SPEC §5).
//!
//! For each mode and each budget, trace, build the maps, render, and measure
//! against a converged reference:
//! - **time**: trace (with the analysis) + kd-trees + render, seconds;
//! - **image error**: RMSE and relative RMSE (over the reference's mean) of the
//!   full render, and of the map view (the map's estimate at the first hit, no
//!   light sampling: the map's quality alone); emitters seen by the camera are
//!   hidden (their radiance is exact in every mode, and the aliasing of a
//!   bright light's edges would swamp the RMSE);
//! - **floor irradiance** on a 16 x 16 grid over the floor mesh: the full map's
//!   estimate against the reference maps' (relative RMSE), and the primary
//!   (depth-0) map's against the direct-light quadrature over the lights with
//!   shadow rays (the oracle of `tests/render.rs`).
//!
//! k of every estimate grows as `sqrt(N_MAX) / 2` (clamped to 20..=1000) so
//! that both the noise (~1/sqrt(k)) and the kernel bias (r^2 ~ k/N) fall with
//! the budget; at a fixed k the error would stall at the k-NN noise.
//!
//! The reference is the mean of two classic-mode renders with different seeds
//! (`--reference-n-max` photons and `--reference-spp` samples each), cached in
//! `DIR/reference.exr` with its parameters in `DIR/reference.json` and reused
//! when they match. Its remaining noise is `rmse(A, B) / 2` (the difference of
//! two independent halves has twice the variance of one; their mean has half),
//! printed and stored. Kernel bias common to both halves is not in that number.

use super::super::common::{open_scene, ThreadArgs};
use adaptive_pm::embree::{CommittedScene, Device};
use adaptive_pm::engine::{Budget, Mode, TraceConfig, Tracer};
use adaptive_pm::render::{
    floor_points, irradiance_estimate, quadrature_irradiance, relative_rmse, render, rmse, Image,
    Lookup, RenderConfig, RenderMaps, View,
};
use adaptive_pm::scene::{PreparedScene, Scene, SurfacePoint};
use anyhow::Context;
use plotters::prelude::*;
use serde_json::json;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Bumped when the reference's computation changes, so old caches are redone.
const REFERENCE_VERSION: u32 = 2;

/// Arguments of `bench tradeoff`.
#[derive(clap::Args, Debug)]
pub struct TradeoffArgs {
    /// A glTF file, or `cornell` for the built-in Cornell box.
    #[arg(default_value = "cornell")]
    pub scene: String,
    /// N_MAX values (comma separated).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "10000,30000,100000,300000,1000000"
    )]
    pub n_max: Vec<u64>,
    /// Q values instead of N_MAX (comma separated); N_MAX = Q^2 (2^31 - 1).
    #[arg(long, value_delimiter = ',', conflicts_with = "n_max")]
    pub qualities: Option<Vec<f64>>,
    /// Modes (comma separated).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "classic,density,adaptive"
    )]
    pub modes: Vec<Mode>,
    /// Override every area light's cos^n exponent.
    #[arg(long)]
    pub cosn: Option<f32>,
    /// Image width.
    #[arg(long, default_value_t = 96)]
    pub width: u32,
    /// Image height.
    #[arg(long, default_value_t = 96)]
    pub height: u32,
    /// Samples per pixel of the measured renders.
    #[arg(long, default_value_t = 8)]
    pub spp: u32,
    /// Photons of each half of the reference (classic mode).
    #[arg(long, default_value_t = 4_000_000)]
    pub reference_n_max: u64,
    /// Samples per pixel of each half of the reference.
    #[arg(long, default_value_t = 64)]
    pub reference_spp: u32,
    /// Seed of the measured runs.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output folder (created): CSVs, plot, cached reference.
    #[arg(long, default_value = "tradeoff-out")]
    pub out: PathBuf,
    #[command(flatten)]
    pub threads: ThreadArgs,
    /// Print one JSON object on stdout (the table and summary go to stderr).
    #[arg(long)]
    pub json: bool,
}

/// k of the estimates for a budget (see the module docs).
pub fn k_for(n_max: u64) -> usize {
    ((n_max as f64).sqrt() / 2.0).round().clamp(20.0, 1000.0) as usize
}

struct Reference {
    image: Image,
    floor: Vec<f64>,
    noise_rmse: f64,
}

fn floor_irradiance(maps: &RenderMaps, primary: bool, pts: &[SurfacePoint], k: usize) -> Vec<f64> {
    let map = if primary { &maps.primary } else { &maps.full };
    let mut scratch = Vec::new();
    let lk = Lookup {
        k,
        max_radius: f32::INFINITY,
    };
    pts.iter()
        .map(|p| {
            let e = irradiance_estimate(map, p.position, p.normal, lk, &mut scratch).value;
            (e.x as f64 + e.y as f64 + e.z as f64) / 3.0
        })
        .collect()
}

/// `sqrt(mean (a - b)^2) / mean(b)`.
fn rel_rmse(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().max(1) as f64;
    let mse = a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>() / n;
    let mean = b.iter().sum::<f64>() / n;
    if mean > 0.0 {
        mse.sqrt() / mean
    } else {
        0.0
    }
}

fn trace(
    scene: &Scene,
    rt: &CommittedScene,
    mode: Mode,
    n_max: u64,
    seed: u64,
) -> anyhow::Result<(RenderMaps, usize, f64, f64)> {
    let mut cfg = TraceConfig::new(mode, Budget::NMax(n_max));
    cfg.seed = seed;
    let t = Instant::now();
    let out = Tracer::new(PreparedScene::new(scene.clone(), rt)?).trace(&cfg)?;
    let trace_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let maps = RenderMaps::build(&out.records());
    Ok((maps, out.photons.len(), trace_s, t.elapsed().as_secs_f64()))
}

fn render_cfg(args: &TradeoffArgs, spp: u32, k: usize, seed: u64, view: View) -> RenderConfig {
    let mut c = RenderConfig::new(args.width, args.height);
    c.spp = spp;
    c.k = k;
    c.seed = seed;
    c.view = view;
    c.show_emitters = false;
    c
}

fn reference(
    args: &TradeoffArgs,
    scene: &Scene,
    rt: &CommittedScene,
    pts: &[SurfacePoint],
) -> anyhow::Result<Reference> {
    let k = k_for(args.reference_n_max);
    let params = json!({
        "version": REFERENCE_VERSION,
        "scene": args.scene,
        "cosn": args.cosn,
        "width": args.width,
        "height": args.height,
        "n_max": args.reference_n_max,
        "spp": args.reference_spp,
        "k": k,
        "floor_points": pts.len(),
    });
    let exr = args.out.join("reference.exr");
    let meta = args.out.join("reference.json");
    if let (Ok(text), true) = (std::fs::read_to_string(&meta), exr.exists()) {
        if let Ok(v) = serde_json::from_str::<serde_json::Value>(&text) {
            if v.get("params") == Some(&params) {
                let image = Image::read_exr(&exr)?;
                let floor: Vec<f64> = serde_json::from_value(v["floor"].clone())?;
                let noise_rmse = v["noise_rmse"].as_f64().unwrap_or(f64::NAN);
                eprintln!("reference: reusing {}", exr.display());
                return Ok(Reference {
                    image,
                    floor,
                    noise_rmse,
                });
            }
        }
    }
    eprintln!(
        "reference: 2 x {} photons (classic), {} spp, k = {k} ...",
        args.reference_n_max, args.reference_spp
    );
    let t = Instant::now();
    let mut halves = Vec::new();
    let mut floors = Vec::new();
    for seed in [1001u64, 2002] {
        let (maps, _, _, _) = trace(scene, rt, Mode::Classic, args.reference_n_max, seed)?;
        let cfg = render_cfg(args, args.reference_spp, k, seed, View::Full);
        halves.push(render(scene, rt, Some(&maps), &cfg, &|_, _| {})?);
        floors.push(floor_irradiance(&maps, false, pts, k));
    }
    let noise_rmse = rmse(&halves[0], &halves[1])? / 2.0;
    let mut image = halves[0].clone();
    for (p, q) in image.pixels.iter_mut().zip(&halves[1].pixels) {
        *p = (*p + *q) * 0.5;
    }
    let floor: Vec<f64> = floors[0]
        .iter()
        .zip(&floors[1])
        .map(|(a, b)| 0.5 * (a + b))
        .collect();
    image.write_exr(&exr)?;
    let doc = json!({
        "params": params,
        "noise_rmse": noise_rmse,
        "floor": floor,
        "seconds": t.elapsed().as_secs_f64(),
    });
    std::fs::write(&meta, serde_json::to_string_pretty(&doc)?)
        .with_context(|| meta.display().to_string())?;
    Ok(Reference {
        image,
        floor,
        noise_rmse,
    })
}

/// `println!`, or `eprintln!` when stdout is reserved for `--json`.
macro_rules! say {
    ($json:expr, $($t:tt)*) => {
        if $json { eprintln!($($t)*) } else { println!($($t)*) }
    };
}

#[derive(serde::Serialize)]
struct Row {
    mode: Mode,
    n_max: u64,
    k: usize,
    photons: usize,
    trace_s: f64,
    build_s: f64,
    render_s: f64,
    rmse: f64,
    rel_rmse: f64,
    map_rel_rmse: f64,
    floor_rel_rmse: f64,
    floor_direct_rel_rmse: f64,
}

impl Row {
    fn total_s(&self) -> f64 {
        self.trace_s + self.build_s + self.render_s
    }
}

pub fn run(args: TradeoffArgs) -> anyhow::Result<()> {
    let scene = open_scene(&args.scene, args.cosn)?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let budgets: Vec<u64> = match &args.qualities {
        Some(qs) => qs
            .iter()
            .map(|&q| Budget::Quality(q).n_max())
            .collect::<Result<_, _>>()?,
        None => args.n_max.clone(),
    };
    if budgets.is_empty() || budgets.contains(&0) {
        anyhow::bail!("every budget must give N_MAX >= 1");
    }
    render_cfg(&args, args.spp, 20, 1, View::Full).validate()?;
    let pool = args.threads.pool()?;
    let device = Device::new()?;
    let rt = scene.embree_geometry(&device)?;
    let pts = floor_points(&scene, "floor", 16, 16, 0.05);
    if pts.is_empty() {
        anyhow::bail!("the scene has no mesh named `floor*`: the floor irradiance needs one");
    }
    pool.install(|| -> anyhow::Result<()> {
        let reference = reference(&args, &scene, &rt, &pts)?;
        let ref_mean = reference.image.mean().as_dvec3().element_sum() / 3.0;
        say!(
            args.json,
            "reference noise: RMSE {:.3e} ({:.2} % of the mean radiance {:.4})",
            reference.noise_rmse,
            100.0 * reference.noise_rmse / ref_mean,
            ref_mean
        );
        let direct: Vec<f64> = pts
            .iter()
            .map(|p| {
                let e = quadrature_irradiance(&scene, Some(&rt), p.position, p.normal, 16);
                (e.x as f64 + e.y as f64 + e.z as f64) / 3.0
            })
            .collect();
        let mut floor_csv = String::from("x,y,z,e_reference,e_direct_quadrature\n");
        for ((p, r), d) in pts.iter().zip(&reference.floor).zip(&direct) {
            let q = p.position;
            floor_csv += &format!("{},{},{},{r:.6e},{d:.6e}\n", q.x, q.y, q.z);
        }
        std::fs::write(args.out.join("floor.csv"), floor_csv)?;
        let mut rows = Vec::new();
        say!(
            args.json,
            "{:>9} {:>9} {:>5} {:>9} {:>8} {:>9} {:>9} {:>9} {:>9}",
            "mode",
            "N_MAX",
            "k",
            "photons",
            "time s",
            "rel RMSE",
            "map rel",
            "floor",
            "floor dir"
        );
        for &mode in &args.modes {
            for &n_max in &budgets {
                let k = k_for(n_max);
                let (maps, photons, trace_s, build_s) = trace(&scene, &rt, mode, n_max, args.seed)?;
                let t = Instant::now();
                let img = render(
                    &scene,
                    &rt,
                    Some(&maps),
                    &render_cfg(&args, args.spp, k, args.seed, View::Full),
                    &|_, _| {},
                )?;
                let render_s = t.elapsed().as_secs_f64();
                let map_view = View::Map {
                    primary_only: false,
                };
                let map_img = render(
                    &scene,
                    &rt,
                    Some(&maps),
                    &render_cfg(&args, args.spp, k, args.seed, map_view),
                    &|_, _| {},
                )?;
                let row = Row {
                    mode,
                    n_max,
                    k,
                    photons,
                    trace_s,
                    build_s,
                    render_s,
                    rmse: rmse(&img, &reference.image)?,
                    rel_rmse: relative_rmse(&img, &reference.image)?,
                    map_rel_rmse: relative_rmse(&map_img, &reference.image)?,
                    floor_rel_rmse: rel_rmse(
                        &floor_irradiance(&maps, false, &pts, k),
                        &reference.floor,
                    ),
                    floor_direct_rel_rmse: rel_rmse(
                        &floor_irradiance(&maps, true, &pts, k),
                        &direct,
                    ),
                };
                say!(
                    args.json,
                    "{:>9} {:>9} {:>5} {:>9} {:>8.3} {:>9.4} {:>9.4} {:>9.4} {:>9.4}",
                    mode.name(),
                    n_max,
                    k,
                    photons,
                    row.total_s(),
                    row.rel_rmse,
                    row.map_rel_rmse,
                    row.floor_rel_rmse,
                    row.floor_direct_rel_rmse
                );
                rows.push(row);
            }
        }
        write_csv(&args.out.join("tradeoff.csv"), &args.scene, &rows)?;
        plot(
            &args.out.join("tradeoff.png"),
            &args.scene,
            &rows,
            reference.noise_rmse / ref_mean,
        )?;
        let lines = summary(&rows, &args.modes, args.json);
        say!(
            args.json,
            "wrote {}/{{tradeoff.csv,floor.csv,tradeoff.png,reference.exr,reference.json}}",
            args.out.display()
        );
        if args.json {
            let rows: Vec<serde_json::Value> = rows
                .iter()
                .map(|r| {
                    let mut v = serde_json::to_value(r).unwrap_or_default();
                    v["total_s"] = json!(r.total_s());
                    v
                })
                .collect();
            println!(
                "{}",
                json!({
                    "scene": args.scene,
                    "reference_noise_rel": reference.noise_rmse / ref_mean,
                    "rows": rows,
                    "equal_time": lines,
                    "out_dir": args.out,
                })
            );
        }
        Ok(())
    })
}

fn write_csv(path: &Path, scene: &str, rows: &[Row]) -> anyhow::Result<()> {
    let mut f = std::io::BufWriter::new(
        std::fs::File::create(path).with_context(|| path.display().to_string())?,
    );
    writeln!(f, "scene,mode,n_max,k,photons,trace_s,build_s,render_s,total_s,rmse,rel_rmse,map_rel_rmse,floor_rel_rmse,floor_direct_rel_rmse")?;
    for r in rows {
        writeln!(
            f,
            "{scene},{},{},{},{},{:.4},{:.4},{:.4},{:.4},{:.6e},{:.6},{:.6},{:.6},{:.6}",
            r.mode.name(),
            r.n_max,
            r.k,
            r.photons,
            r.trace_s,
            r.build_s,
            r.render_s,
            r.total_s(),
            r.rmse,
            r.rel_rmse,
            r.map_rel_rmse,
            r.floor_rel_rmse,
            r.floor_direct_rel_rmse
        )?;
    }
    Ok(())
}

/// `(time, rel_rmse)` of one mode, by time.
fn curve(rows: &[Row], mode: Mode) -> Vec<(f64, f64)> {
    let mut c: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.mode == mode)
        .map(|r| (r.total_s(), r.rel_rmse))
        .filter(|(t, e)| *t > 0.0 && *e > 0.0)
        .collect();
    c.sort_by(|a, b| a.0.total_cmp(&b.0));
    c
}

/// Error at time `t` by log-log interpolation; `None` outside the curve.
fn at_time(c: &[(f64, f64)], t: f64) -> Option<f64> {
    c.windows(2).find(|w| w[0].0 <= t && t <= w[1].0).map(|w| {
        let (t0, e0, t1, e1) = (w[0].0.ln(), w[0].1.ln(), w[1].0.ln(), w[1].1.ln());
        let f = if t1 > t0 {
            (t.ln() - t0) / (t1 - t0)
        } else {
            0.0
        };
        (e0 + f * (e1 - e0)).exp()
    })
}

/// Prints, and returns, the equal-time comparison.
fn summary(rows: &[Row], modes: &[Mode], json: bool) -> Vec<String> {
    let mut lines = Vec::new();
    let curves: Vec<(Mode, Vec<(f64, f64)>)> = modes.iter().map(|&m| (m, curve(rows, m))).collect();
    let lo = curves
        .iter()
        .filter_map(|(_, c)| c.first().map(|p| p.0))
        .fold(0.0, f64::max);
    let hi = curves
        .iter()
        .filter_map(|(_, c)| c.last().map(|p| p.0))
        .fold(f64::INFINITY, f64::min);
    if curves.len() < 2 || lo.partial_cmp(&hi) != Some(std::cmp::Ordering::Less) {
        say!(
            json,
            "summary: the modes' time ranges do not overlap; compare the table"
        );
        return lines;
    }
    say!(
        json,
        "at equal time (log-log interpolation of relative RMSE):"
    );
    for f in [0.1, 0.5, 0.9] {
        let t = (lo.ln() + f * (hi.ln() - lo.ln())).exp();
        let mut errs: Vec<(Mode, f64)> = curves
            .iter()
            .filter_map(|(m, c)| at_time(c, t).map(|e| (*m, e)))
            .collect();
        errs.sort_by(|a, b| a.1.total_cmp(&b.1));
        let Some(&(best, e)) = errs.first() else {
            continue;
        };
        let others: Vec<String> = errs[1..]
            .iter()
            .map(|(m, x)| format!("{} {:.4} (x{:.2})", m.name(), x, x / e))
            .collect();
        let line = format!(
            "t = {t:.2} s: {} lowest, {:.4}; {}",
            best.name(),
            e,
            others.join(", ")
        );
        say!(json, "  {line}");
        lines.push(line);
    }
    lines
}

fn plot(path: &Path, scene: &str, rows: &[Row], reference_noise: f64) -> anyhow::Result<()> {
    adaptive_pm::experiments::plot::register_font()?;
    let pts: Vec<(f64, f64)> = rows
        .iter()
        .map(|r| (r.total_s(), r.rel_rmse))
        .filter(|p| p.0 > 0.0 && p.1 > 0.0)
        .collect();
    if pts.is_empty() {
        return Ok(());
    }
    let (t0, t1) = pts
        .iter()
        .fold((f64::INFINITY, 0.0f64), |a, p| (a.0.min(p.0), a.1.max(p.0)));
    let (e0, e1) = pts
        .iter()
        .fold((f64::INFINITY, 0.0f64), |a, p| (a.0.min(p.1), a.1.max(p.1)));
    let e0 = e0.min(reference_noise.max(1e-6));
    let root = BitMapBackend::new(path, (900, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(format!("{scene}: image error vs time"), ("sans-serif", 24))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(
            (t0 * 0.8..t1 * 1.25).log_scale(),
            (e0 * 0.8..e1 * 1.25).log_scale(),
        )
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    chart
        .configure_mesh()
        .x_desc("trace + kd-trees + render (s)")
        .y_desc("relative RMSE vs reference")
        .x_label_formatter(&|v| format!("{v:.3}"))
        .y_label_formatter(&|v| format!("{v:.3}"))
        .draw()
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    let colors = [
        RGBColor(31, 119, 180),
        RGBColor(214, 39, 40),
        RGBColor(44, 160, 44),
    ];
    for (i, mode) in Mode::ALL.iter().enumerate() {
        let c = curve(rows, *mode);
        if c.is_empty() {
            continue;
        }
        let color = colors[i % colors.len()];
        chart
            .draw_series(LineSeries::new(c.clone(), color.stroke_width(2)))
            .map_err(|e| anyhow::anyhow!("{e}"))?
            .label(mode.name())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
            });
        chart
            .draw_series(c.iter().map(|p| Circle::new(*p, 4, color.filled())))
            .map_err(|e| anyhow::anyhow!("{e}"))?;
    }
    chart
        .draw_series(LineSeries::new(
            vec![(t0 * 0.8, reference_noise), (t1 * 1.25, reference_noise)],
            BLACK.stroke_width(1),
        ))
        .map_err(|e| anyhow::anyhow!("{e}"))?
        .label("reference noise")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    root.present().map_err(|e| anyhow::anyhow!("{e}"))?;
    Ok(())
}
