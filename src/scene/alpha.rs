//! Alpha masks (glTF `alphaMode: MASK`): cut-outs, so that leaves and fences
//! are holes, not walls.
//!
//! - A masked material's alpha at a point is `factor * texel.a`: glTF's
//!   `baseColorFactor.a` times the alpha of `baseColorTexture` (linear, not
//!   sRGB-decoded; filtered and wrapped by its sampler, through its
//!   `KHR_texture_transform`, at the hit's interpolated `TEXCOORD_n`), or the
//!   factor alone without a texture. A point whose alpha is below the
//!   cut-off (`alphaCutoff`, default 0.5) is a **hole**: no surface is there.
//! - Holes are cut in the ray caster, not in shading: every ray (photons,
//!   camera rays, gather and shadow rays, light sampling, the path tracer)
//!   passes through them as if the triangle were absent, so no photon is
//!   stored and no path scatters in a hole. With Embree the caster asks a
//!   [`Cutout`] from Embree's intersection and occlusion filters
//!   ([`crate::embree::HitFilter`]); a caster of one's own asks
//!   [`Scene::is_hole`] while it traverses and says so with
//!   [`crate::raycast::RayCaster::cuts_alpha_masks`]. A scene with holes is
//!   refused for a caster that does not cut them.
//! - A mask that cannot fall below its cut-off (the factor times the least
//!   texel alpha is at least the cut-off) cuts no hole: the material is
//!   opaque, costs nothing, and none of the refusals below applies to it.
//! - Refused, naming the material: a cut-off that is not finite or is
//!   negative, a factor outside [0, 1], a mask with holes on an emissive
//!   material (holes must not emit: emission is sampled over the whole
//!   triangles, so the holes would have to be taken out of the light's
//!   sampling and power too; that is not done) and on refracting glass (a
//!   refracting mesh must be closed to say which side is inside).
//! - Everything else that uses a surface is unaffected: the BRDF at a hit
//!   ([`Scene::surface_brdf`]) is read where rays stop, which is never a
//!   hole; the area-uniform surface points ([`super::SurfaceSampler`]) leave
//!   the holes out.

use super::texture::{TexTransform, Texture, TextureRef};
use super::Scene;
use crate::brdf::Brdf;
use crate::error::{Error, Result};
use crate::raycast::Hit;
use glam::Vec2;
use std::sync::Arc;

/// A material's alpha mask: glTF `alphaMode: MASK` with its `alphaCutoff`,
/// `baseColorFactor.a` and `baseColorTexture` (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AlphaMask {
    /// A point whose alpha is below this is a hole (glTF's default 0.5).
    pub cutoff: f32,
    /// `baseColorFactor.a`, in [0, 1].
    pub factor: f32,
    /// The texture whose alpha multiplies the factor (glTF's
    /// `baseColorTexture`), if any.
    pub texture: Option<TextureRef>,
}

impl AlphaMask {
    /// glTF's default cut-off.
    pub const DEFAULT_CUTOFF: f32 = 0.5;

    /// A mask of `factor` alone (no texture) at `cutoff`.
    pub fn new(cutoff: f32, factor: f32) -> Self {
        AlphaMask {
            cutoff,
            factor,
            texture: None,
        }
    }

    /// This mask with `texture`'s alpha multiplying the factor.
    pub fn with_texture(mut self, texture: TextureRef) -> Self {
        self.texture = Some(texture);
        self
    }
}

/// The alpha at barycentrics `(u, v)` of triangle `tri`: the factor times
/// the texture's alpha at the interpolated coordinates. One function for
/// [`Cutout`] and [`Scene::is_hole`], so both cut the same holes.
#[inline]
fn alpha_at(
    factor: f32,
    map: Option<(&Texture, &TexTransform, &[Vec2])>,
    tri: Option<[u32; 3]>,
    u: f32,
    v: f32,
) -> f32 {
    let (Some((texture, transform, uvs)), Some([a, b, c])) = (map, tri) else {
        return factor;
    };
    let (Some(&ta), Some(&tb), Some(&tc)) = (
        uvs.get(a as usize),
        uvs.get(b as usize),
        uvs.get(c as usize),
    ) else {
        return factor;
    };
    // The interpolation `Scene::surface_brdf` reads colour textures with.
    let uv = ta * (1.0 - u - v) + tb * u + tc * v;
    factor * texture.alpha(transform.apply(uv))
}

