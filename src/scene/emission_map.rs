//! An emissive texture over an area light: radiance `L0(x) = factor *
//! texel(uv(x))` (sRGB-decoded RGB), its exact integral, and points sampled
//! by emitted power.
//!
//! # The pieces
//! The texture is constant over each texel (`NEAREST`) or bilinear between
//! each square of four texel centres (`LINEAR`): call those squares *cells*.
//! Each triangle's texture coordinates (after `KHR_texture_transform`) are
//! an affine map, so the triangle cut along the cell lines (clipped in
//! texel units, in f64) is a set of convex *pieces*, each of at most seven
//! corners, over which the radiance is a polynomial of degree 0 or 2 in the
//! triangle's barycentrics. Its integral over a piece is then exact: the
//! texel times the area, or the three-edge-midpoint rule over a fan of the
//! piece (exact for degree 2). The light's total is the f64 sum of the
//! pieces, so [`super::AreaLight::power`] is the sum over the texels the
//! mesh covers, up to rounding.
//!
//! A triangle that crosses more cells than the light's budget has left
//! ([`MAX_CELLS`] cells examined per light, which bounds both the work and
//! the memory), or whose texture coordinates are
//! degenerate (no area in uv), is one piece whose integral is a midpoint
//! rule over 256 sub-triangles: the light's power estimate is then
//! approximate, the photons' power is not (below).
//!
//! # Sampling
//! A piece is chosen with probability `ticks / 2^24`, its ticks in
//! proportion to its power (at least one): the choice compares `u * 2^24`
//! with integer running ticks, so for a uniform `u` (continuous, or the
//! 24-bit floats of [`crate::rng::Rng::next_f32`]) the probability is
//! exactly the one the weights use. Inside a piece the point is uniform in
//! area (a fan triangle by area, then uniform in it). The area pdf is
//! `ticks / 2^24 / piece area`, and a photon carries `L0(x) (profile
//! integral) sides / pdf` over `N`: unbiased for any ticks, whatever the
//! error of a piece's power estimate, since the weight uses the true
//! radiance at the point and the true pdf.

use super::emission_cells::{cell_integral, row, running_ticks, Poly, TICKS};
use super::texture::{Encoding, Filter, Texture};
use crate::sampling::{luminance, uniform_triangle};
use glam::{DVec2, Vec2, Vec3};
use std::sync::Arc;

/// The most texel cells one light's triangles may cross, summed: at most
/// this many pieces (16 bytes, and 4 of ticks, each: 160 MB at most), and
/// this many polygon clips to build them. A 2k x 2k texture over a quad
/// (4.2M cells) is cut exactly; a 4k one is cut until the budget runs out,
/// its remaining triangles whole.
pub const MAX_CELLS: usize = 1 << 23;

/// The cell of a piece that is a whole triangle.
const WHOLE: [i32; 2] = [i32::MIN, i32::MIN];

/// Cell coordinates beyond this (in texels) make a triangle whole.
const MAX_TEXEL_COORDINATE: f64 = 1e9;

#[derive(Clone, Copy, Debug, PartialEq)]
struct Piece {
    triangle: u32,
    /// `[i, j]`, or [`WHOLE`].
    cell: [i32; 2],
    /// World area.
    area: f32,
}

/// A triangle's pieces with their powers, and the cells it examined.
type Cut = (Vec<(Piece, [f64; 3])>, usize);

/// A point sampled on a textured light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct MapSample {
    pub triangle: usize,
    /// Barycentrics of vertices 1 and 2.
    pub bary: (f32, f32),
    /// Area pdf (world) of the point.
    pub pdf_area: f32,
    /// The radiance of a `NEAREST` cell, constant over the piece: the
    /// photon's weight takes it from the piece drawn, not from a lookup at
    /// the point, whose rounding may land on the neighbouring texel (a weight
    /// of that texel's radiance over this one's pdf: a firefly where a dim
    /// texel borders a bright one). `None`: read at the point.
    pub radiance: Option<Vec3>,
}

