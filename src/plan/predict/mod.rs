//! The measuring planner (issue 31): per specular object, the method whose predicted error
//! is lowest for the frame's predicted time on this device.
//!
//! * **Error** is predicted from the object, not its class: per method a ridge regression
//!   over the planner's facts and the knobs (`features`, `error_model`), fitted on a corpus
//!   of scenes generated in code (`scenes::corpus`, measured by `specula corpus` against the exact
//!   tracer into `assets/models/corpus.json`); held-out scenes measure how well it
//!   generalises (`error_model::leave_one_scene_out`). The part every method shares, the
//!   exact tracer's own error (aliasing, at this frame's size and anti-aliasing), is not
//!   predicted but measured on the scene: the CPU reference traces a sample of each
//!   object's pixels (`aliasing`), and the models' aliasing parts are anchored on it.
//! * **Cost** is measured on the device: unit costs per method and workload term
//!   (`cost_model`), fitted on a calibration run of a few corpus scenes (`specula calibrate`,
//!   or automatically the first time a device is seen), cached per device; the stored
//!   calibration of the machine the corpus was measured on ships in
//!   `assets/models/costs.json`.
//! * **The choice** is the budgeted planner's search (`plan::budget`) over per-object
//!   candidates built from these predictions: shared passes paid once, composition cycles
//!   counted, dominated candidates dropped. Without a budget, `auto` spends at most what
//!   `bvh` or the device's exact tracer ([`device_exact`]: ray queries where it has them) is
//!   predicted to cost, and within that takes the fastest choice within [`TOLERANCE_DB`] of
//!   the most accurate one; objects it ray traces get `bvh` unless another scheme is
//!   predicted more than [`SCHEME_MARGIN`] faster (the schemes render one image, and the
//!   unit costs do not rank them reliably).

pub mod aliasing;
pub mod cost_model;
pub mod device;
pub use cost_model::Target;
pub mod error_model;
pub mod features;
mod linear;
pub mod samples;

use std::sync::{Arc, OnceLock};

use cost_model::CostModel;
use error_model::ErrorModel;
use features::{error_features, workload, FrameWork, MapWork};
use samples::Corpus;

use super::budget::{self, Budget, Cost, Models, ObjectModel, Prediction, VariantModel};
use super::facts::SceneFacts;
use super::{Choice, Choices, Method};
use crate::error::{Error, Result};
use crate::methods::{BVH, LAYERED, RAY_QUERY};
use crate::quality::Quality;
use crate::scene::Scene;

/// `auto`'s tolerance: choices predicted within this many dB of the most accurate one are
/// as good, and the fastest of them wins (`planner=speed`: [`SPEED_TOLERANCE_DB`]).
pub const TOLERANCE_DB: f64 = 0.5;
pub const SPEED_TOLERANCE_DB: f64 = 3.0;
/// The frame size predictions assume when the caller does not say (`Target::nominal`).
pub const NOMINAL_SIZE: u32 = 512;

const CORPUS_FILE: &str = "assets/models/corpus.json";
const COSTS_FILE: &str = "assets/models/costs.json";

/// The stored corpus (the error models' data).
pub fn stored_corpus() -> Result<&'static Corpus> {
    static C: OnceLock<std::result::Result<Corpus, String>> = OnceLock::new();
    C.get_or_init(|| Corpus::parse(include_str!("../../../assets/models/corpus.json"), CORPUS_FILE).map_err(|e| e.to_string()))
        .as_ref()
        .map_err(|e| Error::invalid(CORPUS_FILE, e.clone()))
}

/// The error models fitted on the stored corpus (empty if it cannot be read, which its own
/// test rules out).
pub fn error_model() -> &'static ErrorModel {
    static M: OnceLock<ErrorModel> = OnceLock::new();
    M.get_or_init(|| stored_corpus().map(|c| ErrorModel::fit(&c.samples, &|_| true)).unwrap_or_default())
}

