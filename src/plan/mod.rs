//! Scene + choices → Plan: "model only what the scene requires". The plan holds, for each
//! specular object, its method (chosen by the user, by the scene file or by the planner,
//! with the reason) and that method's maps; per light a shadow map; and the frame's
//! ordered stages, which are exactly what the renderer records. A scene without specular
//! objects gets no map pass and no cube map; one without punctual lights no shadow map.

pub mod budget;
pub mod facts;
pub mod ids;
pub mod knobs;
pub mod predict;
pub mod reflection_points;
pub mod types;

use glam::Vec3;

use crate::error::{Error, Result};
pub use crate::methods::registry::CameraPass;
pub use types::*;

use crate::methods::FAMILIES;
use crate::quality::{Planner, Quality};
use crate::scene::{LightKind, Scene};
use facts::ObjectFacts;

impl Plan {
    pub fn object(&self, mesh: usize) -> Option<&ObjectPlan> {
        self.objects.iter().find(|o| o.mesh == mesh)
    }

    /// Per object (in `objects`' order) the positions of the other objects it sees
    /// (`ObjectPlan::sees`): composition's input (`registry::Composes`).
    pub fn sight(&self) -> Vec<Vec<usize>> {
        let at = |m: &usize| self.objects.iter().position(|o| o.mesh == *m);
        self.objects.iter().map(|o| o.sees.iter().filter_map(at).collect()).collect()
    }

    /// The map pass named `name`, if planned.
    pub fn map(&self, name: &str) -> Option<&MapPlan> {
        self.stages.iter().find_map(|s| match s {
            StageSpec::Map(m) if m.name == name => Some(m),
            _ => None,
        })
    }

    /// Meshes whose method is `m`.
    pub fn objects_with(&self, m: Method) -> Vec<usize> {
        self.objects.iter().filter(|o| o.method == m).map(|o| o.mesh).collect()
    }

    /// Whether every object's method renders on the GPU.
    pub fn is_gpu(&self) -> bool {
        self.objects.iter().all(|o| o.method.is_gpu()) && !matches!(self.choice, Choice::Method(m) if !m.is_gpu())
    }

