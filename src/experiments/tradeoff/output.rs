//! The study's files: `tradeoff.json` (the `--json` object), `runs.csv`,
//! `groups.csv`, and log-log charts (log10 on both axes, drawn by
//! [`crate::experiments::plot`]): indirect and points error against time,
//! against map memory, and error and time against Q (the knob's calibration).

use super::summary::{Group, Level};
use super::{Contender, TradeoffResults};
use crate::error::{Error, Result};
use crate::experiments::plot::{write_plot, Plot, RefLine, Series};
use serde_json::{json, Value};
use std::fmt::Write as _;
use std::path::Path;

/// The `--json` object: `reference`, `runs`, `equal_time`, `equal_memory`,
/// and the groups, the estimate's tracking, threads and time.
pub fn to_json(r: &TradeoffResults) -> Value {
    json!({
        "scene": r.scene,
        "reference": r.reference,
        "runs": r.runs,
        "equal_time": r.equal_time,
        "equal_memory": r.equal_memory,
        "groups": r.groups,
        "estimate_tracking": r.estimate_tracking,
        "threads": r.threads,
        "elapsed_s": r.elapsed_s,
    })
}

fn io(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::param("output", format!("{}: {e}", path.display()))
}

/// Writes the JSON, the CSVs and the charts into `dir` (created).
///
/// # Errors
/// When a file cannot be written.
pub fn write_outputs(r: &TradeoffResults, dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| io(dir, e))?;
    let write = |name: &str, text: String| {
        let p = dir.join(name);
        std::fs::write(&p, text).map_err(|e| io(&p, e))
    };
    write(
        "tradeoff.json",
        serde_json::to_string_pretty(&to_json(r)).unwrap_or_default(),
    )?;
    let mut csv = String::from("scene,mode,quality,n_max,seed,photons,k,trace_s,importance_s,build_s,render_s,time_s,map_bytes,indirect_rel_rmse,image_rel_rmse,points_rel_err,estimated_rel_err,read_share,read_share_pixels\n");
    for x in &r.runs {
        let _ = writeln!(
            csv,
            "{},{},{:.6},{},{},{},{},{:.4},{:.4},{:.4},{:.4},{:.4},{},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6}",
            r.scene,
            x.mode.name(),
            x.quality,
            x.n_max,
            x.seed,
            x.photons,
            x.k,
            x.trace_s,
            x.importance_s,
            x.build_s,
            x.render_s,
            x.time_s,
            x.map_bytes,
            x.indirect_rel_rmse,
            x.image_rel_rmse,
            x.points_rel_err,
            x.estimated_rel_err,
            x.read_share,
            x.read_share_pixels
        );
    }
    write("runs.csv", csv)?;
    let mut csv = String::from("scene,mode,quality,n_max,time_s,map_bytes,indirect_mean,indirect_bias,indirect_spread,image_mean,image_bias,image_spread,points_mean,points_bias,points_spread,read_share,read_share_pixels\n");
    for g in &r.groups {
        let _ = writeln!(
            csv,
            "{},{},{:.6},{},{:.4},{:.0},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6}",
            r.scene,
            g.mode.name(),
            g.quality,
            g.n_max,
            g.time_s,
            g.map_bytes,
            g.indirect.mean,
            g.indirect.bias,
            g.indirect.spread,
            g.image.mean,
            g.image.bias,
            g.image.spread,
            g.points.mean,
            g.points.bias,
            g.points.spread,
            g.read_share,
            g.read_share_pixels
        );
    }
    write("groups.csv", csv)?;
    charts(r, dir)
}

fn series(groups: &[Group], x: fn(&Group) -> f64, y: fn(&Group) -> f64) -> Vec<Series> {
    Contender::ALL
        .iter()
        .map(|m| Series {
            name: m.name().to_string(),
            points: groups
                .iter()
                .filter(|g| g.mode == *m && x(g) > 0.0 && y(g) > 0.0)
                .map(|g| (x(g).log10(), y(g).log10()))
                .collect(),
        })
        .filter(|s| !s.points.is_empty())
        .collect()
}

