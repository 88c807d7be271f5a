//! SVG charts with `plotters` (SVG backend only, no system fonts needed):
//! box plots of error sets (seed 004 Fig 8) and x–y line/point plots
//! (trajectories before and after compensation, residual against a variable).
//! The charts of the studies are drawn with them: [`error_along_path`]
//! (compensation), [`effect_plots`] (diagnosis), [`path_plots`] (physics
//! comparison), [`demo_plots`] (the demo).

mod studies;

pub use studies::{
    cv_errors, demo_plots, effect_plots, error_along_path, measured_errors, methods_errors,
    path_plots,
};

use crate::stats::box_stats;
use crate::{Error, Result};
use plotters::prelude::*;
use std::path::Path;

const PALETTE: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

/// The `i`-th colour of the plot palette.
pub fn color(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

fn plot_err(path: &Path) -> impl Fn(String) -> Error + '_ {
    move |message| Error::Plot {
        path: path.to_path_buf(),
        message,
    }
}

/// A tick label without spurious decimals ("10", "0.25", "1e-4").
fn tick(v: f64) -> String {
    if v.abs() < 1e-12 {
        return "0".into();
    }
    if v.abs() >= 1e-3 && v.abs() < 1e6 {
        let s = format!("{v:.6}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("{v:.1e}")
    }
}

/// Caption font size that fits `title` into `width` pixels (sans-serif
/// glyphs average about 0.55 em).
fn caption_size(title: &str, width: u32) -> u32 {
    let chars = title.chars().count().max(1) as f64;
    ((width as f64 - 24.0) / (0.55 * chars)).clamp(11.0, 20.0) as u32
}

/// A padded range covering `values` (never empty).
fn span(values: impl Iterator<Item = f64>, from_zero: bool) -> (f64, f64) {
    let (mut lo, mut hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        (lo, hi) = (0.0, 1.0);
    }
    if from_zero {
        lo = lo.min(0.0);
    }
    let pad = if hi > lo { 0.05 * (hi - lo) } else { 0.5 };
    (
        if from_zero && lo >= 0.0 {
            0.0
        } else {
            lo - pad
        },
        hi + pad,
    )
}

/// Box plots of several groups of values (one box per group): quartiles,
/// median, Tukey whiskers (1.5·IQR) and the outliers as dots.
pub fn box_plot(
    path: &Path,
    title: &str,
    y_label: &str,
    groups: &[(String, Vec<f64>)],
) -> Result<()> {
    let mut svg = String::new();
    draw_box_plot(&mut svg, path, title, y_label, groups)?;
    crate::output::write_text(path, &svg)
}

fn draw_box_plot(
    svg: &mut String,
    path: &Path,
    title: &str,
    y_label: &str,
    groups: &[(String, Vec<f64>)],
) -> Result<()> {
    let err = plot_err(path);
    let width = (160 + 120 * groups.len() as u32).max(480);
    let root = SVGBackend::with_string(svg, (width, 420)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(e.to_string()))?;
    let (_, hi) = span(groups.iter().flat_map(|g| g.1.iter().copied()), true);
    let n = groups.len().max(1);
    let names: Vec<String> = groups.iter().map(|g| g.0.clone()).collect();
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", caption_size(title, width)))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(64)
        .build_cartesian_2d(-0.5f64..(n as f64 - 0.5), 0.0..hi)
        .map_err(|e| err(e.to_string()))?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(n)
        .x_label_formatter(&|x| {
            let i = x.round();
            if (x - i).abs() < 1e-6 && i >= 0.0 {
                names.get(i as usize).cloned().unwrap_or_default()
            } else {
                String::new()
            }
        })
        .y_desc(y_label)
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(|e| err(e.to_string()))?;
    for (i, (_, v)) in groups.iter().enumerate() {
        if v.is_empty() {
            continue;
        }
        let b = box_stats(v);
        let c = color(i);
        let x = i as f64;
        let (l, r) = (x - 0.3, x + 0.3);
        let mut elems: Vec<PathElement<(f64, f64)>> = vec![
            PathElement::new(vec![(x, b.whisker_lo), (x, b.q1)], c.stroke_width(1)),
            PathElement::new(vec![(x, b.q3), (x, b.whisker_hi)], c.stroke_width(1)),
            PathElement::new(
                vec![(x - 0.15, b.whisker_lo), (x + 0.15, b.whisker_lo)],
                c.stroke_width(1),
            ),
            PathElement::new(
                vec![(x - 0.15, b.whisker_hi), (x + 0.15, b.whisker_hi)],
                c.stroke_width(1),
            ),
            PathElement::new(vec![(l, b.median), (r, b.median)], BLACK.stroke_width(2)),
        ];
        elems.push(PathElement::new(
            vec![(l, b.q1), (r, b.q1), (r, b.q3), (l, b.q3), (l, b.q1)],
            c.stroke_width(2),
        ));
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [(l, b.q1), (r, b.q3)],
                c.mix(0.25).filled(),
            )))
            .map_err(|e| err(e.to_string()))?;
        chart.draw_series(elems).map_err(|e| err(e.to_string()))?;
        chart
            .draw_series(
                v.iter()
                    .filter(|y| **y < b.whisker_lo || **y > b.whisker_hi)
                    .map(|&y| Circle::new((x, y), 2, c.filled())),
            )
            .map_err(|e| err(e.to_string()))?;
    }
    root.present().map_err(|e| err(e.to_string()))
}

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mark {
    /// Straight segments joining the points in order.
    Line,
    /// One marker per point, unjoined.
    Points,
}

