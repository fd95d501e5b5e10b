//! Decoding a glTF image (PNG or JPEG, or WebP for `EXT_texture_webp`,
//! told apart by their first bytes, as a file's declared `mimeType` may be
//! wrong) into 8-bit RGBA texels.
//!
//! Every image's size is read from its header and counted against one
//! budget per scene, [`MAX_TEXELS`], before its pixels are decoded, so a
//! small file that declares a huge image is refused, not allocated.
//! 16-bit channels keep their high byte; grey becomes RGB; a missing alpha
//! is opaque. CMYK JPEGs are refused.

use crate::error::{Error, Result};

/// Texels all the textures of one scene may hold together (2^28: 1 GiB of
/// RGBA).
pub const MAX_TEXELS: u64 = 1 << 28;

/// A decoded image: width, height and its texels in rows from the top.
pub(super) type Decoded = (u32, u32, Vec<[u8; 4]>);

fn bad(what: &str, why: impl std::fmt::Display) -> Error {
    Error::InvalidScene(format!("{what}: {why}"))
}

/// Decodes `bytes`, taking its texels from `budget` (texels left).
pub(super) fn decode(what: &str, bytes: &[u8], budget: &mut u64) -> Result<Decoded> {
    if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
        decode_png(what, bytes, budget)
    } else if bytes.starts_with(&[0xFF, 0xD8, 0xFF]) {
        decode_jpeg(what, bytes, budget)
    } else if bytes.len() >= 12 && &bytes[..4] == b"RIFF" && &bytes[8..12] == b"WEBP" {
        decode_webp(what, bytes, budget)
    } else {
        Err(bad(
            what,
            "not a PNG, JPEG or WebP image (glTF 2.0's formats, and EXT_texture_webp's)",
        ))
    }
}

/// A WebP image, lossless or lossy; an animation's first frame (glTF has
/// no use for the others).
fn decode_webp(what: &str, bytes: &[u8], budget: &mut u64) -> Result<Decoded> {
    let invalid = |e: image_webp::DecodingError| bad(what, format!("invalid WebP: {e}"));
    let mut decoder = image_webp::WebPDecoder::new(std::io::Cursor::new(bytes)).map_err(invalid)?;
    let (w, h) = decoder.dimensions();
    take(what, w, h, budget)?;
    let size = decoder
        .output_buffer_size()
        .ok_or_else(|| bad(what, "a WebP image too large to hold"))?;
    let mut buf = vec![0u8; size];
    decoder.read_image(&mut buf).map_err(invalid)?;
    let texels: Vec<[u8; 4]> = match decoder.has_alpha() {
        true => buf
            .chunks_exact(4)
            .map(|p| [p[0], p[1], p[2], p[3]])
            .collect(),
        false => buf
            .chunks_exact(3)
            .map(|p| [p[0], p[1], p[2], 255])
            .collect(),
    };
    Ok((w, h, texels))
}

/// Takes `w * h` texels from the budget, or says why not.
fn take(what: &str, w: u32, h: u32, budget: &mut u64) -> Result<()> {
    let n = u64::from(w) * u64::from(h);
    if n == 0 {
        return Err(bad(what, "the image has no pixel"));
    }
    if n > *budget {
        return Err(bad(
            what,
            format!(
                "a {w} x {h} image is past the scene's limit of {MAX_TEXELS} texels for all textures"
            ),
        ));
    }
    *budget -= n;
    Ok(())
}

fn decode_png(what: &str, bytes: &[u8], budget: &mut u64) -> Result<Decoded> {
    let mut decoder = png::Decoder::new(bytes);
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = decoder
        .read_info()
        .map_err(|e| bad(what, format!("invalid PNG: {e}")))?;
    let (w, h) = (reader.info().width, reader.info().height);
    take(what, w, h, budget)?;
    let mut buf = vec![0u8; reader.output_buffer_size()];
    let frame = reader
        .next_frame(&mut buf)
        .map_err(|e| bad(what, format!("invalid PNG: {e}")))?;
    let data = &buf[..frame.buffer_size()];
    let texels = match frame.color_type {
        png::ColorType::Grayscale => data.iter().map(|&g| [g, g, g, 255]).collect(),
        png::ColorType::GrayscaleAlpha => data
            .chunks_exact(2)
            .map(|p| [p[0], p[0], p[0], p[1]])
            .collect(),
        png::ColorType::Rgb => data
            .chunks_exact(3)
            .map(|p| [p[0], p[1], p[2], 255])
            .collect(),
        png::ColorType::Rgba => data
            .chunks_exact(4)
            .map(|p| [p[0], p[1], p[2], p[3]])
            .collect(),
        png::ColorType::Indexed => {
            return Err(bad(what, "an indexed PNG that did not expand"));
        }
    };
    Ok((w, h, texels))
}

