//! Measurements the models are fitted on: per corpus scene, method and knob variant, each
//! specular object's error against the exact tracer and its share of the frame's GPU time,
//! with the facts and workload the models predict from; per frame the base (what belongs
//! to no object). Written by `specula corpus` (every scene, the error models' data, stored
//! in `assets/models/corpus.json`) and `specula calibrate` (a subset at two sizes on the
//! device at hand, for its cost model).

use serde::{Deserialize, Serialize};

use super::features::{Workload, ERROR_FEATURES};
use crate::error::{Error, Result};
use crate::plan::ids::Method;

/// The first line of every corpus file's `format` field.
pub const FORMAT: &str = "specula-corpus 1";
/// Measured PSNR is stored and fitted capped here: beyond it an image equals the exact
/// tracer's to within float rounding (every exact scheme measures above it).
pub const PSNR_CAP: f64 = 60.0;

/// One object under one method and knob variant.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sample {
    /// Corpus scene number (`corpus::scene`).
    pub scene: usize,
    pub object: String,
    /// The method the object got (a whole-scene method's fallback where it did not serve it).
    pub method: String,
    /// `default` or `knob=value …` over the defaults.
    pub knobs: String,
    /// [`ERROR_FEATURES`], in order.
    pub features: Vec<f64>,
    pub work: Workload,
    /// PSNR on its own pixels against the exact tracer, capped at [`PSNR_CAP`].
    pub psnr_db: f64,
    /// Its share of the map passes (independent of the output size).
    pub fixed_ms: f64,
    /// Its share of the camera passes.
    pub screen_ms: f64,
    /// Its method's whole-screen kernels, whole (paid once per method a frame uses).
    pub shared_ms: f64,
    /// Inter-object cycles of the frame it was measured in.
    pub cycles: u32,
}

/// One frame's base: the GPU time that belongs to no object.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameSample {
    pub scene: usize,
    pub method: String,
    pub knobs: String,
    pub work: Workload,
    pub base_ms: f64,
}

/// One timing of how a BVH follows moved geometry (`bvh_update`): `way` is `sah` (the CPU's
/// build, host milliseconds), `lbvh` (a linear BVH built on the GPU) or `refit` (on the
/// GPU), over `triangles`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BvhUpdateSample {
    pub way: String,
    pub triangles: f64,
    pub ms: f64,
}

/// A measurement run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Corpus {
    pub format: String,
    /// Where it was measured.
    pub device: super::device::DeviceKey,
    pub samples: Vec<Sample>,
    pub frames: Vec<FrameSample>,
    /// What following moved geometry costs the BVH (a calibration's; none in the error
    /// corpus, nor in runs from before they were measured).
    #[serde(default)]
    pub bvh_updates: Vec<BvhUpdateSample>,
}

impl Corpus {
    pub fn new(device: super::device::DeviceKey) -> Corpus {
        Corpus { format: FORMAT.into(), device, samples: Vec::new(), frames: Vec::new(), bvh_updates: Vec::new() }
    }

    /// Parses and checks a corpus file (`what` names it in errors).
    pub fn parse(text: &str, what: &str) -> Result<Corpus> {
        let c: Corpus = serde_json::from_str(text).map_err(|e| Error::invalid(what.to_string(), format!("not a corpus file: {e}")))?;
        if c.format != FORMAT {
            return Err(Error::invalid(format!("{what} format"), format!("'{}', expected '{FORMAT}'", crate::error::clip(&c.format))));
        }
        for (k, s) in c.samples.iter().enumerate() {
            let field = |f: &str| format!("{what} samples[{k}].{f}");
            Method::parse(&s.method).map_err(|e| Error::invalid(field("method"), e.to_string()))?;
            if s.features.len() != ERROR_FEATURES.len() || s.features.iter().any(|x| !x.is_finite()) {
                return Err(Error::invalid(
                    field("features"),
                    format!("{} finite values expected, got {:?}", ERROR_FEATURES.len(), s.features),
                ));
            }
            for (name, v) in [("psnr_db", s.psnr_db), ("fixed_ms", s.fixed_ms), ("screen_ms", s.screen_ms), ("shared_ms", s.shared_ms)] {
                if !v.is_finite() || v < 0.0 {
                    return Err(Error::invalid(field(name), format!("{v} is not a finite non-negative number")));
                }
            }
            check_work(&s.work, &field("work"))?;
        }
        for (k, f) in c.frames.iter().enumerate() {
            if !f.base_ms.is_finite() || f.base_ms < 0.0 {
                return Err(Error::invalid(
                    format!("{what} frames[{k}].base_ms"),
                    format!("{} is not a finite non-negative number", f.base_ms),
                ));
            }
            check_work(&f.work, &format!("{what} frames[{k}].work"))?;
        }
        Ok(c)
    }

    pub fn to_json(&self) -> String {
        serde_json::to_string(self).unwrap_or_default()
    }

    /// Adds `other`'s measurements; a (scene, object, method, knobs, frame size) that both
    /// hold keeps `other`'s (a re-measurement replaces the old one).
    pub fn merge(&mut self, other: Corpus) {
        let key = |s: &Sample| (s.scene, s.object.clone(), s.method.clone(), s.knobs.clone(), s.work.screen as u64);
        let fkey = |f: &FrameSample| (f.scene, f.method.clone(), f.knobs.clone(), f.work.screen as u64);
        let new: Vec<_> = other.samples.iter().map(key).collect();
        let fnew: Vec<_> = other.frames.iter().map(fkey).collect();
        self.samples.retain(|s| !new.contains(&key(s)));
        self.frames.retain(|f| !fnew.contains(&fkey(f)));
        self.samples.extend(other.samples);
        self.frames.extend(other.frames);
        if !other.bvh_updates.is_empty() {
            self.bvh_updates = other.bvh_updates;
        }
    }

    /// The scene numbers it measured.
    pub fn scenes(&self) -> Vec<usize> {
        let mut s: Vec<usize> = self.samples.iter().map(|s| s.scene).collect();
        s.sort();
        s.dedup();
        s
    }
}

fn check_work(w: &Workload, what: &str) -> Result<()> {
    let all = [
        w.pixels,
        w.screen,
        w.scene_triangles,
        w.triangles,
        w.cube_texels,
        w.lights,
        w.caustic_photons,
        w.caustic_texels,
        w.covered.unwrap_or(0.0),
        w.map_texels.unwrap_or(0.0),
        w.shared_texels,
    ];
    let at_least_one = |x: f64| x.is_finite() && x >= 1.0;
    if all.iter().any(|x| !x.is_finite() || *x < 0.0) || !at_least_one(w.samples) || !at_least_one(w.layers) {
        return Err(Error::invalid(what.to_string(), format!("{w:?}: every count must be finite and non-negative")));
    }
    Ok(())
}