/// A textured light's radiance and its power distribution.
#[derive(Clone, PartialEq)]
pub(crate) struct EmissionMap {
    /// Shared by the lights of every mesh that reads it.
    texture: Arc<Texture>,
    factor: Vec3,
    /// Per triangle, the transformed texture coordinates of its vertices.
    uvs: Vec<[Vec2; 3]>,
    /// Per triangle, its world area.
    areas: Vec<f32>,
    pieces: Vec<Piece>,
    /// Running ticks: piece `k` holds `[ticks[k - 1], ticks[k])`.
    ticks: Vec<u32>,
    /// Pieces of triangle `t`: `first[t]..first[t + 1]`, by row then column.
    first: Vec<u32>,
    /// `integral L0 dA` per channel.
    integral: Vec3,
    exact: bool,
}

impl std::fmt::Debug for EmissionMap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EmissionMap")
            .field("texels", &(self.texture.width(), self.texture.height()))
            .field("factor", &self.factor)
            .field("pieces", &self.pieces.len())
            .field("integral", &self.integral)
            .field("exact", &self.exact)
            .finish()
    }
}

impl EmissionMap {
    /// The map of `texture` times `factor` over `triangles` with texture
    /// coordinates `uvs` (transformed); `None` when the light emits nothing.
    pub(crate) fn new(
        texture: Arc<Texture>,
        factor: Vec3,
        triangles: &[[Vec3; 3]],
        uvs: Vec<[Vec2; 3]>,
    ) -> Option<Self> {
        let mut map = EmissionMap {
            areas: triangles.iter().map(|&t| super::triangle_area(t)).collect(),
            texture,
            factor,
            uvs,
            pieces: Vec::new(),
            ticks: Vec::new(),
            first: vec![0],
            integral: Vec3::ZERO,
            exact: true,
        };
        // The luminance of the texture's mean radiance: a whole piece's floor.
        let mean = f64::from(luminance(
            map.factor * map.texture.mean(Encoding::Srgb).truncate(),
        ));
        let mut powers = Vec::new();
        let mut total = [0.0f64; 3];
        let mut spent = 0usize;
        for t in 0..map.uvs.len() {
            let cut = match map.cut(t, MAX_CELLS - spent) {
                Some((pieces, cells)) => {
                    spent += cells;
                    pieces
                }
                None => {
                    map.exact = false;
                    vec![map.whole(t)]
                }
            };
            for (piece, power) in cut {
                let lum = f64::from(luminance(Vec3::from(power.map(|p| p as f32))));
                if piece.cell == WHOLE {
                    map.pieces.push(piece);
                    powers.push(lum.max(1e-3 * f64::from(piece.area) * mean));
                } else if lum > 0.0 {
                    map.pieces.push(piece);
                    powers.push(lum);
                }
                for (s, p) in total.iter_mut().zip(power) {
                    *s += p;
                }
            }
            map.first.push(map.pieces.len() as u32);
        }
        map.integral = Vec3::from(total.map(|p| p as f32));
        map.ticks = running_ticks(&powers)?;
        Some(map)
    }

    /// Emitted `integral L0 dA`, per channel.
    pub(crate) fn integral(&self) -> Vec3 {
        self.integral
    }

    /// Whether [`Self::integral`] is the exact sum over the texels.
    pub(crate) fn is_exact(&self) -> bool {
        self.exact
    }

    /// Number of pieces.
    pub(crate) fn piece_count(&self) -> usize {
        self.pieces.len()
    }

    /// Triangle `t`'s vertices in texel units (cells start at integers).
    fn texel_space(&self, t: usize) -> [DVec2; 3] {
        let (w, h) = (self.texture.width(), self.texture.height());
        let shift = match self.texture.sampler.filter {
            Filter::Nearest => 0.0,
            Filter::Linear => 0.5,
        };
        self.uvs[t].map(|uv| {
            DVec2::new(
                f64::from(uv.x) * f64::from(w) - shift,
                f64::from(uv.y) * f64::from(h) - shift,
            )
        })
    }

    /// Texel-unit area of triangle `t`'s texture coordinates.
    fn uv_area(&self, t: usize) -> f64 {
        let [a, b, c] = self.texel_space(t);
        0.5 * (b - a).perp_dot(c - a).abs()
    }

