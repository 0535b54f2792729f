//! The method registry. Every method is described once, in its family's folder, by one
//! `MethodInfo`: its CLI name, its stable C ABI number, its survey section, the objects it
//! can serve, the knobs it reads, how it plans (the maps it needs, its camera pass, its
//! map cycles). `--method auto` chooses among them by prediction (`plan::predict`). Everything that lists methods — the CLI,
//! `specula knobs`, the C header's `SPECULA_METHOD_*`, the README tables, `tradeoff`, the
//! demo — reads `methods::ALL`.

use crate::frame::stage::{CreateFramePart, EffectInfo, MapInfo};
use crate::plan::facts::ObjectFacts;
pub use crate::plan::ids::{Choice, LeavesOut, MapShading, Method, ObjectClass, Profiled};
use crate::plan::types::{CameraPlan, Plan, PlanStages};
use crate::quality::Quality;
use crate::scene::Scene;

/// A method's camera pass: its objects drawn over `scene.direct`'s colour and depth with
/// its shaders. Methods that name the same pass share it (and must name the same shaders).
#[derive(Clone, Copy, Debug)]
pub struct CameraPass {
    /// Stable profiler key, e.g. `distance.search`.
    pub name: &'static str,
    pub vertex: &'static str,
    pub fragment: &'static str,
    /// Push-constant flags of this method's draws (e.g. `FLAG_PROXY_BOX`).
    pub flags: u32,
    /// Position among the frame's passes (`frame::stage::order`).
    pub order: u32,
    /// A stage of the method's own instead of the one fragment pass that draws its objects
    /// with `vertex` and `fragment` (ray tracing in the original geometry: a pipeline of
    /// passes).
    pub create: Option<CreateCamera>,
    /// The passes its stage records and how the budget charges them.
    pub profiled: Profiled,
}

/// Creates a method's own camera stage for the plan's objects.
pub type CreateCamera = fn(&crate::frame::stage::StageInit, &CameraPlan) -> crate::Result<Box<dyn crate::frame::stage::Stage>>;

/// How a GPU method plans an object.
#[derive(Clone, Copy)]
pub struct GpuSpec {
    /// The maps the object needs, in the order they are generated; each map kind is one
    /// pass for all the objects that need it.
    pub maps: &'static [MapInfo],
    pub camera: CameraPass,
    /// How the object looks in the other objects' distance maps.
    pub map_shading: MapShading,
    /// What the object's own cube maps leave out.
    pub leaves_out: LeavesOut,
    /// Distance-map cycles per frame this method asks for (§4.3).
    pub cycles: fn(&Quality) -> u32,
    /// Views of the whole scene it renders per object it serves, at most (planar mirrors'
    /// and planar refraction's mirrored views, §5): every other object's camera work repeats
    /// in each — what the planner's cost of a mix counts (`plan::budget`).
    pub views: fn(&Quality) -> u32,
    /// Whether, asked for the whole scene (`--method`), it shades every pixel in its own
    /// stage, diffuse surfaces included (exact shadow rays), from no maps and with no
    /// fallback: no other family's pass reaches its image, so only the knobs it lists and
    /// the frame's change it (`tradeoff` measures variants that agree on those once;
    /// caustics, §6, aside). Ray tracing in the original geometry (§2).
    pub shades_every_pixel: bool,
}

/// One method, described once.
pub struct MethodInfo {
    /// The CLI's `--method` value and the C ABI's name, a stable interface.
    pub name: &'static str,
    /// `SPECULA_METHOD_<NAME>` in the C header, a stable interface.
    pub abi: u32,
    /// Survey section(s).
    pub section: &'static str,
    /// `src/methods/<family>/` and `glsl/<family>/`.
    pub family: &'static str,
    /// One sentence for the README's method table and `specula knobs`.
    pub summary: &'static str,
    pub serves: &'static [ObjectClass],
    /// Knob names (`quality::KNOBS`) this method reads.
    pub knobs: &'static [&'static str],
    /// `None`: a CPU method (the reference).
    pub gpu: Option<GpuSpec>,
    /// For objects it cannot serve when it is asked for the whole scene (`--method`): the
    /// method those objects get instead (e.g. refractor-map leaves mirrors to distance).
    pub fallback: Option<Method>,
    /// What shape of object it can serve beyond its class (planar-mirror: planar only).
    pub shape: Shape,
    /// What it needs of the device beyond the library's requirements, and what serves
    /// its objects on a device without it.
    pub needs: DeviceNeeds,
}

