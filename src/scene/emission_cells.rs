//! The geometry and arithmetic under [`super::emission_map`]: convex
//! polygons clipped along texel cells, a texture's exact integral over
//! one, and the integer ticks of the piece choice.

use super::texture::{Encoding, Filter, Texture};
use glam::DVec2;

/// Ticks of the piece choice: `u * TICKS` is exact for a 24-bit float.
pub(super) const TICKS: u32 = 1 << 24;

/// A convex polygon in texel units (a triangle clipped by at most four
/// axis-aligned lines: seven corners at most).
#[derive(Clone, Copy)]
pub(super) struct Poly {
    pub(super) v: [DVec2; 8],
    pub(super) n: usize,
}

impl Poly {
    pub(super) fn triangle(t: [DVec2; 3]) -> Self {
        let mut v = [DVec2::ZERO; 8];
        v[..3].copy_from_slice(&t);
        Poly { v, n: 3 }
    }

    /// The part on the side of `axis = at` that `keep` (+1 above, -1 below) says.
    pub(super) fn clip(&self, axis: usize, at: f64, keep: f64) -> Poly {
        let mut out = Poly {
            v: [DVec2::ZERO; 8],
            n: 0,
        };
        let side = |p: DVec2| (p[axis] - at) * keep;
        for k in 0..self.n {
            let (p, q) = (self.v[k], self.v[(k + 1) % self.n]);
            let (sp, sq) = (side(p), side(q));
            if sp >= 0.0 && out.n < 8 {
                out.v[out.n] = p;
                out.n += 1;
            }
            if (sp >= 0.0) != (sq >= 0.0) && out.n < 8 {
                out.v[out.n] = p + (q - p) * (sp / (sp - sq));
                out.n += 1;
            }
        }
        out
    }

    pub(super) fn cell(&self, [i, j]: [i32; 2]) -> Poly {
        let (i, j) = (f64::from(i), f64::from(j));
        self.clip(1, j, 1.0)
            .clip(1, j + 1.0, -1.0)
            .clip(0, i, 1.0)
            .clip(0, i + 1.0, -1.0)
    }

    /// Fan triangles and their areas.
    pub(super) fn fan(&self) -> impl Iterator<Item = ([DVec2; 3], f64)> + '_ {
        (1..self.n.saturating_sub(1)).map(|k| {
            let t = [self.v[0], self.v[k], self.v[k + 1]];
            (t, 0.5 * (t[1] - t[0]).perp_dot(t[2] - t[0]).abs())
        })
    }

    pub(super) fn area(&self) -> f64 {
        self.fan().map(|(_, a)| a).sum()
    }
}

/// Running ticks summing to [`TICKS`]: one per piece, the rest in
/// proportion to `powers`; `None` when nothing emits.
pub(super) fn running_ticks(powers: &[f64]) -> Option<Vec<u32>> {
    let total: f64 = powers.iter().sum();
    let n = powers.len();
    if n == 0 || n > TICKS as usize || total.is_nan() || total <= 0.0 || !total.is_finite() {
        return None;
    }
    let spare = f64::from(TICKS - n as u32);
    let mut ticks: Vec<u32> = powers
        .iter()
        .map(|p| 1 + (p / total * spare).floor() as u32)
        .collect();
    let given: u64 = ticks.iter().map(|&t| u64::from(t)).sum();
    let largest = (0..n).max_by(|&a, &b| powers[a].total_cmp(&powers[b]))?;
    ticks[largest] += (u64::from(TICKS) - given) as u32;
    let mut acc = 0u32;
    Some(
        ticks
            .into_iter()
            .map(|t| {
                acc += t;
                acc
            })
            .collect(),
    )
}

