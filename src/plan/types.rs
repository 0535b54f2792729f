//! The plan's data: per specular object its method (by id) and maps, the frame's stages in
//! recording order, and what the families planned for the whole frame (shadow maps, planar
//! mirrors' view layers, the shared layered map's centre, the caustics' generators). Plain
//! data that names no family and holds no constructor: built by `plan::plan` and the
//! families' planning hooks (`registry::Family`), read by the frame's stages (which receive
//! it as their frame description) and by the renderer, which looks each stage's constructor
//! up in the registry by its name (`methods::map_named`, `camera_named`, `effect_named`).

use glam::Vec3;

pub use super::ids::{Choice, LeavesOut, MapShading, Method, ObjectClass, Profiled};
use crate::frame::schedule::{order, Deps, LayerField};
use crate::quality::{CausticSpace, Caustics, Quality};

/// One cube-mapped object's views: the six faces around its reference point.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct EnvmapPlan {
    pub mesh: usize,
    /// Index of the object among the plan's cube-mapped objects.
    pub layer: u32,
    pub reference_point: Vec3,
}

/// One object's image-based captures (§3.3): a lattice of `per_axis`³ cube-map centres,
/// x fastest, then y, then z (the order of their layers and views).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct CaptureSet {
    pub mesh: usize,
    pub per_axis: u32,
    pub centres: Vec<Vec3>,
    /// Captures moved out of other objects, with where from.
    pub notes: Vec<String>,
}

/// One map an object gets.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ObjectMap {
    /// The pass that makes it.
    pub pass: &'static str,
    /// The object's layer in that pass's map array.
    pub layer: u32,
    #[serde(skip)]
    pub layer_field: Option<LayerField>,
    pub what: String,
    pub bytes: u64,
}

/// One specular object's plan.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ObjectPlan {
    pub mesh: usize,
    pub name: String,
    pub class: ObjectClass,
    pub method: Method,
    /// Why this method: the user's choice, the scene file's, or the planner's rule.
    pub reason: String,
    pub reference_point: Vec3,
    /// The object's own reference point, before a shared map (layered, §4.5) moved
    /// `reference_point` to the map's: its caustics' cube is centred here, where the
    /// receiver map it searches does not have the object itself in front of the receivers.
    #[serde(skip)]
    pub own_reference_point: Vec3,
    /// Set when the automatic reference point had to move (or could not).
    pub reference_note: Option<String>,
    /// How the object appears in the other objects' distance maps.
    pub map_shading: MapShading,
    /// What its own cube maps leave out.
    pub leaves_out: LeavesOut,
    pub maps: Vec<ObjectMap>,
    /// The passes that draw or map this object.
    pub passes: Vec<&'static str>,
    /// The knobs its method reads, with their values in force.
    pub knobs: Vec<(&'static str, String)>,
    /// The other specular objects it sees over at least `facts::MIN_COVERAGE` of its
    /// directions (empty for a whole-scene method, planned without mutual visibility):
    /// composition's input (who must show right in whose map).
    #[serde(skip)]
    pub sees: Vec<usize>,
}

/// A map pass over all the objects that need that map.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct MapPlan {
    /// The map kind's pass (`frame::stage::MapInfo::name`).
    pub name: &'static str,
    /// Its `MapInfo::order` and whether it is a cube around each object.
    #[serde(skip)]
    pub order: u32,
    #[serde(skip)]
    pub cube: bool,
    /// One map for all its objects (`MapInfo::shared`).
    #[serde(skip)]
    pub shared: bool,
    /// Meshes, in layer order.
    pub objects: Vec<usize>,
    pub bytes: u64,
}

/// A camera pass over the objects of the methods that share it.
#[derive(Clone, Debug, serde::Serialize)]
pub struct CameraPlan {
    /// The camera pass's name (`registry::CameraPass::name`), its shaders and position.
    pub name: &'static str,
    #[serde(skip)]
    pub vertex: &'static str,
    #[serde(skip)]
    pub fragment: &'static str,
    #[serde(skip)]
    pub order: u32,
    /// The passes its stage records, for the budget.
    #[serde(skip)]
    pub profiled: Profiled,
    /// (mesh, push flags of its method).
    pub objects: Vec<(usize, u32)>,
}

impl PartialEq for CameraPlan {
    fn eq(&self, o: &CameraPlan) -> bool {
        self.name == o.name && self.objects == o.objects
    }
}