    /// Triangle `t` cut along the cells, each piece with its power, and the
    /// cells its rows cross; `None` when those (or its rows) are more than
    /// `budget`, or its uv map is degenerate.
    fn cut(&self, t: usize, budget: usize) -> Option<Cut> {
        let tv = self.texel_space(t);
        let uv_area = self.uv_area(t);
        let (lo, hi) = (tv[0].min(tv[1]).min(tv[2]), tv[0].max(tv[1]).max(tv[2]));
        let span = (hi - lo).max_element().max(1.0);
        let sane = lo.abs().max(hi.abs()).max_element() < MAX_TEXEL_COORDINATE;
        if !(sane && uv_area > 1e-9 * span * span) || hi.y.ceil() - lo.y.floor() > budget as f64 {
            return None;
        }
        let tri = Poly::triangle(tv);
        let rows = (lo.y.floor() as i32..hi.y.ceil() as i32).filter_map(|j| row(&tri, j));
        let cells: usize = rows.clone().map(|(_, _, i)| i.len()).sum();
        if cells > budget {
            return None;
        }
        let scale = f64::from(self.areas[t]) / uv_area;
        let mut out = Vec::new();
        for (j, strip, columns) in rows {
            for i in columns {
                let poly = strip
                    .clip(0, f64::from(i), 1.0)
                    .clip(0, f64::from(i) + 1.0, -1.0);
                let area = poly.area();
                if area <= 0.0 {
                    continue;
                }
                let f = [self.factor.x, self.factor.y, self.factor.z].map(f64::from);
                let power = cell_integral(&self.texture, &poly, [i, j]);
                let power = std::array::from_fn(|c| power[c] * f[c] * scale);
                let piece = Piece {
                    triangle: t as u32,
                    cell: [i, j],
                    area: (area * scale) as f32,
                };
                out.push((piece, power));
            }
        }
        Some((out, cells))
    }

    /// Triangle `t` as one piece, its power by a midpoint rule over 256
    /// sub-triangles (at least a thousandth of its area at the texture's
    /// mean, so that it keeps a fair share of the photons).
    fn whole(&self, t: usize) -> (Piece, [f64; 3]) {
        const G: u32 = 16;
        let g = f64::from(G);
        let mut s = [0.0f64; 3];
        for i in 0..G {
            for j in 0..G - i {
                let up = (f64::from(i) + 1.0 / 3.0, f64::from(j) + 1.0 / 3.0);
                let down = (f64::from(i) + 2.0 / 3.0, f64::from(j) + 2.0 / 3.0);
                let count = if i + j + 1 < G { 2 } else { 1 };
                for (b1, b2) in [up, down].into_iter().take(count) {
                    let l = self.radiance(t, ((b1 / g) as f32, (b2 / g) as f32));
                    (0..3).for_each(|c| s[c] += f64::from(l[c]));
                }
            }
        }
        let da = f64::from(self.areas[t]) / (g * g);
        let piece = Piece {
            triangle: t as u32,
            cell: WHOLE,
            area: self.areas[t],
        };
        (piece, s.map(|v| v * da))
    }

    /// `L0` at barycentrics `(b1, b2)` of triangle `t`: the factor times
    /// the texel, read through the texture's sampler.
    pub(crate) fn radiance(&self, t: usize, (b1, b2): (f32, f32)) -> Vec3 {
        let [a, b, c] = self.uvs[t];
        let uv = a * (1.0 - b1 - b2) + b * b1 + c * b2;
        self.factor * self.texture.sample(uv, Encoding::Srgb).truncate()
    }

    /// Piece `k`'s probability.
    fn probability(&self, k: usize) -> f64 {
        let lo = if k == 0 { 0 } else { self.ticks[k - 1] };
        f64::from(self.ticks[k] - lo) / f64::from(TICKS)
    }

