//! Normal textures (glTF's `normalTexture`): a tangent-space normal per
//! texel that replaces the mesh's shading normal at each surface point.
//!
//! As glTF says (§3.9.3): the texel's RGB is linear, mapped to
//! `n_t = (2 rgb - 1) * (scale, scale, 1)`, and the shading normal is
//! `normalize(n_t.x T + n_t.y B + n_t.z N)` with `N` the interpolated
//! vertex normal (the winding normal on a flat mesh), `T` the tangent
//! (Gram–Schmidt-orthogonalised against `N`) and `B = (N x T) w`, `w` the
//! tangent's handedness. Tangents come from the mesh's `TANGENT` attribute
//! ([`Scene::set_vertex_tangents`]) or, as glTF asks when it is absent,
//! from the MikkTSpace algorithm over the positions, normals and the
//! normal texture's coordinates (`Scene::generate_tangents`, feature `gltf`, by the
//! `bevy_mikktspace` crate). They are kept per triangle corner, since
//! MikkTSpace may give one shared vertex different tangents in two faces.
//!
//! The mapped normal is a shading normal like the interpolated one, and is
//! used wherever that is ([`Scene::shading_normal`]): the frame mirrors and
//! glass reflect and refract in, and the frame the renderer and the path
//! tracer evaluate other BRDFs in (`docs/scenes.md`, "Normal textures").

use super::texture::{Encoding, TextureRef};
use super::{Mesh, Scene};
use crate::error::{Error, Result};
use crate::raycast::Hit;
use glam::{Vec2, Vec3, Vec4};

/// A material's normal texture and its `scale` (of the tangent-space x and y).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NormalMap {
    /// The texture (linear RGB) and the coordinates it reads.
    pub texture: TextureRef,
    /// glTF's `normalTexture.scale`.
    pub scale: f32,
}

impl Mesh {
    /// The winding (front) normal of triangle `i`, unit; `None` when degenerate.
    fn winding_normal(&self, i: usize) -> Option<Vec3> {
        let [a, b, c] = self.triangle(i);
        let n = (b - a).cross(c - a).normalize_or_zero();
        (n != Vec3::ZERO).then_some(n)
    }

    /// The interpolated tangent (xyz) and handedness (w, +1 or -1) of
    /// triangle `i` at barycentrics `(u, v)`.
    fn tangent_at(&self, i: usize, u: f32, v: f32) -> Option<Vec4> {
        let [t0, t1, t2] = *self.tangents.get(i)?;
        let t = t0.truncate() * (1.0 - u - v) + t1.truncate() * u + t2.truncate() * v;
        Some(t.extend(if t0.w < 0.0 { -1.0 } else { 1.0 }))
    }
}

/// The tangent-space normal of a texel: `(2 rgb - 1) * (scale, scale, 1)`.
pub fn tangent_space_normal(texel: Vec4, scale: f32) -> Vec3 {
    let n = texel.truncate() * 2.0 - Vec3::ONE;
    Vec3::new(n.x * scale, n.y * scale, n.z)
}

/// `n_t` in the frame `(T, B, N)` built from `normal` and `tangent` (module
/// docs); `None` when the frame or the result is degenerate.
pub fn perturb(normal: Vec3, tangent: Vec4, n_t: Vec3) -> Option<Vec3> {
    let t = (tangent.truncate() - normal * normal.dot(tangent.truncate())).normalize_or_zero();
    if t == Vec3::ZERO {
        return None;
    }
    let b = normal.cross(t) * tangent.w;
    let n = (t * n_t.x + b * n_t.y + normal * n_t.z).normalize_or_zero();
    (n != Vec3::ZERO && n.is_finite()).then_some(n)
}

impl Scene {
    /// The shading normal at a hit: the mesh's interpolated vertex normal,
    /// perturbed by its material's normal texture when it has one (module
    /// docs); `None` for a flat mesh without a normal texture (shade with
    /// the geometric normal). Not flipped to any side.
    ///
    /// A flat mesh without a normal texture (every hit of the built-in
    /// boxes) is answered inline: the full lookup, a call at every photon
    /// hit, cost the tracer about 70 instructions a hit (callgrind).
    #[inline]
    pub fn shading_normal(&self, hit: &Hit) -> Option<Vec3> {
        let mesh = self.meshes.get(hit.geom_id as usize)?;
        let map = self
            .material_maps(mesh.material)
            .and_then(|m| m.normal.as_ref());
        if mesh.normals.is_empty() && map.is_none() {
            return None;
        }
        self.curved_shading_normal(mesh, map, hit)
    }

