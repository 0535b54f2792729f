//! The measuring planner (issue 31) on scenes its models never saw: corpus scenes numbered
//! past `corpus::SIZE` (the generator continues its pattern; `specula corpus` measured only
//! the first `SIZE`), each rendered at 64² with every GPU method, `auto`, `--max-ms` and
//! `--min-psnr`, errors against the exact tracer (`bvh`) supersampled 4×4
//! (`tradeoff::reference_quality`) on the specular pixels, times as
//! ratios within this run (lavapipe, validation on).
//!
//! Timing noise: each configuration's time is the fastest of two rounds of three frames'
//! medians, measured in turns; a method is "faster" only below 1/1.25 of the other's time.

mod common;

use specula::metrics::errors_by_object;
use specula::plan::budget::Budget;
use specula::plan::predict::{self, error_model, Target};
use specula::plan::{plan_for, Choices};
use specula::scenes::corpus;
use specula::{Choice, Method, Quality, Scene};

const SIZE: (u32, u32) = (64, 64);
/// Three unseen scenes: a mirror torus in a far room; a glass sphere behind an occluder; a
/// planar mirror beside a glass prism.
const UNSEEN: [usize; 3] = [38, 49, 54];
/// An unseen scene where auto is predicted to gain from anti-aliasing at 128² (a mirror
/// sphere in a room: proxy-box with `aa=msaa4` inside the exact tracer's time; measured 33.3
/// dB at 24 ms against bvh's 24.3 dB at 21 ms. Scene 48 took bih with `aa=msaa4` until the
/// exact tracer's error was measured on the object: plain bih then fits and is as accurate).
const AA_SCENE: usize = 60;
/// An unseen scene where auto takes a knob variant at the nominal 512² (a mirror blob:
/// proxy-box with `aa=ssaa2`, predicted 43.8 dB, measured 42.55 against bvh's 32.14. Scenes
/// 46, 58 and 59 took `cube_size=128` until the probe's samples changed).
const KNOB_SCENE: usize = 44;
/// PSNR is capped here (the stored corpus's cap: beyond it an image is the exact tracer's).
const CAP: f64 = 60.0;
const NOISE: f64 = 1.25;
/// Against the best single method's time: the machine's noise and the cost model's spread
/// between schemes that render the same image (bvh, kd-tree and grid measured within 1.4× of
/// each other at 64², in either order from run to run).
const CHOICE: f64 = 1.5;

/// The GPU timings must not share the cores with this file's CPU-heavy tests.
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn turn() -> std::sync::MutexGuard<'static, ()> {
    ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner())
}

#[derive(Clone)]
struct Measured {
    label: String,
    ms: f64,
    /// The specular pixels' PSNR, and the lowest object's.
    psnr: f64,
    floor: f64,
}

/// What every measurement of one scene compares against: the exact tracer supersampled, and
/// which object each pixel shows.
struct Truth {
    reference: specula::Frame,
    ids: Vec<u32>,
    size: (u32, u32),
}

fn measure(
    ctx: &specula::vk::Context,
    scene: &Scene,
    label: &str,
    choices: &Choices,
    q: &Quality,
    target: &Target,
    truth: &Truth,
) -> Measured {
    let plan = plan_for(scene, choices, q, Some(target)).unwrap();
    measure_plan(ctx, scene, label, plan, truth, TIMED)
}

/// One renderer (creating one, its pipelines compiled, costs more than its frames), the
/// median of 5 timed frames per pass after one untimed.
const TIMED: (u32, u32) = (1, 5);

fn measure_plan(
    ctx: &specula::vk::Context,
    scene: &Scene,
    label: &str,
    plan: specula::Plan,
    truth: &Truth,
    frames: (u32, u32),
) -> Measured {
    let frame = specula::render_plan(ctx, scene, plan, truth.size, frames).unwrap();
    let ms = frame.passes.iter().filter(|p| p.name != "frame.readback").map(|p| p.gpu_ms).sum();
    let (reference, ids) = (&truth.reference, &truth.ids);
    let specular: Vec<bool> = scene.meshes.iter().map(|m| scene.materials[m.material].kind.is_specular()).collect();
    let names: Vec<String> = scene.meshes.iter().map(|m| m.name.clone()).collect();
    let mut spec_px = vec![false; ids.len()];
    for (k, &id) in ids.iter().enumerate() {
        spec_px[k] = id > 0 && specular[id as usize - 1];
    }
    let all =
        specula::metrics::masked_error(&frame.image, &reference.image, &spec_px, "specular").unwrap().map_or(CAP, |e| e.psnr.min(CAP));
    let regions = errors_by_object(&frame.image, &reference.image, ids, &specular, &names).unwrap();
    let floor = regions.iter().map(|r| r.psnr.min(CAP)).fold(CAP, f64::min);
    Measured { label: label.into(), ms, psnr: all, floor }
}

