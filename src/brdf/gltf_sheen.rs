//! The sheen of `KHR_materials_sheen` as [`super::GltfPbr`] layers it: the
//! back-scattering of a layer of fibres (velvet, cloth), Conty and Kulla's
//! "Charlie" microfibre lobe (2017, *Production Friendly Microfacet Sheen
//! BRDF*) of colour `c` (`sheenColor`) and roughness `r`
//! (`sheenRoughness`, `alpha = r^2`), over the base material, with the
//! extension's albedo scaling.
//!
//! ```text
//! D(h)    = (2 + 1/alpha) sin(theta_h)^(1/alpha) / (2 pi)
//! V       = 1 / ((1 + Lambda(cos_i) + Lambda(cos_o)) 4 cos_i cos_o)
//! sheen   = c D(h) V / max(1, E_fit(cos_i), E_fit(cos_o))
//! S(i, o) = min(1 - max3(c) E(cos_i), 1 - max3(c) E(cos_o))
//! f_r     = sheen + S(i, o) f_base
//! ```
//! `Lambda` is the paper's fit, as the extension gives it (coefficients
//! mixed by `(1 - alpha)^2`); `D` and `V` are the extension's, to within
//! 1e-4 of its formulas in f64 (a test).
//!
//! `E_fit(mu, r)` is the directional albedo of the white lobe `D V`. It
//! passes 1 towards grazing incidence at small roughness (2.7 at `r =
//! 0.07` and `mu = 1e-4`; above 1 below `mu = 0.054` at `r = 0.07`, 0.026
//! at `r = 0.2`, nowhere above `mu = 1e-4` from `r = 0.3`), and below
//! `mu = 1e-4` it grows without bound at every roughness (1.5 at `mu =
//! 1e-6` at `r = 1`): the fit does not conserve energy there, and a photon
//! would gain power at every such bounce. So the lobe is cut where either
//! cosine is below 1e-4 (`GRAZING`), and divided by the larger of 1 and
//! `E_fit` at either cosine: symmetric, so reciprocal, and of albedo at
//! most 1. It is the extension's lobe wherever `E_fit <= 1` at both
//! cosines; a pair with one end in the band where it is not is dimmed,
//! which takes the albedo at `mu = 0.1` from 0.416 to 0.378 at `r = 0.07`
//! (-9 %), by 4 % at `r = 0.1` and by less than 0.2 % from `r = 0.2`
//! (`print_profile` in the tests). `E(mu, r)` is the directional albedo of
//! that modelled white lobe.
//!
//! Both are tabulated once per process by quadrature over the reflected
//! hemisphere (`cos_o = t^2` rows, which gather at grazing directions),
//! on nodes in `sqrt(mu)` and `sqrt(r)`, and read high: each node is
//! raised by twice the largest shortfall of the bilinear interpolant found
//! at nine points of the cells around it, plus a margin of 2e-3. A test
//! checks every cell at nine more points against a quadrature of twice
//! the rows and columns. With `E` read high, the layer reflects at most
//! `max3(c) E(cos_i)` of the light and lets the base reflect at most `1 -
//! max3(c) E(cos_i)` of it: the albedo is at most 1, and the scaling, the
//! extension's own symmetric form, keeps the model reciprocal. The
//! extension's Fresnel term is 1.
//!
//! The layer is sampled apart from the base, by uniform directions over
//! the hemisphere (`brdf/gltf_pbr.rs`): it gathers at grazing directions,
//! where a cosine's pdf vanishes and its weights would not be bounded.
//!
//! A roughness below [`Sheen::MIN_ROUGHNESS`] is raised to it: the lobe is
//! then a spike at half vectors within a few degrees of the horizon, where
//! the tables' quadrature is not checked.

use glam::Vec3;
use std::f32::consts::PI;
use std::sync::OnceLock;

/// A sheen layer: colour and perceptual roughness ([`Sheen::NONE`]: none).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Sheen {
    pub(crate) color: Vec3,
    /// In [[`Sheen::MIN_ROUGHNESS`], 1].
    pub(crate) roughness: f32,
}

/// The fit's coefficients `(a, b, c, d, e)` at alpha 1 and at alpha 0.
const FIT_AT_1: [f32; 5] = [21.5473, 3.82987, 0.19823, -1.97760, -4.32054];
const FIT_AT_0: [f32; 5] = [25.3245, 3.32435, 0.16801, -1.27393, -4.85967];

