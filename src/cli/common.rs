//! Arguments and helpers shared by the subcommands.

use adaptive_pm::analysis::Estimator;
use adaptive_pm::embree::Device;
use adaptive_pm::emitter::CosN;
use adaptive_pm::engine::config::{DEFAULT_MAX_DEPTH, DEFAULT_SPLIT_CAP};
use adaptive_pm::engine::{Budget, Mode, TraceConfig};
use adaptive_pm::isa::Isa;
use adaptive_pm::scene::{Camera, Light, LoadOptions, PointLight, Scene};
use anyhow::Context;
use glam::Vec3;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::path::PathBuf;

/// The flags that make a run's [`TraceConfig`] (its photon budget, seed,
/// depth, split cap, memory and estimator), and the `--cosn` override of the
/// scene it traces.
#[derive(clap::Args, Debug, Clone)]
pub struct TraceConfigArgs {
    /// Quality Q in [0, 1]: N_MAX = Q^2 * (2^31 - 1).
    #[arg(long, short = 'q', conflicts_with = "n_max")]
    pub quality: Option<f64>,
    /// N_MAX directly (default 100000, the paper's experiments).
    #[arg(long, short = 'n')]
    pub n_max: Option<u64>,
    /// Override every area light's cos^n exponent.
    #[arg(long, allow_negative_numbers = true, value_parser = parse_finite)]
    pub cosn: Option<f32>,
    /// Seed of every random number.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Bounces after the first hit.
    #[arg(long, default_value_t = DEFAULT_MAX_DEPTH)]
    pub max_depth: u32,
    /// Per-hit cap on children (adaptive mode).
    #[arg(long, default_value_t = DEFAULT_SPLIT_CAP)]
    pub split_cap: u32,
    #[arg(long, help = budget_help())]
    pub budget_mb: Option<u64>,
    /// Directionality estimator: paper (the paper's clustering) or peak (peak density).
    #[arg(long, default_value = "paper", value_parser = parse_estimator)]
    pub directionality: Estimator,
    /// Importance from the camera in the counts (adaptive mode only, beyond
    /// the paper): `camera` traces importance from the scene's camera first
    /// (128 x 128 x 4 samples, the gather's bounce and 4 more), then splits
    /// photons by the adjoint where they land, rations each light's photons
    /// by pilot photons, and stores none where nothing reads them; `off`
    /// (default) is the paper's counts.
    #[arg(long, default_value = "off", value_parser = ["off", "camera"])]
    pub importance: String,
}

/// A finite `f32` (clap parser): NaN and infinities are refused with a
/// message instead of silently giving black images.
pub fn parse_finite(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(x) if x.is_finite() => Ok(x),
        Ok(x) => Err(format!("`{s}` is {x}, not a finite number")),
        Err(e) => Err(format!("`{s}`: {e}")),
    }
}

/// Exposure in stops: finite and within +-64 (`2^64` already saturates
/// every pixel; beyond, the scale overflows to infinity and the image is NaN).
pub fn parse_exposure(s: &str) -> Result<f32, String> {
    let x = parse_finite(s)?;
    if x.abs() <= 64.0 {
        Ok(x)
    } else {
        Err(format!("`{s}` is outside [-64, 64] stops"))
    }
}

/// `--budget-mb`'s help, from the default the engine uses.
fn budget_help() -> String {
    use adaptive_pm::engine::config::{
        available_memory, default_memory_budget, DEFAULT_MEMORY_SHARE,
    };
    let (num, den) = DEFAULT_MEMORY_SHARE;
    format!(
        "Memory for photons in MiB (default: {num}/{den} of the available memory, now {} MiB)",
        default_memory_budget(available_memory()) >> 20
    )
}

pub fn parse_estimator(s: &str) -> Result<Estimator, String> {
    s.parse().map_err(|e: adaptive_pm::Error| e.to_string())
}

