//! Error models: per method, PSNR on an object's pixels (against the exact tracer) as a
//! linear function of the object's error features (`features::ERROR_FEATURES`), fitted by
//! ridge regression on the corpus's frames of [`BASE_SCREEN`] pixels; the part of the error
//! that is aliasing falls with the frame's size by an exponent per method, measured on the
//! corpus's objects at a second size. Generalisation is measured by leaving each scene out
//! in turn ([`leave_one_scene_out`]): the fit never sees the scene it predicts.

use std::collections::BTreeMap;

use serde::Serialize;

use super::aliasing::{Aliasing, Probes};
use super::linear;
use super::samples::{Sample, PSNR_CAP};

/// The ridge penalty (relative to each feature's norm): chosen by leave-one-scene-out over
/// 0.001–1 on the stored corpus (BENCHMARKS.md).
pub const RIDGE: f64 = 0.03;
/// Predictions are clamped here (a method's error cannot fall below the exact tracer's,
/// and no object is predicted below a blank image's typical PSNR).
pub const PSNR_FLOOR: f64 = 5.0;
/// The frame size (pixels) the error features are fitted at: the corpus's 128².
pub const BASE_SCREEN: f64 = 128.0 * 128.0;
/// The largest size exponent a fit may give (a method measured on few objects).
pub const MAX_SIZE_EXPONENT: f64 = 3.0;

/// Per method its coefficients over `ERROR_FEATURES`, and how many samples fitted it
/// (fitted on frames of [`BASE_SCREEN`] pixels without anti-aliasing); per method and `aa`
/// value the factor by which anti-aliasing scales the part of an object's error that is
/// aliasing; per method the exponent by which the frame's size does ([`ErrorModel::predict`]).
#[derive(Clone, Debug, Default)]
pub struct ErrorModel {
    pub methods: BTreeMap<String, (Vec<f64>, usize)>,
    /// (model key, `aa` value) → (aliasing factor, samples).
    pub aa: BTreeMap<(String, String), (f64, usize)>,
    /// Model key → (k, samples): a frame N pixels across scales the aliasing part of the
    /// error at [`BASE_SCREEN`] by (N / 128)^−k (edge aliasing in theory: k = 1; a map
    /// method's error is its map's, which the frame's size does not change: k = 0).
    pub size: BTreeMap<String, (f64, usize)>,
    /// Model key → (dB, samples): the most its PSNR measured above the exact tracer's on the
    /// same object and frame in the corpus (a cube map's filtering can smooth away some
    /// aliasing): with the exact tracer's error measured on the object, no prediction of the
    /// method goes further above it than the corpus ever saw (a fit extrapolated to an
    /// object unlike the corpus's predicted curved-reflector at 51.6 dB on a planar panel
    /// that it renders at 23.8, where the exact tracer reaches 35.1).
    pub excess: BTreeMap<String, (f64, usize)>,
}

/// The frame's anti-aliasing as a sample's knobs or a quality name it (`off` when unset).
pub fn aa_of(knobs: &str) -> &str {
    knobs.split_whitespace().find_map(|p| p.strip_prefix("aa=")).unwrap_or("off")
}

/// The aliasing factor of an `aa` value the corpus did not measure: its resolved samples
/// `n` (`features::aa_samples`) to the power −1.6 (the exact tracer's measured factors at
/// 4 samples, 0.09 multisampled and 0.13 supersampled, lie either side of 4^−1.6 = 0.11).
pub fn unmeasured_aa_factor(samples: f64) -> f64 {
    samples.max(1.0).powf(-1.6)
}

use crate::plan::budget::{mse_of as mse, psnr_of};

fn psnr(mse: f64) -> f64 {
    psnr_of(mse).max(PSNR_FLOOR)
}

