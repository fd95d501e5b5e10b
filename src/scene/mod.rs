//! The scene model: triangle meshes with a material each, area lights made of
//! emissive meshes with a `cos^n` profile, punctual lights, and an optional camera.
//!
//! Scenes come from glTF 2.0 files ([`Scene::load`]), from the built-in Cornell box
//! ([`Scene::cornell`]), or are assembled in code ([`Scene::new`], [`Scene::add_mesh`]).
//! Only what the scene uses is modelled: the directionality analysis later runs on
//! the emitters and materials found here, nothing else.

mod cornell;
mod gltf_load;
mod light;
mod surface;

pub use light::{AreaLight, EmittedPhoton, Light, PointLight, SpotLight};
pub use surface::{SurfacePoint, SurfaceSampler};

use crate::brdf::Brdf;
use crate::embree::{CommittedScene, Device};
use crate::emitter::CosN;
use crate::error::{Error, Result};
use glam::Vec3;
use std::path::Path;

/// What a built-in scene is called on the command line.
pub const BUILTIN_CORNELL: &str = "cornell";

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
/// geometric normal (the side the triangle winding faces). One-sided.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Emission {
    /// Radiance along the normal, linear RGB.
    pub radiance: Vec3,
    /// The angular profile.
    pub profile: CosN,
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

    /// Total surface area.
    pub fn area(&self) -> f32 {
        (0..self.indices.len())
            .map(|i| triangle_area(self.triangle(i)))
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
}

/// A scene ready to be traced.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    /// Materials; meshes refer to them by index.
    pub materials: Vec<Material>,
    /// Triangle meshes.
    pub meshes: Vec<Mesh>,
    /// Lights: one per emissive mesh, plus punctual lights.
    pub lights: Vec<Light>,
    /// The camera, when the file has one.
    pub camera: Option<Camera>,
    /// Zero-area triangles dropped while loading.
    pub skipped_degenerate: usize,
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
    ///
    /// # Errors
    /// Never in practice: the asset is compiled in and tested.
    pub fn cornell() -> Result<Self> {
        cornell::load()
    }

    /// Loads a `.gltf` or `.glb` file.
    ///
    /// # Errors
    /// [`Error::Load`] for a missing, truncated or malformed file;
    /// [`Error::InvalidScene`] for NaN or infinite positions, a scene without
    /// any light, or an unsupported primitive; [`Error::InvalidParameter`] for a
    /// negative or NaN `cos^n` exponent.
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        gltf_load::load_path(path.as_ref())
    }

    /// `cornell` for the built-in scene, else a path to a glTF file.
    ///
    /// # Errors
    /// As [`Scene::load`].
    pub fn open(name_or_path: &str) -> Result<Self> {
        if name_or_path == BUILTIN_CORNELL {
            Self::cornell()
        } else {
            Self::load(name_or_path)
        }
    }

    /// Adds a material and returns its index.
    pub fn add_material(&mut self, material: Material) -> usize {
        self.materials.push(material);
        self.materials.len() - 1
    }

    /// Adds a mesh; an emissive material makes it an area light.
    /// Zero-area triangles are dropped and counted in [`Scene::skipped_degenerate`].
    ///
    /// # Errors
    /// [`Error::InvalidScene`] for a non-finite position, an index out of range
    /// or an unknown material.
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
        if let Some(p) = positions.iter().find(|p| !p.is_finite()) {
            return Err(Error::InvalidScene(format!(
                "mesh `{name}` has a non-finite vertex position {p}"
            )));
        }
        let n = positions.len() as u64;
        if let Some(t) = indices.iter().find(|t| t.iter().any(|&i| i as u64 >= n)) {
            return Err(Error::InvalidScene(format!(
                "mesh `{name}` has a triangle {t:?} indexing past its {n} vertices"
            )));
        }
        let before = indices.len();
        let indices: Vec<[u32; 3]> = indices
            .into_iter()
            .filter(|&[a, b, c]| {
                let tri = [a, b, c].map(|i| positions[i as usize]);
                let c = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
                c.length_squared() > 0.0 && c.is_finite()
            })
            .collect();
        self.skipped_degenerate += before - indices.len();
        let emission = mat.emission;
        let mesh = Mesh {
            name,
            positions,
            indices,
            material,
            normals: Vec::new(),
        };
        self.meshes.push(mesh);
        let index = self.meshes.len() - 1;
        if let Some(e) = emission {
            if let Some(light) = AreaLight::new(&self.meshes[index], index, e) {
                self.lights.push(Light::Area(light));
            }
        }
        Ok(index)
    }

    /// Gives mesh `mesh` per-vertex shading normals (one per vertex; they are
    /// normalised, and a zero or non-finite one makes the mesh flat again).
    ///
    /// # Errors
    /// [`Error::InvalidScene`] for an unknown mesh or a count that is not the
    /// mesh's vertex count.
    pub fn set_vertex_normals(&mut self, mesh: usize, normals: Vec<Vec3>) -> Result<()> {
        let Some(m) = self.meshes.get_mut(mesh) else {
            return Err(Error::InvalidScene(format!(
                "no mesh {mesh} to give normals"
            )));
        };
        if normals.len() != m.positions.len() {
            return Err(Error::InvalidScene(format!(
                "mesh `{}` has {} vertices but {} normals",
                m.name,
                m.positions.len(),
                normals.len()
            )));
        }
        let unit: Vec<Vec3> = normals.iter().map(|n| n.normalize_or_zero()).collect();
        m.normals = if unit.iter().all(|n| *n != Vec3::ZERO) {
            unit
        } else {
            Vec::new()
        };
        Ok(())
    }

    /// Adds a punctual light.
    pub fn add_light(&mut self, light: Light) {
        self.lights.push(light);
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

    /// Axis-aligned bounds of all meshes (and punctual light positions).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for m in &self.meshes {
            for t in &m.indices {
                for &i in t {
                    lo = lo.min(m.positions[i as usize]);
                    hi = hi.max(m.positions[i as usize]);
                }
            }
        }
        for l in &self.lights {
            if let Some(p) = l.position() {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        (lo, hi)
    }

    /// Checks the scene can be traced.
    ///
    /// # Errors
    /// [`Error::InvalidScene`] when it has no light or no triangle.
    pub fn validate(&self) -> Result<()> {
        if self.lights.is_empty() {
            return Err(Error::InvalidScene(
                "the scene has no light: give a material an emissiveFactor, or add a \
                 KHR_lights_punctual light"
                    .into(),
            ));
        }
        if self.triangle_count() == 0 {
            return Err(Error::InvalidScene("the scene has no triangle".into()));
        }
        Ok(())
    }

    /// Hands the geometry to Embree. A hit's `material` is the mesh's material
    /// index and its `geom_id` the mesh index.
    ///
    /// # Errors
    /// [`Error::Embree`] when Embree rejects the geometry.
    pub fn commit(&self, device: &Device) -> Result<CommittedScene> {
        let mut builder = device.scene_builder()?;
        for m in &self.meshes {
            builder.add_triangles(&m.positions, &m.indices, m.material as u32)?;
        }
        builder.commit()
    }

    /// An area-uniform sampler over every triangle of the scene.
    pub fn surface_sampler(&self) -> SurfaceSampler {
        SurfaceSampler::new(self)
    }
}
