//! The scene model: triangle meshes with a material each, area lights made of
//! emissive meshes with a `cos^n` profile (their radiance varying over the
//! surface with an emissive texture: [`Scene::set_emission_texture`]),
//! punctual lights (point, spot and directional), and an optional camera.
//!
//! Scenes come from glTF 2.0 files (`Scene::load`), from the built-in Cornell box
//! (`Scene::cornell`; both with the feature `gltf`), or are assembled in code
//! ([`Scene::new`], [`Scene::add_mesh`]).
//! Only what the scene uses is modelled: the directionality analysis later runs on
//! the emitters and materials found here, nothing else. A material may cut
//! holes (glTF `alphaMode: MASK`, [`AlphaMask`]) that rays pass through.

mod alpha;
#[cfg(feature = "gltf")]
mod assets;
#[cfg(feature = "gltf")]
mod buffers;
mod checks;
#[cfg(feature = "gltf")]
mod cornell;
mod directional;
mod emission_cells;
mod emission_map;
mod emissive;
#[cfg(feature = "gltf")]
pub mod gltf_checks;
#[cfg(feature = "gltf")]
mod gltf_data;
#[cfg(feature = "gltf")]
mod gltf_emissive;
#[cfg(feature = "gltf")]
mod gltf_graph;
#[cfg(feature = "gltf")]
mod gltf_images;
#[cfg(feature = "gltf")]
mod gltf_instancing;
#[cfg(feature = "gltf")]
mod gltf_load;
#[cfg(feature = "gltf")]
mod gltf_meshopt;
#[cfg(feature = "gltf")]
mod gltf_quantized;
// Valid files the gltf crate's schema refuses, rewritten to read.
#[cfg(feature = "gltf")]
mod gltf_relaxed;
// A skinned mesh posed by its joints.
#[cfg(feature = "gltf")]
mod gltf_skin;
#[cfg(feature = "gltf")]
mod gltf_textures;
mod light;
pub mod normal_map;
mod prepared;
mod surface;
pub mod texture;
mod textured;
mod transmission_mix;

#[cfg(feature = "gltf")]
pub use assets::{percent_decode, resolve_inside};
#[cfg(feature = "gltf")]
pub use buffers::MAX_BUFFER_BYTES;
pub use checks::{MAX_COORDINATE, MAX_LIGHT_POWER, MAX_RADIANCE, MIN_LIGHT_POWER};
#[cfg(feature = "gltf")]
pub use gltf_images::MAX_TEXELS;
#[cfg(feature = "gltf")]
pub use gltf_load::LoadOptions;

pub use alpha::{AlphaMask, Cutout};
pub use directional::DirectionalLight;
pub use emission_map::MAX_CELLS;
pub use light::{AreaLight, EmittedPhoton, Light, LightPoint, PointLight, SpotLight};
pub use normal_map::NormalMap;
pub use prepared::PreparedScene;
pub use surface::{consistent_with_geometry, photon_shading_factor, SurfacePoint, SurfaceSampler};
pub use texture::{Encoding, Filter, Sampler, TexTransform, Texture, TextureRef, Wrap};
pub use textured::{flat_base_color, MaterialMaps};
pub use transmission_mix::TransmissionMix;

use crate::brdf::Brdf;
use crate::emitter::CosN;
use crate::error::{Error, Result};
use crate::sampling::luminance;
use glam::{Vec2, Vec3, Vec4};
#[cfg(feature = "gltf")]
use std::path::Path;

/// What a built-in scene is called on the command line.
#[doc(hidden)]
pub const BUILTIN_CORNELL: &str = "cornell";
/// The empty Cornell box (walls and light, no blocks): the paper's scene.
#[doc(hidden)]
pub const BUILTIN_CORNELL_EMPTY: &str = "cornell-empty";
/// The empty Cornell box with a mirror sphere and a glass sphere.
#[doc(hidden)]
pub const BUILTIN_CORNELL_GLASS: &str = "cornell-glass";
/// Veach's door scene: two rooms, a door ajar, the light in the unseen room.
#[doc(hidden)]
pub const BUILTIN_DOOR: &str = "door";