/// On each unseen scene: `auto` is within 0.5 dB of the most accurate single method that
/// fits its default budget, the exact tracer's frame (ties within 0.5 dB: the fastest of
/// them), at no more than its time (× `CHOICE`), and no
/// single method is both faster beyond the noise and more accurate by over 0.5 dB (`bvh`
/// above all); `--max-ms T` (T: the median single-method time) renders within 1.25 T and
/// within 1 dB of the most accurate single method measured within T; `--min-psnr P`
/// (P: 4 dB under the best single method's lowest object) reaches P − 1 dB on every object.
#[test]
fn auto_and_budgets_on_unseen_scenes() {
    let _turn = turn();
    let ctx = common::gpu();
    let target = specula::target_for(&ctx, SIZE).expect("unit costs for this device");
    // Where the device has ray queries its calibration measured `ray-query` (a candidate of
    // auto and of every budget); where it has none, nothing did.
    assert_eq!(target.costs.methods.contains_key("ray-query"), ctx.ray_query.is_ok(), "{:?}", target.costs.methods.keys());
    let q = {
        let mut q = Quality::default();
        q.frame.map_updates_always = true;
        q
    };
    // The slow software tracers are exact like bvh and slower everywhere (BENCHMARKS.md);
    // bvh first, since the others' timing depends on it (below). The methods the planner can
    // choose: those its corpus measured (an error model) and that it considers
    // (`predict::NOT_CANDIDATES`: measured, models mispredicting their scenes); another would
    // only move the median budget below without being a candidate.
    let errors = predict::error_model();
    let mut methods: Vec<Method> = Method::ALL
        .iter()
        .copied()
        .filter(|m| m.is_gpu() && *m != specula::methods::RAY_ENGINE && *m != specula::methods::RAY_HIERARCHY)
        .filter(|m| errors.methods.contains_key(error_model::model_key(m.name)) && predict::is_candidate(*m))
        .collect();
    // Which those are, so that a method that loses its model (or a new one without) is seen.
    let unmeasured: Vec<&str> =
        Method::ALL.iter().filter(|m| m.is_gpu() && !errors.methods.contains_key(error_model::model_key(m.name))).map(|m| m.name).collect();
    assert!(unmeasured.is_empty(), "GPU methods the planner's corpus has not measured: {unmeasured:?}");
    methods.sort_by_key(|&m| m != specula::methods::BVH);
    for i in UNSEEN {
        assert!(i >= corpus::SIZE, "scene {i} was measured");
        let scene = corpus::scene(i).unwrap();
        let name = corpus::name(i);
        let reference =
            specula::render(&ctx, &scene, specula::methods::BVH, &specula::tradeoff::reference_quality(&q), SIZE, (1, 1)).unwrap();
        let reference = Truth { reference, ids: specula::reference::object_ids(&scene, SIZE).unwrap(), size: SIZE };
        // A method that serves none of the scene's objects falls back to one measured already:
        // the same plan (stages and per-object methods) is the same frame, measured once.
        let mut singles: Vec<Measured> = Vec::new();
        let mut plans: Vec<specula::Plan> = Vec::new();
        for &m in &methods {
            let plan = plan_for(&scene, &Choices::all(m), &q, Some(&target)).unwrap();
            let same =
                |p: &specula::Plan| p.stages == plan.stages && p.objects.iter().map(|o| o.method).eq(plan.objects.iter().map(|o| o.method));
            // A method whose first frame takes over `SLOW` × the exact tracer's frame is far
            // outside every budget the checks below draw from the singles (the exact tracer's
            // frame, their median time), and cannot dominate auto: that frame is its measure.
            const SLOW: f64 = 3.0;
            let measured = match plans.iter().position(same) {
                Some(k) => Measured { label: m.name.into(), ..singles[k].clone() },
                None => {
                    let first = measure_plan(&ctx, &scene, m.name, plan.clone(), &reference, (0, 1));
                    match singles.first() {
                        Some(bvh) if first.ms > SLOW * bvh.ms => first,
                        _ => measure_plan(&ctx, &scene, m.name, plan.clone(), &reference, TIMED),
                    }
                }
            };
            singles.push(measured);
            plans.push(plan);
        }
        let auto_plan = plan_for(&scene, &Choices::all(Choice::Auto), &q, Some(&target)).unwrap();
        // Where auto's plan is a single method's (same stages, methods and knobs), the two
        // are one frame measured twice: auto's time is the faster of the two measurements.
        let twin = plans
            .iter()
            .position(|p| {
                p.stages == auto_plan.stages
                    && p.quality == auto_plan.quality
                    && p.objects.iter().map(|o| o.method).eq(auto_plan.objects.iter().map(|o| o.method))
            })
            .map(|k| singles[k].ms);
        let auto_methods: Vec<String> = auto_plan
            .objects
            .iter()
            .map(|o| format!("{}={}", scene.meshes[o.mesh].name, o.method.name))
            .chain(
                specula::quality::KNOBS
                    .iter()
                    .filter(|k| auto_plan.quality.get(k.name) != q.get(k.name))
                    .map(|k| format!("{}={}", k.name, auto_plan.quality.get(k.name))),
            )
            .collect();
        let mut auto = measure_plan(&ctx, &scene, "auto", auto_plan, &reference, TIMED);
        auto.ms = auto.ms.min(twin.unwrap_or(f64::INFINITY));
        let table: String = singles
            .iter()
            .chain([&auto])
            .map(|m| format!("\n  {:<24} {:>9.2} ms {:>6.1} dB (lowest object {:.1})", m.label, m.ms, m.psnr, m.floor))
            .collect();
        for s in &singles {
            let dominates = s.ms * NOISE < auto.ms && s.psnr > auto.psnr + 0.5;
            assert!(!dominates, "{name}: {} beats auto in both time and error:{table}", s.label);
        }
        // The default budget is the exact tracer's frame: the best single method within it.
        let bvh_ms = singles.iter().find(|s| s.label == "bvh").unwrap().ms;
        let budget = bvh_ms * NOISE;
        // The exact schemes render one image, and auto takes bvh among them unless another is
        // predicted faster by more than SCHEME_MARGIN: the exact frame auto is held to is
        // bvh's, unless a scheme measured faster beyond that margin (a CI run held auto to
        // octree's 26.7 ms, the fastest of five exact frames within 1.2x of each other).
        let exact = |s: &Measured| error_model::model_key(&s.label) == error_model::EXACT;
        let held = |s: &Measured| match exact(s) && s.ms * (1.0 + predict::SCHEME_MARGIN) >= bvh_ms {
            true => Measured { label: "bvh".into(), ms: bvh_ms, ..s.clone() },
            false => s.clone(),
        };
        let fits: Vec<Measured> = singles.iter().filter(|s| s.ms <= budget).map(held).collect();
        let top = fits.iter().map(|s| s.psnr).fold(f64::NEG_INFINITY, f64::max);
        let best = fits.iter().filter(|s| s.psnr >= top - 0.5).min_by(|a, b| a.ms.total_cmp(&b.ms)).unwrap();
        // A time check that fails is measured again, the two in turns (the machine is shared).
        let (auto_ms, best_ms) = if auto.ms <= CHOICE * best.ms {
            (auto.ms, best.ms)
        } else {
            let m = Method::parse(&best.label).unwrap();
            let again = |label: &str, c: &Choices| {
                (0..3).map(|_| measure(&ctx, &scene, label, c, &q, &target, &reference).ms).fold(f64::INFINITY, f64::min)
            };
            (again("auto", &Choices::all(Choice::Auto)).min(auto.ms), again(&best.label, &Choices::all(m)).min(best.ms))
        };
        // (A knob variant auto took may spend more than the best single method for more
        // accuracy, within the default budget.)
        let richer = auto.psnr > best.psnr + 0.5 && auto_ms <= budget;
        assert!(
            auto.psnr >= best.psnr - 0.5 && (auto_ms <= CHOICE * best_ms || richer),
            "{name}: auto ({}) {:.2} ms {:.1} dB against the best single method {} {:.2} ms {:.1} dB:{table}",
            auto_methods.join(" "),
            auto_ms,
            auto.psnr,
            best.label,
            best_ms,
            best.psnr
        );

        // --max-ms: the median single-method time.
        let mut times: Vec<f64> = singles.iter().map(|s| s.ms).collect();
        times.sort_by(f64::total_cmp);
        let t = times[times.len() / 2];
        let (choices, qt, pred) =
            predict::choose(&scene, &Choices::all(Choice::Auto), &q, Budget::MaxMs(t), &target, &["default".into()]).unwrap().unwrap();
        let mut got = measure(&ctx, &scene, "max-ms", &choices, &qt, &target, &reference);
        // A frame over the budget is measured twice more, the fastest kept (the machine is
        // shared: a CI run measured 79.84 ms where T was 59.14 and the same plan 28 ms before).
        for _ in 0..2 {
            if got.ms <= NOISE * t {
                break;
            }
            got.ms = got.ms.min(measure(&ctx, &scene, "max-ms", &choices, &qt, &target, &reference).ms);
        }
        let best = singles.iter().filter(|s| s.ms <= t).map(|s| s.psnr).fold(f64::NEG_INFINITY, f64::max);
        assert!(
            got.ms <= NOISE * t,
            "{name}: --max-ms {t:.2} rendered {choices:?} with {} in {:.2} ms (predicted {:.2}):{table}",
            specula::quality::KNOBS
                .iter()
                .filter(|k| qt.get(k.name) != q.get(k.name))
                .map(|k| format!("{}={} ", k.name, qt.get(k.name)))
                .collect::<String>(),
            got.ms,
            pred.frame_ms
        );
        assert!(got.psnr >= best - 1.0, "{name}: --max-ms {t:.2} gave {:.1} dB, the best within it {best:.1}:{table}", got.psnr);

        // --min-psnr P: 4 dB under the best single method's lowest object (reachable).
        let p = singles.iter().map(|s| s.floor).fold(f64::NEG_INFINITY, f64::max) - 4.0;
        let (choices, qp, _) =
            predict::choose(&scene, &Choices::all(Choice::Auto), &q, Budget::MinPsnr(p), &target, &["default".into()]).unwrap().unwrap();
        let got = measure(&ctx, &scene, "min-psnr", &choices, &qp, &target, &reference);
        assert!(got.floor >= p - 1.0, "{name}: --min-psnr {p:.1} gave {:.1} dB on its worst object ({choices:?}):{table}", got.floor);
    }
    common::assert_clean(&ctx);
}