impl Sheen {
    /// No sheen: the base material alone, bit for bit.
    pub(crate) const NONE: Sheen = Sheen {
        color: Vec3::ZERO,
        roughness: 1.0,
    };

    /// The smallest roughness modelled (module docs).
    pub(crate) const MIN_ROUGHNESS: f32 = 0.07;

    pub(crate) fn is_none(&self) -> bool {
        self.color.max_element() <= 0.0
    }

    /// `max3(c) E(mu)`: the most any channel of the layer reflects of the
    /// light arriving at cosine `mu` (read high, module docs).
    pub(crate) fn reflected(&self, mu: f32) -> f32 {
        self.color.max_element() * white_albedo(mu, self.roughness)
    }

    /// `S(i, o)`: the share of the base's reflection the layer lets
    /// through, for a pair of cosines.
    pub(crate) fn scaling(&self, cos_i: f32, cos_o: f32) -> f32 {
        (1.0 - self.reflected(cos_i).max(self.reflected(cos_o))).max(0.0)
    }

    /// The sheen lobe `c D V` (both directions above the horizon).
    pub(crate) fn eval(&self, wi: Vec3, wo: Vec3) -> Vec3 {
        self.color * modelled_lobe(wi, wo, self.roughness)
    }

    /// The lobe's albedo from `wi`, each reflected direction weighted by
    /// `weight(wo)` (what a layer above lets out towards it; 1 for the
    /// plain albedo), per channel, by the tables' quadrature
    /// ([`quadrature_by_rows`]).
    pub(crate) fn albedo_weighted(&self, wi: Vec3, weight: impl Fn(Vec3) -> f32) -> Vec3 {
        let weight = &weight;
        let e = lobe_albedo(wi, self.roughness, modelled_side, weight);
        self.color * e
    }
}

/// The fit's `l(x)` at `alpha` (the extension's `lambdaSheenNumericHelper`).
fn fit_l(x: f32, alpha: f32) -> f32 {
    let t = (1.0 - alpha) * (1.0 - alpha);
    let p: [f32; 5] = std::array::from_fn(|k| FIT_AT_1[k] + (FIT_AT_0[k] - FIT_AT_1[k]) * t);
    p[0] / (1.0 + p[1] * x.powf(p[2])) + p[3] * x + p[4]
}

/// The fibres' `Lambda(cos_theta)` (cosine in [0, 1]).
fn lambda(cos: f32, alpha: f32) -> f32 {
    if cos < 0.5 {
        fit_l(cos, alpha).exp()
    } else {
        (2.0 * fit_l(0.5, alpha) - fit_l(1.0 - cos, alpha)).exp()
    }
}

/// The Charlie distribution at a half vector of cosine `cos_h`.
fn charlie(cos_h: f32, alpha: f32) -> f32 {
    let sin2 = (1.0 - cos_h * cos_h).max(0.0);
    (2.0 + 1.0 / alpha) * sin2.powf(0.5 / alpha) / (2.0 * PI)
}

/// What the lobe needs of one direction alone: its `Lambda`, and what the
/// lobe is divided by on its account (1 for the fit's own lobe,
/// `max(1, E_fit(cos))` for the modelled one).
#[derive(Clone, Copy)]
struct Side {
    lambda: f32,
    norm: f32,
}

/// The fit's own lobe's [`Side`] at cosine `cos`.
fn fit_side(cos: f32, roughness: f32) -> Side {
    Side {
        lambda: lambda(cos, roughness * roughness),
        norm: 1.0,
    }
}

/// The modelled lobe's [`Side`] at cosine `cos`, from the fit's albedo
/// table `fit`.
fn modelled_side_of(fit: &[f32], cos: f32, roughness: f32) -> Side {
    Side {
        lambda: lambda(cos, roughness * roughness),
        norm: 1f32.max(lookup(fit, cos, roughness)),
    }
}

fn modelled_side(cos: f32, roughness: f32) -> Side {
    modelled_side_of(&tables().fit, cos, roughness)
}

/// `D V` of a white lobe over the larger of its sides' norms; 0 unless
/// both directions are at least [`GRAZING`] above the horizon.
fn lobe_of_sides(wi: Vec3, wo: Vec3, (si, so): (Side, Side), alpha: f32) -> f32 {
    // Below GRAZING the fit's albedo grows without bound as the cosine
    // falls (module docs): the lobe is cut there, on both sides alike.
    if wi.z < GRAZING || wo.z < GRAZING {
        return 0.0;
    }
    let sum = wi + wo;
    let len = sum.length();
    if len <= 0.0 {
        return 0.0;
    }
    let d = charlie(sum.z / len, alpha);
    // Written symmetric in the two directions, bit for bit (reciprocity).
    let v = 1.0 / ((1.0 + (si.lambda + so.lambda)) * (4.0 * (wi.z * wo.z)));
    let f = d * v / si.norm.max(so.norm);
    if f.is_finite() {
        f
    } else {
        0.0
    }
}

