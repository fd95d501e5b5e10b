//! The noise between renders of one scene made with other seeds: each
//! pixel's variance over the images (per channel, unbiased), averaged over
//! the pixels, and its square root over the mean value. Pixels within two
//! of one that reads above 1 in any image (a light's, and its edges) are
//! left out: their anti-aliasing would hide the rest.
//!
//! `cargo run --release --example seed_noise -- A.exr B.exr [C.exr ...]`
//!
//! With the renders of one map (`render --map M --seed S`) it is the
//! render's own noise; with `--direct-only` the direct light's; the
//! variances are comparable when the images come from the same scene and
//! camera (docs/rendering.md, "Again, and two exact speed-ups").

use adaptive_pm::render::image::Image;

/// How far from a bright pixel a pixel is left out.
const MARGIN: i64 = 2;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let paths: Vec<String> = std::env::args().skip(1).collect();
    if paths.len() < 2 {
        return Err("usage: seed_noise A.exr B.exr [C.exr ...]".into());
    }
    let images = paths
        .iter()
        .map(Image::read_exr)
        .collect::<Result<Vec<_>, _>>()?;
    let (w, h) = (images[0].width, images[0].height);
    if images.iter().any(|i| (i.width, i.height) != (w, h)) {
        return Err("the images differ in size".into());
    }
    let kept = kept_pixels(&images, w as i64, h as i64);
    let n = images.len() as f64;
    let (mut variance, mut mean, mut count) = (0.0f64, 0.0f64, 0usize);
    for p in (0..kept.len()).filter(|&p| kept[p]) {
        for c in 0..3 {
            let v: Vec<f64> = images.iter().map(|i| f64::from(i.pixels[p][c])).collect();
            let m = v.iter().sum::<f64>() / n;
            variance += v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0);
            mean += m;
            count += 1;
        }
    }
    if count == 0 || !mean.is_finite() || mean <= 0.0 || !variance.is_finite() {
        return Err("no pixel is kept, or the kept ones are black or not finite".into());
    }
    let (variance, mean) = (variance / count as f64, mean / count as f64);
    println!(
        "{} images, {} of {} pixels kept: mean {mean:.5}, variance {variance:.4e}, relative noise {:.3} %",
        images.len(),
        count / 3,
        kept.len(),
        100.0 * variance.sqrt() / mean
    );
    Ok(())
}

/// Whether each pixel is farther than [`MARGIN`] from every pixel that
/// reads above 1 in some image.
fn kept_pixels(images: &[Image], w: i64, h: i64) -> Vec<bool> {
    let bright: Vec<bool> = (0..(w * h) as usize)
        .map(|p| images.iter().any(|i| i.pixels[p].max_element() > 1.0))
        .collect();
    (0..w * h)
        .map(|p| {
            let (x, y) = (p % w, p / w);
            !(-MARGIN..=MARGIN).any(|dy| {
                (-MARGIN..=MARGIN).any(|dx| {
                    let (a, b) = (x + dx, y + dy);
                    (0..w).contains(&a) && (0..h).contains(&b) && bright[(b * w + a) as usize]
                })
            })
        })
        .collect()
}
