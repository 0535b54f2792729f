//! The budgeted planner (issue 15): per specular object a method, and for the frame one set
//! of knob values, chosen from per-object error and cost models so that the frame meets an
//! error floor (`--min-psnr`: every specular object's PSNR on its own pixels) at the least
//! predicted time, or a time budget (`--max-ms`) at the least predicted error.
//!
//! **Models** come from a calibration run (`specula tradeoff --calibrate`): the study renders
//! every method × knob variant; per row, each specular object's PSNR on its own pixels (the
//! reference's object ids) and its share of the GPU time. A pass belongs to the objects whose
//! plan lists it (`ObjectPlan::passes`; a pass no plan lists, e.g. `geometry.mirror_view`,
//! to the objects of its family); what belongs to none is the frame's base (direct light,
//! shadow maps). Map and camera passes work per object (a layer, the object's pixels) and
//! are split evenly among their objects; a ray tracer's kernels run over the whole screen
//! whatever it serves, so they are *shared*: paid once per method a frame uses. Each cost
//! has a fixed part (maps, shadow maps, photons: independent of the output size) and a screen
//! part, scaled by the pixel count when a frame's size differs from the calibration's. Without a calibration the planner uses the
//! stored defaults measured on the bundled scenes (`assets/models/`), matched by object class
//! (mirror, thin or solid dielectric); without those, the rules of the registry.
//!
//! **Choice.** Knob values are global to a frame (one `Quality`), so a choice is one
//! calibrated knob variant and, per object, one method measured with it. Predicted frame ms =
//! base + Σ object shares + Σ shared kernels of the methods used, the maps' share scaled by
//! the frame's inter-object cycles over the calibration row's: objects of different methods
//! compose through cycles (survey §4.3; `plan_with` runs at least two where a map sees a
//! self-refracting object), which a study of whole-scene methods never ran. A choice that
//! gives every object the same method is planned as that whole-scene method, exactly what the
//! study measured. Object o's PSNR is the one measured with its method and variant (other
//! objects' methods change what o reflects only at second order); the specular pixels' PSNR
//! combines the objects' mean squared errors weighted by their pixel counts. The search is
//! exhaustive over the variants and the per-object candidates left after dropping the
//! dominated ones (slower and no more accurate), greedy past [`MAX_COMBINATIONS`].

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::{facts::SceneFacts, Choices, Method, Plan, StageSpec};
use crate::error::{Error, Result};
use crate::quality::Quality;
use crate::scene::Scene;

/// The first line of every models file's `format` field.
pub const FORMAT: &str = "specula-models 1";
/// PSNR is stored capped here (an exact method's infinite PSNR does not fit JSON).
pub const PSNR_CAP: f64 = 200.0;
/// Past this many (variant × per-object candidate) combinations the search is greedy.
pub const MAX_COMBINATIONS: u64 = 2_000_000;

/// GPU milliseconds, split by what they scale with.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Cost {
    /// Passes whose work does not depend on the output size (maps, shadow maps, photons).
    pub fixed_ms: f64,
    /// Passes over the output's pixels.
    pub screen_ms: f64,
}

/// Whether a pass runs once for all the objects of its method (a ray tracer's full-screen
/// kernels) rather than per object.
pub fn shared_pass(name: &str) -> bool {
    name.starts_with("raytrace.")
}

impl Cost {
    /// The cost at `pixels` output pixels, measured at `measured` pixels.
    pub fn at(&self, pixels: f64, measured: f64) -> f64 {
        self.fixed_ms + self.screen_ms * if measured > 0.0 { pixels / measured } else { 1.0 }
    }
    fn add(&mut self, o: Cost, w: f64) {
        self.fixed_ms += o.fixed_ms * w;
        self.screen_ms += o.screen_ms * w;
    }
}

/// One object with one method in one variant.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ObjectModel {
    /// The object's (mesh) name.
    pub object: String,
    /// `ObjectClass::label`.
    pub class: String,
    /// Its pixels in the calibration frame (the reference's first hits).
    pub pixels: usize,
    pub method: String,
    /// Its share of the per-object passes.
    pub cost: Cost,
    /// Its method's shared kernels, whole (see [`shared_pass`]).
    #[serde(default)]
    pub shared: Cost,
    /// Inter-object cycles of the calibration frame (its maps' share covers that many).
    #[serde(default = "one")]
    pub cycles: u32,
    /// The whole-scene method of the calibration row (`method` where it served the object,
    /// else that method's fallback is `method`).
    #[serde(default)]
    pub row: String,
    /// PSNR on its own pixels, capped at [`PSNR_CAP`].
    pub psnr_db: f64,
}

fn one() -> u32 {
    1
}

/// One knob variant of the calibration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VariantModel {
    /// `default`, or `knob=value knob=value` applied over the base knobs.
    pub knobs: String,
    /// What belongs to no object (median over the variant's rows).
    pub base: Cost,
    /// Each whole-scene row's own base (a row predicts exactly its measured frame).
    #[serde(default)]
    pub row_bases: Vec<RowBase>,
    pub objects: Vec<ObjectModel>,
}

/// One calibration row's base.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RowBase {
    pub row: String,
    pub base: Cost,
}

