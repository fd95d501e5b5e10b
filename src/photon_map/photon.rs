//! The compact photon: 16 bytes, against 20–28 for Jensen's photon.
//!
//! | word | bits | content |
//! |------|------|---------|
//! | `pos: u64` | 3 × 21 + 1 | position, quantised on a uniform grid over the map's bounds; the top bit marks a caustic photon |
//! | `power: u32` | 3 × 9 + 5 | RGB power, shared exponent, relative to the map's largest channel |
//! | `dir: u32` | 2 × 12 + 6 + 2 | octahedral direction of travel, bounce depth, kd-tree split axis |
//!
//! Precision (all bounds are tested in `tests/library/kdtree.rs`):
//! - **Position**: one grid step `s = extent / (2^21 - 1)` on every axis, where `extent`
//!   is the largest side of the map's bounding box; each coordinate is off by at most
//!   `s / 2` (plus the f32 rounding of the decoded value): 2.4e-7 of the extent.
//! - **Power**: `P` is the largest channel of the whole map; a photon's three channels
//!   share an exponent `E` in `[0, 31]` with 9-bit mantissas `m`: `channel = m 2^(E-39) P`.
//!   Each channel is off by at most `2^-9` times the photon's largest channel (half a
//!   mantissa step), for photons whose largest channel is above `2^-31 P`; below that
//!   the error is at most `2^-40 P` (the photon is then almost black next to the map's
//!   brightest). Negative channels are stored as 0.
//! - **Direction**: octahedral map (Cigolle et al. 2014) on a 4095 × 4095 grid (codes
//!   0..=4094 so that 0 and the poles are exact). Rounding moves each octahedral
//!   coordinate by at most `h / 2` with `h = 2 / 4094`; the octahedron point moves by at
//!   most `sqrt(1.5) h` and normalising scales lengths by at most `sqrt(3)` (the
//!   octahedron's smallest radius is `1/sqrt(3)`), so the angular error is at most
//!   `sqrt(4.5) h` = 1.04e-3 rad = 0.059° ([`MAX_DIRECTION_ERROR`]).
//! - **Depth**: 6 bits; depths above [`MAX_DEPTH`] are stored as `MAX_DEPTH`.
//! - **Caustic**: bit 63 of `pos` (above the three coordinates, so every
//!   masked coordinate read ignores it; files written before it existed
//!   have it clear).

use super::PhotonRecord;
use glam::Vec3;

/// Bits per position coordinate.
pub const POSITION_BITS: u32 = 21;
/// Largest quantised position coordinate.
pub(crate) const POSITION_MAX: u32 = (1 << POSITION_BITS) - 1;
const POSITION_MASK: u64 = POSITION_MAX as u64;
/// The caustic flag, above the three 21-bit coordinates.
const CAUSTIC_BIT: u64 = 1 << 63;

/// Largest bounce depth a compact photon stores; deeper photons are stored at this depth.
pub const MAX_DEPTH: u8 = 63;

/// Upper bound of the angle (radians) between a direction and its decoded value:
/// `sqrt(4.5) * 2 / 4094` (see the module docs), rounded up, plus f32 slack.
pub const MAX_DIRECTION_ERROR: f32 = 1.04e-3;

/// Relative bound of the power error: every channel is within this fraction of the
/// photon's largest channel (see the module docs for very dark photons).
pub const POWER_RELATIVE_ERROR: f32 = 1.0 / 512.0;

/// Largest octahedral code; the codes are 0..=OCT_MAX with OCT_MAX / 2 mapping to 0.
const OCT_MAX: u32 = 4094;
const OCT_BITS: u32 = 12;
const OCT_MASK: u32 = (1 << OCT_BITS) - 1;
const DEPTH_SHIFT: u32 = 24;
const AXIS_SHIFT: u32 = 30;
/// Power exponent offset: `channel = m 2^(E - POWER_BIAS) P`, so that the map's largest
/// channel (1 after normalising by `P`) has `E = 31, m = 256`.
const POWER_BIAS: i32 = 39;

