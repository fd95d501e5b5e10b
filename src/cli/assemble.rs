//! `render --tile I/N` writes rows of an image as an OpenEXR tile (its data
//! window placed in the whole image's display window); `adaptive-pm assemble
//! TILE.exr... --out IMG.exr` stacks the tiles back into the whole image,
//! refusing tiles of different images, overlaps and gaps.

use adaptive_pm::output::{check_target, refuse_overwrite};
use adaptive_pm::render::image::check_dimensions;
use adaptive_pm::render::{ExrFile, Image, MAX_DIMENSION};
use anyhow::{bail, Context};
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

/// Opens a tile (header only: [`ExrFile`]) and checks where its rows sit,
/// before any pixel is allocated.
fn open_tile(path: &Path) -> anyhow::Result<(ExrFile, Placement)> {
    let exr = ExrFile::open(path).with_context(|| format!("reading tile {}", path.display()))?;
    let placement = placement_of(path, &exr)?;
    Ok((exr, placement))
}

/// Checks a tile's header: one layer of whole rows of an image within
/// [`MAX_DIMENSION`] a side.
fn placement_of(path: &Path, exr: &ExrFile) -> anyhow::Result<Placement> {
    if exr.layers != 1 {
        bail!("{}: {} layers; a tile has one", path.display(), exr.layers);
    }
    let (w, ht) = exr.display;
    let max = MAX_DIMENSION as usize;
    if w == 0 || ht == 0 || w > max || ht > max {
        bail!(
            "{}: a tile of a {w}x{ht} image; images are at most {max}x{max}",
            path.display()
        );
    }
    let (x, y) = exr.layer_position;
    if x != 0 || exr.layer_size.0 != w {
        bail!(
            "{}: not a tile of whole rows (render --tile)",
            path.display()
        );
    }
    if y < 0 || y as usize + exr.layer_size.1 > ht {
        bail!("{}: its rows lie outside its image", path.display());
    }
    Ok(Placement {
        display: (w, ht),
        y0: y as usize,
        rows: exr.layer_size.1,
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
        let rows = reader
            .read_pixels()
            .with_context(|| format!("reading tile {}", p.display()))?;
        pixels[start..start + w * at.rows].copy_from_slice(&rows);
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