/// The names of every built-in scene (`Scene::open` accepts each).
#[cfg(feature = "gltf")]
#[doc(hidden)]
pub fn builtin_names() -> Vec<&'static str> {
    cornell::BUILTINS.iter().map(|(n, _)| *n).collect()
}

/// A surface material: a BRDF, and emission when the surface is a light.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name (from the file, or given in code).
    pub name: String,
    /// How the surface reflects.
    pub brdf: Brdf,
    /// Emitted radiance, when the surface emits.
    pub emission: Option<Emission>,
}

/// Emission of an area light: `L(theta) = radiance * cos^n(theta)` about the
/// geometric normal (the side the triangle winding faces), from the front
/// only, or from both faces when `two_sided` (glTF's `doubleSided`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Emission {
    /// Radiance along the normal, linear RGB.
    pub radiance: Vec3,
    /// The angular profile.
    pub profile: CosN,
    /// Emits from both faces: twice the power, the same profile about each
    /// face's normal.
    pub two_sided: bool,
}

impl Emission {
    /// A one-sided emission.
    pub fn new(radiance: Vec3, profile: CosN) -> Self {
        Emission {
            radiance,
            profile,
            two_sided: false,
        }
    }

    /// The cosine the profile sees for a direction at cosine `cos` from the
    /// geometric normal: `cos` for a one-sided emitter (whose back, `cos <= 0`,
    /// is dark), `|cos|` for a two-sided one.
    #[inline]
    pub fn facing(&self, cos: f32) -> f32 {
        if self.two_sided {
            cos.abs()
        } else {
            cos
        }
    }

    /// Radiance leaving toward a direction at cosine `cos` from the geometric normal.
    #[inline]
    pub fn radiance_at(&self, cos: f32) -> Vec3 {
        let c = self.facing(cos);
        if c > 0.0 {
            self.radiance_toward(c)
        } else {
            Vec3::ZERO
        }
    }

    /// Radiance toward a direction whose profile cosine (already
    /// [`facing`](Self::facing)) is `cos`: `radiance * profile(cos)`.
    #[inline]
    pub fn radiance_toward(&self, cos: f32) -> Vec3 {
        self.radiance * self.profile_toward(cos)
    }

    /// The profile's factor at the profile cosine `cos` (`cos^n` for the
    /// paper's lights).
    #[inline]
    pub fn profile_toward(&self, cos: f32) -> f32 {
        self.profile.eval(Vec3::new(0.0, 0.0, cos))
    }

    /// Faces that emit: 1 or 2.
    pub fn sides(&self) -> f32 {
        if self.two_sided {
            2.0
        } else {
            1.0
        }
    }
}

/// A triangle mesh with one material.
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    /// Name (from the file, or given in code).
    pub name: String,
    /// Vertex positions (world space).
    pub positions: Vec<Vec3>,
    /// Triangles as vertex indices; degenerate triangles were removed.
    pub indices: Vec<[u32; 3]>,
    /// Index into [`Scene::materials`].
    pub material: usize,
    /// Per-vertex shading normals (unit, world space), or empty for flat
    /// shading ([`Scene::set_vertex_normals`]).
    pub normals: Vec<Vec3>,
    /// Per-vertex texture coordinates by set (`texcoords[n]` is glTF's
    /// `TEXCOORD_n`; empty when absent; [`Scene::set_texcoords`]).
    pub texcoords: Vec<Vec<Vec2>>,
    /// Per-vertex colours (linear RGB in [0, 1]) that multiply a glTF
    /// material's base colour (glTF's `COLOR_0`), or empty
    /// ([`Scene::set_vertex_colors`]).
    pub colors: Vec<Vec3>,
    /// Tangents (xyz, world space) and handedness (w) by triangle corner,
    /// for a normal texture; empty without one ([`normal_map`]).
    pub tangents: Vec<[Vec4; 3]>,
}

impl Mesh {
    /// Vertices of triangle `i`.
    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        let [a, b, c] = self.indices[i];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    /// The interpolated shading normal of triangle `i` at barycentrics
    /// `(u, v)` (of vertices 1 and 2), unit; `None` for a flat mesh or a
    /// degenerate interpolation.
    pub fn shading_normal(&self, i: usize, u: f32, v: f32) -> Option<Vec3> {
        if self.normals.is_empty() {
            return None;
        }
        let [a, b, c] = *self.indices.get(i)?;
        let n = self.normals.get(a as usize)? * (1.0 - u - v)
            + self.normals.get(b as usize)? * u
            + self.normals.get(c as usize)? * v;
        let n = n.normalize_or_zero();
        (n != Vec3::ZERO).then_some(n)
    }