/// A photon in 16 bytes. Decode it with the [`Quantizer`] of the map that holds it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[repr(C)]
pub struct CompactPhoton {
    pos: u64,
    power: u32,
    dir: u32,
}

impl CompactPhoton {
    /// A value that [`Quantizer::encode`] never returns (its octahedral codes are
    /// out of range): marks skipped records during the build.
    pub(crate) const INVALID: CompactPhoton = CompactPhoton {
        pos: u64::MAX,
        power: u32::MAX,
        dir: u32::MAX,
    };

    /// Quantised position, in grid steps.
    #[inline(always)]
    pub fn grid(&self) -> [u32; 3] {
        [
            (self.pos & POSITION_MASK) as u32,
            ((self.pos >> POSITION_BITS) & POSITION_MASK) as u32,
            ((self.pos >> (2 * POSITION_BITS)) & POSITION_MASK) as u32,
        ]
    }

    /// One quantised coordinate (`axis` in 0..3).
    #[inline(always)]
    pub fn coord(&self, axis: usize) -> u32 {
        ((self.pos >> (axis as u32 * POSITION_BITS)) & POSITION_MASK) as u32
    }

    /// The packed position word (coordinate `a` in bits `21 a .. 21 a + 21`).
    #[inline(always)]
    pub(crate) fn packed_position(&self) -> u64 {
        self.pos
    }

    /// The bits of coordinate `axis` in [`CompactPhoton::packed_position`].
    #[inline(always)]
    pub(crate) const fn coord_mask(axis: usize) -> u64 {
        POSITION_MASK << (axis as u32 * POSITION_BITS)
    }

    /// A masked field of `axis` (or a difference of two), in grid steps.
    #[inline(always)]
    pub(crate) fn field_value(field: u64, axis: usize) -> u32 {
        (field >> (axis as u32 * POSITION_BITS)) as u32
    }

    /// A hash of what the photon carries (position, power, direction, depth),
    /// not of where the tree put it (its split axis is left out): the same
    /// photon gives the same value in any map built from it. Used as a coin
    /// independent of the photons' layout, to thin a map at random.
    #[inline]
    pub fn content_hash(&self) -> u64 {
        // One mixing round: a coin per photon, read for every candidate of
        // every cache estimate, need not be a keyed hash.
        let dir = self.dir & !(3 << AXIS_SHIFT);
        crate::rng::mix64(
            self.pos ^ ((u64::from(self.power) << 32) | u64::from(dir)).rotate_left(23),
        )
    }

    /// The kd-tree split axis stored with this photon (meaningful for inner nodes only).
    #[inline(always)]
    pub fn axis(&self) -> usize {
        (self.dir >> AXIS_SHIFT) as usize
    }

    #[inline]
    pub(crate) fn set_axis(&mut self, axis: usize) {
        debug_assert!(axis < 3);
        self.dir = (self.dir & !(3 << AXIS_SHIFT)) | ((axis as u32) << AXIS_SHIFT);
    }

    /// Whether this is a caustic photon (`L S+ D`, see [`PhotonRecord::caustic`]).
    #[inline]
    pub fn is_caustic(&self) -> bool {
        self.pos & CAUSTIC_BIT != 0
    }

    /// Bounce depth (0 = stored at the first hit after leaving the light).
    #[inline]
    pub fn depth(&self) -> u8 {
        ((self.dir >> DEPTH_SHIFT) & 63) as u8
    }

    /// Direction of travel, decoded and normalised.
    #[inline]
    pub fn direction(&self) -> Vec3 {
        self.direction_unnormalised().normalize()
    }

    /// Direction of travel on the octahedron (`|x| + |y| + |z| = 1`): enough for signs
    /// of dot products, without the square root.
    #[inline]
    pub fn direction_unnormalised(&self) -> Vec3 {
        // (code - 2047) / 2047 is exact at -1, 0 and 1, so the poles decode exactly.
        const HALF: f32 = (OCT_MAX / 2) as f32;
        let x = ((self.dir & OCT_MASK) as f32 - HALF) / HALF;
        let y = (((self.dir >> OCT_BITS) & OCT_MASK) as f32 - HALF) / HALF;
        oct_unfold(x, y)
    }