/// Anti-aliasing's effect on an object: its error without it (`mse_method`) is aliasing up
/// to the exact tracer's error (`mse_exact`, which is aliasing alone) and a bias beyond it
/// that more samples do not remove; anti-aliasing scales the aliasing part by `factor`.
fn with_aa(mse_method: f64, mse_exact: f64, factor: f64) -> f64 {
    let alias = mse_method.min(mse_exact);
    (mse_method - alias) + alias * factor
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

/// The candidate a (method, knob variant) pair is, for the models: the method, or
/// `METHOD+hybrid` where the variant turns on the hybrid search (`hybrid=rays`) of a method
/// that reads it, `METHOD+confirm` for `hybrid=confirm` (their errors and costs are other
/// methods').
pub fn candidate(method: &str, knobs: &str) -> String {
    let mode = knobs.split_whitespace().find_map(|p| p.strip_prefix("hybrid="));
    let suffix = match mode {
        Some("rays") => "hybrid",
        Some("confirm") => "confirm",
        _ => return method.to_string(),
    };
    match crate::plan::Method::parse(method) {
        Ok(m) if m.knobs.contains(&"hybrid") => format!("{method}+{suffix}"),
        _ => method.to_string(),
    }
}

/// A candidate fires ray queries of its own (the hybrid searches), beyond what its method needs.
pub fn candidate_traces(name: &str) -> bool {
    name.ends_with("+hybrid") || name.ends_with("+confirm")
}

/// The method of a [`candidate`] name.
pub fn candidate_method(name: &str) -> &str {
    name.split('+').next().unwrap_or(name)
}

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
        let mut by: BTreeMap<String, Vec<&Sample>> = BTreeMap::new();
        for s in samples.iter().filter(|s| keep(s) && at_base(s) && aa_of(&s.knobs) == "off") {
            by.entry(model_key(&candidate(&s.method, &s.knobs)).to_string()).or_default().push(s);
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
                (m, (beta, ss.len()))
            })
            .collect();
        ErrorModel { methods, aa: fit_aa(samples, keep), size: fit_size(samples, keep), excess: fit_excess(samples, keep) }
    }

    /// Predicted PSNR of `method` on an object with these features in a frame of `screen`
    /// pixels anti-aliased by `aa` (a value of the `aa` knob) resolving `aa_samples` samples
    /// per pixel with cube maps of `cube_size`; `None` for a method the corpus never
    /// measured. `measured`: what the probe measured on the object at this size
    /// ([`super::aliasing`]): the exact tracer's error, the anchor of every method's
    /// aliasing part (with the error under `aa` where it was measured), and on a mirror the
    /// error of the cube-map lookups, which with that aliasing is their prediction.
    pub fn predict(
        &self,
        method: &str,
        features: &[f64],
        (aa, aa_samples, per_sample, cube_size): (&str, f64, bool, u32),
        screen: f64,
        measured: Option<&Aliasing>,
    ) -> Option<f64> {
        if let Some(m) = measured {
            if let Some(lookup) = m.lookup(method, cube_size) {
                return Some(psnr(lookup.under(aa, per_sample, m.mse(aa, per_sample))));
            }
        }
        let own = self.predict_off(method, features)?;
        let aa_factor = if aa == "off" { 1.0 } else { self.aa_factor(method, aa, aa_samples) };
        let size = self.size_factor(method, screen);
        let exact = self.predict_off(EXACT, features).unwrap_or(PSNR_CAP);
        let (own, exact) = (mse(own), mse(exact));
        if let Some(m) = measured.filter(|m| m.off > 0.0 && m.off.is_finite()) {
            // The model's aliasing of the exact tracer at this size against the measured:
            // their ratio corrects every method's aliasing part (its bias beyond aliasing
            // is the model's), and the measured factor of `aa` is what sampling removes.
            let model_exact = exact * self.size_factor(EXACT, screen);
            let scale = m.off / model_exact;
            let alias = own.min(exact);
            let sized = alias * size * scale;
            let removable = sized.min(m.off);
            let factor = m.mse(aa, per_sample).map_or(aa_factor, |e| e / m.off);
            let predicted = psnr((own - alias) + (sized - removable) + removable * factor);
            let at = |k: &str| self.excess.get(k).filter(|(_, n)| *n >= 4).map(|(e, _)| *e);
            let excess = at(model_key(method)).or_else(|| at(model_key(candidate_method(method))));
            return Some(excess.map_or(predicted, |e| predicted.min(psnr(m.off * factor) + e.max(0.0))));
        }
        if aa_factor == 1.0 && size == 1.0 {
            return Some(psnr(own));
        }
        // At this frame's size: the method's error (its aliasing part scaled by its own
        // exponent), and the aliasing anti-aliasing can remove — at most the exact tracer's
        // own at this size. A method whose error does not fall with the frame (a cube map's
        // bias, exponent 0) keeps it under multisampling at 512² although at 128², where
        // the exact tracer aliases as much, the part up to the exact tracer's error is
        // aliasing (concave-occluder: proxy-box with msaa4 predicted 29.9 dB, measured 24.5).
        let sized = with_aa(own, exact, size);
        let alias = (own.min(exact) * size).min(exact * self.size_factor(EXACT, screen));
        Some(psnr(sized - alias + alias * aa_factor))
    }

    /// The factor by which a frame of `screen` pixels scales `method`'s aliasing at
    /// [`BASE_SCREEN`]: its own measured exponent, else (a `METHOD+hybrid` candidate) its
    /// method's, else the exact tracers'.
    pub fn size_factor(&self, method: &str, screen: f64) -> f64 {
        if screen <= 0.0 || (screen - BASE_SCREEN).abs() < 0.5 {
            return 1.0;
        }
        let at = |m: &str| self.size.get(m).filter(|(_, n)| *n >= 4).map(|(k, _)| *k);
        let k = at(model_key(method)).or_else(|| at(model_key(candidate_method(method)))).or_else(|| at(EXACT)).unwrap_or(0.0);
        (screen / BASE_SCREEN).sqrt().powf(-k)
    }

    /// The aliasing factor of `method` under `aa`: measured on the corpus where it has at
    /// least 4 samples, else the exact tracers', else [`unmeasured_aa_factor`].
    pub fn aa_factor(&self, method: &str, aa: &str, aa_samples: f64) -> f64 {
        let at = |m: &str| self.aa.get(&(m.to_string(), aa.to_string())).filter(|(_, n)| *n >= 4).map(|(f, _)| *f);
        at(model_key(method)).or_else(|| at(EXACT)).unwrap_or_else(|| unmeasured_aa_factor(aa_samples))
    }

    /// The PSNR without anti-aliasing.
    fn predict_off(&self, method: &str, features: &[f64]) -> Option<f64> {
        let (beta, _) = self.methods.get(model_key(method))?;
        Some(linear::dot(beta, features).clamp(PSNR_FLOOR, PSNR_CAP))
    }
}

