//! The trade-off figure through plotters: panels of the metric against GPU time, one curve
//! and marker per method, the Pareto front, labelled points and a legend; written as SVG
//! and PNG (the bundled font, so no system font is needed).

use std::path::{Path, PathBuf};

use super::labels::{knob_names, knob_values, place_labels, PixelRect};
use super::rows::{pareto_front, Metric, Panel};
use super::ticks::{fmt_num, log_ticks, minor_log_ticks};
use crate::error::{Error, Result};

/// The files [`plot`] wrote.
#[derive(Clone, Debug)]
pub struct Figure {
    pub svg: PathBuf,
    pub png: PathBuf,
}

/// The bundled font as plotters' `sans-serif` (`output::register_font`).
pub(super) use crate::output::register_font;

/// Renders `draw` into an RGB bitmap of `size` through plotters' bitmap backend and writes
/// it as a PNG; `base` is the bitmap before drawing (white where `None`).
pub(crate) fn write_bitmap_png(
    path: &Path,
    (w, h): (u32, u32),
    base: Option<Vec<u8>>,
    draw: impl FnOnce(
        &plotters::drawing::DrawingArea<plotters::prelude::BitMapBackend, plotters::coord::Shift>,
    ) -> std::result::Result<(), String>,
) -> Result<()> {
    use plotters::prelude::*;
    register_font()?;
    let err = |e: &dyn std::fmt::Display| Error::Image(format!("{}: {e}", path.display()));
    let mut buf = base.unwrap_or_else(|| vec![255u8; (w * h * 3) as usize]);
    if buf.len() != (w * h * 3) as usize {
        return Err(err(&format!("bitmap of {} bytes for {w}x{h} RGB", buf.len())));
    }
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        draw(&root).map_err(|e| err(&e))?;
        root.present().map_err(|e| err(&e))?;
    }
    let mut png = Vec::new();
    image::ImageEncoder::write_image(image::codecs::png::PngEncoder::new(&mut png), &buf, w, h, image::ExtendedColorType::Rgb8)
        .map_err(|e| err(&e))?;
    crate::output::write_file(path, &png)
}

const PANEL_W: u32 = 860;
const PANEL_H: u32 = 620;
const LEGEND_W: u32 = 300;
const TITLE_H: u32 = 48;

/// The trade-off figure, `stem`.svg and `stem`.png (the same drawing through plotters' SVG
/// and bitmap backends): one panel per entry of `panels` (two columns), each the metric
/// against frame GPU time on a log axis, both ranges from the data with a margin; one
/// curve per method (its points in time order, or in the sweep's order where its rows vary
/// one knob; a colour and marker of its own, named in the legend beside the panels), each
/// point labelled with its knob values (a method's only point with the method's name) where
/// there is room (Pareto points first; far labels get a leader line), the Pareto front as a
/// step line through ringed points.
pub fn plot(stem: &Path, panels: &[Panel], metric: Metric, title: &str) -> Result<Figure> {
    use plotters::prelude::*;
    if panels.is_empty() {
        return Err(Error::invalid("plot", "no panels"));
    }
    register_font()?;
    let cols = panels.len().min(2) as u32;
    let grid = (panels.len() as u32).div_ceil(cols);
    let size = (cols * PANEL_W + LEGEND_W, TITLE_H + grid * PANEL_H);
    let fig = Figure { svg: stem.with_extension("svg"), png: stem.with_extension("png") };
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        draw_figure(&root, panels, metric, title, (grid as usize, cols as usize))
            .and_then(|()| root.present().map_err(|e| e.to_string()))
            .map_err(|e| Error::Image(format!("{}: {e}", fig.svg.display())))?;
    }
    crate::output::write_file(&fig.svg, svg.as_bytes())?;
    write_bitmap_png(&fig.png, size, None, |root| draw_figure(root, panels, metric, title, (grid as usize, cols as usize)))?;
    Ok(fig)
}

/// Colours (tab10, the grey swapped for a dark teal) and marker shapes: method k gets
/// colour k mod 10 and marker k mod 6, distinct for 30 methods.
const COLOURS: [(u8, u8, u8); 10] = [
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (0, 105, 105),
    (188, 189, 34),
    (23, 190, 207),
];

