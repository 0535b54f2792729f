//! The speed–accuracy trade-off study behind `specula tradeoff`: knob sweeps, one row per
//! (method, knob values) with its median GPU time per pass and its errors against the
//! exact reference, the Pareto front of (time, error), `tradeoff.csv` and an SVG plot.
//! [`run`] drives the rendering (the CLI only parses its arguments and prints the table);
//! everything else here is plain data, so it is tested alone.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::methods::{Choice, Method};
use crate::metrics::ImageErrors;
use crate::quality::Quality;
use crate::scene::Scene;
use crate::vk::{Context, DeviceOptions};

/// One `--sweep knob=v1,v2,…`.
#[derive(Clone, Debug, PartialEq)]
pub struct Sweep {
    pub knob: String,
    pub values: Vec<String>,
}

impl Sweep {
    /// Parses `knob=v1,v2,…`; every value is checked against the knob's range now.
    pub fn parse(s: &str) -> Result<Sweep> {
        let (knob, values) = s.split_once('=').ok_or_else(|| Error::invalid("--sweep", format!("'{s}' is not knob=v1,v2,...")))?;
        let knob = knob.trim().to_string();
        // ref_point values contain commas themselves: split them on ';' instead.
        let sep = if knob == crate::quality::CubeKnobs::ref_point { ';' } else { ',' };
        let values: Vec<String> = values.split(sep).map(|v| v.trim().to_string()).filter(|v| !v.is_empty()).collect();
        if values.is_empty() {
            return Err(Error::invalid("--sweep", format!("'{s}' lists no values")));
        }
        for v in &values {
            Quality::default().set(&knob, v)?;
        }
        Ok(Sweep { knob, values })
    }
}

/// Every combination of the sweeps' values applied to `base` (the cartesian product, the
/// first sweep varying slowest), labelled `knob=value knob=value`; `base` alone, labelled
/// `default`, without sweeps.
pub fn variants(base: &Quality, sweeps: &[Sweep]) -> Result<Vec<(String, Quality)>> {
    let mut out = vec![(String::new(), base.clone())];
    for s in sweeps {
        let mut next = Vec::with_capacity(out.len() * s.values.len());
        for (label, q) in &out {
            for v in &s.values {
                let mut q = q.clone();
                q.set(&s.knob, v)?;
                let l = if label.is_empty() { format!("{}={v}", s.knob) } else { format!("{label} {}={v}", s.knob) };
                next.push((l, q));
            }
        }
        out = next;
    }
    if sweeps.is_empty() {
        out[0].0 = "default".into();
    }
    Ok(out)
}

/// One series of a study: the swept knob's name (`None`: every combination, or the
/// defaults) and its labelled variants.
pub type Series = (Option<String>, Vec<(String, Quality)>);

/// A knob no GPU method lists is the frame's (shadow maps, caustics, anti-aliasing): every
/// method's image may depend on it. (The CPU reference lists the ones it reads too.)
fn frame_knob(k: &str) -> bool {
    !Method::ALL.iter().any(|m| m.is_gpu() && m.knobs.contains(&k))
}

/// The study's series: with `each`, one per sweep, its values applied to `base` one at a
/// time (the other knobs at `base`), named by the sweep's knob; else one unnamed series of
/// every combination ([`variants`]).
pub fn series(base: &Quality, sweeps: &[Sweep], each: bool) -> Result<Vec<Series>> {
    if !each || sweeps.is_empty() {
        return Ok(vec![(None, variants(base, sweeps)?)]);
    }
    sweeps.iter().map(|s| Ok((Some(s.knob.clone()), variants(base, std::slice::from_ref(s))?))).collect()
}

/// One measured configuration.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    pub method: String,
    pub knobs: String,
    /// Median GPU ms per pass, in frame order.
    pub passes: Vec<(String, f64)>,
    /// Sum of the passes except `frame.readback` (the standalone copy to the host).
    pub frame_ms: f64,
    pub errors: ImageErrors,
    /// The error where the method acts (issue 15): per specular object, on all specular
    /// pixels and on the rest (`metrics::errors_by_object`); empty where not measured.
    pub regions: Vec<crate::metrics::MaskedError>,
}

impl Row {
    pub fn new(method: &str, knobs: &str, passes: &[crate::vk::PassTiming], errors: ImageErrors) -> Row {
        let passes: Vec<(String, f64)> = passes.iter().map(|p| (p.name.clone(), p.gpu_ms)).collect();
        let frame_ms = passes.iter().filter(|(n, _)| n != "frame.readback").map(|(_, ms)| ms).sum();
        Row { method: method.into(), knobs: knobs.into(), passes, frame_ms, errors, regions: Vec::new() }
    }
}

