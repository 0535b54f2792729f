//! What the renderer runs: a plan's stages, each one profiled pass with its own resources.
//! The renderer creates the stages the plan lists, records them in order and frees them; it
//! holds the frame's shared map slots (`maps`, declared by their owners) but names no
//! method.

use ash::vk;

use crate::frame::FrameInputs;
use crate::gpu_scene::GpuScene;
use crate::plan::types::{EffectKind, EffectPlan, MapKind, Plan, StageSpec};
use crate::quality::Quality;
use crate::scene::Scene;
use crate::vk::{Context, Image, Recorder};

pub use super::maps::{MapSets, Maps, Slot};
pub use super::schedule::{order, Deps, LayerField};
use crate::Result;

/// One recorded pass with its resources (`new` creates everything, `destroy` frees it).
pub trait Stage {
    /// The stable profiler key.
    fn name(&self) -> &'static str;
    fn record(&mut self, rec: &mut Recorder, f: &FrameInputs, io: &mut FrameIo);
    /// Frees everything; the GPU must be idle with respect to the renderer's frames.
    fn destroy(&mut self, ctx: &Context);
    /// What the last frame counted (rays per bounce, culling rates …), read after the frame
    /// finished: (name, value), names stable like pass names.
    fn stats(&self, _ctx: &Context) -> Vec<(String, f64)> {
        Vec::new()
    }
    /// Takes a change of the scene (`init.scene` is the new state) before the frame that
    /// shows it is recorded: a stage that holds data derived from the geometry or the
    /// materials (an acceleration structure, per-vertex thickness) refreshes it here. The
    /// GPU has completed every earlier frame of this renderer.
    fn update(&mut self, _init: &StageInit, _changes: &crate::scene::update::Changes, _maps: &mut Maps) -> Result<()> {
        Ok(())
    }
    /// After `update`: the part of its maps the next record draws again, as (faces to draw,
    /// faces in all), where the stage tracks what each face saw (cube maps, `cube_deps`); a
    /// frame records no stage with nothing to draw. None: the whole stage.
    fn redraw(&self) -> Option<(u32, u32)> {
        None
    }
    /// What `redraw` counts, said in the frame's map-update list (None: "k of n faces").
    fn redraw_note(&self) -> Option<String> {
        None
    }
    /// Flags `scene.direct` shades with because this stage exists (e.g. a pass of its own
    /// projects the caustics: `FLAG_CAUSTICS_APART`).
    fn direct_flags(&self) -> u32 {
        0
    }
}

/// Indices into the frame's view table.
#[derive(Clone, Debug, Default)]
pub struct ViewLayout {
    pub camera: u32,
    pub shadow_cubes: Vec<u32>,
    pub shadow_planes: Vec<u32>,
    /// First of the six views of `plan.envmaps[i]` (its reference point).
    pub envmaps: Vec<u32>,
    /// The families' blocks of views, in table order (`registry::Family::views`).
    pub blocks: Vec<ViewBlock>,
    pub count: u32,
}

/// A block of consecutive views a family declares (its cube faces, photon views, mirrored
/// views), found by its name.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewBlock {
    pub name: &'static str,
    pub first: u32,
    pub count: u32,
}

/// The block of extra camera views that frame parts render the camera's stages into
/// (`FramePart::record_views`; `EXTRA_VIEW_BASE` of the push words is its first view).
pub const EXTRA_VIEWS: &str = "frame.extra_views";

impl ViewLayout {
    /// The first cube view of mesh `mesh`'s reference point, if it has cube maps.
    pub fn cube_of(&self, plan: &Plan, mesh: usize) -> Option<u32> {
        plan.envmaps.iter().position(|e| e.mesh == mesh).map(|i| self.envmaps[i])
    }

    /// Appends a block of `count` views named `name`.
    pub fn add(&mut self, name: &'static str, count: u32) {
        self.blocks.push(ViewBlock { name, first: self.count, count });
        self.count += count;
    }

    /// The first view of block `name`, if declared.
    pub fn first(&self, name: &str) -> Option<u32> {
        self.blocks.iter().find(|b| b.name == name).map(|b| b.first)
    }
}

