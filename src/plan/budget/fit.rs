//! Fitting models to a calibration study's rows.

use std::collections::BTreeMap;

use super::attribute::attribute;
use super::models::{mse_of, psnr_of};
use super::{Cost, Models, ObjectModel, RowBase, VariantModel, FORMAT, PSNR_CAP};
use crate::plan::{Choice, Plan};
use crate::scene::Scene;

/// One calibration row as the fit needs it.
pub struct Measured<'a> {
    pub knobs: &'a str,
    pub plan: &'a Plan,
    pub passes: &'a [(String, f64)],
    /// The row's error per object name (pixels, PSNR on them).
    pub regions: &'a [crate::metrics::MaskedError],
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
        if r.plan.choice == Choice::Auto {
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
                    under: 1.0,
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
