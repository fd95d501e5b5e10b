//! The Cornell sweep on three exponents at a small N_MAX: every file is
//! written and parses, and the paper's qualitative claims hold with margins
//! derived from the sampling error (see each test).

use adaptive_pm::engine::Mode;
use adaptive_pm::experiments::claims::{judged_rates, DENSITY_FACTOR};
use adaptive_pm::experiments::cornell::{run_cornell, CornellConfig, CornellResults};
use adaptive_pm::experiments::output::{write_outputs, CSV_FILES, PLOT_STEMS};
use adaptive_pm::experiments::sweep::parse_sweep;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// Large enough that even at n = 200 (alpha_D ~ 0.017) the adaptive mode's
/// first hits (~340) pass the 100-hit floor under which a depth's split rate
/// is not judged (`judged_rates`).
const N_MAX: u64 = 20_000;

/// One sweep shared by every test of this file (tests run in one process).
fn sweep() -> &'static (CornellResults, tempfile::TempDir, Vec<PathBuf>) {
    static S: OnceLock<(CornellResults, tempfile::TempDir, Vec<PathBuf>)> = OnceLock::new();
    S.get_or_init(|| {
        let mut cfg = CornellConfig::paper();
        cfg.n_values = parse_sweep("0,20,200").unwrap();
        cfg.n_max = N_MAX;
        cfg.seed = crate::common::seed(1);
        let r = run_cornell(&cfg, &|_| {}).unwrap();
        for x in &r.runs {
            eprintln!("XC {:?} n {} emitted {} maxdp {:.4e} reemit {} alpha {:.4} paper {:.4} rates {:?} hits {:?}", x.mode, x.n, x.emitted, x.max_density_primary, x.reemitted_first_hit, x.alpha_d, x.alpha_d_paper, x.split_rate_by_depth, x.hits_by_depth);
        }
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("nested/out");
        let files = write_outputs(&r, &out).unwrap();
        (r, dir, files)
    })
}

fn out_dir() -> PathBuf {
    sweep().1.path().join("nested/out")
}

/// Header and rows of a CSV file.
fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    for r in &rows {
        assert_eq!(
            r.len(),
            header.len(),
            "{}: ragged row {r:?}",
            path.display()
        );
    }
    (header, rows)
}

fn numeric(rows: &[Vec<String>], skip: &[usize]) {
    for r in rows {
        for (i, c) in r.iter().enumerate() {
            if !skip.contains(&i) {
                let v: f64 = c.parse().unwrap_or_else(|_| panic!("cell `{c}` of {r:?}"));
                assert!(v.is_finite() && v >= 0.0, "{r:?}");
            }
        }
    }
}

#[test]
fn every_file_is_written_and_every_csv_parses() {
    let (r, _, files) = sweep();
    let dir = out_dir();
    for f in CSV_FILES.iter().chain(&["summary.json", "README.txt"]) {
        assert!(files.contains(&dir.join(f)), "{f} not listed");
    }
    for stem in PLOT_STEMS {
        let svg = std::fs::read_to_string(dir.join(stem).with_extension("svg")).unwrap();
        assert!(svg.contains("<svg") && svg.contains("</svg>"), "{stem}.svg");
        let png = std::fs::read(dir.join(stem).with_extension("png")).unwrap();
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "{stem}.png");
    }
    let per_n = |name: &str, cols: usize| {
        let (h, rows) = read_csv(&dir.join(name));
        assert_eq!(h.len(), cols, "{name}: {h:?}");
        assert_eq!(h[0], "n");
        assert_eq!(rows.len(), 3, "{name}");
        numeric(&rows, &[]);
        let ns: Vec<f64> = rows.iter().map(|r| r[0].parse().unwrap()).collect();
        assert_eq!(ns, [0.0, 20.0, 200.0], "{name}");
        rows
    };
    let fig7a = per_n("fig7a_max_density.csv", 5);
    // the reference column is the classic diffuse run, which is the n = 0 classic row
    assert_eq!(fig7a[0][1], fig7a[0][4]);
    per_n("fig7b_build_time.csv", 4);
    let fig8 = per_n("fig8_reemitted.csv", 3);
    assert!(fig8.iter().all(|row| row[2] == N_MAX.to_string()));
    per_n("fig9a_sigma_density.csv", 9);
    per_n("alpha_d.csv", 5);

    let (h, rows) = read_csv(&dir.join("fig9b_split_rate.csv"));
    assert_eq!(h, ["n", "depth", "hits", "split_rate", "paths_stop"]);
    numeric(&rows, &[]);
    let depths: usize = r
        .mode_runs(Mode::Adaptive)
        .iter()
        .map(|x| x.split_rate_by_depth.len())
        .sum();
    assert_eq!(rows.len(), depths);

    let (h, rows) = read_csv(&dir.join("runs.csv"));
    assert_eq!(rows.len(), 1 + 3 * 3, "the reference and 9 runs");
    assert_eq!(rows[0][0], "reference");
    let col = |name: &str| h.iter().position(|c| c == name).unwrap();
    let text_cols = [
        col("role"),
        col("scene"),
        col("max_density_primary_mesh"),
        col("max_density_primary_at"),
        col("mode"),
        col("budget_bound"),
        col("split_rate_by_depth"),
        col("hits_by_depth"),
    ];
    numeric(&rows, &text_cols);
    for row in &rows {
        for s in row[col("split_rate_by_depth")].split(';') {
            assert!(s.parse::<f64>().unwrap() >= 0.0);
        }
        // Fig. 7b's time is the trace of the first hits plus the primary kd-tree
        let t: f64 = row[col("primary_map_time_s")].parse().unwrap();
        let a: f64 = row[col("trace_primary_s")].parse().unwrap();
        let b: f64 = row[col("build_primary_s")].parse().unwrap();
        assert!((t - a - b).abs() <= 1e-9 * t.max(1.0));
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["results"]["runs"].as_array().unwrap().len(), 9);
    assert!(!summary["claims"].as_array().unwrap().is_empty());
}