    /// After objects moved: the geometry-dependent parts of the plan (reference points,
    /// proxies, the cube maps' near plane) as the planner computes them for `scene` with
    /// every object kept on its method. Refused, with the plan unchanged, when that plan
    /// would have another structure (other stages, maps or shadow maps).
    pub fn refresh_geometry(&mut self, scene: &Scene) -> Result<()> {
        let methods = |p: &Plan| p.objects.iter().map(|o| (o.mesh, o.method.name())).collect::<Vec<_>>();
        // How each object shows in the others' maps, and the maps it keeps (composition may
        // change with a move: who sees a self-refracting object decides the cycles).
        let shading = |p: &Plan| {
            p.objects
                .iter()
                .map(|o| (o.map_shading, o.leaves_out, o.maps.iter().map(|m| (m.pass, m.layer)).collect::<Vec<_>>()))
                .collect::<Vec<_>>()
        };
        // The stages as a structure: a map's bytes may follow the geometry (the layered map's
        // depth complexity) without changing what the frame records.
        let structure = |p: &Plan| {
            p.stages
                .iter()
                .map(|s| match s {
                    StageSpec::Map(m) => StageSpec::Map(MapPlan { bytes: 0, ..m.clone() }),
                    s => s.clone(),
                })
                .collect::<Vec<_>>()
        };
        let same = |fresh: &Plan| {
            structure(fresh) == structure(self)
                && (fresh.inter_object, fresh.cycles, fresh.frame_latency) == (self.inter_object, self.cycles, self.frame_latency)
                && shading(fresh) == shading(self)
                && fresh.shadow_cubes == self.shadow_cubes
                && fresh.shadow_planes == self.shadow_planes
                && methods(fresh) == methods(self)
                && fresh.envmaps.iter().map(|e| e.mesh).eq(self.envmaps.iter().map(|e| e.mesh))
                && fresh.caustics == self.caustics
        };
        // The plan a fresh renderer would get; if the planner would now choose otherwise for
        // some object, the same plan with every object kept on its method — unless `auto`
        // predicts the new choice better by more than its hysteresis (then a new renderer).
        let asked = Choices { method: self.choice, objects: self.overrides.clone() };
        let kept = Choices { method: self.choice, objects: self.objects.iter().map(|o| (o.name.clone(), o.method)).collect() };
        // Under `auto` with its hysteresis, the choice is predicted again only once the view
        // has moved by REPLAN_MOTION since it was last predicted: a prediction measures the
        // scene on the CPU (0.1–0.6 s in a release build), and an engine moves objects
        // every frame.
        let settled = self.choice == Choice::Auto && self.quality.plan.plan_hysteresis && self.anchor.motion(scene) < REPLAN_MOTION;
        let mut fresh = if settled {
            plan_inner(scene, &kept, &self.quality, true, self.target.as_ref())?
        } else {
            plan_inner(scene, &asked, &self.asked_quality, true, self.target.as_ref())?
        };
        if !settled && (methods(&fresh) != methods(self) || fresh.quality != self.quality) {
            if self.choice == Choice::Auto && !self.quality.plan.plan_hysteresis {
                let changed: Vec<String> = fresh
                    .objects
                    .iter()
                    .zip(&self.objects)
                    .filter(|(n, o)| n.method != o.method)
                    .map(|(n, o)| format!("{} {} → {}", n.name, o.method, n.method))
                    .chain(knob_changes(&self.quality, &fresh.quality))
                    .collect();
                return Err(Error::PlanChanged(format!("auto: {} (plan_hysteresis=off: re-chosen as a fresh plan)", changed.join(", "))));
            }
            if self.choice == Choice::Auto {
                let nominal = predict::Target::nominal();
                if let Some(t) = self.target.as_ref().or(nominal.as_ref()) {
                    let facts = facts::SceneFacts::new(scene, &self.quality, true);
                    let now = Choices { method: self.choice, objects: fresh.objects.iter().map(|o| (o.name.clone(), o.method)).collect() };
                    let knobs = (&self.quality, &fresh.quality);
                    if let Some(why) = predict::switch(scene, &facts, (&kept, knobs.0), (&now, knobs.1), t)? {
                        return Err(Error::PlanChanged(format!("auto: {why}")));
                    }
                }
            }
            if let Ok(k) = plan_inner(scene, &kept, &self.quality, true, self.target.as_ref()) {
                fresh = k;
            }
        }
        if !same(&fresh) {
            let what = match structure(&fresh).iter().zip(&structure(self)).find(|(a, b)| a != b) {
                Some((a, b)) => format!("{} was {b:?}, now {a:?}", a.name()),
                None if fresh.cycles != self.cycles || fresh.inter_object != self.inter_object => {
                    format!("inter-object cycles {} → {}", self.cycles * self.inter_object as u32, fresh.cycles * fresh.inter_object as u32)
                }
                None if shading(&fresh) != shading(self) => "how the objects show in each other's maps (composition)".to_string(),
                None => format!(
                    "passes now {}, maps of {:?}",
                    fresh.passes.join(", "),
                    fresh.envmaps.iter().map(|e| e.mesh).collect::<Vec<_>>()
                ),
            };
            return Err(Error::PlanChanged(what));
        }
        for (o, f) in self.objects.iter_mut().zip(&fresh.objects) {
            o.reference_point = f.reference_point;
            o.own_reference_point = f.own_reference_point;
            o.reference_note = f.reference_note.clone();
        }
        for (e, f) in self.envmaps.iter_mut().zip(&fresh.envmaps) {
            e.reference_point = f.reference_point;
        }
        self.layered_centre = fresh.layered_centre;
        self.layered_extent = fresh.layered_extent.clone();
        self.stages = fresh.stages;
        self.captures = fresh.captures;
        for f in FAMILIES {
            if let Some(h) = f.refresh {
                h(self);
            }
        }
        self.cube_near = fresh.cube_near;
        self.proxy_radius = fresh.proxy_radius;
        self.proxy_box = fresh.proxy_box;
        if !settled {
            self.anchor = Anchor::of(scene);
        }
        Ok(())
    }

