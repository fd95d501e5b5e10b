//! Textures as glTF 2.0 defines them: an image of 8-bit RGBA texels read
//! through a sampler (wrap modes and a filter), at texture coordinates that
//! `KHR_texture_transform` may offset, rotate and scale.
//!
//! - Texture coordinates: `(0, 0)` is the first texel of the image's first
//!   row (its top-left corner), `u` runs along a row and `v` down the rows.
//!   Texel `(i, j)` covers `[i, i + 1) / width x [j, j + 1) / height`, its
//!   centre at `((i + 0.5) / width, (j + 0.5) / height)`.
//! - Wrap modes (glTF `sampler.wrapS` / `wrapT`, default `REPEAT`) map any
//!   texel index into the image: `REPEAT` modulo the size,
//!   `CLAMP_TO_EDGE` to the nearest edge, `MIRRORED_REPEAT` back and forth.
//! - Filter: `magFilter` `NEAREST` reads the texel under the point,
//!   `LINEAR` (the default when absent) blends the four nearest texel
//!   centres bilinearly, each wrapped. A ray tracer has no pixel footprint
//!   to choose a mip level from, so `minFilter` and mipmaps are not used.
//! - Colour: a base colour or emissive texture holds sRGB-encoded values,
//!   decoded to linear before filtering; metallic-roughness, occlusion and
//!   normal textures hold linear values ([`Encoding`]).
//! - Alpha ([`Texture::alpha`], glTF `alphaMode: MASK`): the texel's 8-bit
//!   alpha over 255, linear in both encodings, filtered like the colour.
//! - `KHR_texture_transform`: `uv' = offset + R(rotation) (scale * uv)`
//!   with `R = [[cos, sin], [-sin, cos]]` (the extension's
//!   `translation * rotation * scale` matrix), and its `texCoord`, when
//!   given, replaces the texture info's.

use crate::error::{Error, Result};
use glam::{Vec2, Vec4};
use std::sync::{Arc, OnceLock};

/// How a texture coordinate outside [0, 1] is brought back into the image.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Wrap {
    /// Tiles the image (glTF's default).
    #[default]
    Repeat,
    /// Repeats the edge texels.
    ClampToEdge,
    /// Tiles the image, every other tile mirrored.
    MirroredRepeat,
}

/// How texels are read at a point.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Filter {
    /// The texel under the point.
    Nearest,
    /// Bilinear between the four nearest texel centres (the default).
    #[default]
    Linear,
}

/// A sampler: a wrap mode per axis and a filter.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Sampler {
    /// Along `u` (glTF `wrapS`).
    pub wrap_u: Wrap,
    /// Along `v` (glTF `wrapT`).
    pub wrap_v: Wrap,
    /// glTF `magFilter`.
    pub filter: Filter,
}

/// How a texture's values are encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Encoding {
    /// sRGB-encoded colour (base colour, emissive); alpha is linear.
    Srgb,
    /// Linear values (metallic-roughness, normal, occlusion).
    Linear,
}

/// `KHR_texture_transform`'s offset, rotation (radians, counter-clockwise
/// in the image) and scale; the identity by default.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexTransform {
    /// Added last.
    pub offset: Vec2,
    /// Applied after the scale.
    pub rotation: f32,
    /// Applied first.
    pub scale: Vec2,
}

impl Default for TexTransform {
    fn default() -> Self {
        TexTransform {
            offset: Vec2::ZERO,
            rotation: 0.0,
            scale: Vec2::ONE,
        }
    }
}

impl TexTransform {
    /// `offset + R(rotation) (scale * uv)`.
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        let s = uv * self.scale;
        let (sin, cos) = self.rotation.sin_cos();
        self.offset + Vec2::new(cos * s.x + sin * s.y, -sin * s.x + cos * s.y)
    }
}

/// A texture as a material uses it: which texture, which set of texture
/// coordinates (`TEXCOORD_n`), and the transform applied to them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureRef {
    /// Index into [`super::Scene::textures`].
    pub texture: usize,
    /// The `n` of the `TEXCOORD_n` attribute read.
    pub tex_coord: usize,
    /// `KHR_texture_transform`, the identity without it.
    pub transform: TexTransform,
}

/// An image of 8-bit RGBA texels with its sampler. Cloning shares the
/// texels (an alpha mask's [`super::Cutout`] holds a clone).
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    width: u32,
    height: u32,
    texels: Arc<[[u8; 4]]>,
    /// How the texture is read.
    pub sampler: Sampler,
}