/// Per-object error and cost models of a scene (or, as stored defaults, of a few scenes).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Models {
    pub format: String,
    /// Where they were measured (a scene name, or several joined by `+`).
    pub scene: String,
    pub device: String,
    /// The calibration frames' size.
    pub size: [u32; 2],
    pub variants: Vec<VariantModel>,
}

/// A frame budget.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub enum Budget {
    /// At most this many GPU milliseconds per frame; the least error within it.
    MaxMs(f64),
    /// Every specular object at least this PSNR (dB) on its pixels; the least time.
    MinPsnr(f64),
}

impl Budget {
    /// From the CLI's two options (the C ABI passes 0 as absent); at most one may be set.
    pub fn from_limits(max_ms: Option<f64>, min_psnr: Option<f64>) -> Result<Option<Budget>> {
        match (max_ms, min_psnr) {
            (Some(_), Some(_)) => Err(Error::invalid("budget", "a time budget (max-ms) or a PSNR floor (min-psnr), not both")),
            (Some(ms), None) if !(ms.is_finite() && ms > 0.0) => Err(Error::invalid("max-ms", format!("{ms} is not a positive time"))),
            (None, Some(db)) if !db.is_finite() => Err(Error::invalid("min-psnr", format!("{db} is not a finite PSNR"))),
            (Some(ms), None) => Ok(Some(Budget::MaxMs(ms))),
            (None, Some(db)) => Ok(Some(Budget::MinPsnr(db))),
            (None, None) => Ok(None),
        }
    }
    pub fn describe(&self) -> String {
        // Three decimals at most, trailing zeros dropped.
        let short = |v: f64| format!("{:.3}", v).trim_end_matches('0').trim_end_matches('.').to_string();
        match self {
            Budget::MaxMs(ms) => format!("--max-ms {}", short(*ms)),
            Budget::MinPsnr(db) => format!("--min-psnr {}", short(*db)),
        }
    }
}

/// What the planner predicts for one object.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ObjectPrediction {
    pub mesh: usize,
    pub name: String,
    pub method: Method,
    pub ms: f64,
    pub psnr_db: f64,
    /// Its pixels in the models' frame (weights the specular PSNR).
    pub pixels: usize,
    /// The model it came from: the object's own name, or its class.
    pub model: String,
}

/// The budgeted planner's choice and prediction.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Prediction {
    pub budget: Budget,
    /// The knob variant chosen (`default` or `knob=value …`).
    pub knobs: String,
    pub base_ms: f64,
    pub frame_ms: f64,
    /// The specular pixels' PSNR (the objects' pixel-weighted mean squared error).
    pub specular_psnr_db: f64,
    pub objects: Vec<ObjectPrediction>,
    /// Whether the prediction meets the budget (otherwise: the nearest it could get).
    pub met: bool,
    /// Where the models came from.
    pub source: String,
    /// The whole-scene method chosen (its fallbacks serve the objects it cannot), or `None`
    /// for per-object methods.
    pub whole_scene: Option<String>,
}

/// The stored defaults, measured on the bundled scenes (`assets/models/*.json`, written by
/// `specula tradeoff --calibrate`; see BENCHMARKS.md for the commands).
pub fn stored_defaults() -> Result<Models> {
    let files = [
        ("assets/models/demo.json", include_str!("../../assets/models/demo.json")),
        ("assets/models/mirrors.json", include_str!("../../assets/models/mirrors.json")),
    ];
    let mut all: Vec<Models> = Vec::new();
    for (name, text) in files {
        let mut m = Models::parse(text, name)?;
        // Matched by class only: a user's object that shares a bundled object's name is
        // not that object.
        for o in m.variants.iter_mut().flat_map(|v| v.objects.iter_mut()) {
            o.object = format!("{}:{}", m.scene, o.object);
        }
        all.push(m);
    }
    Ok(Models::merge(all))
}

impl Models {
    pub fn parse(text: &str, what: &str) -> Result<Models> {
        let m: Models = serde_json::from_str(text).map_err(|e| Error::invalid(what.to_string(), format!("not a models file: {e}")))?;
        if m.format != FORMAT {
            return Err(Error::invalid(format!("{what} format"), format!("'{}', expected '{FORMAT}'", crate::error::clip(&m.format))));
        }
        for v in &m.variants {
            variant_quality(&Quality::default(), &v.knobs).map_err(|e| Error::invalid(format!("{what} knobs"), e.to_string()))?;
            for o in &v.objects {
                Method::parse(&o.method).map_err(|e| Error::invalid(format!("{what} object '{}' method", o.object), e.to_string()))?;
                let costs = [o.cost.fixed_ms, o.cost.screen_ms, o.shared.fixed_ms, o.shared.screen_ms];
                let finite = costs.iter().chain([&o.psnr_db]).all(|x| x.is_finite());
                if !finite || costs.iter().any(|c| *c < 0.0) || o.cycles == 0 {
                    return Err(Error::invalid(
                        format!("{what} object '{}'", o.object),
                        format!(
                            "costs {:?} {:?} and PSNR {} must be finite and non-negative, cycles {} at least 1",
                            o.cost, o.shared, o.psnr_db, o.cycles
                        ),
                    ));
                }
            }
        }
        if m.size[0] == 0 || m.size[1] == 0 {
            return Err(Error::invalid(format!("{what} size"), format!("{:?} is empty", m.size)));
        }
        Ok(m)
    }