/// What the stored models predict for the concave mirror (`builtin:concave-occluder`) at
/// `size` in each of `variants`, with the nominal unit costs.
fn concave_models(size: (u32, u32), variants: &[&str]) -> specula::plan::budget::Models {
    let scene = specula::scenes::builtin("concave-occluder").unwrap().unwrap();
    let q = Quality::default();
    let facts = specula::plan::facts::SceneFacts::new(&scene, &q, true);
    let t = Target { size, ..Target::nominal().unwrap() };
    let variants: Vec<String> = variants.iter().map(|v| v.to_string()).collect();
    predict::predict_models(&scene, &facts, &q, &t, &variants).unwrap()
}

/// The exact schemes render one image and the unit costs misrank them at 512² (bih
/// predicted fastest on the concave mirror, measured 1.47× ray-query's frame; ray queries
/// on lavapipe predicted 1.6× bvh's frame on the glass bunny, measured 10.6×): auto ray
/// traces with bvh and says why, unless another scheme is predicted more than twice as fast
/// (ray queries where the device's calibration times them 10× faster than here).
#[test]
fn auto_ray_traces_with_bvh_unless_another_scheme_is_clearly_faster() {
    let _turn = turn();
    let scene = specula::scenes::builtin("concave-occluder").unwrap().unwrap();
    let t = Target { size: (512, 512), ..Target::nominal().unwrap() };
    let p = plan_for(&scene, &Choices::all(Choice::Auto), &Quality::default(), Some(&t)).unwrap();
    let o = &p.objects[0];
    assert_eq!(o.method, specula::methods::BVH, "{}", o.reason);
    // The scheme predicted fastest, named in the reason (bih, then kd-tree with the light
    // terms' calibration: both predicted 1.5–1.7× faster than bvh here).
    let rather = ["bih", "kd-tree", "grid", "octree", "ray-query"].iter().any(|s| o.reason.contains(&format!("bvh rather than {s}:")));
    assert!(rather, "{}", o.reason);
    // Ray-tracing hardware: ray queries' unit costs a tenth of this machine's.
    let mut costs = (*t.costs).clone();
    let rq = costs.methods.get_mut("ray-query").expect("the nominal costs time ray queries");
    for c in rq.fixed.iter_mut().chain(rq.screen.iter_mut()).chain(rq.shared.iter_mut()) {
        *c *= 0.1;
    }
    let fast = Target { costs: std::sync::Arc::new(costs), ..t.clone() };
    let p = plan_for(&scene, &Choices::all(Choice::Auto), &Quality::default(), Some(&fast)).unwrap();
    assert_eq!(p.objects[0].method, specula::methods::RAY_QUERY, "{}", p.objects[0].reason);
}

/// Anti-aliasing removes at most the exact tracer's aliasing at the frame's size: on the
/// concave mirror at 512² the proxy box's error (its map's, which does not fall with the
/// frame) gains little from multisampling (measured +0.1 dB; predicted +8.4 before the bound),
/// bvh's (aliasing) much; at 128², where the exact tracer aliases more against the proxy
/// box's error, multisampling gains the proxy box more than at 512² (predicted from the
/// measured aliasing and lookups: +0.99 dB against +0.05).
#[test]
fn anti_aliasing_removes_at_most_the_exact_tracers_aliasing_at_the_frames_size() {
    let gain = |method: &str, size: (u32, u32)| {
        let models = concave_models(size, &["default", "aa=msaa4"]);
        let db = |k: usize| models.variants[k].objects.iter().find(|o| o.method == method).map(|o| o.psnr_db).unwrap();
        db(1) - db(0)
    };
    let (proxy, bvh, proxy_base) = (gain("proxy-box", (512, 512)), gain("bvh", (512, 512)), gain("proxy-box", (128, 128)));
    println!("msaa4 gains, predicted: proxy-box {proxy:.2} dB, bvh {bvh:.2} dB at 512²; proxy-box {proxy_base:.2} dB at 128²");
    assert!(
        proxy < 2.0 && bvh > 3.0 && proxy_base > proxy + 0.5,
        "proxy-box {proxy:.2}, bvh {bvh:.2}, proxy-box at 128² {proxy_base:.2} dB"
    );
}