    /// The piece `u` in `[0, 1)` picks: the one whose ticks hold `u 2^24`.
    /// Its rescaled remainder is not offered: `u`'s 24 bits leave a piece
    /// of `c` ticks only `c` values of it.
    pub(crate) fn pick(&self, u: f32) -> usize {
        let x = f64::from(u) * f64::from(TICKS);
        self.ticks
            .partition_point(|&c| f64::from(c) <= x)
            .min(self.ticks.len() - 1)
    }

    /// A point of piece `k`, uniform in its area, from `u`.
    pub(crate) fn sample_in(&self, k: usize, u: [f32; 2]) -> MapSample {
        let piece = self.pieces[k];
        let t = piece.triangle as usize;
        let q = self.probability(k);
        if piece.cell == WHOLE {
            let (b0, b1) = uniform_triangle(u);
            return MapSample {
                triangle: t,
                bary: (b1, 1.0 - b0 - b1),
                pdf_area: (q / f64::from(piece.area)) as f32,
                radiance: None,
            };
        }
        let radiance = (self.texture.sampler.filter == Filter::Nearest).then(|| {
            let [i, j] = piece.cell;
            let texel = self
                .texture
                .texel(i64::from(i), i64::from(j), Encoding::Srgb);
            self.factor * texel.truncate()
        });
        let tv = self.texel_space(t);
        let poly = Poly::triangle(tv).cell(piece.cell);
        let total = poly.area();
        let mut target = f64::from(u[0]) * total;
        let mut chosen = None;
        for (tri, a) in poly.fan() {
            chosen = Some((tri, ((target / a).clamp(0.0, 0.999_999_9)) as f32));
            if target < a {
                break;
            }
            target -= a;
        }
        let Some(([p0, p1, p2], u0)) = chosen else {
            // A piece has area (it was kept for it): unreachable, but a
            // centroid is still a point of the triangle.
            return MapSample {
                triangle: t,
                bary: (1.0 / 3.0, 1.0 / 3.0),
                pdf_area: (q / f64::from(piece.area)) as f32,
                radiance,
            };
        };
        let (c0, c1) = uniform_triangle([u0, u[1]]);
        let (c0, c1) = (f64::from(c0), f64::from(c1));
        let p = p0 * c0 + p1 * c1 + p2 * (1.0 - c0 - c1);
        let (e1, e2, d) = (tv[1] - tv[0], tv[2] - tv[0], p - tv[0]);
        let det = e1.perp_dot(e2);
        let (b1, b2) = (d.perp_dot(e2) / det, e1.perp_dot(d) / det);
        let world_area = total * f64::from(self.areas[t]) / self.uv_area(t);
        MapSample {
            triangle: t,
            bary: (
                b1.clamp(0.0, 1.0) as f32,
                b2.clamp(0.0, 1.0 - b1.clamp(0.0, 1.0)) as f32,
            ),
            pdf_area: (q / world_area) as f32,
            radiance,
        }
    }

