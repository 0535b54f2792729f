//! The study's driver: the reference once, then every method × variant rendered, timed
//! and compared with it; the images, `tradeoff.csv` and the figure written.

use std::path::PathBuf;

use super::csv::csv;
use super::plot::{plot, Figure};
use super::rows::{region_panels, Metric, Row};
use super::sweep::{frame_knob, series, variants, Series, Sweep};
use crate::error::{Error, Result};
use crate::methods::{Choice, Method};
use crate::metrics::ImageErrors;
use crate::quality::Quality;
use crate::scene::Scene;
use crate::vk::{Context, DeviceOptions};

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
    // By default every GPU method but the O(N)-per-ray schemes (the ray engine and the ray
    // hierarchy test every triangle for every ray: minutes a frame on a CPU device), which
    // run when named (`--method`).
    let linear = |m: &Method| crate::methods::raytrace::bench::complexity(*m).starts_with("O(N)");
    let methods: Vec<Choice> = if cfg.methods.is_empty() {
        std::iter::once(Choice::Auto).chain(Method::ALL.iter().copied().filter(|m| m.is_gpu() && !linear(m)).map(Choice::Method)).collect()
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
        // A method that shades every pixel in its own stage (its registry entry says so:
        // ray tracing in the original geometry, survey §2, makes no maps and no shadow
        // maps) has an image only the knobs it lists and the frame's change, so variants
        // that agree on those are measured once and reported for each (the sweeps are
        // usually map knobs). Not when the frame has caustics (§6): they come from light
        // cube maps, refractor maps and shadow maps whatever the method, so every map knob
        // can change its image.
        let decided_by = match method {
            // Its own knobs and the frame's.
            Choice::Method(m) if m.gpu.is_some_and(|g| g.shades_every_pixel) => {
                Some(crate::quality::KNOBS.iter().map(|k| k.name).filter(|k| m.knobs.contains(k) || frame_knob(k)).collect::<Vec<_>>())
            }
            _ => None,
        };
        let mut measured: Vec<(String, crate::Frame, ImageErrors, Vec<crate::metrics::MaskedError>)> = Vec::new();
        for (label, q) in variants {
            progress(Progress::Begin(format!("{name} {label}")));
            let reads = decided_by.as_ref().filter(|_| !has_caustics(q));
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