/// The stored unit costs follow the frame's size: a ray tracer's frame has a constant part
/// (dispatches, barriers, resets) and a part per pixel, so bvh on the concave mirror costs
/// far less than 64× more at 512² than at 64² (measured on lavapipe: 11.8 ms at 64², 72–99 ms
/// at 512² when this test was written; 19.5 ms at 64², 29 / 51 ms at 128² / 256² and 106–140
/// ms at 512² on 2026-12-06, 10.8 / 207 ms on 2026-12-07, `specula bench
/// builtin:concave-occluder --method bvh --size NxN -q map_updates=always --frames 3`; a
/// model without the constant predicted 449 ms; the stored calibration, 64² and 256², of
/// 2026-12-07 predicts 10.5 and 189 ms: 18× where 64× would be pixels alone, bounded at
/// half of that), and no method's frame shrinks with
/// its pixels (curved-reflector's does not grow: its calibration frames took 39 / 33 ms and
/// 68 / 73 ms at 64² / 256², its search is over the geometry image, not the pixels).
#[test]
fn unit_costs_follow_the_frame_size() {
    let frame = |size: (u32, u32)| {
        let models = concave_models(size, &["default"]);
        let mut by_method = std::collections::BTreeMap::<String, f64>::new();
        for o in &models.variants[0].objects {
            *by_method.entry(o.method.to_string()).or_default() += o.cost.fixed_ms + o.cost.screen_ms + o.shared.screen_ms;
        }
        by_method
    };
    let (small, large) = (frame((64, 64)), frame((512, 512)));
    println!("predicted ms at 64² and 512²: {:?}", small.iter().map(|(m, v)| format!("{m} {v:.1} / {:.1}", large[m])).collect::<Vec<_>>());
    let bvh = (small["bvh"], large["bvh"]);
    assert!((5.0..25.0).contains(&bvh.0) && (36.0..200.0).contains(&bvh.1), "bvh {bvh:?} ms");
    assert!(bvh.1 / bvh.0 < 32.0, "bvh grows {:.1}× for 64× the pixels", bvh.1 / bvh.0);
    for (m, v) in &small {
        assert!(large[m] >= *v, "{m}: {v:.2} ms at 64², {:.2} at 512²", large[m]);
    }
}

/// The error models generalise: fitted with each corpus scene left out in turn, they predict
/// that scene's objects within a median of `BOUND` dB (the stored corpus: 36 scenes, every
/// method and three cube-map sizes; measured 1.85 dB, BENCHMARKS.md has the distribution).
/// And they follow the frame's size: fitted at 128², they predict the corpus's frames at
/// 256² closer (median and bias) with the size exponents than with the size ignored, and
/// the exact tracers' exponent is edge aliasing's (1: +3 dB per doubling) within ±0.5 while a
/// cube map's error does not fall with the frame.
#[test]
fn error_models_predict_held_out_scenes_and_frame_sizes() {
    let _turn = turn();
    const BOUND: f64 = 3.0;
    use specula::plan::predict::error_model::{
        abs_error_quantiles, leave_one_scene_out, leave_one_scene_out_unsized, ErrorModel, Held, BASE_SCREEN, EXACT,
    };
    let c = predict::stored_corpus().unwrap();
    assert!(c.scenes().len() >= 30, "{} scenes", c.scenes().len());
    let held = leave_one_scene_out(&c.samples);
    assert_eq!(held.len(), c.samples.len(), "every sample predicted with its scene held out");
    // The approximate methods alone (the exact ones sit at the cap and are easy).
    let exact = |h: &Held| ["bvh", "kd-tree", "grid", "ray-engine", "ray-hierarchy"].contains(&h.method.as_str());
    let approx: Vec<_> = held.iter().filter(|h| !exact(h)).cloned().collect();
    let (median, p90) = abs_error_quantiles(&approx);
    assert!(median <= BOUND, "held-out median |predicted − measured| {median:.2} dB (90th percentile {p90:.2})");

    let larger = |h: &Held| h.screen > BASE_SCREEN + 0.5;
    let sized: Vec<Held> = held.into_iter().filter(larger).collect();
    let ignored: Vec<Held> = leave_one_scene_out_unsized(&c.samples).into_iter().filter(larger).collect();
    assert!(sized.len() >= 300 && sized.len() == ignored.len(), "{} samples at a larger size", sized.len());
    let bias = |hs: &[Held]| hs.iter().map(|h| h.predicted_db - h.measured_db).sum::<f64>() / hs.len() as f64;
    let ((m1, _), (m0, _)) = (abs_error_quantiles(&sized), abs_error_quantiles(&ignored));
    let (b1, b0) = (bias(&sized), bias(&ignored));
    assert!(m1 < m0 && b1.abs() < b0.abs(), "at 256²: median {m1:.2} dB, bias {b1:.2} with the size; {m0:.2}, {b0:.2} without");
    let model = ErrorModel::fit(&c.samples, &|_| true);
    let k = |m: &str| model.size.get(m).map_or(f64::NAN, |(k, _)| *k);
    assert!((0.5..=1.5).contains(&k(EXACT)) && k("envmap") < 0.3, "exponents: {:?}", model.size);
}