    /// The plan for a device that may lack what some methods need (`missing(m)`: the method
    /// that serves instead of `m`, and why; `DeviceNeeds::missing_on`): every object whose
    /// method the device cannot run gets that fallback, planned as if it had been asked for,
    /// and its reason says so. The plan itself when nothing is missing.
    pub fn for_device(mut self, scene: &Scene, missing: impl Fn(Method) -> Option<(Method, String)>) -> Result<Plan> {
        // The hybrid search auto chose (on another device's costs) needs ray queries too:
        // off where the device has none, said in the reasons of the objects that read it.
        // (Asked for by the caller, it stays, and the stage refuses with the reason.)
        if self.quality.distance.hybrid.traces() && !self.asked_quality.distance.hybrid.traces() {
            if let Some((_, why)) = missing(crate::methods::RAY_QUERY) {
                let hybrid = self.quality.get("hybrid");
                self.quality.distance.hybrid = crate::methods::distance::knobs::Hybrid::Off;
                for o in self.objects.iter_mut().filter(|o| o.method.knobs.contains(&"hybrid")) {
                    o.knobs = o.method.knobs.iter().map(|k| (*k, self.quality.get(k))).collect();
                    o.reason = format!("{}; hybrid={hybrid} cannot run on this device ({why}): off", o.reason);
                }
            }
        }
        let lacking: Vec<(usize, Method, Method, String)> =
            self.objects.iter().filter_map(|o| missing(o.method).map(|(f, why)| (o.mesh, o.method, f, why))).collect();
        let whole = match self.choice {
            Choice::Method(m) => missing(m),
            _ => None,
        };
        if lacking.is_empty() && whole.is_none() {
            return Ok(self);
        }
        let sub = |m: Method| missing(m).map_or(m, |(f, _)| f);
        let method = match self.choice {
            Choice::Method(m) => Choice::Method(sub(m)),
            c => c,
        };
        let mut objects: Vec<(String, Method)> = self.overrides.iter().map(|(n, m)| (n.clone(), sub(*m))).collect();
        // Objects `auto` gave the method (on another device's costs) keep their fallback.
        for (mesh, _, f, _) in &lacking {
            let name = &scene.meshes[*mesh].name;
            if !objects.iter().any(|(n, _)| names_object(scene, *mesh, n)) {
                objects.push((name.clone(), *f));
            }
        }
        let mut fresh = plan_inner(scene, &Choices { method, objects }, &self.quality, true, self.target.as_ref())?;
        fresh.asked_quality = self.asked_quality.clone();
        for o in &mut fresh.objects {
            if let Some((_, m, f, why)) = lacking.iter().find(|(mesh, ..)| *mesh == o.mesh) {
                let before = self.objects.iter().find(|x| x.mesh == o.mesh).map_or(String::new(), |x| x.reason.clone());
                o.reason = format!("{before}; '{}' cannot run on this device ({why}): its fallback {}", m.name, f.name);
            }
        }
        Ok(fresh)
    }

    /// Device memory the plan's maps will hold (bytes), excluding the frame's own images.
    pub fn map_bytes(&self) -> u64 {
        let caustics = self.caustics.as_ref().map_or(0, |c| c.bytes);
        caustics + self.stages.iter().map(|s| if let StageSpec::Map(m) = s { m.bytes } else { 0 }).sum::<u64>()
    }
}

/// Per-object choices: the whole scene's method and per-object overrides by name.
#[derive(Clone, Debug, PartialEq)]
pub struct Choices {
    pub method: Choice,
    /// (glTF node or mesh name, method): overrides `method` and the scene file.
    pub objects: Vec<(String, Method)>,
}

impl Choices {
    pub fn all(method: impl Into<Choice>) -> Choices {
        Choices { method: method.into(), objects: Vec::new() }
    }
}

impl Default for Choices {
    fn default() -> Choices {
        Choices::all(Choice::Auto)
    }
}

/// The pass `reference` reports: one CPU pass, no maps.
pub const REFERENCE_PASS: &str = "reference.trace";

/// How far the view must move from where `auto` last predicted its choice (a fraction of
/// the distance from the camera to a specular object, of the camera's field of view, or of
/// an object's size: `Anchor::motion`) before a move predicts again. A choice depends on
/// what each object covers and sees; at a tenth of the view those change by about a fifth
/// (coverage goes with the distance squared), within the hysteresis' margins.
pub const REPLAN_MOTION: f32 = 0.1;

/// The plan of one method for the whole scene (objects it cannot serve get its fallback),
/// or of the planner (`Choice::Auto`, honouring the scene file's `extras.specula.method`
/// where it can; `plan_with` reports a hint that cannot serve its object as an error).
pub fn plan(scene: &Scene, method: impl Into<Choice>, quality: &Quality) -> Plan {
    let choices = Choices::all(method);
    // A whole-scene method cannot fail (the registry checks that every method serves every
    // class or falls back to one that does), nor can the planner without the scene's hints.
    plan_inner(scene, &choices, quality, true, None).or_else(|_| plan_inner(scene, &choices, quality, false, None)).unwrap_or_else(|e| {
        // Unreachable by the registry's checks; a plan that renders nothing but says why.
        let mut p =
            plan_inner(scene, &Choices::all(crate::methods::REFERENCE), quality, false, None).unwrap_or_else(|_| empty_plan(quality));
        p.objects.iter_mut().for_each(|o| o.reason = format!("no GPU plan: {e}"));
        p
    })
}