    /// The area pdf of [`Self::sample_in`] after [`Self::pick`] at
    /// barycentrics `(b1, b2)` of triangle `t` (0 where no piece emits).
    pub(crate) fn pdf_area(&self, t: usize, (b1, b2): (f32, f32)) -> f32 {
        let (Some(&lo), Some(&hi)) = (self.first.get(t), self.first.get(t + 1)) else {
            return 0.0;
        };
        let range = lo as usize..hi as usize;
        let Some(found) = (match self.pieces[range.clone()].first() {
            Some(p) if p.cell == WHOLE => Some(range.start),
            Some(_) => {
                let tv = self.texel_space(t);
                let (b1, b2) = (f64::from(b1), f64::from(b2));
                let p = tv[0] * (1.0 - b1 - b2) + tv[1] * b1 + tv[2] * b2;
                let cell = [p.x.floor() as i32, p.y.floor() as i32];
                self.pieces[range.clone()]
                    .binary_search_by_key(&(cell[1], cell[0]), |p| (p.cell[1], p.cell[0]))
                    .ok()
                    .map(|k| range.start + k)
            }
            None => None,
        }) else {
            return 0.0;
        };
        (self.probability(found) / f64::from(self.pieces[found].area)) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;
    use crate::scene::texture::{Sampler, Wrap};

    fn texture(filter: Filter) -> Texture {
        let texels = (0..16u8)
            .map(|k| [16 * k, 255 - 16 * k, 7 * k, 255])
            .collect();
        let sampler = Sampler {
            wrap_u: Wrap::Repeat,
            wrap_v: Wrap::MirroredRepeat,
            filter,
        };
        Texture::new(4, 4, texels, sampler).unwrap()
    }

    fn triangles() -> Vec<[Vec3; 3]> {
        vec![
            [
                Vec3::ZERO,
                Vec3::new(2.0, 0.0, 0.0),
                Vec3::new(0.0, 0.0, 1.5),
            ],
            [
                Vec3::new(2.0, 0.0, 0.0),
                Vec3::new(2.0, 0.0, 1.5),
                Vec3::new(0.0, 0.0, 1.5),
            ],
        ]
    }

    /// Every sampled point's pdf is the one the lookup at that point gives
    /// (what the path tracer's MIS reads), and the pieces' probabilities
    /// sum to one.
    #[test]
    fn the_pdf_at_a_sampled_point_is_the_lookups() {
        for filter in [Filter::Nearest, Filter::Linear] {
            let uvs = vec![
                [
                    Vec2::new(0.1, -0.3),
                    Vec2::new(1.7, 0.2),
                    Vec2::new(-0.2, 1.1),
                ],
                [
                    Vec2::new(1.7, 0.2),
                    Vec2::new(1.3, 1.4),
                    Vec2::new(-0.2, 1.1),
                ],
            ];
            let map =
                EmissionMap::new(Arc::new(texture(filter)), Vec3::ONE, &triangles(), uvs).unwrap();
            assert!(map.is_exact() && map.piece_count() > 20);
            let sum: f64 = (0..map.piece_count()).map(|k| map.probability(k)).sum();
            assert!((sum - 1.0).abs() < 1e-12);
            let mut rng = Rng::new(3);
            for _ in 0..20_000 {
                let k = map.pick(rng.next_f32());
                let s = map.sample_in(k, rng.next_2d());
                let looked_up = map.pdf_area(s.triangle, s.bary);
                let on_edge = (looked_up - s.pdf_area).abs() > 1e-4 * s.pdf_area;
                // A point on a cell's edge may read the neighbour's piece.
                if on_edge {
                    let tv = map.texel_space(s.triangle);
                    let (b1, b2) = (f64::from(s.bary.0), f64::from(s.bary.1));
                    let p = tv[0] * (1.0 - b1 - b2) + tv[1] * b1 + tv[2] * b2;
                    let d = (p - p.round()).abs().min_element();
                    assert!(
                        d < 1e-4,
                        "{filter:?}: pdf {} vs {looked_up} at {p}",
                        s.pdf_area
                    );
                }
            }
        }
    }

    /// A triangle whose texture coordinates are one point is one piece of
    /// the texel there (its power exact by the midpoint rule, a constant);
    /// one over the budget is one piece too, its power approximate.
    #[test]
    fn degenerate_or_huge_uv_triangles_are_whole() {
        let p = Vec2::new(0.3, 0.6);
        let tex = texture(Filter::Nearest);
        let texel = tex.sample(p, Encoding::Srgb).truncate();
        let map = EmissionMap::new(
            Arc::new(tex),
            Vec3::splat(2.0),
            &triangles()[..1],
            vec![[p; 3]],
        )
        .unwrap();
        assert_eq!(map.piece_count(), 1);
        assert!(!map.is_exact());
        let want = texel * 2.0 * 1.5;
        assert!((map.integral() - want).abs().max_element() < 1e-5 * want.max_element());
        let huge = vec![[Vec2::ZERO, Vec2::new(3000.0, 0.0), Vec2::new(0.0, 3000.0)]];
        let map = EmissionMap::new(
            Arc::new(texture(Filter::Linear)),
            Vec3::ONE,
            &triangles()[..1],
            huge,
        );
        assert!(map
            .as_ref()
            .is_some_and(|m| m.cut(0, MAX_CELLS).is_none() && !m.is_exact()));
    }
}