/// `D V` of the fit's white lobe.
#[cfg(test)]
fn white_lobe(wi: Vec3, wo: Vec3, roughness: f32) -> f32 {
    let sides = (fit_side(wi.z, roughness), fit_side(wo.z, roughness));
    lobe_of_sides(wi, wo, sides, roughness * roughness)
}

/// `integral lobe(wi, wo) weight(wo) cos_o dwo` for the white lobe whose
/// sides `side` gives, by [`quadrature_by_rows`] (each row's side computed
/// once).
fn lobe_albedo(
    wi: Vec3,
    roughness: f32,
    side: impl Fn(f32, f32) -> Side,
    weight: &impl Fn(Vec3) -> f32,
) -> f32 {
    let alpha = roughness * roughness;
    let si = side(wi.z, roughness);
    let row = |cos_o: f32| {
        let so = side(cos_o, roughness);
        move |wo: Vec3| lobe_of_sides(wi, wo, (si, so), alpha) * weight(wo)
    };
    quadrature_by_rows(wi, row, QUAD_T, QUAD_PHI)
}

/// Rows of the cosine substitution `cos_o = t^2` (the lobe gathers at
/// grazing reflected directions, where `t` puts its rows closest).
const QUAD_T: usize = 64;
/// Columns in the azimuth relative to `wi`, over half the circle (the lobe
/// is symmetric about the plane of incidence).
const QUAD_PHI: usize = 32;

/// [`quadrature_by_rows`] of one integrand `g` for every row, at the
/// tables' resolution.
#[cfg(test)]
fn hemisphere_quadrature(wi: Vec3, g: impl Fn(Vec3) -> f32) -> f32 {
    hemisphere_quadrature_n(wi, g, QUAD_T, QUAD_PHI)
}

#[cfg(test)]
fn hemisphere_quadrature_n(wi: Vec3, g: impl Fn(Vec3) -> f32, nt: usize, nphi: usize) -> f32 {
    quadrature_by_rows(wi, |_| &g, nt, nphi)
}

/// `integral g(wo) cos_o dwo` over the upper hemisphere by the midpoint
/// rule in `(t, phi)`, `cos_o = t^2`, on `nt` rows and `nphi` columns over
/// half the circle, for a `g` symmetric about the plane of `wi` and the
/// normal; `g = row(cos_o)` is made once per row, for what depends on
/// `cos_o` alone.
fn quadrature_by_rows<G: Fn(Vec3) -> f32>(
    wi: Vec3,
    row: impl Fn(f32) -> G,
    nt: usize,
    nphi: usize,
) -> f32 {
    // The azimuth is measured from wi's own, so the grid's symmetry is the
    // lobe's whatever wi is.
    let phi_i = wi.y.atan2(wi.x);
    let columns: Vec<(f32, f32)> = (0..nphi)
        .map(|b| (phi_i + PI * (b as f32 + 0.5) / nphi as f32).sin_cos())
        .collect();
    let mut sum = 0.0f64;
    for a in 0..nt {
        let t = (a as f32 + 0.5) / nt as f32;
        let cos_o = t * t;
        let sin_o = (1.0 - cos_o * cos_o).max(0.0).sqrt();
        // dw cos_o = cos_o d(cos_o) dphi = t^2 2t dt dphi.
        let jacobian = f64::from(cos_o * 2.0 * t);
        let g = row(cos_o);
        let mut sum_row = 0.0f64;
        for &(sin, cos) in &columns {
            sum_row += f64::from(g(Vec3::new(sin_o * cos, sin_o * sin, cos_o)));
        }
        sum += sum_row * jacobian;
    }
    // Both halves of the circle: 2 pi / nphi per column, 1 / nt per row.
    (sum * 2.0 * std::f64::consts::PI / (nphi * nt) as f64) as f32
}