fn decode_jpeg(what: &str, bytes: &[u8], budget: &mut u64) -> Result<Decoded> {
    let mut decoder = jpeg_decoder::Decoder::new(bytes);
    decoder
        .read_info()
        .map_err(|e| bad(what, format!("invalid JPEG: {e}")))?;
    let Some(info) = decoder.info() else {
        return Err(bad(what, "invalid JPEG: no frame header"));
    };
    let (w, h) = (u32::from(info.width), u32::from(info.height));
    take(what, w, h, budget)?;
    let pixels = decoder
        .decode()
        .map_err(|e| bad(what, format!("invalid JPEG: {e}")))?;
    use jpeg_decoder::PixelFormat;
    let texels: Vec<[u8; 4]> = match info.pixel_format {
        PixelFormat::L8 => pixels.iter().map(|&g| [g, g, g, 255]).collect(),
        // Big-endian 16-bit samples: the first byte is the high one.
        PixelFormat::L16 => pixels
            .chunks_exact(2)
            .map(|p| [p[0], p[0], p[0], 255])
            .collect(),
        PixelFormat::RGB24 => pixels
            .chunks_exact(3)
            .map(|p| [p[0], p[1], p[2], 255])
            .collect(),
        PixelFormat::CMYK32 => {
            return Err(bad(
                what,
                "CMYK JPEG images are not supported (glTF expects RGB)",
            ));
        }
    };
    if texels.len() as u64 != u64::from(w) * u64::from(h) {
        return Err(bad(
            what,
            "the JPEG decoded to fewer pixels than its header says",
        ));
    }
    Ok((w, h, texels))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A PNG of `w x h` pixels of colour type `ct`, 8 bits, from raw rows.
    pub(crate) fn png_bytes(w: u32, h: u32, ct: png::ColorType, data: &[u8]) -> Vec<u8> {
        let mut out = Vec::new();
        let mut enc = png::Encoder::new(&mut out, w, h);
        enc.set_color(ct);
        enc.set_depth(png::BitDepth::Eight);
        enc.write_header().unwrap().write_image_data(data).unwrap();
        out
    }

    #[test]
    fn png_colour_types_become_rgba() {
        let mut budget = MAX_TEXELS;
        let rgb = png_bytes(2, 1, png::ColorType::Rgb, &[1, 2, 3, 4, 5, 6]);
        let (w, h, t) = decode("image 0", &rgb, &mut budget).unwrap();
        assert_eq!((w, h, t), (2, 1, vec![[1, 2, 3, 255], [4, 5, 6, 255]]));
        let ga = png_bytes(1, 1, png::ColorType::GrayscaleAlpha, &[9, 7]);
        assert_eq!(
            decode("image 1", &ga, &mut budget).unwrap().2,
            vec![[9, 9, 9, 7]]
        );
        assert_eq!(budget, MAX_TEXELS - 3);
    }

    #[test]
    fn bad_images_are_refused_by_name() {
        let mut budget = MAX_TEXELS;
        let e = decode("image 4", b"GIF89a....", &mut budget).unwrap_err();
        assert!(e.to_string().contains("image 4") && e.to_string().contains("PNG, JPEG or WebP"));
        let mut cut = png_bytes(4, 4, png::ColorType::Rgba, &[0; 64]);
        cut.truncate(cut.len() - 20);
        assert!(decode("image 5", &cut, &mut budget).is_err());
        assert!(decode("image 6", &[0xFF, 0xD8, 0xFF, 0xE0, 0, 0], &mut budget).is_err());
    }

    #[test]
    fn the_budget_is_taken_from_the_header_before_decoding() {
        let bytes = png_bytes(3, 2, png::ColorType::Rgb, &[0; 18]);
        let mut budget = 5;
        let e = decode("image 7", &bytes, &mut budget).unwrap_err();
        assert!(
            e.to_string().contains("3 x 2") && e.to_string().contains("limit"),
            "{e}"
        );
        assert_eq!(budget, 5);
    }
}
