//! Line plots of the experiments, written as SVG and PNG by `plotters`.
//!
//! Text is drawn with DejaVu Sans, shipped in `assets/fonts/` (its licence
//! beside it) and compiled into the library: `plotters`' `ab_glyph` backend
//! has no access to system fonts, and machines that run the bench may have none.

use crate::error::{Error, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;
use std::sync::OnceLock;

static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// Size of every plot in pixels (PNG) or SVG user units.
pub const PLOT_SIZE: (u32, u32) = (960, 640);

/// A curve of a plot.
#[derive(Clone, Debug)]
pub struct Series {
    /// Its legend.
    pub name: String,
    /// `(x, y)` points in drawing order; non-finite points are skipped.
    pub points: Vec<(f64, f64)>,
}

/// A horizontal reference line.
#[derive(Clone, Debug)]
pub struct RefLine {
    /// Its legend.
    pub name: String,
    /// Its height.
    pub y: f64,
}

/// One figure.
#[derive(Clone, Debug, Default)]
pub struct Plot {
    /// Title above the chart.
    pub title: String,
    /// Label of the x axis, with its unit.
    pub x_label: String,
    /// Label of the y axis, with its unit.
    pub y_label: String,
    /// Curves.
    pub series: Vec<Series>,
    /// Reference lines, dashed.
    pub lines: Vec<RefLine>,
    /// A log10 y axis (for values spanning decades); points and lines at
    /// y <= 0 are left out.
    pub log_y: bool,
}

/// `plot` with its y values mapped to log10 when it asks for a log axis.
fn y_mapped(plot: &Plot) -> Plot {
    if !plot.log_y {
        return plot.clone();
    }
    let f = |y: f64| if y > 0.0 { y.log10() } else { f64::NAN };
    Plot {
        series: plot
            .series
            .iter()
            .map(|s| Series {
                name: s.name.clone(),
                points: s.points.iter().map(|&(x, y)| (x, f(y))).collect(),
            })
            .collect(),
        lines: plot
            .lines
            .iter()
            .map(|l| RefLine {
                name: l.name.clone(),
                y: f(l.y),
            })
            .collect(),
        ..plot.clone()
    }
}

/// Registers the bundled DejaVu Sans as "sans-serif" (once): plotters'
/// `ab_glyph` backend sees no system fonts.
///
/// # Errors
/// [`Error::InvalidParameter`] if the bundled font does not parse.
pub fn register_font() -> Result<()> {
    static DONE: OnceLock<bool> = OnceLock::new();
    let ok = *DONE.get_or_init(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, FONT).is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err(Error::param(
            "font",
            "the bundled DejaVu Sans did not parse",
        ))
    }
}

const COLORS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
];

fn bounds(plot: &Plot) -> ((f64, f64), (f64, f64)) {
    let mut x = (f64::INFINITY, f64::NEG_INFINITY);
    let mut y = (f64::INFINITY, f64::NEG_INFINITY);
    for s in &plot.series {
        for &(a, b) in s
            .points
            .iter()
            .filter(|p| p.0.is_finite() && p.1.is_finite())
        {
            x = (x.0.min(a), x.1.max(a));
            y = (y.0.min(b), y.1.max(b));
        }
    }
    for l in plot.lines.iter().filter(|l| l.y.is_finite()) {
        y = (y.0.min(l.y), y.1.max(l.y));
    }
    if !x.0.is_finite() {
        x = (0.0, 1.0);
    }
    if !y.0.is_finite() {
        y = (0.0, 1.0);
    }
    // every figure's quantity is >= 0: start a linear y axis at 0, leave
    // headroom; a log axis starts just under the smallest value
    let y0 = if plot.log_y {
        y.0 - 0.05 * (y.1 - y.0).max(0.5)
    } else {
        y.0.min(0.0)
    };
    let mut y1 = y.1 + 0.08 * (y.1 - y0);
    if y1 <= y0 {
        y1 = y0 + 1.0;
    }
    if x.1 <= x.0 {
        x = (x.0 - 0.5, x.1 + 0.5);
    }
    (x, (y0, y1))
}