/// The stored calibration (of the device the corpus was measured on).
pub fn stored_costs() -> Option<&'static CostModel> {
    static C: OnceLock<Option<CostModel>> = OnceLock::new();
    C.get_or_init(|| CostModel::parse(include_str!("../../../assets/models/costs.json"), COSTS_FILE).ok()).as_ref()
}

impl Target {
    /// [`NOMINAL_SIZE`]², on the stored calibration's device.
    pub fn nominal() -> Option<Target> {
        stored_costs().map(|c| Target { size: (NOMINAL_SIZE, NOMINAL_SIZE), costs: Arc::new(c.clone()) })
    }
}

/// Each specular object's pixels at `size`, from the exact first hits of a frame of at
/// most 128 pixels across (scaled up).
fn coverage(scene: &Scene, size: (u32, u32)) -> Vec<f64> {
    let scale = (128.0 / size.0.max(size.1) as f64).min(1.0);
    let small = (((size.0 as f64 * scale).round() as u32).max(1), ((size.1 as f64 * scale).round() as u32).max(1));
    let up = (size.0 as f64 * size.1 as f64) / (small.0 as f64 * small.1 as f64);
    let mut px = vec![0.0; scene.meshes.len()];
    if let Ok(ids) = crate::reference::object_ids(scene, small) {
        for id in ids.into_iter().filter(|&id| id > 0) {
            if let Some(p) = px.get_mut(id as usize - 1) {
                *p += up;
            }
        }
    }
    px
}

/// Per object and method, the predicted cost and error at `target`, in the budgeted
/// planner's format (one variant per entry of `variants`).
pub fn predict_models(scene: &Scene, facts: &SceneFacts, quality: &Quality, target: &Target, variants: &[String]) -> Result<Models> {
    let cube_sizes: Vec<u32> = variants.iter().filter_map(|v| budget::variant_quality(quality, v).ok()).map(|q| q.cube.cube_size).collect();
    let measured = probe(scene, facts, quality, target, &cube_sizes);
    models_measured(scene, facts, quality, target, variants, &measured)
}

/// What [`aliasing::measure`] measures on each object at `target`'s size, the lookups at
/// each of `cube_sizes`.
fn probe(scene: &Scene, facts: &SceneFacts, quality: &Quality, target: &Target, cube_sizes: &[u32]) -> Vec<Option<aliasing::Aliasing>> {
    let mut sizes = cube_sizes.to_vec();
    sizes.sort();
    sizes.dedup();
    let objects = aliasing::references(facts);
    aliasing::measure(scene, quality, target.size, &aliasing::Lookups { objects: &objects, cube_sizes: &sizes })
}