    /// [`Self::shading_normal`] of a mesh with vertex normals or a normal
    /// texture (`map`).
    #[inline(never)]
    fn curved_shading_normal(
        &self,
        mesh: &Mesh,
        map: Option<&NormalMap>,
        hit: &Hit,
    ) -> Option<Vec3> {
        let i = hit.prim_id as usize;
        let interpolated = mesh.shading_normal(i, hit.u, hit.v);
        let Some(map) = map else {
            return interpolated;
        };
        let base = interpolated.or_else(|| mesh.winding_normal(i))?;
        let mapped = (|| {
            let tangent = mesh.tangent_at(i, hit.u, hit.v)?;
            let uv = self.texcoord(hit, &map.texture)?;
            let texel = self.textures[map.texture.texture].sample(uv, Encoding::Linear);
            perturb(base, tangent, tangent_space_normal(texel, map.scale))
        })();
        Some(mapped.unwrap_or(base))
    }

    /// Gives mesh `mesh` glTF `TANGENT`s, one per vertex (world space: xyz
    /// the tangent, w its handedness, +1 or -1).
    ///
    /// # Errors
    /// [`Error::InvalidScene`] for an unknown mesh, a count that is not the
    /// mesh's vertex count, or a tangent that is not finite.
    pub fn set_vertex_tangents(&mut self, mesh: usize, tangents: Vec<Vec4>) -> Result<()> {
        let what = ("tangents", "TANGENT values".to_string());
        let m = self.mesh_for_vertex_data(mesh, tangents.len(), what)?;
        if let Some(i) = tangents.iter().position(|t| !t.is_finite()) {
            return Err(Error::InvalidScene(format!(
                "mesh `{}` has a TANGENT that is not finite (vertex {i})",
                m.name
            )));
        }
        let corner = |i: u32| {
            let t = tangents[i as usize];
            t.truncate().extend(if t.w < 0.0 { -1.0 } else { 1.0 })
        };
        m.tangents = m.indices.iter().map(|t| t.map(corner)).collect();
        Ok(())
    }

    /// Computes mesh `mesh`'s tangents by MikkTSpace (feature `gltf`) from its positions, its
    /// normals (the winding normals on a flat mesh) and its texture
    /// coordinates `TEXCOORD_set`.
    ///
    /// # Errors
    /// [`Error::InvalidScene`] for an unknown mesh, a mesh without that set,
    /// or coordinates from which MikkTSpace finds no tangent at all.
    #[cfg(feature = "gltf")]
    pub fn generate_tangents(&mut self, mesh: usize, set: usize) -> Result<()> {
        let Some(m) = self.meshes.get_mut(mesh) else {
            return Err(Error::InvalidScene(format!(
                "no mesh {mesh} to give tangents"
            )));
        };
        if m.texcoords.get(set).is_none_or(Vec::is_empty) {
            return Err(Error::InvalidScene(format!(
                "mesh `{}` has no TEXCOORD_{set} to derive its tangents from",
                m.name
            )));
        }
        let mut geometry = Mikk {
            mesh: m,
            set,
            out: Vec::new(),
        };
        geometry.out = vec![[Vec4::ZERO; 3]; geometry.mesh.indices.len()];
        let ok = bevy_mikktspace::generate_tangents(&mut geometry).is_ok();
        let out = std::mem::take(&mut geometry.out);
        if !ok || out.iter().flatten().all(|t| t.truncate() == Vec3::ZERO) {
            return Err(Error::InvalidScene(format!(
                "mesh `{}`: MikkTSpace finds no tangent from its TEXCOORD_{set} \
                 (are they all equal?)",
                m.name
            )));
        }
        m.tangents = out;
        Ok(())
    }
}

/// A mesh seen by MikkTSpace: one face per triangle.
#[cfg(feature = "gltf")]
struct Mikk<'a> {
    mesh: &'a Mesh,
    set: usize,
    /// Per triangle corner; a corner MikkTSpace leaves out stays zero (the
    /// shading normal there is the unperturbed one).
    out: Vec<[Vec4; 3]>,
}

#[cfg(feature = "gltf")]
impl Mikk<'_> {
    fn vertex(&self, face: usize, vert: usize) -> usize {
        self.mesh.indices[face][vert] as usize
    }
}