    pub fn load(path: &Path) -> Result<Models> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Models::parse(&text, &path.display().to_string())
    }

    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// Several scenes' models as one: variants with the same knobs join (objects appended,
    /// base averaged); screen costs are rescaled to the first one's size.
    pub fn merge(all: Vec<Models>) -> Models {
        let mut it = all.into_iter();
        let Some(mut out) = it.next() else {
            return Models { format: FORMAT.into(), scene: String::new(), device: String::new(), size: [1, 1], variants: Vec::new() };
        };
        let px = (out.size[0] * out.size[1]) as f64;
        let mut counts: Vec<f64> = vec![1.0; out.variants.len()];
        for m in it {
            let scale = px / (m.size[0] * m.size[1]) as f64;
            out.scene = format!("{}+{}", out.scene, m.scene);
            for mut v in m.variants {
                v.base.screen_ms *= scale;
                v.row_bases.iter_mut().for_each(|b| b.base.screen_ms *= scale);
                for o in &mut v.objects {
                    o.cost.screen_ms *= scale;
                    o.shared.screen_ms *= scale;
                    o.pixels = (o.pixels as f64 * scale).round() as usize;
                }
                match out.variants.iter().position(|w| w.knobs == v.knobs) {
                    Some(k) => {
                        let n = counts[k];
                        let b = &mut out.variants[k].base;
                        b.fixed_ms = (b.fixed_ms * n + v.base.fixed_ms) / (n + 1.0);
                        b.screen_ms = (b.screen_ms * n + v.base.screen_ms) / (n + 1.0);
                        counts[k] += 1.0;
                        out.variants[k].objects.extend(v.objects);
                        // Rows of several scenes: their bases differ; the variant's mean serves.
                        out.variants[k].row_bases.clear();
                    }
                    None => {
                        out.variants.push(v);
                        counts.push(1.0);
                    }
                }
            }
        }
        out
    }
}

/// `base` with a variant's knobs applied.
pub fn variant_quality(base: &Quality, knobs: &str) -> Result<Quality> {
    let mut q = base.clone();
    if knobs != "default" {
        for pair in knobs.split_whitespace() {
            q.set_pair(pair)?;
        }
    }
    Ok(q)
}

/// Whether pass `name` of plan `p` works independently of the output size.
fn fixed_pass(p: &Plan, name: &str) -> bool {
    p.stages.iter().any(|s| match s {
        StageSpec::Map(m) => m.name == name,
        StageSpec::Upload | StageSpec::Shadows => s.name() == name,
        StageSpec::Caustics => p.caustics.as_ref().is_some_and(|c| c.passes(&p.quality).contains(&name)),
        _ => false,
    })
}

/// A frame's GPU time split by object: per mesh (its share, its method's shared kernels
/// whole), and the rest (base); see the module doc.
pub fn attribute(p: &Plan, passes: &[(String, f64)]) -> (Vec<(usize, Cost, Cost)>, Cost) {
    let mut objects: Vec<(usize, Cost, Cost)> = p.objects.iter().map(|o| (o.mesh, Cost::default(), Cost::default())).collect();
    let mut base = Cost::default();
    for (name, ms) in passes {
        if name == "frame.readback" || !ms.is_finite() {
            continue;
        }
        let part = if fixed_pass(p, name) { Cost { fixed_ms: *ms, screen_ms: 0.0 } } else { Cost { fixed_ms: 0.0, screen_ms: *ms } };
        let mut owners: Vec<usize> = (0..p.objects.len()).filter(|&i| p.objects[i].passes.iter().any(|q| q == name)).collect();
        if owners.is_empty() {
            let family = name.split('.').next().unwrap_or("");
            owners = (0..p.objects.len()).filter(|&i| p.objects[i].method.family == family).collect();
        }
        if owners.is_empty() {
            base.add(part, 1.0);
        } else if shared_pass(name) {
            owners.iter().for_each(|&i| objects[i].2.add(part, 1.0));
        } else {
            let w = 1.0 / owners.len() as f64;
            owners.iter().for_each(|&i| objects[i].1.add(part, w));
        }
    }
    (objects, base)
}

/// What a frame spent per object, as the prediction counts it (its share, plus its
/// method's shared kernels split among the objects that use it), and on the base.
pub fn measured_by_object(p: &Plan, passes: &[(String, f64)]) -> (Vec<(usize, f64)>, f64) {
    let (costs, base) = attribute(p, passes);
    let per = costs
        .iter()
        .zip(&p.objects)
        .map(|((mesh, own, shared), o)| {
            let users = p.objects.iter().filter(|q| q.method == o.method).count().max(1) as f64;
            (*mesh, own.fixed_ms + own.screen_ms + (shared.fixed_ms + shared.screen_ms) / users)
        })
        .collect();
    (per, base.fixed_ms + base.screen_ms)
}

/// One calibration row as the fit needs it.
pub struct Measured<'a> {
    pub knobs: &'a str,
    pub plan: &'a Plan,
    pub passes: &'a [(String, f64)],
    /// The row's error per object name (pixels, PSNR on them).
    pub regions: &'a [crate::metrics::MaskedError],
}

fn mse_of(psnr: f64) -> f64 {
    10f64.powf(-psnr.min(PSNR_CAP) / 10.0)
}

