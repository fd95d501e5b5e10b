//! Images in memory and on disk (the files with the feature `image-io`).
//!
//! - OpenEXR: linear RGB radiance, 32-bit float, no alpha (`Image::write_exr`).
//! - PNG preview: 8-bit sRGB after a tone map ([`ToneMap`], `Image::write_png`): the radiance is
//!   scaled by `2^exposure`, then Reinhard's `c / (1 + c)` per channel, then the
//!   sRGB transfer curve. Documented and simple, not a film emulation.
//! - Files are written to a temporary name in the same folder and renamed, so
//!   a partial image never sits under the final name.
//! - Sizes: each side in `1..=`[`MAX_DIMENSION`], and the pixel buffer within a
//!   quarter of the available memory.

use crate::engine::config::available_memory;
use crate::engine::Shard;
use crate::error::{Error, Result};
use glam::Vec3;
use std::path::Path;

/// Largest width or height accepted.
pub const MAX_DIMENSION: u32 = 16384;

/// Checks an image size.
///
/// # Errors
/// [`Error::InvalidParameter`] for a zero side, a side above [`MAX_DIMENSION`],
/// or a pixel buffer larger than a quarter of the available memory.
pub fn check_dimensions(width: u32, height: u32) -> Result<()> {
    check_sides(width, height)?;
    // The RGB buffer plus the EXR writer's copy.
    let bytes = width as u64 * height as u64 * 12 * 2;
    let allowed = available_memory() / 4;
    if bytes > allowed {
        return Err(Error::param(
            "width",
            format!(
                "{width} x {height} pixels need {bytes} bytes, more than a quarter of the \
                 available memory ({allowed} bytes)"
            ),
        ));
    }
    Ok(())
}

/// Each side in `1..=`[`MAX_DIMENSION`].
fn check_sides(width: u32, height: u32) -> Result<()> {
    for (name, v) in [("width", width), ("height", height)] {
        if v == 0 || v > MAX_DIMENSION {
            return Err(Error::param(
                name,
                format!("must be in 1..={MAX_DIMENSION} pixels, got {v}"),
            ));
        }
    }
    Ok(())
}

/// Linear RGB pixels, row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height` pixels.
    pub pixels: Vec<Vec3>,
}

/// The PNG tone map: `2^exposure` scale, Reinhard per channel, sRGB.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToneMap {
    /// Exposure in stops.
    pub exposure: f32,
}

impl Default for ToneMap {
    fn default() -> Self {
        ToneMap { exposure: 0.0 }
    }
}

impl ToneMap {
    /// One linear channel to an 8-bit sRGB value.
    pub fn apply(&self, c: f32) -> u8 {
        let c = if c.is_finite() { c.max(0.0) } else { 0.0 };
        let c = c * self.exposure.exp2();
        let c = c / (1.0 + c);
        let s = if c <= 0.003_130_8 {
            12.92 * c
        } else {
            1.055 * c.powf(1.0 / 2.4) - 0.055
        };
        (s * 255.0 + 0.5).clamp(0.0, 255.0) as u8
    }
}

