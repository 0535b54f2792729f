//! Runs a Plan: creates the stages the plan lists (and nothing else) and the families'
//! frame parts, records them in order into a command buffer it is handed, and in
//! standalone mode submits the frame and reads the image back with its per-pass profile.
//! It names no method and no family: stages come from the plan (`StageSpec`: the frame's
//! own, the methods' maps and camera passes, the families' effects), frame parts from the
//! registry's families (`methods::FAMILIES`).
//!
//! One job a file: `targets` (the camera's colour, depth and resolve), `bindings`
//! (descriptor sets, the pipeline layout and the tables behind them), `updates` (scene
//! changes between frames and which maps they invalidate), `submit` (standalone frames
//! and their readback, host-device frames, timings); this file orchestrates.

mod bindings;
mod submit;
mod targets;
mod updates;

use ash::vk;
use glam::Mat4;

use crate::error::{Error, Result};
use crate::frame::camera::CameraShade;
use crate::frame::direct::SceneDirect;
use crate::frame::shadow::ShadowMaps;
use crate::frame::stage::{Deps, FrameIo, FramePart, MapSets, Maps, Stage, StageInit, ViewFrame, ViewLayout, ViewPass, EXTRA_VIEWS};
use crate::frame::views;
use crate::frame::{FrameInputs, FLAG_FRESNEL_EXACT, FLAG_HAS_ENVIRONMENT};
use crate::gpu_scene::{GpuLight, GpuScene};
use crate::methods::{camera_named, effect_named, map_named, FAMILIES};
use crate::plan::{Plan, StageSpec};
use crate::quality::FresnelMode;
use crate::scene::{Camera, Scene};
use crate::vk::{record_copy_to_buffer, Access, Buffer, Context, Image, PassTiming, Profiler, Recorder};
use bindings::Bindings;
pub use submit::Frame;
use targets::Targets;
pub use updates::MapUpdate;

/// Profiled passes a frame may record (ray tracing records about 7 per bounce).
const MAX_PASSES: u32 = 512;

pub struct Renderer {
    pub plan: Plan,
    pub width: u32,
    pub height: u32,
    scene: GpuScene,
    camera: Camera,
    views: ViewLayout,
    bindings: Bindings,
    /// The plan's stages, in recording order, and what each depends on.
    stages: Vec<Box<dyn Stage>>,
    deps: Vec<Deps>,
    /// What the families add to the frame beyond stages (`methods::FAMILIES`).
    parts: Vec<Box<dyn FramePart>>,
    /// The frame's shared maps (every stage's images), by descriptor slot.
    maps: Maps,
    targets: Targets,
    readback: Option<Buffer>,
    profiler: Profiler,
    flags: u32,
    /// Flags `scene.direct` shades with (every stage's `direct_flags`).
    direct_flags: u32,
    light_table: Vec<GpuLight>,
    last_timings: Vec<PassTiming>,
    /// Scene changes and the maps they invalidate.
    updates: updates::Updates,
    /// Each view's eye (the view table's), for per-face culling.
    view_eyes: Vec<glam::Vec3>,
    /// `frame.object_ids`, with `object_ids=on`.
    ids: Option<crate::frame::ids::ObjectIds>,
    /// What stages share (one set of ray-query acceleration structures, whoever traces).
    shared: crate::frame::shared::Shared,
}

/// The frame-wide part of what stages see, built once a frame; `io` adds one view's target.
struct FrameShared<'a> {
    plan: &'a Plan,
    sets: &'a MapSets,
    view_eyes: &'a [glam::Vec3],
    scene_images: Vec<&'a Image>,
    direct_flags: u32,
}

impl<'a> FrameShared<'a> {
    /// The stages' inputs and outputs for one camera view (the camera's, or a planar
    /// mirror's): its view table entry, target, depth and area, and per-object push flags.
    fn io<'b>(
        &'b self,
        views: &'b ViewLayout,
        target: &'b mut Image,
        depth: &'b mut Image,
        maps: &'b mut Maps,
        area: vk::Rect2D,
        object_flags: &'b [(usize, u32)],
    ) -> FrameIo<'b> {
        FrameIo {
            plan: self.plan,
            views,
            target,
            depth,
            maps,
            sets: self.sets,
            view_eyes: self.view_eyes,
            scene_images: self.scene_images.clone(),
            area,
            object_flags,
            depth_masked: false,
            direct_flags: self.direct_flags,
        }
    }
}