/// sRGB's decoding of the 256 8-bit values (IEC 61966-2-1).
fn srgb_table() -> &'static [f32; 256] {
    static TABLE: OnceLock<[f32; 256]> = OnceLock::new();
    TABLE.get_or_init(|| {
        std::array::from_fn(|i| {
            let c = i as f64 / 255.0;
            let linear = if c <= 0.04045 {
                c / 12.92
            } else {
                ((c + 0.055) / 1.055).powf(2.4)
            };
            linear as f32
        })
    })
}

/// `i` in `0..n` by the wrap mode.
fn wrap_index(i: i64, n: u32, wrap: Wrap) -> usize {
    let n = i64::from(n);
    let k = match wrap {
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::ClampToEdge => i.clamp(0, n - 1),
        Wrap::MirroredRepeat => {
            let p = i.rem_euclid(2 * n);
            if p < n {
                p
            } else {
                2 * n - 1 - p
            }
        }
    };
    k as usize
}

/// A coordinate in texels, bounded so that casts to integers stay exact (a
/// coordinate of 1e30 repeats like any other; REPEAT's period divides it).
fn texel_coordinate(c: f32, n: u32) -> f64 {
    let x = f64::from(c) * f64::from(n);
    if x.is_finite() {
        x.clamp(-1e15, 1e15)
    } else {
        0.0
    }
}

impl Texture {
    /// A texture of `width x height` RGBA texels in rows from the top.
    ///
    /// # Errors
    /// [`Error::InvalidScene`] when a side is 0 or the texel count is not
    /// `width * height`.
    pub fn new(width: u32, height: u32, texels: Vec<[u8; 4]>, sampler: Sampler) -> Result<Self> {
        if width == 0 || height == 0 || texels.len() as u64 != u64::from(width) * u64::from(height)
        {
            return Err(Error::InvalidScene(format!(
                "a texture of {width} x {height} texels needs {} texels, got {}",
                u64::from(width) * u64::from(height),
                texels.len()
            )));
        }
        Ok(Texture {
            width,
            height,
            texels: texels.into(),
            sampler,
        })
    }

    /// Width in texels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The texels, row by row from the top (as the image stores them).
    pub fn texels(&self) -> &[[u8; 4]] {
        &self.texels
    }

    /// Texel `(i, j)` (wrapped), as stored.
    fn raw_texel(&self, i: i64, j: i64) -> [u8; 4] {
        let x = wrap_index(i, self.width, self.sampler.wrap_u);
        let y = wrap_index(j, self.height, self.sampler.wrap_v);
        self.texels[y * self.width as usize + x]
    }

    /// Texel `(i, j)` (wrapped) decoded to [0, 1].
    pub(crate) fn texel(&self, i: i64, j: i64, encoding: Encoding) -> Vec4 {
        let [r, g, b, a] = self.raw_texel(i, j);
        let alpha = f32::from(a) / 255.0;
        match encoding {
            Encoding::Srgb => {
                let t = srgb_table();
                Vec4::new(t[r as usize], t[g as usize], t[b as usize], alpha)
            }
            Encoding::Linear => Vec4::new(r as f32, g as f32, b as f32, 255.0 * alpha) / 255.0,
        }
    }

    /// The filtered value at texture coordinates `uv` (module docs), linear
    /// RGBA in [0, 1].
    pub fn sample(&self, uv: Vec2, encoding: Encoding) -> Vec4 {
        let x = texel_coordinate(uv.x, self.width);
        let y = texel_coordinate(uv.y, self.height);
        match self.sampler.filter {
            Filter::Nearest => self.texel(x.floor() as i64, y.floor() as i64, encoding),
            Filter::Linear => {
                let (x, y) = (x - 0.5, y - 0.5);
                let (i, j) = (x.floor(), y.floor());
                let (fx, fy) = ((x - i) as f32, (y - j) as f32);
                let (i, j) = (i as i64, j as i64);
                let top = self
                    .texel(i, j, encoding)
                    .lerp(self.texel(i + 1, j, encoding), fx);
                let bottom = self
                    .texel(i, j + 1, encoding)
                    .lerp(self.texel(i + 1, j + 1, encoding), fx);
                top.lerp(bottom, fy)
            }
        }
    }

