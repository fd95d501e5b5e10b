//! `render --tile I/N` writes rows of an image as an OpenEXR tile (its data
//! window placed in the whole image's display window); `adaptive-pm assemble
//! TILE.exr... --out IMG.exr` stacks the tiles back into the whole image,
//! refusing tiles of different images, overlaps and gaps.

use adaptive_pm::engine::Shard;
use adaptive_pm::output::{check_target, refuse_overwrite};
use adaptive_pm::photon_file::AtomicOutput;
use adaptive_pm::render::image::check_dimensions;
use adaptive_pm::render::{Image, MAX_DIMENSION};
use anyhow::{bail, Context};
use exr::prelude::*;
use glam::Vec3;
use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};

/// Arguments of `assemble`.
#[derive(clap::Args, Debug)]
pub struct AssembleArgs {
    /// The tiles (`render --tile I/N --out TILE.exr`), in any order.
    #[arg(required = true)]
    pub tiles: Vec<PathBuf>,
    /// The whole image (OpenEXR).
    #[arg(long)]
    pub out: PathBuf,
}

/// Rows `start..end` of a `height`-row image that tile `t` renders.
pub fn tile_rows(t: Shard, height: u32) -> (u32, u32) {
    let r = t.range(height as u64);
    (r.start as u32, r.end as u32)
}

/// Writes `image` (rows `y0..` of a `width x full_height` image) as an EXR
/// whose data window sits at row `y0` of the display window.
pub fn write_tile(image: &Image, y0: u32, full_height: u32, path: &Path) -> anyhow::Result<()> {
    let w = image.width as usize;
    let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
        let p = image.pixels[y * w + x];
        (p.x, p.y, p.z)
    });
    let attrs = LayerAttributes {
        layer_position: Vec2(0, y0 as i32),
        ..LayerAttributes::default()
    };
    let layer = Layer::new(
        (w, image.height as usize),
        attrs,
        Encoding::FAST_LOSSLESS,
        channels,
    );
    let mut img = exr::image::Image::from_layer(layer);
    img.attributes.display_window =
        IntegerBounds::new((0, 0), (image.width as usize, full_height as usize));
    let mut out = AtomicOutput::create(path)?;
    let file = std::io::BufWriter::new(out.file());
    img.write()
        .to_buffered(file)
        .with_context(|| format!("writing {}", path.display()))?;
    out.finish()?;
    Ok(())
}

/// Where a tile's rows sit in its image, from its header alone.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Placement {
    /// The whole image's width and height.
    display: (usize, usize),
    /// The tile's first row.
    y0: usize,
    /// The tile's rows (each `display.0` pixels wide).
    rows: usize,
}

/// An EXR file opened past its header, its pixels not yet read.
type TileReader = exr::block::reader::Reader<BufReader<File>>;

/// Opens a tile (a regular file only: a FIFO would block) and reads its
/// header, checking where its rows sit before any pixel is allocated.
fn open_tile(path: &Path) -> anyhow::Result<(TileReader, Placement)> {
    let (file, meta) = adaptive_pm::input::open_regular_file(path)?;
    let reader = exr::block::read(BufReader::new(file), false)
        .with_context(|| format!("reading tile {}", path.display()))?;
    let placement = placement_of(path, reader.headers(), meta.len())?;
    Ok((reader, placement))
}

/// Checks a tile's header: one layer of whole rows of an image within
/// [`MAX_DIMENSION`] a side, and a file long enough for the blocks of pixels
/// its header announces (a 1 KB file claiming 30000x30000 pixels made the
/// decoder allocate 10.8 GB).
fn placement_of(
    path: &Path,
    headers: &[exr::meta::header::Header],
    len: u64,
) -> anyhow::Result<Placement> {
    let [h] = headers else {
        bail!(
            "{}: {} layers; a tile has one",
            path.display(),
            headers.len()
        );
    };
    let d = h.shared_attributes.display_window;
    let (w, ht) = (d.size.width(), d.size.height());
    let max = MAX_DIMENSION as usize;
    if w == 0 || ht == 0 || w > max || ht > max {
        bail!(
            "{}: a tile of a {w}x{ht} image; images are at most {max}x{max}",
            path.display()
        );
    }
    let pos = h.own_attributes.layer_position;
    let size = h.layer_size;
    if d.position != Vec2(0, 0) || pos.x() != 0 || size.width() != w {
        bail!(
            "{}: not a tile of whole rows (render --tile)",
            path.display()
        );
    }
    if pos.y() < 0 || pos.y() as usize + size.height() > ht {
        bail!("{}: its rows lie outside its image", path.display());
    }
    // Every block of pixels has at least its 8-byte entry in the offset table.
    if (h.chunk_count as u64).saturating_mul(8) > len {
        bail!(
            "{}: its header announces {} blocks of pixels, more than its {len} bytes can hold \
             (truncated or corrupt)",
            path.display(),
            h.chunk_count
        );
    }
    Ok(Placement {
        display: (w, ht),
        y0: pos.y() as usize,
        rows: size.height(),
    })
}