/// The figure's panels: the whole image, and with PSNR, one panel per specular object (its
/// rows' PSNR and RMSE those of its pixels; FLIP is per image only): where the method acts.
pub fn region_panels(rows: &[Row], metric: Metric) -> Vec<Panel> {
    let mut panels = vec![Panel { name: "whole image".into(), rows: rows.to_vec() }];
    let objects: Vec<String> = rows
        .first()
        .map(|r| r.regions.iter().map(|e| e.name.clone()).filter(|n| n != "specular" && n != "non-specular").collect())
        .unwrap_or_default();
    if metric != Metric::Psnr || objects.is_empty() {
        return panels;
    }
    for name in objects {
        let rows: Vec<Row> = rows
            .iter()
            .filter_map(|r| {
                let e = r.regions.iter().find(|e| e.name == name)?;
                let mut r = r.clone();
                r.errors = ImageErrors { rmse: e.rmse, psnr: e.psnr, flip: f64::NAN, ..r.errors };
                Some(r)
            })
            .collect();
        panels.push(Panel { name: format!("{name} (its pixels)"), rows });
    }
    panels
}

/// Which of the points (time, cost) are Pareto-optimal, the cost lower-is-better (see
/// [`Metric::cost`]): no other point is at least as fast and at least as accurate and
/// strictly better in one of the two. NaN never is.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<bool> {
    points
        .iter()
        .map(|&(t, e)| !t.is_nan() && !e.is_nan() && !points.iter().any(|&(t2, e2)| t2 <= t && e2 <= e && (t2 < t || e2 < e)))
        .collect()
}

/// The error the study plots and ranks by (`specula tradeoff --metric`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Metric {
    /// PSNR against the reference in dB (peak 1): higher is better.
    #[default]
    Psnr,
    /// Mean FLIP against the reference, in [0, 1]: lower is better.
    Flip,
}

impl Metric {
    /// `psnr` or `flip` (any case).
    pub fn parse(s: &str) -> Result<Metric> {
        match s.trim().to_ascii_lowercase().as_str() {
            "psnr" => Ok(Metric::Psnr),
            "flip" => Ok(Metric::Flip),
            _ => Err(Error::invalid("--metric", format!("'{s}' is neither psnr nor flip"))),
        }
    }

    /// Its name in titles: `PSNR` or `mean FLIP`.
    pub fn name(self) -> &'static str {
        match self {
            Metric::Psnr => "PSNR",
            Metric::Flip => "mean FLIP",
        }
    }

    pub fn value(self, e: &ImageErrors) -> f64 {
        match self {
            Metric::Psnr => e.psnr,
            Metric::Flip => e.flip,
        }
    }

    pub fn higher_is_better(self) -> bool {
        self == Metric::Psnr
    }

    /// The value as a cost, lower is better: what [`pareto_front`] minimises.
    pub fn cost(self, e: &ImageErrors) -> f64 {
        if self.higher_is_better() {
            -self.value(e)
        } else {
            self.value(e)
        }
    }

    fn axis_label(self) -> &'static str {
        match self {
            Metric::Psnr => "PSNR vs reference [dB]  (higher is better)",
            Metric::Flip => "mean FLIP vs reference  (lower is better)",
        }
    }
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// `tradeoff.csv`: method, knobs, frame ms, the errors, Pareto membership in (frame ms,
/// mean FLIP) (`pareto`) and in (frame ms, PSNR) (`pareto_psnr`), the device and driver
/// that ran it, then one `<pass> ms` column per pass name any row has (empty where a row
/// has no such pass).
pub fn csv(rows: &[Row], device: &str) -> String {
    let mut pass_names: Vec<&str> = Vec::new();
    for r in rows {
        for (n, _) in &r.passes {
            if !pass_names.contains(&n.as_str()) {
                pass_names.push(n);
            }
        }
    }
    let front = |m: Metric| pareto_front(&rows.iter().map(|r| (r.frame_ms, m.cost(&r.errors))).collect::<Vec<_>>());
    let (flip_front, psnr_front) = (front(Metric::Flip), front(Metric::Psnr));
    let mut regions: Vec<&str> = Vec::new();
    for r in rows {
        for e in &r.regions {
            if !regions.contains(&e.name.as_str()) {
                regions.push(&e.name);
            }
        }
    }
    let mut s = String::from("method,knobs,frame_ms,rmse,psnr_db,flip_mean,p99_abs,max_abs,pareto,pareto_psnr,device");
    for n in &regions {
        let _ = write!(s, ",{}", csv_field(&format!("psnr_db[{n}]")));
    }
    for n in &pass_names {
        let _ = write!(s, ",{} ms", csv_field(n));
    }
    s.push('\n');
    for ((r, on_flip), on_psnr) in rows.iter().zip(flip_front).zip(psnr_front) {
        let e = &r.errors;
        let _ = write!(
            s,
            "{},{},{:.4},{:.6},{:.3},{:.6},{:.6},{:.6},{},{},{}",
            csv_field(&r.method),
            csv_field(&r.knobs),
            r.frame_ms,
            e.rmse,
            e.psnr,
            e.flip,
            e.p99_abs,
            e.max_abs,
            on_flip,
            on_psnr,
            csv_field(device)
        );
        for n in &regions {
            match r.regions.iter().find(|e| e.name == *n) {
                Some(e) => {
                    let _ = write!(s, ",{:.3}", e.psnr);
                }
                None => s.push(','),
            }
        }
        for n in &pass_names {
            match r.passes.iter().find(|(p, _)| p == n) {
                Some((_, ms)) => {
                    let _ = write!(s, ",{ms:.4}");
                }
                None => s.push(','),
            }
        }
        s.push('\n');
    }
    s
}

