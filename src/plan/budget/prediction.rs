//! Budgets, what the planner predicts for them, and the prediction as a table.

use serde::Serialize;

use crate::error::{Error, Result};
use crate::plan::ids::Method;

/// The longest frame a budget may ask for (a minute).
pub const MAX_FRAME_MS: f64 = 60_000.0;
/// The highest PSNR floor a budget may ask for (the error models are fitted up to
/// `samples::PSNR_CAP`, 60 dB: a floor above that is refused as unreachable, not as invalid).
pub const MAX_PSNR_DB: f64 = 200.0;

/// A frame budget.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub enum Budget {
    /// At most this many GPU milliseconds per frame; the least error within it. A choice's
    /// frame counts as its prediction times the largest under-prediction margin of its
    /// methods' cost models (`MethodCost::under`): the frame, not only its prediction,
    /// should fit.
    MaxMs(f64),
    /// A predicted frame of at most this many milliseconds, the least error within it:
    /// predictions compared with predictions (`auto`'s default, within the exact tracer's
    /// predicted frame), no margin.
    Within(f64),
    /// Every specular object at least this PSNR (dB) on its pixels; the least time.
    MinPsnr(f64),
    /// `auto`'s default: at most `max_ms` (the exact tracer's predicted frame), and within
    /// that the fastest choice whose specular PSNR reaches `floor_db` (the best reachable
    /// within `max_ms` less a tolerance).
    Near { max_ms: f64, floor_db: f64 },
}

impl Budget {
    /// From the CLI's two options (the C ABI passes 0 as absent); at most one may be set,
    /// `max_ms` in (0, [`MAX_FRAME_MS`]] and `min_psnr` in (0, [`MAX_PSNR_DB`]].
    pub fn from_limits(max_ms: Option<f64>, min_psnr: Option<f64>) -> Result<Option<Budget>> {
        match (max_ms, min_psnr) {
            (Some(_), Some(_)) => Err(Error::invalid("budget", "a time budget (max-ms) or a PSNR floor (min-psnr), not both")),
            (Some(ms), None) if !(ms.is_finite() && ms > 0.0 && ms <= MAX_FRAME_MS) => {
                Err(Error::invalid("max-ms", format!("{ms} is not a frame time in (0, {MAX_FRAME_MS}] ms")))
            }
            (None, Some(db)) if !(db.is_finite() && db > 0.0 && db <= MAX_PSNR_DB) => {
                Err(Error::invalid("min-psnr", format!("{db} is not a PSNR in (0, {MAX_PSNR_DB}] dB")))
            }
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
            Budget::Within(ms) => format!("a predicted frame within {} ms", short(*ms)),
            Budget::MinPsnr(db) => format!("--min-psnr {}", short(*db)),
            Budget::Near { max_ms, floor_db } => {
                format!("default (at most the exact tracer's {} ms, the fastest reaching {} dB)", short(*max_ms), short(*floor_db))
            }
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
    /// Of `ms`, its maps (passes that do not scale with the output); the
    /// rest is its camera work (its camera passes, in every view that shows it, and its share
    /// of its method's whole-screen kernels).
    pub maps_ms: f64,
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

/// What a frame measured for one object: its passes split as the predictions split them
/// (`attribute::measured_by_object`), and its PSNR.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ObjectMeasured {
    pub maps_ms: f64,
    pub camera_ms: f64,
    pub psnr_db: Option<f64>,
}

/// What a frame measured: per object in the prediction's order, then the frame's (ms,
/// specular PSNR).
pub type FrameMeasured<'a> = (&'a [ObjectMeasured], (f64, Option<f64>));

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
        "{:<24} {:<18} {:>12} {:>10} {:>14} {:>12}  {:>17}  {:>17}  model",
        "object", "method", "predicted ms", "actual ms", "predicted PSNR", "actual PSNR", "maps ms pred/act", "camera ms pred/act"
    );
    let fmt = |v: Option<f64>, prec: usize| v.map_or("-".to_string(), |v| format!("{v:.prec$}"));
    for (i, o) in p.objects.iter().enumerate() {
        let a = actual.and_then(|(objs, _)| objs.get(i).copied());
        let pair = |pred: f64, act: Option<f64>| format!("{pred:.3}/{}", fmt(act, 3));
        let _ = writeln!(
            s,
            "{:<24} {:<18} {:>12.3} {:>10} {:>14.2} {:>12}  {:>17}  {:>17}  {}",
            crate::error::clip(&o.name),
            o.method.name(),
            o.ms,
            fmt(a.map(|a| a.maps_ms + a.camera_ms), 3),
            o.psnr_db,
            fmt(a.and_then(|a| a.psnr_db), 2),
            pair(o.maps_ms, a.map(|a| a.maps_ms)),
            pair(o.ms - o.maps_ms, a.map(|a| a.camera_ms)),
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