/// One stage of the frame, in recording order.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum StageSpec {
    /// `scene.upload`: textures and the environment map, first frame only.
    Upload,
    /// `shadow.generate`.
    Shadows,
    /// `scene.direct`.
    Direct,
    Map(MapPlan),
    /// A family's frame effect (caustics, §6), over some objects.
    Effect(EffectPlan),
    Camera(CameraPlan),
}

/// A frame effect over the objects it was planned for.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct EffectPlan {
    /// The effect's name (`frame::stage::EffectInfo::name`).
    pub name: &'static str,
    #[serde(skip)]
    pub order: u32,
    #[serde(skip)]
    pub deps: Deps,
    /// The profiled passes it records, in order.
    #[serde(skip)]
    pub passes: Vec<&'static str>,
    /// Meshes it serves (caustics: the generators).
    pub objects: Vec<usize>,
}

impl StageSpec {
    pub fn name(&self) -> &'static str {
        match self {
            StageSpec::Upload => "scene.upload",
            StageSpec::Shadows => "shadow.generate",
            StageSpec::Direct => "scene.direct",
            StageSpec::Map(m) => m.name,
            StageSpec::Effect(e) => e.name,
            StageSpec::Camera(c) => c.name,
        }
    }
    pub fn order(&self) -> u32 {
        match self {
            StageSpec::Upload => order::UPLOAD,
            StageSpec::Shadows => order::SHADOWS,
            StageSpec::Direct => order::DIRECT,
            StageSpec::Map(m) => m.order,
            StageSpec::Effect(e) => e.order,
            StageSpec::Camera(c) => c.order,
        }
    }

    /// What its output depends on: when a frame must record it again.
    pub fn deps(&self) -> Deps {
        match self {
            StageSpec::Upload | StageSpec::Direct | StageSpec::Camera(_) => Deps::EveryFrame,
            StageSpec::Shadows => Deps::Shadows,
            StageSpec::Map(m) if m.order == order::CAMERA_MAPS => Deps::CameraMap,
            StageSpec::Map(m) if m.order == order::GEOMETRY_MAPS => Deps::Geometry,
            StageSpec::Map(_) => Deps::World,
            StageSpec::Effect(e) => e.deps,
        }
    }

    /// The meshes it was planned for (none for the frame's own stages).
    pub fn objects(&self) -> Vec<usize> {
        match self {
            StageSpec::Map(m) => m.objects.clone(),
            StageSpec::Effect(e) => e.objects.clone(),
            StageSpec::Camera(c) => c.objects.iter().map(|(m, _)| *m).collect(),
            _ => Vec::new(),
        }
    }

    /// The profiled passes it records.
    pub fn passes(&self) -> Vec<&'static str> {
        match self {
            StageSpec::Effect(e) => e.passes.clone(),
            s => vec![s.name()],
        }
    }
}