/// The holes of one mesh, owning what it reads (a clone of the texture,
/// which shares its texels, the mesh's triangles and texture coordinates):
/// what an Embree filter, which outlives any borrow of the scene, asks.
/// Built by [`Scene::cutout`].
#[derive(Clone, Debug)]
pub struct Cutout {
    cutoff: f32,
    factor: f32,
    map: Option<CutoutMap>,
}

#[derive(Clone, Debug)]
struct CutoutMap {
    texture: Texture,
    transform: TexTransform,
    indices: Arc<[[u32; 3]]>,
    uvs: Arc<[Vec2]>,
}

impl Cutout {
    /// The alpha at barycentrics `(u, v)` (of vertices 1 and 2) of triangle
    /// `prim` of the mesh, as a [`Hit`] reports them. A triangle the mesh
    /// does not have reads the factor alone.
    #[inline]
    pub fn alpha(&self, prim: u32, u: f32, v: f32) -> f32 {
        match &self.map {
            None => self.factor,
            Some(m) => alpha_at(
                self.factor,
                Some((&m.texture, &m.transform, &m.uvs)),
                m.indices.get(prim as usize).copied(),
                u,
                v,
            ),
        }
    }

    /// Whether that point is a hole: its alpha is below the cut-off.
    #[inline]
    pub fn is_hole(&self, prim: u32, u: f32, v: f32) -> bool {
        self.alpha(prim, u, v) < self.cutoff
    }

    /// The cut-off.
    pub fn cutoff(&self) -> f32 {
        self.cutoff
    }
}

impl Scene {
    /// Gives material `material` an alpha mask (glTF `alphaMode: MASK`;
    /// module docs): its points of alpha below `mask.cutoff` become holes
    /// that every ray passes through.
    ///
    /// # Errors
    /// [`Error::InvalidScene`] naming the material for an unknown material
    /// or texture, a cut-off that is not finite or is negative, a factor
    /// outside [0, 1], and a mask that can cut holes in an emissive material
    /// or in refracting (not thin-walled) glass.
    pub fn set_alpha_mask(&mut self, material: usize, mask: AlphaMask) -> Result<()> {
        let Some(m) = self.materials.get(material) else {
            return Err(Error::InvalidScene(format!(
                "no material {material} to give an alpha mask"
            )));
        };
        let name = &m.name;
        if !(mask.cutoff.is_finite() && mask.cutoff >= 0.0) {
            return Err(Error::InvalidScene(format!(
                "material `{name}` has the alphaCutoff {}: it must be a finite number >= 0",
                mask.cutoff
            )));
        }
        if !(0.0..=1.0).contains(&mask.factor) {
            return Err(Error::InvalidScene(format!(
                "material `{name}` has the alpha factor {}: it must be in [0, 1]",
                mask.factor
            )));
        }
        if let Some(r) = mask.texture.filter(|r| r.texture >= self.textures.len()) {
            return Err(Error::InvalidScene(format!(
                "material `{name}`'s alpha mask reads texture {}, which does not exist",
                r.texture
            )));
        }
        if self.mask_cuts_holes(&mask) {
            if m.emission.is_some() {
                return Err(Error::InvalidScene(format!(
                    "material `{name}` is emissive and alphaMode MASK with holes (alpha below \
                     the cutoff {}): masked emitters are not supported, as holes must not emit; \
                     make it OPAQUE, or put the emission on a separate unmasked material",
                    mask.cutoff
                )));
            }
            // A partly transmitting material refracts by its glass part.
            let glass = self
                .transmission_mix(material as u32)
                .map(|t| &self.materials[t.glass]);
            let refracts = match glass.unwrap_or(m).brdf {
                Brdf::Dielectric(d) => !d.thin(),
                Brdf::RoughDielectric(d) => !d.thin(),
                _ => false,
            };
            if refracts {
                return Err(Error::InvalidScene(format!(
                    "material `{name}` refracts (glass with a volume) and is alphaMode MASK \
                     with holes: a refracting mesh must be closed, so it cannot have holes \
                     (make it thin-walled or OPAQUE)"
                )));
            }
        }
        if self.alpha_masks.len() <= material {
            self.alpha_masks.resize(material + 1, None);
        }
        self.alpha_masks[material] = Some(mask);
        Ok(())
    }