    /// Total surface area, summed in f64: an f32 sum of a million small
    /// triangles lost half a percent.
    pub fn area(&self) -> f64 {
        (0..self.indices.len())
            .map(|i| f64::from(triangle_area(self.triangle(i))))
            .sum()
    }
}

/// A pinhole camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub eye: Vec3,
    /// Unit viewing direction.
    pub forward: Vec3,
    /// Unit up vector (orthogonal to `forward`).
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub vfov_deg: f32,
}

impl Camera {
    /// The classic Cornell box camera: eye (278, 273, -800) looking along +z, 39.3077 degrees.
    pub fn cornell() -> Self {
        Camera {
            eye: Vec3::new(278.0, 273.0, -800.0),
            forward: Vec3::Z,
            up: Vec3::Y,
            vfov_deg: 39.3077,
        }
    }

    /// A camera at `eye` looking at `target`, with `up` (any vector not
    /// along the view) made orthogonal to the view, and a vertical field of
    /// view of `vfov_deg` degrees.
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] when `eye` is `target`, `up` lies
    /// along the view, a value is not finite, or the field of view is not in
    /// `(0, 180)`.
    pub fn look_at(eye: Vec3, target: Vec3, up: Vec3, vfov_deg: f32) -> crate::Result<Self> {
        let forward = (target - eye).normalize_or_zero();
        let right = forward.cross(up).normalize_or_zero();
        if !(eye.is_finite() && target.is_finite() && up.is_finite()) {
            return Err(crate::Error::param(
                "camera",
                "eye, target and up must be finite",
            ));
        }
        if forward == Vec3::ZERO || right == Vec3::ZERO {
            return Err(crate::Error::param(
                "camera",
                "the eye must differ from the target, and up must not lie along the view",
            ));
        }
        if !(vfov_deg > 0.0 && vfov_deg < 180.0) {
            return Err(crate::Error::param(
                "camera",
                format!("the vertical field of view must be in (0, 180) degrees, got {vfov_deg}"),
            ));
        }
        Ok(Camera {
            eye,
            forward,
            up: right.cross(forward),
            vfov_deg,
        })
    }

    /// A camera that sees the whole box `lo..hi` from its front (glTF's
    /// +z, +y up), a little above, with a 40-degree vertical field of view:
    /// the box's bounding sphere fits the view with a tenth to spare, as a
    /// glTF viewer frames a model that comes without a camera.
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] for a box that is not finite.
    pub fn framing(lo: Vec3, hi: Vec3) -> crate::Result<Self> {
        const VFOV_DEG: f32 = 40.0;
        let centre = (lo + hi) * 0.5;
        let radius = ((hi - lo).length() * 0.5).max(1e-3);
        let distance = 1.1 * radius / (0.5 * VFOV_DEG).to_radians().sin();
        let from = Vec3::new(0.0, 0.25, 1.0).normalize();
        Self::look_at(centre + from * distance, centre, Vec3::Y, VFOV_DEG)
    }
}

