//! `specula bench`: one method, several knob values, one process.

use specula::Quality;

use crate::args::{context, prepare, render_reference, RenderArgs};

/// `specula bench`: every variant in the same process and run, so the machine's noise
/// affects them alike; compare the ratios, not the absolute figures.
pub fn run(args: &RenderArgs, sweep: Option<&str>) -> specula::Result<()> {
    let job = prepare(args)?;
    let variants: Vec<(String, Quality)> = match sweep {
        None => vec![("default".into(), job.quality.clone())],
        Some(s) => {
            let (key, values) = s.split_once('=').ok_or_else(|| specula::Error::invalid("--sweep", "expected knob=v1,v2,..."))?;
            values
                .split(',')
                .map(|v| {
                    let mut q = job.quality.clone();
                    q.set(key, v)?;
                    Ok((format!("{key}={v}"), q))
                })
                .collect::<specula::Result<_>>()?
        }
    };
    if job.cpu_method().is_some() {
        println!(
            "{} on the CPU ({} threads), {}x{}, median of {} renders",
            job.label(),
            rayon::current_num_threads(),
            job.width,
            job.height,
            args.frames.max(1)
        );
        let mut base = None;
        for (label, q) in variants {
            let mut times = Vec::new();
            for _ in 0..args.frames.max(1) {
                times.push(render_reference(&job.scene, &q, (job.width, job.height))?.1);
            }
            times.sort_by(|a, b| a.total_cmp(b));
            let ms = times[times.len() / 2];
            let b = *base.get_or_insert(ms);
            println!("== {label}: {ms:.1} ms CPU ({:.2}x the first variant)", ms / b);
        }
        return Ok(());
    }
    let ctx = context(args.validate, &args.device)?;
    println!(
        "{} on {} ({}), {}x{}, median of {} frames after {} warm-up",
        job.label(),
        ctx.device_name,
        ctx.driver_info,
        job.width,
        job.height,
        args.frames,
        args.warmup
    );
    let mut base = None;
    for (label, q) in variants {
        let f = specula::render_plan(&ctx, &job.scene, job.plan(&q)?, (job.width, job.height), (args.warmup, args.frames))?;
        let ms = f.gpu_ms();
        let b = *base.get_or_insert(ms);
        println!(
            "\n== {label}: frame {ms:.3} ms GPU ({:.2}x the first variant), {:.2} MiB device memory",
            ms / b,
            f.memory_bytes() as f64 / 1048576.0
        );
        for p in &f.passes {
            println!("   {:<22} {:>9.3} ms GPU {:>8.3} ms CPU", p.name, p.gpu_ms, p.cpu_ms);
        }
    }
    Ok(())
}