    /// The filtered alpha at `uv`, in [0, 1]: what
    /// [`sample`](Self::sample)`(uv, Encoding::Srgb).w` gives, bit for bit,
    /// reading one channel instead of four.
    pub fn alpha(&self, uv: Vec2) -> f32 {
        let a = |i: i64, j: i64| f32::from(self.raw_texel(i, j)[3]) / 255.0;
        // `Vec4::lerp`'s formula, so the result is `sample`'s alpha exactly.
        let lerp = |p: f32, q: f32, s: f32| p * (1.0 - s) + q * s;
        let x = texel_coordinate(uv.x, self.width);
        let y = texel_coordinate(uv.y, self.height);
        match self.sampler.filter {
            Filter::Nearest => a(x.floor() as i64, y.floor() as i64),
            Filter::Linear => {
                let (x, y) = (x - 0.5, y - 0.5);
                let (i, j) = (x.floor(), y.floor());
                let (fx, fy) = ((x - i) as f32, (y - j) as f32);
                let (i, j) = (i as i64, j as i64);
                let top = lerp(a(i, j), a(i + 1, j), fx);
                let bottom = lerp(a(i, j + 1), a(i + 1, j + 1), fx);
                lerp(top, bottom, fy)
            }
        }
    }

    /// The least and the greatest texel alpha, in [0, 1]: the filtered
    /// alpha lies between them (up to a rounding of the blend).
    pub fn alpha_range(&self) -> (f32, f32) {
        let (lo, hi) = self.texels.iter().fold((u8::MAX, u8::MIN), |(lo, hi), t| {
            (lo.min(t[3]), hi.max(t[3]))
        });
        (f32::from(lo) / 255.0, f32::from(hi) / 255.0)
    }