/// A scene ready to be traced.
///
/// Its fields are private to the crate: a `Scene` is only built through
/// [`Scene::add_material`], [`Scene::add_mesh`], [`Scene::add_light`] and
/// [`Scene::set_camera`], which refuse what would later panic or abort
/// (bad indices, non-finite or huge coordinates, overflowing powers), so every
/// `Scene` a caller holds can be committed and traced.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    /// Materials; meshes refer to them by index.
    pub(crate) materials: Vec<Material>,
    /// Triangle meshes.
    pub(crate) meshes: Vec<Mesh>,
    /// Lights: one per emissive mesh, plus punctual lights.
    pub(crate) lights: Vec<Light>,
    /// The camera, when the file has one.
    pub(crate) camera: Option<Camera>,
    /// Zero-area triangles dropped while loading.
    pub(crate) skipped_degenerate: usize,
    /// Per mesh, the caller's index of each kept triangle, when some were
    /// dropped (`None`: the identity). Maps `Hit::prim_id` back.
    pub(crate) source_triangles: Vec<Option<Vec<u32>>>,
    /// What the loader skipped or changed without refusing the file.
    pub(crate) warnings: Vec<String>,
    /// Textures; [`MaterialMaps`] refer to them by index.
    pub(crate) textures: Vec<Texture>,
    /// Per material, its textures (`None`, or past the end: untextured).
    pub(crate) material_maps: Vec<Option<MaterialMaps>>,
    /// Per material, its emissive texture (`None`, or past the end: none).
    pub(crate) emission_textures: Vec<Option<TextureRef>>,
    /// Emissive textures as their lights share them (one copy each).
    pub(crate) shared_textures: Vec<Option<std::sync::Arc<Texture>>>,
    /// Per material, its alpha mask (`None`, or past the end: opaque).
    pub(crate) alpha_masks: Vec<Option<AlphaMask>>,
    /// Bounds of every kept triangle's vertices, `None` before the first
    /// mesh: kept as meshes are added, so that directional lights can be
    /// refitted to it without a pass over all the geometry.
    pub(crate) geometry_bounds: Option<(Vec3, Vec3)>,
    /// Per material, its transmitted part (`None`, or past the end: none).
    pub(crate) transmission_mixes: Vec<Option<TransmissionMix>>,
}

/// `bounds` grown by the vertices of `mesh`'s triangles.
fn mesh_bounds(mesh: &Mesh, bounds: Option<(Vec3, Vec3)>) -> (Vec3, Vec3) {
    let start = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    let (mut lo, mut hi) = bounds.unwrap_or(start);
    for t in &mesh.indices {
        for &i in t {
            lo = lo.min(mesh.positions[i as usize]);
            hi = hi.max(mesh.positions[i as usize]);
        }
    }
    (lo, hi)
}

/// Area of a triangle.
pub fn triangle_area([a, b, c]: [Vec3; 3]) -> f32 {
    0.5 * (b - a).cross(c - a).length()
}

impl Scene {
    /// An empty scene.
    pub fn new() -> Self {
        Self::default()
    }

    /// The built-in Cornell box (see `assets/cornell_box.gltf`).
    #[cfg(feature = "gltf")]
    ///
    /// # Errors
    /// Never in practice: the asset is compiled in and tested.
    pub fn cornell() -> Result<Self> {
        cornell::load()
    }