/// The exact tracer's error measured on each object (`predict::aliasing`, the CPU reference
/// tracing a sample of the object's pixels at the frame's size) predicts the held-out third of
/// the corpus better than the model alone: the exact tracers' own error (their error is
/// aliasing alone, the measured quantity) and every method's, whose aliasing part it
/// anchors. With the measurement an exact tracer's prediction is the measured error, and no
/// method is predicted further above it than the corpus ever measured one.
#[test]
fn measured_exact_error_predicts_held_out_objects() {
    let _turn = turn();
    use specula::plan::predict::aliasing::{probe_corpus, Aliasing};
    use specula::plan::predict::error_model::{
        abs_error_quantiles, leave_one_scene_out, leave_one_scene_out_probed, ErrorModel, Held, EXACT,
    };
    let c = predict::stored_corpus().unwrap();
    let third = |scene: usize| scene.is_multiple_of(3);
    let probes = probe_corpus(&c.samples, &third).unwrap();
    assert!(probes.len() >= 20, "{} objects probed", probes.len());
    let held: Vec<Held> = leave_one_scene_out(&c.samples).into_iter().filter(|h| third(h.scene)).collect();
    let probed: Vec<Held> = leave_one_scene_out_probed(&c.samples, &probes).into_iter().filter(|h| third(h.scene)).collect();
    let exact = |hs: &[Held]| hs.iter().filter(|h| h.method == "bvh").cloned().collect::<Vec<_>>();
    let ((e1, e1p), (e0, e0p)) = (abs_error_quantiles(&exact(&probed)), abs_error_quantiles(&exact(&held)));
    let ((a1, a1p), (a0, a0p)) = (abs_error_quantiles(&probed), abs_error_quantiles(&held));
    let table = format!("exact: {e1:.2}/{e1p:.2} dB measured, {e0:.2}/{e0p:.2} modelled; all: {a1:.2}/{a1p:.2}, {a0:.2}/{a0p:.2}");
    println!("{table} (median/90th percentile |predicted − measured|)");
    assert!(e1 <= 1.5 && e1 < e0 && a1 < a0 && a1p < a0p, "{table}");
    // The cube-map lookups and a solid's self refraction, simulated on the object, predict
    // the map methods (on this third: proxy-box 0.25 dB against 1.94 modelled, distance 0.29
    // against 1.65, refractor-map 0.70 against 6.85).
    for m in ["proxy-box", "distance", "refractor-map"] {
        let of = |hs: &[Held]| abs_error_quantiles(&hs.iter().filter(|h| h.method == m).cloned().collect::<Vec<_>>()).0;
        let (with, without) = (of(&probed), of(&held));
        println!("{m}: {with:.2} dB measured, {without:.2} modelled");
        assert!(with < 0.5 * without, "{m}: held-out median {with:.2} dB with the lookups simulated, {without:.2} without");
    }

    let model = ErrorModel::fit(&c.samples, &|_| true);
    let s = c.samples.iter().find(|s| s.method == "layered" && s.knobs == "default").unwrap();
    let a = Aliasing { pixels: 100, off: 1e-3, msaa4: 2e-4, ssaa2: 3e-4, lookups: Vec::new() };
    let at = |m: &str, aa: &str| model.predict(m, &s.features, (aa, 4.0, true, 256), 512.0 * 512.0, Some(&a)).unwrap();
    assert!((at(EXACT, "off") - 30.0).abs() < 1e-9 && (at("bvh", "msaa4") - 10.0 * 5f64.log10() - 30.0).abs() < 1e-9);
    for m in ["layered", "envmap", "proxy-box", "curved-reflector", "refractor-map"] {
        let most = model.excess.get(m).map_or(f64::INFINITY, |e| e.0.max(0.0));
        for aa in ["off", "msaa4", "ssaa2"] {
            assert!(at(m, aa) <= at(EXACT, aa) + most + 1e-9, "{m} {aa}: {} over the exact {}", at(m, aa), at(EXACT, aa));
        }
    }
}

/// The budget search reaches what it is measured against: within the exact tracer's
/// predicted frame (bvh on every object, the default budget) it finds a choice predicted at
/// least as accurate, on unseen scenes at 64² and 512². (Pruning each object's candidates
/// by their own parts once dropped bvh where another method beat it counting bvh's
/// whole-frame kernels as the object's alone, so bvh on every object, which pays them once,
/// was out of reach: corpus-49's best within that frame came out 5 dB under it.)
#[test]
fn the_search_within_the_exact_frame_is_at_least_as_accurate_as_the_exact_tracer() {
    let _turn = turn();
    let nominal = Target::nominal().unwrap();
    let q = Quality::default();
    for size in [(64, 64), (512, 512)] {
        let t = Target { size, ..nominal.clone() };
        for i in [36, 38, 41, 45, 49, 54] {
            let scene = corpus::scene(i).unwrap();
            let facts = specula::plan::facts::SceneFacts::new(&scene, &q, true);
            let exact = Choices {
                method: Choice::Auto,
                objects: facts.objects.iter().map(|f| (scene.meshes[f.mesh].name.clone(), specula::methods::BVH)).collect(),
            };
            let run = |c: &Choices, b: Budget| predict::choose(&scene, c, &q, b, &t, &predict::budget_variants()).unwrap().unwrap().2;
            let e = run(&exact, Budget::Within(f64::INFINITY));
            let best = run(&Choices::all(Choice::Auto), Budget::Within(e.frame_ms));
            assert!(
                best.met && best.frame_ms <= e.frame_ms && best.specular_psnr_db >= e.specular_psnr_db - 1e-9,
                "{} at {size:?}: best within bvh's {:.2} ms is {:.2} ms {:.2} dB, bvh {:.2} dB ({:?})",
                corpus::name(i),
                e.frame_ms,
                best.frame_ms,
                best.specular_psnr_db,
                e.specular_psnr_db,
                best.objects.iter().map(|o| o.method.name).collect::<Vec<_>>()
            );
        }
    }
}

/// Frames over time: a small camera move keeps `auto`'s choice (hysteresis); a plan whose
/// objects sit on a method far worse than auto's prediction is left, with the reason; and
/// the switch does not go back.
#[test]
fn auto_keeps_its_choice_within_the_hysteresis_and_says_why_it_switches() {
    let _turn = turn();
    let scene = corpus::scene(40).unwrap();
    let q = Quality::default();
    let t = Target::nominal().unwrap();
    let p = plan_for(&scene, &Choices::all(Choice::Auto), &q, Some(&t)).unwrap();
    let methods = |p: &specula::Plan| p.objects.iter().map(|o| o.method.name).collect::<Vec<_>>();
    assert!(p.prediction.is_some() && p.objects.iter().all(|o| o.reason.starts_with("auto: predicted")), "{:?}", p.objects);

    let mut moved = scene.clone();
    let mut cam = moved.camera_or_default();
    cam.position += glam::Vec3::new(0.01, 0.0, 0.0);
    moved.camera = Some(cam);
    let mut kept = p.clone();
    kept.refresh_geometry(&moved).unwrap();
    assert_eq!(methods(&kept), methods(&p));
    // ... without predicting again: within REPLAN_MOTION of where auto last predicted, the
    // anchor stays there. A move beyond it predicts again: the anchor follows, or auto
    // switches (with its reason).
    assert!(kept.anchor.motion(&moved) > 0.0 && kept.anchor.motion(&scene) == 0.0);
    let mut far = scene.clone();
    let mut cam = far.camera_or_default();
    let target = scene.meshes[p.objects[0].mesh].positions[0];
    cam.position += (target - cam.position) * 2.0 * specula::plan::REPLAN_MOTION;
    far.camera = Some(cam);
    assert!(p.anchor.motion(&far) >= specula::plan::REPLAN_MOTION, "{}", p.anchor.motion(&far));
    let mut again = p.clone();
    match again.refresh_geometry(&far) {
        Ok(()) => assert_eq!(again.anchor.motion(&far), 0.0),
        Err(specula::Error::PlanChanged(w)) => assert!(w.starts_with("auto: "), "{w}"),
        Err(e) => panic!("{e}"),
    }

    let facts = specula::plan::facts::SceneFacts::new(&scene, &q, true);
    let on = |m: Method| Choices { method: Choice::Auto, objects: p.objects.iter().map(|o| (o.name.clone(), m)).collect() };
    let auto = Choices { method: Choice::Auto, objects: p.objects.iter().map(|o| (o.name.clone(), o.method)).collect() };
    let envmap = on(specula::methods::ENVMAP);
    if auto != envmap {
        let why =
            predict::switch(&scene, &facts, (&envmap, &q), (&auto, &q), &t).unwrap().expect("auto's choice is far better than envmap");
        assert!(why.contains("envmap →"), "{why}");
        assert_eq!(predict::switch(&scene, &facts, (&auto, &q), (&envmap, &q), &t).unwrap(), None, "and not back");
        // (A plan whose anchor is unknown predicts again at its first move.)
        let mut poor = p.clone();
        poor.objects.iter_mut().for_each(|o| o.method = specula::methods::ENVMAP);
        poor.anchor = Default::default();
        match poor.refresh_geometry(&scene) {
            Err(specula::Error::PlanChanged(w)) => assert!(w.starts_with("auto: "), "{w}"),
            other => panic!("expected a plan change, got {other:?}"),
        }
    }
    // plan_hysteresis=off: a choice that differs from a fresh plan's by any margin is left at
    // the next move (here the first object moved to the method auto ranks second: within the
    // hysteresis, so kept when it is on).
    let mut off = q.clone();
    off.set("plan_hysteresis", "off").unwrap();
    let fresh = plan_for(&scene, &Choices::all(Choice::Auto), &off, Some(&t)).unwrap();
    assert_eq!(methods(&fresh), methods(&p), "the knob changes moves, not the first choice");
    let other = if p.objects[0].method == specula::methods::BVH { specula::methods::KD_TREE } else { specula::methods::BVH };
    let mut near = fresh.clone();
    near.objects[0].method = other;
    match near.refresh_geometry(&moved) {
        Err(specula::Error::PlanChanged(w)) => assert!(w.contains("plan_hysteresis=off") && w.contains(&p.objects[0].name), "{w}"),
        other => panic!("expected a plan change with plan_hysteresis=off, got {other:?}"),
    }
}