#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Plan {
    /// What was asked for the whole scene (`--method`).
    pub choice: Choice,
    /// What was asked per object (by name), over `choice`.
    pub overrides: Vec<(String, Method)>,
    /// What `auto` predicted for (the frame's size, the device's unit costs); `None`: the
    /// nominal target.
    #[serde(skip)]
    pub target: Option<super::predict::cost_model::Target>,
    /// What `auto` predicted per object and for the frame (`None` when no object was left
    /// to it).
    #[serde(skip)]
    pub prediction: Option<super::budget::prediction::Prediction>,
    /// The frame's knobs: the asked ones, with any `auto` chose over them
    /// (`predict::auto_variants`).
    pub quality: Quality,
    /// The knobs as asked (what a re-plan starts from).
    #[serde(skip)]
    pub asked_quality: Quality,
    /// Lights that get a cube distance map (point and spot), in cube order.
    pub shadow_cubes: Vec<usize>,
    /// Directional lights, each with a planar distance map, in layer order.
    pub shadow_planes: Vec<usize>,
    /// Every specular object, in mesh order.
    pub objects: Vec<ObjectPlan>,
    /// The objects with cube maps around their own reference points (their views).
    pub envmaps: Vec<EnvmapPlan>,
    /// The shared layered map's centre (§4.5), when an object takes `layered`: its six
    /// views are the peel's, apart from the objects' own (their refractor maps for caustics).
    pub layered_centre: Option<Vec3>,
    /// The scene's depth complexity around `layered_centre`, counted on the CPU along the
    /// texel rays of six faces of at most 64² (`layered::peel::extent_on_cpu`), texel by
    /// texel: its depth is the layers the plan budgets, where each layer of each face holds
    /// surfaces what the peel draws (`layered::drawn_cubes`); the stage counts again on the
    /// GPU at the map's own size.
    #[serde(skip)]
    pub layered_extent: Option<crate::methods::layered::peel::PeelExtent>,
    /// Image-based reflections' captures (§3.3): per object that takes the method, in the
    /// order of its layers in `envmap.captures`, the centres of its cube maps.
    pub captures: Vec<CaptureSet>,
    /// What the renderer records, in order.
    pub stages: Vec<StageSpec>,
    /// The stages' names, in order: the stable profiler keys.
    pub passes: Vec<&'static str>,
    /// Near plane of cube-map rendering (metres), relative to the scene's size.
    pub cube_near: f32,
    /// Distance-map cycles per frame (§4.3).
    pub cycles: u32,
    /// Whether specular objects in distance maps search their own maps of the previous
    /// cycle (§4.3): a method asks for it, or methods are mixed and must compose.
    pub inter_object: bool,
    /// Inter-object cycles, one per frame, reusing the previous frame's maps.
    pub frame_latency: bool,
    /// Proxy geometry (§3.2): sphere radius and box, world space.
    pub proxy_radius: f32,
    pub proxy_box: (Vec3, Vec3),
    /// Planar mirrors (§5), in mesh order, and the most views a frame of them can have
    /// (within `mirror_budget`): the layers of their views' image.
    pub mirrors: Vec<usize>,
    pub mirror_layers: u32,
    /// Planar mirrors (§5) drawn into the other objects' cube maps by their mirrored views:
    /// the first `mirror_budget` planar mirrors, when any object has cube maps.
    pub map_mirrors: Vec<usize>,
    /// Caustics (§6): the generators and their lights, when the scene has caustics.
    pub caustics: Option<CausticsPlan>,
    /// Where the camera and the specular objects stood when the plan was chosen (under
    /// `auto`: when its choice was last predicted).
    #[serde(skip)]
    pub anchor: Anchor,
}

/// The camera (position, viewing direction) and each specular object's bounding sphere
/// (mesh, centre, radius) at a moment: how far a frame's view has moved from it.
/// Equal to every other anchor, so that two plans compare by what they render.
#[derive(Clone, Debug, Default)]
pub struct Anchor {
    camera: Option<(Vec3, Vec3)>,
    objects: Vec<(usize, Vec3, f32, glam::Quat)>,
}

impl PartialEq for Anchor {
    fn eq(&self, _: &Anchor) -> bool {
        true
    }
}

impl Anchor {
    pub fn of(scene: &crate::scene::Scene) -> Anchor {
        let cam = scene.camera_or_default();
        let forward = cam.world_from_camera.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
        let objects = scene
            .specular_meshes()
            .map(|(i, m)| {
                let (lo, hi) = m.positions.iter().fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(a, b), &p| (a.min(p), b.max(p)));
                let centre = 0.5 * (lo + hi);
                let (_, turn, _) = m.world.to_scale_rotation_translation();
                (i, centre, 0.5 * (hi - lo).length(), turn.normalize())
            })
            .collect();
        Anchor { camera: Some((cam.position, forward)), objects }
    }

    /// How far `scene`'s view has moved from this anchor, as a fraction of the view: the
    /// largest over the specular objects of the camera's and the object's displacement over
    /// the object's distance from the camera, the change of its size over its size, its
    /// turn in radians, and the camera's turn over its field of view; infinite when the
    /// objects are not the same.
    pub fn motion(&self, scene: &crate::scene::Scene) -> f32 {
        let now = Anchor::of(scene);
        let (Some((c0, f0)), Some((c1, f1))) = (self.camera, now.camera) else { return f32::INFINITY };
        if self.objects.len() != now.objects.len() || self.objects.iter().zip(&now.objects).any(|(a, b)| a.0 != b.0) {
            return f32::INFINITY;
        }
        let fov = scene.camera_or_default().yfov.max(1e-3);
        let turn = f0.dot(f1).clamp(-1.0, 1.0).acos() / fov;
        let moved = self.objects.iter().zip(&now.objects).map(|(&(_, p0, r0, q0), &(_, p1, r1, q1))| {
            let d = (p1 - c1).length().max(r1).max(f32::MIN_POSITIVE);
            let shift = ((c1 - c0).length() / d).max((p1 - p0).length() / d);
            shift.max((r1 - r0).abs() / r0.max(f32::MIN_POSITIVE)).max(q0.angle_between(q1))
        });
        let m = moved.fold(turn, f32::max);
        if m.is_nan() {
            f32::INFINITY
        } else {
            m
        }
    }
}