#[cfg(feature = "gltf")]
impl bevy_mikktspace::Geometry for Mikk<'_> {
    fn num_faces(&self) -> usize {
        self.mesh.indices.len()
    }

    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }

    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.mesh.positions[self.vertex(face, vert)].to_array()
    }

    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        let n = match self.mesh.normals.get(self.vertex(face, vert)) {
            Some(n) => *n,
            None => self.mesh.winding_normal(face).unwrap_or(Vec3::Z),
        };
        n.to_array()
    }

    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        let uv: Vec2 = self.mesh.texcoords[self.set][self.vertex(face, vert)];
        uv.to_array()
    }

    fn set_tangent(
        &mut self,
        tangent_space: Option<bevy_mikktspace::TangentSpace>,
        face: usize,
        vert: usize,
    ) {
        if let Some(t) = tangent_space {
            self.out[face][vert] = Vec4::from_array(t.tangent_encoded());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_flat_texel_keeps_the_normal() {
        let flat = Vec4::new(0.5, 0.5, 1.0, 1.0);
        let n = perturb(
            Vec3::Z,
            Vec4::new(1.0, 0.0, 0.0, 1.0),
            tangent_space_normal(flat, 1.0),
        );
        assert!((n.unwrap() - Vec3::Z).length() < 1e-6);
    }

    #[test]
    fn a_tilted_texel_tilts_along_the_tangent_and_the_bitangent() {
        // (x, y, z) = (sin 30, 0, cos 30): tilted 30 degrees towards T.
        let (s, c) = 30f32.to_radians().sin_cos();
        let texel = Vec4::new((s + 1.0) / 2.0, 0.5, (c + 1.0) / 2.0, 1.0);
        let t = Vec4::new(1.0, 0.0, 0.0, 1.0);
        let n = perturb(Vec3::Z, t, tangent_space_normal(texel, 1.0)).unwrap();
        assert!((n - Vec3::new(s, 0.0, c)).length() < 1e-6, "{n}");
        // y goes along B = N x T = +Y, or -Y when the handedness is -1.
        let texel = Vec4::new(0.5, (s + 1.0) / 2.0, (c + 1.0) / 2.0, 1.0);
        let n = perturb(Vec3::Z, t, tangent_space_normal(texel, 1.0)).unwrap();
        assert!((n - Vec3::new(0.0, s, c)).length() < 1e-6, "{n}");
        let n = perturb(
            Vec3::Z,
            t * Vec4::new(1.0, 1.0, 1.0, -1.0),
            tangent_space_normal(texel, 1.0),
        );
        assert!((n.unwrap() - Vec3::new(0.0, -s, c)).length() < 1e-6);
    }

    #[test]
    fn scale_multiplies_x_and_y_only() {
        let texel = Vec4::new(0.75, 0.25, 0.8, 1.0);
        let n = tangent_space_normal(texel, 2.0);
        assert!((n - Vec3::new(1.0, -1.0, 0.6)).length() < 1e-6, "{n}");
    }

    /// One triangle in z = 0 (winding normal +z) of a grey material.
    fn one_triangle() -> Scene {
        let mut scene = Scene::new();
        let grey = scene.add_material(crate::scene::Material {
            name: "grey".into(),
            brdf: crate::brdf::Lambert::new(Vec3::splat(0.5)).unwrap().into(),
            emission: None,
        });
        let positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y];
        scene
            .add_mesh("t", positions, vec![[0, 1, 2]], grey)
            .unwrap();
        scene
    }

    fn hit_at(u: f32, v: f32) -> Hit {
        Hit {
            t: 1.0,
            ng: Vec3::Z,
            geom_id: 0,
            prim_id: 0,
            u,
            v,
            material: 0,
        }
    }

    #[test]
    fn a_flat_mesh_has_no_shading_normal_and_vertex_normals_are_interpolated() {
        let mut scene = one_triangle();
        assert_eq!(scene.shading_normal(&hit_at(0.25, 0.25)), None);
        let tilted = Vec3::new(1.0, 0.0, 1.0).normalize();
        scene
            .set_vertex_normals(0, vec![Vec3::Z, tilted, Vec3::Z])
            .unwrap();
        let n = scene.shading_normal(&hit_at(0.5, 0.0)).unwrap();
        let want = (Vec3::Z + tilted).normalize();
        assert!((n - want).length() < 1e-6, "{n}");
        assert_eq!(scene.shading_normal(&hit_at(0.0, 0.0)), Some(Vec3::Z));
        // A hit on a mesh the scene does not have.
        let mut far = hit_at(0.0, 0.0);
        far.geom_id = 3;
        assert_eq!(scene.shading_normal(&far), None);
    }

    #[test]
    fn a_tangent_along_the_normal_is_degenerate() {
        let n_t = Vec3::new(0.3, 0.0, 0.9);
        assert_eq!(perturb(Vec3::Z, Vec4::new(0.0, 0.0, 2.0, 1.0), n_t), None);
    }
}