/// Nodes in `sqrt(mu)`, uniform over [0, 1]: the albedo changes fastest
/// at grazing incidence.
const MU_NODES: usize = 48;
/// Nodes in `sqrt((r - MIN_ROUGHNESS) / (1 - MIN_ROUGHNESS))`: it changes
/// fastest at small roughness.
const ROUGH_NODES: usize = 24;
/// The smallest cosine at which the lobe reflects, and the one the node at
/// `mu = 0` is computed at.
const GRAZING: f32 = 1e-4;

fn rough_at(j: usize) -> f32 {
    rough_from(j as f32 / (ROUGH_NODES - 1) as f32)
}

fn mu_at(i: usize) -> f32 {
    let s = i as f32 / (MU_NODES - 1) as f32;
    (s * s).max(GRAZING)
}

/// The two tables, `[rough * MU_NODES + mu]`, read high (module docs).
struct Tables {
    /// The directional albedo of the fit's white lobe `D V`.
    fit: Vec<f32>,
    /// That of the lobe as modelled, `D V / max(1, raw(cos_i), raw(cos_o))`.
    lobe: Vec<f32>,
}

fn tables() -> &'static Tables {
    static TABLES: OnceLock<Tables> = OnceLock::new();
    TABLES.get_or_init(|| {
        let fit = read_high(|mu, r| lobe_albedo(incident(mu), r, fit_side, &|_| 1.0));
        let modelled = |cos, r| modelled_side_of(&fit, cos, r);
        let lobe = read_high(|mu, r| lobe_albedo(incident(mu), r, modelled, &|_| 1.0));
        Tables { fit, lobe }
    })
}

/// The incident direction of cosine `mu` (azimuth 0).
fn incident(mu: f32) -> Vec3 {
    Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu)
}

/// The table of `albedo(mu, r)`, raised so that its bilinear interpolant
/// does not read below it between the nodes: each node goes up by twice
/// the largest shortfall found at the [`PROBES`] of the cells around it,
/// and by [`MARGIN`].
fn read_high(albedo: impl Fn(f32, f32) -> f32) -> Vec<f32> {
    let mut t = Vec::with_capacity(ROUGH_NODES * MU_NODES);
    for j in 0..ROUGH_NODES {
        for i in 0..MU_NODES {
            t.push(albedo(mu_at(i), rough_at(j)));
        }
    }
    // The shortfall of each cell, `[j * (MU_NODES - 1) + i]`.
    let mut short = Vec::with_capacity((ROUGH_NODES - 1) * (MU_NODES - 1));
    for j in 0..ROUGH_NODES - 1 {
        for i in 0..MU_NODES - 1 {
            let mut worst = 0.0f32;
            for (du, dv) in PROBES {
                let x = (i as f32 + du) / (MU_NODES - 1) as f32;
                let y = (j as f32 + dv) / (ROUGH_NODES - 1) as f32;
                let (mu, r) = ((x * x).max(GRAZING), rough_from(y));
                worst = worst.max(albedo(mu, r) - lookup(&t, mu, r));
            }
            short.push(worst);
        }
    }
    for j in 0..ROUGH_NODES {
        for i in 0..MU_NODES {
            let mut raise = 0.0f32;
            for jj in j.saturating_sub(1)..j.min(ROUGH_NODES - 2) + 1 {
                for ii in i.saturating_sub(1)..i.min(MU_NODES - 2) + 1 {
                    raise = raise.max(short[jj * (MU_NODES - 1) + ii]);
                }
            }
            t[j * MU_NODES + i] += 2.0 * raise + MARGIN;
        }
    }
    t
}

/// What every node of the tables is raised by beyond twice the measured
/// shortfall of its cells (the interpolant's error between the points
/// checked: the modelled lobe's albedo has a ridge where the fit's crosses
/// 1, which a cell's probes may straddle, and there the shortfall they
/// find is large).
const MARGIN: f32 = 2e-3;

/// Where in a cell (in node spacings) [`read_high`] measures the
/// interpolant's shortfall: the middles of its edges, its centre and the
/// quarter points of its diagonals.
const PROBES: [(f32, f32); 9] = [
    (0.5, 0.0),
    (0.0, 0.5),
    (0.5, 0.5),
    (1.0, 0.5),
    (0.5, 1.0),
    (0.25, 0.25),
    (0.75, 0.75),
    (0.25, 0.75),
    (0.75, 0.25),
];

fn rough_from(y: f32) -> f32 {
    Sheen::MIN_ROUGHNESS + (1.0 - Sheen::MIN_ROUGHNESS) * y * y
}