/// `integral texel duv` over `poly` inside cell `[i, j]` of `texture`
/// (sRGB-decoded RGB): the texel times the area (`NEAREST`), or the
/// three-edge-midpoint rule over a fan of `poly`, exact for the bilinear
/// blend of the cell's four texels (degree 2).
pub(super) fn cell_integral(texture: &Texture, poly: &Poly, [i, j]: [i32; 2]) -> [f64; 3] {
    let texel = |di: i32, dj: i32| {
        let t = texture.texel(
            i64::from(i) + i64::from(di),
            i64::from(j) + i64::from(dj),
            Encoding::Srgb,
        );
        [t.x, t.y, t.z].map(f64::from)
    };
    let mut s = [0.0f64; 3];
    match texture.sampler.filter {
        Filter::Nearest => {
            let (t, a) = (texel(0, 0), poly.area());
            (0..3).for_each(|c| s[c] = t[c] * a);
        }
        Filter::Linear => {
            let corners = [texel(0, 0), texel(1, 0), texel(0, 1), texel(1, 1)];
            let origin = DVec2::new(f64::from(i), f64::from(j));
            for (t, a) in poly.fan() {
                for (p, q) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                    let m = (p + q) * 0.5 - origin;
                    let w = [
                        (1.0 - m.x) * (1.0 - m.y),
                        m.x * (1.0 - m.y),
                        (1.0 - m.x) * m.y,
                        m.x * m.y,
                    ];
                    for c in 0..3 {
                        s[c] += a / 3.0 * (0..4).map(|k| w[k] * corners[k][c]).sum::<f64>();
                    }
                }
            }
        }
    }
    s
}

/// Row `j` of triangle `tri`: the strip of it between `y = j` and `j + 1`,
/// and the columns that strip spans; `None` when it misses the row.
pub(super) fn row(tri: &Poly, j: i32) -> Option<(i32, Poly, std::ops::Range<i32>)> {
    let strip = tri
        .clip(1, f64::from(j), 1.0)
        .clip(1, f64::from(j) + 1.0, -1.0);
    if strip.n < 3 {
        return None;
    }
    let (x0, x1) = (0..strip.n).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), k| {
        (a.min(strip.v[k].x), b.max(strip.v[k].x))
    });
    Some((j, strip, x0.floor() as i32..x1.ceil() as i32))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The right triangle (0, 0), (3, 0), (0, 3) over the unit cells: its
    /// pieces tile it (areas sum to 4.5), a cell inside is whole, one the
    /// hypotenuse crosses corner to corner keeps the half below it, and a
    /// cell outside is empty.
    #[test]
    fn cells_tile_a_triangle() {
        let t = Poly::triangle([DVec2::ZERO, DVec2::new(3.0, 0.0), DVec2::new(0.0, 3.0)]);
        let mut sum = 0.0;
        for j in -1..4 {
            for i in -1..4 {
                sum += t.cell([i, j]).area();
            }
        }
        assert!((sum - 4.5).abs() < 1e-12, "{sum}");
        assert!((t.cell([1, 0]).area() - 1.0).abs() < 1e-12);
        assert!((t.cell([1, 1]).area() - 0.5).abs() < 1e-12);
        assert!((t.cell([2, 0]).area() - 0.5).abs() < 1e-12);
        assert_eq!(t.cell([2, 2]).area(), 0.0);
        assert_eq!(t.cell([-1, 0]).area(), 0.0);
    }

    #[test]
    fn ticks_sum_to_the_total_and_give_every_piece_one() {
        let powers = [1e-30, 5.0, 0.25, 3.0, 1e-12];
        let ticks = running_ticks(&powers).unwrap();
        assert_eq!(*ticks.last().unwrap(), TICKS);
        let counts: Vec<u32> = std::iter::once(0)
            .chain(ticks.iter().copied())
            .collect::<Vec<_>>()
            .windows(2)
            .map(|w| w[1] - w[0])
            .collect();
        assert!(counts.iter().all(|&c| c >= 1), "{counts:?}");
        // In proportion, to a tick or so (the remainder goes to the largest).
        let total: f64 = powers.iter().sum();
        for (c, p) in counts.iter().zip(powers) {
            let want = p / total * f64::from(TICKS);
            assert!((f64::from(*c) - want).abs() <= 6.0, "{c} vs {want}");
        }
        assert_eq!(running_ticks(&[]), None);
        assert_eq!(running_ticks(&[0.0, 0.0]), None);
        assert_eq!(running_ticks(&[f64::NAN]), None);
    }
}
