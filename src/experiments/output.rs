//! The files of a Cornell sweep: one CSV per figure, `runs.csv` with every
//! metric of every run, `alpha_d.csv`, `summary.json` (results and claims), a
//! `README.txt` naming every column and unit, and each figure as SVG and PNG.
//!
//! CSV cells are plain numbers in Rust's shortest round-trip form; a mode left
//! out of the sweep leaves its column empty. Densities are photons per mm^2
//! (the built-in box is in millimetres), times are seconds.

use super::claims::{check_claims, judged_rates};
use super::cornell::{CornellResults, RunMetrics};
use super::plot::{write_plot, Plot, RefLine, Series};
use crate::engine::Mode;
use crate::error::{Error, Result};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The CSV files, in the order they are written.
pub const CSV_FILES: [&str; 7] = [
    "fig7a_max_density.csv",
    "fig7b_build_time.csv",
    "fig8_reemitted.csv",
    "fig9a_sigma_density.csv",
    "fig9b_split_rate.csv",
    "runs.csv",
    "alpha_d.csv",
];

/// The plots (each written as `.svg` and `.png`).
pub const PLOT_STEMS: [&str; 7] = [
    "fig7a_max_density",
    "fig7b_build_time",
    "fig8_reemitted",
    "fig9a_sigma_density",
    "fig9a_sigma_over_mean",
    "fig9b_split_rate",
    "alpha_d_ratio",
];

/// How many `n` values Fig. 9b draws a curve for.
pub const FIG9B_CURVES: usize = 4;