fn psnr_of(mse: f64) -> f64 {
    if mse > 0.0 {
        (-10.0 * mse.log10()).min(PSNR_CAP)
    } else {
        PSNR_CAP
    }
}

/// Fits models from a study's rows: per variant and object, each method the object got (its
/// fallback where the row's method did not serve it) with its cost and PSNR, averaged where
/// several rows measured the same pair; the variant's base is the median of its rows'.
pub fn fit(scene: &Scene, scene_name: &str, device: &str, size: (u32, u32), rows: &[Measured]) -> Models {
    let mut variants: Vec<VariantModel> = Vec::new();
    let mut bases: BTreeMap<String, Vec<Cost>> = BTreeMap::new();
    let mut seen: BTreeMap<(String, String, String), f64> = BTreeMap::new();
    for r in rows {
        // Whole-scene methods only: `auto` mixes methods, whose composition the prediction
        // models itself (cycles), so its rows would count it twice.
        if r.plan.choice == super::Choice::Auto {
            continue;
        }
        let (costs, base) = attribute(r.plan, r.passes);
        bases.entry(r.knobs.to_string()).or_default().push(base);
        let row_name = r.plan.choice.name().to_string();
        let k = match variants.iter().position(|v| v.knobs == r.knobs) {
            Some(k) => k,
            None => {
                variants.push(VariantModel {
                    knobs: r.knobs.to_string(),
                    base: Cost::default(),
                    row_bases: Vec::new(),
                    objects: Vec::new(),
                });
                variants.len() - 1
            }
        };
        if !variants[k].row_bases.iter().any(|b| b.row == row_name) {
            variants[k].row_bases.push(RowBase { row: row_name, base });
        }
        for (o, (mesh, cost, shared)) in r.plan.objects.iter().zip(costs) {
            let name = &scene.meshes[mesh].name;
            let Some(region) = r.regions.iter().find(|e| &e.name == name) else { continue };
            let row = r.plan.choice.name().to_string();
            let key = (r.knobs.to_string(), name.clone(), row.clone());
            let objects = &mut variants[k].objects;
            match objects.iter_mut().find(|m| &m.object == name && m.row == row) {
                Some(m) => {
                    // A running mean (MSE domain for the error).
                    let n = seen[&key];
                    let mean = |a: Cost, b: Cost| Cost {
                        fixed_ms: (a.fixed_ms * n + b.fixed_ms) / (n + 1.0),
                        screen_ms: (a.screen_ms * n + b.screen_ms) / (n + 1.0),
                    };
                    m.cost = mean(m.cost, cost);
                    m.shared = mean(m.shared, shared);
                    m.psnr_db = psnr_of((mse_of(m.psnr_db) * n + mse_of(region.psnr)) / (n + 1.0));
                }
                None => objects.push(ObjectModel {
                    object: name.clone(),
                    class: o.class.label().to_string(),
                    pixels: region.pixels,
                    method: o.method.name.to_string(),
                    cost,
                    shared,
                    cycles: r.plan.cycles.max(1),
                    row,
                    psnr_db: region.psnr.min(PSNR_CAP),
                }),
            }
            *seen.entry(key).or_insert(0.0) += 1.0;
        }
    }
    for v in &mut variants {
        let mut b = bases.remove(&v.knobs).unwrap_or_default();
        b.sort_by(|x, y| (x.fixed_ms + x.screen_ms).total_cmp(&(y.fixed_ms + y.screen_ms)));
        v.base = b.get(b.len() / 2).copied().unwrap_or_default();
    }
    Models { format: FORMAT.into(), scene: scene_name.into(), device: device.into(), size: [size.0, size.1], variants }
}

/// One candidate of one object in one variant (costs at the frame's size).
#[derive(Clone, Debug)]
struct Candidate {
    method: Method,
    /// Its share of the per-object map passes, at `cycles` inter-object cycles.
    fixed: f64,
    /// Its share of the per-object screen passes.
    screen: f64,
    /// Its method's shared kernels, whole.
    shared: f64,
    cycles: u32,
    psnr: f64,
    pixels: usize,
    model: String,
}

/// One knob variant's candidates.
struct VariantCandidates {
    knobs: String,
    base: f64,
    /// Per object its candidates, one per method, for mixed choices.
    per_object: Vec<Vec<Candidate>>,
    /// The whole-scene methods the calibration ran, each with its objects as measured
    /// (fallbacks included, cycles as run) and its own base: choices of their own.
    wholes: Vec<(Method, f64, Vec<Candidate>)>,
}