    /// The alpha mask of material `material`, when it has one.
    pub fn alpha_mask(&self, material: usize) -> Option<&AlphaMask> {
        self.alpha_masks.get(material)?.as_ref()
    }

    /// Whether `mask` can cut a hole anywhere: its factor times the least
    /// texel alpha of its texture is below its cut-off.
    fn mask_cuts_holes(&self, mask: &AlphaMask) -> bool {
        let least = mask
            .texture
            .and_then(|r| self.textures.get(r.texture))
            .map_or(1.0, |t| t.alpha_range().0);
        mask.factor * least < mask.cutoff
    }

    /// The mask of mesh `mesh`'s material, when it cuts holes.
    fn holes_of(&self, mesh: usize) -> Option<&AlphaMask> {
        let m = self.meshes.get(mesh)?;
        self.alpha_mask(m.material)
            .filter(|mask| self.mask_cuts_holes(mask))
    }

    /// Whether mesh `mesh` has holes: its material's alpha mask can cut
    /// some (module docs).
    pub fn mesh_has_holes(&self, mesh: usize) -> bool {
        self.holes_of(mesh).is_some()
    }

    /// Whether some mesh has holes.
    pub fn has_holes(&self) -> bool {
        (0..self.meshes.len()).any(|m| self.mesh_has_holes(m))
    }

    /// The holes of mesh `mesh` as a self-contained [`Cutout`], `None` when
    /// its material has no mask or one that cuts no hole. What
    /// `Scene::commit` hands Embree as the mesh's hit filter.
    pub fn cutout(&self, mesh: usize) -> Option<Cutout> {
        let mask = self.holes_of(mesh)?;
        let m = &self.meshes[mesh];
        let map = mask.texture.and_then(|r| {
            let uvs = m.texcoords.get(r.tex_coord).filter(|t| !t.is_empty())?;
            Some(CutoutMap {
                texture: self.textures.get(r.texture)?.clone(),
                transform: r.transform,
                indices: m.indices.as_slice().into(),
                uvs: uvs.as_slice().into(),
            })
        });
        Some(Cutout {
            cutoff: mask.cutoff,
            factor: mask.factor,
            map,
        })
    }

    /// Whether the point of `hit` (its `geom_id`, `prim_id`, `u` and `v`)
    /// lies in a hole of its mesh's alpha mask: what a ray caster of one's
    /// own asks of every candidate hit to cut the holes, as Embree's filters
    /// ask [`Cutout::is_hole`] (the same answer). `false` for a mesh
    /// without holes or one the scene does not have.
    pub fn is_hole(&self, hit: &Hit) -> bool {
        let mesh = hit.geom_id as usize;
        let Some(mask) = self.holes_of(mesh) else {
            return false;
        };
        let m = &self.meshes[mesh];
        let map = mask.texture.as_ref().and_then(|r| {
            let uvs = m.texcoords.get(r.tex_coord).filter(|t| !t.is_empty())?;
            Some((self.textures.get(r.texture)?, &r.transform, uvs.as_slice()))
        });
        let tri = m.indices.get(hit.prim_id as usize).copied();
        alpha_at(mask.factor, map, tri, hit.u, hit.v) < mask.cutoff
    }
}