fn io(path: &Path, source: std::io::Error) -> Error {
    Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

fn write(dir: &Path, name: &str, text: &str) -> Result<PathBuf> {
    let p = dir.join(name);
    // Hook (issue 12): atomic, exclusive, regular-file-only write.
    crate::output::write_bytes(&p, text.as_bytes())?;
    Ok(p)
}

fn csv(header: &[&str], rows: impl IntoIterator<Item = Vec<String>>) -> String {
    let mut s = header.join(",");
    s.push('\n');
    for r in rows {
        s.push_str(&r.join(","));
        s.push('\n');
    }
    s
}

fn cell(v: Option<f64>) -> String {
    v.map_or(String::new(), |x| x.to_string())
}

fn per_mode(r: &CornellResults, i: usize, get: fn(&RunMetrics) -> f64) -> Vec<String> {
    Mode::ALL
        .iter()
        .map(|&m| cell(r.run(i, m).map(get)))
        .collect()
}

fn series(r: &CornellResults, get: fn(&RunMetrics) -> f64) -> Vec<Series> {
    r.modes
        .iter()
        .map(|&m| Series {
            name: m.name().to_string(),
            points: r.mode_runs(m).iter().map(|x| (x.n, get(x))).collect(),
        })
        .collect()
}

const RUN_COLUMNS: [&str; 36] = [
    "role",
    "scene",
    "n",
    "mode",
    "n_max",
    "emitted",
    "stored",
    "stored_primary",
    "reemitted_first_hit",
    "max_density_primary",
    "max_density_primary_mesh",
    "max_density_primary_at",
    "mean_density_primary",
    "sigma_density_primary",
    "sigma_over_mean_primary",
    "max_density",
    "mean_density",
    "sigma_density",
    "sigma_over_mean",
    "trace_s",
    "trace_primary_s",
    "build_s",
    "build_primary_s",
    "primary_map_time_s",
    "measure_s",
    "budget_bound",
    "capped_hits",
    "density_rejected",
    "alpha_d",
    "alpha_d_paper",
    "alpha_d_peak",
    "ratio_paper",
    "ratio_peak",
    "split_rate_by_depth",
    "hits_by_depth",
    "seed",
];

fn run_row(role: &str, scene: &str, x: &RunMetrics, seed: u64) -> Vec<String> {
    let k = (x.n + 2.0) / 2.0;
    let join = |v: Vec<String>| v.join(";");
    vec![
        role.into(),
        scene.into(),
        x.n.to_string(),
        x.mode.name().into(),
        x.n_max.to_string(),
        x.emitted.to_string(),
        x.stored.to_string(),
        x.stored_primary.to_string(),
        x.reemitted_first_hit.to_string(),
        x.max_density_primary.to_string(),
        x.max_density_primary_mesh.clone(),
        join(
            x.max_density_primary_at
                .iter()
                .map(f64::to_string)
                .collect(),
        ),
        x.mean_density_primary.to_string(),
        x.sigma_density_primary.to_string(),
        x.sigma_over_mean_primary.to_string(),
        x.max_density.to_string(),
        x.mean_density.to_string(),
        x.sigma_density.to_string(),
        x.sigma_over_mean.to_string(),
        x.trace_s.to_string(),
        x.trace_primary_s.to_string(),
        x.build_s.to_string(),
        x.build_primary_s.to_string(),
        x.primary_map_time_s.to_string(),
        x.measure_s.to_string(),
        x.budget_bound.to_string(),
        x.capped_hits.to_string(),
        x.density_rejected.to_string(),
        x.alpha_d.to_string(),
        x.alpha_d_paper.to_string(),
        x.alpha_d_peak.to_string(),
        (x.alpha_d_paper * k).to_string(),
        (x.alpha_d_peak * k).to_string(),
        join(x.split_rate_by_depth.iter().map(f64::to_string).collect()),
        join(x.hits_by_depth.iter().map(u64::to_string).collect()),
        seed.to_string(),
    ]
}

/// The `n` values whose split rates Fig. 9b draws: up to [`FIG9B_CURVES`]
/// spread evenly over the sweep (first and last included).
pub fn fig9b_indices(count: usize) -> Vec<usize> {
    if count <= FIG9B_CURVES {
        return (0..count).collect();
    }
    let mut v: Vec<usize> = (0..FIG9B_CURVES)
        .map(|j| j * (count - 1) / (FIG9B_CURVES - 1))
        .collect();
    v.dedup();
    v
}

const README: &str = "\
Cornell box sweep of `adaptive-pm bench cornell` (docs/method.md, The experiments).
x = n, the exponent of the light's cos^n radiance. Densities: photons per mm^2
(k = 50 nearest photons, 4096 fixed area-uniform points). Times: seconds.
The reference is the classic mode with a diffuse light (n = 0).

fig7a_max_density.csv    max density of the primary map (first hits only) per mode; reference
fig7b_build_time.csv     time to have the primary map = trace of wave 0 + its kd-tree build
fig8_reemitted.csv       photons re-emitted after the first hit (adaptive) and N_MAX
fig9a_sigma_density.csv  standard deviation of the full map's density, and sigma/mean, per mode
fig9b_split_rate.csv     adaptive mode, long format: n, depth, hits, mean children per hit;
                         paths_stop = 1 at the depth limit, where the rate is 0 by construction
runs.csv                 every metric of every run (role = reference or sweep); split rates and
                         hits per depth joined by ';'; ratio_* = alpha_D * (n + 2) / 2;
                         max_density_primary_mesh / _at: the mesh and the point (x;y;z) of the
                         primary map's max density
alpha_d.csv              alpha_D of the light by both estimators and alpha_D * (n + 2) / 2
                         (1 keeps the peak density of the emitted directions equal to a diffuse light's)
summary.json             every number above, the claims and their verdicts
claims.md                the claims as a Markdown table (the README's results tables)
*.svg, *.png             the figures
";

/// Writes every file into `dir` (created with its parents) and returns their paths.
///
/// # Errors
/// [`Error::Io`] naming the directory or file that could not be created or written.
pub fn write_outputs(r: &CornellResults, dir: &Path) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).map_err(|e| io(dir, e))?;
    let mut files = write_density_tables(r, dir)?;
    files.extend(write_run_tables(r, dir)?);
    let claims = check_claims(r);
    let summary = serde_json::json!({ "results": r, "claims": claims });
    files.push(write(dir, "summary.json", &summary.to_string())?);
    files.push(write(dir, "claims.md", &claims_markdown(r))?);
    files.push(write(dir, "README.txt", README)?);

    for (stem, plot) in PLOT_STEMS.iter().zip(&figures(r)) {
        let p = dir.join(stem);
        write_plot(&p, plot)?;
        files.push(p.with_extension("svg"));
        files.push(p.with_extension("png"));
    }
    Ok(files)
}

/// The density figures' tables (Fig. 7a, 7b, 8, 9a): `CSV_FILES[0..4]`.
fn write_density_tables(r: &CornellResults, dir: &Path) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    let ns = || 0..r.n_values.len();
    let reference = r.reference_max_density();
    let rows = ns().map(|i| {
        let mut v = vec![r.n_values[i].to_string()];
        v.extend(per_mode(r, i, |x| x.max_density_primary));
        v.push(reference.to_string());
        v
    });
    files.push(write(
        dir,
        CSV_FILES[0],
        &csv(&["n", "classic", "density", "adaptive", "reference"], rows),
    )?);

    let rows = ns().map(|i| {
        let mut v = vec![r.n_values[i].to_string()];
        v.extend(per_mode(r, i, |x| x.primary_map_time_s));
        v
    });
    files.push(write(
        dir,
        CSV_FILES[1],
        &csv(&["n", "classic_s", "density_s", "adaptive_s"], rows),
    )?);

    let rows = ns().map(|i| {
        vec![
            r.n_values[i].to_string(),
            cell(
                r.run(i, Mode::Adaptive)
                    .map(|x| x.reemitted_first_hit as f64),
            ),
            r.n_max.to_string(),
        ]
    });
    files.push(write(
        dir,
        CSV_FILES[2],
        &csv(&["n", "adaptive_reemitted", "n_max"], rows),
    )?);

    let rows = ns().map(|i| {
        let mut v = vec![r.n_values[i].to_string()];
        v.extend(per_mode(r, i, |x| x.sigma_density));
        v.extend(per_mode(r, i, |x| x.sigma_over_mean));
        v.push(r.reference.sigma_density.to_string());
        v.push(r.reference.sigma_over_mean.to_string());
        v
    });
    files.push(write(
        dir,
        CSV_FILES[3],
        &csv(
            &[
                "n",
                "classic_sigma",
                "density_sigma",
                "adaptive_sigma",
                "classic_sigma_over_mean",
                "density_sigma_over_mean",
                "adaptive_sigma_over_mean",
                "reference_sigma",
                "reference_sigma_over_mean",
            ],
            rows,
        ),
    )?);

    Ok(files)
}