/// The candidates of every object in every variant, from one models set; `None` when the
/// set covers some object neither by name nor by class.
fn candidates(scene: &Scene, facts: &SceneFacts, choices: &Choices, models: &Models, size: (u32, u32)) -> Option<Vec<VariantCandidates>> {
    let px = size.0 as f64 * size.1 as f64;
    let measured = models.size[0] as f64 * models.size[1] as f64;
    let ratio = if measured > 0.0 { px / measured } else { 1.0 };
    let mut out = Vec::new();
    for v in &models.variants {
        let mut per_object = Vec::new();
        let mut wholes: Vec<(Method, Vec<Candidate>)> = Vec::new();
        let base = v.base.at(px, measured);
        for f in &facts.objects {
            let name = &scene.meshes[f.mesh].name;
            let forced = choices.objects.iter().rev().find(|(n, _)| super::names_object(scene, f.mesh, n)).map(|(_, m)| *m);
            let by_name: Vec<&ObjectModel> = v.objects.iter().filter(|o| &o.object == name).collect();
            let (entries, model) = if by_name.is_empty() {
                (v.objects.iter().filter(|o| o.class == f.class.label()).collect::<Vec<_>>(), format!("class '{}'", f.class.label()))
            } else {
                (by_name, format!("object '{name}'"))
            };
            // The mean over entries (several rows, or several objects of a class).
            let make = |m: Method, es: &[&ObjectModel]| {
                let n = es.len() as f64;
                let mean = |g: &dyn Fn(&ObjectModel) -> f64| es.iter().map(|o| g(o)).sum::<f64>() / n;
                Candidate {
                    method: m,
                    fixed: mean(&|o| o.cost.fixed_ms),
                    screen: mean(&|o| o.cost.screen_ms) * ratio,
                    shared: mean(&|o| o.shared.at(px, measured)),
                    cycles: es.iter().map(|o| o.cycles).max().unwrap_or(1).max(1),
                    psnr: psnr_of(mean(&|o| mse_of(o.psnr_db))),
                    pixels: (mean(&|o| o.pixels as f64) * ratio).round() as usize,
                    model: model.clone(),
                }
            };
            let usable = |m: Method| m.is_gpu() && m.fits(f);
            // Whole-scene rows: per row, this object as that row measured it.
            let mut rows: Vec<&str> = entries.iter().map(|o| o.row.as_str()).filter(|r| !r.is_empty()).collect();
            rows.sort();
            rows.dedup();
            for row in rows {
                let es: Vec<&ObjectModel> = entries.iter().copied().filter(|o| o.row == row).collect();
                let (Ok(r), Ok(m)) = (Method::parse(row), Method::parse(&es[0].method)) else { continue };
                if usable(m) && es.iter().all(|o| o.method == es[0].method) {
                    match wholes.iter_mut().find(|(w, _)| *w == r) {
                        Some((_, list)) => list.push(make(m, &es)),
                        None if per_object.is_empty() => wholes.push((r, vec![make(m, &es)])),
                        None => {}
                    }
                }
            }
            // Keep the whole-scene rows that measured every object so far.
            let k = per_object.len() + 1;
            wholes.retain(|(_, list)| list.len() == k);
            // Per method, for mixed choices.
            let mut list: Vec<Candidate> = Vec::new();
            let mut methods: Vec<&str> = entries.iter().map(|o| o.method.as_str()).collect();
            methods.sort();
            methods.dedup();
            for mname in methods {
                let Ok(m) = Method::parse(mname) else { continue };
                if !usable(m) || forced.is_some_and(|fm| fm != m) {
                    continue;
                }
                let es: Vec<&ObjectModel> = entries.iter().copied().filter(|o| o.method == mname).collect();
                list.push(make(m, &es));
            }
            if list.is_empty() {
                // This variant cannot serve the object (or not with its forced method).
                per_object.clear();
                break;
            }
            // Drop the dominated: another candidate of no higher cost in every part and
            // at least as accurate (strictly better somewhere).
            let le = |d: &Candidate, c: &Candidate| d.fixed <= c.fixed && d.screen <= c.screen && d.shared <= c.shared && d.psnr >= c.psnr;
            let keep: Vec<Candidate> = list
                .iter()
                .enumerate()
                .filter(|(i, c)| !list.iter().enumerate().any(|(j, d)| j != *i && le(d, c) && (!le(c, d) || j < *i)))
                .map(|(_, c)| c.clone())
                .collect();
            per_object.push(keep);
        }
        if per_object.len() == facts.objects.len() {
            // Forced objects: only mixed choices honour them.
            if !choices.objects.is_empty() {
                wholes.clear();
            }
            let wholes = wholes
                .into_iter()
                .map(|(m, list)| {
                    let own = v.row_bases.iter().find(|b| b.row == m.name).map_or(base, |b| b.base.at(px, measured));
                    (m, own, list)
                })
                .collect();
            out.push(VariantCandidates { knobs: v.knobs.clone(), base, per_object, wholes });
        }
    }
    if out.is_empty() && !facts.objects.is_empty() {
        return None;
    }
    Some(out)
}

/// The frame time of a choice (see the module doc): what composition through inter-object
/// cycles adds, from the planner's own rule.
struct Timing<'a> {
    base: f64,
    quality: Quality,
    facts: &'a SceneFacts,
}

