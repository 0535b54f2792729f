//! `specula render`: one image (GPU method, or the CPU reference) and its profile.

use std::path::Path;

use crate::args::{context, prepare, reference_summary, reference_timing, render_reference, write_image, RenderArgs};
use crate::budget::BudgetArgs;

pub fn run(args: &RenderArgs, out: &Path, profile: Option<&Path>, budget: &BudgetArgs) -> specula::Result<()> {
    let mut job = prepare(args)?;
    let prediction = crate::budget::apply(&mut job, &args.scene, budget)?;
    if job.cpu_method().is_some() {
        let (img, ms) = render_reference(&job.scene, &job.quality, (job.width, job.height))?;
        write_image(out, &img)?;
        println!("{}", reference_summary(&job.quality, job.width, job.height, ms));
        if let Some(p) = profile {
            let passes = [reference_timing(ms)];
            specula::output::write_file(p, specula::profile::chrome_trace(&passes, &[], "CPU").as_bytes())?;
        }
        return Ok(());
    }
    let ctx = context(args.validate, &args.device)?;
    let asked = job.plan(&job.quality)?;
    // What this device cannot run (ray-query without ray queries) gives way to its fallback,
    // said here as the renderer would.
    let plan = asked.clone().for_device(&job.scene, |m| m.needs.missing_on(&ctx))?;
    for (o, _) in plan.objects.iter().zip(&asked.objects).filter(|(o, a)| o.method != a.method) {
        eprintln!("specula: object '{}' gets {}: {}", o.name, o.method.name(), o.reason.rsplit("; ").next().unwrap_or(&o.reason));
    }
    // Auto's own prediction where no budget made one.
    let prediction = prediction.or_else(|| plan.prediction.clone());
    let budget_plan = prediction.as_ref().map(|_| plan.clone());
    let methods: Vec<String> = plan.objects.iter().map(|o| format!("{}: {}", o.name, o.method.name())).collect();
    let mut rebuilt = Vec::new();
    let frame = specula::render_frames(&ctx, &job.scene, plan, (job.width, job.height), (args.warmup, args.frames), |k, f| {
        let maps: Vec<String> = f.map_updates.iter().map(|u| format!("{} ({})", u.stage, u.reason)).collect();
        rebuilt.push(format!("frame {k}: maps rebuilt: {}", if maps.is_empty() { "none".to_string() } else { maps.join(", ") }));
    })?;
    write_image(out, &frame.image)?;
    println!("{} on {} ({}), {}x{}", job.label(), ctx.device_name, ctx.driver_info, job.width, job.height);
    if !methods.is_empty() {
        println!("objects: {}", methods.join(", "));
    }
    for line in &rebuilt {
        println!("{line}");
    }
    print!("{}", specula::profile::table(&frame.passes, &frame.memory));
    for (name, value) in &frame.stats {
        println!("{name:<40} {value:>12.4}");
    }
    if let Some((_, n)) = frame.stats.iter().find(|(k, _)| k == "raytrace.dropped_rays").filter(|(_, n)| *n > 0.0) {
        let weight = frame.stats.iter().find(|(k, _)| k == "raytrace.dropped_weight").map_or(0.0, |(_, w)| *w);
        eprintln!(
            "specula: warning: {n} rays did not fit in their queues and were dropped, the lightest paths first (path weight {weight:.3} in all, a camera ray weighing 1: their light is missing); raise the ray_budget knob"
        );
    }
    if let (Some(pr), Some(plan)) = (&prediction, &budget_plan) {
        // What the frame measured beside the prediction: each object's share of the passes,
        // and its PSNR against the exact tracer (bvh supersampled 4×4, rendered now at the same
        // size: what the error models predict).
        let passes: Vec<(String, f64)> = frame.passes.iter().map(|p| (p.name.clone(), p.gpu_ms)).collect();
        let (costs, base) = specula::plan::budget::measured_by_object(plan, &passes);
        let frame_ms: f64 = passes.iter().filter(|(n, _)| n != "frame.readback").map(|(_, ms)| ms).sum();
        let size = (job.width, job.height);
        let reference =
            specula::render(&ctx, &job.scene, specula::methods::BVH, &specula::tradeoff::reference_quality(&job.quality), size, (1, 1))?
                .image;
        let ids = specula::reference::object_ids(&job.scene, size)?;
        let specular: Vec<bool> = job.scene.meshes.iter().map(|m| job.scene.materials[m.material].kind.is_specular()).collect();
        let names: Vec<String> = job.scene.meshes.iter().map(|m| m.name.clone()).collect();
        let regions = specula::metrics::errors_by_object(&frame.image, &reference, &ids, &specular, &names)?;
        let psnr = |name: &str| regions.iter().find(|e| e.name == name).map(|e| e.psnr);
        let objects: Vec<specula::plan::budget::ObjectMeasured> = pr
            .objects
            .iter()
            .map(|o| {
                let (maps_ms, camera_ms) = costs.iter().find(|(m, ..)| *m == o.mesh).map_or((0.0, 0.0), |&(_, a, b)| (a, b));
                specula::plan::budget::ObjectMeasured { maps_ms, camera_ms, psnr_db: psnr(&o.name) }
            })
            .collect();
        println!("\n{}", specula::plan::budget::report(pr, Some((&objects, (frame_ms, psnr("specular"))))));
        println!("(actual: this frame's passes split as the models split them — maps, camera passes and kernels — base {base:.3} ms with its shadow maps and caustics; PSNR against the exact tracer, bvh supersampled 4×4)");
    }
    if let Some(p) = profile {
        let json = specula::profile::chrome_trace(&frame.passes, &frame.memory, &ctx.device_name);
        specula::output::write_file(p, json.as_bytes())?;
    }
    if args.validate {
        println!("validation: {} error(s), {} warning(s)", ctx.validation.error_count(), ctx.validation.warning_count());
    }
    Ok(())
}