fn empty_plan(quality: &Quality) -> Plan {
    Plan {
        choice: Choice::Method(crate::methods::REFERENCE),
        overrides: Vec::new(),
        target: None,
        prediction: None,
        quality: quality.clone(),
        asked_quality: quality.clone(),
        shadow_cubes: Vec::new(),
        shadow_planes: Vec::new(),
        objects: Vec::new(),
        envmaps: Vec::new(),
        layered_centre: None,
        layered_extent: None,
        captures: Vec::new(),
        stages: Vec::new(),
        passes: vec![REFERENCE_PASS],
        cube_near: 1e-4,
        cycles: 0,
        inter_object: false,
        frame_latency: false,
        proxy_radius: 1.0,
        proxy_box: (Vec3::ZERO, Vec3::ZERO),
        mirrors: Vec::new(),
        map_mirrors: Vec::new(),
        mirror_layers: 0,
        caustics: None,
        anchor: Anchor::default(),
    }
}

/// Which method an object gets, and why (`hints`: honour the scene file's methods).
fn choose(
    scene: &Scene,
    facts: &ObjectFacts,
    choices: &Choices,
    hints: bool,
    auto: Option<&predict::AutoPlan>,
) -> Result<(Method, String)> {
    let mesh = &scene.meshes[facts.mesh];
    let class = facts.class;
    let curved = || format!("only {} trace them", Method::curved_ray_tracers().join(", "));
    let check = |m: Method, source: &str| -> Result<(Method, String)> {
        if facts.graded && !m.traces_curved_rays() {
            Err(Error::invalid(
                format!("object '{}'", mesh.name),
                format!("method '{}' cannot serve a graded-index medium, whose rays curve (survey §6.5): {}", m.name, curved()),
            ))
        } else if let Some(f) = m.fallback.filter(|f| m.can_serve(class) && m.shape.misses_from_this_view(facts) && f.fits(facts)) {
            // A chosen method that cannot serve the object from where the camera is now (a
            // curved reflector with several reflection points from this eye) takes its
            // fallback, with the refusal as the reason, rather than failing the plan: the
            // camera (or the object) moves, and an engine moves them every frame.
            Ok((f, format!("{source}: {}, refused from this view — it serves {}: its fallback {}", m.name, m.shape.refusal(facts), f.name)))
        } else if m.can_serve(class) && !m.shape.fits(facts) {
            Err(Error::invalid(format!("object '{}'", mesh.name), format!("method '{}' serves {}", m.name, m.shape.refusal(facts))))
        } else if m.can_serve(class) {
            Ok((m, format!("{source}: {}", m.name)))
        } else {
            let serves: Vec<_> = m.serves.iter().map(|c| c.label()).collect();
            Err(Error::invalid(
                format!("object '{}'", mesh.name),
                format!("method '{}' cannot serve a {} (it serves: {})", m.name, class.label(), serves.join(", ")),
            ))
        }
    };
    if let Some((_, m)) = choices.objects.iter().rev().find(|(n, _)| names_object(scene, facts.mesh, n)) {
        return check(*m, "chosen for this object");
    }
    if let Choice::Method(m) = choices.method {
        if m.fits(facts) {
            return Ok((m, format!("--method {}", m.name)));
        }
        if facts.graded && !m.traces_curved_rays() {
            let f = crate::methods::BVH;
            return Ok((
                f,
                format!("--method {} does not trace the curved rays of a graded-index medium (survey §6.5): {}", m.name, f.name),
            ));
        }
        if let Some(f) = m.fallback.filter(|f| f.fits(facts)) {
            let what =
                if m.can_serve(class) { format!("{} {}", m.shape.misfit_of(facts), class.label()) } else { format!("a {}", class.label()) };
            return Ok((f, format!("--method {} does not serve {what}: its fallback {}", m.name, f.name)));
        }
        return check(m, "--method");
    }
    if let Some(name) = mesh.method.as_ref().filter(|_| hints) {
        let m = Method::parse(name).map_err(|e| Error::invalid(format!("object '{}' extras.specula.method", mesh.name), e.to_string()))?;
        return check(m, "the scene file's extras.specula.method");
    }
    let picked = auto.and_then(|a| match a.choices.method {
        Choice::Method(m) if a.choices.objects.is_empty() => Some((a, m)),
        _ => a.choices.objects.iter().find(|(n, _)| names_object(scene, facts.mesh, n)).map(|(_, m)| (a, *m)),
    });
    match picked {
        // The measured choice among methods whose rays stay straight: a graded medium gets
        // the exact tracer (the ray pipeline marches its curved rays).
        Some((_, m)) if facts.graded && !m.traces_curved_rays() => Ok((
            crate::methods::BVH,
            format!("auto: a graded-index medium's rays curve (survey §6.5), which {} does not trace: bvh", m.name),
        )),
        Some((a, m)) => Ok((m, a.reason(&mesh.name, m))),
        // No prediction covers the object (no stored models): the exact tracer serves every
        // class.
        None => Ok((crate::methods::BVH, "auto: no prediction covers this object: the exact tracer".into())),
    }
}