/// [`predict_models`] with the probe's measurements given.
fn models_measured(
    scene: &Scene,
    facts: &SceneFacts,
    quality: &Quality,
    target: &Target,
    variants: &[String],
    measured: &[Option<aliasing::Aliasing>],
) -> Result<Models> {
    let errors = error_model();
    let px = coverage(scene, target.size);
    let mut out = Vec::new();
    // The layered map's layers per (count size, reference point, layers knob): the variants
    // mostly share them, and each count builds a BVH of the scene.
    type Count = (u32, Option<[u32; 3]>, Option<u32>);
    let mut counted: Vec<(Count, (u32, f64))> = Vec::new();
    for v in variants {
        let q = budget::variant_quality(quality, v)?;
        let (aa, aa_n, per_sample) = (q.get("aa"), features::aa_samples(&q).1, q.frame.msaa_per_sample);
        let mut objects = Vec::new();
        let mut base = 0.0;
        let meshes: Vec<usize> = facts.objects.iter().map(|f| f.mesh).collect();
        let frame = FrameWork::new(scene, &meshes, &q, px.iter().sum());
        let key = (q.cube.cube_size.min(64), q.cube.ref_point.map(|p| p.to_array().map(f32::to_bits)), q.layered.layers);
        let layers = match counted.iter().find(|(k, _)| *k == key) {
            Some(&(_, l)) => l,
            None => {
                let l = layered_layers(scene, facts, &q);
                counted.push((key, l));
                l
            }
        };
        for f in &facts.objects {
            let name = &scene.meshes[f.mesh].name;
            let work_of = |m: Method| workload(f, scene, &q, MapWork::of(m, &q, layers, target.size), target.size, px[f.mesh], &frame);
            base = target.costs.base_ms(&work_of(BVH));
            let feats = error_features(f, scene, &q);
            let first = objects.len();
            for &m in Method::ALL.iter().filter(|m| m.is_gpu() && m.fits(f) && is_candidate(**m)) {
                let work = work_of(m);
                let key = error_model::candidate(m.name, v);
                let (Some(psnr), Some((fixed, screen, shared))) = (
                    errors.predict(&key, &feats, (&aa, aa_n, per_sample, q.cube.cube_size), work.screen, measured[f.mesh].as_ref()),
                    target.costs.predict(&key, &work),
                ) else {
                    continue;
                };
                let (cycles, under) = target.costs.methods.get(&key).map_or((1, 1.0), |c| (c.cycles, c.under));
                objects.push(ObjectModel {
                    object: name.clone(),
                    class: f.class.label().to_string(),
                    pixels: work.pixels.round() as usize,
                    method: m.name.to_string(),
                    cost: Cost { fixed_ms: fixed, screen_ms: screen },
                    shared: Cost { fixed_ms: 0.0, screen_ms: shared },
                    cycles,
                    row: String::new(),
                    psnr_db: psnr,
                    under,
                });
            }
            exact_bounds_error(&mut objects[first..]);
        }
        out.push(VariantModel { knobs: v.clone(), base: Cost { fixed_ms: base, screen_ms: 0.0 }, row_bases: Vec::new(), objects });
    }
    Ok(Models {
        format: budget::FORMAT.into(),
        scene: "predicted".into(),
        device: target.costs.key.label(),
        size: [target.size.0, target.size.1],
        variants: out,
    })
}

/// GPU methods that the corpus and the calibration measure (error and cost models exist,
/// `specula corpus --evaluate` reports them) but that the predicted models leave out, so
/// that `auto` and the budgets over them do not choose them (a scene's own models file,
/// `specula tradeoff --calibrate`, still may): image-based reflections, whose error model,
/// fitted on corpus rooms where their filtered captures measured up to 5 dB above the
/// exact tracer's aliased frame on thin panes, predicts them at the exact tracer's 50.7 dB
/// on a thin pane in a box room (capped there, and taken for speed) where they measure
/// 38.6 (proxy-box 40.8; 72×48 against a one-sample reference, `tests/per_object.rs`).
/// Displacement-mapped proxies were here too, predicted at 20.5 dB on a mirror ball in a box
/// room where they measured 51.8: with their height maps drawn from the object's side and
/// their march going on past silhouettes (BENCHMARKS.md) the corpus measures them as it does
/// proxy-box wherever nothing stands between an object and the walls, and they are
/// candidates. Chosen by name they render as any method.
pub const NOT_CANDIDATES: [&str; 1] = ["image-based"];

/// Whether `auto` and the budgets consider method `m` ([`NOT_CANDIDATES`]).
pub fn is_candidate(m: Method) -> bool {
    !NOT_CANDIDATES.contains(&m.name)
}

/// The layers a layered map of every object it could serve would allocate under `q`, and the
/// cubes' worth of faces its peel would draw (its depth complexity counted per face from
/// their boxes' centre, as the plan counts it).
fn layered_layers(scene: &Scene, facts: &SceneFacts, q: &Quality) -> (u32, f64) {
    let meshes: Vec<usize> = facts.objects.iter().filter(|f| LAYERED.fits(f)).map(|f| f.mesh).collect();
    if meshes.is_empty() {
        return (1, 1.0);
    }
    let centre = crate::methods::layered::centre(scene, q, &meshes);
    let extent = crate::methods::layered::peel::extent_on_cpu(scene, centre, q.cube.cube_size.min(64));
    let layers = crate::methods::layered::layers_for(q, Some(extent.depth()));
    (layers, crate::methods::layered::drawn_cubes(q, Some(&extent)))
}

