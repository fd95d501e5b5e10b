//! `adaptive-pm analyze`: directionality of named functions, and of every
//! emission profile and BRDF a scene uses (each distinct one once).
//!
//! Text output: one row per function (kind, param, alpha_d, peaks,
//! sample_ms, cluster_ms). For BRDFs `alpha_d` and `peaks` are at normal
//! incidence and the times are for the whole theta_in table. `--json`: one
//! object `{"functions":[{kind, param, alpha_d, alpha_d_by_theta_in (BRDFs
//! only), peaks, sample_ms, cluster_ms}]}`.

use adaptive_pm::analysis::{
    analyze_brdf, analyze_brdf_at, analyze_emitter, AnalysisParams, Estimator,
};
use adaptive_pm::brdf::{Brdf, CookTorrance, GltfPbr, Lambert, Mirror, Phong};
use adaptive_pm::emitter::CosN;
use adaptive_pm::scene::{Light, LoadOptions, Scene};

use super::common::AssetRootArgs;
use anyhow::{bail, Context};
use glam::Vec3;

/// Arguments of `analyze`.
#[derive(clap::Args, Debug)]
pub struct AnalyzeArgs {
    /// A scene (glTF path, or a built-in: `cornell`, `cornell-empty`,
    /// `cornell-glass`, `door`) whose emitters and BRDFs to analyse.
    pub scene: Option<String>,
    #[command(flatten)]
    pub assets: AssetRootArgs,
    /// `cos^n` emitters to analyse, by exponent.
    #[arg(long, value_delimiter = ',')]
    pub cosn: Vec<f32>,
    /// Modified Phong BRDFs (kd 0, ks 0.9) to analyse, by exponent.
    #[arg(long, value_delimiter = ',')]
    pub phong: Vec<f32>,
    /// Cook–Torrance metals (f0 0.9) to analyse, by Beckmann roughness.
    #[arg(long = "cook-torrance", value_delimiter = ',')]
    pub cook_torrance: Vec<f32>,
    /// glTF metallic-roughness metals (base colour 0.9, GGX) to analyse, by
    /// glTF roughness (alpha = roughness^2).
    #[arg(long = "gltf-metal", value_delimiter = ',')]
    pub gltf_metal: Vec<f32>,
    /// Analyse a Lambert BRDF.
    #[arg(long)]
    pub lambert: bool,
    /// Analyse a mirror.
    #[arg(long)]
    pub mirror: bool,
    /// Estimator: `paper` (clustering, default) or `peak` (1 / (pi max p)).
    #[arg(long, default_value = "paper")]
    pub directionality: String,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
}

#[derive(serde::Serialize)]
struct Row {
    kind: &'static str,
    /// The scene material or light the function belongs to.
    #[serde(skip_serializing_if = "Option::is_none")]
    name: Option<String>,
    param: Option<f32>,
    alpha_d: f32,
    #[serde(skip_serializing_if = "Option::is_none")]
    alpha_d_by_theta_in: Option<Vec<f32>>,
    peaks: usize,
    sample_ms: f64,
    cluster_ms: f64,
}

fn checked(name: &str, v: &[f32]) -> anyhow::Result<()> {
    if let Some(bad) = v.iter().find(|x| !(x.is_finite() && **x >= 0.0)) {
        bail!("--{name}: every value must be a finite number >= 0, got {bad}");
    }
    Ok(())
}

fn emitter_row(e: &CosN, est: Estimator, p: &AnalysisParams) -> anyhow::Result<Row> {
    let d = analyze_emitter(e, est, p)?;
    Ok(Row {
        kind: "cosn",
        name: None,
        param: Some(e.exponent()),
        alpha_d: d.alpha_d,
        alpha_d_by_theta_in: None,
        peaks: d.peaks.len(),
        sample_ms: d.sample_time.as_secs_f64() * 1e3,
        cluster_ms: d.cluster_time.as_secs_f64() * 1e3,
    })
}

fn brdf_row(
    kind: &'static str,
    param: Option<f32>,
    b: Brdf,
    est: Estimator,
    p: &AnalysisParams,
) -> anyhow::Result<Row> {
    let t = analyze_brdf(&b, est, p)?;
    let at0 = analyze_brdf_at(&b, 1.0, est, p)?;
    Ok(Row {
        kind,
        name: None,
        param,
        alpha_d: t.alpha_d(1.0),
        alpha_d_by_theta_in: Some(t.values()),
        peaks: at0.peaks.len(),
        sample_ms: t.sample_time.as_secs_f64() * 1e3,
        cluster_ms: t.cluster_time.as_secs_f64() * 1e3,
    })
}