/// The cost cache on a real context: a cache file of this device that is corrupt or
/// truncated is a warning naming it and a fresh source (here the stored calibration, made on
/// this very device), never a panic; a cache holding another device's file beside it keeps
/// both.
#[test]
fn a_corrupt_cost_cache_is_named_and_replaced() {
    let _turn = turn();
    use specula::plan::predict::cost_model::{store, CostModel, DeviceKey, FORMAT};
    let ctx = common::gpu();
    let key = specula::plan::predict::device::DeviceKey::of(&ctx);
    let dir = common::scratch_dir("cost-cache");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // Another device's costs, cached beside.
    let other = CostModel {
        format: FORMAT.into(),
        key: DeviceKey { device: key.device ^ 1, ..key.clone() },
        methods: Default::default(),
        base: vec![0.0; 4],
        calibration_s: 0.0,
        bvh_updates: None,
    };
    store(&dir, &other).unwrap();
    std::fs::write(dir.join(key.file_name()), b"{\"format\":\"specula-costs 1\",\"key\":").unwrap();
    let mut warnings = Vec::new();
    let (costs, source) = specula::tradeoff::costs_for(&ctx, Some(dir.clone()), &mut |w| warnings.push(w)).unwrap();
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(warnings[0].contains(&key.file_name()) && warnings[0].contains("re-calibrating"), "{warnings:?}");
    if specula::plan::predict::stored_costs().is_some_and(|s| s.key.label() == key.label()) {
        assert_eq!(source, specula::tradeoff::Source::Stored);
        assert_eq!(costs.key, key);
        // ... and replaced the unreadable file.
        assert_eq!(specula::plan::predict::cost_model::load_cached(&dir, &key).unwrap().map(|c| c.key), Some(key.clone()));
    }
    assert!(dir.join(other.key.file_name()).exists(), "the other device's file is kept");
    std::fs::remove_dir_all(&dir).ok();
    common::assert_clean(&ctx);
}