#[cfg(feature = "image-io")]
fn io_err(path: &Path, source: std::io::Error) -> Error {
    Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Checks that `path` can receive a file: its folder exists, it is not a
/// folder, and a file can be created beside it (tried and removed).
///
/// # Errors
/// [`Error::Io`] saying which.
pub fn check_output_path(path: &Path) -> Result<()> {
    // Hook (issue 12): the shared safe-output module refuses non-regular
    // targets and probes with an exclusively created temporary file.
    crate::output::probe(path)
}

/// Writes through `write` to an exclusive temporary file, then renames it to
/// `path` ([`crate::output::write_via_path`]).
#[cfg(feature = "image-io")]
fn write_atomic(path: &Path, write: impl FnOnce(&Path) -> std::io::Result<()>) -> Result<()> {
    crate::output::write_via_path(path, write)
}

#[cfg(feature = "image-io")]
fn exr_io(e: exr::error::Error) -> std::io::Error {
    match e {
        exr::error::Error::Io(e) => e,
        other => std::io::Error::other(other.to_string()),
    }
}

impl Image {
    /// A black image.
    ///
    /// # Errors
    /// As [`check_dimensions`].
    pub fn new(width: u32, height: u32) -> Result<Self> {
        check_dimensions(width, height)?;
        Ok(Image {
            width,
            height,
            pixels: vec![Vec3::ZERO; width as usize * height as usize],
        })
    }

    /// The pixel at column `x`, row `y` (row 0 at the top).
    pub fn pixel(&self, x: u32, y: u32) -> Vec3 {
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// Mean RGB over the pixels.
    pub fn mean(&self) -> Vec3 {
        let s = self.pixels.iter().fold([0f64; 3], |a, p| {
            [a[0] + p.x as f64, a[1] + p.y as f64, a[2] + p.z as f64]
        });
        let n = self.pixels.len().max(1) as f64;
        Vec3::new((s[0] / n) as f32, (s[1] / n) as f32, (s[2] / n) as f32)
    }
}

/// Rows `start..end` of a `height`-row image that tile `t` of a tiled
/// render covers (bands of rows, as [`Shard::range`] splits them).
pub fn tile_rows(t: Shard, height: u32) -> (u32, u32) {
    let r = t.range(u64::from(height));
    (r.start as u32, r.end as u32)
}

/// Image files: the `image-io` feature.
#[cfg(feature = "image-io")]
#[cfg_attr(docsrs, doc(cfg(feature = "image-io")))]
impl Image {
    /// Writes linear RGB as a 32-bit float OpenEXR file (temporary name, then rename).
    ///
    /// # Errors
    /// [`Error::Io`] when the folder is missing or the file cannot be written.
    pub fn write_exr(&self, path: impl AsRef<Path>) -> Result<()> {
        self.write_exr_tile(0, self.height, path)
    }

    /// Writes this image as rows `y0..` of a `width x full_height` image: an
    /// OpenEXR file whose data window sits at row `y0` of the display window
    /// (`render --tile`; `assemble` stacks such tiles back).
    ///
    /// # Errors
    /// [`Error::Io`] when the folder is missing or the file cannot be written.
    pub fn write_exr_tile(&self, y0: u32, full_height: u32, path: impl AsRef<Path>) -> Result<()> {
        use exr::prelude::*;
        let w = self.width as usize;
        let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
            let p = self.pixels[y * w + x];
            (p.x, p.y, p.z)
        });
        let attrs = LayerAttributes {
            layer_position: Vec2(0, y0 as i32),
            ..LayerAttributes::default()
        };
        // Tiles are compressed in parallel; in increasing order they are
        // also written in order, so the same image is the same file (with
        // no order given, each tile went out as its worker finished it).
        let encoding = Encoding {
            line_order: LineOrder::Increasing,
            ..Encoding::FAST_LOSSLESS
        };
        let layer = Layer::new((w, self.height as usize), attrs, encoding, channels);
        let mut img = exr::image::Image::from_layer(layer);
        img.attributes.display_window = IntegerBounds::new((0, 0), (w, full_height as usize));
        write_atomic(path.as_ref(), |tmp| {
            img.write().to_file(tmp).map_err(exr_io)
        })
    }

    /// Reads the first RGB(A) layer of an OpenEXR file (alpha dropped),
    /// header first ([`ExrFile`]).
    ///
    /// # Errors
    /// As [`ExrFile::open`] and [`ExrFile::read_pixels`].
    pub fn read_exr(path: impl AsRef<Path>) -> Result<Self> {
        let file = ExrFile::open(path.as_ref())?;
        let (width, height) = file.layer_size;
        let pixels = file.read_pixels()?;
        Ok(Image {
            width: width as u32,
            height: height as u32,
            pixels,
        })
    }

    /// Writes an 8-bit sRGB PNG after `tone` (temporary name, then rename).
    ///
    /// # Errors
    /// [`Error::Io`] when the folder is missing or the file cannot be written.
    pub fn write_png(&self, path: impl AsRef<Path>, tone: ToneMap) -> Result<()> {
        let data: Vec<u8> = self
            .pixels
            .iter()
            .flat_map(|p| [tone.apply(p.x), tone.apply(p.y), tone.apply(p.z)])
            .collect();
        crate::output::write_with(path.as_ref(), |file| {
            let mut enc = png::Encoder::new(file, self.width, self.height);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            enc.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
            let mut w = enc.write_header().map_err(std::io::Error::other)?;
            w.write_image_data(&data).map_err(std::io::Error::other)?;
            w.finish().map_err(std::io::Error::other)
        })
    }
}

/// An OpenEXR file opened past its header: its sizes are known, its pixels
/// not yet read, so a caller can check them (and allocate) first.
///
/// Only a regular file is opened (a FIFO would block, [`crate::input`]);
/// the first layer's size is within [`check_dimensions`] and the file is
/// long enough for the blocks of pixels its header announces: a 1 KB file
/// may claim 30000 x 30000 pixels, which the decoder would allocate.
#[cfg(feature = "image-io")]
#[cfg_attr(docsrs, doc(cfg(feature = "image-io")))]
pub struct ExrFile {
    reader: exr::block::reader::Reader<std::io::BufReader<std::fs::File>>,
    path: std::path::PathBuf,
    /// Layers in the file.
    pub layers: usize,
    /// The whole image's size (the display window), in pixels.
    pub display: (usize, usize),
    /// The first layer's position in the display window.
    pub layer_position: (i32, i32),
    /// The first layer's size, in pixels.
    pub layer_size: (usize, usize),
}