/// Rows for what a scene uses: each distinct emission profile, and each
/// distinct BRDF that some mesh carries (nothing the scene does not use).
fn scene_rows(
    name: &str,
    options: &LoadOptions,
    est: Estimator,
    p: &AnalysisParams,
    rows: &mut Vec<Row>,
) -> anyhow::Result<()> {
    let scene = Scene::open_with(name, options).with_context(|| format!("scene `{name}`"))?;
    let mut seen = std::collections::HashSet::new();
    for l in scene.lights() {
        if let Light::Area(a) = l {
            let n = a.emission.profile.exponent();
            if seen.insert(("cosn", n.to_bits() as u64)) {
                let mut row = emitter_row(&a.emission.profile, est, p)?;
                row.name = Some(scene.meshes()[a.mesh].name.clone());
                rows.push(row);
            }
        }
    }
    for mesh in scene.meshes() {
        let m = &scene.materials()[mesh.material];
        if seen.insert(("brdf", m.brdf.key())) {
            let mut row = brdf_row(m.brdf.kind(), None, m.brdf, est, p)?;
            row.name = Some(m.name.clone());
            rows.push(row);
        }
    }
    Ok(())
}

/// Runs `analyze`.
pub fn run(args: AnalyzeArgs) -> anyhow::Result<()> {
    let est: Estimator = args.directionality.parse()?;
    checked("cosn", &args.cosn)?;
    checked("phong", &args.phong)?;
    checked("cook-torrance", &args.cook_torrance)?;
    checked("gltf-metal", &args.gltf_metal)?;
    let p = AnalysisParams::default();
    let mut rows = Vec::new();
    if let Some(name) = &args.scene {
        scene_rows(name, &args.assets.options(), est, &p, &mut rows)?;
    }
    for &n in &args.cosn {
        rows.push(emitter_row(&CosN::new(n)?, est, &p)?);
    }
    for &e in &args.phong {
        let b = Phong::new(Vec3::ZERO, Vec3::splat(0.9), e).context("--phong")?;
        rows.push(brdf_row("phong", Some(e), b.into(), est, &p)?);
    }
    for &m in &args.cook_torrance {
        let b = CookTorrance::new(m, Vec3::splat(0.9), Vec3::ZERO).context("--cook-torrance")?;
        rows.push(brdf_row("cook-torrance", Some(m), b.into(), est, &p)?);
    }
    for &r in &args.gltf_metal {
        let b = GltfPbr::new(Vec3::splat(0.9), 1.0, r * r, 0.04).context("--gltf-metal")?;
        rows.push(brdf_row("gltf-pbr", Some(r), b.into(), est, &p)?);
    }
    if args.lambert {
        rows.push(brdf_row(
            "lambert",
            None,
            Lambert::new(Vec3::splat(0.8))?.into(),
            est,
            &p,
        )?);
    }
    if args.mirror {
        rows.push(brdf_row(
            "mirror",
            None,
            Mirror::new(Vec3::splat(0.9))?.into(),
            est,
            &p,
        )?);
    }
    if rows.is_empty() {
        bail!(
            "nothing to analyse: give a scene or --cosn/--phong/--cook-torrance/--gltf-metal/--lambert/--mirror"
        );
    }
    if args.json {
        println!("{}", serde_json::json!({ "functions": rows }));
    } else {
        println!(
            "{:<14} {:<12} {:>10} {:>9} {:>6} {:>10} {:>11}",
            "kind", "name", "param", "alpha_d", "peaks", "sample_ms", "cluster_ms"
        );
        for r in &rows {
            let param = r.param.map_or("-".to_string(), |v| v.to_string());
            println!(
                "{:<14} {:<12} {:>10} {:>9.5} {:>6} {:>10.3} {:>11.3}",
                r.kind,
                r.name.as_deref().unwrap_or("-"),
                param,
                r.alpha_d,
                r.peaks,
                r.sample_ms,
                r.cluster_ms
            );
        }
        println!("(estimator: {est}; BRDFs: alpha_d and peaks at normal incidence, times for the whole theta_in table)");
    }
    Ok(())
}
