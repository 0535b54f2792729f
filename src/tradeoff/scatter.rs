//! A predicted-against-measured scatter (the measuring planner's held-out check): one
//! marker per point, coloured by series (a method), the diagonal y = x, a ±`band` corridor,
//! and a legend; SVG and PNG through the same drawing.

use std::path::Path;

use super::plot::{colour, draw_marker, font, register_font, write_bitmap_png, Figure};
use crate::error::{Error, Result};

const W: u32 = 980;
const H: u32 = 760;
const LEGEND: u32 = 260;

/// Writes `stem`.svg and `stem`.png: `points` are (x, y, series); both axes span `range`.
pub fn scatter(stem: &Path, points: &[(f64, f64, String)], range: (f64, f64), band: f64, title: &str, x: &str, y: &str) -> Result<Figure> {
    use plotters::prelude::*;
    register_font()?;
    let mut series: Vec<&str> = points.iter().map(|p| p.2.as_str()).collect();
    series.sort();
    series.dedup();
    let fig = Figure { svg: stem.with_extension("svg"), png: stem.with_extension("png") };
    let draw = |root: &DrawingArea<_, plotters::coord::Shift>| -> std::result::Result<(), String> {
        draw_scatter(root, points, &series, range, band, title, (x, y))
    };
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (W + LEGEND, H)).into_drawing_area();
        draw(&root)
            .and_then(|()| root.present().map_err(|e| e.to_string()))
            .map_err(|e| Error::Image(format!("{}: {e}", fig.svg.display())))?;
    }
    crate::output::write_file(&fig.svg, svg.as_bytes())?;
    write_bitmap_png(&fig.png, (W + LEGEND, H), None, |root| draw_scatter(root, points, &series, range, band, title, (x, y)))?;
    Ok(fig)
}

fn draw_scatter<DB: plotters::prelude::DrawingBackend>(
    root: &plotters::drawing::DrawingArea<DB, plotters::coord::Shift>,
    points: &[(f64, f64, String)],
    series: &[&str],
    (lo, hi): (f64, f64),
    band: f64,
    title: &str,
    (xl, yl): (&str, &str),
) -> std::result::Result<(), String> {
    use plotters::prelude::*;
    let e = |e: &dyn std::fmt::Display| e.to_string();
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let (plot, legend) = root.split_horizontally(W);
    let mut chart = ChartBuilder::on(&plot)
        .caption(title, font(20.0))
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(60)
        .build_cartesian_2d(lo..hi, lo..hi)
        .map_err(|x| e(&x))?;
    chart.configure_mesh().x_desc(xl).y_desc(yl).label_style(font(14.0)).axis_desc_style(font(16.0)).draw().map_err(|x| e(&x))?;
    let grey = RGBColor(150, 150, 150);
    chart.draw_series(LineSeries::new(vec![(lo, lo), (hi, hi)], grey.stroke_width(2))).map_err(|x| e(&x))?;
    for d in [-band, band] {
        chart.draw_series(LineSeries::new(vec![(lo, lo + d), (hi, hi + d)], grey.stroke_width(1))).map_err(|x| e(&x))?;
    }
    // backend_coord is in the whole drawing's pixels: `plot` starts at its origin.
    let area = &plot;
    for (px, py, s) in points {
        let k = series.iter().position(|n| n == s).unwrap_or(0);
        let at = chart.backend_coord(&(px.clamp(lo, hi), py.clamp(lo, hi)));
        draw_marker(area, k, at, 4)?;
    }
    for (k, s) in series.iter().enumerate() {
        let y = 40 + 26 * k as i32;
        draw_marker(&legend, k, (16, y), 5)?;
        legend.draw(&Text::new(s.to_string(), (30, y - 8), font(15.0).color(&colour(k)))).map_err(|x| e(&x))?;
    }
    Ok(())
}