impl Timing<'_> {
    /// Whether every object has the same method (planned as that whole-scene method).
    fn uniform(picks: &[&Candidate]) -> bool {
        picks.windows(2).all(|w| w[0].method == w[1].method)
    }

    /// The inter-object cycles `plan_with` runs for these per-object methods.
    fn cycles(&self, picks: &[&Candidate]) -> u32 {
        if Self::uniform(picks) {
            return picks.first().map_or(1, |c| c.cycles);
        }
        let gpu = |m: Method| m.gpu.expect("GPU method");
        let own = picks.iter().map(|c| (gpu(c.method).cycles)(&self.quality)).max().unwrap_or(1).max(1);
        let composes = picks
            .iter()
            .zip(&self.facts.objects)
            .any(|(c, f)| gpu(c.method).map_shading == super::MapShading::Refractor && self.facts.objects.iter().any(|g| g.sees(f.mesh)));
        let latency = picks.iter().any(|c| gpu(c.method).map_shading == super::MapShading::Traced) && self.quality.distance.frame_latency;
        if latency {
            1
        } else if composes {
            own.max(2)
        } else {
            own
        }
    }

    /// The scale of each object's map share: the frame's cycles over its calibration's (1 for
    /// a whole-scene row, which runs as measured).
    fn scale(&self, picks: &[&Candidate], c: &Candidate, whole: bool) -> f64 {
        if whole {
            1.0
        } else {
            self.cycles(picks) as f64 / c.cycles as f64
        }
    }

    fn frame_ms(&self, picks: &[&Candidate], whole: bool) -> f64 {
        let own: f64 = picks.iter().map(|c| c.fixed * self.scale(picks, c, whole) + c.screen).sum();
        let mut methods: Vec<(Method, f64)> = Vec::new();
        for c in picks {
            match methods.iter_mut().find(|(m, _)| *m == c.method) {
                Some((_, s)) => *s = s.max(c.shared),
                None => methods.push((c.method, c.shared)),
            }
        }
        self.base + own + methods.iter().map(|(_, s)| s).sum::<f64>()
    }

    /// Object `i`'s part of the frame: its share, and its method's shared kernels split
    /// among the objects that use it.
    fn object_ms(&self, picks: &[&Candidate], i: usize, whole: bool) -> f64 {
        let c = picks[i];
        let users = picks.iter().filter(|d| d.method == c.method).count().max(1) as f64;
        c.fixed * self.scale(picks, c, whole) + c.screen + c.shared / users
    }
}

/// Pixel-weighted specular PSNR of a choice.
fn combined_psnr(picks: &[&Candidate]) -> f64 {
    let n: f64 = picks.iter().map(|c| c.pixels.max(1) as f64).sum();
    psnr_of(picks.iter().map(|c| c.pixels.max(1) as f64 * mse_of(c.psnr)).sum::<f64>() / n.max(1.0))
}

/// How a choice ranks under a budget: (meets it, score, tie-break), higher better.
fn rank(budget: Budget, ms: f64, picks: &[&Candidate]) -> (bool, f64, f64) {
    let min_psnr = picks.iter().map(|c| c.psnr).fold(f64::INFINITY, f64::min);
    match budget {
        // Within the floor: the fastest; below it: the highest floor, then the fastest.
        Budget::MinPsnr(db) => {
            if min_psnr >= db {
                (true, -ms, 0.0)
            } else {
                (false, min_psnr, -ms)
            }
        }
        // Within the time: the most accurate, then the fastest; over it: the fastest.
        Budget::MaxMs(t) => {
            if ms <= t {
                (true, combined_psnr(picks), -ms)
            } else {
                (false, -ms, combined_psnr(picks))
            }
        }
    }
}

fn better(a: (bool, f64, f64), b: (bool, f64, f64)) -> bool {
    (a.0 && !b.0) || (a.0 == b.0 && (a.1 > b.1 || (a.1 == b.1 && a.2 > b.2)))
}

/// Per object one candidate index, exhaustively or greedily; `time` is the frame's.
fn search(budget: Budget, time: &dyn Fn(&[&Candidate]) -> f64, per_object: &[Vec<Candidate>]) -> Vec<usize> {
    let eval = |idx: &[usize]| {
        let picks: Vec<&Candidate> = idx.iter().zip(per_object).map(|(&i, c)| &c[i]).collect();
        rank(budget, time(&picks), &picks)
    };
    let combos = per_object.iter().try_fold(1u64, |n, c| n.checked_mul(c.len() as u64)).unwrap_or(u64::MAX);
    if combos <= MAX_COMBINATIONS {
        let mut idx = vec![0usize; per_object.len()];
        let mut best = (idx.clone(), eval(&idx));
        loop {
            let mut k = 0;
            while k < idx.len() {
                idx[k] += 1;
                if idx[k] < per_object[k].len() {
                    break;
                }
                idx[k] = 0;
                k += 1;
            }
            if k == idx.len() {
                return best.0;
            }
            let r = eval(&idx);
            if better(r, best.1) {
                best = (idx.clone(), r);
            }
        }
    }
    // Greedy: from each object's cheapest, change one object at a time while that helps.
    let mut idx: Vec<usize> = per_object
        .iter()
        .map(|c| {
            (0..c.len())
                .min_by(|&a, &b| (c[a].fixed + c[a].screen + c[a].shared).total_cmp(&(c[b].fixed + c[b].screen + c[b].shared)))
                .unwrap_or(0)
        })
        .collect();
    let mut cur = eval(&idx);
    loop {
        let mut step = None;
        for k in 0..idx.len() {
            for i in 0..per_object[k].len() {
                let mut t = idx.clone();
                t[k] = i;
                let r = eval(&t);
                if better(r, step.as_ref().map_or(cur, |(_, s)| *s)) {
                    step = Some((t, r));
                }
            }
        }
        match step {
            Some((t, r)) => {
                idx = t;
                cur = r;
            }
            None => return idx,
        }
    }
}

