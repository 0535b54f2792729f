//! `specula tradeoff`: parses the arguments, runs `specula::tradeoff::run` with a progress
//! bar and prints its table.

use std::path::Path;

use specula::tradeoff::{Config, Metric, Progress, Sweep};
use specula::vk::DeviceOptions;
use specula::Choice;

use crate::args::{prepare, reference_summary, RenderArgs, TradeoffArgs};

/// The reference once, then every GPU method × every sweep variant, timed and compared;
/// CSV, the figure (SVG and PNG) and the images into `out`.
pub fn run(a: &TradeoffArgs, sweeps: &[String], each: bool, only: &[String], out: &Path, calibrate: Option<&Path>) -> specula::Result<()> {
    let render_args = RenderArgs {
        scene: a.scene.clone(),
        method: "auto".into(),
        objects: Vec::new(),
        size: a.size.clone(),
        quality: a.quality.clone(),
        env: a.env.clone(),
        camera_pos: None,
        camera_target: None,
        fov: None,
        time: None,
        validate: a.validate,
        device: a.device.clone(),
        warmup: a.warmup,
        frames: a.frames,
    };
    let job = prepare(&render_args)?;
    let sweeps: Vec<Sweep> = sweeps.iter().map(|s| Sweep::parse(s)).collect::<specula::Result<_>>()?;
    let metric = Metric::parse(&a.metric)?;
    let methods = only.iter().map(|n| Choice::parse(n)).collect::<specula::Result<Vec<_>>>()?;
    let (w, h) = (job.width, job.height);
    let quality = job.quality.clone();
    let cfg = Config {
        scene: job.scene,
        scene_name: a.scene.file_name().unwrap_or_default().to_string_lossy().into_owned(),
        quality: job.quality,
        sweeps,
        each,
        methods,
        size: (w, h),
        warmup: a.warmup,
        frames: a.frames,
        device: DeviceOptions { validation: a.validate, device_filter: a.device.clone(), ..Default::default() },
        out: out.to_path_buf(),
        metric,
        calibrate: calibrate.map(Path::to_path_buf),
    };

    let mut bar = None;
    let report = specula::tradeoff::run(&cfg, &mut |p| match p {
        Progress::Start { steps } => {
            let b = indicatif::ProgressBar::new(steps);
            b.set_style(
                indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} [{elapsed_precise}, about {eta} left] {msg}")
                    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            bar = Some(b);
        }
        Progress::Begin(msg) => {
            if let Some(b) = &bar {
                b.set_message(msg);
            }
        }
        Progress::Done => {
            if let Some(b) = &bar {
                b.inc(1);
            }
        }
        Progress::Finished => {
            if let Some(b) = &bar {
                b.finish_and_clear();
            }
        }
    })?;

    println!(
        "{} on {} ({}), {w}x{h}, median of {} frames after {} warm-up",
        a.scene.display(),
        report.device_name,
        report.driver_info,
        a.frames.max(1),
        a.warmup.max(1)
    );
    println!("{}", reference_summary(&quality, w, h, report.reference_ms));
    let width = report.rows.iter().map(|r| r.method.len()).max().unwrap_or(0).max(10);
    println!("\n{:<width$} {:<40} {:>10} {:>10} {:>9} {:>9} {:>9}", "method", "knobs", "frame ms", "RMSE", "PSNR dB", "FLIP", "p99");
    for r in &report.rows {
        let e = &r.errors;
        println!(
            "{:<width$} {:<40} {:>10.3} {:>10.5} {:>9.2} {:>9.5} {:>9.5}",
            r.method, r.knobs, r.frame_ms, e.rmse, e.psnr, e.flip, e.p99_abs
        );
    }
    println!("\nwrote {}, {} and {}", report.csv.display(), report.figure.svg.display(), report.figure.png.display());
    if let (Some(p), Some(m)) = (calibrate, &report.models) {
        let n: usize = m.variants.iter().map(|v| v.objects.len()).sum();
        println!("wrote {} ({} knob variant(s), {n} object × method model(s))", p.display(), m.variants.len());
    }
    if a.validate {
        let (errors, warnings) = report.validation;
        println!("validation: {errors} error(s), {warnings} warning(s)");
    }
    Ok(())
}