impl TraceConfigArgs {
    /// The [`TraceConfig`] of these flags in `mode`, checked.
    pub fn config(&self, mode: Mode) -> anyhow::Result<TraceConfig> {
        let budget = match (self.quality, self.n_max) {
            (Some(q), _) => Budget::Quality(q),
            (None, Some(n)) => Budget::NMax(n),
            (None, None) => Budget::default(),
        };
        let mut cfg = TraceConfig::new(mode, budget);
        cfg.seed = self.seed;
        cfg.max_depth = self.max_depth;
        cfg.split_cap = self.split_cap;
        cfg.memory_budget = match self.budget_mb {
            // Checked: `mb << 20` silently dropped the high bits.
            Some(mb) => Some(mb.checked_mul(1 << 20).ok_or_else(|| {
                anyhow::anyhow!("--budget-mb {mb} does not fit in 64 bits of bytes")
            })?),
            None => None,
        };
        cfg.estimator = self.directionality;
        if self.importance == "camera" {
            cfg.importance = Some(adaptive_pm::importance::ImportanceConfig {
                seed: self.seed,
                ..Default::default()
            });
        }
        cfg.validate()?;
        Ok(cfg)
    }
}

/// Thread count.
#[derive(clap::Args, Debug, Clone)]
pub struct ThreadArgs {
    /// Worker threads (0 = all cores; at most 4 per available core).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
}

impl ThreadArgs {
    pub fn pool(&self) -> anyhow::Result<rayon::ThreadPool> {
        Ok(adaptive_pm::embree::thread_pool(self.threads)?)
    }
}

/// Embree's kernel set.
#[derive(clap::Args, Debug, Clone)]
pub struct EmbreeArgs {
    /// Pin Embree's x86 kernel set (sse2, sse4.2, avx, avx2, avx512): the
    /// same settings then give the same photons on every host that runs it.
    /// Default: the CPU's widest set, whose photons differ between CPUs.
    #[arg(long = "embree-isa", env = adaptive_pm::isa::ISA_ENV, value_name = "SET")]
    pub embree_isa: Option<Isa>,
}

impl EmbreeArgs {
    /// The Embree device of these settings.
    pub fn device(&self) -> anyhow::Result<Device> {
        Ok(Device::pinned_or_default(self.embree_isa)?)
    }
}

/// Where a glTF scene's external files may be read from.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct AssetRootArgs {
    /// Folder the scene's buffers and images may be read from, anywhere
    /// inside it (`../buffers/x.bin`, through symbolic links too), nothing
    /// outside it; it must hold the scene file. Default: the scene file's
    /// folder.
    #[arg(long, value_name = "DIR")]
    pub asset_root: Option<PathBuf>,
}

impl AssetRootArgs {
    /// The load options of this flag.
    pub fn options(&self) -> LoadOptions {
        match &self.asset_root {
            Some(dir) => LoadOptions::default().with_asset_root(dir),
            None => LoadOptions::default(),
        }
    }
}

/// Where a glTF scene's external files may be read from, and the light and
/// the view the command line adds to it (for the commands that trace or
/// render it).
#[derive(clap::Args, Debug, Clone, Default)]
pub struct SceneFileArgs {
    #[command(flatten)]
    pub root: AssetRootArgs,
    /// Add an isotropic white point light at X,Y,Z (scene units, glTF's
    /// +Y up) emitting WATTS in all (repeat the flag for more): most glTF
    /// models come without a light.
    #[arg(long = "point-light", value_name = "X,Y,Z,WATTS", value_parser = parse_point_light)]
    pub point_lights: Vec<PointLightSpec>,
    /// View from EYE towards TARGET (+Y up) with a vertical field of view
    /// of VFOV degrees (default 40), instead of the scene's camera. A scene
    /// without a camera is otherwise seen from its front (+Z), framed whole.
    #[arg(long, value_name = "EX,EY,EZ,TX,TY,TZ[,VFOV]", value_parser = parse_camera)]
    pub camera: Option<Camera>,
}

/// A comma-separated list of finite numbers, `form` naming it in errors.
fn finite_numbers(s: &str, form: &str) -> Result<Vec<f32>, String> {
    s.split(',')
        .map(|x| x.trim().parse::<f32>().ok().filter(|v| v.is_finite()))
        .collect::<Option<_>>()
        .ok_or_else(|| format!("`{s}`: expected {form}, finite numbers"))
}