/// The budgeted plan: per object a method and the frame's knobs from the first models set
/// (in `sources`: (models, where from)) that covers every specular object, with its
/// prediction; `None` when none covers them (the caller falls back to the registry's rules
/// and says so). The objects the user forced (`choices.objects`) keep their method; a choice
/// of one method for every object is returned as that whole-scene method.
pub fn choose(
    scene: &Scene,
    choices: &Choices,
    quality: &Quality,
    budget: Budget,
    size: (u32, u32),
    sources: &[(&Models, String)],
) -> Result<Option<(Choices, Quality, Prediction)>> {
    let facts = SceneFacts::new(scene, quality, true);
    if facts.objects.is_empty() {
        return Ok(None);
    }
    for (models, source) in sources {
        let Some(variants) = candidates(scene, &facts, choices, models, size) else { continue };
        // (variant, whole-scene method or None for mixed, picks, rank)
        let mut best: Option<Best> = None;
        for (k, v) in variants.iter().enumerate() {
            let timing = Timing { base: v.base, quality: variant_quality(quality, &v.knobs)?, facts: &facts };
            let idx = search(budget, &|p| timing.frame_ms(p, false), &v.per_object);
            let mixed: Vec<Candidate> = idx.iter().zip(&v.per_object).map(|(&i, c)| c[i].clone()).collect();
            let options = std::iter::once((None, v.base, mixed)).chain(v.wholes.iter().map(|(m, b, list)| (Some(*m), *b, list.clone())));
            for (whole, base, picks) in options {
                let refs: Vec<&Candidate> = picks.iter().collect();
                let t = Timing { base, quality: timing.quality.clone(), facts: &facts };
                let r = rank(budget, t.frame_ms(&refs, whole.is_some()), &refs);
                if best.as_ref().is_none_or(|b| better(r, b.4)) {
                    best = Some((k, whole, base, picks, r));
                }
            }
        }
        let Some((k, whole, base, picks, r)) = best else { continue };
        let v = &variants[k];
        let q = variant_quality(quality, &v.knobs)?;
        let timing = Timing { base, quality: q.clone(), facts: &facts };
        let refs: Vec<&Candidate> = picks.iter().collect();
        let objects: Vec<ObjectPrediction> = facts
            .objects
            .iter()
            .zip(&picks)
            .enumerate()
            .map(|(i, (f, c))| ObjectPrediction {
                mesh: f.mesh,
                name: scene.meshes[f.mesh].name.clone(),
                method: c.method,
                ms: timing.object_ms(&refs, i, whole.is_some()),
                psnr_db: c.psnr,
                pixels: c.pixels,
                model: c.model.clone(),
            })
            .collect();
        // A whole-scene method as the study ran it; one method everywhere (nothing forced)
        // planned the same way; otherwise per-object methods.
        let whole = whole.or_else(|| (Timing::uniform(&refs) && choices.objects.is_empty()).then(|| refs[0].method));
        let out = match whole {
            Some(m) => Choices::all(m),
            None => Choices { method: choices.method, objects: objects.iter().map(|o| (o.name.clone(), o.method)).collect() },
        };
        let prediction = Prediction {
            budget,
            knobs: v.knobs.clone(),
            base_ms: base,
            frame_ms: timing.frame_ms(&refs, whole.is_some()),
            specular_psnr_db: combined_psnr(&refs),
            objects,
            met: r.0,
            source: source.clone(),
            whole_scene: whole.map(|m| m.name.to_string()),
        };
        return Ok(Some((out, q, prediction)));
    }
    Ok(None)
}

/// The best variant so far: (variant, whole-scene method or None for mixed, predicted ms,
/// picks, rank).
type Best = (usize, Option<Method>, f64, Vec<Candidate>, (bool, f64, f64));

/// What a frame measured: per object (ms, PSNR) in the prediction's order, then the
/// frame's (ms, specular PSNR).
pub type FrameMeasured<'a> = (&'a [(f64, Option<f64>)], (f64, Option<f64>));