/// One named series of an x–y plot.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend entry.
    pub name: String,
    /// `(x, y)` points, in drawing order.
    pub points: Vec<(f64, f64)>,
    /// Line or markers.
    pub mark: Mark,
}

impl Series {
    /// A series drawn as a line through `points` in order.
    pub fn line(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Series {
            name: name.into(),
            points,
            mark: Mark::Line,
        }
    }

    /// A series drawn as unjoined markers.
    pub fn points(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Series {
            name: name.into(),
            points,
            mark: Mark::Points,
        }
    }
}

/// Axis labels and the title of an x–y plot.
#[derive(Debug, Clone)]
pub struct Labels<'a> {
    /// Chart title.
    pub title: &'a str,
    /// Label of the x axis, drawn as given (e.g. "X (mm)").
    pub x: &'a str,
    /// Label of the y axis, drawn as given (e.g. "3D position error (mm)").
    pub y: &'a str,
}

/// An x–y plot of several series with a legend below the axes (never over
/// the data); `equal_aspect` gives both axes the same scale (for paths in a
/// plane).
pub fn xy_plot(path: &Path, labels: &Labels, series: &[Series], equal_aspect: bool) -> Result<()> {
    let mut svg = String::new();
    draw_xy_plot(&mut svg, path, labels, series, equal_aspect)?;
    crate::output::write_text(path, &svg)
}

fn draw_xy_plot(
    svg: &mut String,
    path: &Path,
    labels: &Labels,
    series: &[Series],
    equal_aspect: bool,
) -> Result<()> {
    let err = plot_err(path);
    let cols = series.len().clamp(1, 2);
    let rows = series.len().div_ceil(cols);
    let legend_h = 22 * rows as u32 + 12;
    let root = SVGBackend::with_string(svg, (640, 520 + legend_h)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(e.to_string()))?;
    let (root, legend) = root.split_vertically(520);
    let mut xr = span(
        series.iter().flat_map(|s| s.points.iter().map(|p| p.0)),
        false,
    );
    let mut yr = span(
        series.iter().flat_map(|s| s.points.iter().map(|p| p.1)),
        false,
    );
    if equal_aspect {
        let half = 0.5 * (xr.1 - xr.0).max(yr.1 - yr.0);
        let (cx, cy) = (0.5 * (xr.0 + xr.1), 0.5 * (yr.0 + yr.1));
        xr = (cx - half, cx + half);
        yr = (cy - half, cy + half);
    }
    let mut chart = ChartBuilder::on(&root)
        .caption(
            labels.title,
            ("sans-serif", caption_size(labels.title, 640)),
        )
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(72)
        .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)
        .map_err(|e| err(e.to_string()))?;
    chart
        .configure_mesh()
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .x_desc(labels.x)
        .y_desc(labels.y)
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(|e| err(e.to_string()))?;
    for (i, s) in series.iter().enumerate() {
        let c = color(i);
        match s.mark {
            Mark::Line => {
                chart.draw_series(LineSeries::new(s.points.iter().copied(), c.stroke_width(2)))
            }
            Mark::Points => {
                chart.draw_series(s.points.iter().map(|&p| Circle::new(p, 2, c.filled())))
            }
        }
        .map_err(|e| err(e.to_string()))?;
        // the legend: its own strip below the chart, `cols` entries a row
        let (col, row) = ((i % cols) as i32, (i / cols) as i32);
        let (x, y) = (84 + col * 280, 12 + row * 22);
        legend
            .draw(&PathElement::new(
                vec![(x, y), (x + 18, y)],
                c.stroke_width(3),
            ))
            .map_err(|e| err(e.to_string()))?;
        legend
            .draw(&Text::new(
                s.name.clone(),
                (x + 24, y - 8),
                ("sans-serif", 14),
            ))
            .map_err(|e| err(e.to_string()))?;
    }
    root.present().map_err(|e| err(e.to_string()))?;
    legend.present().map_err(|e| err(e.to_string()))
}