fn charts(r: &TradeoffResults, dir: &Path) -> Result<()> {
    let g = &r.groups;
    let noise = |v: f64, name: &str| {
        (v > 0.0).then(|| RefLine {
            name: format!("{name} (log10)"),
            y: v.log10(),
        })
    };
    let time = format!("log10 trace + kd-trees + render (s), {} threads", r.threads);
    let plots = [
        (
            "indirect_vs_time",
            "indirect light: error vs time",
            time.clone(),
            "log10 relative RMSE (indirect, non-light pixels)",
            series(g, |g| g.time_s, |g| g.indirect.mean),
            noise(r.reference.noise, "reference noise"),
        ),
        (
            "indirect_vs_memory",
            "indirect light: error vs map memory",
            "log10 bytes of the kept maps".to_string(),
            "log10 relative RMSE (indirect, non-light pixels)",
            series(g, |g| g.map_bytes, |g| g.indirect.mean),
            noise(r.reference.noise, "reference noise"),
        ),
        (
            "points_vs_time",
            "irradiance at fixed points from the map alone vs time",
            time.clone(),
            "log10 relative RMSE (points)",
            series(g, |g| g.time_s, |g| g.points.mean),
            noise(r.reference.points_noise, "reference noise"),
        ),
        (
            "error_vs_quality",
            "the knob: indirect error vs Q",
            "log10 Q".to_string(),
            "log10 relative RMSE (indirect)",
            series(g, |g| g.quality, |g| g.indirect.mean),
            None,
        ),
        (
            "time_vs_quality",
            "the knob: time vs Q",
            "log10 Q".to_string(),
            "log10 seconds",
            series(g, |g| g.quality, |g| g.time_s),
            None,
        ),
    ];
    for (stem, title, x, y, series, line) in plots {
        let plot = Plot {
            title: format!("{}: {title}", r.scene),
            x_label: x,
            y_label: y.to_string(),
            series,
            lines: line.into_iter().collect(),
            // The values are log10 already (the axes say so).
            log_y: false,
        };
        write_plot(&dir.join(stem), &plot)?;
    }
    Ok(())
}

fn level_line(l: &Level, unit: &str) -> String {
    let mut errs: Vec<(&String, &f64)> = l.errors.iter().collect();
    errs.sort_by(|a, b| a.1.total_cmp(b.1));
    let Some((best, e)) = errs.first() else {
        return format!(
            "level {}: no mode measured near {:.3} {unit}",
            l.level, l.at
        );
    };
    let others: Vec<String> = errs[1..]
        .iter()
        .map(|(m, x)| format!("{m} {x:.4} (x{:.2})", *x / *e))
        .collect();
    format!(
        "level {} ({:.3} {unit}): {best} lowest indirect error {e:.4}; {}",
        l.level,
        l.at,
        others.join(", ")
    )
}

/// A plain-text summary: reference, per-group table, comparisons, tracking.
pub fn summary_text(r: &TradeoffResults) -> String {
    let mut s = String::new();
    let ri = &r.reference;
    let _ = writeln!(
        s,
        "reference: path tracer, {} spp, noise {:.4} (indirect) {:.4} (image) {:.4} (points){}",
        ri.spp,
        ri.noise,
        ri.image_noise,
        ri.points_noise,
        if ri.cached { ", from the cache" } else { "" }
    );
    let _ = writeln!(
        s,
        "{:>9} {:>8} {:>8} {:>10} {:>8} {:>7} {:>7} {:>8} {:>7} {:>7} {:>6} {:>6}",
        "mode",
        "N_MAX",
        "time s",
        "map bytes",
        "indirect",
        "bias",
        "spread",
        "points",
        "bias",
        "spread",
        "read",
        "px"
    );
    for g in &r.groups {
        let _ = writeln!(
            s,
            "{:>9} {:>8} {:>8.3} {:>10.0} {:>8.4} {:>7.4} {:>7.4} {:>8.4} {:>7.4} {:>7.4} {:>6.3} {:>6.3}",
            g.mode.name(),
            g.n_max,
            g.time_s,
            g.map_bytes,
            g.indirect.mean,
            g.indirect.bias,
            g.indirect.spread,
            g.points.mean,
            g.points.bias,
            g.points.spread,
            g.read_share,
            g.read_share_pixels
        );
    }
    let _ = writeln!(s, "equal time ({} threads):", r.threads);
    for l in &r.equal_time {
        let _ = writeln!(s, "  {}", level_line(l, "s"));
    }
    let _ = writeln!(s, "equal memory:");
    for l in &r.equal_memory {
        let _ = writeln!(s, "  {}", level_line(l, "bytes"));
    }
    let t = &r.estimate_tracking;
    let _ = writeln!(
        s,
        "half-map error estimate: true/estimated points error over {} runs: median {:.2} (min {:.2}, max {:.2})",
        t.runs, t.median_ratio, t.min_ratio, t.max_ratio
    );
    s
}