pub(super) fn colour(k: usize) -> plotters::style::RGBColor {
    let (r, g, b) = COLOURS[k % COLOURS.len()];
    plotters::style::RGBColor(r, g, b)
}

pub(super) fn font(size: f64) -> plotters::style::FontDesc<'static> {
    plotters::style::FontDesc::new(plotters::style::FontFamily::SansSerif, size, plotters::style::FontStyle::Normal)
}

pub(super) fn draw_marker<DB: plotters::prelude::DrawingBackend>(
    area: &plotters::drawing::DrawingArea<DB, plotters::coord::Shift>,
    k: usize,
    (x, y): (i32, i32),
    r: i32,
) -> std::result::Result<(), String> {
    use plotters::prelude::*;
    let style = colour(k).filled();
    match k % 6 {
        0 => area.draw(&Circle::new((x, y), r, style)),
        1 => area.draw(&Rectangle::new([(x - r + 1, y - r + 1), (x + r - 1, y + r - 1)], style)),
        2 => area.draw(&Polygon::new(vec![(x, y - r - 1), (x + r, y + r - 1), (x - r, y + r - 1)], style)),
        3 => area.draw(&Polygon::new(vec![(x, y - r - 1), (x + r + 1, y), (x, y + r + 1), (x - r - 1, y)], style)),
        4 => area.draw(&Polygon::new(vec![(x, y + r + 1), (x + r, y - r + 1), (x - r, y - r + 1)], style)),
        _ => area
            .draw(&PathElement::new(vec![(x - r, y - r), (x + r, y + r)], colour(k).stroke_width(3)))
            .and_then(|()| area.draw(&PathElement::new(vec![(x - r, y + r), (x + r, y - r)], colour(k).stroke_width(3)))),
    }
    .map_err(|e| e.to_string())
}

/// What drawing one panel left unsaid, for the legend's notes.
#[derive(Default)]
struct Omitted {
    labels: usize,
    points: usize,
}

fn draw_figure<DB: plotters::prelude::DrawingBackend>(
    root: &plotters::drawing::DrawingArea<DB, plotters::coord::Shift>,
    panels: &[Panel],
    metric: Metric,
    title: &str,
    (grid, cols): (usize, usize),
) -> std::result::Result<(), String> {
    use plotters::prelude::*;
    let e = |e: &dyn std::fmt::Display| e.to_string();
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let (title_area, body) = root.split_vertically(TITLE_H);
    title_area.draw_text(title, &font(20.0).color(&BLACK), (16, 14)).map_err(|x| e(&x))?;
    let (plots, legend) = body.split_horizontally(body.dim_in_pixel().0 - LEGEND_W);
    let mut methods: Vec<&str> = Vec::new();
    for r in panels.iter().flat_map(|p| &p.rows) {
        if !methods.contains(&r.method.as_str()) {
            methods.push(&r.method);
        }
    }
    let mut omitted = Omitted::default();
    for (panel, area) in panels.iter().zip(plots.split_evenly((grid, cols))) {
        draw_panel(root, &area, panel, metric, &methods, &mut omitted)?;
    }
    // Every set of knob names the labels use (one per sweep with `--each`).
    let mut sets: Vec<String> = Vec::new();
    for k in panels.iter().flat_map(|p| &p.rows).filter_map(|r| knob_names(&r.knobs)) {
        if !sets.contains(&k) {
            sets.push(k);
        }
    }
    let knobs = (!sets.is_empty()).then(|| sets.join("; "));
    draw_legend(&legend, &methods, metric, knobs.as_deref(), &omitted)
}