/// What a stage's or frame part's constructor may look at.
#[allow(clippy::too_many_arguments)]
fn stage_init<'a>(
    ctx: &'a Context,
    scene: &'a Scene,
    gpu: &'a GpuScene,
    plan: &'a Plan,
    b: &Bindings,
    t: &Targets,
    size: (u32, u32),
    shared: &'a crate::frame::shared::Shared,
) -> StageInit<'a> {
    let (width, height) = t.size(size.0, size.1);
    StageInit { ctx, scene, gpu, plan, layout: b.layout, set_layouts: b.set_layouts(), width, height, multisample: t.multisample, shared }
}

impl Renderer {
    /// Creates everything the plan needs at `width`×`height`. On error, everything created
    /// so far is destroyed again.
    pub fn new(ctx: &Context, scene: &Scene, plan: Plan, width: u32, height: u32) -> Result<Renderer> {
        if !plan.is_gpu() {
            return Err(Error::invalid("method", format!("'{}' renders on the CPU: use reference::render_reference", plan.choice.name())));
        }
        if width == 0 || height == 0 || width > 16384 || height > 16384 {
            return Err(Error::invalid("size", format!("{width}x{height} is outside 1..=16384")));
        }
        let camera = scene.camera_or_default();
        camera.validate()?;
        // Methods the device cannot run (ray queries without the extensions) give way to
        // their fallbacks, named in the objects' reasons.
        let plan = plan.for_device(scene, |m| m.needs.missing_on(ctx))?;
        if plan.caustics.is_some() && plan.quality.caustics.caustic_paths == crate::quality::CausticPaths::Exact {
            if let Err(why) = &ctx.ray_query {
                return Err(Error::Unsupported(format!(
                    "knob caustic_paths=exact traces photons through ray queries, and {why}: use caustic_paths=both"
                )));
            }
        }
        let (ssaa, multisample) = Targets::check(ctx, &plan, width, height)?;
        // Partial construction: every field that owns something starts empty, and
        // `destroy` frees whatever exists.
        let r = Renderer {
            plan,
            width,
            height,
            scene: GpuScene::new(ctx, scene)?,
            camera,
            views: ViewLayout::default(),
            bindings: Bindings::empty(),
            stages: Vec::new(),
            deps: Vec::new(),
            parts: Vec::new(),
            maps: Maps::new(crate::methods::all_slots()),
            targets: Targets::empty(ssaa, multisample),
            readback: None,
            profiler: Profiler::placeholder(),
            flags: 0,
            direct_flags: 0,
            light_table: Vec::new(),
            last_timings: Vec::new(),
            updates: updates::Updates::new(scene),
            view_eyes: Vec::new(),
            ids: None,
            shared: Default::default(),
        };
        crate::vk::build(ctx, r, |r| r.init(ctx, scene))
    }

    fn init(&mut self, ctx: &Context, scene: &Scene) -> Result<()> {
        let plan = &self.plan;
        self.views = ViewLayout::of(plan);
        for (name, count) in FAMILIES.iter().filter_map(|f| f.views).flat_map(|h| h(plan)) {
            self.views.add(name, count);
        }
        self.light_table = views::light_table(scene, plan);
        self.bindings.create(ctx, self.views.count, &bindings::object_table(scene, plan), &self.light_table)?;
        let q = &plan.quality;
        self.flags = if q.frame.fresnel == FresnelMode::Exact { FLAG_FRESNEL_EXACT } else { 0 }
            | if scene.environment.is_some() { FLAG_HAS_ENVIRONMENT } else { 0 }
            | if q.layered.layered_both { 0 } else { crate::frame::layout::FLAG_LAYERED_STRONGEST }
            | if q.frame.shadows { 0 } else { crate::frame::layout::FLAG_UNSHADOWED };
        self.create_stages(ctx, scene)?;
        self.bindings.allocate_map_sets(ctx, &self.maps)?;
        self.targets.create(ctx, self.width, self.height)?;
        if self.plan.quality.frame.object_ids {
            self.ids = Some(crate::frame::ids::ObjectIds::new(ctx, self.bindings.layout, self.width, self.height)?);
        }
        let init = stage_init(ctx, scene, &self.scene, &self.plan, &self.bindings, &self.targets, (self.width, self.height), &self.shared);
        for family in FAMILIES {
            if let Some(create) = family.frame_part {
                if let Some(part) = create(&init, &mut self.maps)? {
                    self.parts.push(part);
                }
            }
        }
        // A frame part's extra views record the camera's passes again (a ray pipeline is a
        // hundred passes at depth 16).
        let views: u32 = self.parts.iter().map(|p| p.extra_views()).sum();
        self.profiler = Profiler::new(ctx, MAX_PASSES * (1 + views))?;
        self.bindings.write(ctx, &self.scene, &self.maps);
        Ok(())
    }