/// What a stage reads and writes while it records, besides the frame inputs.
pub struct FrameIo<'a> {
    pub plan: &'a Plan,
    pub views: &'a ViewLayout,
    pub target: &'a mut Image,
    pub depth: &'a mut Image,
    pub maps: &'a mut Maps,
    pub sets: &'a MapSets,
    /// Each view's eye (world space), by view index: where a cube face looks from.
    pub view_eyes: &'a [glam::Vec3],
    /// Images every pass that shades diffuse surfaces samples (textures, environment).
    pub scene_images: Vec<&'a Image>,
    /// The camera passes draw within this rectangle of the target (the whole target for the
    /// camera; for a planar mirror's view the mirror's pixels).
    pub area: vk::Rect2D,
    /// Push flags a camera pass adds for an object in this view: (mesh, flags), e.g. which
    /// mirrored view a planar mirror shows (`FLAG_MIRROR_VIEW`).
    pub object_flags: &'a [(usize, u32)],
    /// The depth buffer holds a mask the first pass must keep (a planar mirror's view:
    /// `geometry.stencil` left the farthest depth on the mirror's pixels, the nearest
    /// elsewhere, so that nothing is drawn where the view is not seen).
    pub depth_masked: bool,
    /// Flags `scene.direct` adds (every stage's `direct_flags`).
    pub direct_flags: u32,
}

/// What a stage's constructor may look at.
pub struct StageInit<'a> {
    pub ctx: &'a Context,
    pub scene: &'a Scene,
    pub gpu: &'a GpuScene,
    pub plan: &'a Plan,
    pub layout: vk::PipelineLayout,
    /// The frame's descriptor set layouts (set 0, set 1), for stages with layouts of their own.
    pub set_layouts: [vk::DescriptorSetLayout; 2],
    /// The camera target's size (the output's, times the supersampling factor).
    pub width: u32,
    pub height: u32,
    /// The camera target's samples per pixel, and whether specular camera passes shade
    /// each sample (`aa=msaaN`, `msaa_shading`).
    pub multisample: crate::vk::pipeline::Multisample,
    /// Resources the frame's stages share (made by the first that asks).
    pub shared: &'a crate::frame::shared::Shared,
}

/// A frame effect's constructor: its stage, its images into `maps`.
pub type CreateEffect = fn(init: &StageInit, maps: &mut Maps) -> Result<Box<dyn Stage>>;

/// A stage a family adds to the frame beyond maps and camera passes (caustics, §6): declared
/// once in its family's folder, planned by the family's hook, created by the renderer
/// without knowing what it is.
#[derive(Clone, Copy)]
pub struct EffectInfo {
    /// The stage's name (for `plan.stages`); the passes it records are `passes`.
    pub name: &'static str,
    pub order: u32,
    pub deps: Deps,
    pub create: CreateEffect,
    /// The profiled passes it records, in order, for this plan.
    pub passes: fn(&Plan) -> Vec<&'static str>,
}

impl EffectInfo {
    /// Its stage over `objects` in `plan` (whose frame-wide plans its passes read).
    pub fn stage(&self, plan: &Plan, objects: Vec<usize>) -> StageSpec {
        EffectPlan::stage(EffectKind { name: self.name, order: self.order, deps: self.deps }, objects, (self.passes)(plan))
    }
}

impl std::fmt::Debug for EffectInfo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name)
    }
}

impl PartialEq for EffectInfo {
    fn eq(&self, o: &EffectInfo) -> bool {
        self.name == o.name
    }
}

/// Where the camera looks from this frame: what a family's own views are planned from.
pub struct ViewFrame<'a> {
    pub plan: &'a Plan,
    /// The scene as the GPU holds it (no texels).
    pub scene: &'a Scene,
    pub lights: &'a [crate::gpu_scene::GpuLight],
    pub layout: &'a ViewLayout,
    /// The camera's world → clip matrix and eye.
    pub view_proj: glam::Mat4,
    pub eye: glam::Vec3,
    pub yfov: f32,
    pub aspect: f32,
}

/// One extra camera view a frame part renders the camera-dependent stages into.
pub struct ViewPass<'a> {
    /// The view table as the stages see it (`camera` is this view's entry).
    pub views: ViewLayout,
    pub target: &'a mut Image,
    pub depth: &'a mut Image,
    pub maps: &'a mut Maps,
    pub area: vk::Rect2D,
    pub object_flags: &'a [(usize, u32)],
    pub depth_masked: bool,
}

