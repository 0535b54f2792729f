//! Measuring the corpus (`plan::predict::corpus`) for the measuring planner: per scene, size
//! and knob variant, the exact tracer's image (`bvh`) once, then every method rendered,
//! timed and compared with it object by object; each object's error, its share of the GPU
//! time (`plan::budget::attribute`), its facts and its workload become a `Sample`, each
//! frame's base a `FrameSample`. `specula corpus` runs it over every scene (the error
//! models' data); `specula calibrate` over a few at two sizes (a device's unit costs).

use crate::error::Result;
use crate::methods::{Choice, Method, BVH};
use crate::plan::predict::features::{error_features, workload, MapWork};
use crate::plan::predict::samples::{Corpus, FrameSample, Sample, PSNR_CAP};
use crate::plan::{plan_with, Choices};
use crate::quality::Quality;
use crate::scenes::corpus;
use crate::vk::Context;

/// What [`measure`] renders.
#[derive(Clone, Debug)]
pub struct Measure {
    /// Corpus scene numbers.
    pub scenes: Vec<usize>,
    pub sizes: Vec<(u32, u32)>,
    /// `default` or `knob=value …` over the base knobs; a method is measured in a variant
    /// only when it reads every knob the variant sets or the knob is frame-wide (`aa`) or
    /// the caustics' on a scene with a light, else the variant is its default.
    pub variants: Vec<String>,
    pub methods: Vec<Method>,
    /// Methods measured on every n-th scene only (the slow exact schemes: their cost per
    /// ray is what the calibration needs, not their error, which is the exact tracer's).
    pub sparse: Vec<(Method, usize)>,
    /// The scenes on which a variant other than `default` is measured at the sizes after
    /// the first (`None`: every scene). A calibration times the knobs' per-sample and
    /// per-texel costs at both sizes on a few scenes and each method's own on all: the
    /// variants at the larger size were most of its time.
    pub variant_scenes: Option<Vec<usize>>,
    pub warmup: u32,
    pub frames: u32,
    pub base: Quality,
    /// Whether to measure errors (against [`reference_quality`]'s exact image); a
    /// calibration measures time only.
    pub errors: bool,
}

/// The reference every error is measured against: the exact tracer (bvh) supersampled 4×4
/// per pixel — the image a converged renderer shows, up to what bvh and a path tracer
/// shade differently. (A 1-sample exact image would count the blur of a filtered map lookup,
/// which hides aliasing, as error.)
pub fn reference_quality(q: &Quality) -> Quality {
    let mut r = q.clone();
    r.frame.aa = crate::quality::Aa::Ssaa(4);
    r
}

/// Whether knob `k` is frame-wide (anti-aliasing, shading, depth: every method reads it).
fn frame_wide(k: &str) -> bool {
    crate::frame::knobs::FrameKnobs::KNOBS.iter().any(|f| f.name == k)
}

/// Whether knob `k` is the caustics' (an effect: every method's frame runs it where a light
/// sees a specular object, none where the scene has no light).
fn caustic_knob(k: &str) -> bool {
    crate::methods::caustics::knobs::CausticsKnobs::KNOBS.iter().any(|f| f.name == k)
}

/// Every GPU method of the registry.
pub fn gpu_methods() -> Vec<Method> {
    Method::ALL.iter().copied().filter(|m| m.is_gpu()).collect()
}