    /// Creates the plan's stages in order; each map stage puts its images into `maps`.
    fn create_stages(&mut self, ctx: &Context, scene: &Scene) -> Result<()> {
        let init = stage_init(ctx, scene, &self.scene, &self.plan, &self.bindings, &self.targets, (self.width, self.height), &self.shared);
        let multisample = self.targets.multisample;
        let mut objects = Vec::new();
        for spec in &self.plan.stages {
            let stage: Box<dyn Stage> = match spec {
                // The scene records its own upload (first frame only).
                StageSpec::Upload => continue,
                StageSpec::Shadows => ShadowMaps::create(&init, &mut self.maps)?,
                StageSpec::Direct => Box::new(SceneDirect::new(ctx, init.layout, multisample)?),
                StageSpec::Map(m) => (map_named(m.name).ok_or_else(|| unregistered(m.name))?.create)(&init, &m.objects, &mut self.maps)?,
                StageSpec::Effect(e) => (effect_named(e.name).ok_or_else(|| unregistered(e.name))?.create)(&init, &mut self.maps)?,
                StageSpec::Camera(c) => match camera_named(c.name).ok_or_else(|| unregistered(c.name))?.create {
                    Some(create) => create(&init, c)?,
                    None => Box::new(CameraShade::new(ctx, init.layout, c, multisample)?),
                },
            };
            self.deps.push(spec.deps());
            objects.push(spec.objects());
            self.direct_flags |= stage.direct_flags();
            self.stages.push(stage);
        }
        self.updates.track(objects);
        Ok(())
    }

    /// This frame's `Push.words`: the frame's own, then each family's.
    fn push_words(&self, q: &crate::quality::Quality) -> crate::frame::words::PushWords {
        use crate::frame::layout::{EXTRA_VIEW_BASE, RECURSION_DEPTH};
        let mut w = crate::frame::words::PushWords::default();
        w.set(RECURSION_DEPTH, q.frame.depth);
        w.set(EXTRA_VIEW_BASE, self.views.first(EXTRA_VIEWS).unwrap_or(self.views.count));
        FAMILIES.iter().filter_map(|f| f.push_words).for_each(|fill| fill(q, &self.views, &mut w));
        w
    }

    /// Every map image, by slot: what tests and tools inspect after a frame.
    pub fn maps(&self) -> &Maps {
        &self.maps
    }

    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// The camera's world → clip matrix (reversed-Z, infinite far plane, Vulkan y-down).
    pub fn camera_view_proj(&self) -> Mat4 {
        let aspect = self.width as f32 / self.height as f32;
        let mut proj = Mat4::perspective_infinite_reverse_rh(self.camera.yfov, aspect, self.camera.znear);
        proj.y_axis.y = -proj.y_axis.y;
        proj * self.camera.view()
    }

    /// The view table: the frame's own views, then each frame part's.
    fn write_views(&mut self) -> Result<()> {
        let vp = self.camera_view_proj();
        let mut table = views::view_table(&self.plan, &self.views, &self.light_table, (vp, self.camera.position));
        let frame = ViewFrame {
            plan: &self.plan,
            scene: self.updates.scene(),
            lights: &self.light_table,
            layout: &self.views,
            view_proj: vp,
            eye: self.camera.position,
            yfov: self.camera.yfov,
            aspect: self.width as f32 / self.height as f32,
        };
        for p in &mut self.parts {
            p.write_views(&frame, &mut table);
        }
        self.view_eyes = table.iter().map(|v| glam::Vec3::from_slice(&v.eye[..3])).collect();
        self.bindings.views.write(bytemuck::cast_slice(&table))
    }