/// The bilinear interpolant of a table at `(mu, r)`.
fn lookup(t: &[f32], mu: f32, roughness: f32) -> f32 {
    let r0 = Sheen::MIN_ROUGHNESS;
    let y = ((roughness.clamp(r0, 1.0) - r0) / (1.0 - r0)).sqrt() * (ROUGH_NODES - 1) as f32;
    let j = (y as usize).min(ROUGH_NODES - 2);
    let v = (y - j as f32).clamp(0.0, 1.0);
    let x = mu.clamp(0.0, 1.0).sqrt() * (MU_NODES - 1) as f32;
    let i = (x as usize).min(MU_NODES - 2);
    let u = x - i as f32;
    let row = |j: usize| {
        let k = j * MU_NODES + i;
        t[k] + (t[k + 1] - t[k]) * u
    };
    row(j) + (row(j + 1) - row(j)) * v
}

/// The fit's white lobe `D V` as modelled: divided by
/// `max(1, E_fit(cos_i), E_fit(cos_o))`, so that it never reflects more
/// than it receives (the fit's albedo exceeds 1 towards grazing incidence
/// at small roughness); symmetric, so reciprocal.
fn modelled_lobe(wi: Vec3, wo: Vec3, roughness: f32) -> f32 {
    let sides = (
        modelled_side(wi.z, roughness),
        modelled_side(wo.z, roughness),
    );
    lobe_of_sides(wi, wo, sides, roughness * roughness)
}