/// The split rates by depth, every run's row and the light's alpha_D:
/// `CSV_FILES[4..7]`.
fn write_run_tables(r: &CornellResults, dir: &Path) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    let adaptive = r.mode_runs(Mode::Adaptive);
    let mut rows = Vec::new();
    for x in &adaptive {
        for (d, (rate, hits)) in x
            .split_rate_by_depth
            .iter()
            .zip(&x.hits_by_depth)
            .enumerate()
        {
            rows.push(vec![
                x.n.to_string(),
                d.to_string(),
                hits.to_string(),
                rate.to_string(),
                u8::from(d as u32 >= r.max_depth).to_string(),
            ]);
        }
    }
    files.push(write(
        dir,
        CSV_FILES[4],
        &csv(&["n", "depth", "hits", "split_rate", "paths_stop"], rows),
    )?);

    let rows = std::iter::once(run_row("reference", &r.scene, &r.reference, r.seed))
        .chain(r.runs.iter().map(|x| run_row("sweep", &r.scene, x, r.seed)));
    files.push(write(dir, CSV_FILES[5], &csv(&RUN_COLUMNS, rows))?);

    let rows = r.alpha.iter().map(|a| {
        vec![
            a.n.to_string(),
            a.alpha_d_paper.to_string(),
            a.alpha_d_peak.to_string(),
            a.ratio_paper.to_string(),
            a.ratio_peak.to_string(),
        ]
    });
    files.push(write(
        dir,
        CSV_FILES[6],
        &csv(
            &[
                "n",
                "alpha_d_paper",
                "alpha_d_peak",
                "ratio_paper",
                "ratio_peak",
            ],
            rows,
        ),
    )?);

    Ok(files)
}

