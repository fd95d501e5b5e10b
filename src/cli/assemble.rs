//! `render --tile I/N` writes rows of an image as an OpenEXR tile (its data
//! window placed in the whole image's display window); `adaptive-pm assemble
//! TILE.exr... --out IMG.exr` stacks the tiles back into the whole image,
//! refusing tiles of different images, overlaps and gaps.

use adaptive_pm::engine::Shard;
use adaptive_pm::photon_file::AtomicOutput;
use adaptive_pm::render::Image;
use anyhow::{bail, Context};
use exr::prelude::*;
use glam::Vec3;
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

/// One tile: its display size, its first row and its pixels.
struct Tile {
    display: (usize, usize),
    y0: usize,
    image: Image,
}

fn read_tile(path: &Path) -> anyhow::Result<Tile> {
    let img = read_first_rgba_layer_from_file(
        path,
        |res, _| (res.width(), vec![Vec3::ZERO; res.width() * res.height()]),
        |(w, px): &mut (usize, Vec<Vec3>), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            px[pos.y() * *w + pos.x()] = Vec3::new(r, g, b);
        },
    )
    .with_context(|| format!("reading tile {}", path.display()))?;
    let d = img.attributes.display_window;
    let pos = img.layer_data.attributes.layer_position;
    let size = img.layer_data.size;
    if d.position != Vec2(0, 0) || pos.x() != 0 || size.width() != d.size.width() {
        bail!(
            "{}: not a tile of whole rows (render --tile)",
            path.display()
        );
    }
    if pos.y() < 0 || pos.y() as usize + size.height() > d.size.height() {
        bail!("{}: its rows lie outside its image", path.display());
    }
    Ok(Tile {
        display: (d.size.width(), d.size.height()),
        y0: pos.y() as usize,
        image: Image {
            width: size.width() as u32,
            height: size.height() as u32,
            pixels: img.layer_data.channel_data.pixels.1,
        },
    })
}

pub fn run(args: AssembleArgs) -> anyhow::Result<()> {
    let mut tiles = args
        .tiles
        .iter()
        .map(|p| read_tile(p).map(|t| (p, t)))
        .collect::<anyhow::Result<Vec<_>>>()?;
    tiles.sort_by_key(|(_, t)| t.y0);
    let (w, h) = tiles[0].1.display;
    let mut next = 0usize;
    for (p, t) in &tiles {
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
        next = t.y0 + t.image.height as usize;
    }
    if next != h {
        bail!("rows {next}..{h} are missing (no tile covers them)");
    }
    let mut image = Image::new(w as u32, h as u32)?;
    for (_, t) in &tiles {
        let start = t.y0 * w;
        image.pixels[start..start + t.image.pixels.len()].copy_from_slice(&t.image.pixels);
    }
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
