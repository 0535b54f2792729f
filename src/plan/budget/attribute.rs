//! A frame's GPU time split among its objects and the frame's base (see the module doc of
//! `plan::budget`).

use serde::{Deserialize, Serialize};

use crate::plan::{Plan, StageSpec};

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