/// One panel of the trade-off figure: what its rows measure (the whole image, or one
/// specular object) and the rows.
#[derive(Clone, Debug)]
pub struct Panel {
    pub name: String,
    pub rows: Vec<Row>,
}

/// The files [`plot`] wrote.
#[derive(Clone, Debug)]
pub struct Figure {
    pub svg: PathBuf,
    pub png: PathBuf,
}

/// DejaVu Sans (assets/fonts/, Bitstream Vera licence): every figure's text, in the PNGs
/// rasterised by ab_glyph, so no system font is needed.
static FONT: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");

/// Registers the bundled font as plotters' `sans-serif` (once).
pub(crate) fn register_font() -> Result<()> {
    static DONE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok = *DONE.get_or_init(|| plotters::style::register_font("sans-serif", plotters::style::FontStyle::Normal, FONT).is_ok());
    if ok {
        Ok(())
    } else {
        Err(Error::Image("the bundled font assets/fonts/DejaVuSans.ttf does not parse".into()))
    }
}

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

fn colour(k: usize) -> plotters::style::RGBColor {
    let (r, g, b) = COLOURS[k % COLOURS.len()];
    plotters::style::RGBColor(r, g, b)
}

fn font(size: f64) -> plotters::style::FontDesc<'static> {
    plotters::style::FontDesc::new(plotters::style::FontFamily::SansSerif, size, plotters::style::FontStyle::Normal)
}

fn draw_marker<DB: plotters::prelude::DrawingBackend>(
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

/// A pixel rectangle, `x1`, `y1` exclusive.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelRect {
    pub x0: i32,
    pub y0: i32,
    pub x1: i32,
    pub y1: i32,
}

impl PixelRect {
    pub fn overlaps(&self, o: &PixelRect) -> bool {
        self.x0 < o.x1 && o.x0 < self.x1 && self.y0 < o.y1 && o.y0 < self.y1
    }
    fn inside(&self, o: &PixelRect) -> bool {
        self.x0 >= o.x0 && self.y0 >= o.y0 && self.x1 <= o.x1 && self.y1 <= o.y1
    }
}