#[cfg(feature = "image-io")]
impl std::fmt::Debug for ExrFile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ExrFile")
            .field("path", &self.path)
            .field("layers", &self.layers)
            .field("display", &self.display)
            .field("layer_position", &self.layer_position)
            .field("layer_size", &self.layer_size)
            .finish_non_exhaustive()
    }
}

#[cfg(feature = "image-io")]
impl ExrFile {
    /// Opens `path` and reads its header.
    ///
    /// # Errors
    /// [`Error::Io`] when the file is missing, not a regular file, not an
    /// EXR image, or shorter than its header announces;
    /// [`Error::InvalidParameter`] for a layer size out of range.
    pub fn open(path: &Path) -> Result<Self> {
        let (file, meta) = crate::input::open_regular_file(path)?;
        let reader = exr::block::read(std::io::BufReader::new(file), false)
            .map_err(|e| io_err(path, exr_io(e)))?;
        let headers = reader.headers();
        let Some(h) = headers.first() else {
            return Err(io_err(path, std::io::Error::other("no layer")));
        };
        let side = |v: usize| u32::try_from(v).unwrap_or(u32::MAX);
        let (w, ht) = (side(h.layer_size.width()), side(h.layer_size.height()));
        // The sides, then the file's length, then memory (which varies from
        // run to run): a given file always meets the same first error.
        check_sides(w, ht)?;
        // Every block of pixels has at least its 8-byte offset-table entry.
        let blocks: u64 = headers.iter().map(|h| h.chunk_count as u64).sum();
        if blocks.saturating_mul(8) > meta.len() {
            return Err(io_err(
                path,
                std::io::Error::other(format!(
                    "its header announces {blocks} blocks of pixels, more than its {} bytes \
                     can hold (truncated or corrupt)",
                    meta.len()
                )),
            ));
        }
        check_dimensions(w, ht)?;
        let d = h.shared_attributes.display_window;
        let pos = h.own_attributes.layer_position;
        Ok(ExrFile {
            layers: headers.len(),
            display: (d.size.width(), d.size.height()),
            layer_position: (pos.x(), pos.y()),
            layer_size: (h.layer_size.width(), h.layer_size.height()),
            path: path.to_path_buf(),
            reader,
        })
    }

    /// Decodes the first layer's RGB pixels (alpha dropped), row-major.
    ///
    /// # Errors
    /// [`Error::Io`] for undecodable pixels or a first valid RGB(A) layer
    /// that is not the first layer; [`Error::OutOfMemory`] when they
    /// cannot be allocated.
    pub fn read_pixels(self) -> Result<Vec<Vec3>> {
        use exr::prelude::{read, ReadChannels, ReadLayers};
        let path = self.path;
        let n = self.layer_size.0 * self.layer_size.1;
        let mut buffer = Vec::new();
        buffer
            .try_reserve_exact(n)
            .map_err(|_| Error::OutOfMemory {
                what: "an EXR image's pixels",
                bytes: n as u64 * 12,
                budget_bytes: available_memory() / 4,
            })?;
        buffer.resize(n, Vec3::ZERO);
        // The decoder asks for its buffer through a closure that cannot
        // fail: hand it the one reserved above.
        let buffer = std::cell::Cell::new(Some(buffer));
        let img = read()
            .no_deep_data()
            .largest_resolution_level()
            .rgba_channels(
                move |res, _| (res.width(), buffer.take().unwrap_or_default()),
                |(w, px): &mut (usize, Vec<Vec3>), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                    if let Some(p) = px.get_mut(pos.y() * *w + pos.x()) {
                        *p = Vec3::new(r, g, b);
                    }
                },
            )
            .first_valid_layer()
            .all_attributes()
            .from_chunks(self.reader)
            .map_err(|e| io_err(&path, exr_io(e)))?;
        let size = img.layer_data.size;
        let (_, pixels) = img.layer_data.channel_data.pixels;
        if (size.width(), size.height()) != self.layer_size || pixels.len() != n {
            return Err(io_err(
                &path,
                std::io::Error::other("its pixels do not match its header"),
            ));
        }
        Ok(pixels)
    }
}