fn draw_panel<DB: plotters::prelude::DrawingBackend>(
    root: &plotters::drawing::DrawingArea<DB, plotters::coord::Shift>,
    area: &plotters::drawing::DrawingArea<DB, plotters::coord::Shift>,
    panel: &Panel,
    metric: Metric,
    methods: &[&str],
    omitted: &mut Omitted,
) -> std::result::Result<(), String> {
    use plotters::prelude::*;
    let e = |e: &dyn std::fmt::Display| e.to_string();
    // (method index, ms, metric, knob labels): rows of one method that measured the same
    // (the ray tracers ignore map knobs) are one point.
    let mut pts: Vec<(usize, f64, f64, Vec<String>)> = Vec::new();
    for r in &panel.rows {
        let (t, v) = (r.frame_ms, metric.value(&r.errors));
        if !(t > 0.0 && t.is_finite() && v.is_finite()) {
            omitted.points += 1;
            continue;
        }
        let k = methods.iter().position(|m| *m == r.method).unwrap_or(0);
        match pts.iter_mut().find(|p| p.0 == k && p.1 == t && p.2 == v) {
            Some(p) => p.3.push(knob_values(&r.knobs)),
            None => pts.push((k, t, v, vec![knob_values(&r.knobs)])),
        }
    }
    let (tmin, tmax) = pts.iter().fold((f64::INFINITY, 0f64), |(a, b), p| (a.min(p.1), b.max(p.1)));
    let (vmin, vmax) = pts.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.2), b.max(p.2)));
    let (t_range, v_range) = if pts.is_empty() {
        (0.1..10.0, if metric.higher_is_better() { 0.0..50.0 } else { 0.0..1.0 })
    } else {
        let pad = ((tmax / tmin).ln() * 0.08).max(1.3f64.ln());
        let span = (vmax - vmin).max(if metric.higher_is_better() { 1.0 } else { (vmax.abs() * 0.1).max(1e-3) });
        let mid = (vmax + vmin) / 2.0;
        let half = span * 0.58;
        (tmin * (-pad).exp()..tmax * pad.exp(), mid - half..mid + half)
    };
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.name, font(17.0))
        .margin(10)
        .margin_right(24)
        .x_label_area_size(52)
        .y_label_area_size(76)
        .build_cartesian_2d(
            t_range.clone().log_scale().with_key_points(log_ticks(t_range.start, t_range.end)).with_light_points(minor_log_ticks(t_range)),
            v_range,
        )
        .map_err(|x| e(&x))?;
    chart
        .configure_mesh()
        .x_desc("frame GPU time [ms], median, log scale")
        .y_desc(metric.axis_label())
        .x_label_formatter(&|v| fmt_num(*v))
        .y_label_formatter(&|v| fmt_num(*v))
        .label_style(font(14.0))
        .axis_desc_style(font(15.0))
        .y_labels(8)
        .light_line_style(RGBColor(244, 244, 244))
        .bold_line_style(RGBColor(212, 212, 212))
        .draw()
        .map_err(|x| e(&x))?;
    let (xr, yr) = chart.plotting_area().get_pixel_range();
    let px: Vec<(i32, i32)> = pts.iter().map(|p| chart.backend_coord(&(p.1, p.2))).collect();

    // The Pareto front: the best metric within a time budget, a step at each front point.
    let costs: Vec<(f64, f64)> = pts.iter().map(|p| (p.1, if metric.higher_is_better() { -p.2 } else { p.2 })).collect();
    let front = pareto_front(&costs);
    let mut on: Vec<usize> = (0..pts.len()).filter(|&i| front[i]).collect();
    on.sort_by(|&a, &b| pts[a].1.total_cmp(&pts[b].1));
    on.dedup_by(|a, b| px[*a] == px[*b]);
    let mut step: Vec<(i32, i32)> = Vec::new();
    for (n, &i) in on.iter().enumerate() {
        step.push(px[i]);
        let next_x = on.get(n + 1).map_or(xr.end, |&j| px[j].0);
        step.push((next_x, px[i].1));
    }
    // Labels keep clear of the markers and of the front's steps.
    let mut obstacles: Vec<PixelRect> = px.iter().map(|&(x, y)| PixelRect { x0: x - 10, y0: y - 10, x1: x + 11, y1: y + 11 }).collect();
    for s in step.windows(2) {
        let ((ax, ay), (bx, by)) = (s[0], s[1]);
        obstacles.push(PixelRect { x0: ax.min(bx) - 2, y0: ay.min(by) - 2, x1: ax.max(bx) + 3, y1: ay.max(by) + 3 });
    }
    root.draw(&PathElement::new(step, RGBAColor(0, 0, 0, 0.45).stroke_width(3))).map_err(|x| e(&x))?;

    // One curve per method through its points in time order; a curve of one knob's sweep
    // (`--each`) through its points in the sweep's order, so that noisy times do not fold it.
    for (k, method) in methods.iter().enumerate() {
        let mut idx: Vec<usize> = (0..pts.len()).filter(|&i| pts[i].0 == k).collect();
        let names: Vec<Option<String>> = panel.rows.iter().filter(|r| r.method == *method).map(|r| knob_names(&r.knobs)).collect();
        let one_knob = names.first().is_some_and(|n| n.as_ref().is_some_and(|n| !n.contains(" / ")) && names.iter().all(|m| m == n));
        if !one_knob {
            idx.sort_by(|&a, &b| pts[a].1.total_cmp(&pts[b].1));
        }
        if idx.len() > 1 {
            let c = colour(k);
            let line = RGBAColor(c.0, c.1, c.2, 0.7).stroke_width(2);
            root.draw(&PathElement::new(idx.iter().map(|&i| px[i]).collect::<Vec<_>>(), line)).map_err(|x| e(&x))?;
        }
    }
    for (i, p) in pts.iter().enumerate() {
        if front[i] {
            root.draw(&Circle::new(px[i], 10, BLACK.stroke_width(2))).map_err(|x| e(&x))?;
        }
        draw_marker(root, p.0, px[i], 6)?;
    }

    // Knob values beside the points of methods with more than one point, the method's name
    // beside a method's only point; front first.
    let label_font = font(13.0);
    let single = |k: usize| pts.iter().filter(|p| p.0 == k).count() == 1;
    let mut order: Vec<usize> = (0..pts.len()).collect();
    order.sort_by_key(|&i| (!front[i], pts[i].0));
    let texts: Vec<String> = order
        .iter()
        .map(|&i| {
            let l = &pts[i].3;
            if single(pts[i].0) {
                methods[pts[i].0].to_string()
            } else if l.len() > 2 {
                format!("{} knob sets", l.len())
            } else {
                l.join(", ")
            }
        })
        .collect();
    let sizes: Vec<(i32, i32)> = texts
        .iter()
        .map(|t| root.estimate_text_size(t, &TextStyle::from(label_font.clone())).map(|(w, h)| (w as i32 + 4, h as i32 + 4)))
        .collect::<std::result::Result<_, _>>()
        .map_err(|x| e(&x))?;
    let anchors: Vec<(i32, i32)> = order.iter().map(|&i| px[i]).collect();
    let bounds = PixelRect { x0: xr.start, y0: yr.start, x1: xr.end, y1: yr.end };
    let places = place_labels(&anchors, &sizes, &obstacles, 12, bounds);
    for ((t, &i), place) in texts.iter().zip(&order).zip(places) {
        let Some((r, leader)) = place else {
            omitted.labels += 1;
            continue;
        };
        if leader {
            let to = (px[i].0.clamp(r.x0, r.x1), px[i].1.clamp(r.y0, r.y1));
            root.draw(&PathElement::new(vec![px[i], to], RGBColor(150, 150, 150).stroke_width(1))).map_err(|x| e(&x))?;
        }
        let c = colour(pts[i].0);
        let dark = RGBColor((c.0 as u32 * 3 / 4) as u8, (c.1 as u32 * 3 / 4) as u8, (c.2 as u32 * 3 / 4) as u8);
        root.draw(&Text::new(t.clone(), (r.x0 + 2, r.y0 + 2), label_font.color(&dark))).map_err(|x| e(&x))?;
    }
    Ok(())
}