/// Places text boxes of `sizes` next to their `anchors` (pixels), in the order given (the
/// first get the best places): the first of eight directions, at three distances from the
/// anchor (`gap` pixels, then 14 and 30 more), whose box stays in `bounds` and overlaps no
/// box placed before and none of `obstacles` (markers, lines). `None` where nothing fits;
/// the `bool` says the box is far enough from its anchor to need a leader line.
pub fn place_labels(
    anchors: &[(i32, i32)],
    sizes: &[(i32, i32)],
    obstacles: &[PixelRect],
    gap: i32,
    bounds: PixelRect,
) -> Vec<Option<(PixelRect, bool)>> {
    let mut placed: Vec<PixelRect> = Vec::new();
    anchors
        .iter()
        .zip(sizes)
        .map(|(&(x, y), &(w, h))| {
            for d in [gap, gap + 14, gap + 30] {
                let candidates = [
                    (x + d, y - h / 2),
                    (x - d - w, y - h / 2),
                    (x - w / 2, y - d - h),
                    (x - w / 2, y + d),
                    (x + d * 2 / 3, y - d * 2 / 3 - h),
                    (x + d * 2 / 3, y + d * 2 / 3),
                    (x - d * 2 / 3 - w, y - d * 2 / 3 - h),
                    (x - d * 2 / 3 - w, y + d * 2 / 3),
                ];
                for (x0, y0) in candidates {
                    let r = PixelRect { x0, y0, x1: x0 + w, y1: y0 + h };
                    if r.inside(&bounds) && !placed.iter().chain(obstacles).any(|o| o.overlaps(&r)) {
                        placed.push(r);
                        return Some((r, d > gap));
                    }
                }
            }
            None
        })
        .collect()
}

/// The label of a point: its knob values (`cube_size=16 cube_precision=half` → `16/half`).
fn knob_values(knobs: &str) -> String {
    let values: Vec<&str> = knobs.split_whitespace().filter_map(|kv| kv.split_once('=').map(|(_, v)| v)).collect();
    if values.is_empty() {
        knobs.to_string()
    } else {
        values.join("/")
    }
}

/// `cube_size / cube_precision`: the knob names of `knobs`, or `None` without any.
fn knob_names(knobs: &str) -> Option<String> {
    let names: Vec<&str> = knobs.split_whitespace().filter_map(|kv| kv.split_once('=').map(|(k, _)| k)).collect();
    (!names.is_empty()).then(|| names.join(" / "))
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

/// Labelled ticks of a log axis over `lo..hi`: 1-2-5 per decade (1 alone over many
/// decades, 1 to 9 over a few), at least four; linear steps of 1, 2 or 5 × 10^k over a
/// range too narrow for that.
fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    if !(lo > 0.0 && hi > lo && hi.is_finite()) {
        return Vec::new();
    }
    let per_decade = |mults: &[f64]| {
        let mut v = Vec::new();
        let mut p = 10f64.powf(lo.log10().floor());
        while p <= hi {
            v.extend(mults.iter().map(|m| m * p).filter(|x| (lo..=hi).contains(x)));
            p *= 10.0;
        }
        v
    };
    for mults in [&[1.0][..], &[1.0, 2.0, 5.0], &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]] {
        let v = per_decade(mults);
        if (4..=12).contains(&v.len()) {
            return v;
        }
    }
    let rough = (hi - lo) / 5.0;
    let mag = 10f64.powf(rough.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0].iter().map(|m| m * mag).find(|s| *s >= rough).unwrap_or(10.0 * mag);
    ((lo / step).ceil() as i64..=(hi / step).floor() as i64).map(|i| i as f64 * step).collect()
}

/// The grid's light lines on a log axis: 1 to 9 × 10^k.
fn minor_log_ticks(r: std::ops::Range<f64>) -> Vec<f64> {
    let mut v = Vec::new();
    if !(r.start > 0.0 && r.end > r.start && r.end.is_finite()) {
        return v;
    }
    let mut p = 10f64.powf(r.start.log10().floor());
    while p <= r.end {
        v.extend((1..10).map(|m| m as f64 * p).filter(|x| r.contains(x)));
        p *= 10.0;
    }
    v
}