    /// The two words as one `u128`, for hashing and total ordering.
    #[inline]
    pub(crate) fn bits(&self) -> (u64, u64) {
        (self.pos, ((self.power as u64) << 32) | self.dir as u64)
    }

    /// The photon whose [`CompactPhoton::bits`] are `(a, b)`, without a kd-tree split
    /// axis (photon files store photons this way).
    #[inline]
    #[cfg_attr(not(feature = "embree"), allow(dead_code))] // photon files only
    pub(crate) fn from_bits(a: u64, b: u64) -> CompactPhoton {
        let mut p = CompactPhoton {
            pos: a,
            power: (b >> 32) as u32,
            dir: b as u32,
        };
        p.dir &= !(3 << AXIS_SHIFT);
        p
    }

    /// A total order whose first key is the coordinate on `axis`, then all 16 bytes:
    /// equal means bitwise equal, which is what makes the build canonical. (Photons
    /// being partitioned have no split axis written yet, so the axis bits are 0.)
    /// The build uses its strict part, [`CompactPhoton::less_on`].
    #[cfg(test)]
    pub(crate) fn cmp_on(&self, other: &Self, axis: usize) -> std::cmp::Ordering {
        // The coordinate's field masked in place orders as the coordinate.
        let mask = Self::coord_mask(axis);
        (self.pos & mask)
            .cmp(&(other.pos & mask))
            .then_with(|| self.bits().cmp(&other.bits()))
    }

    /// Whether `self` comes before `other` in the build's total order: the
    /// coordinate on `axis` first, then all 16 bytes (equal means bitwise
    /// equal, which is what makes the build canonical; photons being
    /// partitioned have no split axis written yet). The tie on the coordinate
    /// (rare) sits behind a branch: the build's partitions call this most.
    #[inline(always)]
    pub(crate) fn less_on(&self, other: &Self, axis: usize) -> bool {
        let mask = Self::coord_mask(axis);
        let (a, b) = (self.pos & mask, other.pos & mask);
        if a != b {
            a < b
        } else {
            self.bits() < other.bits()
        }
    }
}

/// `(x, y)` in `[-1, 1]^2` to the octahedron; the lower half is folded out to the corners.
#[inline]
fn oct_unfold(x: f32, y: f32) -> Vec3 {
    let z = 1.0 - x.abs() - y.abs();
    if z < 0.0 {
        Vec3::new(
            (1.0 - y.abs()) * sign_not_zero(x),
            (1.0 - x.abs()) * sign_not_zero(y),
            z,
        )
    } else {
        Vec3::new(x, y, z)
    }
}

#[inline]
fn sign_not_zero(v: f32) -> f32 {
    if v >= 0.0 {
        1.0
    } else {
        -1.0
    }
}

/// `v` rounded to the nearest integer (ties to even), for `0 <= v < 2^51`.
/// Adding `2^52` leaves the integer in the low bits of the mantissa: no
/// float-to-integer conversion, which Rust makes saturating (on x86-64 a
/// compare and two selects around each `cvttsd2si`). Encoding runs at every
/// stored photon, so this is on the tracer's hot path.
#[inline(always)]
fn round_to_u64(v: f64) -> u64 {
    const TWO_52: f64 = 4_503_599_627_370_496.0;
    (v + TWO_52).to_bits() & ((1 << 52) - 1)
}

/// `2^n` for `n` in the normal range of f64 (`powi` is a loop in compiler-rt).
#[inline(always)]
fn exp2(n: i32) -> f64 {
    debug_assert!((-1022..=1023).contains(&n));
    f64::from_bits(((n + 1023) as u64) << 52)
}