/// Auto chooses the frame's knobs too (`predict::auto_variants`): only those left at their
/// defaults, none under `plan_knobs=keep`; a plan that took a variant names it in its reason,
/// renders with it, and a small move keeps it (a re-plan starts from the asked knobs).
#[test]
fn auto_chooses_only_the_knobs_left_to_it() {
    let _turn = turn();
    let q = Quality::default();
    assert_eq!(predict::auto_variants(&q), predict::budget_variants());
    let with = |pairs: &[&str]| {
        let mut q = Quality::default();
        pairs.iter().for_each(|p| q.set_pair(p).unwrap());
        q
    };
    let names = |q: &Quality| predict::auto_variants(q);
    assert!(names(&with(&["aa=msaa8"])).iter().all(|v| !v.contains("aa=")), "{:?}", names(&with(&["aa=msaa8"])));
    assert!(names(&with(&["cube_size=1024"])).iter().all(|v| !v.contains("cube_size")));
    assert_eq!(names(&with(&["plan_knobs=keep"])), vec!["default".to_string()]);

    let t = Target::nominal().unwrap();
    let (scene, p) = (KNOB_SCENE..KNOB_SCENE + 1)
        .map(|i| corpus::scene(i).unwrap())
        .map(|s| {
            let p = plan_for(&s, &Choices::all(Choice::Auto), &q, Some(&t)).unwrap();
            (s, p)
        })
        .next()
        .unwrap();
    let knobs = p.prediction.as_ref().unwrap().knobs.clone();
    assert_ne!(knobs, "default", "scene {KNOB_SCENE}: auto is predicted to gain from a knob variant here");
    for pair in knobs.split_whitespace() {
        let (k, v) = pair.split_once('=').unwrap();
        assert_eq!(p.quality.get(k), v, "the plan renders with {pair}");
    }
    assert!(p.objects.iter().any(|o| o.reason.contains(&format!("with {knobs}"))), "{:?}", p.objects);
    let kept = plan_for(&scene, &Choices::all(Choice::Auto), &with(&["plan_knobs=keep"]), Some(&t)).unwrap();
    assert_eq!(kept.quality.get("aa"), "off");
    assert_eq!(kept.quality.get("cube_size"), q.get("cube_size"));
    let mut moved = scene.clone();
    let mut cam = moved.camera_or_default();
    cam.position += glam::Vec3::new(0.01, 0.0, 0.0);
    moved.camera = Some(cam);
    let mut again = p.clone();
    again.refresh_geometry(&moved).expect("a small move keeps the plan and its knobs");
    assert_eq!(again.quality, p.quality);

    // The hybrid search is a candidate of its own where the calibration measured it (this
    // machine's, with ray queries): its own error and cost (it traces where maps fail).
    let facts = specula::plan::facts::SceneFacts::new(&scene, &q, true);
    let models = predict::predict_models(&scene, &facts, &q, &t, &["default".into(), "hybrid=rays".into()]).unwrap();
    let get = |k: usize| {
        let o = models.variants[k].objects.iter().find(|o| o.method == "distance").expect("distance serves the mirror");
        (o.psnr_db, o.cost.fixed_ms + o.cost.screen_ms + o.shared.screen_ms)
    };
    let (plain, hybrid) = (get(0), get(1));
    assert!(hybrid.0 != plain.0 && hybrid.1 > plain.1, "plain {plain:?}, hybrid {hybrid:?}");

    // The hybrid search, chosen by auto on costs of a device with ray queries, is turned off
    // (with the reason) on a device without them; asked for, it is the caller's.
    let distance = Choices::all(Choice::Method(specula::methods::DISTANCE));
    let mut chose = plan_for(&scene, &distance, &q, Some(&t)).unwrap();
    chose.quality.distance.hybrid = specula::methods::distance::knobs::Hybrid::Rays;
    let none = |m: Method| (m == specula::methods::RAY_QUERY).then(|| (specula::methods::BVH, "no ray queries".to_string()));
    let off = chose.clone().for_device(&scene, none).unwrap();
    assert!(!off.quality.distance.hybrid.traces());
    assert!(off.objects.iter().all(|o| o.reason.contains("hybrid=rays cannot run on this device (no ray queries)")), "{:?}", off.objects);
    let asked = plan_for(&scene, &distance, &with(&["hybrid=rays"]), Some(&t)).unwrap().for_device(&scene, none).unwrap();
    assert!(asked.quality.distance.hybrid.traces(), "asked for: kept (the stage then refuses with its reason)");

    // Rendered (128²: at 64² the maps' fixed cost outweighs what anti-aliasing gains, and
    // auto ray traces; this device's costs): the variant auto takes is more accurate than
    // the same methods without it, and the exact tracer does not beat it in both time and
    // error.
    const AA_SIZE: (u32, u32) = (128, 128);
    let aa_scene = corpus::scene(AA_SCENE).unwrap();
    let ctx = common::gpu();
    let target = specula::target_for(&ctx, AA_SIZE).expect("unit costs for this device");
    let q = {
        let mut q = Quality::default();
        q.frame.map_updates_always = true;
        q
    };
    let reference =
        specula::render(&ctx, &aa_scene, specula::methods::BVH, &specula::tradeoff::reference_quality(&q), AA_SIZE, (1, 1)).unwrap();
    let truth = Truth { reference, ids: specula::reference::object_ids(&aa_scene, AA_SIZE).unwrap(), size: AA_SIZE };
    let auto = plan_for(&aa_scene, &Choices::all(Choice::Auto), &q, Some(&target)).unwrap();
    assert_ne!(auto.quality, q, "at 128² too auto takes a variant here: {:?}", auto.prediction);
    let same = Choices { method: Choice::Auto, objects: auto.objects.iter().map(|o| (o.name.clone(), o.method)).collect() };
    let a = measure_plan(&ctx, &aa_scene, "auto", auto, &truth, TIMED);
    let plain = measure(&ctx, &aa_scene, "same methods, asked knobs", &same, &q, &target, &truth);
    let bvh = measure(&ctx, &aa_scene, "bvh", &Choices::all(Choice::Method(specula::methods::BVH)), &q, &target, &truth);
    let table = format!("{:?}", [&a, &plain, &bvh].map(|m| format!("{} {:.2} ms {:.1} dB", m.label, m.ms, m.psnr)));
    println!("{table}");
    assert!(a.psnr > plain.psnr + 0.5, "the variant gains: {table}");
    assert!(!(bvh.ms * NOISE < a.ms && bvh.psnr > a.psnr + 0.5), "bvh dominates auto: {table}");
    common::assert_clean(&ctx);
}

/// A calibration (timing only, no errors) measures each object's pixels — its camera-work
/// unit costs are fitted on them — and times a method under every variant knob it reads: the
/// ray tracers under `cube_size=128 aa=msaa4` (they read `aa`, not `cube_size`). At the
/// sizes after the first it times the variants on `variant_scenes` only.
#[test]
fn a_calibration_measures_pixels_and_the_knobs_a_method_reads() {
    let _turn = turn();
    let ctx = common::gpu();
    let variant = "cube_size=128 aa=msaa4";
    let cfg = specula::tradeoff::Measure {
        scenes: vec![0, 1],
        sizes: vec![(32, 32), (16, 16)],
        variants: vec!["default".into(), variant.into()],
        methods: vec![specula::methods::ENVMAP, specula::methods::BVH],
        sparse: Vec::new(),
        variant_scenes: Some(vec![1]),
        warmup: 1,
        frames: 1,
        base: Quality::default(),
        errors: false,
    };
    let c = specula::tradeoff::measure(&ctx, &cfg, &mut |_| {}).unwrap();
    let scene = corpus::scene(0).unwrap();
    let ids = specula::reference::object_ids(&scene, (32, 32)).unwrap();
    for m in ["envmap", "bvh"] {
        let s = c
            .samples
            .iter()
            .find(|s| s.method == m && s.scene == 0 && s.knobs == variant)
            .unwrap_or_else(|| panic!("{m} was not measured"));
        let mesh = scene.meshes.iter().position(|x| x.name == s.object).unwrap();
        let px = ids.iter().filter(|&&id| id as usize == mesh + 1).count() as f64;
        assert!(px > 0.0 && s.work.pixels == px, "{m}: {} pixels measured, {px} in the frame", s.work.pixels);
    }
    let measured = |scene: usize, knobs: &str, screen: f64| {
        c.samples.iter().any(|s| s.scene == scene && s.knobs == knobs && s.work.screen == screen && s.method == "bvh")
    };
    for scene in [0, 1] {
        assert!(measured(scene, "default", 256.0) && measured(scene, variant, 1024.0), "scene {scene}");
    }
    assert!(measured(1, variant, 256.0) && !measured(0, variant, 256.0), "the variant at 16² on scene 1 only");

    // The caustics' knobs are every method's where the scene has a light (scene 3), no
    // method's where it has none (scene 0): `caustics=off` is measured on lit scenes only.
    let cfg = specula::tradeoff::Measure {
        scenes: vec![0, 3],
        sizes: vec![(16, 16)],
        variants: vec!["default".into(), "caustics=off".into()],
        methods: vec![specula::methods::BVH],
        variant_scenes: None,
        ..cfg
    };
    let c = specula::tradeoff::measure(&ctx, &cfg, &mut |_| {}).unwrap();
    let off = |scene: usize| c.samples.iter().filter(|s| s.scene == scene && s.knobs == "caustics=off").collect::<Vec<_>>();
    assert!(off(0).is_empty(), "caustics=off measured on an unlit scene");
    assert!(!off(3).is_empty() && off(3).iter().all(|s| s.work.caustic_photons == 0.0), "{:?}", off(3));
    let lit = c.samples.iter().find(|s| s.scene == 3 && s.knobs == "default").unwrap();
    assert!(lit.work.caustic_photons > 0.0 && lit.work.caustic_texels > 0.0, "{:?}", lit.work);
    common::assert_clean(&ctx);
}

