//! A frame's GPU time split among its objects and the frame's base (see the module doc of
//! `plan::budget`).

use serde::{Deserialize, Serialize};

use crate::plan::types::{Plan, StageSpec};

/// GPU milliseconds, split by what they scale with.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Cost {
    /// Passes whose work does not depend on the output size (maps, shadow maps, photons).
    pub fixed_ms: f64,
    /// Passes over the output's pixels.
    pub screen_ms: f64,
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

/// The stages of `p` that record the timed pass `name`: those that declare it
/// (`StageSpec::passes`: an effect's passes), else the camera stages whose declared prefix it carries
/// (`Profiled::prefix`: a ray tracer's kernels, planar mirrors' views). None: the frame's
/// own work outside the plan's stages (resolve, object ids, output).
fn recorded_by<'p>(p: &'p Plan, name: &str) -> Vec<&'p StageSpec> {
    let own = |s: &StageSpec| s.passes().contains(&name);
    let exact: Vec<&StageSpec> = p.stages.iter().filter(|s| own(s)).collect();
    if !exact.is_empty() {
        return exact;
    }
    let declares =
        |s: &&StageSpec| matches!(s, StageSpec::Camera(c) if !c.profiled.prefix.is_empty() && name.starts_with(c.profiled.prefix));
    p.stages.iter().filter(declares).collect()
}

/// Whether a stage's work is independent of the output size.
fn fixed(s: &StageSpec) -> bool {
    match s {
        StageSpec::Map(_) | StageSpec::Upload | StageSpec::Shadows => true,
        // An effect that is not drawn per view (caustics' maps and photons, not their
        // projection onto the camera's surfaces).
        StageSpec::Effect(e) => !e.deps.per_view(),
        StageSpec::Direct | StageSpec::Camera(_) => false,
    }
}

/// A frame's GPU time split by object: per mesh (its share, its method's shared kernels
/// whole), and the rest (base); see the module doc. A timed pass belongs to the objects
/// whose plans list it (`ObjectPlan::passes`), else to those of the camera stages that
/// record it under their prefix; a frame stage's, a frame effect's (caustics), or one no
/// stage records, to the base.
pub fn attribute(p: &Plan, passes: &[(String, f64)]) -> (Vec<(usize, Cost, Cost)>, Cost) {
    let mut objects: Vec<(usize, Cost, Cost)> = p.objects.iter().map(|o| (o.mesh, Cost::default(), Cost::default())).collect();
    let mut base = Cost::default();
    for (name, ms) in passes {
        // The standalone frame's copy to the host: no part of the frame's cost.
        if name == "frame.readback" || !ms.is_finite() {
            continue;
        }
        let stages = recorded_by(p, name);
        // A frame effect's pass (caustics: every generator's photons, light and receiver
        // cubes, their projection) costs the same whatever methods the objects get: the
        // base's, predicted from the frame's effect workload (`cost_model::BASE_FEATURES`).
        // Split among its generators, it was fitted per method, on two lit calibration
        // scenes, as light terms that did not hold on unseen scenes.
        let effect = stages.iter().any(|s| matches!(s, StageSpec::Effect(_)));
        let part =
            if stages.iter().any(|s| fixed(s)) { Cost { fixed_ms: *ms, screen_ms: 0.0 } } else { Cost { fixed_ms: 0.0, screen_ms: *ms } };
        let mut owners: Vec<usize> = (0..p.objects.len()).filter(|&i| p.objects[i].passes.iter().any(|q| q == name)).collect();
        if owners.is_empty() {
            let draws = |s: &StageSpec, mesh: usize| matches!(s, StageSpec::Camera(c) if c.objects.iter().any(|(m, _)| *m == mesh));
            owners = (0..p.objects.len()).filter(|&i| stages.iter().any(|s| draws(s, p.objects[i].mesh))).collect();
        }
        let shared = stages.iter().any(|s| match s {
            StageSpec::Camera(c) => c.profiled.shared,
            StageSpec::Map(m) => m.shared,
            _ => false,
        });
        if owners.is_empty() || effect {
            base.add(part, 1.0);
        } else if shared {
            owners.iter().for_each(|&i| objects[i].2.add(part, 1.0));
        } else {
            let w = 1.0 / owners.len() as f64;
            owners.iter().for_each(|&i| objects[i].1.add(part, w));
        }
    }
    (objects, base)
}