/// Octahedral code of a non-zero direction.
fn oct_encode(d: Vec3) -> u32 {
    let n = d / (d.x.abs() + d.y.abs() + d.z.abs());
    let (x, y) = if n.z < 0.0 {
        (
            (1.0 - n.y.abs()) * sign_not_zero(n.x),
            (1.0 - n.x.abs()) * sign_not_zero(n.y),
        )
    } else {
        (n.x, n.y)
    };
    const HALF: f64 = (OCT_MAX / 2) as f64;
    // max/min, not clamp: they map NaN to a bound.
    #[allow(clippy::manual_clamp)]
    let q = |v: f32| round_to_u64(v.max(-1.0).min(1.0) as f64 * HALF + HALF) as u32;
    q(x) | (q(y) << OCT_BITS)
}

/// The map-wide frame that compact photons are quantised in: the grid origin and step
/// for positions, the largest power channel for powers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quantizer {
    origin: [f64; 3],
    step: f64,
    inv_step: f64,
    power_scale: f64,
    inv_power_scale: f64,
}

impl Quantizer {
    /// A frame for photons inside the box `[min, max]` whose largest power channel is
    /// `max_power`. Non-finite or inverted bounds give a frame with the box `[0, 0]`
    /// (every position then decodes to the origin); a non-positive or non-finite
    /// `max_power` stores every power as 0.
    pub fn new(min: Vec3, max: Vec3, max_power: f32) -> Self {
        let ok = min.is_finite() && max.is_finite() && min.cmple(max).all();
        let (min, max) = if ok {
            (min, max)
        } else {
            (Vec3::ZERO, Vec3::ZERO)
        };
        let extent = (0..3)
            .map(|a| max[a] as f64 - min[a] as f64)
            .fold(0.0, f64::max);
        // A zero extent (one point) still needs an invertible step; any value works.
        let step = if extent > 0.0 {
            extent / POSITION_MAX as f64
        } else {
            1.0
        };
        let power_scale = if max_power.is_finite() && max_power > 0.0 {
            max_power as f64
        } else {
            0.0
        };
        Quantizer {
            origin: [min.x as f64, min.y as f64, min.z as f64],
            step,
            inv_step: 1.0 / step,
            power_scale,
            inv_power_scale: if power_scale > 0.0 {
                1.0 / power_scale
            } else {
                0.0
            },
        }
    }

    /// The grid step (world units): positions are off by at most half of it per axis.
    pub fn step(&self) -> f64 {
        self.step
    }

    /// Largest error of a decoded coordinate (world units): half a grid step plus the
    /// f32 rounding of a coordinate of magnitude `magnitude`.
    pub fn position_error_bound(&self, magnitude: f32) -> f32 {
        (0.5 * self.step) as f32 + magnitude.abs() * f32::EPSILON
    }

    /// The largest power channel the powers are stored relative to.
    pub fn power_scale(&self) -> f64 {
        self.power_scale
    }

    /// Packs a record. The caller checks that the position, power and direction are
    /// finite and the direction non-zero (`PhotonMap::build` skips other records);
    /// positions outside the box are clamped onto it.
    #[inline]
    pub fn encode(&self, r: &PhotonRecord) -> CompactPhoton {
        let q = |x: f32, o: f64| {
            let g = (x as f64 - o) * self.inv_step;
            round_to_u64(g.max(0.0).min(POSITION_MAX as f64))
        };
        let p = r.position;
        let pos = q(p.x, self.origin[0])
            | (q(p.y, self.origin[1]) << POSITION_BITS)
            | (q(p.z, self.origin[2]) << (2 * POSITION_BITS))
            | if r.caustic { CAUSTIC_BIT } else { 0 };
        let depth = r.depth.min(MAX_DEPTH) as u32;
        CompactPhoton {
            pos,
            power: self.encode_power(r.power),
            dir: oct_encode(r.direction) | (depth << DEPTH_SHIFT),
        }
    }