/// `E(mu, r)`: the directional albedo of the modelled white sheen lobe of
/// roughness `r` at incident cosine `mu`, from the table (read high).
pub(crate) fn white_albedo(mu: f32, roughness: f32) -> f32 {
    lookup(&tables().lobe, mu, roughness)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The specification's lobe, in f64, as it writes it.
    fn spec_lobe(l: Vec3, v: Vec3, roughness: f64) -> f64 {
        let (l, v) = (l.as_dvec3(), v.as_dvec3());
        let h = (l + v).normalize();
        let alpha_g = roughness * roughness;
        let inv_r = 1.0 / alpha_g;
        let sin2h = 1.0 - h.z * h.z;
        let d = (2.0 + inv_r) * sin2h.powf(inv_r * 0.5) / (2.0 * std::f64::consts::PI);
        let l_fit = |x: f64| {
            let t = (1.0 - alpha_g) * (1.0 - alpha_g);
            let mix = |p1: f64, p0: f64| p1 + (p0 - p1) * t;
            let a = mix(21.5473, 25.3245);
            let b = mix(3.82987, 3.32435);
            let c = mix(0.19823, 0.16801);
            let dd = mix(-1.97760, -1.27393);
            let e = mix(-4.32054, -4.85967);
            a / (1.0 + b * x.powf(c)) + dd * x + e
        };
        let lambda = |c: f64| {
            if c.abs() < 0.5 {
                l_fit(c).exp()
            } else {
                (2.0 * l_fit(0.5) - l_fit(1.0 - c)).exp()
            }
        };
        d / ((1.0 + lambda(v.z) + lambda(l.z)) * (4.0 * v.z * l.z))
    }

    fn dir(theta: f32, phi: f32) -> Vec3 {
        Vec3::new(
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        )
    }

    #[test]
    fn the_lobe_is_the_specifications() {
        for r in [0.1f32, 0.3, 0.6, 1.0] {
            for (ti, to, phi) in [
                (0.3, 1.2, 2.0),
                (1.3, 1.4, 0.4),
                (0.0, 0.7, 1.0),
                (1.5, 0.2, 3.0),
            ] {
                let (wi, wo) = (dir(ti, 0.0), dir(to, phi));
                let want = spec_lobe(wi, wo, f64::from(r));
                let got = f64::from(white_lobe(wi, wo, r));
                assert!(
                    (got - want).abs() <= 1e-4 * want.max(1e-3),
                    "r={r} ({ti}, {to}, {phi}): {got} vs {want}"
                );
                // Reciprocal.
                assert_eq!(white_lobe(wi, wo, r), white_lobe(wo, wi, r));
            }
        }
    }

    #[test]
    fn the_distribution_is_normalised() {
        // integral D(h) cos(theta_h) dh over the hemisphere = 1.
        for r in [Sheen::MIN_ROUGHNESS, 0.3, 1.0] {
            let alpha = r * r;
            let n = 200_000;
            let s: f64 = (0..n)
                .map(|k| {
                    let c = (k as f64 + 0.5) / n as f64;
                    f64::from(charlie(c as f32, alpha)) * c * 2.0 * std::f64::consts::PI / n as f64
                })
                .sum();
            assert!((s - 1.0).abs() < 2e-3, "r={r}: {s}");
        }
    }

    /// The modelled white lobe's albedo at `mu` by a quadrature of `nt` x
    /// `nphi` (the tables' is 64 x 32).
    fn albedo_by_quadrature(mu: f32, r: f32, nt: usize, nphi: usize) -> f32 {
        let wi = incident(mu);
        hemisphere_quadrature_n(wi, |wo| modelled_lobe(wi, wo, r), nt, nphi)
    }

    #[test]
    fn the_table_never_reads_below_a_finer_quadrature() {
        // Every cell at the nine inner points of its 4 x 4 subdivision,
        // against a quadrature of twice the rows and columns.
        let (mut below, mut above) = (0.0f32, 0.0f32);
        for j in 0..ROUGH_NODES - 1 {
            for i in 0..MU_NODES - 1 {
                for (du, dv) in [0.25f32, 0.5, 0.75]
                    .iter()
                    .flat_map(|&a| [(a, 0.25), (a, 0.5), (a, 0.75)])
                {
                    let x = (i as f32 + du) / (MU_NODES - 1) as f32;
                    let y = (j as f32 + dv) / (ROUGH_NODES - 1) as f32;
                    let (mu, r) = ((x * x).max(GRAZING), rough_from(y));
                    let fine = albedo_by_quadrature(mu, r, 2 * QUAD_T, 2 * QUAD_PHI);
                    let table = white_albedo(mu, r);
                    below = below.max(fine - table);
                    above = above.max(table - fine);
                    // Less the two quadratures' difference, about 1e-4.
                    assert!(table >= fine - 2e-4, "mu={mu} r={r}: {table} < {fine}");
                    assert!(
                        fine <= 1.0 + 2e-4,
                        "mu={mu} r={r}: the lobe reflects {fine}"
                    );
                }
            }
        }
        eprintln!("table below the fine quadrature by at most {below}, above by at most {above}");
        assert!(above < 0.1, "{above}");
    }

    /// Prints, per roughness, the largest cosine at which the fit's lobe
    /// reflects more than it receives, and the modelled lobe's albedo
    /// beside the fit's at a few cosines (`cargo test --release --lib
    /// print_profile -- --ignored --nocapture`; docs/scenes.md).
    #[test]
    #[ignore]
    fn print_profile() {
        let fit = |mu: f32, r: f32| lobe_albedo(incident(mu), r, fit_side, &|_| 1.0);
        for r in [0.07f32, 0.1, 0.2, 0.3, 0.5, 1.0] {
            let over = (0..2000)
                .map(|k| 1e-4 + 0.2 * k as f32 / 2000.0)
                .filter(|&mu| fit(mu, r) > 1.0)
                .fold(0.0f32, f32::max);
            let row: Vec<String> = [1e-4f32, 0.01, 0.05, 0.1, 0.15, 0.3, 0.6, 1.0]
                .iter()
                .map(|&mu| {
                    format!(
                        "{mu}: {:.3}/{:.3}",
                        fit(mu, r),
                        albedo_by_quadrature(mu, r, 64, 32)
                    )
                })
                .collect();
            eprintln!(
                "r={r}: fit > 1 up to cos {over:.4}; fit/modelled {}",
                row.join(" ")
            );
        }
    }

    #[test]
    fn the_quadrature_integrates_a_cosine_lobe() {
        // integral cos_o dw = pi; integral cos_o^2 dw = 2 pi / 3.
        let wi = dir(0.7, 0.3);
        let one = hemisphere_quadrature(wi, |_| 1.0);
        let cos = hemisphere_quadrature(wi, |wo| wo.z);
        assert!((one - PI).abs() < 1e-3, "{one}");
        assert!((cos - 2.0 * PI / 3.0).abs() < 1e-3, "{cos}");
    }

    #[test]
    fn the_white_albedo_is_positive_and_at_most_about_1() {
        for i in 0..MU_NODES {
            let mu = mu_at(i);
            let mut last = 0.0;
            for j in 0..ROUGH_NODES {
                let e = white_albedo(mu, rough_at(j));
                // Read high by the margin and the cells' shortfall (up to
                // 0.05 in the first cells above grazing, where the albedo
                // turns fastest): S clamps at 0 where it passes 1.
                assert!((0.0..=1.05).contains(&e), "{mu} {j}: {e}");
                last = e.max(last);
            }
            assert!(last > 0.0);
        }
    }
}