/// A tick label: a few significant digits, no trailing zeros.
fn fmt_num(v: f64) -> String {
    let a = v.abs();
    let s = if a >= 100.0 {
        format!("{v:.0}")
    } else if a >= 10.0 {
        format!("{v:.1}")
    } else if a >= 1.0 {
        format!("{v:.2}")
    } else if a >= 0.001 || a == 0.0 {
        format!("{v:.4}")
    } else {
        return format!("{v:.1e}");
    };
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// What [`run`] measures.
#[derive(Clone, Debug)]
pub struct Config {
    pub scene: Scene,
    /// The scene's name in the plot's title (e.g. its file name).
    pub scene_name: String,
    /// Base knobs of every variant; `spp` and `depth` also set the reference's.
    pub quality: Quality,
    /// The combinations multiply (see [`variants`]), unless `each`.
    pub sweeps: Vec<Sweep>,
    /// One sweep at a time from `quality` (see [`series`]): each method gets one curve
    /// per sweep, its rows' method `METHOD (KNOB)`.
    pub each: bool,
    /// The choices to measure (GPU methods or `auto`); empty: `auto` and every GPU method
    /// of the registry. The reference is not one.
    pub methods: Vec<Choice>,
    pub size: (u32, u32),
    /// Untimed frames per configuration (at least 1: the first frame uploads the scene).
    pub warmup: u32,
    /// Timed frames per configuration (at least 1); the median per pass is kept.
    pub frames: u32,
    /// The device the GPU methods run on.
    pub device: DeviceOptions,
    /// Output directory (created): reference.exr/.png, one PNG per row, tradeoff.csv and
    /// the figure tradeoff.svg + tradeoff.png.
    pub out: PathBuf,
    /// The figure's error axis (the CSV has both).
    pub metric: Metric,
    /// `--calibrate`: also fit the budgeted planner's per-object models from the rows
    /// (`plan::budget::fit`) and write them here as JSON.
    pub calibrate: Option<PathBuf>,
}

/// How far [`run`] has come, for a progress bar.
#[derive(Clone, Debug, PartialEq)]
pub enum Progress {
    /// The study has `steps` steps: the reference, then one per method × variant.
    Start { steps: u64 },
    /// A step begins (what it renders).
    Begin(String),
    /// The step that began last is done.
    Done,
    /// Every step is done (the CSV and the plot are written next).
    Finished,
}

/// What [`run`] measured and wrote.
#[derive(Clone, Debug)]
pub struct Report {
    /// One per method × variant, in that order.
    pub rows: Vec<Row>,
    /// Wall-clock milliseconds of the CPU reference.
    pub reference_ms: f64,
    pub device_name: String,
    pub driver_info: String,
    pub csv: PathBuf,
    /// tradeoff.svg and tradeoff.png.
    pub figure: Figure,
    /// Validation layer messages over the whole study: (errors, warnings).
    pub validation: (u32, u32),
    /// With `calibrate`: the fitted models (also written to that path).
    pub models: Option<crate::plan::budget::Models>,
}

/// The study behind `specula tradeoff`: the exact reference once, then every method ×
/// every sweep variant rendered, timed and compared with it; writes the images,
/// `tradeoff.csv` and the figure (`tradeoff.svg`, `tradeoff.png`, see [`plot`]) into
/// `cfg.out`.
pub fn run(cfg: &Config, progress: &mut dyn FnMut(Progress)) -> Result<Report> {
    let series = series(&cfg.quality, &cfg.sweeps, cfg.each)?;
    let methods: Vec<Choice> = if cfg.methods.is_empty() {
        std::iter::once(Choice::Auto).chain(Method::ALL.iter().copied().filter(|m| m.is_gpu()).map(Choice::Method)).collect()
    } else {
        if let Some(m) = cfg.methods.iter().find(|m| matches!(m, Choice::Method(m) if !m.is_gpu())) {
            return Err(Error::invalid("--method", format!("'{}' is the reference itself", m.name())));
        }
        cfg.methods.clone()
    };
    let out = cfg.out.as_path();
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    let (w, h) = cfg.size;

    // One sweep at a time: a method gets the series of the knobs it reads, or its
    // defaults alone when it reads none of them: its own, the frame's (`frame_knob`), and
    // with caustics (§6) the map knobs the caustics stage reads whatever the method.
    let defaults = vec![(None, variants(&cfg.quality, &[])?)];
    // Whether a frame under `q` has caustics (where auto cannot plan the scene, taken as
    // having them: more rows measured, none copied wrongly).
    let has_caustics = |q: &Quality| {
        crate::plan::plan_with(&cfg.scene, &crate::plan::Choices::all(Choice::Auto), q).map_or(true, |p| p.caustics.is_some())
    };
    let caustics = has_caustics(&cfg.quality);
    let method_reads =
        |m: &Method, k: &str| m.knobs.contains(&k) || frame_knob(k) || (caustics && crate::methods::caustics::MAP_KNOBS.contains(&k));
    let of = |m: &Choice| -> &Vec<Series> {
        match m {
            Choice::Method(m) if cfg.each && !series.iter().any(|(k, _)| k.as_ref().is_some_and(|k| method_reads(m, k))) => &defaults,
            _ => &series,
        }
    };
    let reads = |m: &Choice, knob: &Option<String>| match (m, knob) {
        (Choice::Method(m), Some(k)) => method_reads(m, k),
        _ => true,
    };
    let runs: Vec<(Choice, &Series)> = methods.iter().flat_map(|m| of(m).iter().filter(|s| reads(m, &s.0)).map(move |s| (*m, s))).collect();
    let steps: usize = runs.iter().map(|(_, (_, v))| v.len()).sum();
    progress(Progress::Start { steps: (1 + steps) as u64 });
    progress(Progress::Begin(format!("reference ({} spp, depth {})", cfg.quality.reference.spp, cfg.quality.frame.depth)));
    let t = std::time::Instant::now();
    let reference = crate::reference::render_reference(&cfg.scene, &cfg.quality, (w, h))?;
    let reference_ms = t.elapsed().as_secs_f64() * 1e3;
    // Where each method acts: the reference's first hits split the error by object.
    let ids = crate::reference::object_ids(&cfg.scene, (w, h))?;
    let specular: Vec<bool> = cfg.scene.meshes.iter().map(|m| cfg.scene.materials[m.material].kind.is_specular()).collect();
    let names: Vec<String> = cfg.scene.meshes.iter().map(|m| m.name.clone()).collect();
    reference.write_exr(&out.join("reference.exr"))?;
    reference.write_png_srgb(&out.join("reference.png"))?;
    progress(Progress::Done);

    let ctx = Context::new(&cfg.device)?;
    let mut rows = Vec::new();
    // With --calibrate: per row its knobs and plan (which passes serve which object).
    let mut plans: Vec<(String, crate::plan::Plan)> = Vec::new();
    for (method, (knob, variants)) in runs {
        let name = knob.as_ref().map_or_else(|| method.name().to_string(), |k| format!("{} ({k})", method.name()));
        // A ray tracer in the original geometry (survey §2) makes no maps and no shadow
        // maps: only the knobs it lists change its image, so variants that agree on those
        // are measured once and reported for each (the sweeps are usually map knobs). Not
        // when the frame has caustics (§6): they come from light cube maps, refractor maps
        // and shadow maps whatever the method, so every map knob can change its image.
        let raytrace = match method {
            // Its own knobs and the frame's.
            Choice::Method(m) if m.family == "raytrace" => {
                Some(crate::quality::KNOBS.iter().map(|k| k.name).filter(|k| m.knobs.contains(k) || frame_knob(k)).collect::<Vec<_>>())
            }
            _ => None,
        };
        let mut measured: Vec<(String, crate::Frame, ImageErrors, Vec<crate::metrics::MaskedError>)> = Vec::new();
        for (label, q) in variants {
            progress(Progress::Begin(format!("{name} {label}")));
            let reads = raytrace.as_ref().filter(|_| !has_caustics(q));
            let key = reads.map(|knobs| knobs.iter().map(|k| q.get(k)).collect::<Vec<_>>().join(" "));
            let done = key.as_ref().and_then(|k| measured.iter().position(|(mk, _, _, _)| mk == k));
            let i = match done {
                Some(i) => i,
                None => {
                    let frame = crate::render(&ctx, &cfg.scene, method, q, (w, h), (cfg.warmup.max(1), cfg.frames.max(1)))?;
                    let errors = crate::metrics::compare(&frame.image, &reference)?;
                    let regions = crate::metrics::errors_by_object(&frame.image, &reference, &ids, &specular, &names)?;
                    measured.push((key.unwrap_or_default(), frame, errors, regions));
                    measured.len() - 1
                }
            };
            let (_, frame, errors, regions) = &measured[i];
            let stem = format!("{}-{}", method.name(), label.replace([' ', '=', ',', ';', '/'], "_"));
            frame.image.write_png_srgb(&out.join(format!("{stem}.png")))?;
            let mut row = Row::new(&name, label, &frame.passes, *errors);
            row.regions = regions.clone();
            rows.push(row);
            if cfg.calibrate.is_some() {
                plans.push((label.clone(), crate::plan::plan_with(&cfg.scene, &crate::plan::Choices::all(method), q)?));
            }
            if reads.is_none() {
                measured.clear();
            }
            progress(Progress::Done);
        }
    }
    progress(Progress::Finished);

    let csv_path = out.join("tradeoff.csv");
    let device = format!("{} ({})", ctx.device_name, ctx.driver_info);
    crate::output::write_file(&csv_path, csv(&rows, &device).as_bytes())?;
    let title = format!("{} at {w}x{h} on {}: {} vs GPU time", cfg.scene_name, ctx.device_name, cfg.metric.name());
    let figure = plot(&out.join("tradeoff"), &region_panels(&rows, cfg.metric), cfg.metric, &title)?;
    let models = match &cfg.calibrate {
        Some(path) => {
            let measured: Vec<crate::plan::budget::Measured> = rows
                .iter()
                .zip(&plans)
                .map(|(r, (knobs, plan))| crate::plan::budget::Measured { knobs, plan, passes: &r.passes, regions: &r.regions })
                .collect();
            let m = crate::plan::budget::fit(&cfg.scene, &cfg.scene_name, &device, (w, h), &measured);
            crate::output::write_file(path, m.to_json().as_bytes())?;
            Some(m)
        }
        None => None,
    };
    Ok(Report {
        rows,
        reference_ms,
        device_name: ctx.device_name.clone(),
        driver_info: ctx.driver_info.clone(),
        csv: csv_path,
        figure,
        validation: (ctx.validation.error_count(), ctx.validation.warning_count()),
        models,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn errors(flip: f64) -> ImageErrors {
        ImageErrors { rmse: flip, psnr: 1.0, max_abs: flip, p99_abs: flip, flip }
    }

    #[test]
    fn each_sweep_is_a_series_of_its_own() {
        let s = [Sweep::parse("secant_steps=0,1").unwrap(), Sweep::parse("linear_steps=4,8,16").unwrap()];
        let base = {
            let mut knobs = Quality::default();
            knobs.search.linear_steps = 4;
            knobs.search.secant_steps = 0;
            knobs
        };
        let v = series(&base, &s, true).unwrap();
        assert_eq!(v.len(), 2);
        assert_eq!(v[0].0.as_deref(), Some("secant_steps"));
        assert_eq!(v[1].1.iter().map(|(l, _)| l.as_str()).collect::<Vec<_>>(), ["linear_steps=4", "linear_steps=8", "linear_steps=16"]);
        // The other knobs stay at the base.
        assert!(v[0].1.iter().all(|(_, q)| q.search.linear_steps == 4) && v[1].1.iter().all(|(_, q)| q.search.secant_steps == 0));
        assert_eq!(v[0].1[1].1.search.secant_steps, 1);
        let product = series(&base, &s, false).unwrap();
        assert_eq!((product.len(), product[0].0.clone(), product[0].1.len()), (1, None, 6));
    }

    #[test]
    fn sweeps_multiply_out() {
        let s = [Sweep::parse("cube_size=32,64").unwrap(), Sweep::parse("cube_precision=half,single").unwrap()];
        let v = variants(&Quality::default(), &s).unwrap();
        let labels: Vec<&str> = v.iter().map(|(l, _)| l.as_str()).collect();
        assert_eq!(
            labels,
            [
                "cube_size=32 cube_precision=half",
                "cube_size=32 cube_precision=single",
                "cube_size=64 cube_precision=half",
                "cube_size=64 cube_precision=single"
            ]
        );
        assert_eq!(v[3].1.cube.cube_size, 64);
        assert_eq!(variants(&Quality::default(), &[]).unwrap()[0].0, "default");
        assert!(Sweep::parse("cube_size=8").is_err());
        assert!(Sweep::parse("nonsense=1").is_err());
        assert!(Sweep::parse("cube_size").is_err());
        assert_eq!(Sweep::parse("ref_point=auto;0,0,1").unwrap().values, ["auto", "0,0,1"]);
    }

    #[test]
    fn pareto_front_keeps_the_undominated() {
        let pts = [(1.0, 0.5), (2.0, 0.2), (3.0, 0.3), (0.5, 0.9), (2.0, 0.2), (f64::NAN, 0.0)];
        assert_eq!(pareto_front(&pts), [true, true, false, true, true, false]);
    }

    #[test]
    fn csv_has_a_column_per_pass_and_quotes() {
        let t = |n: &str, ms| crate::vk::PassTiming { name: n.into(), gpu_ms: ms, cpu_ms: 0.0, gpu_start_ms: 0.0 };
        let rows = [
            Row::new("envmap", "cube_size=32", &[t("envmap.generate", 2.0), t("frame.readback", 9.0)], errors(0.1)),
            Row::new("envmap", "ref_point=0,0,1", &[t("scene.direct", 1.0)], errors(0.2)),
        ];
        assert_eq!(rows[0].frame_ms, 2.0, "readback is not the method's time");
        let s = csv(&rows, "llvmpipe, Mesa");
        let lines: Vec<&str> = s.lines().collect();
        assert_eq!(
            lines[0],
            "method,knobs,frame_ms,rmse,psnr_db,flip_mean,p99_abs,max_abs,pareto,pareto_psnr,device,envmap.generate ms,frame.readback ms,scene.direct ms"
        );
        // Both on the FLIP front; the second, faster at the same PSNR, alone on PSNR's.
        assert!(lines[1].starts_with("envmap,cube_size=32,2.0000,") && lines[1].ends_with(",true,false,\"llvmpipe, Mesa\",2.0000,9.0000,"));
        assert!(lines[2].starts_with("envmap,\"ref_point=0,0,1\",1.0000,") && lines[2].ends_with(",true,true,\"llvmpipe, Mesa\",,,1.0000"));
    }

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

    #[test]
    fn log_axis_ticks_fit_the_range() {
        assert_eq!(log_ticks(0.5, 2000.0), [1.0, 10.0, 100.0, 1000.0]);
        assert_eq!(log_ticks(0.7, 30.0), [1.0, 2.0, 5.0, 10.0, 20.0]);
        assert_eq!(log_ticks(1.5, 9.5), [2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]);
        let narrow = log_ticks(2.3, 4.1);
        assert!(narrow.len() >= 4 && narrow.iter().all(|t| (2.3..=4.1).contains(t)), "{narrow:?}");
        let minor = minor_log_ticks(0.5..3.0);
        assert_eq!(minor.len(), 7, "{minor:?}");
        assert!(minor.iter().zip([0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 2.0]).all(|(a, b)| (a - b).abs() < 1e-12), "{minor:?}");
        assert_eq!(
            (fmt_num(0.30000000000000004), fmt_num(12.0), fmt_num(24.5), fmt_num(0.0002)),
            ("0.3".into(), "12".into(), "24.5".into(), "2.0e-4".into())
        );
    }

    #[test]
    fn metric_parses_and_ranks() {
        assert_eq!(Metric::parse("PSNR").unwrap(), Metric::Psnr);
        assert_eq!(Metric::parse("flip").unwrap(), Metric::Flip);
        assert!(Metric::parse("rmse").is_err());
        assert_eq!(Metric::default(), Metric::Psnr);
        let e = ImageErrors { rmse: 0.1, psnr: 20.0, max_abs: 0.5, p99_abs: 0.3, flip: 0.2 };
        assert_eq!((Metric::Psnr.cost(&e), Metric::Flip.cost(&e)), (-20.0, 0.2));
    }

    #[test]
    fn labels_are_placed_without_overlap() {
        // A tight cluster: every label that is placed is inside the bounds, clear of every
        // marker and of every other label; the first, its right blocked by its neighbour's
        // marker, takes the left-hand place.
        let anchors: Vec<(i32, i32)> = (0..12).map(|i| (200 + (i % 4) * 14, 150 + (i / 4) * 12)).collect();
        let markers: Vec<PixelRect> = anchors.iter().map(|&(x, y)| PixelRect { x0: x - 10, y0: y - 10, x1: x + 11, y1: y + 11 }).collect();
        let sizes = vec![(60, 16); anchors.len()];
        let bounds = PixelRect { x0: 0, y0: 0, x1: 400, y1: 300 };
        let places = place_labels(&anchors, &sizes, &markers, 12, bounds);
        assert_eq!(places[0], Some((PixelRect { x0: 128, y0: 142, x1: 188, y1: 158 }, false)));
        // Alone, a point's label goes to its right.
        assert_eq!(
            place_labels(&anchors[..1], &sizes[..1], &markers[..1], 12, bounds)[0],
            Some((PixelRect { x0: 212, y0: 142, x1: 272, y1: 158 }, false))
        );
        let rects: Vec<PixelRect> = places.iter().flatten().map(|(r, _)| *r).collect();
        assert!(rects.len() >= 6, "only {} of 12 placed", rects.len());
        for (i, r) in rects.iter().enumerate() {
            assert!(r.inside(&bounds), "{r:?}");
            assert!(rects[i + 1..].iter().all(|o| !o.overlaps(r)), "{r:?} overlaps another label");
            assert!(markers.iter().all(|m| !r.overlaps(m)), "{r:?} covers a marker");
        }
        // No room at all: nothing is placed.
        assert_eq!(place_labels(&[(5, 5)], &[(60, 16)], &markers, 12, PixelRect { x0: 0, y0: 0, x1: 20, y1: 20 }), [None]);
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