/// Whether `name` addresses mesh `m` (its node or mesh name; meshes imported from glTF
/// are named after their node, with the mesh name kept as an alias).
pub fn names_object(scene: &Scene, m: usize, name: &str) -> bool {
    let mesh = &scene.meshes[m];
    mesh.name == name || mesh.aliases.iter().any(|a| a == name)
}

/// Checks that every per-object choice names a specular object of the scene.
fn check_names(scene: &Scene, choices: &Choices) -> Result<()> {
    for (name, _) in &choices.objects {
        let specular: Vec<&str> = scene.specular_meshes().map(|(_, m)| m.name.as_str()).collect();
        let found = scene.meshes.iter().enumerate().find(|(i, _)| names_object(scene, *i, name));
        match found {
            None => {
                return Err(Error::invalid(
                    "object",
                    format!("no object is named '{}' (specular objects: {})", crate::error::clip(name), specular.join(", ")),
                ))
            }
            Some((i, _)) if !scene.materials[scene.meshes[i].material].kind.is_specular() => {
                return Err(Error::invalid(
                    format!("object '{name}'"),
                    format!(
                        "is not specular (material '{}'): only specular objects take a method",
                        scene.materials[scene.meshes[i].material].name
                    ),
                ))
            }
            _ => {}
        }
    }
    Ok(())
}

/// The knobs `b` sets otherwise than `a`, as `knob a → b`.
pub(crate) fn knob_changes(a: &Quality, b: &Quality) -> Vec<String> {
    crate::quality::KNOBS
        .iter()
        .filter(|k| a.get(k.name) != b.get(k.name))
        .map(|k| format!("{} {} → {}", k.name, a.get(k.name), b.get(k.name)))
        .collect()
}

/// The plan for per-object choices (`auto` predicted for a nominal frame on the stored
/// calibration's device: [`plan_for`] names the frame).
pub fn plan_with(scene: &Scene, choices: &Choices, quality: &Quality) -> Result<Plan> {
    plan_inner(scene, choices, quality, true, None)
}

/// The plan for per-object choices, `auto` predicted for `target` (the frame's size and the
/// device's unit costs).
pub fn plan_for(scene: &Scene, choices: &Choices, quality: &Quality, target: Option<&predict::Target>) -> Result<Plan> {
    plan_inner(scene, choices, quality, true, target)
}

/// `auto`'s choice for the objects `choices` and (with `hints`) the scene file leave to it.
fn auto_plan(
    scene: &Scene,
    facts: &facts::SceneFacts,
    choices: &Choices,
    quality: &Quality,
    hints: bool,
    target: Option<&predict::Target>,
) -> Result<Option<predict::AutoPlan>> {
    if choices.method != Choice::Auto {
        return Ok(None);
    }
    let mut forced = choices.clone();
    for f in facts.objects.iter().filter(|_| hints) {
        let mesh = &scene.meshes[f.mesh];
        let named = forced.objects.iter().any(|(n, _)| names_object(scene, f.mesh, n));
        if let (false, Some(Ok(m))) = (named, mesh.method.as_deref().map(Method::parse)) {
            forced.objects.push((mesh.name.clone(), m));
        }
    }
    if facts.objects.iter().all(|f| forced.objects.iter().any(|(n, _)| names_object(scene, f.mesh, n))) {
        return Ok(None);
    }
    let nominal = predict::Target::nominal();
    match target.or(nominal.as_ref()) {
        Some(t) => predict::auto(scene, facts, &forced, quality, t),
        None => Ok(None),
    }
}