/// Whether a sample's frame has the size the error features are fitted at.
fn at_base(s: &Sample) -> bool {
    (s.work.screen - BASE_SCREEN).abs() < 0.5
}

/// A sample's (scene, object, model key, frame pixels).
type SampleKey<'a> = (usize, &'a str, String, u64);

fn sample_key(s: &Sample) -> SampleKey<'_> {
    (s.scene, s.object.as_str(), model_key(&candidate(&s.method, &s.knobs)).to_string(), s.work.screen as u64)
}

/// The PSNR of every sample measured with the default knobs, by [`sample_key`].
fn default_psnr<'a>(samples: &'a [Sample], keep: &dyn Fn(&Sample) -> bool) -> BTreeMap<SampleKey<'a>, f64> {
    let mut off = BTreeMap::new();
    for s in samples.iter().filter(|s| keep(s) && s.knobs == "default") {
        off.entry(sample_key(s)).or_insert(s.psnr_db);
    }
    off
}

/// The factor [`with_aa`] needs to turn an object's error `own` (its method's, without the
/// change) into `changed`, with `exact` the exact tracer's (all of it aliasing); `None`
/// where the exact error sits at the cap (it tells nothing).
fn aliasing_factor(own: f64, exact: f64, changed: f64) -> Option<f64> {
    if exact >= PSNR_CAP - 1.0 {
        return None;
    }
    let (mo, me, ma) = (mse(own), mse(exact), mse(changed));
    let alias = mo.min(me);
    Some(((ma - (mo - alias)) / alias).clamp(1e-3, 10.0))
}

/// The median of each key's values (logarithms of factors, or exponents).
fn log_medians<K>(logs: BTreeMap<K, Vec<f64>>) -> impl Iterator<Item = (K, (f64, usize))> {
    logs.into_iter().map(|(k, mut v)| {
        v.sort_by(f64::total_cmp);
        (k, (v[v.len() / 2], v.len()))
    })
}

/// Per method its size exponent: over the objects measured with the default knobs both at
/// [`BASE_SCREEN`] and at another size (and by the exact tracer at the base size), the
/// median of the exponent k for which (N / 128)^−k is the factor [`with_aa`] needs to turn
/// the error at the base size into the error at the other; clamped to 0–[`MAX_SIZE_EXPONENT`].
fn fit_size(samples: &[Sample], keep: &dyn Fn(&Sample) -> bool) -> BTreeMap<String, (f64, usize)> {
    let off = default_psnr(samples, keep);
    let mut ks: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    for s in samples.iter().filter(|s| keep(s) && s.knobs == "default" && !at_base(s) && s.work.screen > 0.0) {
        let (sc, o, m, _) = sample_key(s);
        let base = BASE_SCREEN as u64;
        let (Some(&own), Some(&exact)) = (off.get(&(sc, o, m.clone(), base)), off.get(&(sc, o, EXACT.to_string(), base))) else { continue };
        let Some(factor) = aliasing_factor(own, exact, s.psnr_db.min(PSNR_CAP)) else { continue };
        let ratio = (s.work.screen / BASE_SCREEN).sqrt();
        ks.entry(m).or_default().push(-factor.ln() / ratio.ln());
    }
    log_medians(ks).map(|(m, (k, n))| (m, (k.clamp(0.0, MAX_SIZE_EXPONENT), n))).collect()
}