/// One object's candidates in one variant: none is predicted more accurate than the exact
/// tracer at the same knobs (its error is the frame's sampling alone, which every method
/// shares). Each method's error model is fitted apart, and on an object none of them saw
/// the approximate ones can extrapolate past it: corpus-38's mirror torus was predicted
/// better on `layered` than on `bvh` (measured 14.2 against 14.6 dB), which then took a
/// frame budget with a peel twice as slow as predicted. Capped at the exact tracer's
/// prediction, an approximate method is still chosen where it is faster at that accuracy.
fn exact_bounds_error(candidates: &mut [ObjectModel]) {
    let exact = candidates.iter().filter(|o| error_model::model_key(&o.method) == error_model::EXACT).map(|o| o.psnr_db).reduce(f64::max);
    if let Some(cap) = exact {
        for o in candidates.iter_mut() {
            o.psnr_db = o.psnr_db.min(cap);
        }
    }
}

/// The knob variants the planner chooses among (besides the methods): the cube maps' size,
/// the knob most of the map-based methods' error and cost turn on, the frame's
/// anti-aliasing (4-sample multisampling shaded per sample, 2×2 supersampling), and the
/// distance family's hybrid search (ray queries where its maps cannot answer; a candidate
/// only on devices whose calibration measured it, i.e. that have ray queries).
pub fn budget_variants() -> Vec<String> {
    ["default", "cube_size=128", "cube_size=512", "aa=msaa4", "aa=ssaa2", "hybrid=rays"].iter().map(|s| s.to_string()).collect()
}

/// One object's Pareto front: its name, its undominated (knobs, candidate), how many were
/// dominated.
pub type Front<'a> = (String, Vec<(&'a str, &'a ObjectModel)>, usize);

/// Per object, its candidates over every variant of `models` (knobs, method) that no other
/// candidate beats in both predicted time (its own share plus its method's whole-screen
/// kernels) and error, fastest first, and how many were dominated.
pub fn pareto(models: &Models) -> Vec<Front<'_>> {
    let ms = |o: &ObjectModel| o.cost.fixed_ms + o.cost.screen_ms + o.shared.fixed_ms + o.shared.screen_ms;
    let Some(first) = models.variants.first() else { return Vec::new() };
    let mut names: Vec<&str> = first.objects.iter().map(|o| o.object.as_str()).collect();
    names.dedup();
    names
        .into_iter()
        .map(|n| {
            let all: Vec<(&str, &ObjectModel)> = models
                .variants
                .iter()
                .flat_map(|v| v.objects.iter().filter(|o| o.object == n).map(move |o| (v.knobs.as_str(), o)))
                .collect();
            let beats =
                |a: &ObjectModel, b: &ObjectModel| ms(a) <= ms(b) && a.psnr_db >= b.psnr_db && (ms(a) < ms(b) || a.psnr_db > b.psnr_db);
            let mut front: Vec<(&str, &ObjectModel)> = all.iter().copied().filter(|c| !all.iter().any(|d| beats(d.1, c.1))).collect();
            front.sort_by(|a, b| ms(a.1).total_cmp(&ms(b.1)));
            let dominated = all.len() - front.len();
            (n.to_string(), front, dominated)
        })
        .collect()
}

/// Where predictions come from, for reports.
pub fn source(target: &Target) -> String {
    let n = stored_corpus().map_or(0, |c| c.scenes().len());
    format!("predicted (errors: {n} corpus scenes; costs: {})", target.costs.key.label())
}

/// The budgeted choice from predictions: per object a method (and, over `variants`, the
/// frame's knobs), with the prediction. `None` when some object has no candidate.
pub fn choose(
    scene: &Scene,
    choices: &Choices,
    quality: &Quality,
    budget: Budget,
    target: &Target,
    variants: &[String],
) -> Result<Option<(Choices, Quality, Prediction)>> {
    let facts = SceneFacts::new(scene, quality, true);
    let models = predict_models(scene, &facts, quality, target, variants)?;
    budget::choose_with(scene, &facts, choices, quality, budget, target.size, &[(&models, source(target))])
}

