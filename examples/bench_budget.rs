//! The budgeted planner (issue 15) measured: `cargo run --example bench_budget --
//! [SIZE] [FRAMES]` (default 96 and 5). On two scenes (a mirror and a glass sphere in the
//! emissive quadrant room; `specula::scenes::flat_glass`), a calibration study over envmap,
//! distance, refractor-map, planar-refraction and bvh × a knob sweep fits the per-object
//! models; then for several floors (`--min-psnr`) and time budgets (`--max-ms`) taken from
//! the study's own spread, the planner chooses, and the chosen frame is rendered and timed in
//! turns with the configuration it is compared with (the cheapest single method reaching the
//! floor; the row that set the budget), five rounds, the fastest round kept. Prints Markdown:
//! predicted vs measured frame ms and PSNR per object, and measured / budget. (The dev
//! profile is optimised; GPU times are the device's timestamp queries either way.)

use specula::plan::budget::{self, Budget, Models};
use specula::plan::{plan_with, Choices};
use specula::scene::{shapes, Camera, Material, Scene, SurfaceKind};
use specula::tradeoff::{Config, Metric, Row, Sweep};
use specula::vk::{Context, DeviceOptions};
use specula::Quality;

fn spheres() -> specula::Result<Scene> {
    let mut s = Scene::new();
    specula::scenes::emissive_room(&mut s, glam::Vec3::new(0.0, 2.0, 0.0), 2.0)?;
    let glass =
        s.add_material(Material { name: "glass".into(), kind: SurfaceKind::Dielectric { ior: 1.5, thin: false }, ..Default::default() })?;
    // F0 0.9: ν from Schlick's F0 = ((ν-1)/(ν+1))², κ = 0.
    let r = 0.9f32.sqrt();
    let nu = (1.0 + r) / (1.0 - r);
    let mirror = s.add_material(Material {
        name: "mirror".into(),
        kind: SurfaceKind::Mirror { nu: glam::Vec3::splat(nu), kappa: glam::Vec3::ZERO },
        ..Default::default()
    })?;
    s.add_mesh(shapes::uv_sphere("glass", glam::Vec3::new(0.6, 1.5, 0.0), 0.5, 32, 16, glass))?;
    s.add_mesh(shapes::uv_sphere("mirror", glam::Vec3::new(-0.7, 1.5, -0.2), 0.5, 32, 16, mirror))?;
    s.camera = Some(Camera::look_at(glam::Vec3::new(0.0, 1.8, 1.9), glam::Vec3::new(0.0, 1.5, 0.0), 50f32.to_radians()));
    Ok(s)
}

fn floor(row: &Row, objects: &[String]) -> f64 {
    objects.iter().map(|o| row.regions.iter().find(|e| &e.name == o).map_or(f64::NEG_INFINITY, |e| e.psnr)).fold(f64::INFINITY, f64::min)
}