/// Adaptive emission is `alpha_D(n) N_MAX`. The value that keeps the peak
/// density is `2 / (n + 2)`: 1, 0.091, 0.0099 at n = 0, 20, 200, factors of
/// 11 and 10 apart. The paper's estimator varies by ~10 % between seeds
/// (AnalysisParams docs) and overshoots `2 / (n + 2)` by at most ~2.5x here,
/// so demanding a factor 2 at each step leaves a wide margin on both sides.
#[test]
fn adaptive_emits_fewer_primary_photons_as_n_grows() {
    let (r, ..) = sweep();
    let e: Vec<u64> = r
        .mode_runs(Mode::Adaptive)
        .iter()
        .map(|x| x.emitted)
        .collect();
    assert_eq!(e[0], N_MAX, "a diffuse light has alpha_D = 1");
    assert!(e[1] * 2 < e[0] && e[2] * 2 < e[1], "{e:?}");
    // classic always emits N_MAX
    assert!(r
        .mode_runs(Mode::Classic)
        .iter()
        .all(|x| x.emitted == N_MAX));
}

/// The classic primary map concentrates under a directional light. Two max
/// densities of the same light differ by less than DENSITY_FACTOR = 1.5
/// (3 sigma of a k = 50 estimate, see the claims module), so growth is only
/// asserted beyond that factor between n = 0 and n = 200 and as a strict rise
/// otherwise; at N_MAX = 1e5 the growth is x8 (bench run), and the k = 50
/// neighbourhood at N_MAX = 2e4 is ~sqrt(5) times wider, which smooths the
/// peak but not by a factor 5.
#[test]
fn classic_max_density_grows_with_n() {
    let (r, ..) = sweep();
    let m: Vec<f64> = r
        .mode_runs(Mode::Classic)
        .iter()
        .map(|x| x.max_density_primary)
        .collect();
    assert!(m[0] < m[1] && m[1] < m[2], "{m:?}");
    assert!(m[2] > DENSITY_FACTOR * m[0], "{m:?}");
}

/// The explosion is controlled: the adaptive mode splits at the first hit of
/// a directional light (rate > 1 at depth 0, where `s = alpha_E alpha_D N_MAX`
/// per photon is large), then the rate falls below 1 and never rises again by
/// more than 3 standard errors (`se = sqrt(max(rate, 1/4) / hits)`: children
/// per hit are Bernoulli under Russian roulette, about Poisson when splitting).
#[test]
fn adaptive_split_rate_falls_with_depth() {
    let (r, ..) = sweep();
    for run in r.mode_runs(Mode::Adaptive).iter().filter(|x| x.n > 0.0) {
        let rates = judged_rates(run, r.max_depth);
        assert!(rates.len() >= 3, "n = {}: {rates:?}", run.n);
        assert!(
            rates[0].1 > 1.0 && rates[1].1 < 1.0,
            "n = {}: {rates:?}",
            run.n
        );
        assert!(rates[1].1 < rates[0].1 - 3.0 * rates[0].2.max(rates[1].2));
        for w in rates[1..].windows(2) {
            let (a, b) = (w[0], w[1]);
            assert!(
                b.1 <= a.1 + 3.0 * a.2.max(b.2),
                "n = {}: {a:?} -> {b:?}",
                run.n
            );
        }
    }
}

/// Fig. 8: after the first hit the adaptive mode re-emits about N_MAX photons
/// (the paper derives N_MAX_refl = N_MAX from a diffuse box). At n = 200 the
/// whole emission hits the floor and blocks, each first hit re-emitting
/// `N_MAX / emitted` in expectation, so the total is N_MAX up to the stochastic
/// rounding of each hit (relative sd < 1/sqrt(N_MAX) = 1.4 %): 5 % is > 3 sd.
#[test]
fn adaptive_reemits_about_n_max_at_large_n() {
    let (r, ..) = sweep();
    let run = r.mode_runs(Mode::Adaptive)[2];
    let q = run.reemitted_first_hit as f64 / N_MAX as f64;
    assert!((q - 1.0).abs() < 0.05, "{q}");
}