    /// Loads a `.gltf` or `.glb` file; its external files are read from its
    /// own folder (see [`Scene::load_with`] for another).
    ///
    /// # Errors
    /// [`Error::Io`] (with the path) for a file that cannot be read: missing,
    /// unreadable, not a regular file, or over 2 GiB; [`Error::Load`] for a
    /// truncated or malformed one;
    /// [`Error::InvalidScene`] for NaN or infinite positions, an
    /// unsupported primitive, or an external file outside the
    /// scene's folder; [`Error::InvalidParameter`] for a negative or NaN
    /// `cos^n` exponent. A file without a light loads (most glTF models
    /// have none): give it one with [`Scene::add_light`], as tracing and
    /// rendering need one ([`Scene::validate`]).
    #[cfg(feature = "gltf")]
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        Self::load_with(path, &LoadOptions::default())
    }

    /// Loads a `.gltf` or `.glb` file as `options` say: with
    /// [`LoadOptions::asset_root`], its buffers and images may be anywhere
    /// inside that folder (`../buffers/x.bin`), never outside it.
    ///
    /// ```no_run
    /// # use adaptive_pm::scene::{LoadOptions, Scene};
    /// let options = LoadOptions::default().with_asset_root("assets");
    /// let scene = Scene::load_with("assets/scenes/room.gltf", &options)?;
    /// # Ok::<(), adaptive_pm::Error>(())
    /// ```
    ///
    /// # Errors
    /// As [`Scene::load`]; [`Error::Io`] naming the root when it cannot be
    /// resolved; [`Error::InvalidScene`] when it is not a folder, when it
    /// does not hold the scene file, or when an external file lies outside it
    /// (the message names the URI and the root).
    #[cfg(feature = "gltf")]
    pub fn load_with(path: impl AsRef<Path>, options: &LoadOptions) -> Result<Self> {
        gltf_load::load_path(path.as_ref(), options)
    }

    /// A built-in scene by name ([`builtin_names`]), else a path to a glTF
    /// file: the command line's scene argument (a library names its scene
    /// explicitly, with [`Scene::cornell`] or [`Scene::load`]).
    #[cfg(feature = "gltf")]
    #[doc(hidden)]
    ///
    /// # Errors
    /// As [`Scene::load`]; [`Error::InvalidScene`] listing the built-in names
    /// when `name_or_path` is neither a built-in name nor an existing file.
    pub fn open(name_or_path: &str) -> Result<Self> {
        Self::open_with(name_or_path, &LoadOptions::default())
    }

    /// As [`Scene::open`], a file loaded as `options` say.
    #[cfg(feature = "gltf")]
    #[doc(hidden)]
    ///
    /// # Errors
    /// As [`Scene::open`] and [`Scene::load_with`]; [`Error::InvalidScene`]
    /// for an asset root given with a built-in scene (it reads no file).
    pub fn open_with(name_or_path: &str, options: &LoadOptions) -> Result<Self> {
        if let Some(s) = cornell::builtin(name_or_path) {
            if let Some(root) = &options.asset_root {
                return Err(Error::InvalidScene(format!(
                    "the built-in scene `{name_or_path}` reads no file: the asset root `{}` does not apply",
                    root.display()
                )));
            }
            return s;
        }
        if !Path::new(name_or_path).exists() {
            return Err(Error::InvalidScene(format!(
                "`{name_or_path}` is neither a built-in scene ({}) nor an existing glTF file",
                builtin_names().join(", ")
            )));
        }
        Self::load_with(name_or_path, options)
    }

    /// Adds a material and returns its index.
    pub fn add_material(&mut self, material: Material) -> usize {
        self.materials.push(material);
        self.materials.len() - 1
    }

    /// Adds a mesh; an emissive material makes it an area light.
    /// Zero-area triangles are dropped and counted in [`Scene::skipped_degenerate`];
    /// [`Scene::source_triangle`] maps a kept triangle back to `indices`.
    ///
    /// # Errors
    /// [`Error::InvalidScene`] naming the mesh for a position that is not
    /// finite or beyond [`MAX_COORDINATE`], an index out of range, an unknown
    /// material or one with a bad emission, only degenerate triangles, or an
    /// emitted power that overflows.
    pub fn add_mesh(
        &mut self,
        name: impl Into<String>,
        positions: Vec<Vec3>,
        indices: Vec<[u32; 3]>,
        material: usize,
    ) -> Result<usize> {
        let name = name.into();
        let Some(mat) = self.materials.get(material) else {
            return Err(Error::InvalidScene(format!(
                "mesh `{name}` refers to material {material}, which does not exist"
            )));
        };
        checks::check_material(mat)?;
        checks::check_positions(&name, &positions)?;
        let n = positions.len() as u64;
        if let Some(t) = indices
            .iter()
            .position(|t| t.iter().any(|&i| i as u64 >= n))
        {
            // The index values are not shown: they may be bytes of any file.
            return Err(Error::InvalidScene(format!(
                "mesh `{name}` has triangle {t} indexing past its {n} vertices"
            )));
        }
        let (indices, source) = checks::drop_degenerate(&positions, indices);
        let dropped = source.as_ref().map_or(0, |s| s.len_dropped);
        if indices.is_empty() && dropped > 0 {
            return Err(Error::InvalidScene(format!(
                "mesh `{name}` has only degenerate (zero-area) triangles ({dropped})"
            )));
        }
        if indices.is_empty() {
            return Err(Error::InvalidScene(format!(
                "mesh `{name}` has no triangle"
            )));
        }
        let emission = mat.emission;
        let mesh = Mesh {
            name,
            positions,
            indices,
            material,
            normals: Vec::new(),
            texcoords: Vec::new(),
            colors: Vec::new(),
            tangents: Vec::new(),
        };
        let light = match emission {
            Some(e) => Some(checks::area_light(&mesh, self.meshes.len(), e)?),
            None => None,
        };
        self.skipped_degenerate += dropped;
        self.source_triangles.push(source.map(|s| s.kept));
        self.geometry_bounds = Some(mesh_bounds(&mesh, self.geometry_bounds));
        self.meshes.push(mesh);
        if let Some(light) = light {
            self.lights.push(Light::Area(light));
        }
        self.fit_directional_lights();
        Ok(self.meshes.len() - 1)
    }

    /// Gives every directional light the disc of the geometry as it is now:
    /// called whenever a mesh or a light is added, so no disc is stale.
    fn fit_directional_lights(&mut self) {
        let bounds = self.geometry_bounds;
        for l in &mut self.lights {
            if let Light::Directional(d) = l {
                d.fit(bounds);
            }
        }
    }

    /// Gives mesh `mesh` per-vertex shading normals (one per vertex; they are
    /// normalised, and a zero or non-finite one makes the mesh flat again).
    ///
    /// # Errors
    /// [`Error::InvalidScene`] for an unknown mesh or a count that is not the
    /// mesh's vertex count.
    pub fn set_vertex_normals(&mut self, mesh: usize, normals: Vec<Vec3>) -> Result<()> {
        let m = self.mesh_for_vertex_data(mesh, normals.len(), ("normals", "normals".into()))?;
        let unit: Vec<Vec3> = normals.iter().map(|n| n.normalize_or_zero()).collect();
        m.normals = if unit.iter().all(|n| *n != Vec3::ZERO) {
            unit
        } else {
            Vec::new()
        };
        Ok(())
    }

    /// Gives mesh `mesh` per-vertex colours (linear RGB, one per vertex)
    /// that multiply the base colour of its material where it is a glTF
    /// material with maps ([`Scene::set_material_maps`]; the loader gives
    /// one to every material a coloured mesh uses), as glTF's `COLOR_0`
    /// does. Mirrors and glass scatter by their factors.
    ///
    /// # Errors
    /// [`Error::InvalidScene`] for an unknown mesh, a count that is not the
    /// mesh's vertex count, or a channel outside [0, 1] or NaN.
    pub fn set_vertex_colors(&mut self, mesh: usize, colors: Vec<Vec3>) -> Result<()> {
        let m = self.mesh_for_vertex_data(mesh, colors.len(), ("colours", "colours".into()))?;
        let outside = |c: &Vec3| !(c.min_element() >= 0.0 && c.max_element() <= 1.0);
        if let Some(i) = colors.iter().position(outside) {
            return Err(Error::InvalidScene(format!(
                "mesh `{}` has the vertex colour {} at vertex {i}: channels must be in [0, 1]",
                m.name, colors[i]
            )));
        }
        m.colors = colors;
        Ok(())
    }

    /// Mesh `mesh`, when it exists and has `n` vertices, for per-vertex
    /// data named `(what it is given, what the values are)` in errors.
    fn mesh_for_vertex_data(
        &mut self,
        mesh: usize,
        n: usize,
        (given, values): (&str, String),
    ) -> Result<&mut Mesh> {
        let Some(m) = self.meshes.get_mut(mesh) else {
            return Err(Error::InvalidScene(format!(
                "no mesh {mesh} to give {given}"
            )));
        };
        if n != m.positions.len() {
            return Err(Error::InvalidScene(format!(
                "mesh `{}` has {} vertices but {n} {values}",
                m.name,
                m.positions.len()
            )));
        }
        Ok(m)
    }

    /// Adds a punctual light (point, spot or directional) and returns its
    /// index in [`Scene::lights`]. A directional light's photon disc is
    /// fitted to the scene's geometry, now and whenever a mesh is added
    /// later; its power, which depends on that disc, is checked by
    /// [`Scene::validate`].
    ///
    /// # Errors
    /// [`Error::InvalidScene`] for a position that is not finite or beyond
    /// [`MAX_COORDINATE`], a spot axis or a directional light's direction that
    /// is not finite and non-zero, cone cosines out of order, a negative or
    /// non-finite intensity or irradiance, or a power that overflows. Area
    /// lights come from [`Scene::add_mesh`] only.
    pub fn add_light(&mut self, light: Light) -> Result<usize> {
        checks::check_punctual(&light)?;
        self.lights.push(light);
        self.fit_directional_lights();
        Ok(self.lights.len() - 1)
    }

    /// Sets the camera.
    ///
    /// # Errors
    /// [`Error::InvalidScene`] for an eye that is not finite or beyond
    /// [`MAX_COORDINATE`], axes that are not orthogonal unit vectors, or a
    /// vertical field of view outside (0, 180) degrees.
    pub fn set_camera(&mut self, camera: Camera) -> Result<()> {
        checks::check_camera(&camera)?;
        self.camera = Some(camera);
        Ok(())
    }

    /// Removes every light: emissive meshes stay but no longer emit photons,
    /// and [`Scene::validate`] refuses a scene left without light.
    pub fn clear_lights(&mut self) {
        self.lights.clear();
    }

    /// Materials; meshes refer to them by index.
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    /// Triangle meshes, in the order they were added (the Embree geometry id).
    pub fn meshes(&self) -> &[Mesh] {
        &self.meshes
    }

    /// Lights: one per emissive mesh, plus punctual lights.
    pub fn lights(&self) -> &[Light] {
        &self.lights
    }

    /// The camera, when the scene has one.
    pub fn camera(&self) -> Option<Camera> {
        self.camera
    }

    /// Zero-area triangles dropped by [`Scene::add_mesh`].
    pub fn skipped_degenerate(&self) -> usize {
        self.skipped_degenerate
    }

    /// What the loader skipped without refusing the file (a points or lines
    /// primitive, ...), one sentence each, naming the object.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// The index, in the `indices` given to [`Scene::add_mesh`], of triangle
    /// `prim_id` of mesh `mesh` (a hit's `geom_id` and `prim_id`): they differ
    /// once degenerate triangles were dropped. `None` when out of range.
    pub fn source_triangle(&self, mesh: u32, prim_id: u32) -> Option<usize> {
        let m = self.meshes.get(mesh as usize)?;
        if prim_id as usize >= m.indices.len() {
            return None;
        }
        match self.source_triangles.get(mesh as usize)? {
            Some(map) => map.get(prim_id as usize).map(|&i| i as usize),
            None => Some(prim_id as usize),
        }
    }

    /// The offset that keeps a ray leaving a surface off it: `1e-5` of the
    /// scene's bounding-box diagonal, at least `1e-8`. One value for the
    /// tracer, the renderer and the benchmarks.
    pub fn ray_epsilon(&self) -> f32 {
        let (lo, hi) = self.bounds();
        let d = (hi - lo).length();
        if d.is_finite() {
            1e-5 * d.max(1e-3)
        } else {
            1e-8
        }
    }

    /// Sets every area light's `cos^n` exponent (the `--cosn` override).
    pub fn set_cosn(&mut self, profile: CosN) {
        for m in &mut self.materials {
            if let Some(e) = &mut m.emission {
                e.profile = profile;
            }
        }
        for l in &mut self.lights {
            if let Light::Area(a) = l {
                a.set_profile(profile);
            }
        }
    }

    /// Total triangle count.
    pub fn triangle_count(&self) -> usize {
        self.meshes.iter().map(|m| m.indices.len()).sum()
    }

    /// Axis-aligned bounds of the meshes alone; `None` without a triangle.
    pub fn geometry_bounds(&self) -> Option<(Vec3, Vec3)> {
        self.geometry_bounds
    }

    /// Axis-aligned bounds of all meshes (and point and spot light positions);
    /// `lo` infinite and above `hi` when the scene is empty.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let (mut lo, mut hi) = self
            .geometry_bounds
            .unwrap_or((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)));
        for l in &self.lights {
            if let Some(p) = l.position() {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        (lo, hi)
    }

    /// Checks the scene can be traced and rendered.
    ///
    /// # Errors
    /// [`Error::InvalidScene`] when it has no light or no triangle (a
    /// directional light without geometry has no bounds to emit across),
    /// when a directional light's power is unusable, when the lights' total
    /// power is above [`MAX_LIGHT_POWER`] in some channel, or when every
    /// light is dark.
    pub fn validate(&self) -> Result<()> {
        if self.lights.is_empty() {
            return Err(Error::InvalidScene(
                "the scene has no light: give a material an emissiveFactor, or add a \
                 KHR_lights_punctual light"
                    .into(),
            ));
        }
        self.check_contents()?;
        if !self.lights.iter().any(|l| luminance(l.power()) > 0.0) {
            return Err(Error::InvalidScene(
                "the scene has no light that emits: every light's power is zero".into(),
            ));
        }
        Ok(())
    }

    /// What [`Self::validate`] checks but that the scene has a light that
    /// emits: a file without one loads (most glTF models have none), so
    /// that lights can be added with [`Self::add_light`].
    pub(crate) fn check_contents(&self) -> Result<()> {
        if self.triangle_count() == 0 {
            let directional = self
                .lights
                .iter()
                .any(|l| matches!(l, Light::Directional(_)));
            return Err(Error::InvalidScene(if directional {
                "the scene has a directional light but no triangle: with no bounds there is \
                 nowhere to send its photons from (add geometry for it to light)"
                    .into()
            } else {
                "the scene has no triangle".into()
            }));
        }
        self.check_texcoords()?;
        self.check_emission_texcoords()?;
        checks::check_directional_powers(&self.lights)?;
        // In f64: forty lights of 1e37 W each summed to infinity in f32.
        let total = self.lights.iter().fold([0.0f64; 3], |mut t, l| {
            let p = l.power();
            for (t, c) in t.iter_mut().zip([p.x, p.y, p.z]) {
                *t += f64::from(c);
            }
            t
        });
        let max = total.into_iter().fold(0.0, f64::max);
        if max > f64::from(checks::MAX_LIGHT_POWER) {
            return Err(Error::InvalidScene(format!(
                "the lights' total power {max:e} W is above {:e} W (scale the scene's lights down)",
                checks::MAX_LIGHT_POWER
            )));
        }
        Ok(())
    }

    // `commit` (the scene and its Embree geometry, owned together) is in
    // src/embree/commit.rs: Embree-specific code stays in src/embree/.

    /// An area-uniform sampler over every triangle of the scene.
    pub fn surface_sampler(&self) -> SurfaceSampler {
        SurfaceSampler::new(self)
    }
}