/// The radius of proxy-sphere's proxy: the `proxy_radius` knob, else the scene's mean
/// half extent.
pub fn proxy_radius(scene: &Scene, quality: &Quality) -> f32 {
    let bounds = scene.bounds();
    quality.envmap.proxy_radius.unwrap_or_else(|| {
        let half = (bounds.max - bounds.min) * 0.5;
        if bounds.is_empty() {
            1.0
        } else {
            ((half.x + half.y + half.z) / 3.0).max(1e-6)
        }
    })
}

fn plan_inner(scene: &Scene, choices: &Choices, quality: &Quality, hints: bool, target: Option<&predict::Target>) -> Result<Plan> {
    check_names(scene, choices)?;
    let bounds = scene.bounds();
    let diag = bounds.diagonal();
    let cube_near = if diag > 0.0 { diag * 1e-5 } else { 1e-4 };
    let proxy_radius = proxy_radius(scene, quality);
    // Deep facts (convexity, mutual visibility) for the planner and for mixed choices,
    // whose composition depends on who sees whom; a whole-scene method needs none.
    let whole_scene = matches!(choices.method, Choice::Method(_)) && choices.objects.is_empty();
    let scene_facts = facts::SceneFacts::new(scene, quality, !whole_scene);
    let auto = auto_plan(scene, &scene_facts, choices, quality, hints, target)?;
    // The frame's knobs: the asked ones, with those `auto` chose over them.
    let asked_quality = quality.clone();
    let quality = auto.as_ref().map_or(quality, |a| &a.quality);
    let mut objects = Vec::new();
    for f in &scene_facts.objects {
        let (method, reason) = choose(scene, f, choices, hints, auto.as_ref())?;
        objects.push(ObjectPlan {
            mesh: f.mesh,
            name: scene.meshes[f.mesh].name.clone(),
            class: f.class,
            method,
            reason,
            reference_point: f.reference_point,
            own_reference_point: f.reference_point,
            reference_note: f.reference_note.clone(),
            map_shading: MapShading::Sky,
            leaves_out: method.gpu.map_or(LeavesOut::Itself, |g| g.leaves_out),
            maps: Vec::new(),
            passes: Vec::new(),
            knobs: method.knobs.iter().map(|k| (*k, quality.get(k))).collect(),
            sees: scene_facts.objects.iter().filter(|g| g.mesh != f.mesh && f.sees(g.mesh)).map(|g| g.mesh).collect(),
        });
    }
    let mut p = Plan {
        choice: choices.method,
        overrides: choices.objects.clone(),
        target: target.cloned(),
        prediction: auto.as_ref().map(|a| a.prediction.clone()),
        quality: quality.clone(),
        asked_quality,
        shadow_cubes: Vec::new(),
        shadow_planes: Vec::new(),
        objects,
        envmaps: Vec::new(),
        layered_centre: None,
        layered_extent: None,
        captures: Vec::new(),
        stages: Vec::new(),
        passes: Vec::new(),
        cube_near,
        cycles: 1,
        inter_object: false,
        frame_latency: false,
        proxy_radius,
        proxy_box: (bounds.min, bounds.max),
        mirrors: Vec::new(),
        map_mirrors: Vec::new(),
        mirror_layers: 0,
        caustics: None,
        anchor: Anchor::of(scene),
    };
    if !p.is_gpu() {
        p.stages.clear();
        p.passes = vec![REFERENCE_PASS];
        p.cycles = 0;
        return Ok(p);
    }
    // A whole-scene method keeps its own behaviour (its fallbacks do not compose); mixed
    // choices compose through inter-object cycles where an object's map sees a
    // self-refracting one over at least `facts::MIN_COVERAGE` of its directions.
    let self_refracting = |o: &ObjectPlan| o.method.gpu.is_some_and(|g| g.map_shading == MapShading::Refractor);
    let composes = !whole_scene
        && p.quality.frame.compose
        && p.objects.iter().filter(|o| self_refracting(o)).any(|o| scene_facts.objects.iter().any(|f| f.sees(o.mesh)));
    // Layered maps (§4.5): one map of the whole scene, shared by the objects that take it.
    for f in FAMILIES {
        if let Some(h) = f.plan_objects {
            h(scene, &mut p);
        }
    }
    stages(scene, &mut p, composes);
    Ok(p)
}