/// One light's views of a generator: layers `first_layer ..` of the photon images.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct LightViews {
    pub light: usize,
    pub first_layer: u32,
    /// 1 (a cone or an orthographic view), or 6 (a cube around a light inside the
    /// generator's bounding sphere).
    pub faces: u32,
    /// 1, or 2 for a dielectric with `caustic_paths=both`: layers `first_layer + b·faces ..`
    /// hold branch b (0 refracted, 1 reflected).
    pub branches: u32,
    /// The caustic cube its photons land in (`CausticsPlan::cubes`).
    pub cube: u32,
}

/// One caustic cube: a receiver distance cube and a light cube map around a centre.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct CausticCube {
    /// Index into `CausticsPlan::generators`.
    pub generator: usize,
    /// `Some(light)`: centred at that light (light space); `None`: at the generator's
    /// reference point (cube-map space).
    pub light: Option<usize>,
}

/// One caustic generator.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Generator {
    pub mesh: usize,
    pub name: String,
    /// Its light cube map's and receiver distance map's centre: the object's reference point.
    pub reference_point: Vec3,
    pub lights: Vec<LightViews>,
}

/// The structure of a generator (what it renders), not where it is.
impl PartialEq for Generator {
    fn eq(&self, o: &Generator) -> bool {
        self.mesh == o.mesh && self.lights == o.lights
    }
}

/// The caustics stage of a plan.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct CausticsPlan {
    /// `Splat` or `Triangles`.
    pub filter: Caustics,
    pub generators: Vec<Generator>,
    /// The caustic cubes, in layer order of the cube arrays.
    pub cubes: Vec<CausticCube>,
    pub space: CausticSpace,
    /// Layers of the photon images: Σ faces over every generator's lights.
    pub photon_layers: u32,
    /// Device memory of its images.
    pub bytes: u64,
}

/// What the plan needs of a map kind (`frame::stage::MapInfo`, which carries its
/// constructor): its pass, position, shape and the object field that indexes it.
#[derive(Clone, Copy, Debug)]
pub struct MapKind {
    pub name: &'static str,
    pub order: u32,
    pub cube: bool,
    pub layer_field: Option<LayerField>,
    pub shared: bool,
}

/// What the plan needs of a frame effect (`frame::stage::EffectInfo`): its stage over
/// `objects`, its passes for this plan.
pub struct EffectKind {
    pub name: &'static str,
    pub order: u32,
    pub deps: Deps,
}

impl EffectPlan {
    /// The stage of effect `kind` over `objects`, recording `passes`.
    pub fn stage(kind: EffectKind, objects: Vec<usize>, passes: Vec<&'static str>) -> StageSpec {
        StageSpec::Effect(EffectPlan { name: kind.name, order: kind.order, deps: kind.deps, passes, objects })
    }
}

/// What the planner has derived when `Family::plan_stages` runs: the map passes (one per
/// map kind, layers in mesh order) and the frame's stages so far.
pub struct PlanStages {
    pub maps: Vec<MapPlan>,
    pub stages: Vec<StageSpec>,
    /// A whole-scene method shades every pixel itself (`GpuSpec::shades_every_pixel`): with
    /// exact shadow rays and the caustics projected in its own kernel.
    pub shades_scene: bool,
}

impl PlanStages {
    /// Gives `object` map `info` (its layer the next of that map's array), unless it has it.
    pub fn add_map(&mut self, object: &mut ObjectPlan, info: MapKind, what: String) {
        if object.maps.iter().any(|m| m.pass == info.name) {
            return;
        }
        let k = match self.maps.iter().position(|m| m.name == info.name) {
            Some(k) => k,
            None => {
                self.maps.push(MapPlan {
                    name: info.name,
                    order: info.order,
                    cube: info.cube,
                    shared: info.shared,
                    objects: Vec::new(),
                    bytes: 0,
                });
                self.maps.len() - 1
            }
        };
        object.maps.push(ObjectMap {
            pass: info.name,
            layer: self.maps[k].objects.len() as u32,
            layer_field: info.layer_field,
            what,
            bytes: 0,
        });
        self.maps[k].objects.push(object.mesh);
        object.passes.push(info.name);
    }