/// The knob variants `auto` may choose for a frame asked with `quality`: those of
/// [`budget_variants`] whose every knob the caller left at its default (a knob the caller
/// set is the caller's), none but `default` under `plan_knobs=keep`.
pub fn auto_variants(quality: &Quality) -> Vec<String> {
    let defaults = Quality::default();
    budget_variants()
        .into_iter()
        .filter(|v| {
            v == "default"
                || (quality.plan.plan_knobs
                    && v.split_whitespace().all(|pair| {
                        let k = pair.split('=').next().unwrap_or(pair);
                        crate::quality::knob(k).is_some_and(|k| quality.get(k.name) == defaults.get(k.name))
                    }))
        })
        .collect()
}

/// `auto`'s choice for a scene: per object its method, the frame's knobs (`quality`, the
/// asked ones with the chosen variant's over them), the prediction, and the candidates it
/// was chosen from.
#[derive(Clone, Debug)]
pub struct AutoPlan {
    pub choices: Choices,
    pub quality: Quality,
    pub prediction: Prediction,
    pub models: Models,
    /// Why the exact objects got `bvh` over the scheme predicted fastest (`SCHEME_MARGIN`),
    /// where they did.
    pub note: Option<String>,
}

impl AutoPlan {
    /// Why object `name` got `method`: its prediction and the runner-up (the most accurate
    /// other candidate).
    pub fn reason(&self, name: &str, method: Method) -> String {
        let b = &self.prediction.budget;
        let Some(o) = self.prediction.objects.iter().find(|o| o.name == name) else {
            return format!("auto ({})", b.describe());
        };
        let chosen = self.models.variants.iter().find(|v| v.knobs == self.prediction.knobs).or(self.models.variants.first());
        let others = chosen.map(|v| v.objects.iter().filter(|c| c.object == name && c.method != method.name));
        let runner =
            others.and_then(|it| it.max_by(|a, b| a.psnr_db.total_cmp(&b.psnr_db).then(b.cost.fixed_ms.total_cmp(&a.cost.fixed_ms))));
        let runner = runner.map_or(String::new(), |r| {
            let ms = r.cost.fixed_ms + r.cost.screen_ms + r.shared.screen_ms;
            format!("; runner-up {} ({:.1} dB, {:.1} ms)", r.method, r.psnr_db, ms)
        });
        let knobs = if self.prediction.knobs == "default" { String::new() } else { format!(" with {}", self.prediction.knobs) };
        let note = match &self.note {
            Some(n) if error_model::model_key(method.name) == error_model::EXACT => format!("; {n}"),
            _ => String::new(),
        };
        format!("auto: predicted {:.1} dB, {:.1} ms{knobs}{runner}; budget {}{note}", o.psnr_db, o.ms, b.describe())
    }
}