/// The prediction as a table, with what a frame measured beside it where given.
pub fn report(p: &Prediction, actual: Option<FrameMeasured>) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "budget {}: {} · {} · knobs {} · models: {}",
        p.budget.describe(),
        if p.met { "met (predicted)" } else { "NOT reachable with these models: the nearest choice" },
        p.whole_scene.as_ref().map_or("per-object methods".to_string(), |m| format!("whole-scene --method {m}")),
        p.knobs,
        p.source
    );
    let _ = writeln!(
        s,
        "{:<24} {:<18} {:>12} {:>10} {:>14} {:>12}  model",
        "object", "method", "predicted ms", "actual ms", "predicted PSNR", "actual PSNR"
    );
    let fmt = |v: Option<f64>, prec: usize| v.map_or("-".to_string(), |v| format!("{v:.prec$}"));
    for (i, o) in p.objects.iter().enumerate() {
        let a = actual.and_then(|(objs, _)| objs.get(i).copied());
        let _ = writeln!(
            s,
            "{:<24} {:<18} {:>12.3} {:>10} {:>14.2} {:>12}  {}",
            crate::error::clip(&o.name),
            o.method.name,
            o.ms,
            fmt(a.map(|a| a.0), 3),
            o.psnr_db,
            fmt(a.and_then(|a| a.1), 2),
            o.model
        );
    }
    let a = actual.map(|(_, f)| f);
    let _ = writeln!(
        s,
        "{:<24} {:<18} {:>12.3} {:>10} {:>14.2} {:>12}  (base {:.3} ms; PSNR of all specular pixels)",
        "frame",
        "",
        p.frame_ms,
        fmt(a.map(|a| a.0), 3),
        p.specular_psnr_db,
        fmt(a.and_then(|a| a.1), 2),
        p.base_ms
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cand(ms: f64, psnr: f64) -> Candidate {
        Candidate {
            method: crate::methods::ENVMAP,
            fixed: 0.0,
            screen: ms,
            shared: 0.0,
            cycles: 1,
            psnr,
            pixels: 100,
            model: String::new(),
        }
    }

    /// Base 1 ms plus the candidates' screen parts.
    fn time(p: &[&Candidate]) -> f64 {
        1.0 + p.iter().map(|c| c.screen).sum::<f64>()
    }

    /// Three objects × three candidates: the exhaustive search's answers, by hand.
    #[test]
    fn search_meets_floors_at_least_time_and_times_at_least_error() {
        let per = vec![
            vec![cand(1.0, 20.0), cand(2.0, 30.0), cand(5.0, 40.0)],
            vec![cand(1.0, 25.0), cand(3.0, 35.0), cand(4.0, 45.0)],
            vec![cand(0.5, 18.0), cand(1.5, 33.0), cand(6.0, 50.0)],
        ];
        // Floor 30: the cheapest per object that reaches it.
        assert_eq!(search(Budget::MinPsnr(30.0), &time, &per), [1, 1, 1]);
        // Floor 60: unreachable; the highest floor (40, 45, 50), then the fastest.
        assert_eq!(search(Budget::MinPsnr(60.0), &time, &per), [2, 2, 2]);
        // 8 ms with a 1 ms base: 7 ms for the objects; the least pixel-weighted error.
        let pick = search(Budget::MaxMs(8.0), &time, &per);
        let ms: f64 = pick.iter().zip(&per).map(|(&i, c)| c[i].screen).sum();
        assert!(ms <= 7.0, "{pick:?}");
        let mse = |p: &[usize]| p.iter().zip(&per).map(|(&i, c)| mse_of(c[i].psnr)).sum::<f64>();
        for a in 0..3 {
            for b in 0..3 {
                for c in 0..3 {
                    let t = [a, b, c];
                    let tm: f64 = t.iter().zip(&per).map(|(&i, c)| c[i].screen).sum();
                    if tm <= 7.0 {
                        assert!(mse(&pick) <= mse(&t) + 1e-15, "{t:?} beats {pick:?}");
                    }
                }
            }
        }
        // No time at all: the fastest.
        assert_eq!(search(Budget::MaxMs(0.1), &time, &per), [0, 0, 0]);
    }

    #[test]
    fn combined_psnr_weights_by_pixels() {
        let a = Candidate { pixels: 300, ..cand(1.0, 20.0) };
        let b = Candidate { pixels: 100, ..cand(1.0, 40.0) };
        // MSE 0.01 on 300 px and 0.0001 on 100: mean 0.007525.
        assert!((combined_psnr(&[&a, &b]) - -10.0 * 0.007525f64.log10()).abs() < 1e-9);
        assert_eq!(psnr_of(0.0), PSNR_CAP);
    }

    #[test]
    fn merge_joins_variants_and_rescales_screen_costs() {
        let obj = |name: &str, screen| ObjectModel {
            object: name.into(),
            class: "mirror".into(),
            pixels: 10,
            method: "envmap".into(),
            cost: Cost { fixed_ms: 1.0, screen_ms: screen },
            shared: Cost::default(),
            cycles: 1,
            row: "envmap".into(),
            psnr_db: 30.0,
        };
        let m = |size: u32, screen| Models {
            format: FORMAT.into(),
            scene: format!("s{size}"),
            device: String::new(),
            size: [size, size],
            variants: vec![VariantModel {
                knobs: "default".into(),
                base: Cost { fixed_ms: 2.0, screen_ms: screen },
                row_bases: Vec::new(),
                objects: vec![obj("a", screen)],
            }],
        };
        let joined = Models::merge(vec![m(10, 1.0), m(20, 4.0)]);
        assert_eq!(joined.scene, "s10+s20");
        assert_eq!(joined.variants.len(), 1);
        let v = &joined.variants[0];
        assert_eq!(v.objects.len(), 2);
        // 20² → 10²: a quarter of the pixels, a quarter of the screen time.
        assert_eq!((v.objects[1].cost.screen_ms, v.objects[1].pixels), (1.0, 3));
        assert_eq!(v.base, Cost { fixed_ms: 2.0, screen_ms: 1.0 });
        assert_eq!(Cost { fixed_ms: 1.0, screen_ms: 2.0 }.at(200.0, 100.0), 5.0);
    }

    #[test]
    fn stored_defaults_parse_and_cover_the_bundled_classes() {
        let d = stored_defaults().unwrap();
        let classes: std::collections::BTreeSet<&str> =
            d.variants.iter().flat_map(|v| v.objects.iter().map(|o| o.class.as_str())).collect();
        assert!(classes.contains("mirror") && classes.contains("solid dielectric"), "{classes:?}");
    }
}