/// What a family adds to a frame beyond its stages, kept across frames: views of its own
/// in the view table, extra camera views (planar mirrors, §5), push flags the camera's
/// objects get, counts for `Frame::stats`. Created by the family's hook
/// (`registry::Family::frame_part`); the renderer calls it without knowing what it is.
pub trait FramePart {
    /// Plans this frame's views from the camera and writes its entries of the view table.
    fn write_views(&mut self, frame: &ViewFrame, table: &mut [crate::gpu_scene::GpuView]);
    /// Records the camera-dependent stages again for each view of its own, through
    /// `camera_stages`, before the camera's; returns whether any view was recorded (the
    /// camera's own camera-space maps must then be recorded again).
    fn record_views(
        &mut self,
        _rec: &mut Recorder,
        _f: &FrameInputs,
        _layout: &ViewLayout,
        _maps: &mut Maps,
        _camera_stages: &mut dyn FnMut(&mut Recorder, ViewPass),
    ) -> bool {
        false
    }
    /// Push flags the camera view adds per object (`FrameIo::object_flags`).
    fn camera_flags(&self) -> Vec<(usize, u32)> {
        Vec::new()
    }
    /// How many times a frame may record the camera's passes again (profiler capacity).
    fn extra_views(&self) -> u32 {
        0
    }
    /// What the last frame counted: (name, value), names stable like pass names.
    fn stats(&self) -> Vec<(String, f64)> {
        Vec::new()
    }
    fn destroy(&mut self, ctx: &Context);
}

/// A family's frame-part constructor: `None` when the plan needs none.
pub type CreateFramePart = fn(init: &StageInit, maps: &mut Maps) -> Result<Option<Box<dyn FramePart>>>;

/// A map pass's constructor: the pass for `objects` (mesh indices), its images into `maps`.
pub type CreateStage = fn(init: &StageInit, objects: &[usize], maps: &mut Maps) -> Result<Box<dyn Stage>>;

/// A map kind some method needs for its objects (the radiance cubes of §3, the distance
/// cubes of §4, refractor maps, back faces …): one pass for all the objects that need it,
/// declared once in its family's folder.
#[derive(Clone, Copy)]
pub struct MapInfo {
    /// The pass name (stable profiler key), e.g. `distance.generate`.
    pub name: &'static str,
    pub order: u32,
    /// Whether the map is a cube around each object's reference point (it then needs the
    /// object's six views).
    pub cube: bool,
    /// Which field of the object's GPU record holds its layer in this map's array.
    pub layer_field: Option<LayerField>,
    /// Creates the pass for `objects` (mesh indices, layer = position) and its images in
    /// `maps`.
    pub create: CreateStage,
    /// Device memory of its images for `objects` objects at a `width`×`height` camera.
    pub bytes: fn(&Plan, u32, (u32, u32)) -> u64,
    /// Texels it draws for one object (for a shared map, the whole map) under these knobs,
    /// with `layers` layers where it peels (`layered::planned_layers`), at a `width`×`height`
    /// camera: the map work the planner's cost model counts (`plan::predict::features`).
    pub texels: fn(&Quality, u32, (u32, u32)) -> f64,
    /// What one object's map is, for `specula plan` (e.g. "cube 6×256² RGBA16F").
    pub describe: fn(&Quality, (u32, u32)) -> String,
    /// One map for all the objects that take it (a layered map of the whole scene): its
    /// time does not grow with them, so the planner's cost model counts it once per frame,
    /// as a method's whole-screen kernels, not shared out among its objects.
    pub shared: bool,
}

impl MapInfo {
    /// What the plan keeps of it.
    pub fn kind(&self) -> MapKind {
        MapKind { name: self.name, order: self.order, cube: self.cube, layer_field: self.layer_field, shared: self.shared }
    }
}

impl std::fmt::Debug for MapInfo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name)
    }
}

impl PartialEq for MapInfo {
    fn eq(&self, o: &MapInfo) -> bool {
        self.name == o.name
    }
}

/// Texels of one cube map at `q`'s `cube_size` (`MapInfo::texels` of a cube map per object).
pub fn cube_texels(q: &Quality, _layers: u32, _size: (u32, u32)) -> f64 {
    6.0 * (q.cube.cube_size as f64).powi(2)
}

/// Bytes per texel of the cube maps at a precision.
pub fn cube_texel_bytes(q: &Quality) -> u64 {
    match q.cube.cube_precision {
        crate::quality::Precision::Half => 8,
        crate::quality::Precision::Single => 16,
    }
}

/// "cube 6×256² RGBA16F"
pub fn describe_cube(q: &Quality) -> String {
    let f = match q.cube.cube_precision {
        crate::quality::Precision::Half => "RGBA16F",
        crate::quality::Precision::Single => "RGBA32F",
    };
    format!("cube 6×{}² {f}", q.cube.cube_size)
}