/// `auto` without a budget: the exact tracers' predicted frame (bvh's or the device's own
/// scheme's, the larger; at the asked knobs) is the
/// budget; within it, over the methods and [`auto_variants`], the fastest choice within the
/// tolerance of the most accurate. `None` when some object has no prediction.
pub fn auto(scene: &Scene, facts: &SceneFacts, choices: &Choices, quality: &Quality, target: &Target) -> Result<Option<AutoPlan>> {
    if facts.objects.is_empty() {
        return Ok(None);
    }
    // One prediction for every variant; the asked knobs are its first ("default").
    let models = predict_models(scene, facts, quality, target, &auto_variants(quality))?;
    let asked = Models { variants: models.variants.iter().take(1).cloned().collect(), ..models.clone() };
    let exact_src = [(&asked, source(target))];
    let src = [(&models, source(target))];
    let run = |c: &Choices, b: Budget| budget::choose_with(scene, facts, c, quality, b, target.size, &src);
    // An exact tracer for every object the caller left to auto: bvh, and the device's own
    // scheme; the budget is the larger of their predicted frames.
    let mut max_ms = f64::NEG_INFINITY;
    let schemes = if device_exact(target) == BVH { vec![BVH] } else { vec![BVH, device_exact(target)] };
    for scheme in schemes {
        let mut exact = choices.clone();
        for f in &facts.objects {
            if !choices.objects.iter().any(|(n, _)| super::names_object(scene, f.mesh, n)) {
                exact.objects.push((scene.meshes[f.mesh].name.clone(), scheme));
            }
        }
        let Some((_, _, e)) = budget::choose_with(scene, facts, &exact, quality, Budget::Within(f64::INFINITY), target.size, &exact_src)?
        else {
            return Ok(None);
        };
        max_ms = max_ms.max(e.frame_ms);
    }
    let Some((_, _, best)) = run(choices, Budget::Within(max_ms))? else { return Ok(None) };
    let tolerance = if quality.plan.planner.speed() { SPEED_TOLERANCE_DB } else { TOLERANCE_DB };
    let floor_db = best.specular_psnr_db - tolerance;
    let Some((mut chosen, quality_chosen, mut prediction)) = run(choices, Budget::Near { max_ms, floor_db })? else { return Ok(None) };
    // Among the exact schemes, which render the same image, bvh (this project's own kernels,
    // whose traversal the calibration times as it runs on any scene) unless another is
    // predicted faster by more than the unit costs can rank them (SCHEME_MARGIN): a device's
    // ray queries traverse the driver's own structure, whose cost the calibration's sphere
    // does not tell (lavapipe: 0.9× bvh's frame on the spheres, 10× on the glass bunny).
    let preferred = BVH;
    let exact = |m: Method| error_model::model_key(m.name) == error_model::EXACT;
    let fixed = |mesh: usize| choices.objects.iter().any(|(n, _)| super::names_object(scene, mesh, n));
    let methods: Vec<(String, Method)> = prediction.objects.iter().map(|o| (o.name.clone(), o.method)).collect();
    let swapped = Choices {
        method: Choice::Auto,
        objects: prediction
            .objects
            .iter()
            .map(|o| (o.name.clone(), if exact(o.method) && !fixed(o.mesh) { preferred } else { o.method }))
            .collect(),
    };
    let mut note = None;
    // A whole choice's prediction at the chosen knobs.
    let same_knobs =
        Models { variants: models.variants.iter().filter(|v| v.knobs == prediction.knobs).cloned().collect(), ..models.clone() };
    let at_chosen_knobs = |c: &Choices| {
        budget::choose_with(scene, facts, c, &quality_chosen, Budget::Within(f64::INFINITY), target.size, &[(&same_knobs, source(target))])
    };
    if swapped.objects != methods {
        if let Some((c, _, p)) = at_chosen_knobs(&swapped)? {
            // The schemes' own work (the frame's base, its own stages and effects, is the same
            // under either, and predicted as well: a frame supersampled 2×2 is mostly base).
            let (own, theirs) = (p.frame_ms - p.base_ms, prediction.frame_ms - prediction.base_ms);
            if own <= theirs * (1.0 + SCHEME_MARGIN) {
                let mut names: Vec<String> =
                    methods.iter().zip(&swapped.objects).filter(|(a, b)| a.1 != b.1).map(|(a, _)| a.1.name.to_string()).collect();
                names.sort();
                names.dedup();
                note = Some(format!(
                    "{preferred} rather than {}: the exact schemes render one image, and its work, predicted at {:.1} ms against {:.1} (besides the frame's own {:.1}), is within the {:.1}× by which the unit costs misrank them",
                    names.join(", "),
                    own,
                    theirs,
                    p.base_ms,
                    1.0 + SCHEME_MARGIN
                ));
                chosen = c;
                prediction = Prediction { budget: prediction.budget, knobs: prediction.knobs, ..p };
            }
        }
    }
    // The exact tracer on every object auto serves, at the chosen knobs, unless the choice is
    // predicted faster than it by more than the unit costs' own error (EXACT_MARGIN): no
    // candidate is predicted more accurate than the exact tracer (`exact_bounds_error`), so a
    // map method is only ever taken for speed, and a map pass the calibration under-predicts
    // can turn the saving into a loss.
    let all_exact = Choices {
        method: Choice::Auto,
        objects: prediction.objects.iter().map(|o| (o.name.clone(), if fixed(o.mesh) { o.method } else { preferred })).collect(),
    };
    let current: Vec<(String, Method)> = prediction.objects.iter().map(|o| (o.name.clone(), o.method)).collect();
    if all_exact.objects != current {
        if let Some((c, _, p)) = at_chosen_knobs(&all_exact)? {
            if p.specular_psnr_db >= prediction.specular_psnr_db - 1e-6 && p.frame_ms <= prediction.frame_ms * (1.0 + EXACT_MARGIN) {
                note = Some(format!(
                    "{preferred} rather than the map methods: as accurate, and its frame, predicted at {:.1} ms against {:.1}, is within the {:.1}× by which the unit costs under-predict map passes",
                    p.frame_ms,
                    prediction.frame_ms,
                    1.0 + EXACT_MARGIN
                ));
                chosen = c;
                prediction = Prediction { budget: prediction.budget, knobs: prediction.knobs, ..p };
            }
        }
    }
    Ok(Some(AutoPlan { choices: chosen, quality: quality_chosen, prediction, models, note }))
}