    #[inline]
    fn encode_power(&self, power: Vec3) -> u32 {
        if self.power_scale == 0.0 {
            return 0;
        }
        let norm = |v: f32| (v.max(0.0) as f64 * self.inv_power_scale).min(1.0);
        let c = [norm(power.x), norm(power.y), norm(power.z)];
        let max = c[0].max(c[1]).max(c[2]);
        if max < exp2(-POWER_BIAS - 2) {
            return 0; // rounds to zero at the smallest exponent anyway
        }
        // Exact binary exponent of `max` (normal since max >= 2^-41): max in [2^e, 2^(e+1)).
        let e = ((max.to_bits() >> 52) & 0x7ff) as i32 - 1023;
        // E - 39 = e - 8 puts the largest mantissa in [256, 512).
        let mut exp = (e + POWER_BIAS - 8).clamp(0, 31);
        let mantissa = |exp: i32, v: f64| round_to_u64(v * exp2(POWER_BIAS - exp)) as u32;
        if mantissa(exp, max) >= 512 {
            exp += 1; // rounding carried; max <= 1 keeps exp <= 31
        }
        let m = |v: f64| mantissa(exp, v).min(511);
        m(c[0]) | (m(c[1]) << 9) | (m(c[2]) << 18) | ((exp as u32) << 27)
    }

    /// Decoded position (world units).
    #[inline]
    pub fn position(&self, p: &CompactPhoton) -> Vec3 {
        let g = p.grid();
        Vec3::new(
            (self.origin[0] + g[0] as f64 * self.step) as f32,
            (self.origin[1] + g[1] as f64 * self.step) as f32,
            (self.origin[2] + g[2] as f64 * self.step) as f32,
        )
    }

    /// The exact sum of the decoded powers of `photons`, per bounce depth
    /// (index = depth) and channel, with the photon count of each depth. The
    /// stored powers are integers times `2^(E - 39)`, so they are summed as
    /// integers: the result does not depend on the order or the thread count.
    pub fn power_sums(&self, photons: &[CompactPhoton]) -> Vec<(u64, [f64; 3])> {
        const DEPTHS: usize = MAX_DEPTH as usize + 1;
        let empty = || vec![(0u64, [0u128; 3]); DEPTHS];
        let add = |mut a: Vec<(u64, [u128; 3])>, b: Vec<(u64, [u128; 3])>| {
            for (x, y) in a.iter_mut().zip(b) {
                x.0 += y.0;
                for c in 0..3 {
                    x.1[c] += y.1[c];
                }
            }
            a
        };
        use rayon::prelude::*;
        let sums = photons
            .par_chunks(1 << 16)
            .map(|chunk| {
                let mut acc = empty();
                for p in chunk {
                    let e = &mut acc[p.depth() as usize];
                    e.0 += 1;
                    let exp = p.power >> 27;
                    for c in 0..3 {
                        e.1[c] += (((p.power >> (9 * c)) & 511) as u128) << exp;
                    }
                }
                acc
            })
            .reduce(empty, add);
        let unit = exp2(-POWER_BIAS) * self.power_scale;
        let mut out: Vec<(u64, [f64; 3])> = sums
            .into_iter()
            .map(|(n, s)| (n, s.map(|v| v as f64 * unit)))
            .collect();
        while out.last().is_some_and(|d| d.0 == 0) {
            out.pop();
        }
        out
    }

    /// Decoded power.
    pub fn power(&self, p: &CompactPhoton) -> Vec3 {
        let exp = (p.power >> 27) as i32;
        let unit = exp2(exp - POWER_BIAS) * self.power_scale;
        let m = |i: u32| ((p.power >> (9 * i)) & 511) as f64 * unit;
        Vec3::new(m(0) as f32, m(1) as f32, m(2) as f32)
    }

    /// Unpacks a photon.
    pub fn decode(&self, p: &CompactPhoton) -> PhotonRecord {
        PhotonRecord {
            position: self.position(p),
            power: self.power(p),
            direction: p.direction(),
            depth: p.depth(),
            caustic: p.is_caustic(),
        }
    }