/// The paper's figures 7 to 9 and the light's alpha_D, in [`PLOT_STEMS`] order.
fn figures(r: &CornellResults) -> Vec<Plot> {
    let reference = r.reference_max_density();
    let adaptive = r.mode_runs(Mode::Adaptive);
    let sweep = format!("{}, N_MAX = {}, seed {}", r.scene, r.n_max, r.seed);
    let ref_name = |what: &str, y: f64| {
        format!(
            "reference {what} = {y:.3e} (classic, diffuse light, {})",
            r.scene
        )
    };
    let x_label = "n (exponent of the light's cos^n radiance)".to_string();
    vec![
        Plot {
            title: format!("Fig. 7a: max density of the primary map ({sweep})"),
            x_label: x_label.clone(),
            y_label: "max density (photons / mm^2, log scale)".into(),
            series: series(r, |x| x.max_density_primary),
            lines: vec![RefLine {
                name: ref_name("max", reference),
                y: reference,
            }],
            log_y: true,
        },
        Plot {
            title: format!("Fig. 7b: time to build the primary map ({sweep})"),
            x_label: x_label.clone(),
            y_label: "trace of first hits + kd-tree (s, log scale)".into(),
            series: series(r, |x| x.primary_map_time_s),
            lines: vec![],
            log_y: true,
        },
        Plot {
            title: format!("Fig. 8: photons re-emitted after the first hit ({sweep})"),
            x_label: x_label.clone(),
            y_label: "photons re-emitted".into(),
            series: vec![Series {
                name: "adaptive".into(),
                points: adaptive
                    .iter()
                    .map(|x| (x.n, x.reemitted_first_hit as f64))
                    .collect(),
            }],
            lines: vec![RefLine {
                name: "N_MAX".into(),
                y: r.n_max as f64,
            }],
            log_y: false,
        },
        Plot {
            title: format!("Fig. 9a: sigma of the full map's density ({sweep})"),
            x_label: x_label.clone(),
            y_label: "sigma of density (photons / mm^2, log scale)".into(),
            series: series(r, |x| x.sigma_density),
            lines: vec![RefLine {
                name: ref_name("sigma", r.reference.sigma_density),
                y: r.reference.sigma_density,
            }],
            log_y: true,
        },
        Plot {
            title: format!("Fig. 9a (normalised): sigma / mean of the density ({sweep})"),
            x_label: x_label.clone(),
            y_label: "sigma / mean of density (1)".into(),
            series: series(r, |x| x.sigma_over_mean),
            lines: vec![RefLine {
                name: ref_name("sigma / mean", r.reference.sigma_over_mean),
                y: r.reference.sigma_over_mean,
            }],
            log_y: false,
        },
        Plot {
            title: format!("Fig. 9b: mean split rate by depth, adaptive ({sweep})"),
            x_label: "bounce depth (0 = first hit)".into(),
            y_label: "children per hit (log scale)".into(),
            series: fig9b_indices(adaptive.len())
                .into_iter()
                .map(|i| Series {
                    name: format!("n = {}", adaptive[i].n),
                    points: judged_rates(adaptive[i], r.max_depth)
                        .into_iter()
                        .map(|(d, rate, _)| (d as f64, rate))
                        .collect(),
                })
                .collect(),
            lines: vec![RefLine {
                name: "1 child per hit".into(),
                y: 1.0,
            }],
            log_y: true,
        },
        Plot {
            title: "alpha_D(n) (n + 2) / 2 of the light, both estimators".into(),
            x_label,
            y_label: "alpha_D (n + 2) / 2 (1)".into(),
            series: vec![
                Series {
                    name: "paper estimator".into(),
                    points: r.alpha.iter().map(|a| (a.n, a.ratio_paper)).collect(),
                },
                Series {
                    name: "peak-density estimator".into(),
                    points: r.alpha.iter().map(|a| (a.n, a.ratio_peak)).collect(),
                },
            ],
            lines: vec![RefLine {
                name: "1 = peak density kept".into(),
                y: 1.0,
            }],
            log_y: false,
        },
    ]
}

/// The claims as a Markdown table (written as `claims.md`; the README's
/// results tables are these files, pasted unedited).
pub fn claims_markdown(r: &CornellResults) -> String {
    let mut s = format!(
        "Scene `{}`, N_MAX = {}, seed {}, n = {}..{} ({} values), {} estimator.\n\n\
         | fig. | verdict | paper | measured |\n|---|---|---|---|\n",
        r.scene,
        r.n_max,
        r.seed,
        r.n_values.first().copied().unwrap_or(0.0),
        r.n_values.last().copied().unwrap_or(0.0),
        r.n_values.len(),
        r.estimator
    );
    let esc = |t: &str| t.replace('|', "\\|");
    for c in check_claims(r) {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} |",
            c.figure,
            c.verdict.word(),
            esc(c.paper),
            esc(&c.measured)
        );
    }
    s
}

/// The claims as a fixed-width text table, one claim per block.
pub fn claims_table(r: &CornellResults) -> String {
    let mut s = String::new();
    for c in check_claims(r) {
        let _ = writeln!(
            s,
            "{:<5} {:<9} paper:    {}",
            c.figure,
            c.verdict.word(),
            c.paper
        );
        let _ = writeln!(s, "{:<15} measured: {}", "", c.measured);
    }
    s
}