/// How much faster than the exact tracer a choice of map methods must be predicted for auto
/// to take it (0.5: 1.5× as fast), at no better predicted accuracy (none is better). The
/// unit costs under-predict map passes on this machine by up to 2.2× a frame: corpus-49's
/// planar mirror on `proxy-box` at `cube_size=128` (its cube raster predicted 5.97 ms,
/// measured 13.3 at 64²) beside bvh on its glass sphere measured 1.42–1.55× bvh's whole frame;
/// layered's peel on corpus-38, 2.2× (BENCHMARKS.md).
pub const EXACT_MARGIN: f64 = 0.5;

/// The device's own exact tracer: ray queries where its unit costs measured them (the
/// device has them), else bvh. `auto`'s default budget is its predicted frame.
pub fn device_exact(target: &Target) -> Method {
    if target.costs.methods.contains_key(RAY_QUERY.name) {
        RAY_QUERY
    } else {
        BVH
    }
}

/// How much faster than `bvh` another exact scheme must be predicted for auto to take it
/// (1.0: twice as fast). The schemes render the same image, and the unit costs, fitted at
/// 64² and 192², rank their traversal at 512² wrong by up to 2.3× on this machine (concave
/// mirror: bih predicted 0.63× ray-query's frame, measured 1.47×); ray queries traverse the
/// driver's structure, measured on lavapipe at 0.87–1.0× bvh's frame on the showcase scenes
/// and 10.6× on the glass bunny (`assets/bunny`), predicted 1.6× (BENCHMARKS.md). A GPU whose
/// ray-tracing hardware the calibration measures several times faster than bvh gets them.
pub const SCHEME_MARGIN: f64 = 1.0;

/// Hysteresis: switching from `current` to `next` (per-object methods, every object named)
/// must gain more than this PSNR (within the default budget) ...
pub const SWITCH_DB: f64 = 1.0;
/// ... or save this fraction of the frame at no more than the tolerance's loss, or bring a
/// frame more than 10 % over the budget back within it.
pub const SWITCH_SAVING: f64 = 0.2;