    /// A query point in grid units (f32; see `query.rs` for why it is clamped).
    #[inline]
    pub(crate) fn grid_point(&self, p: Vec3) -> [f32; 3] {
        // 2^40 grid steps is 2^19 map extents away: any farther point is clamped there,
        // which keeps squared distances finite in f32 (their order is kept).
        const FAR: f64 = (1u64 << 40) as f64;
        [0, 1, 2].map(|a| ((p[a] as f64 - self.origin[a]) * self.inv_step).clamp(-FAR, FAR) as f32)
    }

    /// A length in grid units.
    #[inline]
    pub(crate) fn grid_length(&self, r: f32) -> f64 {
        r as f64 * self.inv_step
    }

    /// A squared length from grid units to world units.
    #[inline]
    pub(crate) fn world_dist2(&self, d2: f32) -> f32 {
        (d2 as f64 * self.step * self.step) as f32
    }

    /// The frame's parameters as bits, for checksums.
    pub(crate) fn bits(&self) -> [u64; 5] {
        [
            self.origin[0].to_bits(),
            self.origin[1].to_bits(),
            self.origin[2].to_bits(),
            self.step.to_bits(),
            self.power_scale.to_bits(),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compact_photon_is_16_bytes() {
        assert_eq!(std::mem::size_of::<CompactPhoton>(), 16);
    }

    #[test]
    fn order_puts_the_axis_first_and_split_axis_does_not_change_the_photon() {
        let q = Quantizer::new(Vec3::ZERO, Vec3::ONE, 1.0);
        let r = |x: f32, y: f32| PhotonRecord {
            position: Vec3::new(x, y, 0.5),
            power: Vec3::ONE,
            direction: Vec3::Z,
            depth: 0,
            caustic: false,
        };
        let a = q.encode(&r(0.1, 0.9));
        let mut b = q.encode(&r(0.9, 0.1));
        assert!(a.cmp_on(&b, 0).is_lt());
        assert!(a.cmp_on(&b, 1).is_gt());
        assert!(a.cmp_on(&a, 2).is_eq());
        b.set_axis(2);
        assert_eq!(b.axis(), 2);
        assert_eq!(q.decode(&b), q.decode(&q.encode(&r(0.9, 0.1))));
    }

    #[test]
    fn less_on_is_the_strict_part_of_cmp_on() {
        // A coarse lattice: many ties on each coordinate, some on the whole position.
        let q = Quantizer::new(Vec3::ZERO, Vec3::splat(3.0), 1.0);
        let mut rng = crate::rng::Rng::new(11);
        let photons: Vec<CompactPhoton> = (0..64)
            .map(|_| {
                let mut c = || (rng.next_f32() * 4.0).floor();
                let position = Vec3::new(c(), c(), c());
                let power = Vec3::splat(1.0 + c());
                q.encode(&PhotonRecord {
                    position,
                    power,
                    direction: Vec3::Z,
                    depth: 0,
                    caustic: false,
                })
            })
            .collect();
        for a in &photons {
            for b in &photons {
                for axis in 0..3 {
                    assert_eq!(a.less_on(b, axis), a.cmp_on(b, axis).is_lt());
                }
            }
        }
    }

    #[test]
    fn invalid_marker_is_never_an_encoding() {
        // Octahedral codes stop at 4094, the marker's are 4095.
        let q = Quantizer::new(Vec3::ZERO, Vec3::ONE, 1.0);
        for d in [
            Vec3::X,
            -Vec3::X,
            Vec3::Y,
            -Vec3::Y,
            Vec3::Z,
            -Vec3::Z,
            Vec3::ONE,
        ] {
            let p = q.encode(&PhotonRecord {
                position: Vec3::ONE,
                power: Vec3::ONE,
                direction: d,
                depth: 255,
                caustic: false,
            });
            assert_ne!(
                p.dir & 0x00FF_FFFF,
                CompactPhoton::INVALID.dir & 0x00FF_FFFF
            );
            assert_eq!(p.depth(), MAX_DEPTH);
        }
    }
}