/// What a move costs the BVH, as a calibration times it (`measure_bvh_updates`, at small
/// triangle counts here): every way at every count, positive, and a line per way fitted;
/// `specula plan` states the policy with the predicted milliseconds.
#[test]
fn a_calibration_times_how_the_bvh_follows_moves() {
    let _turn = turn();
    let ctx = common::gpu();
    let samples = specula::tradeoff::calibrate::measure_bvh_updates(&ctx, &[300, 3000]).unwrap();
    for way in ["sah", "lbvh", "refit"] {
        let ms: Vec<f64> = samples.iter().filter(|s| s.way == way).map(|s| s.ms).collect();
        assert!(ms.len() == 2 && ms.iter().all(|v| *v > 0.0 && v.is_finite()), "{way}: {samples:?}");
    }
    let c = specula::plan::predict::cost_model::BvhUpdateCosts::fit(&samples).expect("a line per way");
    let target = specula::target_for(&ctx, SIZE).unwrap();
    let mut costs = (*target.costs).clone();
    costs.bvh_updates = Some(c);
    let t = Target { size: SIZE, costs: std::sync::Arc::new(costs) };
    let scene = corpus::scene(0).unwrap();
    let plan = plan_for(&scene, &Choices::all(specula::methods::BVH), &Quality::default(), Some(&t)).unwrap();
    let text = specula::plan::table(&plan, &scene);
    assert!(text.contains("bvh_update=auto") && text.contains("rigid moves refit it on the GPU (refit predicted"), "{text}");
    common::assert_clean(&ctx);
}

/// An unseen scene with a light: a glass blob beside a mirror sphere in a closed room lit by
/// a point light (caustics from both, shadow maps; the calibration's lit scenes are 3 and 7).
const LIT_SCENE: usize = 39;
/// How far a lit frame's measured time may lie from its prediction, either way (measured
/// 0.97–1.63× with the stored calibration, BENCHMARKS.md, "The light in the cost models";
/// before the light terms, envmap's lit frames were predicted up to 12× short).
const LIT_SPREAD: f64 = 2.0;

/// The cost models predict frames with a light and caustics on a scene they never measured:
/// every calibrated method's whole frame (its maps, camera work, shadow maps, the caustics'
/// photons, cubes and projection) within [`LIT_SPREAD`] of its measured time, either way.
#[test]
fn frames_with_a_light_and_caustics_are_predicted_on_an_unseen_scene() {
    let _turn = turn();
    let ctx = common::gpu();
    let target = specula::target_for(&ctx, SIZE).expect("unit costs for this device");
    let scene = corpus::scene(LIT_SCENE).unwrap();
    assert!(LIT_SCENE >= corpus::SIZE && !specula::tradeoff::calibrate::SCENES.contains(&LIT_SCENE) && !scene.lights.is_empty());
    let mut q = Quality::default();
    q.frame.map_updates_always = true;
    let mut rows = String::new();
    let mut ratios: Vec<(f64, String)> = Vec::new();
    let methods = Method::ALL.iter().filter(|m| {
        m.is_gpu()
            && target.costs.methods.contains_key(m.name)
            && **m != specula::methods::RAY_ENGINE
            && **m != specula::methods::RAY_HIERARCHY
    });
    let specular: Vec<String> =
        scene.meshes.iter().filter(|x| scene.materials[x.material].kind.is_specular()).map(|x| x.name.clone()).collect();
    for &m in methods {
        // Every object forced to the method (none where it serves not all of them).
        let all = Choices { method: Choice::Method(m), objects: specular.iter().map(|n| (n.clone(), m)).collect() };
        let within = Budget::Within(specula::plan::budget::prediction::MAX_FRAME_MS);
        let Some((choices, qm, pred)) = predict::choose(&scene, &all, &q, within, &target, &["default".into()]).unwrap() else {
            continue;
        };
        let plan = plan_for(&scene, &choices, &qm, Some(&target)).unwrap();
        assert!(plan.caustics.is_some(), "{}: no caustics planned", m.name);
        let measure = || {
            let frame = specula::render_plan(&ctx, &scene, plan.clone(), SIZE, (1, 3)).unwrap();
            frame.passes.iter().filter(|p| p.name != "frame.readback").map(|p| p.gpu_ms).sum::<f64>()
        };
        let mut ms = measure();
        // A frame over the spread is measured up to twice more, the fastest kept (the machine
        // is shared: noise only slows a frame; a CI run measured distance 2.03x twice in a
        // row, 0.97-1.63x here).
        for _ in 0..2 {
            if ms <= LIT_SPREAD * pred.frame_ms {
                break;
            }
            ms = ms.min(measure());
        }
        let ratio = ms / pred.frame_ms;
        rows += &format!("\n  {:<24} predicted {:>8.2} ms, measured {:>8.2} ({ratio:.2}×)", m.name, pred.frame_ms, ms);
        ratios.push((ratio, m.name.to_string()));
    }
    println!("{}: measured over predicted frame time at {}x{}:{rows}", corpus::name(LIT_SCENE), SIZE.0, SIZE.1);
    // The machine's speed of the moment scales every method alike (a CI run measured every
    // method 1.2-1.7x over its prediction, bvh 1.72x where it measures 1.00x alone): the
    // run's median ratio within the spread, and each method within the spread of it.
    let mut sorted: Vec<f64> = ratios.iter().map(|r| r.0).collect();
    sorted.sort_by(f64::total_cmp);
    let median = sorted.get(sorted.len() / 2).copied().expect("some method is calibrated");
    assert!((1.0 / LIT_SPREAD..=LIT_SPREAD).contains(&median), "the median method {median:.2}× off its prediction:{rows}");
    for (ratio, name) in &ratios {
        let off = (ratio / median).max(median / ratio);
        assert!(off <= LIT_SPREAD, "{name}: {off:.2}× off its prediction relative to the run's median ({median:.2}×):{rows}");
    }
    common::assert_clean(&ctx);
}