    /// Records one frame into `cmd` (any primary command buffer in the recording state on
    /// this context's device). Afterwards `target` holds the image in COLOR_ATTACHMENT
    /// layout. The view table is written by the host now, so only one frame may be in
    /// flight at a time.
    pub fn record(&mut self, ctx: &Context, cmd: vk::CommandBuffer) -> Result<()> {
        self.apply_updates(ctx)?;
        self.write_views()?;
        self.shared.begin_frame();
        let words = self.push_words(&self.plan.quality);
        let mut rec = Recorder::new(ctx, cmd, &mut self.profiler);
        self.scene.record_upload(&mut rec);
        let f = FrameInputs {
            scene: &self.scene,
            set: self.bindings.set,
            layout: self.bindings.layout,
            flags: self.flags,
            light_count: self.light_table.len() as u32,
            words,
        };
        let t = &mut self.targets;
        let full = vk::Rect2D { offset: vk::Offset2D::default(), extent: vk::Extent2D { width: t.target.width, height: t.target.height } };
        let shared = FrameShared {
            plan: &self.plan,
            sets: &self.bindings.sets,
            view_eyes: &self.view_eyes,
            scene_images: f.scene.textures.iter().chain(f.scene.environment.iter()).collect(),
            direct_flags: self.direct_flags,
        };
        let updated = self.updates.recorded();
        let mut io = shared.io(&self.views, &mut t.target, &mut t.depth, &mut self.maps, full, &[]);
        // The world's maps first: those this frame must make again.
        for (stage, deps) in self.stages.iter_mut().zip(&self.deps) {
            if !deps.per_view() && updated.iter().any(|u| u.stage == stage.name()) {
                stage.record(&mut rec, &f, &mut io);
            }
        }
        drop(io);
        // The frame parts' own camera views (planar mirrors', §5), before the camera's: each
        // records the camera-dependent stages again.
        let (stages, deps) = (&mut self.stages, &self.deps);
        let mut camera_stages = |rec: &mut Recorder, v: ViewPass| {
            let mut io = shared.io(&v.views, v.target, v.depth, v.maps, v.area, v.object_flags);
            io.depth_masked = v.depth_masked;
            for (stage, _) in stages.iter_mut().zip(deps).filter(|(_, d)| d.per_view()) {
                stage.record(rec, &f, &mut io);
            }
        };
        let mut views_ran = false;
        // The per-object counters the views and camera passes add to (`Slot::counts`).
        self.maps.clear_counts(&mut rec);
        for p in &mut self.parts {
            views_ran |= p.record_views(&mut rec, &f, &self.views, &mut self.maps, &mut camera_stages);
        }
        let camera_flags: Vec<(usize, u32)> = self.parts.iter().flat_map(|p| p.camera_flags()).collect();
        let mut io = shared.io(&self.views, &mut t.target, &mut t.depth, &mut self.maps, full, &camera_flags);
        // Extra views re-recorded the camera-space maps from their cameras.
        for (stage, deps) in self.stages.iter_mut().zip(&self.deps) {
            let needed = *deps == Deps::EveryFrame || views_ran || updated.iter().any(|u| u.stage == stage.name());
            if deps.per_view() && needed {
                stage.record(&mut rec, &f, &mut io);
            }
        }
        drop(io);
        t.record_resolve(&mut rec);
        if let Some(ids) = self.ids.as_mut() {
            ids.record(&mut rec, &f, self.views.camera);
        }
        if let Some(rb) = &self.readback {
            let out = t.output();
            let open = rec.pass("frame.readback").reads(out, Access::TransferSrc).begin();
            record_copy_to_buffer(ctx, cmd, out, rb);
            rec.end(open);
        }
        Ok(())
    }

    /// Frees everything. The GPU must be idle with respect to this renderer's frames.
    pub fn destroy(&mut self, ctx: &Context) {
        for s in &mut self.stages {
            s.destroy(ctx);
        }
        self.stages.clear();
        for p in &mut self.parts {
            p.destroy(ctx);
        }
        self.parts.clear();
        self.shared.destroy(ctx);
        if let Some(mut i) = self.ids.take() {
            crate::vk::Owner::destroy(&mut i, ctx);
        }
        self.maps.destroy(ctx);
        self.targets.destroy(ctx);
        if let Some(b) = self.readback.as_mut() {
            b.destroy(ctx);
        }
        self.scene.destroy(ctx);
        self.profiler.destroy(ctx);
        self.bindings.destroy(ctx);
    }
}

impl crate::vk::Owner for Renderer {
    fn destroy(&mut self, ctx: &Context) {
        Renderer::destroy(self, ctx)
    }
}

/// A plan's stage that no registered family declares (a plan built by hand, or by another
/// build of the library).
fn unregistered(name: &str) -> Error {
    Error::invalid("plan", format!("stage '{}' is not declared by any registered family", crate::error::clip(name)))
}
