//! `adaptive-pm scene <SCENE>`: what a scene holds.

use adaptive_pm::brdf::Brdf;
use adaptive_pm::sampling::luminance;
use adaptive_pm::scene::{Light, Scene};
use serde_json::json;

use super::common::SceneFileArgs;

/// Arguments of `scene`.
#[derive(clap::Args, Debug)]
pub struct SceneArgs {
    /// A glTF file (.gltf or .glb), or a built-in scene: `cornell` (the Cornell
    /// box), `cornell-empty` (without its blocks), `cornell-glass` (with a mirror
    /// and a glass sphere instead), `door` (two rooms, a door ajar, the light in
    /// the room the camera does not see).
    pub scene: String,
    #[command(flatten)]
    pub assets: SceneFileArgs,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

/// The axis of a spot light, the direction of travel of a directional one.
fn direction_of(l: &Light) -> Option<glam::Vec3> {
    match l {
        Light::Spot(s) => Some(s.direction),
        Light::Directional(d) => Some(d.direction()),
        _ => None,
    }
}

fn brdf_name(b: &Brdf) -> String {
    let rgb = |v: glam::Vec3| format!("({:.3}, {:.3}, {:.3})", v.x, v.y, v.z);
    match b {
        Brdf::Lambert(l) => format!("lambert albedo {}", rgb(l.albedo)),
        Brdf::Phong(p) => format!(
            "phong kd {} ks {} n {}",
            rgb(p.kd()),
            rgb(p.ks()),
            p.exponent()
        ),
        Brdf::CookTorrance(c) => {
            format!(
                "cook-torrance m {} f0 {} kd {}",
                c.roughness(),
                rgb(c.f0()),
                rgb(c.kd())
            )
        }
        Brdf::GltfPbr(g) => format!(
            "gltf-pbr base {} metallic {} alpha {} f0 {}{}{}{}",
            rgb(g.base_color()),
            g.metallic(),
            g.alpha(),
            rgb(g.dielectric_f0()),
            match g.dielectric_f90() {
                1.0 => String::new(),
                f90 => format!(" f90 {f90}"),
            },
            match g.clearcoat() {
                (0.0, _) => String::new(),
                (w, a) => format!(" clearcoat {w} alpha {a}"),
            },
            match g.sheen() {
                (c, _) if c.max_element() <= 0.0 => String::new(),
                (c, r) => format!(" sheen {} roughness {r}", rgb(c)),
            }
        ),
        Brdf::Mirror(m) => format!("mirror {}", rgb(m.reflectance())),
        Brdf::Dielectric(d) => format!(
            "dielectric ior {} tint {}{}",
            d.ior(),
            rgb(d.tint()),
            if d.thin() { " thin" } else { "" }
        ),
        Brdf::RoughDielectric(d) => format!(
            "rough-dielectric alpha {} ior {} tint {}{}",
            d.alpha(),
            d.ior(),
            rgb(d.tint()),
            if d.thin() { " thin" } else { "" }
        ),
    }
}

/// What a material's textures are, for the listing (empty when it has none).
fn textures_note(scene: &Scene, material: usize) -> String {
    let Some(maps) = scene.material_maps(material) else {
        return String::new();
    };
    let size = |r: &adaptive_pm::scene::TextureRef| {
        let t = &scene.textures()[r.texture];
        format!("{} x {} (TEXCOORD_{})", t.width(), t.height(), r.tex_coord)
    };
    let mut parts = Vec::new();
    if let Some(r) = &maps.base_color {
        parts.push(format!("base colour {}", size(r)));
    }
    if let Some(r) = &maps.metallic_roughness {
        parts.push(format!("metallic-roughness {}", size(r)));
    }
    format!(
        "  textured: {} (BRDF shown at the mean texel)",
        parts.join(", ")
    )
}

/// A material's alpha mask, for the listing (empty when it has none).
/// The transmitted part of a partly transmitting material, if it has one.
fn mix_note(scene: &Scene, material: usize) -> String {
    match scene.transmission_mix(material as u32) {
        Some(t) => format!(
            "  transmits {}: `{}`",
            t.weight,
            scene.materials()[t.glass].name
        ),
        None => String::new(),
    }
}

fn mask_note(scene: &Scene, material: usize) -> String {
    let Some(mask) = scene.alpha_mask(material) else {
        return String::new();
    };
    let texture = match &mask.texture {
        Some(r) => format!(
            " x texture {}'s alpha (TEXCOORD_{})",
            r.texture, r.tex_coord
        ),
        None => String::new(),
    };
    format!(
        "  alpha mask: cutoff {} on factor {}{texture}",
        mask.cutoff, mask.factor
    )
}

pub fn run(args: SceneArgs) -> anyhow::Result<()> {
    let scene = args.assets.open(&args.scene)?;
    let no_light = scene
        .lights()
        .is_empty()
        .then(|| super::common::no_light_hint(&args.scene, &scene));
    let (lo, hi) = scene.bounds();
    let lights: Vec<_> = scene
        .lights()
        .iter()
        .map(|l| {
            let p = l.power();
            json!({
                "kind": l.kind(),
                "area": l.area(),
                "power": [p.x, p.y, p.z],
                "power_luminance": luminance(p),
                "cosn": match l { Light::Area(a) => Some(a.emission.profile.exponent()), _ => None },
                "two_sided": match l { Light::Area(a) => Some(a.emission.two_sided), _ => None },
                "mesh": match l { Light::Area(a) => Some(scene.meshes()[a.mesh].name.clone()), _ => None },
                "emissive_texture_pieces": match l { Light::Area(a) if a.is_textured() => Some(a.piece_count()), _ => None },
                "power_exact": match l { Light::Area(a) => Some(a.power_is_exact()), _ => None },
                "position": l.position().map(|p| [p.x, p.y, p.z]),
                "direction": direction_of(l).map(|d| [d.x, d.y, d.z]),
                "irradiance": match l { Light::Directional(d) => Some(d.irradiance().to_array()), _ => None },
                "disc_radius": match l { Light::Directional(d) => Some(d.scene_radius()), _ => None },
            })
        })
        .collect();
    if args.json {
        let out = json!({
            "scene": args.scene,
            "triangles": scene.triangle_count(),
            "meshes": scene.meshes().len(),
            "materials": scene.materials().iter().enumerate().map(|(i, m)| json!({"name": m.name, "brdf": brdf_name(&m.brdf), "emissive": m.emission.is_some(),
                "alpha_cutoff": scene.alpha_mask(i).map(|a| a.cutoff),
                "transmitted": scene.transmission_mix(i as u32).map(|t| json!({"weight": t.weight, "material": t.glass}))})).collect::<Vec<_>>(),
            "lights": lights,
            "bounds": {"min": [lo.x, lo.y, lo.z], "max": [hi.x, hi.y, hi.z]},
            "camera": scene.camera().map(|c| json!({"eye": [c.eye.x, c.eye.y, c.eye.z], "forward": [c.forward.x, c.forward.y, c.forward.z], "vfov_deg": c.vfov_deg})),
            "skipped_degenerate": scene.skipped_degenerate(),
            "warnings": scene.warnings().iter().chain(&no_light).collect::<Vec<_>>(),
        });
        println!("{out}");
        return Ok(());
    }
    println!("scene      {}", args.scene);
    println!("triangles  {}", scene.triangle_count());
    if scene.skipped_degenerate() > 0 {
        println!(
            "skipped    {} zero-area triangles",
            scene.skipped_degenerate()
        );
    }
    for w in scene.warnings().iter().chain(&no_light) {
        println!("warning    {w}");
    }
    println!("meshes     {}", scene.meshes().len());
    for m in scene.meshes() {
        println!(
            "  {:<16} {:>6} triangles  area {:>10.1}  material {}",
            m.name,
            m.indices.len(),
            m.area(),
            scene.materials()[m.material].name
        );
    }
    println!("materials  {}", scene.materials().len());
    for (i, m) in scene.materials().iter().enumerate() {
        println!(
            "  {:<16} {}{}{}{}{}",
            m.name,
            brdf_name(&m.brdf),
            if m.emission.is_some() {
                "  (emissive)"
            } else {
                ""
            },
            textures_note(&scene, i),
            mask_note(&scene, i),
            mix_note(&scene, i)
        );
    }
    println!("lights     {}", scene.lights().len());
    for l in scene.lights() {
        let p = l.power();
        let extra = match l {
            Light::Area(a) => format!(
                "area {:.1}  cos^n n = {}{}",
                a.area,
                a.emission.profile.exponent(),
                if a.emission.two_sided {
                    "  two-sided"
                } else {
                    ""
                }
            ),
            Light::Directional(d) => {
                let (w, e) = (d.direction(), d.irradiance());
                format!(
                    "direction ({:.4}, {:.4}, {:.4})  irradiance ({:.4e}, {:.4e}, {:.4e})  \
                     disc radius {:.4}  (alpha_A = 1, alpha_D = alpha_min)",
                    w.x,
                    w.y,
                    w.z,
                    e.x,
                    e.y,
                    e.z,
                    d.scene_radius()
                )
            }
            _ => "punctual (alpha_A = 1)".to_string(),
        };
        println!(
            "  {:<11} power ({:.4e}, {:.4e}, {:.4e})  {extra}",
            l.kind(),
            p.x,
            p.y,
            p.z
        );
    }
    println!(
        "bounds     ({:.1}, {:.1}, {:.1}) .. ({:.1}, {:.1}, {:.1})",
        lo.x, lo.y, lo.z, hi.x, hi.y, hi.z
    );
    if let Some(c) = scene.camera() {
        println!(
            "camera     eye {}  forward {}  vfov {:.4} deg",
            c.eye, c.forward, c.vfov_deg
        );
    }
    Ok(())
}