fn parse_camera(s: &str) -> Result<Camera, String> {
    let numbers = finite_numbers(s, "EX,EY,EZ,TX,TY,TZ[,VFOV]")?;
    let (eye, target, vfov) = match numbers[..] {
        [ex, ey, ez, tx, ty, tz] => (Vec3::new(ex, ey, ez), Vec3::new(tx, ty, tz), 40.0),
        [ex, ey, ez, tx, ty, tz, v] => (Vec3::new(ex, ey, ez), Vec3::new(tx, ty, tz), v),
        _ => {
            return Err(format!(
                "`{s}`: expected EX,EY,EZ,TX,TY,TZ[,VFOV], six or seven numbers, got {}",
                numbers.len()
            ))
        }
    };
    Camera::look_at(eye, target, Vec3::Y, vfov).map_err(|e| format!("`{s}`: {e}"))
}

/// A point light given on the command line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLightSpec {
    pub position: Vec3,
    pub watts: f32,
}

fn parse_point_light(s: &str) -> Result<PointLightSpec, String> {
    let numbers = finite_numbers(s, "X,Y,Z,WATTS")?;
    let [x, y, z, watts] = numbers[..] else {
        return Err(format!(
            "`{s}`: expected X,Y,Z,WATTS, four numbers, got {}",
            numbers.len()
        ));
    };
    if watts <= 0.0 {
        return Err(format!("`{s}`: the power must be above 0 W, got {watts}"));
    }
    Ok(PointLightSpec {
        position: Vec3::new(x, y, z),
        watts,
    })
}

impl SceneFileArgs {
    /// Opens a scene by name or path with these flags' asset root and
    /// lights, unchecked: a scene without a light is returned as it is, to
    /// be described ([`open_scene`] checks it for tracing).
    pub fn open(&self, name: &str) -> anyhow::Result<Scene> {
        let mut scene = Scene::open_with(name, &self.root.options())
            .with_context(|| format!("scene `{name}`"))?;
        for p in &self.point_lights {
            let intensity = Vec3::splat(p.watts / (4.0 * std::f32::consts::PI));
            scene
                .add_light(Light::Point(PointLight {
                    position: p.position,
                    intensity,
                }))
                .with_context(|| format!("--point-light at {}", p.position))?;
        }
        if let Some(camera) = self.camera {
            scene.set_camera(camera).context("--camera")?;
        }
        Ok(scene)
    }
}

/// Opens a scene by name or path, with its assets' root, the lights the
/// command line adds and an optional cos^n override, prints its warnings,
/// and checks it can be traced.
pub fn open_scene(name: &str, file: &SceneFileArgs, cosn: Option<f32>) -> anyhow::Result<Scene> {
    let mut scene = file.open(name)?;
    for w in scene.warnings() {
        eprintln!("warning: scene `{name}`: {w}");
    }
    if let Some(n) = cosn {
        scene.set_cosn(CosN::new(n)?);
    }
    if scene.lights().is_empty() {
        anyhow::bail!("{}", no_light_hint(name, &scene));
    }
    scene.validate()?;
    if let (None, Some((lo, hi))) = (scene.camera(), scene.geometry_bounds()) {
        let camera = Camera::framing(lo, hi)?;
        let (e, f) = (camera.eye, (lo + hi) * 0.5);
        eprintln!(
            "note: scene `{name}` has no camera: seen from its front, framed whole \
             (--camera {},{},{},{},{},{},{})",
            short(e.x),
            short(e.y),
            short(e.z),
            short(f.x),
            short(f.y),
            short(f.z),
            camera.vfov_deg
        );
        scene.set_camera(camera)?;
    }
    Ok(scene)
}

/// Why a scene without a light cannot be traced, and a `--point-light`
/// that would light it: above the middle of its bounds by half their size,
/// bright enough for about 1 W/m^2 at the middle.
pub fn no_light_hint(name: &str, scene: &Scene) -> String {
    let (lo, hi) = scene.geometry_bounds().unwrap_or((Vec3::ZERO, Vec3::ZERO));
    let size = (hi - lo).max_element().max(1e-3);
    let centre = (lo + hi) * 0.5;
    let at = Vec3::new(centre.x, hi.y + 0.5 * size, centre.z);
    let d = at.distance(centre);
    let watts = 4.0 * std::f32::consts::PI * d * d;
    format!(
        "scene `{name}` has no light: give a material an emissiveFactor or add a \
         KHR_lights_punctual light, or add one here, for example \
         --point-light {},{},{},{}",
        short(at.x),
        short(at.y),
        short(at.z),
        short(watts)
    )
}