/// A tick label: short, scientific only for very small or large values.
fn tick(v: &f64) -> String {
    if *v != 0.0 && (v.abs() < 1e-2 || v.abs() >= 1e5) {
        format!("{v:.1e}")
    } else {
        format!("{v:.3}")
            .trim_end_matches('0')
            .trim_end_matches('.')
            .to_string()
    }
}

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    plot: &Plot,
) -> std::result::Result<(), String> {
    let e = |e: &dyn std::fmt::Debug| format!("{e:?}");
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let plot = &y_mapped(plot);
    let ((x0, x1), (y0, y1)) = bounds(plot);
    let log_tick = |v: &f64| tick(&10f64.powf(*v));
    let y_tick: &dyn Fn(&f64) -> String = if plot.log_y { &log_tick } else { &tick };
    let mut chart = ChartBuilder::on(&root)
        .caption(&plot.title, ("sans-serif", 22))
        .margin(16)
        .margin_right(40)
        .x_label_area_size(48)
        .y_label_area_size(84)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(|x| e(&x))?;
    chart
        .configure_mesh()
        .x_desc(&plot.x_label)
        .y_desc(&plot.y_label)
        .label_style(("sans-serif", 15))
        .axis_desc_style(("sans-serif", 17))
        .x_label_formatter(&tick)
        .y_label_formatter(y_tick)
        .draw()
        .map_err(|x| e(&x))?;
    for (i, s) in plot.series.iter().enumerate() {
        let c = COLORS[i % COLORS.len()];
        let pts: Vec<(f64, f64)> = s
            .points
            .iter()
            .copied()
            .filter(|p| p.0.is_finite() && p.1.is_finite())
            .collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), c.stroke_width(2)))
            .map_err(|x| e(&x))?
            .label(&s.name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2)));
        if pts.len() <= 30 {
            chart
                .draw_series(pts.iter().map(|&p| Circle::new(p, 3, c.filled())))
                .map_err(|x| e(&x))?;
        }
    }
    for l in plot.lines.iter().filter(|l| l.y.is_finite()) {
        let c = BLACK;
        // a dashed line: short segments along x
        let steps = 60;
        let segs = (0..steps).step_by(2).map(move |k| {
            let a = x0 + (x1 - x0) * k as f64 / steps as f64;
            let b = x0 + (x1 - x0) * (k + 1) as f64 / steps as f64;
            PathElement::new(vec![(a, l.y), (b, l.y)], c.stroke_width(2))
        });
        chart
            .draw_series(segs)
            .map_err(|x| e(&x))?
            .label(&l.name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 8, y)], c.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 15))
        .position(legend_corner(plot, (x0, x1), (y0, y1)))
        .draw()
        .map_err(|x| e(&x))?;
    root.present().map_err(|x| e(&x))?;
    Ok(())
}

/// The corner whose box (the outer 45 % of x, 30 % of y) covers the fewest
/// data points, so the legend hides as little as possible; a reference line
/// crossing a box counts as a whole series.
fn legend_corner(plot: &Plot, x: (f64, f64), y: (f64, f64)) -> SeriesLabelPosition {
    let fx = |v: f64| (v - x.0) / (x.1 - x.0);
    let fy = |v: f64| (v - y.0) / (y.1 - y.0);
    let count = |right: bool, top: bool| {
        let in_x = |v: f64| if right { fx(v) > 0.55 } else { fx(v) < 0.45 };
        let in_y = |v: f64| if top { fy(v) > 0.7 } else { fy(v) < 0.3 };
        let points = plot
            .series
            .iter()
            .flat_map(|s| &s.points)
            .filter(|p| in_x(p.0) && in_y(p.1))
            .count();
        let per_line = plot
            .series
            .iter()
            .map(|s| s.points.len())
            .max()
            .unwrap_or(1);
        points + plot.lines.iter().filter(|l| in_y(l.y)).count() * per_line
    };
    [
        (SeriesLabelPosition::UpperRight, true, true),
        (SeriesLabelPosition::UpperLeft, false, true),
        (SeriesLabelPosition::LowerRight, true, false),
        (SeriesLabelPosition::LowerLeft, false, false),
    ]
    .into_iter()
    .min_by_key(|(_, right, top)| count(*right, *top))
    .map_or(SeriesLabelPosition::UpperRight, |c| c.0)
}

/// Writes `plot` to `stem.svg` and `stem.png`.
///
/// # Errors
/// [`Error::Io`] when a file cannot be written.
pub fn write_plot(stem: &Path, plot: &Plot) -> Result<()> {
    register_font()?;
    let svg = stem.with_extension("svg");
    // Hook (issue 12): each figure goes to an exclusive temporary file, renamed when whole.
    crate::output::write_via_path(&svg, |tmp| {
        draw(SVGBackend::new(tmp, PLOT_SIZE).into_drawing_area(), plot)
            .map_err(|e| std::io::Error::other(e.to_string()))
    })?;
    let png = stem.with_extension("png");
    crate::output::write_via_path(&png, |tmp| {
        draw(BitMapBackend::new(tmp, PLOT_SIZE).into_drawing_area(), plot)
            .map_err(|e| std::io::Error::other(e.to_string()))
    })?;
    Ok(())
}