/// Derives the frame's stages from the objects' methods and the families' planning hooks
/// (`registry::Family`).
fn stages(scene: &Scene, p: &mut Plan, composes: bool) {
    let q = p.quality.clone();
    let has_diffuse = scene.meshes.iter().any(|m| !scene.materials[m.material].kind.is_specular());
    let mut st = PlanStages {
        maps: Vec::new(),
        stages: Vec::new(),
        shades_scene: matches!(p.choice, Choice::Method(m) if m.gpu.is_some_and(|g| g.shades_every_pixel)),
    };
    if !scene.textures.is_empty() || scene.environment.is_some() {
        st.stages.push(StageSpec::Upload);
    }
    for f in FAMILIES {
        if let Some(h) = f.plan_frame {
            h(scene, p);
        }
    }
    // Shadows matter only where a diffuse surface receives light, and not at all where a
    // whole-scene ray tracer shades every pixel with exact shadow rays (survey §2), unless
    // caustic photons need them (occluders between a light and a generator).
    if has_diffuse && q.frame.shadows && (!st.shades_scene || p.caustics.is_some()) {
        for (i, l) in scene.lights.iter().enumerate() {
            match l.kind {
                LightKind::Point | LightKind::Spot { .. } => p.shadow_cubes.push(i),
                LightKind::Directional => p.shadow_planes.push(i),
            }
        }
    }
    if !(p.shadow_cubes.is_empty() && p.shadow_planes.is_empty()) {
        st.stages.push(StageSpec::Shadows);
    }
    st.stages.push(StageSpec::Direct);

    // Inter-object cycles (§4.3): asked for by a method, or needed so that mixed methods
    // compose (a mirror's map shows the refractor-mapped glass refracting the room).
    let gpu = |m: Method| m.gpu.expect("GPU plan");
    let methods: Vec<Method> = p.objects.iter().map(|o| o.method).collect();
    let asks = methods.iter().any(|&m| gpu(m).map_shading == MapShading::Traced);
    p.inter_object = asks || composes;
    p.frame_latency = asks && q.distance.frame_latency;
    p.cycles = methods.iter().map(|&m| (gpu(m).cycles)(&q)).max().unwrap_or(1).max(1);
    if composes && !p.frame_latency {
        p.cycles = p.cycles.max(2);
    }
    if p.frame_latency {
        p.cycles = 1;
    }

    // Maps: one pass per map kind over the objects that need it, layers in mesh order.
    let mut cameras: Vec<CameraPlan> = Vec::new();
    for o in &mut p.objects {
        let spec = gpu(o.method);
        o.map_shading = if p.inter_object { spec.map_shading } else { MapShading::Sky };
        for info in spec.maps {
            st.add_map(o, info.kind(), (info.describe)(&q, (0, 0)));
        }
        let cam = spec.camera;
        match cameras.iter_mut().find(|c| c.name == cam.name) {
            Some(c) => c.objects.push((o.mesh, cam.flags)),
            None => cameras.push(CameraPlan {
                name: cam.name,
                vertex: cam.vertex,
                fragment: cam.fragment,
                order: cam.order,
                profiled: cam.profiled,
                objects: vec![(o.mesh, cam.flags)],
            }),
        }
        o.passes.push(cam.name);
    }
    for f in FAMILIES {
        if let Some(h) = f.plan_stages {
            h(scene, p, &mut st);
        }
    }
    let PlanStages { mut maps, mut stages, .. } = st;
    // The cube-mapped objects and their views.
    for o in &p.objects {
        let cube = o.maps.iter().any(|m| maps.iter().any(|mp| mp.name == m.pass && mp.cube));
        if cube {
            p.envmaps.push(EnvmapPlan { mesh: o.mesh, layer: p.envmaps.len() as u32, reference_point: o.own_reference_point });
        }
    }
    for m in &mut maps {
        let info = crate::methods::map_named(m.name).expect("a planned map is registered");
        m.bytes = (info.bytes)(p, m.objects.len() as u32, (0, 0));
    }
    for o in &mut p.objects {
        for om in &mut o.maps {
            let m = maps.iter().find(|m| m.name == om.pass).expect("planned map");
            om.bytes = m.bytes / m.objects.len().max(1) as u64;
        }
    }
    for f in FAMILIES {
        if let Some(h) = f.plan_views {
            h(scene, p);
        }
    }
    stages.extend(maps.into_iter().map(StageSpec::Map));
    stages.extend(cameras.into_iter().map(StageSpec::Camera));
    // Stable sort: equal orders keep their registry order.
    stages.sort_by_key(|s| s.order());
    p.passes = stages.iter().flat_map(|s| s.passes()).collect();
    p.stages = stages;
}

