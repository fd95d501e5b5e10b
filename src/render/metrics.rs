//! Image errors against a reference.
//!
//! - [`rmse`]: `sqrt(mean over pixels and channels of (a - b)^2)`.
//! - [`relative_rmse`]: `rmse(a, b) / mean(b)` (the reference's mean over
//!   pixels and channels): a scale-free number, comparable across scenes.
//!   A per-pixel relative error would blow up on black pixels.

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

/// [`rmse`] over the reference's mean value (0 when that mean is 0).
///
/// # Errors
/// As [`rmse`].
pub fn relative_rmse(a: &Image, reference: &Image) -> Result<f64> {
    let e = rmse(a, reference)?;
    let m = reference.mean().as_dvec3().element_sum() / 3.0;
    Ok(if m > 0.0 { e / m } else { 0.0 })
}