/// What a method needs of the device beyond `REQUIRED_DEVICE_EXTENSIONS`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DeviceNeeds {
    Nothing,
    /// Vulkan's ray queries and acceleration structures (`Context::ray_query`); `otherwise`
    /// serves its objects where they are missing.
    RayQuery {
        otherwise: Method,
    },
}

impl DeviceNeeds {
    /// `None` when `ctx` has what the method needs; else the method that serves instead and
    /// why.
    pub fn missing_on(&self, ctx: &crate::vk::Context) -> Option<(Method, String)> {
        match (*self, &ctx.ray_query) {
            (DeviceNeeds::RayQuery { otherwise }, Err(why)) => Some((otherwise, why.clone())),
            _ => None,
        }
    }
}

/// The object shapes a method serves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Shape {
    Any,
    /// All vertices on one plane, normals agreeing (`ObjectFacts::planar`).
    Planar,
    /// Flat faces: a convex solid of planar faces (`ObjectFacts::faceted`), or a planar
    /// thin-walled pane.
    Faceted,
    /// Convex or concave (or flat), not saddle-shaped (`ObjectFacts::curvature`), and without
    /// several reflection points for the environment seen from the camera
    /// (`ObjectFacts::reflection_points`): where a search on the reflector's surface finds
    /// one reflection point (survey §5).
    ConvexOrConcave,
}

impl Shape {
    pub fn fits(self, f: &ObjectFacts) -> bool {
        match self {
            Shape::Any => true,
            Shape::Planar => f.planar,
            Shape::Faceted => match f.class {
                ObjectClass::SolidDielectric => f.faceted,
                ObjectClass::ThinDielectric => f.planar,
                ObjectClass::Mirror => false,
            },
            Shape::ConvexOrConcave => {
                f.curvature != crate::plan::facts::Curvature::Saddle && !crate::plan::reflection_points::refused(f.reflection_points)
            }
        }
    }

    /// Why object `f` misses the shape (what [`Shape::requirement`] says, with the
    /// measured reflection points where several were found).
    pub fn refusal(self, f: &ObjectFacts) -> String {
        match self {
            Shape::ConvexOrConcave if f.curvature != crate::plan::facts::Curvature::Saddle => {
                let (found, checked) = f.reflection_points;
                format!(
                    "reflectors with one reflection point per environment point only: seen from the camera, {found} of {checked} sampled environment vertices have a second one on this mesh (several minima of the reflection-point search, survey §5; e.g. separate surfaces in one mesh): unsupported"
                )
            }
            _ => self.requirement().to_string(),
        }
    }

    /// Whether object `f` misses the shape only as seen from where the camera is now (several
    /// reflection points of a curved reflector, which a camera move changes), not by its
    /// form (a saddle, a curved face where flat ones are needed).
    pub fn misses_from_this_view(self, f: &ObjectFacts) -> bool {
        matches!(self, Shape::ConvexOrConcave) && f.curvature != crate::plan::facts::Curvature::Saddle && !self.fits(f)
    }

    /// [`Shape::misfit`] for object `f`.
    pub fn misfit_of(self, f: &ObjectFacts) -> &'static str {
        match self {
            Shape::ConvexOrConcave if f.curvature != crate::plan::facts::Curvature::Saddle => {
                "a several-minima (more than one reflection point per environment point, unsupported)"
            }
            _ => self.misfit(),
        }
    }

    /// What the shape requires, and why an object that misses it was refused.
    pub fn requirement(self) -> &'static str {
        match self {
            Shape::Any => "any shape",
            Shape::Planar => "planar reflectors only: the mesh's vertices do not lie on one plane with agreeing normals",
            Shape::Faceted => "flat-faced convex solids and planar thin panes only: the mesh is not a closed convex solid of at most 64 flat faces (each face's vertex normals its plane's), nor a planar thin pane",
            Shape::ConvexOrConcave => "convex or concave reflectors only: the mesh is saddle-shaped (neither convex nor concave), where the reflection-point search has several minima (survey §5): unsupported",
        }
    }

    /// An object of this class that misses the shape, as the planner's reasons name it.
    pub fn misfit(self) -> &'static str {
        match self {
            Shape::Any => "a",
            Shape::Planar => "a non-planar",
            Shape::Faceted => "a curved (not flat-faced)",
            Shape::ConvexOrConcave => "a saddle-shaped (neither convex nor concave, unsupported)",
        }
    }
}