/// A number in at most 4 significant digits.
fn short(x: f32) -> String {
    format!("{}", format!("{x:.4e}").parse::<f32>().unwrap_or(x))
}

/// A progress bar on a terminal's stderr; hidden otherwise or when `show` is false.
pub fn progress_bar(show: bool) -> ProgressBar {
    if !show || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(Some(0), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template("{spinner} {msg:>10} [{bar:40}] {pos}/{len} photons ({eta})")
            .expect("static template")
            .progress_chars("=> "),
    );
    bar
}

/// Property tests of the command line's numbers (issue 12): every value is
/// either accepted and used as given, or refused with a message; never a panic.
#[cfg(test)]
mod tests {
    use super::*;
    use adaptive_pm::engine::config::INT_MAX;
    use clap::Parser;
    use proptest::prelude::*;

    #[derive(clap::Parser, Debug)]
    struct Args {
        #[command(flatten)]
        settings: TraceConfigArgs,
        #[command(flatten)]
        threads: ThreadArgs,
    }

    fn parse(flag: &str, value: &str) -> Result<Args, clap::Error> {
        Args::try_parse_from(["t", flag, value])
    }

    /// A number as a user might type it, including the hostile spellings.
    fn typed() -> impl Strategy<Value = String> {
        prop_oneof![
            any::<f64>().prop_map(|x| x.to_string()),
            any::<i64>().prop_map(|x| x.to_string()),
            any::<u64>().prop_map(|x| x.to_string()),
            Just("nan".to_string()),
            Just("inf".to_string()),
            Just("-inf".to_string()),
            Just("1e400".to_string()),
            Just("".to_string()),
            "[0-9eE.+-]{1,12}",
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        #[test]
        fn trace_config_numbers_are_used_or_refused(v in typed()) {
            for flag in ["--quality", "--n-max", "--cosn", "--seed", "--max-depth", "--split-cap", "--budget-mb"] {
                let Ok(args) = parse(flag, &v) else { continue };
                let b = &args.settings;
                match b.config(Mode::Adaptive) {
                    // Any seed is a seed, and --cosn is checked when the
                    // scene is opened: neither may refuse the settings.
                    Err(e) => prop_assert!(!matches!(flag, "--seed" | "--cosn"), "{flag} {v}: {e}"),
                    Ok(cfg) => match flag {
                        "--quality" => {
                            let q = b.quality.unwrap();
                            prop_assert!((0.0..=1.0).contains(&q));
                            prop_assert_eq!(cfg.budget.n_max().unwrap(), (q * q * INT_MAX as f64).round() as u64);
                        }
                        "--n-max" => prop_assert_eq!(cfg.budget, Budget::NMax(b.n_max.unwrap())),
                        "--seed" => prop_assert_eq!(cfg.seed, b.seed),
                        "--max-depth" => prop_assert!(cfg.max_depth == b.max_depth && b.max_depth <= 250),
                        "--split-cap" => prop_assert!(cfg.split_cap == b.split_cap && b.split_cap >= 1),
                        "--budget-mb" => prop_assert_eq!(
                            cfg.memory_budget,
                            b.budget_mb.map(|m| m * (1 << 20))
                        ),
                        // parse_finite let no NaN or infinity through.
                        _ => prop_assert!(b.cosn.is_some_and(f32::is_finite)),
                    },
                }
            }
        }

        #[test]
        fn exposure_is_finite_and_bounded_or_refused(v in typed()) {
            match parse_exposure(&v) {
                Ok(x) => prop_assert!(x.is_finite() && x.abs() <= 64.0 && x.exp2().is_finite()),
                Err(e) => prop_assert!(e.contains(&v)),
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]

        #[test]
        fn threads_are_started_as_asked_or_refused(t in prop_oneof![0usize..16, any::<usize>()]) {
            let args = parse("--threads", &t.to_string()).unwrap();
            match args.threads.pool() {
                Ok(pool) if t > 0 => prop_assert_eq!(pool.current_num_threads(), t),
                Ok(_) => {}
                Err(e) => {
                    prop_assert!(t > adaptive_pm::embree::max_threads());
                    prop_assert!(e.to_string().contains("threads"));
                }
            }
        }
    }
}