/// What a frame spent per object, as the prediction counts it: (mesh, its maps and frame
/// effects, its camera work with its share of its method's shared kernels), and the base.
pub fn measured_by_object(p: &Plan, passes: &[(String, f64)]) -> (Vec<(usize, f64, f64)>, f64) {
    let (costs, base) = attribute(p, passes);
    let per = costs
        .iter()
        .zip(&p.objects)
        .map(|((mesh, own, shared), o)| {
            let users = p.objects.iter().filter(|q| q.method == o.method).count().max(1) as f64;
            (*mesh, own.fixed_ms, own.screen_ms + (shared.fixed_ms + shared.screen_ms) / users)
        })
        .collect();
    (per, base.fixed_ms + base.screen_ms)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::methods::{BVH, DISTANCE};
    use crate::plan::{plan, MapPlan};

    fn one(p: &Plan, name: &str, ms: f64) -> (Vec<(usize, Cost, Cost)>, Cost) {
        attribute(p, &[(name.to_string(), ms)])
    }

    /// Every pass goes where its stage declares it: maps split among their objects (fixed),
    /// camera passes among theirs (screen), the frame's stages and what no stage records to
    /// the base, a ray tracer's kernels whole to each of its objects.
    #[test]
    fn passes_go_to_the_objects_of_the_stages_that_record_them() {
        let scene = crate::scenes::flat_glass().unwrap();
        let q = crate::quality::Quality::default();
        let screen = |ms| Cost { fixed_ms: 0.0, screen_ms: ms };

        let p = plan(&scene, DISTANCE, &q);
        assert!(p.objects.len() >= 2, "{:?}", p.objects);
        let n = p.objects.len() as f64;
        for s in &p.stages {
            let (objects, base) = one(&p, s.name(), 4.0);
            match s {
                StageSpec::Map(MapPlan { objects: meshes, .. }) => {
                    assert_eq!(base, Cost::default());
                    for (mesh, own, shared) in objects {
                        let w = if meshes.contains(&mesh) { 4.0 / meshes.len() as f64 } else { 0.0 };
                        assert_eq!((own, shared), (Cost { fixed_ms: w, screen_ms: 0.0 }, Cost::default()), "{}", s.name());
                    }
                }
                StageSpec::Camera(_) => {
                    assert_eq!(base, Cost::default());
                    objects.iter().for_each(|o| assert_eq!((o.1, o.2), (screen(4.0 / n), Cost::default()), "{}", s.name()));
                }
                StageSpec::Direct => assert_eq!(base, screen(4.0)),
                StageSpec::Upload | StageSpec::Shadows => assert_eq!(base, Cost { fixed_ms: 4.0, screen_ms: 0.0 }),
                _ => {}
            }
        }
        // A pass no stage records (the frame's resolve, say): the base's.
        let (objects, base) = one(&p, "frame.resolve", 2.0);
        assert_eq!(base, screen(2.0));
        assert!(objects.iter().all(|o| o.1 == Cost::default() && o.2 == Cost::default()));

        // A ray tracer's kernels, named under its declared prefix: each object pays them whole.
        let p = plan(&scene, BVH, &q);
        let prefix = BVH.gpu.unwrap().camera.profiled.prefix;
        assert!(!prefix.is_empty());
        let (objects, base) = one(&p, &format!("{prefix}kernel"), 3.0);
        assert_eq!(base, Cost::default());
        assert_eq!(objects.len(), p.objects.len());
        objects.iter().for_each(|o| assert_eq!((o.1, o.2), (Cost::default(), screen(3.0))));

        // The layered map of the whole scene (`MapInfo::shared`): each of its objects pays it
        // whole, once per frame for the method, as fixed time.
        let p = plan(&scene, crate::methods::LAYERED, &q);
        assert!(p.objects.len() >= 2 && p.stages.iter().any(|s| matches!(s, StageSpec::Map(m) if m.shared)));
        let (objects, base) = one(&p, "layered.peel", 5.0);
        assert_eq!(base, Cost::default());
        objects.iter().for_each(|o| assert_eq!((o.1, o.2), (Cost::default(), Cost { fixed_ms: 5.0, screen_ms: 0.0 })));

        // The caustics (a frame effect): the base's, fixed where independent of the output
        // size, whatever the generators' method.
        let scene = crate::scenes::caustic_ball().unwrap();
        for method in [DISTANCE, BVH] {
            let p = plan(&scene, method, &q);
            let c = p.caustics.as_ref().expect("the caustic ball has caustics");
            for name in c.passes(&q).into_iter().chain(["caustics.project"]) {
                let (objects, base) = one(&p, name, 2.0);
                let fixed = name != "caustics.project";
                let want = if fixed { Cost { fixed_ms: 2.0, screen_ms: 0.0 } } else { Cost { fixed_ms: 0.0, screen_ms: 2.0 } };
                assert_eq!(base, want, "{name}");
                assert!(objects.iter().all(|o| o.1 == Cost::default() && o.2 == Cost::default()), "{name}");
            }
        }
    }
}