/// Per method and measured `aa` value its aliasing factor: over the objects measured both
/// with it and without (and by the exact tracer without), the median (in logarithm) of the
/// factor [`with_aa`] needs to turn the measured error without into the measured error with.
/// Objects whose exact error sits at the cap tell nothing and are left out.
fn fit_aa(samples: &[Sample], keep: &dyn Fn(&Sample) -> bool) -> BTreeMap<(String, String), (f64, usize)> {
    let off = default_psnr(samples, keep);
    let mut logs: BTreeMap<(String, String), Vec<f64>> = BTreeMap::new();
    for s in samples.iter().filter(|s| keep(s) && aa_of(&s.knobs) != "off") {
        let (sc, o, m, px) = sample_key(s);
        let (Some(&own), Some(&exact)) = (off.get(&(sc, o, m.clone(), px)), off.get(&(sc, o, EXACT.to_string(), px))) else { continue };
        let Some(factor) = aliasing_factor(own, exact, s.psnr_db) else { continue };
        logs.entry((m, aa_of(&s.knobs).to_string())).or_default().push(factor.ln());
    }
    log_medians(logs).map(|(k, (median, n))| (k, (median.exp(), n))).collect()
}

/// Per method the most its PSNR measured above the exact tracer's on the same object and
/// frame with the default knobs ([`ErrorModel::excess`]); objects whose exact error sits at
/// the cap tell nothing and are left out.
fn fit_excess(samples: &[Sample], keep: &dyn Fn(&Sample) -> bool) -> BTreeMap<String, (f64, usize)> {
    let off = default_psnr(samples, keep);
    let mut most: BTreeMap<String, (f64, usize)> = BTreeMap::new();
    for s in samples.iter().filter(|s| keep(s) && s.knobs == "default") {
        let (sc, o, m, px) = sample_key(s);
        let Some(&exact) = off.get(&(sc, o, EXACT.to_string(), px)).filter(|&&e| e < PSNR_CAP - 1.0) else { continue };
        let e = most.entry(m).or_insert((f64::NEG_INFINITY, 0));
        *e = (e.0.max(s.psnr_db.min(PSNR_CAP) - exact), e.1 + 1);
    }
    most
}

/// One held-out prediction.
#[derive(Clone, Debug, Serialize)]
pub struct Held {
    pub scene: usize,
    pub object: String,
    pub method: String,
    pub knobs: String,
    /// The frame's pixels.
    pub screen: f64,
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
    held_out(samples, ridge, true, None)
}

/// [`leave_one_scene_out`] with the frame's size ignored (every size predicted as the
/// base size): what the size exponents gain.
pub fn leave_one_scene_out_unsized(samples: &[Sample]) -> Vec<Held> {
    held_out(samples, RIDGE, false, None)
}

/// [`leave_one_scene_out`] as the planner predicts: with the exact tracer's error measured
/// on each held-out object (`probes`; objects without one predicted from the model alone).
pub fn leave_one_scene_out_probed(samples: &[Sample], probes: &Probes) -> Vec<Held> {
    held_out(samples, RIDGE, true, Some(probes))
}

fn held_out(samples: &[Sample], ridge: f64, sized: bool, probes: Option<&Probes>) -> Vec<Held> {
    let mut scenes: Vec<usize> = samples.iter().map(|s| s.scene).collect();
    scenes.sort();
    scenes.dedup();
    let mut out = Vec::new();
    for sc in scenes {
        let mut model = ErrorModel::fit_with(samples, &|s| s.scene != sc, ridge);
        if !sized {
            model.size.clear();
        }
        for s in samples.iter().filter(|s| s.scene == sc) {
            let aa = aa_of(&s.knobs);
            let n = crate::plan::budget::variant_quality(&crate::quality::Quality::default(), &s.knobs)
                .map_or(1.0, |q| super::features::aa_samples(&q).1);
            let name = candidate(&s.method, &s.knobs);
            let screen = if sized { s.work.screen } else { BASE_SCREEN };
            let probe = probes.and_then(|p| p.get(&(sc, s.object.clone(), s.work.screen.round() as u64)));
            let cube =
                crate::plan::budget::variant_quality(&crate::quality::Quality::default(), &s.knobs).map_or(256, |q| q.cube.cube_size);
            if let Some(p) = model.predict(&name, &s.features, (aa, n, true, cube), screen, probe) {
                out.push(Held {
                    scene: sc,
                    object: s.object.clone(),
                    method: name.clone(),
                    knobs: s.knobs.clone(),
                    screen: s.work.screen,
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Each hybrid mode is a candidate of its own, only for methods that read the knob.
    #[test]
    fn hybrid_modes_are_candidates_of_their_own() {
        assert_eq!(candidate("distance", "hybrid=rays"), "distance+hybrid");
        assert_eq!(candidate("refractor-map", "aa=msaa4 hybrid=confirm"), "refractor-map+confirm");
        assert_eq!(candidate("distance", "hybrid=off"), "distance");
        assert_eq!(candidate("bvh", "hybrid=confirm"), "bvh");
        assert_eq!(candidate_method("distance+confirm"), "distance");
        assert!(candidate_traces("distance+confirm") && candidate_traces("distance+hybrid") && !candidate_traces("distance"));
    }
}