    /// Takes map pass `pass` from `objects[k]` (composition draws its map in another pass):
    /// the later layers of that pass move down one, the pass goes when it has no object left.
    pub fn remove_map(&mut self, objects: &mut [ObjectPlan], k: usize, pass: &str) {
        let Some(i) = self.maps.iter().position(|m| m.name == pass) else { return };
        let mesh = objects[k].mesh;
        self.maps[i].objects.retain(|&m| m != mesh);
        objects[k].maps.retain(|m| m.pass != pass);
        objects[k].passes.retain(|p| *p != pass);
        for o in objects.iter_mut() {
            let layer = self.maps[i].objects.iter().position(|&m| m == o.mesh);
            if let (Some(m), Some(layer)) = (o.maps.iter_mut().find(|m| m.pass == pass), layer) {
                m.layer = layer as u32;
            }
        }
        if self.maps[i].objects.is_empty() {
            self.maps.remove(i);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Mat4, Quat};

    /// Taking a map from one object moves the later layers of that pass down and drops a
    /// pass with no object left.
    #[test]
    fn removing_a_map_renumbers_its_layers() {
        let kind = crate::methods::envmap::RADIANCE_CUBES.kind();
        let mut st = PlanStages { maps: Vec::new(), stages: Vec::new(), shades_scene: false };
        let object = |mesh: usize| ObjectPlan {
            mesh,
            name: format!("o{mesh}"),
            class: ObjectClass::Mirror,
            method: crate::methods::ENVMAP,
            reason: String::new(),
            reference_point: Vec3::ZERO,
            own_reference_point: Vec3::ZERO,
            reference_note: None,
            map_shading: MapShading::Sky,
            leaves_out: LeavesOut::Itself,
            maps: Vec::new(),
            passes: Vec::new(),
            knobs: Vec::new(),
            sees: Vec::new(),
        };
        let mut objects: Vec<ObjectPlan> = (0..3).map(object).collect();
        for o in &mut objects {
            st.add_map(o, kind, String::new());
        }
        st.remove_map(&mut objects, 0, kind.name);
        assert_eq!(st.maps[0].objects, [1, 2]);
        assert!(objects[0].maps.is_empty() && objects[0].passes.is_empty());
        assert_eq!((objects[1].maps[0].layer, objects[2].maps[0].layer), (0, 1));
        st.remove_map(&mut objects, 2, kind.name);
        st.remove_map(&mut objects, 1, kind.name);
        assert!(st.maps.is_empty());
    }

    /// The view's motion from an anchor: a camera step as a fraction of the distance to the
    /// object, an object's turn in radians, its move over its distance; infinite when the
    /// objects change.
    #[test]
    fn an_anchor_measures_how_far_the_view_moved() {
        let mut s = crate::scene::Scene::new();
        let m = s.add_material(crate::scenes::mirror_material("m", 0.9)).unwrap();
        let ball = s.add_mesh(crate::scene::shapes::uv_sphere("ball", Vec3::ZERO, 0.5, 16, 8, m)).unwrap();
        s.camera = Some(crate::scene::Camera::look_at(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, 0.8));
        let a = Anchor::of(&s);
        assert_eq!(a.motion(&s), 0.0);
        let mut step = s.clone();
        step.camera = Some(crate::scene::Camera::look_at(Vec3::new(0.0, 0.0, 3.8), Vec3::ZERO, 0.8));
        assert!((a.motion(&step) - 0.2 / 3.8).abs() < 1e-3, "{}", a.motion(&step));
        let mut turned = s.clone();
        turned.set_object_transform(ball, Mat4::from_quat(Quat::from_rotation_y(0.3))).unwrap();
        assert!((a.motion(&turned) - 0.3).abs() < 1e-3, "{}", a.motion(&turned));
        let mut moved = s.clone();
        moved.set_object_transform(ball, Mat4::from_translation(Vec3::new(0.4, 0.0, 0.0))).unwrap();
        assert!(a.motion(&moved) > 0.09, "{}", a.motion(&moved));
        let mut more = s.clone();
        more.add_mesh(crate::scene::shapes::uv_sphere("two", Vec3::X, 0.5, 16, 8, m)).unwrap();
        assert_eq!(a.motion(&more), f32::INFINITY);
        assert_eq!(Anchor::default().motion(&s), f32::INFINITY);
    }
}
