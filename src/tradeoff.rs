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
        let sep = if knob == "ref_point" { ';' } else { ',' };
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
}

impl Row {
    pub fn new(method: &str, knobs: &str, passes: &[crate::vk::PassTiming], errors: ImageErrors) -> Row {
        let passes: Vec<(String, f64)> = passes.iter().map(|p| (p.name.clone(), p.gpu_ms)).collect();
        let frame_ms = passes.iter().filter(|(n, _)| n != "frame.readback").map(|(_, ms)| ms).sum();
        Row { method: method.into(), knobs: knobs.into(), passes, frame_ms, errors }
    }
}

/// Which of the points (time, error) are Pareto-optimal: no other point is at least as
/// fast and at least as accurate and strictly better in one of the two. NaN never is.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<bool> {
    points
        .iter()
        .map(|&(t, e)| !t.is_nan() && !e.is_nan() && !points.iter().any(|&(t2, e2)| t2 <= t && e2 <= e && (t2 < t || e2 < e)))
        .collect()
}

/// The error the study plots and ranks by: mean FLIP.
pub fn plotted_error(e: &ImageErrors) -> f64 {
    e.flip
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// `tradeoff.csv`: method, knobs, frame ms, the errors, Pareto membership, the device and
/// driver that ran it, then one `<pass> ms` column per pass name any row has (empty where a
/// row has no such pass).
pub fn csv(rows: &[Row], device: &str) -> String {
    let mut pass_names: Vec<&str> = Vec::new();
    for r in rows {
        for (n, _) in &r.passes {
            if !pass_names.contains(&n.as_str()) {
                pass_names.push(n);
            }
        }
    }
    let front = pareto_front(&rows.iter().map(|r| (r.frame_ms, plotted_error(&r.errors))).collect::<Vec<_>>());
    let mut s = String::from("method,knobs,frame_ms,rmse,psnr_db,flip_mean,p99_abs,max_abs,pareto,device");
    for n in &pass_names {
        let _ = write!(s, ",{} ms", csv_field(n));
    }
    s.push('\n');
    for (r, on_front) in rows.iter().zip(front) {
        let e = &r.errors;
        let _ = write!(
            s,
            "{},{},{:.4},{:.6},{:.3},{:.6},{:.6},{:.6},{},{}",
            csv_field(&r.method),
            csv_field(&r.knobs),
            r.frame_ms,
            e.rmse,
            e.psnr,
            e.flip,
            e.p99_abs,
            e.max_abs,
            on_front,
            csv_field(device)
        );
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

/// An SVG plot of mean FLIP against frame GPU time, one colour per method, each point
/// labelled with its knobs, the Pareto front drawn as a line through its points.
pub fn plot_svg(path: &Path, rows: &[Row], title: &str) -> Result<()> {
    let err = |e: &dyn std::fmt::Display| Error::Image(format!("{}: {e}", path.display()));
    let points: Vec<(f64, f64)> = rows.iter().map(|r| (r.frame_ms, plotted_error(&r.errors))).collect();
    let finite: Vec<&(f64, f64)> = points.iter().filter(|(t, e)| t.is_finite() && e.is_finite()).collect();
    let (t_max, e_max) = finite.iter().fold((0.0f64, 0.0f64), |(a, b), (t, e)| (a.max(*t), b.max(*e)));
    let (t_max, e_max) = ((t_max * 1.15).max(1e-3), (e_max * 1.15).max(1e-3));
    let mut svg = String::new();
    draw_plot(&mut svg, &points, rows, title, (t_max, e_max)).map_err(|e| err(&e))?;
    crate::output::write_file(path, svg.as_bytes())
}

fn draw_plot(
    svg: &mut String,
    points: &[(f64, f64)],
    rows: &[Row],
    title: &str,
    (t_max, e_max): (f64, f64),
) -> std::result::Result<(), String> {
    use plotters::prelude::*;
    let err = |e: &dyn std::fmt::Display| e.to_string();
    let root = SVGBackend::with_string(svg, (960, 640)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 20))
        .margin(20)
        .x_label_area_size(50)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..t_max, 0.0..e_max)
        .map_err(|e| err(&e))?;
    chart.configure_mesh().x_desc("frame GPU time [ms] (median)").y_desc("mean FLIP vs reference").draw().map_err(|e| err(&e))?;
    let front = pareto_front(points);
    let mut front_pts: Vec<(f64, f64)> = points.iter().zip(&front).filter(|(_, f)| **f).map(|(p, _)| *p).collect();
    front_pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    chart
        .draw_series(LineSeries::new(front_pts.iter().copied(), ShapeStyle::from(&RED).stroke_width(2)))
        .map_err(|e| err(&e))?
        .label("Pareto front")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED));
    let mut methods: Vec<&str> = Vec::new();
    for r in rows {
        if !methods.contains(&r.method.as_str()) {
            methods.push(&r.method);
        }
    }
    for (k, m) in methods.iter().enumerate() {
        let color = Palette99::pick(k).to_rgba();
        let pts: Vec<((f64, f64), bool, &str)> = rows
            .iter()
            .zip(points)
            .zip(&front)
            .filter(|((r, p), _)| r.method == *m && p.0.is_finite() && p.1.is_finite())
            .map(|((r, p), f)| (*p, *f, r.knobs.as_str()))
            .collect();
        chart
            .draw_series(pts.iter().map(|(p, on_front, _)| {
                let size = if *on_front { 7 } else { 4 };
                Circle::new(*p, size, color.filled())
            }))
            .map_err(|e| err(&e))?
            .label(*m)
            .legend(move |(x, y)| Circle::new((x + 10, y), 4, color.filled()));
        chart
            .draw_series(pts.iter().map(|(p, _, label)| Text::new(label.to_string(), *p, ("sans-serif", 11).into_font())))
            .map_err(|e| err(&e))?;
    }
    chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw().map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