/// `specula plan`'s table: per object its method, reason, maps, passes and knobs.
pub fn table(p: &Plan, scene: &Scene) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let _ = writeln!(s, "method {} · {} specular object(s) · passes: {}", p.choice.name(), p.objects.len(), p.passes.join(", "));
    if p.inter_object {
        let _ = writeln!(s, "inter-object cycles: {}{}", p.cycles, if p.frame_latency { " (one per frame, frame latency)" } else { "" });
    }
    let chosen = knob_changes(&p.asked_quality, &p.quality);
    if !chosen.is_empty() {
        let _ = writeln!(s, "frame knobs chosen by auto: {}", chosen.join(", "));
    }
    for o in &p.objects {
        let mat = &scene.materials[scene.meshes[o.mesh].material];
        let _ = writeln!(s, "\n{} ({}, material '{}'): {}", o.name, o.class.label(), mat.name, o.method.name);
        let _ = writeln!(s, "  reason     {}", o.reason);
        let r = o.reference_point;
        let _ = writeln!(
            s,
            "  ref point  ({:.4}, {:.4}, {:.4}){}",
            r.x,
            r.y,
            r.z,
            o.reference_note.as_ref().map_or(String::new(), |n| format!(" — {n}"))
        );
        for m in &o.maps {
            let _ = writeln!(s, "  map        {} layer {}: {} ({:.2} MiB)", m.pass, m.layer, m.what, m.bytes as f64 / (1 << 20) as f64);
        }
        let _ = writeln!(s, "  passes     {}", o.passes.join(", "));
        let knobs: Vec<String> = o.knobs.iter().map(|(k, v)| format!("{k}={v}")).collect();
        let _ = writeln!(s, "  knobs      {}", if knobs.is_empty() { "-".into() } else { knobs.join(" ") });
    }
    let pairs = in_view(p, scene);
    if !pairs.is_empty() {
        let _ = writeln!(s, "\nin view (how each object shows in the view of another that sees it):");
        for l in &pairs {
            let _ = writeln!(s, "  {l}");
        }
    }
    for d in FAMILIES.iter().filter_map(|f| f.describe).filter_map(|h| h(p, scene)) {
        let _ = writeln!(s, "\n{d}");
    }
    let _ = writeln!(s, "\nmaps: {:.2} MiB", p.map_bytes() as f64 / (1 << 20) as f64);
    s
}

/// Per pair of objects where one sees the other (`ObjectPlan::sees`), how the seen one
/// shows in the viewer's view and why (issue 33's contract): traced by the viewer's rays,
/// drawn by its own method in the viewer's mirrored views, found in the shared layered map,
/// or — in the viewer's maps — by its map shading.
pub fn in_view(p: &Plan, scene: &Scene) -> Vec<String> {
    let whole_scene = matches!(p.choice, Choice::Method(_)) && p.overrides.is_empty();
    let mut out = Vec::new();
    for a in &p.objects {
        for b in a.sees.iter().filter_map(|&m| p.object(m)) {
            let g = a.method.gpu;
            let graded = scene.materials[scene.meshes[b.mesh].material].graded.is_some();
            let rays = g.is_none() || a.method.family == "raytrace";
            let how = if rays {
                "traced by its rays, exactly (the ray pipeline)".to_string()
            } else if g.is_some_and(|g| (g.views)(&p.quality) > 0) {
                format!("drawn by its own method ({}) in the mirrored views", b.method.name)
            } else if g.is_some_and(|g| g.leaves_out == LeavesOut::Nothing) {
                "found in the shared layered map (the whole scene, peeled) and traced on through its layers (§4.5)".to_string()
            } else {
                let by_map = match b.map_shading {
                    MapShading::Sky if whole_scene => "as the environment map's reflection (a whole-scene method keeps its own behaviour)",
                    MapShading::Sky if !p.quality.frame.compose => "as the environment map's reflection (compose=off)",
                    MapShading::Sky if p.map_mirrors.contains(&b.mesh) => "by its mirrored view inside the map (one reflection deep)",
                    MapShading::Sky => "as the environment map's reflection (no map of its own planned)",
                    MapShading::Traced => "traced in its own distance map of the previous cycle (§4.3)",
                    MapShading::Refractor => "refracted through its refractor map, then traced in its distance map (§4.4, §4.3)",
                };
                format!("in its maps {by_map}")
            };
            let straight =
                if graded { "; its graded index as a uniform one (straight rays inside: maps do not march the ray equation)" } else { "" };
            out.push(format!("{} shows {}: {how}{}", a.name, b.name, if rays { "" } else { straight }));
        }
    }
    out
}

impl Planner {
    pub fn speed(self) -> bool {
        self == Planner::Speed
    }
}