fn draw_legend<DB: plotters::prelude::DrawingBackend>(
    area: &plotters::drawing::DrawingArea<DB, plotters::coord::Shift>,
    methods: &[&str],
    metric: Metric,
    knobs: Option<&str>,
    omitted: &Omitted,
) -> std::result::Result<(), String> {
    use plotters::prelude::*;
    let e = |e: &dyn std::fmt::Display| e.to_string();
    let text = |s: &str, y: i32, size: f64| area.draw(&Text::new(s.to_string(), (14, y), font(size).color(&BLACK))).map_err(|x| e(&x));
    let mut y = 16;
    text("methods", y, 16.0)?;
    y += 30;
    for (k, m) in methods.iter().enumerate() {
        let c = colour(k);
        area.draw(&PathElement::new(vec![(14, y), (44, y)], RGBAColor(c.0, c.1, c.2, 0.7).stroke_width(2))).map_err(|x| e(&x))?;
        draw_marker(area, k, (29, y), 6)?;
        area.draw(&Text::new(m.to_string(), (54, y - 8), font(15.0).color(&BLACK))).map_err(|x| e(&x))?;
        y += 24;
    }
    y += 10;
    area.draw(&PathElement::new(vec![(14, y + 6), (29, y + 6), (29, y - 4), (44, y - 4)], RGBAColor(0, 0, 0, 0.45).stroke_width(3)))
        .map_err(|x| e(&x))?;
    area.draw(&Text::new("Pareto front".to_string(), (54, y - 6), font(15.0).color(&BLACK))).map_err(|x| e(&x))?;
    y += 28;
    area.draw(&Circle::new((29, y), 10, BLACK.stroke_width(2))).map_err(|x| e(&x))?;
    area.draw(&Text::new("on the front".to_string(), (54, y - 8), font(15.0).color(&BLACK))).map_err(|x| e(&x))?;
    y += 34;
    let mut notes = vec![format!(
        "The front: the best {} for the time ({}).",
        metric.name(),
        if metric.higher_is_better() { "higher is better" } else { "lower is better" }
    )];
    if let Some(k) = knobs {
        notes.push(format!("Point labels: knob values ({k})."));
    }
    if omitted.labels > 0 {
        notes.push(format!("{} point label(s) left out for room; tradeoff.csv has every row.", omitted.labels));
    }
    if omitted.points > 0 {
        notes.push(format!("{} row(s) not drawn: infinite {} or no time.", omitted.points, metric.name()));
    }
    let note_font = font(13.0);
    let max_w = LEGEND_W as i32 - 28;
    for note in notes {
        let mut line = String::new();
        for word in note.split_whitespace() {
            let candidate = if line.is_empty() { word.to_string() } else { format!("{line} {word}") };
            let (w, _) = area.estimate_text_size(&candidate, &TextStyle::from(note_font.clone())).map_err(|x| e(&x))?;
            if w as i32 > max_w && !line.is_empty() {
                area.draw(&Text::new(std::mem::take(&mut line), (14, y), note_font.color(&RGBColor(60, 60, 60)))).map_err(|x| e(&x))?;
                y += 18;
                line = word.to_string();
            } else {
                line = candidate;
            }
        }
        area.draw(&Text::new(line, (14, y), note_font.color(&RGBColor(60, 60, 60)))).map_err(|x| e(&x))?;
        y += 26;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::ImageErrors;
    use crate::tradeoff::Row;

    fn timed(method: &str, knobs: &str, ms: f64, flip: f64, psnr: f64) -> Row {
        let t = [crate::vk::PassTiming { name: "scene.direct".into(), gpu_ms: ms, cpu_ms: 0.0, gpu_start_ms: 0.0 }];
        Row::new(method, knobs, &t, ImageErrors { rmse: flip, psnr, max_abs: flip, p99_abs: flip, flip })
    }

    /// Three methods over a 2 × 2 sweep, the ray tracer the same in every variant.
    fn study(shift: f64) -> Vec<Row> {
        let mut rows = Vec::new();
        for (i, knobs) in [
            "cube_size=16 cube_precision=half",
            "cube_size=16 cube_precision=single",
            "cube_size=64 cube_precision=half",
            "cube_size=64 cube_precision=single",
        ]
        .iter()
        .enumerate()
        {
            let i = i as f64;
            rows.push(timed("envmap", knobs, 1.0 + 0.3 * i, 0.2 - 0.01 * i, 24.0 + i + shift));
            rows.push(timed("distance", knobs, 2.5 + 0.8 * i, 0.12 - 0.01 * i, 28.0 + 1.5 * i + shift));
            rows.push(timed("bvh", knobs, 9.0, 0.05, 35.0 + shift));
        }
        rows
    }

    /// The PNG at `path`: its size, and how many pixels have each of `colours`.
    fn read_png(path: &Path, colours: &[(u8, u8, u8)]) -> ((u32, u32), Vec<usize>, usize) {
        let png = ::image::open(path).unwrap().to_rgb8();
        let counts = colours.iter().map(|&(r, g, b)| png.pixels().filter(|p| p.0 == [r, g, b]).count()).collect();
        let distinct: std::collections::HashSet<[u8; 3]> = png.pixels().map(|p| p.0).collect();
        (png.dimensions(), counts, distinct.len())
    }

    #[test]
    fn figure_has_a_panel_per_entry_in_svg_and_png() {
        let dir = std::env::temp_dir().join(format!("specula-figure-{}", std::process::id()));
        let panels = [Panel { name: "object A".into(), rows: study(0.0) }, Panel { name: "object B".into(), rows: study(3.0) }];
        let fig = plot(&dir.join("tradeoff"), &panels, Metric::Psnr, "two objects: PSNR vs GPU time").unwrap();
        assert_eq!((fig.svg.file_name().unwrap(), fig.png.file_name().unwrap()), ("tradeoff.svg".as_ref(), "tradeoff.png".as_ref()));
        let svg = std::fs::read_to_string(&fig.svg).unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("<circle") && svg.contains("<polygon"));
        let text: Vec<&str> = svg.lines().map(str::trim).collect();
        for label in [
            "two objects: PSNR vs GPU time",
            "object A",
            "object B",
            "envmap",
            "distance",
            "bvh",
            "Pareto front",
            "frame GPU time [ms], median, log scale",
            "PSNR vs reference [dB]  (higher is better)",
            "16/half",
            "64/single",
        ] {
            assert!(text.contains(&label), "{label} missing from the figure");
        }
        // The error axis starts near the data, not at 0 (PSNR 24–38 dB here).
        assert!(!text.contains(&"0"), "a tick at 0");
        // Knob names are explained once; the ray tracer's four identical rows are one point,
        // labelled with its name (twice: once per panel).
        assert!(svg.contains("Point labels: knob values (cube_size") && svg.contains("cube_precision).") && !svg.contains("4 knob sets"));
        assert!(text.iter().filter(|l| **l == "bvh").count() >= 2, "bvh's point unlabelled");

        let ((w, h), counts, distinct) = read_png(&fig.png, &COLOURS[..3]);
        assert_eq!((w, h), (2 * PANEL_W + LEGEND_W, TITLE_H + PANEL_H));
        // Not blank: each method's colour in both panels' markers and the legend, text
        // anti-aliased into many shades.
        for (k, n) in counts.iter().enumerate() {
            assert!(*n > 150, "method {k}: {n} pixels of its colour");
        }
        assert!(distinct > 100, "{distinct} colours");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn figure_plots_flip_and_notes_what_it_leaves_out() {
        let dir = std::env::temp_dir().join(format!("specula-figure-flip-{}", std::process::id()));
        let mut rows = study(0.0);
        rows.push(timed("envmap", "cube_size=16 cube_precision=half", 0.0, 0.1, 20.0));
        let fig = plot(&dir.join("flip"), &[Panel { name: "whole image".into(), rows }], Metric::Flip, "flip").unwrap();
        let svg = std::fs::read_to_string(&fig.svg).unwrap();
        assert!(svg.lines().any(|l| l.trim() == "mean FLIP vs reference  (lower is better)"));
        assert!(svg.contains("1 row(s) not drawn"), "the row without a time is noted");
        let ((w, h), counts, _) = read_png(&fig.png, &COLOURS[..3]);
        assert_eq!((w, h), (PANEL_W + LEGEND_W, TITLE_H + PANEL_H));
        assert!(counts.iter().all(|&n| n > 80), "{counts:?}");
        assert!(plot(&dir.join("none"), &[], Metric::Flip, "").is_err());
        std::fs::remove_dir_all(&dir).ok();
    }
}