fn main() -> specula::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let size: u32 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(96);
    let frames: u32 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(5);
    let base = {
        let mut knobs = Quality::default();
        knobs.frame.map_updates_always = true;
        knobs
    };
    use specula::methods::*;
    let scenes: Vec<(&str, Scene, Vec<Method>, &str)> = vec![
        ("mirror + glass spheres", spheres()?, vec![ENVMAP, DISTANCE, REFRACTOR_MAP, BVH], "cube_size=32,128"),
        ("flat glass", specula::scenes::flat_glass()?, vec![ENVMAP, REFRACTOR_MAP, PLANAR_REFRACTION, BVH], "mirror_budget=4,32"),
    ];
    let ctx = Context::new(&DeviceOptions::default())?;
    println!("device: {} ({}), {size}², {frames} frames per timing", ctx.device_name, ctx.driver_info);
    for (name, scene, methods, sweep) in scenes {
        let out = std::env::temp_dir().join(format!("specula-bench-budget-{}", std::process::id()));
        let cfg = Config {
            scene: scene.clone(),
            scene_name: name.into(),
            quality: base.clone(),
            sweeps: vec![Sweep::parse(sweep)?],
            each: false,
            methods: methods.iter().map(|&m| m.into()).collect(),
            size: (size, size),
            warmup: 1,
            frames,
            device: DeviceOptions::default(),
            out: out.clone(),
            metric: Metric::Psnr,
            calibrate: Some(out.join("models.json")),
        };
        let report = specula::tradeoff::run(&cfg, &mut |_| {})?;
        let models: Models = report.models.clone().expect("calibrated");
        std::fs::remove_dir_all(&out).ok();
        let objects: Vec<String> = scene.specular_meshes().map(|(_, m)| m.name.clone()).collect();
        let single: Vec<&Row> = report.rows.iter().filter(|r| r.method != "auto").collect();
        let sources = [(&models, format!("{name} calibration"))];
        let config = |r: &Row| -> specula::Result<(Choices, Quality)> {
            Ok((Choices::all(Method::parse(&r.method)?), budget::variant_quality(&base, &r.knobs)?))
        };
        // Timed in turns, the fastest of five rounds kept.
        let times = |configs: &[(Choices, Quality)]| -> specula::Result<Vec<f64>> {
            let mut best = vec![f64::INFINITY; configs.len()];
            for _ in 0..5 {
                for (i, (c, q)) in configs.iter().enumerate() {
                    let f = specula::render_plan(&ctx, &scene, plan_with(&scene, c, q)?, (size, size), (1, frames))?;
                    best[i] = best[i].min(f.passes.iter().filter(|p| p.name != "frame.readback").map(|p| p.gpu_ms).sum());
                }
            }
            Ok(best)
        };
        let reference = specula::reference::render_reference(&scene, &base, (size, size))?;
        let ids = specula::reference::object_ids(&scene, (size, size))?;
        let specular: Vec<bool> = scene.meshes.iter().map(|m| scene.materials[m.material].kind.is_specular()).collect();
        let names: Vec<String> = scene.meshes.iter().map(|m| m.name.clone()).collect();
        let measure_psnr = |c: &Choices, q: &Quality| -> specula::Result<Vec<specula::metrics::MaskedError>> {
            let f = specula::render_plan(&ctx, &scene, plan_with(&scene, c, q)?, (size, size), (1, 1))?;
            specula::metrics::errors_by_object(&f.image, &reference, &ids, &specular, &names)
        };
        println!("\n#### {name}: the study ({} single-method rows)\n", single.len());
        println!("| method | knobs | frame ms | {} |", objects.iter().map(|o| format!("{o} dB")).collect::<Vec<_>>().join(" | "));
        println!("|---|---|---:|{}", "---:|".repeat(objects.len()));
        for r in &single {
            let per: Vec<String> =
                objects.iter().map(|o| r.regions.iter().find(|e| &e.name == o).map_or("-".into(), |e| format!("{:.2}", e.psnr))).collect();
            println!("| {} | {} | {:.3} | {} |", r.method, r.knobs, r.frame_ms, per.join(" | "));
        }
        println!("\n#### {name}: budgets\n");
        println!("| budget | choice | predicted ms | measured ms | measured / budget | compared with | its ms now | ratio | predicted dB per object | measured dB per object |");
        println!("|---|---|---:|---:|---:|---|---:|---:|---|---|");
        let mut floors: Vec<f64> = single.iter().map(|r| floor(r, &objects)).collect();
        floors.sort_by(f64::total_cmp);
        floors.dedup();
        let mut by_time: Vec<&Row> = single.clone();
        by_time.sort_by(|a, b| a.frame_ms.total_cmp(&b.frame_ms));
        let mut cases: Vec<(Budget, &Row)> = Vec::new();
        for k in [floors.len() / 4, floors.len() / 2, floors.len() * 3 / 4] {
            let x = floors[k.min(floors.len() - 1)];
            let cheapest = single.iter().filter(|r| floor(r, &objects) >= x).min_by(|a, b| a.frame_ms.total_cmp(&b.frame_ms)).unwrap();
            cases.push((Budget::MinPsnr(x), cheapest));
        }
        for k in [by_time.len() / 4, by_time.len() / 2, by_time.len() * 3 / 4] {
            let r = by_time[k.min(by_time.len() - 1)];
            cases.push((Budget::MaxMs(r.frame_ms), r));
        }
        for (b, against) in cases {
            let Some((choices, q, p)) = budget::choose(&scene, &Choices::default(), &base, b, (size, size), &sources)? else { continue };
            let t = times(&[(choices.clone(), q.clone()), config(against)?])?;
            let got = measure_psnr(&choices, &q)?;
            let choice = p.whole_scene.clone().map_or_else(
                || p.objects.iter().map(|o| format!("{}={}", o.name, o.method.name)).collect::<Vec<_>>().join(" "),
                |m| format!("--method {m}"),
            );
            let pred: Vec<String> = p.objects.iter().map(|o| format!("{:.1}", o.psnr_db)).collect();
            let meas: Vec<String> =
                p.objects.iter().map(|o| got.iter().find(|e| e.name == o.name).map_or("-".into(), |e| format!("{:.1}", e.psnr))).collect();
            println!(
                "| {} | {choice} {} | {:.3} | {:.3} | {} | {} {} | {:.3} | {:.2} | {} | {} |",
                b.describe(),
                p.knobs,
                p.frame_ms,
                t[0],
                match b {
                    Budget::MaxMs(ms) | Budget::Within(ms) | Budget::Near { max_ms: ms, .. } => format!("{:.2}", t[0] / ms),
                    Budget::MinPsnr(_) => "-".into(),
                },
                against.method,
                against.knobs,
                t[1],
                t[0] / t[1],
                pred.join(" / "),
                meas.join(" / ")
            );
        }
    }
    Ok(())
}