/// Whether `auto` should leave `current` for `next` (each: per-object methods, every
/// object named, and the frame's knobs) on the scene as it is now, and why (both
/// predicted: the frame's ms and its specular PSNR, the budget being the exact tracer's
/// predicted frame at `current`'s knobs as in [`auto`]); `None`: keep `current` (the
/// difference is within the hysteresis, so a choice does not flicker frame to frame).
pub fn switch(
    scene: &Scene,
    facts: &SceneFacts,
    current: (&Choices, &Quality),
    next: (&Choices, &Quality),
    target: &Target,
) -> Result<Option<String>> {
    // Predicted once per distinct set of knobs; measured once where the two differ only in
    // knobs the probe reads per variant (anti-aliasing, cube size).
    let default = ["default".to_string()];
    let same_probe = |a: &Quality, b: &Quality| {
        (a.frame.depth, a.frame.fresnel, a.frame.msaa_per_sample, &a.search, a.envmap.proxy_radius)
            == (b.frame.depth, b.frame.fresnel, b.frame.msaa_per_sample, &b.search, b.envmap.proxy_radius)
    };
    let measured = probe(scene, facts, current.1, target, &[current.1.cube.cube_size, next.1.cube.cube_size]);
    let now = models_measured(scene, facts, current.1, target, &default, &measured)?;
    let then = match next.1 == current.1 {
        true => None,
        false if same_probe(current.1, next.1) => Some(models_measured(scene, facts, next.1, target, &default, &measured)?),
        false => Some(predict_models(scene, facts, next.1, target, &default)?),
    };
    let eval = |c: &Choices, q: &Quality, models: &Models| -> Result<Option<Prediction>> {
        let src = [(models, source(target))];
        Ok(budget::choose_with(scene, facts, c, q, Budget::Within(f64::INFINITY), target.size, &src)?.map(|r| r.2))
    };
    let exact = |m: Method| Choices { method: current.0.method, objects: current.0.objects.iter().map(|(n, _)| (n.clone(), m)).collect() };
    let (a, b, e, d) = (
        eval(current.0, current.1, &now)?,
        eval(next.0, next.1, then.as_ref().unwrap_or(&now))?,
        eval(&exact(BVH), current.1, &now)?,
        eval(&exact(device_exact(target)), current.1, &now)?,
    );
    let (Some(a), Some(b), Some(e), Some(d)) = (a, b, e, d) else {
        return Ok(None);
    };
    let max_ms = e.frame_ms.max(d.frame_ms);
    let better = b.specular_psnr_db > a.specular_psnr_db + SWITCH_DB && b.frame_ms <= max_ms;
    let cheaper = b.frame_ms < a.frame_ms * (1.0 - SWITCH_SAVING) && b.specular_psnr_db >= a.specular_psnr_db - TOLERANCE_DB;
    let back = a.frame_ms > max_ms * 1.1 && b.frame_ms <= max_ms;
    if !(better || cheaper || back) {
        return Ok(None);
    }
    let changed: Vec<String> = b
        .objects
        .iter()
        .zip(&a.objects)
        .filter(|(n, o)| n.method != o.method)
        .map(|(n, o)| format!("{} {} → {}", n.name, o.method.name, n.method.name))
        .chain(super::knob_changes(current.1, next.1))
        .collect();
    Ok(Some(format!(
        "{} (predicted {:.1} dB, {:.2} ms against {:.1} dB, {:.2} ms: {})",
        changed.join(", "),
        b.specular_psnr_db,
        b.frame_ms,
        a.specular_psnr_db,
        a.frame_ms,
        if better {
            "more accurate within the exact tracer's time"
        } else if cheaper {
            "faster at no visible loss"
        } else {
            "back within the exact tracer's time"
        }
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model(method: &str, psnr_db: f64) -> ObjectModel {
        ObjectModel {
            object: "torus".into(),
            class: "mirror".into(),
            pixels: 100,
            method: method.into(),
            cost: Cost { fixed_ms: 1.0, screen_ms: 1.0 },
            shared: Cost { fixed_ms: 0.0, screen_ms: 0.0 },
            cycles: 1,
            row: String::new(),
            psnr_db,
            under: 1.0,
        }
    }

    /// No approximate method is predicted above the exact tracer at the same knobs; those
    /// under it keep their prediction; without an exact candidate nothing changes.
    #[test]
    fn the_exact_tracer_bounds_every_prediction() {
        let mut c = vec![model("layered", 17.0), model("bvh", 14.7), model("envmap", 9.0), model("octree", 14.5)];
        exact_bounds_error(&mut c);
        let got: Vec<f64> = c.iter().map(|o| o.psnr_db).collect();
        assert_eq!(got, [14.7, 14.7, 9.0, 14.5]);
        let mut d = vec![model("layered", 17.0), model("envmap", 9.0)];
        exact_bounds_error(&mut d);
        assert_eq!(d[0].psnr_db, 17.0);
    }
}