#[cfg(test)]
mod area_tests {
    use super::*;

    #[test]
    fn framing_sees_every_corner_of_the_box() {
        for (lo, hi) in [
            (Vec3::splat(-0.5), Vec3::splat(0.5)),
            (Vec3::new(0.0, 0.0, 0.0), Vec3::new(556.0, 548.8, 559.2)),
            (Vec3::new(-1e3, 0.0, -2.0), Vec3::new(1e3, 0.1, 2.0)),
        ] {
            let c = Camera::framing(lo, hi).unwrap();
            let half = (0.5 * c.vfov_deg).to_radians();
            for i in 0..8 {
                let corner = Vec3::new(
                    if i & 1 == 0 { lo.x } else { hi.x },
                    if i & 2 == 0 { lo.y } else { hi.y },
                    if i & 4 == 0 { lo.z } else { hi.z },
                );
                let to = (corner - c.eye).normalize();
                // Inside a cone of the vertical half-angle: inside the
                // (square or wider) image.
                assert!(to.dot(c.forward) > half.cos(), "{lo} {hi}: corner {corner}");
            }
        }
        assert!(Camera::framing(Vec3::splat(f32::NAN), Vec3::ONE).is_err());
    }

    /// A 10 x 10 floor of 2 x 1000 x 1000 triangles: 100 exactly (each
    /// triangle's area, 5e-5, is nearly exact in f32); the f32 sum read 99.5.
    #[test]
    fn a_million_small_triangles_add_up_to_their_area() {
        let n = 1000u32;
        let h = 10.0 / n as f32;
        let positions = (0..=n)
            .flat_map(|i| (0..=n).map(move |j| Vec3::new(i as f32 * h, 0.0, j as f32 * h)))
            .collect();
        let at = |i: u32, j: u32| i * (n + 1) + j;
        let indices = (0..n)
            .flat_map(|i| {
                (0..n).flat_map(move |j| {
                    [
                        [at(i, j), at(i, j + 1), at(i + 1, j)],
                        [at(i + 1, j), at(i, j + 1), at(i + 1, j + 1)],
                    ]
                })
            })
            .collect();
        let mesh = Mesh {
            name: "floor".into(),
            positions,
            indices,
            material: 0,
            normals: Vec::new(),
            texcoords: Vec::new(),
            colors: Vec::new(),
            tangents: Vec::new(),
        };
        assert!((mesh.area() - 100.0).abs() < 1e-3, "{}", mesh.area());
    }
}
