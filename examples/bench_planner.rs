//! The measuring planner (issue 31) measured on corpus scenes its models never saw:
//! `cargo run --example bench_planner -- [SIZE] [FIRST] [COUNT] [VARIANTS]` (default 128,
//! scenes 36…47, variants `default,aa=msaa4,aa=ssaa2`: comma-separated knob variants).
//! Per scene, every GPU method but the two slow software tracers is rendered in every
//! variant (maps rebuilt
//! every frame, the median of three frames after one warm-up), timed and compared with the
//! exact tracer (bvh, supersampled 4×4) object by object, beside what the planner predicted for that object
//! and method on this device; then `auto` itself. Prints Markdown: per scene auto's choice
//! against bvh and the single method nearest auto on the Pareto front; at the end the
//! prediction errors' distributions (|predicted − measured| dB; measured / predicted ms), and
//! writes `docs/predicted-vs-measured-ms.svg/.png` (log10 ms, held-out objects).

use specula::metrics::errors_by_object;
use specula::plan::facts::SceneFacts;
use specula::plan::predict;
use specula::plan::{plan_for, Choices};
use specula::scenes::corpus;
use specula::vk::{Context, DeviceOptions};
use specula::{Choice, Method, Quality};

fn main() -> specula::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let size: u32 = args.first().and_then(|s| s.parse().ok()).unwrap_or(128);
    let first: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(corpus::SIZE);
    let count: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(12);
    let variants: Vec<String> =
        args.get(3).map_or("default,aa=msaa4,aa=ssaa2", |s| s.as_str()).split(',').map(|v| v.trim().to_string()).collect();
    let ctx = Context::new(&DeviceOptions::default())?;
    let target = specula::target_for(&ctx, (size, size)).ok_or_else(|| specula::Error::invalid("device", "no unit costs"))?;
    let mut q = Quality::default();
    q.frame.map_updates_always = true;
    let methods: Vec<Method> = Method::ALL
        .iter()
        .copied()
        .filter(|m| m.is_gpu() && *m != specula::methods::RAY_ENGINE && *m != specula::methods::RAY_HIERARCHY)
        .collect();
    println!("{} at {size}x{size}, maps rebuilt every frame; errors against bvh ssaa4 (PSNR capped at 60 dB)\n", ctx.device_name);
    println!("| scene | auto's choice | auto ms | auto dB | bvh ms | bvh dB | dominated by |");
    println!("|---|---|---|---|---|---|---|");
    let (mut db_err, mut ms_ratio, mut points) = (Vec::new(), Vec::new(), Vec::new());
    // Per variant: (|predicted − measured| dB, measured / predicted ms).
    let mut per_variant: Vec<(String, Vec<f64>, Vec<f64>)> = variants.iter().map(|v| (v.clone(), Vec::new(), Vec::new())).collect();
    let mut dominated_scenes = 0;
    for i in first..first + count {
        let scene = corpus::scene(i)?;
        let facts = SceneFacts::new(&scene, &q, true);
        let models = predict::predict_models(&scene, &facts, &q, &target, &variants)?;
        let ids = specula::reference::object_ids(&scene, (size, size))?;
        let specular: Vec<bool> = scene.meshes.iter().map(|m| scene.materials[m.material].kind.is_specular()).collect();
        let names: Vec<String> = scene.meshes.iter().map(|m| m.name.clone()).collect();
        let reference =
            specula::render(&ctx, &scene, specula::methods::BVH, &specula::tradeoff::reference_quality(&q), (size, size), (1, 1))?;
        let mask: Vec<bool> = ids.iter().map(|&id| id > 0 && specular[id as usize - 1]).collect();
        // (label, ms, dB on all specular pixels)
        let mut rows: Vec<(String, f64, f64)> = Vec::new();
        let mut run = |label: String, choices: &Choices, variant: Option<usize>| -> specula::Result<(f64, f64, String)> {
            let qv = match variant {
                Some(k) => specula::plan::budget::variant_quality(&q, &variants[k])?,
                None => q.clone(),
            };
            let plan = plan_for(&scene, choices, &qv, Some(&target))?;
            let mut chosen: Vec<String> = plan.objects.iter().map(|o| format!("{} {}", o.name, o.method.name)).collect();
            if let Some(k) = plan.prediction.as_ref().map(|p| &p.knobs).filter(|k| *k != "default") {
                chosen.push(k.clone());
            }
            let frame = specula::render_plan(&ctx, &scene, plan.clone(), (size, size), (1, 3))?;
            let passes: Vec<(String, f64)> = frame.passes.iter().map(|p| (p.name.clone(), p.gpu_ms)).collect();
            let ms: f64 = passes.iter().filter(|(n, _)| n != "frame.readback").map(|(_, ms)| ms).sum();
            let all = specula::metrics::masked_error(&frame.image, &reference.image, &mask, "specular")?.map_or(60.0, |e| e.psnr.min(60.0));
            if let Some(k) = variant {
                let regions = errors_by_object(&frame.image, &reference.image, &ids, &specular, &names)?;
                let (per, _) = specula::plan::budget::measured_by_object(&plan, &passes);
                for o in &plan.objects {
                    let Some(m) = models.variants[k].objects.iter().find(|m| m.object == o.name && m.method == o.method.name) else {
                        continue;
                    };
                    let measured_db = regions.iter().find(|r| r.name == o.name).map_or(60.0, |r| r.psnr.min(60.0));
                    let measured_ms = per.iter().find(|(k, ..)| *k == o.mesh).map_or(0.0, |&(_, a, b)| a + b);
                    let predicted_ms = m.cost.fixed_ms + m.cost.screen_ms + m.shared.screen_ms;
                    db_err.push((m.psnr_db - measured_db).abs());
                    per_variant[k].1.push((m.psnr_db - measured_db).abs());
                    if measured_ms > 0.0 && predicted_ms > 0.0 {
                        ms_ratio.push(measured_ms / predicted_ms);
                        per_variant[k].2.push(measured_ms / predicted_ms);
                        points.push((measured_ms.log10(), predicted_ms.log10(), o.method.name.to_string()));
                    }
                }
            }
            rows.push((label, ms, all));
            Ok((ms, all, chosen.join(", ")))
        };
        for (k, v) in variants.iter().enumerate() {
            for &m in &methods {
                let label = if v == "default" { m.name.to_string() } else { format!("{} {v}", m.name) };
                run(label, &Choices::all(m), Some(k))?;
            }
        }
        let (ams, adb, chosen) = run("auto".into(), &Choices::all(Choice::Auto), None)?;
        let bvh = rows.iter().find(|r| r.0 == "bvh").cloned().unwrap();
        let beats: Vec<String> = rows
            .iter()
            .filter(|r| r.0 != "auto" && r.1 * 1.25 < ams && r.2 > adb + 0.5)
            .map(|r| format!("{} ({:.1} ms, {:.1} dB)", r.0, r.1, r.2))
            .collect();
        dominated_scenes += !beats.is_empty() as usize;
        println!(
            "| {} | {chosen} | {ams:.1} | {adb:.1} | {:.1} | {:.1} | {} |",
            corpus::name(i),
            bvh.1,
            bvh.2,
            if beats.is_empty() { "none".to_string() } else { beats.join(", ") }
        );
    }
    let q = |v: &mut Vec<f64>, p: f64| {
        v.sort_by(f64::total_cmp);
        v.get(((v.len().max(1) - 1) as f64 * p).round() as usize).copied().unwrap_or(f64::NAN)
    };
    println!("\nauto dominated (a single method ≥ 1.25× faster and > 0.5 dB better) on {dominated_scenes} of {count} unseen scenes");
    println!(
        "per object and method ({} predictions): |predicted − measured| dB median {:.2}, 90th percentile {:.2}; measured / predicted ms median {:.2}, 10th–90th percentile {:.2}–{:.2}",
        db_err.len(),
        q(&mut db_err, 0.5),
        q(&mut db_err, 0.9),
        q(&mut ms_ratio, 0.5),
        q(&mut ms_ratio, 0.1),
        q(&mut ms_ratio, 0.9)
    );
    for (v, db, ms) in &mut per_variant {
        println!(
            "  {v}: {} predictions, |predicted − measured| dB median {:.2}, 90th percentile {:.2}; measured / predicted ms median {:.2}, 10th–90th percentile {:.2}–{:.2}",
            db.len(),
            q(db, 0.5),
            q(db, 0.9),
            q(ms, 0.5),
            q(ms, 0.1),
            q(ms, 0.9)
        );
    }
    let lo = points.iter().map(|p| p.0.min(p.1)).fold(f64::INFINITY, f64::min).floor();
    let hi = points.iter().map(|p| p.0.max(p.1)).fold(f64::NEG_INFINITY, f64::max).ceil();
    let f = specula::tradeoff::scatter(
        std::path::Path::new("docs/predicted-vs-measured-ms"),
        &points,
        (lo, hi),
        0.3,
        &format!("GPU ms per object on {count} unseen corpus scenes at {size}² ({})", ctx.device_name),
        "measured log10 ms",
        "predicted log10 ms",
    )?;
    println!("wrote {} and {}", f.svg.display(), f.png.display());
    Ok(())
}
