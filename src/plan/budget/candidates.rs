//! What the models offer each object of a scene: per knob variant, its candidate methods
//! (the dominated dropped) and the whole-scene rows that measured every object.

use super::models::{mse_of, psnr_of};
use super::{Models, ObjectModel};
use crate::plan::facts::SceneFacts;
use crate::plan::{names_object, Choices, MapShading, Method};
use crate::scene::Scene;

/// One candidate of one object in one variant (costs at the frame's size).
#[derive(Clone, Debug)]
pub(super) struct Candidate {
    pub(super) method: Method,
    /// Its share of the per-object map passes, at `cycles` inter-object cycles.
    pub(super) fixed: f64,
    /// Its share of the per-object screen passes.
    pub(super) screen: f64,
    /// Its method's shared kernels, whole.
    pub(super) shared: f64,
    pub(super) cycles: u32,
    pub(super) psnr: f64,
    pub(super) pixels: usize,
    pub(super) model: String,
    /// The maps the object gets where a mixed choice composes it into another family's maps
    /// (`registry::Family::composes`): the map cost of its cheapest candidate whose method
    /// shades it in maps (0 where the models have none).
    pub(super) compose_fixed: f64,
    /// Its cost model's under-prediction margin (`ObjectModel::under`).
    pub(super) under: f64,
}

/// One knob variant's candidates.
pub(super) struct VariantCandidates {
    pub(super) knobs: String,
    pub(super) base: f64,
    /// Per object its candidates, one per method, for mixed choices.
    pub(super) per_object: Vec<Vec<Candidate>>,
    /// The whole-scene methods the calibration ran, each with its objects as measured
    /// (fallbacks included, cycles as run) and its own base: choices of their own.
    pub(super) wholes: Vec<(Method, f64, Vec<Candidate>)>,
}

/// The candidates of every object in every variant, from one models set; `None` when the
/// set covers some object neither by name nor by class.
pub(super) fn candidates(
    scene: &Scene,
    facts: &SceneFacts,
    choices: &Choices,
    models: &Models,
    size: (u32, u32),
) -> Option<Vec<VariantCandidates>> {
    let px = size.0 as f64 * size.1 as f64;
    let measured = models.size[0] as f64 * models.size[1] as f64;
    let ratio = if measured > 0.0 { px / measured } else { 1.0 };
    let mut out = Vec::new();
    for v in &models.variants {
        let variant_q = super::variant_quality(&crate::quality::Quality::default(), &v.knobs).unwrap_or_default();
        let mut per_object = Vec::new();
        let mut wholes: Vec<(Method, Vec<Candidate>)> = Vec::new();
        let base = v.base.at(px, measured);
        for f in &facts.objects {
            let name = &scene.meshes[f.mesh].name;
            let forced = choices.objects.iter().rev().find(|(n, _)| names_object(scene, f.mesh, n)).map(|(_, m)| *m);
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
                    compose_fixed: 0.0,
                    under: es.iter().map(|o| o.under).fold(1.0, f64::max),
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
            // What composing the object into others' maps costs: its cheapest map-shaded candidate.
            let compose_fixed = entries
                .iter()
                .filter_map(|o| {
                    Method::parse(&o.method)
                        .ok()
                        .filter(|m| m.gpu.is_some_and(|g| g.map_shading != MapShading::Sky))
                        .map(|_| o.cost.fixed_ms)
                })
                .fold(f64::INFINITY, f64::min);
            let compose_fixed = if compose_fixed.is_finite() { compose_fixed } else { 0.0 };
            list.iter_mut().for_each(|c| c.compose_fixed = compose_fixed);
            if list.is_empty() {
                // This variant cannot serve the object (or not with its forced method).
                per_object.clear();
                break;
            }
            // Drop the dominated: another candidate at least as accurate (strictly better
            // somewhere) whose cost is no higher in any part even when this one pays
            // nothing for its method's whole-screen kernels and the other pays them in full
            // and composes into other families' maps: a frame pays a method's kernels once
            // for all its objects (the exact tracer on every object, where another method
            // beats it on one object counting its kernels as shared, is that frame).
            // A candidate that renders views of the scene (`GpuSpec::views`) costs what the
            // other objects' methods cost in them: it dominates nothing by its own parts.
            let renders_views = |d: &Candidate| d.method.gpu.is_some_and(|g| (g.views)(&variant_q) > 0);
            let le = |d: &Candidate, c: &Candidate| {
                !renders_views(d)
                    && d.fixed <= c.fixed
                    && d.screen <= c.screen
                    && d.fixed + d.compose_fixed + d.screen + d.shared <= c.fixed + c.screen
                    && d.psnr >= c.psnr
            };
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