/// A pixel buffer of `n` black pixels, reserved fallibly.
fn black_pixels(n: usize) -> anyhow::Result<Vec<Vec3>> {
    let mut px = Vec::new();
    px.try_reserve_exact(n)
        .map_err(|_| anyhow::anyhow!("not enough memory for {n} pixels"))?;
    px.resize(n, Vec3::ZERO);
    Ok(px)
}

/// Decodes the pixels of a tile checked by [`open_tile`].
fn read_pixels(reader: TileReader, path: &Path, at: Placement) -> anyhow::Result<Vec<Vec3>> {
    let n = at.display.0 * at.rows;
    // The decoder asks for its buffer through a closure that cannot fail:
    // hand it the one reserved above.
    let buffer = std::cell::Cell::new(Some(black_pixels(n)?));
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
        .from_chunks(reader)
        .with_context(|| format!("reading tile {}", path.display()))?;
    let (_, pixels) = img.layer_data.channel_data.pixels;
    anyhow::ensure!(
        pixels.len() == n,
        "{}: its pixels do not match its header",
        path.display()
    );
    Ok(pixels)
}

/// Checks that the tiles (sorted by first row) are of one image and cover
/// its rows once; returns its size.
fn check_layout(tiles: &[(&PathBuf, Placement)]) -> anyhow::Result<(usize, usize)> {
    let (w, h) = tiles[0].1.display;
    let mut next = 0usize;
    for (p, t) in tiles {
        if t.display != (w, h) {
            bail!(
                "{} is a tile of a {}x{} image, not {w}x{h}",
                p.display(),
                t.display.0,
                t.display.1
            );
        }
        if t.y0 < next {
            bail!("{} overlaps another tile at row {}", p.display(), t.y0);
        }
        if t.y0 > next {
            bail!("rows {next}..{} are missing (no tile covers them)", t.y0);
        }
        next = t.y0 + t.rows;
    }
    if next != h {
        bail!("rows {next}..{h} are missing (no tile covers them)");
    }
    Ok((w, h))
}

pub fn run(args: AssembleArgs) -> anyhow::Result<()> {
    let inputs: Vec<&Path> = args.tiles.iter().map(PathBuf::as_path).collect();
    refuse_overwrite(&args.out, &inputs).context("--out")?;
    check_target(&args.out).context("--out")?;
    // First every header (one file open at a time): the layout and the
    // whole image's size are checked before any pixel is allocated.
    let mut tiles = Vec::with_capacity(args.tiles.len());
    for p in &args.tiles {
        tiles.push((p, open_tile(p)?.1));
    }
    tiles.sort_by_key(|(_, t)| t.y0);
    let (w, h) = check_layout(&tiles)?;
    check_dimensions(w as u32, h as u32)?;
    let mut pixels = black_pixels(w * h)?;
    for (p, at) in &tiles {
        let (reader, again) = open_tile(p)?;
        if again != *at {
            bail!("{} changed while the tiles were assembled", p.display());
        }
        let start = at.y0 * w;
        pixels[start..start + w * at.rows].copy_from_slice(&read_pixels(reader, p, *at)?);
    }
    let image = Image {
        width: w as u32,
        height: h as u32,
        pixels,
    };
    image.write_exr(&args.out)?;
    println!(
        "assembled {} tiles into {}x{}: wrote {}",
        tiles.len(),
        w,
        h,
        args.out.display()
    );
    Ok(())
}