/// What [`run`] measures.
#[derive(Clone, Debug)]
pub struct Config {
    pub scene: Scene,
    /// The scene's name in the plot's title (e.g. its file name).
    pub scene_name: String,
    /// Base knobs of every variant; `spp` and `depth` also set the reference's.
    pub quality: Quality,
    /// The combinations multiply (see [`variants`]).
    pub sweeps: Vec<Sweep>,
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
    /// tradeoff.svg.
    pub out: PathBuf,
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
    pub svg: PathBuf,
    /// Validation layer messages over the whole study: (errors, warnings).
    pub validation: (u32, u32),
}

/// The study behind `specula tradeoff`: the exact reference once, then every method ×
/// every sweep variant rendered, timed and compared with it; writes the images,
/// `tradeoff.csv` and `tradeoff.svg` into `cfg.out`.
pub fn run(cfg: &Config, progress: &mut dyn FnMut(Progress)) -> Result<Report> {
    let variants = variants(&cfg.quality, &cfg.sweeps)?;
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

    progress(Progress::Start { steps: (1 + methods.len() * variants.len()) as u64 });
    progress(Progress::Begin(format!("reference ({} spp, depth {})", cfg.quality.spp, cfg.quality.depth)));
    let t = std::time::Instant::now();
    let reference = crate::reference::render_reference(&cfg.scene, &cfg.quality, (w, h))?;
    let reference_ms = t.elapsed().as_secs_f64() * 1e3;
    reference.write_exr(&out.join("reference.exr"))?;
    reference.write_png_srgb(&out.join("reference.png"))?;
    progress(Progress::Done);

    let ctx = Context::new(&cfg.device)?;
    let mut rows = Vec::new();
    for &method in &methods {
        // A ray tracer in the original geometry (survey §2) makes no maps and no shadow
        // maps: only the knobs it lists change its image, so variants that agree on those
        // are measured once and reported for each (the sweeps are usually map knobs).
        let reads = match method {
            Choice::Method(m) if m.family == "raytrace" => Some(m.knobs),
            _ => None,
        };
        let mut measured: Vec<(String, crate::Frame, ImageErrors)> = Vec::new();
        for (label, q) in &variants {
            progress(Progress::Begin(format!("{} {label}", method.name())));
            let key = reads.map(|knobs| knobs.iter().map(|k| q.get(k)).collect::<Vec<_>>().join(" "));
            let done = key.as_ref().and_then(|k| measured.iter().position(|(mk, _, _)| mk == k));
            let i = match done {
                Some(i) => i,
                None => {
                    let frame = crate::render(&ctx, &cfg.scene, method, q, (w, h), (cfg.warmup.max(1), cfg.frames.max(1)))?;
                    let errors = crate::metrics::compare(&frame.image, &reference)?;
                    measured.push((key.unwrap_or_default(), frame, errors));
                    measured.len() - 1
                }
            };
            let (_, frame, errors) = &measured[i];
            let stem = format!("{}-{}", method.name(), label.replace([' ', '=', ',', ';', '/'], "_"));
            frame.image.write_png_srgb(&out.join(format!("{stem}.png")))?;
            rows.push(Row::new(method.name(), label, &frame.passes, *errors));
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
    let svg_path = out.join("tradeoff.svg");
    let title = format!("{} at {w}x{h} on {}: mean FLIP vs GPU time", cfg.scene_name, ctx.device_name);
    plot_svg(&svg_path, &rows, &title)?;
    Ok(Report {
        rows,
        reference_ms,
        device_name: ctx.device_name.clone(),
        driver_info: ctx.driver_info.clone(),
        csv: csv_path,
        svg: svg_path,
        validation: (ctx.validation.error_count(), ctx.validation.warning_count()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn errors(flip: f64) -> ImageErrors {
        ImageErrors { rmse: flip, psnr: 1.0, max_abs: flip, p99_abs: flip, flip }
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
        assert_eq!(v[3].1.cube_size, 64);
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
            "method,knobs,frame_ms,rmse,psnr_db,flip_mean,p99_abs,max_abs,pareto,device,envmap.generate ms,frame.readback ms,scene.direct ms"
        );
        assert!(lines[1].starts_with("envmap,cube_size=32,2.0000,") && lines[1].ends_with(",true,\"llvmpipe, Mesa\",2.0000,9.0000,"));
        assert!(lines[2].starts_with("envmap,\"ref_point=0,0,1\",1.0000,") && lines[2].ends_with(",true,\"llvmpipe, Mesa\",,,1.0000"));
    }

    #[test]
    fn plot_is_an_svg_with_every_point() {
        let t = |ms| [crate::vk::PassTiming { name: "scene.direct".into(), gpu_ms: ms, cpu_ms: 0.0, gpu_start_ms: 0.0 }];
        let rows = [Row::new("envmap", "a", &t(1.0), errors(0.2)), Row::new("envmap", "b", &t(2.0), errors(0.1))];
        let path = std::env::temp_dir().join(format!("specula-plot-{}.svg", std::process::id()));
        plot_svg(&path, &rows, "test").unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("<circle"));
        for label in ["Pareto front", "envmap", "a", "b", "frame GPU time [ms] (median)"] {
            assert!(svg.lines().any(|l| l.trim() == label), "{label} missing from the plot");
        }
        std::fs::remove_file(&path).ok();
    }
}