/// A family of the survey (`src/methods/<family>/`): what it adds to a frame beyond its
/// methods' maps and camera passes, as hooks the planner and the renderer call without
/// naming it. A family sets the hooks it needs over `Family::NONE`.
pub struct Family {
    /// The folder's name, as `MethodInfo::family` names it.
    pub name: &'static str,
    /// Its methods, in the order `methods::ALL` lists them.
    pub methods: &'static [&'static MethodInfo],
    /// The frame effects its planning hooks add (`EffectPlan`s name them; the renderer
    /// finds their constructors here).
    pub effects: &'static [EffectInfo],
    /// Its slots in the frame's maps (`frame::maps::Slot`: binding, sampler, who reads it).
    pub slots: &'static [crate::frame::maps::Slot],
    /// Before the frame's stages are derived: moves the objects' reference points (the
    /// shared layered map's centre, §4.5).
    pub plan_objects: Option<fn(&Scene, &mut Plan)>,
    /// Its frame-wide plan, before the shadow maps are decided (caustics: generators and
    /// their lights, §6).
    pub plan_frame: Option<fn(&Scene, &mut Plan)>,
    /// Stages and maps it adds once the objects' own maps are planned (caustics: their
    /// effect stages and the refractor maps solid generators need).
    pub plan_stages: Option<fn(&Scene, &mut Plan, &mut PlanStages)>,
    /// After the maps: view layers of its own (planar mirrors', §5).
    pub plan_views: Option<fn(&Scene, &mut Plan)>,
    /// Its blocks of views in the frame's view table: (name, count), in table order.
    pub views: Option<ViewBlocks>,
    /// After objects moved, with the plan's structure kept: its plan follows them.
    pub refresh: Option<fn(&mut Plan)>,
    /// Which objects (by position in `methods`, each object's method in a mixed plan) get
    /// maps of their own so that they show in this family's maps (§4.3 across families):
    /// what the budget adds to their cost (their cheapest candidate that shades itself in
    /// maps) and the inter-object cycles that needs.
    pub composes: Option<Composes>,
    /// Its methods that draw the other specular objects by those objects' own maps (curved
    /// reflectors: their environment's specular objects), so that composition gives those
    /// objects maps as it does beside a distance-mapped object.
    pub shows_others_by_maps: &'static [Method],
    /// Its methods whose one map per object is a radiance cube that composition draws as a
    /// distance map instead (environment mapping, §3: radiance with the distance beside it,
    /// drawn in the inter-object cycles of §4.3, the other specular objects shown in it by
    /// their own maps and the object traced in it where the others' maps show it); their
    /// camera passes read it there (`MapShading` other than `Sky` says so).
    pub cubes_compose: &'static [Method],
    /// Its methods that trace rays curved through graded media (survey §6.5: the ray
    /// equation marched through the medium, `scene::medium`): the only ones that serve a
    /// graded-index object.
    pub curved_rays: &'static [Method],
    /// Fills its words of the push block (`push_words!` in its `layout.in.rs`), once a frame
    /// (from the knobs, and the view table's layout where a word names a view).
    pub push_words: Option<fn(&Quality, &crate::frame::stage::ViewLayout, &mut crate::frame::words::PushWords)>,
    /// Its part of `specula plan`'s table, if it planned anything.
    pub describe: Option<fn(&Plan, &Scene) -> Option<String>>,
    /// State it keeps across frames: views of its own in the view table, extra camera views
    /// (planar mirrors), push flags of the camera's objects, stats (`stage::FramePart`).
    pub frame_part: Option<CreateFramePart>,
}

/// Which objects of a mixed plan (their methods, in order; and per object the positions of
/// the others it sees, `plan::facts::SceneFacts::sight`) a family composes into its maps.
pub type Composes = fn(&[Method], &[Vec<usize>]) -> Vec<bool>;