/// Renders and measures `cfg`; `progress` hears each step's name.
pub fn measure(ctx: &Context, cfg: &Measure, progress: &mut dyn FnMut(&str)) -> Result<Corpus> {
    let mut out = Corpus::new(crate::plan::predict::device::DeviceKey::of(ctx));
    for &i in &cfg.scenes {
        let scene = corpus::scene(i)?;
        let specular: Vec<bool> = scene.meshes.iter().map(|m| scene.materials[m.material].kind.is_specular()).collect();
        let names: Vec<String> = scene.meshes.iter().map(|m| m.name.clone()).collect();
        let lit = !scene.lights.is_empty();
        for &size in &cfg.sizes {
            let ids = crate::reference::object_ids(&scene, size)?;
            // Each object's pixels, from the exact first hits (with or without errors: a
            // calibration measures none, and its camera-work terms need them).
            let mut object_pixels = vec![0usize; scene.meshes.len() + 1];
            ids.iter().for_each(|&id| object_pixels[(id as usize).min(scene.meshes.len())] += 1);
            for v in &cfg.variants {
                let later_size = cfg.sizes.first().is_some_and(|&s| s != size);
                if v != "default" && later_size && cfg.variant_scenes.as_ref().is_some_and(|s| !s.contains(&i)) {
                    continue;
                }
                let q = crate::plan::budget::variant_quality(&cfg.base, v)?;
                let set: Vec<&str> =
                    if v == "default" { Vec::new() } else { v.split_whitespace().filter_map(|p| p.split('=').next()).collect() };
                progress(&format!("{} {}x{} {v}: bvh ssaa4 (reference)", corpus::name(i), size.0, size.1));
                let reference = if cfg.errors {
                    Some(crate::render_plan(
                        ctx,
                        &scene,
                        plan_with(&scene, &Choices::all(Choice::Method(BVH)), &reference_quality(&q))?,
                        size,
                        (1, 1),
                    )?)
                } else {
                    None
                };
                let facts = crate::plan::facts::SceneFacts::new(&scene, &q, true);
                for &m in &cfg.methods {
                    // A method this device cannot run (ray-query without ray queries) would
                    // measure its fallback under its name: left out, so the planner never
                    // sees costs for it here.
                    // Nor a variant whose knob needs what the device lacks (the hybrid
                    // search's ray queries) for a method that reads it.
                    let unrunnable = set.contains(&"hybrid") && m.knobs.contains(&"hybrid") && ctx.ray_query.is_err();
                    // A variant measures a method when the method reads all its knobs, or
                    // (a calibration, timing only) some of them: `cube_size=128 aa=msaa4`
                    // times the ray tracers' multisampling too (before, it skipped them, and
                    // their multisamples were predicted free; bvh with msaa4 at 512² measures 346
                    // ms against 99 without).
                    let reads = |k: &&str| m.knobs.contains(k) || frame_wide(k) || (lit && caustic_knob(k));
                    let measured = if cfg.errors { set.iter().all(reads) } else { set.is_empty() || set.iter().any(reads) };
                    if !measured || m.needs.missing_on(ctx).is_some() || unrunnable {
                        continue;
                    }
                    if cfg.sparse.iter().any(|(s, n)| *s == m && i % (*n).max(1) != 0) {
                        continue;
                    }
                    progress(&format!("{} {}x{} {v}: {}", corpus::name(i), size.0, size.1, m.name));
                    let plan = plan_with(&scene, &Choices::all(Choice::Method(m)), &q)?;
                    let frame = crate::render_plan(ctx, &scene, plan.clone(), size, (cfg.warmup.max(1), cfg.frames.max(1)))?;
                    let regions = match &reference {
                        Some(r) => crate::metrics::errors_by_object(&frame.image, &r.image, &ids, &specular, &names)?,
                        None => Vec::new(),
                    };
                    let passes: Vec<(String, f64)> = frame.passes.iter().map(|p| (p.name.clone(), p.gpu_ms)).collect();
                    let (costs, base) = crate::plan::budget::attribute(&plan, &passes);
                    let mut any = None;
                    let covered = object_pixels[1..].iter().sum::<usize>() as f64;
                    let caustics = plan.caustics.as_ref().map_or((0.0, 0.0), |c| c.work(&q));
                    let frame = crate::plan::predict::features::FrameWork::with(caustics, covered);
                    for (o, (mesh, own, shared)) in plan.objects.iter().zip(costs) {
                        let Some(f) = facts.objects.iter().find(|f| f.mesh == mesh) else { continue };
                        let pixels = object_pixels[mesh + 1];
                        let psnr = regions.iter().find(|r| r.name == o.name).map_or(PSNR_CAP, |r| r.psnr);
                        let peel = (
                            crate::methods::layered::planned_layers(&plan),
                            crate::methods::layered::drawn_cubes(&q, plan.layered_extent.as_ref()),
                        );
                        let maps = MapWork::of(o.method, &q, peel, size);
                        let work = workload(f, &scene, &q, maps, size, pixels as f64, &frame);
                        any = Some(work);
                        let dup = out.samples.iter().any(|s| {
                            s.scene == i && s.object == o.name && s.method == o.method.name && s.knobs == *v && s.work.screen == work.screen
                        });
                        if dup {
                            continue;
                        }
                        out.samples.push(Sample {
                            scene: i,
                            object: o.name.clone(),
                            method: o.method.name.to_string(),
                            knobs: v.clone(),
                            features: error_features(f, &scene, &q),
                            work,
                            psnr_db: if psnr.is_finite() { psnr.min(PSNR_CAP) } else { PSNR_CAP },
                            fixed_ms: own.fixed_ms,
                            screen_ms: own.screen_ms,
                            shared_ms: shared.fixed_ms + shared.screen_ms,
                            cycles: plan.cycles.max(1),
                        });
                    }
                    if let Some(work) = any {
                        out.frames.push(FrameSample {
                            scene: i,
                            method: m.name.to_string(),
                            knobs: v.clone(),
                            work,
                            base_ms: base.fixed_ms + base.screen_ms,
                        });
                    }
                }
            }
        }
    }
    Ok(out)
}