    /// The mean of the decoded texels (what a flat factor would be).
    pub fn mean(&self, encoding: Encoding) -> Vec4 {
        let mut s = [0.0f64; 4];
        for j in 0..self.height {
            for i in 0..self.width {
                let t = self.texel(i64::from(i), i64::from(j), encoding);
                for (a, b) in s.iter_mut().zip(t.to_array()) {
                    *a += f64::from(b);
                }
            }
        }
        let n = f64::from(self.width) * f64::from(self.height);
        Vec4::from_array(s.map(|v| (v / n) as f32))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 2 x 2 texels: red, green / blue, white (linear values 10, 20, ...).
    fn four(filter: Filter, wrap: Wrap) -> Texture {
        let texels = vec![
            [40, 0, 0, 255],
            [0, 80, 0, 255],
            [0, 0, 120, 255],
            [200, 200, 200, 0],
        ];
        let sampler = Sampler {
            wrap_u: wrap,
            wrap_v: wrap,
            filter,
        };
        Texture::new(2, 2, texels, sampler).unwrap()
    }

    fn lin(t: &Texture, u: f32, v: f32) -> Vec4 {
        t.sample(Vec2::new(u, v), Encoding::Linear) * 255.0
    }

    fn close(a: Vec4, b: Vec4) -> bool {
        (a - b).abs().max_element() < 1e-3
    }

    #[test]
    fn nearest_reads_the_texel_under_the_point() {
        let t = four(Filter::Nearest, Wrap::Repeat);
        assert!(close(lin(&t, 0.25, 0.25), Vec4::new(40.0, 0.0, 0.0, 255.0)));
        assert!(close(lin(&t, 0.75, 0.25), Vec4::new(0.0, 80.0, 0.0, 255.0)));
        assert!(close(
            lin(&t, 0.25, 0.75),
            Vec4::new(0.0, 0.0, 120.0, 255.0)
        ));
        // REPEAT: u = 1.25 is u = 0.25; v = -0.25 is v = 0.75.
        assert!(close(
            lin(&t, 1.25, -0.25),
            Vec4::new(0.0, 0.0, 120.0, 255.0)
        ));
    }

    #[test]
    fn linear_blends_the_four_nearest_centres() {
        let t = four(Filter::Linear, Wrap::ClampToEdge);
        // The image's centre is the mean of the four.
        assert!(close(
            lin(&t, 0.5, 0.5),
            Vec4::new(60.0, 70.0, 80.0, 191.25)
        ));
        // A texel centre is the texel.
        assert!(close(lin(&t, 0.25, 0.25), Vec4::new(40.0, 0.0, 0.0, 255.0)));
        // Between the top two centres, a quarter of the way.
        assert!(close(
            lin(&t, 0.375, 0.25),
            Vec4::new(30.0, 20.0, 0.0, 255.0)
        ));
        // Past the edge, CLAMP_TO_EDGE holds the edge texel.
        assert!(close(lin(&t, -3.0, 0.25), Vec4::new(40.0, 0.0, 0.0, 255.0)));
    }

    #[test]
    fn wrap_modes_by_hand() {
        // Indices -3..=4 in a row of 2.
        let got = |w| (-3..=4).map(|i| wrap_index(i, 2, w)).collect::<Vec<_>>();
        assert_eq!(got(Wrap::Repeat), [1, 0, 1, 0, 1, 0, 1, 0]);
        assert_eq!(got(Wrap::ClampToEdge), [0, 0, 0, 0, 1, 1, 1, 1]);
        // Tiles [0 1][1 0][0 1] ..., and leftwards from 0 the mirror: 0 1 1 0.
        assert_eq!(got(Wrap::MirroredRepeat), [1, 1, 0, 0, 1, 1, 0, 0]);
        // Bilinear with REPEAT at the left edge blends the row's two ends.
        let t = four(Filter::Linear, Wrap::Repeat);
        assert!(close(lin(&t, 0.0, 0.25), Vec4::new(20.0, 40.0, 0.0, 255.0)));
        // MIRRORED_REPEAT: u = 1.25 mirrors to u = 0.75.
        let m = four(Filter::Nearest, Wrap::MirroredRepeat);
        assert!(close(lin(&m, 1.25, 0.25), lin(&m, 0.75, 0.25)));
        assert!(close(lin(&m, -0.25, 0.25), lin(&m, 0.25, 0.25)));
    }

    #[test]
    fn srgb_is_decoded_before_filtering() {
        let t = four(Filter::Nearest, Wrap::Repeat);
        let red = t.sample(Vec2::new(0.25, 0.25), Encoding::Srgb);
        // sRGB 40/255 = 0.1569 -> ((0.1569 + 0.055) / 1.055)^2.4 = 0.02122.
        assert!((red.x - 0.021_219).abs() < 1e-5, "{red}");
        assert_eq!(srgb_table()[255], 1.0);
        assert_eq!(srgb_table()[0], 0.0);
        // 10/255 is on the linear segment: 0.0392 / 12.92.
        assert!((srgb_table()[10] - 10.0 / 255.0 / 12.92).abs() < 1e-7);
    }

    #[test]
    fn the_texture_transform_offsets_rotates_and_scales() {
        // The extension's own example: a quarter turn about the origin then
        // an offset; (1, 0) scaled by 2 is (2, 0), rotated by pi/2 with
        // R = [[cos, sin], [-sin, cos]] is (0, -2), offset by (0.5, 1) is (0.5, -1).
        let t = TexTransform {
            offset: Vec2::new(0.5, 1.0),
            rotation: std::f32::consts::FRAC_PI_2,
            scale: Vec2::splat(2.0),
        };
        assert!((t.apply(Vec2::new(1.0, 0.0)) - Vec2::new(0.5, -1.0)).length() < 1e-6);
        assert!((t.apply(Vec2::new(0.0, 1.0)) - Vec2::new(2.5, 1.0)).length() < 1e-6);
        assert_eq!(
            TexTransform::default().apply(Vec2::new(0.3, 0.7)),
            Vec2::new(0.3, 0.7)
        );
    }

    #[test]
    fn extreme_coordinates_stay_in_the_image() {
        let t = four(Filter::Linear, Wrap::Repeat);
        for c in [f32::NAN, f32::INFINITY, -1e30, 1e30, 3.5e9] {
            let s = t.sample(Vec2::new(c, c), Encoding::Srgb);
            assert!(s.is_finite() && s.max_element() <= 1.0 && s.min_element() >= 0.0);
        }
        assert!(Texture::new(0, 2, vec![], Sampler::default()).is_err());
        assert!(Texture::new(2, 2, vec![[0; 4]; 3], Sampler::default()).is_err());
    }

    #[test]
    fn alpha_is_the_sampled_alpha_bit_for_bit() {
        let mut rng = crate::rng::Rng::new(3);
        for filter in [Filter::Nearest, Filter::Linear] {
            for wrap in [Wrap::Repeat, Wrap::ClampToEdge, Wrap::MirroredRepeat] {
                let t = four(filter, wrap);
                for _ in 0..2000 {
                    let uv = Vec2::new(rng.next_f32() * 6.0 - 3.0, rng.next_f32() * 6.0 - 3.0);
                    let want = t.sample(uv, Encoding::Srgb).w;
                    assert_eq!(
                        t.alpha(uv).to_bits(),
                        want.to_bits(),
                        "{uv} {filter:?} {wrap:?}"
                    );
                }
            }
        }
        assert_eq!(four(Filter::Linear, Wrap::Repeat).alpha_range(), (0.0, 1.0));
    }

    #[test]
    fn the_mean_is_the_texels_mean() {
        let t = four(Filter::Linear, Wrap::Repeat);
        assert!(close(
            t.mean(Encoding::Linear) * 255.0,
            Vec4::new(60.0, 70.0, 80.0, 191.25)
        ));
    }
}
