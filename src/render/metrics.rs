//! Image errors against a reference.
//!
//! - [`rmse`]: `sqrt(mean over pixels and channels of (a - b)^2)`.
//! - [`relative_rmse_masked`]: `rmse(a, b) / mean(b)` over the kept pixels
//!   (the reference's mean over them and the channels): a scale-free number,
//!   comparable across scenes. A per-pixel relative error would blow up on
//!   black pixels. Pass a mask of all `true` to keep every pixel.

use super::Image;
use crate::error::{Error, Result};

fn check(a: &Image, b: &Image) -> Result<()> {
    if a.width != b.width || a.height != b.height {
        return Err(Error::param(
            "reference",
            format!(
                "is {} x {} but the image is {} x {}",
                b.width, b.height, a.width, a.height
            ),
        ));
    }
    Ok(())
}

/// Root-mean-square difference over pixels and channels.
///
/// # Errors
/// [`Error::InvalidParameter`] when the sizes differ.
pub fn rmse(a: &Image, b: &Image) -> Result<f64> {
    check(a, b)?;
    let sum: f64 = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(p, q)| {
            let d = (*p - *q).as_dvec3();
            d.length_squared()
        })
        .sum();
    Ok((sum / (3 * a.pixels.len().max(1)) as f64).sqrt())
}

/// [`rmse`] over the reference's mean value (0 when that mean is 0), both
/// over the pixels where `keep` is true (the others, for instance the
/// light's own pixels, are left out of both the error and the mean).
///
/// # Errors
/// As [`rmse`], and when `keep` has not one entry per pixel.
pub fn relative_rmse_masked(a: &Image, reference: &Image, keep: &[bool]) -> Result<f64> {
    check(a, reference)?;
    if keep.len() != a.pixels.len() {
        return Err(Error::param(
            "pixel mask",
            format!("has {} entries for {} pixels", keep.len(), a.pixels.len()),
        ));
    }
    let (mut se, mut sum, mut n) = (0.0f64, 0.0f64, 0usize);
    for ((p, q), &k) in a.pixels.iter().zip(&reference.pixels).zip(keep) {
        if k {
            se += (*p - *q).as_dvec3().length_squared();
            sum += q.as_dvec3().element_sum();
            n += 1;
        }
    }
    let n = (3 * n.max(1)) as f64;
    let mean = sum / n;
    Ok(if mean > 0.0 {
        (se / n).sqrt() / mean
    } else {
        0.0
    })
}

/// Per-channel relative difference of the means over the kept pixels:
/// `mean(a) / mean(reference) - 1` (0 where the reference's mean is 0).
///
/// # Errors
/// As [`relative_rmse_masked`].
pub fn mean_bias(a: &Image, reference: &Image, keep: &[bool]) -> Result<[f64; 3]> {
    relative_rmse_masked(a, reference, keep)?;
    let (mut sa, mut sr) = ([0.0f64; 3], [0.0f64; 3]);
    for ((p, q), &k) in a.pixels.iter().zip(&reference.pixels).zip(keep) {
        if k {
            for c in 0..3 {
                sa[c] += p[c] as f64;
                sr[c] += q[c] as f64;
            }
        }
    }
    Ok(std::array::from_fn(|c| {
        if sr[c] > 0.0 {
            sa[c] / sr[c] - 1.0
        } else {
            0.0
        }
    }))
}
