//! Error models: per method, PSNR on an object's pixels (against the exact tracer) as a
//! linear function of the object's error features (`features::ERROR_FEATURES`), fitted by
//! ridge regression on the corpus. Generalisation is measured by leaving each scene out in
//! turn ([`leave_one_scene_out`]): the fit never sees the scene it predicts.

use std::collections::BTreeMap;

use serde::Serialize;

use super::linear;
use super::samples::{Sample, PSNR_CAP};

/// The ridge penalty (relative to each feature's norm): chosen by leave-one-scene-out over
/// 0.001–1 on the stored corpus (BENCHMARKS.md).
pub const RIDGE: f64 = 0.03;
/// Predictions are clamped here (a method's error cannot fall below the exact tracer's,
/// and no object is predicted below a blank image's typical PSNR).
pub const PSNR_FLOOR: f64 = 5.0;

/// Per method its coefficients over `ERROR_FEATURES`, and how many samples fitted it.
#[derive(Clone, Debug, Default)]
pub struct ErrorModel {
    pub methods: BTreeMap<String, (Vec<f64>, usize)>,
}

/// The model a method's error comes from: every scheme of ray tracing in the original
/// geometry (`GpuSpec::shades_every_pixel`) renders the same image, so they share one
/// (fitted on all their samples); every other method has its own.
pub fn model_key(method: &str) -> &str {
    match crate::plan::Method::parse(method) {
        Ok(m) if m.gpu.is_some_and(|g| g.shades_every_pixel) => EXACT,
        _ => method,
    }
}

/// The shared model of the exact tracers.
pub const EXACT: &str = "ray tracing (every scheme)";

/// A sample's weight: objects of few pixels measure their PSNR noisily.
fn weight(s: &Sample) -> f64 {
    (s.work.pixels / 400.0).clamp(0.05, 1.0)
}

impl ErrorModel {
    /// Fits every method's model from `samples` for which `keep` holds.
    pub fn fit(samples: &[Sample], keep: &dyn Fn(&Sample) -> bool) -> ErrorModel {
        Self::fit_with(samples, keep, RIDGE)
    }

    /// [`ErrorModel::fit`] with another ridge penalty.
    pub fn fit_with(samples: &[Sample], keep: &dyn Fn(&Sample) -> bool, ridge: f64) -> ErrorModel {
        let mut by: BTreeMap<&str, Vec<&Sample>> = BTreeMap::new();
        for s in samples.iter().filter(|s| keep(s)) {
            by.entry(model_key(&s.method)).or_default().push(s);
        }
        let methods = by
            .into_iter()
            .map(|(m, ss)| {
                let x: Vec<Vec<f64>> = ss.iter().map(|s| s.features.clone()).collect();
                let y: Vec<f64> = ss.iter().map(|s| s.psnr_db.min(PSNR_CAP)).collect();
                let w: Vec<f64> = ss.iter().map(|s| weight(s)).collect();
                // Few samples: the mean alone (a bias); else ridge over every feature.
                let beta = if ss.len() < 8 {
                    let mut b = vec![0.0; x[0].len()];
                    b[0] = y.iter().zip(&w).map(|(y, w)| y * w).sum::<f64>() / w.iter().sum::<f64>();
                    b
                } else {
                    linear::fit(&x, &y, &w, ridge, false)
                };
                (m.to_string(), (beta, ss.len()))
            })
            .collect();
        ErrorModel { methods }
    }

    /// Predicted PSNR of `method` on an object with these features; `None` for a method
    /// the corpus never measured.
    pub fn predict(&self, method: &str, features: &[f64]) -> Option<f64> {
        let (beta, _) = self.methods.get(model_key(method))?;
        Some(linear::dot(beta, features).clamp(PSNR_FLOOR, PSNR_CAP))
    }
}

/// One held-out prediction.
#[derive(Clone, Debug, Serialize)]
pub struct Held {
    pub scene: usize,
    pub object: String,
    pub method: String,
    pub knobs: String,
    pub predicted_db: f64,
    pub measured_db: f64,
}

/// Leave-one-scene-out: per scene, the models fitted on every other scene predict its
/// samples.
pub fn leave_one_scene_out(samples: &[Sample]) -> Vec<Held> {
    leave_one_scene_out_with(samples, RIDGE)
}

/// [`leave_one_scene_out`] with another ridge penalty.
pub fn leave_one_scene_out_with(samples: &[Sample], ridge: f64) -> Vec<Held> {
    let mut scenes: Vec<usize> = samples.iter().map(|s| s.scene).collect();
    scenes.sort();
    scenes.dedup();
    let mut out = Vec::new();
    for sc in scenes {
        let model = ErrorModel::fit_with(samples, &|s| s.scene != sc, ridge);
        for s in samples.iter().filter(|s| s.scene == sc) {
            if let Some(p) = model.predict(&s.method, &s.features) {
                out.push(Held {
                    scene: sc,
                    object: s.object.clone(),
                    method: s.method.clone(),
                    knobs: s.knobs.clone(),
                    predicted_db: p,
                    measured_db: s.psnr_db.min(PSNR_CAP),
                });
            }
        }
    }
    out
}

/// Median and 90th percentile of |predicted − measured| (dB).
pub fn abs_error_quantiles(held: &[Held]) -> (f64, f64) {
    let mut e: Vec<f64> = held.iter().map(|h| (h.predicted_db - h.measured_db).abs()).collect();
    if e.is_empty() {
        return (0.0, 0.0);
    }
    e.sort_by(f64::total_cmp);
    let q = |p: f64| e[((e.len() - 1) as f64 * p).round() as usize];
    (q(0.5), q(0.9))
}