/// A family's blocks of views for a plan: (name, count), in table order.
pub type ViewBlocks = fn(&Plan) -> Vec<(&'static str, u32)>;

impl Family {
    /// A family with no hooks, to set the ones it needs over.
    pub const NONE: Family = Family {
        name: "",
        methods: &[],
        effects: &[],
        slots: &[],
        plan_objects: None,
        plan_frame: None,
        plan_stages: None,
        plan_views: None,
        views: None,
        refresh: None,
        push_words: None,
        composes: None,
        shows_others_by_maps: &[],
        cubes_compose: &[],
        curved_rays: &[],
        describe: None,
        frame_part: None,
    };
}

/// How many methods `families` register.
pub const fn method_count(families: &[Family]) -> usize {
    let (mut i, mut n) = (0, 0);
    while i < families.len() {
        n += families[i].methods.len();
        i += 1;
    }
    n
}

/// Every method of `families`, family by family (`N`: their `method_count`).
pub const fn all_methods<const N: usize>(families: &[Family]) -> [Method; N] {
    let mut out = [Method(""); N];
    let (mut i, mut n) = (0, 0);
    while i < families.len() {
        let mut j = 0;
        while j < families[i].methods.len() {
            out[n] = Method(families[i].methods[j].name);
            n += 1;
            j += 1;
        }
        i += 1;
    }
    assert!(n == N, "N is the families' method count");
    out
}

/// The map kind named `name` that some registered method needs: its constructor, for the
/// renderer (a plan's `MapPlan` names it), and for a family that needs another's map for its
/// own purpose (caustics need refractor maps) without importing that family.
pub fn map_named(name: &str) -> Option<MapInfo> {
    Method::ALL.iter().filter_map(|m| m.gpu).flat_map(|g| g.maps.iter()).find(|i| i.name == name).copied()
}

/// Every object class, for methods that serve them all.
pub const EVERY_CLASS: &[ObjectClass] = &[ObjectClass::Mirror, ObjectClass::ThinDielectric, ObjectClass::SolidDielectric];

/// The C ABI number of `--method auto` (`SPECULA_METHOD_AUTO`).
pub const ABI_AUTO: u32 = 100;

/// Checks the registry: names and numbers unique, every knob a method reads exists, every
/// fallback serves what the method does not, methods sharing a camera pass share its
/// shaders, a method that shades every pixel has its own stage and no maps or fallback.
/// `methods::ALL` passes (a unit test); a table that breaks a rule is refused.
pub fn check(all: &[&MethodInfo]) -> std::result::Result<(), String> {
    for (i, a) in all.iter().enumerate() {
        for b in &all[i + 1..] {
            if a.name == b.name {
                return Err(format!("two methods are named '{}'", a.name));
            }
            if a.abi == b.abi {
                return Err(format!("'{}' and '{}' share C ABI number {}", a.name, b.name, a.abi));
            }
            if let (Some(ga), Some(gb)) = (a.gpu, b.gpu) {
                let (ca, cb) = (ga.camera, gb.camera);
                if ca.name == cb.name && (ca.vertex != cb.vertex || ca.fragment != cb.fragment) {
                    return Err(format!("'{}' and '{}' share pass {} with different shaders", a.name, b.name, ca.name));
                }
                // A shared camera stage keeps the first method's pass, whose declaration the budget reads.
                if ca.name == cb.name && ca.profiled != cb.profiled {
                    return Err(format!("'{}' and '{}' share pass {} but declare its timed passes differently", a.name, b.name, ca.name));
                }
            }
        }
        if a.abi == ABI_AUTO || a.name == "auto" {
            return Err(format!("'{}' claims the name or number of auto", a.name));
        }
        for k in a.knobs {
            if !crate::quality::KNOBS.iter().any(|n| n.name == *k) {
                return Err(format!("'{}' reads unknown knob '{k}'", a.name));
            }
        }
        if let Some(f) = a.fallback {
            if !f.is_gpu() || a.gpu.is_some() != f.is_gpu() {
                return Err(format!("'{}' falls back to '{}' of another kind", a.name, f.name));
            }
        }
        if let Some(g) = a.gpu.filter(|g| g.shades_every_pixel) {
            if !g.maps.is_empty() || a.fallback.is_some() || g.camera.create.is_none() {
                return Err(format!("'{}' shades every pixel but has maps, a fallback or no stage of its own", a.name));
            }
        }
    }
    Ok(())
}
