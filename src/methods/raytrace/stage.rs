//! The ray pipeline of ray tracing in the original geometry (survey §2.3.1, Purcell's
//! decomposition): rays live in GPU buffers, and each bounce is a sequence of kernels
//! with no readback between them, their sizes from GPU counters (indirect dispatch):
//!
//! 1. `raytrace.primary`: the whole triangle list rasterised from the camera into a
//!    visibility image (each pixel's nearest triangle id); `primary.comp` turns the pixels
//!    of this stage's objects into the first queue's rays with their hits.
//! 2. per bounce k = 0 … R: `raytrace.intersect.<scheme>` answers the queue's nearest-hit
//!    queries (at k = 0 only those of pixels whose raster triangle failed the exact test); `raytrace.shade` adds the environment for rays that left the
//!    scene and, at diffuse hits, the emission and one shadow query per light;
//!    `raytrace.spawn` (k < R) appends the reflected and refracted children of specular
//!    hits, Fresnel-weighted, to the next queue; the shadow queries go through the same
//!    `raytrace.intersect.<scheme>` (any hit), and those that meet nothing add their light.
//! 3. `raytrace.resolve`: the accumulated radiance of this stage's pixels replaces what
//!    the frame's earlier passes drew there.
//!
//! Radiance accumulates per pixel in 64-bit fixed point through integer atomics
//! (`glsl/raytrace/trace.glsl`), so the image does not depend on the order in which the
//! GPU processes rays, and a host-device frame equals a standalone one bit for bit. A full
//! queue keeps the heaviest paths by a histogram of their weights (the budget modes of
//! `trace.glsl`, cut by `spawn_cutoff.comp`), not the first to arrive, so an overflowing
//! frame is the same in every run too; the dropped rays and their path weight are stats.

use ash::vk;
use glam::Mat4;

use super::gpu::Structure;
use super::knobs::BvhUpdate;
use super::lbvh::{GpuBvh, Work};
use super::ray_order::RayOrder;
use super::ray_query::accel::AccelStructures;
use super::{Packed, Scheme, TriangleList};
use crate::error::{Error, Result, VkCall};
use crate::frame::layout::{
    binding, GpuRayHit, GpuRayPayload, GpuRayQuery, GpuSpawnBudget, GpuTraceParams, GpuTriangleShading, RAY_BINDINGS, RAY_QUERY_BINDINGS,
    TRACE_BINDINGS,
};
use crate::frame::stage::{FrameIo, Stage, StageInit};
use crate::frame::{begin_camera_rendering, destroy_pipelines, FrameInputs, PUSH_BYTES};
use crate::methods::Choice;
use crate::plan::predict::cost_model::BvhUpdateCosts;
use crate::plan::types::CameraPlan;
use crate::vk::pipeline::{
    compute_pipeline, descriptor_set_layout, graphics_pipeline, pipeline_layout, write_buffer, GraphicsDesc, Multisample, VertexInput,
};
use crate::vk::{begin_rendering, Access, Buffer, Context, Image, ImageDesc, ImageKind, MemoryLocation, Recorder, Target};

const STORAGE: vk::BufferUsageFlags = vk::BufferUsageFlags::STORAGE_BUFFER;
const VIS_FORMAT: vk::Format = vk::Format::R32_UINT;
const VIS_DEPTH: vk::Format = vk::Format::D32_SFLOAT;

/// One ray queue: queries, their hits and payloads.
struct Queue {
    queries: Buffer,
    hits: Buffer,
    payloads: Buffer,
}

impl Queue {
    fn new(ctx: &Context, name: &str, capacity: u64) -> Result<Queue> {
        let mut q = Queue { queries: Buffer::placeholder(), hits: Buffer::placeholder(), payloads: Buffer::placeholder() };
        let r = (|| {
            let size = |n: usize| capacity.max(1) * n as u64;
            q.queries =
                Buffer::new(ctx, &format!("{name}.queries"), size(std::mem::size_of::<GpuRayQuery>()), STORAGE, MemoryLocation::GpuOnly)?;
            q.hits = Buffer::new(ctx, &format!("{name}.hits"), size(std::mem::size_of::<GpuRayHit>()), STORAGE, MemoryLocation::GpuOnly)?;
            q.payloads = Buffer::new(
                ctx,
                &format!("{name}.payloads"),
                size(std::mem::size_of::<GpuRayPayload>()),
                STORAGE,
                MemoryLocation::GpuOnly,
            )?;
            Ok(())
        })();
        match r {
            Ok(()) => Ok(q),
            Err(e) => {
                q.destroy(ctx);
                Err(e)
            }
        }
    }

    fn destroy(&mut self, ctx: &Context) {
        self.queries.destroy(ctx);
        self.hits.destroy(ctx);
        self.payloads.destroy(ctx);
    }
}

#[derive(Default)]
struct Pipelines {
    primary_raster: vk::Pipeline,
    primary: vk::Pipeline,
    intersect: vk::Pipeline,
    shade: vk::Pipeline,
    spawn: vk::Pipeline,
    spawn_cutoff: vk::Pipeline,
    shadow: vk::Pipeline,
    args: vk::Pipeline,
    resolve: vk::Pipeline,
    /// The ray engine's raster pass (or the ray hierarchy's), its copy into the hit buffer,
    /// and the hierarchy's cone kernel.
    engine: vk::Pipeline,
    engine_copy: vk::Pipeline,
    cones: vk::Pipeline,
    cull_stats: vk::Pipeline,
}

pub struct RayTrace {
    name: &'static str,
    scheme: Scheme,
    depth: u32,
    width: u32,
    height: u32,
    /// Rays per pixel: the camera target's MSAA samples (one camera ray at each sample's
    /// standard position; 1 without MSAA).
    samples: u32,
    triangle_count: u32,
    structure: Option<Structure>,
    /// The ray-query scheme's acceleration structures (the frame's, shared with every stage
    /// that traces ray queries; the renderer destroys them), and its set 5 (the TLAS).
    accel: Option<std::rc::Rc<std::cell::RefCell<AccelStructures>>>,
    rq_set: vk::DescriptorSet,
    /// `map_updates=always`: the TLAS is rebuilt every frame, as when objects move.
    tlas_every_frame: bool,
    /// The frame's triangle shading (shared; the renderer destroys it).
    shading: Option<std::rc::Rc<std::cell::RefCell<SceneShading>>>,
    handled: Buffer,
    queues: Vec<Queue>,
    shadow: Option<Queue>,
    /// Per queue k = 0 … R + 1 a counter, then per bounce a shadow counter, `stride` apart.
    counters: Buffer,
    /// One `TraceParams` per bounce, `stride` apart.
    params: Buffer,
    /// Two `GpuSpawnBudget` per bounce, `budget_stride` apart: the next queue's and the
    /// shadow queue's (host-visible: the dropped rays and weight are stats).
    spawn_budget: Buffer,
    budget_stride: u64,
    /// 8 words per bounce: the rays' and the shadow queries' dispatch arguments.
    dispatch: Buffer,
    accum: Buffer,
    vis: Option<Image>,
    vis_depth: Option<Image>,
    /// The ray engine's (and ray hierarchy's) ray texture: hit records and depth.
    engine: Option<Image>,
    engine_depth: Option<Image>,
    /// The ray hierarchy's cone per tile.
    cones: Buffer,
    /// The ray hierarchy's ray order (each queue's rays by direction cell and pixel, before its cones).
    order: Option<RayOrder>,
    /// With the ray_stats knob: the hierarchy's culling counts (`cull_stats.comp`).
    cull_stats: Buffer,
    stats: bool,
    capacity: u64,
    /// The shadow queue's rays (the budget times the lights, clamped like `capacity`).
    shadow_capacity: u64,
    lights: u64,
    ray_texture: (u32, u32),
    tiles: u32,
    stride: u64,
    /// Sets 2 and 3, then for the ray-query scheme an empty set 4 and set 5 (null for the
    /// others).
    set_layouts: [vk::DescriptorSetLayout; 4],
    layout: vk::PipelineLayout,
    p: Pipelines,
    pool: vk::DescriptorPool,
    /// Set 2 over queue k (k = 0 … R), then over the shadow queue of bounce k.
    ray_sets: Vec<vk::DescriptorSet>,
    shadow_sets: Vec<vk::DescriptorSet>,
    /// Set 3 of bounce k (next queue k + 1, shadow counter k); `primary_set`: next queue 0.
    trace_sets: Vec<vk::DescriptorSet>,
    primary_set: vk::DescriptorSet,
    /// The structure's CPU build time (`raytrace.build`), milliseconds.
    pub build_ms: f64,
    /// The BVH's GPU builder or refitter (`bvh_build=lbvh`, or once a move refitted or
    /// rebuilt the tree on the GPU), and how moves update the BVH (`bvh_update`).
    gpu_bvh: Option<GpuBvh>,
    bvh_update: BvhUpdate,
    /// Each mesh's world transform and object-space shape (a hash of its positions) when the
    /// tree was last built: what `bvh_update=auto` refits over (moves) or rebuilds after
    /// (deformation, turns beyond REFIT_TURN).
    built_at: Vec<(Mat4, u64)>,
    /// Which builder `bvh_update=auto` rebuilds with: the one the device's unit costs predict
    /// faster for the scene's triangles, or without them the CPU's SAH builder where the
    /// device runs compute on the CPU (lavapipe: measured faster than the GPU's linear BVH
    /// there, BENCHMARKS.md), else the GPU's.
    update_costs: Option<BvhUpdateCosts>,
    cpu_device: bool,
}

/// Whether `bvh_update=auto` rebuilds a BVH of `triangles` on the GPU (else the CPU's SAH
/// builder): by the device's measured update costs where there are some, else by whether
/// the device runs its compute on the CPU; never beyond the GPU build's `MAX_TRIANGLES`.
pub fn rebuild_on_gpu(costs: Option<&BvhUpdateCosts>, triangles: usize, cpu_device: bool) -> bool {
    if triangles as u64 > super::lbvh::MAX_TRIANGLES {
        return false;
    }
    match costs {
        Some(c) => BvhUpdateCosts::predict(c.lbvh, triangles as f64) < BvhUpdateCosts::predict(c.sah, triangles as f64),
        None => !cpu_device,
    }
}

/// `bvh_update=auto` refits the tree over objects that moved rigidly (translated, scaled,
/// turned by less than this many radians in all since the tree was built) and rebuilds it
/// after a deformation (an object's own positions changed) or a larger turn. Translation
/// costs a refitted tree nothing measurable (the demo's mirror sphere carried 3 diagonals
/// at 10³ to 10⁶ triangles: frames within the noise of a rebuilt tree's, BENCHMARKS.md,
/// "BVHs for moving geometry"): its subtree keeps its boxes, and only the few nodes that joined it
/// to its neighbours stretch. A turn widens every box of its subtree: an axis-aligned box
/// of a turned box grows by cos θ + sin θ along an axis, 1.34 at 20°.
pub const REFIT_TURN: f32 = 20.0 * std::f32::consts::PI / 180.0;

fn shapes_of(scene: &crate::scene::Scene) -> Vec<(Mat4, u64)> {
    scene.meshes.iter().map(|m| (m.world, shape_hash(m))).collect()
}

fn shape_hash(m: &crate::scene::Mesh) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    for p in m.object_positions() {
        p.to_array().map(f32::to_bits).hash(&mut h);
    }
    m.indices.hash(&mut h);
    h.finish()
}

/// The rotation, in radians, between two transforms' rotation parts.
fn turn(a: Mat4, b: Mat4) -> f32 {
    let (_, ra, _) = a.to_scale_rotation_translation();
    let (_, rb, _) = b.to_scale_rotation_translation();
    let angle = ra.normalize().angle_between(rb.normalize());
    if angle.is_finite() {
        angle
    } else {
        f32::INFINITY
    }
}

/// Creates the stage of a ray-tracing method for the plan's objects.
pub fn create(init: &StageInit, plan: &CameraPlan, scheme: Scheme) -> Result<Box<dyn Stage>> {
    let ctx = init.ctx;
    let q = &init.plan.quality;
    let mut me = RayTrace {
        name: plan.name,
        scheme,
        depth: q.frame.depth,
        width: init.width,
        height: init.height,
        samples: init.multisample.samples,
        triangle_count: 0,
        structure: None,
        accel: None,
        rq_set: vk::DescriptorSet::null(),
        tlas_every_frame: q.frame.map_updates_always,
        shading: None,
        handled: Buffer::placeholder(),
        queues: Vec::new(),
        shadow: None,
        counters: Buffer::placeholder(),
        params: Buffer::placeholder(),
        spawn_budget: Buffer::placeholder(),
        budget_stride: 0,
        dispatch: Buffer::placeholder(),
        accum: Buffer::placeholder(),
        vis: None,
        vis_depth: None,
        engine: None,
        engine_depth: None,
        cones: Buffer::placeholder(),
        order: None,
        cull_stats: Buffer::placeholder(),
        stats: q.raytrace.ray_stats,
        capacity: 0,
        shadow_capacity: 0,
        lights: 1,
        ray_texture: (0, 0),
        tiles: 0,
        stride: 64,
        set_layouts: [vk::DescriptorSetLayout::null(); 4],
        layout: vk::PipelineLayout::null(),
        p: Pipelines::default(),
        pool: vk::DescriptorPool::null(),
        ray_sets: Vec::new(),
        shadow_sets: Vec::new(),
        trace_sets: Vec::new(),
        primary_set: vk::DescriptorSet::null(),
        build_ms: 0.0,
        gpu_bvh: None,
        bvh_update: q.raytrace.bvh_update,
        // Only `bvh_update=auto` reads it (hashing every mesh costs a pass over the scene).
        built_at: match (scheme, q.raytrace.bvh_update) {
            (Scheme::Bvh { .. }, BvhUpdate::Auto) => shapes_of(init.scene),
            _ => Vec::new(),
        },
        update_costs: init.plan.target.as_ref().and_then(|t| t.costs.bvh_updates.clone()),
        cpu_device: ctx.properties.device_type == vk::PhysicalDeviceType::CPU,
    };
    match me.init(init, plan) {
        Ok(()) => Ok(Box::new(me)),
        Err(e) => {
            me.destroy(ctx);
            Err(e)
        }
    }
}

/// Every triangle's shading attributes on the GPU (`raytrace.shading`), one buffer per frame
/// whoever reads it (the ray pipeline, the exact caustic photons, the hybrid searches).
pub(crate) struct SceneShading(pub Buffer);

impl crate::frame::shared::SharedResource for SceneShading {
    /// Rewritten after moves (world-space normals).
    fn scene_changed(&mut self, init: &StageInit, changes: &crate::scene::update::Changes) -> Result<()> {
        if changes.moved.is_empty() {
            return Ok(());
        }
        self.0.write(bytemuck::cast_slice(&triangle_shading(init.scene)))
    }

    fn destroy(&mut self, ctx: &crate::vk::Context) {
        self.0.destroy(ctx);
    }
}

impl SceneShading {
    /// The frame's buffer over `init`'s scene (made by the first stage that asks).
    pub(crate) fn of(init: &StageInit) -> Result<std::rc::Rc<std::cell::RefCell<SceneShading>>> {
        init.shared.get_or_create("raytrace.shading", || {
            Ok(SceneShading(Buffer::with_data(init.ctx, "raytrace.shading", &triangle_shading(init.scene), STORAGE)?))
        })
    }
}

/// The shading attributes of every triangle of the list, in its order.
pub(crate) fn triangle_shading(scene: &crate::scene::Scene) -> Vec<GpuTriangleShading> {
    let mut out = Vec::with_capacity(scene.triangle_count());
    for (m, mesh) in scene.meshes.iter().enumerate() {
        for t in mesh.indices.chunks_exact(3) {
            let n = |k: usize| mesh.normals[t[k] as usize].extend(0.0).to_array();
            let uv = |k: usize| mesh.uvs[t[k] as usize];
            let mut n0 = n(0);
            n0[3] = f32::from_bits(mesh.material as u32);
            let (a, b, c) = (uv(0), uv(1), uv(2));
            out.push(GpuTriangleShading {
                n0,
                n1: n(1),
                n2: n(2),
                uv01: [a.x, a.y, b.x, b.y],
                uv2: [c.x, c.y, f32::from_bits(m as u32), 0.0],
            });
        }
    }
    out
}

impl RayTrace {
    fn shading_raw(&self) -> vk::Buffer {
        self.shading.as_ref().map_or(vk::Buffer::null(), |s| s.borrow().0.raw)
    }

    fn init(&mut self, init: &StageInit, plan: &CameraPlan) -> Result<()> {
        let ctx = init.ctx;
        let scene = init.scene;
        let q = &init.plan.quality;
        let list = TriangleList::from_scene(scene);
        self.triangle_count = list.len() as u32;
        let start = std::time::Instant::now();
        let packed = self.scheme.build(&list)?;
        self.build_ms = start.elapsed().as_secs_f64() * 1e3;
        self.structure = Some(Structure::new(ctx, self.scheme, &list, &packed)?);
        // A BVH built on the GPU: recorded into the first frame (`raytrace.build`).
        if let (Scheme::Bvh { gpu: true, .. }, Some(s), false) = (self.scheme, &self.structure, list.is_empty()) {
            self.gpu_bvh = Some(GpuBvh::linear(ctx, s, &list)?);
        }
        if self.scheme == Scheme::RayQuery {
            self.accel = Some(super::ray_query::accel::scene_structures(init)?);
        }
        self.shading = Some(SceneShading::of(init)?);
        // Its objects' pixels; every pixel when the whole scene is ray traced (the plan then
        // makes no shadow maps: diffuse surfaces seen directly get exact shadow rays too).
        let whole_scene = matches!(init.plan.choice, Choice::Method(m) if m.gpu.is_some_and(|g| g.camera.name == plan.name));
        let mut handled = vec![whole_scene as u32; scene.meshes.len().max(1)];
        for &(m, _) in &plan.objects {
            handled[m] = 1;
        }
        self.handled = Buffer::with_data(ctx, "raytrace.handled", &handled, STORAGE)?;

        // One camera ray per sample: each (pixel, sample) pair accumulates on its own.
        let pixels = self.width as u64 * self.height as u64 * self.samples as u64;
        let lights = scene.lights.len().max(1) as u64;
        if pixels * q.raytrace.ray_budget as u64 * lights > u32::MAX as u64 / 2 {
            return Err(Error::invalid(
                "knob ray_budget",
                format!("{} rays per bounce exceed the queues' 32-bit indices", pixels * q.raytrace.ray_budget as u64 * lights),
            ));
        }
        // A queue's buffers are bound whole: none may exceed the device's storage-buffer
        // range. Every camera ray must fit (else an error naming the frame); the budget's
        // further rays are clamped there, and the rays a bounce then cannot queue are dropped
        // and counted (`raytrace.dropped_rays`), as past the budget itself.
        let limit = ctx.properties.limits.max_storage_buffer_range as u64;
        let widest = [std::mem::size_of::<GpuRayQuery>(), std::mem::size_of::<GpuRayHit>(), std::mem::size_of::<GpuRayPayload>()]
            .into_iter()
            .max()
            .unwrap_or(64) as u64;
        let fits = limit / widest;
        if pixels > fits || pixels * 24 > limit {
            return Err(Error::invalid(
                "frame size",
                format!(
                    "{}x{} × {} samples: {pixels} camera rays need {} MiB per ray queue, over this device's storage-buffer range ({} MiB); a smaller frame or aa (ssaa renders N² rays per pixel, msaaN N)",
                    self.width,
                    self.height,
                    self.samples,
                    (pixels * widest) >> 20,
                    limit >> 20
                ),
            ));
        }
        let capacity = (pixels * q.raytrace.ray_budget as u64).min(fits);
        let shadow_capacity = (capacity * lights).min(fits);
        for i in 0..2 {
            self.queues.push(Queue::new(ctx, &format!("raytrace.queue{i}"), capacity)?);
        }
        self.shadow = Some(Queue::new(ctx, "raytrace.shadow", shadow_capacity)?);
        self.lights = lights;
        self.shadow_capacity = shadow_capacity;
        let align = ctx.properties.limits.min_storage_buffer_offset_alignment.max(4);
        self.stride = 64u64.div_ceil(align) * align;
        let bounces = self.depth as u64 + 1;
        let counter_usage = STORAGE | vk::BufferUsageFlags::TRANSFER_DST;
        // Host-visible: `stats` reads the rays each bounce made after the frame.
        self.counters = Buffer::new(ctx, "raytrace.counters", self.stride * (2 * bounces + 1), counter_usage, MemoryLocation::GpuToCpu)?;
        self.capacity = capacity;
        // The ray texture of the rasterising schemes: every queue's rays, row by row.
        let most = capacity.max(shadow_capacity);
        let width = ((most as f64).sqrt().ceil() as u32).div_ceil(32).max(1) * 32;
        let tile = match self.scheme {
            Scheme::RayHierarchy { tile } => tile,
            _ => 0,
        };
        // The hierarchy fills its texture tile by tile (engine.glsl's texel_slot): whole rows
        // of tiles (the width is a multiple of 32, every tile size divides it).
        let height = (most.div_ceil(width as u64) as u32).div_ceil(tile.max(1)) * tile.max(1);
        let limit = ctx.properties.limits.max_image_dimension2_d;
        if matches!(self.scheme, Scheme::RayEngine | Scheme::RayHierarchy { .. }) {
            if width > limit || height > limit {
                return Err(Error::invalid(
                    "knob ray_budget",
                    format!("the ray texture of {most} rays ({width}×{height}) exceeds the device's {limit}² image limit"),
                ));
            }
            self.ray_texture = (width, height);
            let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::STORAGE;
            let desc = |name, format, usage| ImageDesc { name, format, width, height, kind: ImageKind::D2, usage };
            self.engine = Some(Image::new(ctx, &desc("raytrace.ray_texture", vk::Format::R32G32B32A32_UINT, usage))?);
            self.engine_depth =
                Some(Image::new(ctx, &desc("raytrace.ray_texture_depth", VIS_DEPTH, vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT))?);
        }
        let tiles_per_row = width.checked_div(tile).unwrap_or(0);
        if tile > 0 {
            self.tiles = tiles_per_row * height.div_ceil(tile);
            self.cones = Buffer::new(ctx, "raytrace.tile_cones", 32 * self.tiles.max(1) as u64, STORAGE, MemoryLocation::GpuOnly)?;
            if self.stats {
                let usage = STORAGE | vk::BufferUsageFlags::TRANSFER_DST;
                self.cull_stats = Buffer::new(ctx, "raytrace.cull_stats", 16 * bounces, usage, MemoryLocation::GpuToCpu)?;
            }
        }
        let mut params = vec![0u8; (self.stride * bounces) as usize];
        for k in 0..bounces {
            let p = GpuTraceParams {
                width: self.width,
                height: self.height,
                bounce: k as u32,
                last: (k + 1 == bounces) as u32,
                capacity: capacity as u32,
                shadow_capacity: shadow_capacity as u32,
                t_min: list_offset(&list),
                ray_texture_width: width,
                tile_size: tile.max(1),
                tiles_per_row,
                samples: self.samples,
                ordered: (tile > 0) as u32,
                medium_turn: q.frame.medium_turn,
                direction_cells: super::ray_order::direction_cells(self.width, self.height, self.samples, tile.max(1)),
                pad: [0; 2],
            };
            let at = (k * self.stride) as usize;
            params[at..at + std::mem::size_of::<GpuTraceParams>()].copy_from_slice(bytemuck::bytes_of(&p));
        }
        self.params = Buffer::with_data(ctx, "raytrace.params", &params, STORAGE)?;
        let budget = std::mem::size_of::<GpuSpawnBudget>() as u64;
        self.budget_stride = budget.div_ceil(align) * align;
        self.spawn_budget =
            Buffer::new(ctx, "raytrace.queue_budgets", 2 * self.budget_stride * bounces, counter_usage, MemoryLocation::GpuToCpu)?;
        self.dispatch =
            Buffer::new(ctx, "raytrace.dispatch", 32 * bounces, STORAGE | vk::BufferUsageFlags::INDIRECT_BUFFER, MemoryLocation::GpuOnly)?;
        self.accum = Buffer::new(ctx, "raytrace.accum", pixels * 24, counter_usage, MemoryLocation::GpuOnly)?;
        let image = |name: &'static str, format, kind, usage| {
            Image::new(ctx, &ImageDesc { name, format, width: self.width, height: self.height, kind, usage })
        };
        // One layer per sample: layer s is the nearest triangle at sample s's position.
        let layers = ImageKind::D2Array { layers: self.samples };
        let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::STORAGE;
        self.vis = Some(image("raytrace.visibility", VIS_FORMAT, layers, usage)?);
        self.vis_depth = Some(image("raytrace.visibility_depth", VIS_DEPTH, ImageKind::D2, vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT)?);

        let stages = vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT | vk::ShaderStageFlags::COMPUTE;
        self.set_layouts[0] = descriptor_set_layout(ctx, "raytrace.rays", RAY_BINDINGS, stages)?;
        self.set_layouts[1] = descriptor_set_layout(ctx, "raytrace.trace", TRACE_BINDINGS, stages)?;
        let mut layouts = vec![init.set_layouts[0], init.set_layouts[1], self.set_layouts[0], self.set_layouts[1]];
        if self.accel.is_some() {
            self.set_layouts[2] = descriptor_set_layout(ctx, "raytrace.set4", &[], vk::ShaderStageFlags::COMPUTE)?;
            self.set_layouts[3] = descriptor_set_layout(ctx, "raytrace.ray-query", RAY_QUERY_BINDINGS, vk::ShaderStageFlags::COMPUTE)?;
            layouts.extend([self.set_layouts[2], self.set_layouts[3]]);
        }
        self.layout = pipeline_layout(ctx, "raytrace.layout", &layouts, PUSH_BYTES, stages)?;
        // A scene with graded media (survey §6.5): the intersection kernels' variant that
        // marches curved rays (raytrace/intersect_main.glsl).
        let graded = init.scene.materials.iter().any(|m| m.medium().is_some());
        self.create_pipelines(ctx, crate::methods::caustics::project::photon_map(init), graded)?;
        if tile > 0 {
            self.order = Some(RayOrder::new(ctx, self.layout, most, (self.width, self.height, self.samples, tile))?);
        }
        self.create_sets(ctx)
    }

    /// `photon_map`: the plan's caustics are the photon map (the shading kernel's variant that
    /// gathers it); `graded`: the scene has graded media.
    fn create_pipelines(&mut self, ctx: &Context, photon_map: bool, graded: bool) -> Result<()> {
        let raster = |name, vertex, fragment, formats: &'static [vk::Format], depth: Option<vk::Format>| GraphicsDesc {
            name,
            vertex,
            fragment,
            vertex_input: VertexInput::None,
            color_formats: formats,
            depth_format: depth,
            depth_test: depth.is_some(),
            depth_write: depth.is_some(),
            view_mask: 0,
            cull: vk::CullModeFlags::NONE,
            multisample: Multisample::OFF,
            blend: crate::vk::pipeline::Blend::Replace,
            depth_op: crate::vk::pipeline::DepthOp::Nearer,
        };
        self.p.primary_raster = graphics_pipeline(
            ctx,
            self.layout,
            &raster("raytrace.primary", "raytrace/primary.vert", "raytrace/primary.frag", &[VIS_FORMAT], Some(VIS_DEPTH)),
        )?;
        // The resolve pass draws into the frame's target and depth, testing nothing.
        let mut resolve = raster(
            "raytrace.resolve",
            "raytrace/resolve.vert",
            if self.samples > 1 { "raytrace/resolve_samples.frag" } else { "raytrace/resolve.frag" },
            &[crate::frame::direct::TARGET_FORMAT],
            Some(crate::frame::direct::DEPTH_FORMAT),
        );
        resolve.depth_test = false;
        resolve.depth_write = false;
        // With MSAA each sample takes its own ray's radiance (gl_SampleID).
        resolve.multisample = Multisample { samples: self.samples, per_sample: self.samples > 1 };
        self.p.resolve = graphics_pipeline(ctx, self.layout, &resolve)?;
        match self.scheme {
            Scheme::RayEngine | Scheme::RayHierarchy { .. } => {
                let vertex = if matches!(self.scheme, Scheme::RayEngine) { "raytrace/engine.vert" } else { "raytrace/hierarchy.vert" };
                let mut engine =
                    raster("raytrace.engine", vertex, "raytrace/engine.frag", &[vk::Format::R32G32B32A32_UINT], Some(VIS_DEPTH));
                engine.name = self.scheme.pass_name();
                self.p.engine = graphics_pipeline(ctx, self.layout, &engine)?;
                self.p.engine_copy = compute_pipeline(ctx, self.layout, "raytrace/engine_copy.comp")?;
                if matches!(self.scheme, Scheme::RayHierarchy { .. }) {
                    self.p.cones = compute_pipeline(ctx, self.layout, "raytrace/cones.comp")?;
                    if self.stats {
                        self.p.cull_stats = compute_pipeline(ctx, self.layout, "raytrace/cull_stats.comp")?;
                    }
                }
            }
            _ => {
                let shader = self.structure.as_ref().map_or("raytrace/intersect_brute.comp", |s| s.shader);
                let shader = if graded { graded_variant(shader) } else { shader.to_string() };
                self.p.intersect = compute_pipeline(ctx, self.layout, &shader)?;
            }
        }
        self.p.primary = compute_pipeline(ctx, self.layout, "raytrace/primary.comp")?;
        let shade = if photon_map { "raytrace/shade.comp#CAUSTICS_PHOTON_MAP" } else { "raytrace/shade.comp" };
        self.p.shade = compute_pipeline(ctx, self.layout, shade)?;
        self.p.spawn = compute_pipeline(ctx, self.layout, "raytrace/spawn.comp")?;
        self.p.spawn_cutoff = compute_pipeline(ctx, self.layout, "raytrace/spawn_cutoff.comp")?;
        self.p.shadow = compute_pipeline(ctx, self.layout, "raytrace/shadow.comp")?;
        self.p.args = compute_pipeline(ctx, self.layout, "raytrace/args.comp")?;
        Ok(())
    }

    fn create_sets(&mut self, ctx: &Context) -> Result<()> {
        let bounces = self.depth as usize + 1;
        let ray_sets = 2 * bounces;
        let trace_sets = bounces + 1;
        let count = |bindings: &[crate::vk::pipeline::Binding], ty: vk::DescriptorType, sets: usize| {
            bindings.iter().filter(|b| b.1 == ty).count() as u32 * sets as u32
        };
        let mut sizes = [
            vk::DescriptorPoolSize {
                ty: vk::DescriptorType::STORAGE_BUFFER,
                descriptor_count: count(RAY_BINDINGS, vk::DescriptorType::STORAGE_BUFFER, ray_sets)
                    + count(TRACE_BINDINGS, vk::DescriptorType::STORAGE_BUFFER, trace_sets),
            },
            vk::DescriptorPoolSize {
                ty: vk::DescriptorType::STORAGE_IMAGE,
                descriptor_count: count(TRACE_BINDINGS, vk::DescriptorType::STORAGE_IMAGE, trace_sets),
            },
            vk::DescriptorPoolSize { ty: vk::DescriptorType::ACCELERATION_STRUCTURE_KHR, descriptor_count: 1 },
        ];
        let rq_sets = self.accel.is_some() as usize;
        sizes[0].descriptor_count += count(RAY_QUERY_BINDINGS, vk::DescriptorType::STORAGE_BUFFER, rq_sets);
        let sizes = &sizes[..2 + rq_sets];
        let info = vk::DescriptorPoolCreateInfo::default().max_sets((ray_sets + trace_sets + rq_sets) as u32).pool_sizes(sizes);
        self.pool = unsafe { ctx.device.create_descriptor_pool(&info, ctx.alloc()) }.call("vkCreateDescriptorPool")?;
        let mut layouts = vec![self.set_layouts[0]; ray_sets];
        layouts.extend(std::iter::repeat_n(self.set_layouts[1], trace_sets));
        layouts.extend(std::iter::repeat_n(self.set_layouts[3], rq_sets));
        let sets = unsafe {
            ctx.device.allocate_descriptor_sets(&vk::DescriptorSetAllocateInfo::default().descriptor_pool(self.pool).set_layouts(&layouts))
        }
        .call("vkAllocateDescriptorSets")?;
        self.ray_sets = sets[..bounces].to_vec();
        self.shadow_sets = sets[bounces..ray_sets].to_vec();
        self.primary_set = sets[ray_sets];
        self.trace_sets = sets[ray_sets + 1..ray_sets + trace_sets].to_vec();
        if let Some(accel) = &self.accel {
            self.rq_set = sets[ray_sets + trace_sets];
            super::ray_query::accel::write_tlas(ctx, self.rq_set, accel.borrow().tlas());
            write_buffer(ctx, self.rq_set, binding::RQ_SHADING, vk::DescriptorType::STORAGE_BUFFER, self.shading_raw());
            write_buffer(ctx, self.rq_set, binding::RQ_COUNTS, vk::DescriptorType::STORAGE_BUFFER, vk::Buffer::null());
        }

        let sb = vk::DescriptorType::STORAGE_BUFFER;
        let structure = self.structure.as_ref().expect("created before the sets");
        let at = |set, b, buf: &Buffer, offset: u64, range: u64| {
            let info = [vk::DescriptorBufferInfo { buffer: buf.raw, offset, range }];
            let w = vk::WriteDescriptorSet::default().dst_set(set).dst_binding(b).descriptor_type(sb).buffer_info(&info);
            unsafe { ctx.device.update_descriptor_sets(&[w], &[]) };
        };
        let whole = vk::WHOLE_SIZE;
        let stride = self.stride;
        let counter = |k: usize| k as u64 * stride;
        let shadow_counter = |k: usize| (bounces + 1 + k) as u64 * stride;
        let shadow = self.shadow.as_ref().expect("created before the sets");
        for k in 0..bounces {
            for (set, queue, count_at) in
                [(self.ray_sets[k], &self.queues[k % 2], counter(k)), (self.shadow_sets[k], shadow, shadow_counter(k))]
            {
                structure.write(ctx, set);
                write_buffer(ctx, set, binding::RAY_QUERIES, sb, queue.queries.raw);
                write_buffer(ctx, set, binding::RAY_HITS, sb, queue.hits.raw);
                write_buffer(ctx, set, binding::RAY_PAYLOADS, sb, queue.payloads.raw);
                at(set, binding::RAY_COUNT, &self.counters, count_at, 4);
            }
        }
        // Set 3 of the primary step (next: queue 0) and of each bounce k (next: queue k+1).
        let mut trace: Vec<(vk::DescriptorSet, usize, usize)> = vec![(self.primary_set, 0, 0)];
        trace.extend((0..bounces).map(|k| (self.trace_sets[k], k + 1, k)));
        let vis = self.vis.as_ref().expect("created before the sets");
        for (set, next, k) in trace {
            let queue = &self.queues[next % 2];
            write_buffer(ctx, set, binding::NEXT_QUERIES, sb, queue.queries.raw);
            write_buffer(ctx, set, binding::NEXT_PAYLOADS, sb, queue.payloads.raw);
            write_buffer(ctx, set, binding::NEXT_HITS, sb, queue.hits.raw);
            at(set, binding::NEXT_COUNT, &self.counters, counter(next), 4);
            write_buffer(ctx, set, binding::SHADOW_QUERIES, sb, shadow.queries.raw);
            write_buffer(ctx, set, binding::SHADOW_PAYLOADS, sb, shadow.payloads.raw);
            at(set, binding::SHADOW_COUNT, &self.counters, shadow_counter(k), 4);
            write_buffer(ctx, set, binding::ACCUM, sb, self.accum.raw);
            write_buffer(ctx, set, binding::SHADING, sb, self.shading_raw());
            write_buffer(ctx, set, binding::HANDLED, sb, self.handled.raw);
            at(set, binding::TRACE, &self.params, k as u64 * stride, std::mem::size_of::<GpuTraceParams>() as u64);
            let budget = std::mem::size_of::<GpuSpawnBudget>() as u64;
            at(set, binding::SPAWN_BUDGET, &self.spawn_budget, 2 * k as u64 * self.budget_stride, budget);
            at(set, binding::SHADOW_BUDGET, &self.spawn_budget, (2 * k as u64 + 1) * self.budget_stride, budget);
            at(set, binding::DISPATCH, &self.dispatch, 0, whole);
            let engine = self.engine.as_ref().map_or(vk::ImageView::null(), |e| e.view);
            for (b, view) in [(binding::VISIBILITY, vis.view), (binding::ENGINE_HITS, engine)] {
                let img =
                    [vk::DescriptorImageInfo { sampler: vk::Sampler::null(), image_view: view, image_layout: vk::ImageLayout::GENERAL }];
                let w = vk::WriteDescriptorSet::default()
                    .dst_set(set)
                    .dst_binding(b)
                    .descriptor_type(vk::DescriptorType::STORAGE_IMAGE)
                    .image_info(&img);
                unsafe { ctx.device.update_descriptor_sets(&[w], &[]) };
            }
            RayOrder::write(self.order.as_ref(), ctx, set);
            write_buffer(ctx, set, binding::TILE_CONES, sb, if self.tiles > 0 { self.cones.raw } else { vk::Buffer::null() });
            write_buffer(
                ctx,
                set,
                binding::CULL_STATS,
                sb,
                if self.cull_stats.size > 0 { self.cull_stats.raw } else { vk::Buffer::null() },
            );
        }
        Ok(())
    }

    fn push(&self, ctx: &Context, cmd: vk::CommandBuffer, f: &FrameInputs, view: u32) {
        self.push_object(ctx, cmd, f, view, 0);
    }

    /// `push` with `Push.object` set (cull_stats.comp: which queue it counts).
    fn push_object(&self, ctx: &Context, cmd: vk::CommandBuffer, f: &FrameInputs, view: u32, object: u32) {
        f.push_in(ctx, cmd, self.layout, view, object, f.flags);
    }

    fn bind(
        &self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        point: vk::PipelineBindPoint,
        pipeline: vk::Pipeline,
        f: &FrameInputs,
        sets: [vk::DescriptorSet; 2],
    ) {
        unsafe {
            ctx.device.cmd_bind_pipeline(cmd, point, pipeline);
            ctx.device.cmd_bind_descriptor_sets(cmd, point, self.layout, 0, &[f.set], &[]);
            ctx.device.cmd_bind_descriptor_sets(cmd, point, self.layout, 2, &sets, &[]);
            if self.rq_set != vk::DescriptorSet::null() && point == vk::PipelineBindPoint::COMPUTE {
                ctx.device.cmd_bind_descriptor_sets(cmd, point, self.layout, 5, &[self.rq_set], &[]);
            }
        }
    }

    /// The nearest hits of the queue bound in `sets`: the scheme's kernel (indirect, from the
    /// queue's counter), or the ray engine's raster pass over the ray texture and its copy
    /// into the hit buffer (the ray hierarchy first orders the queue by direction cell and pixel, then builds its
    /// tiles' cones).
    fn intersect(&mut self, rec: &mut Recorder, f: &FrameInputs, sets: [vk::DescriptorSet; 2], at: u64, view: u32, queue: u32) {
        let (ctx, cmd) = (rec.ctx, rec.cmd);
        let name = self.scheme.pass_name();
        let (Some(engine), Some(depth)) = (self.engine.as_mut(), self.engine_depth.as_mut()) else {
            let open = rec.pass(name).after_buffer_writes().begin();
            self.dispatch_indirect((ctx, cmd), self.p.intersect, f, sets, at, view);
            rec.end(open);
            return;
        };
        let open =
            rec.pass(name).after_buffer_writes().writes(engine, Access::ColorAttachment).writes(depth, Access::DepthAttachment).begin();
        if self.tiles > 0 {
            if let Some(order) = &self.order {
                let bind = |p| {
                    self.bind(ctx, cmd, vk::PipelineBindPoint::COMPUTE, p, f, sets);
                    self.push_object(ctx, cmd, f, view, queue);
                };
                order.record(ctx, cmd, &bind, (self.dispatch.raw, at));
            }
            self.bind(ctx, cmd, vk::PipelineBindPoint::COMPUTE, self.p.cones, f, sets);
            self.push_object(ctx, cmd, f, view, queue);
            unsafe { ctx.device.cmd_dispatch(cmd, self.tiles.div_ceil(64), 1, 1) };
            let b = [vk::MemoryBarrier2::default()
                .src_stage_mask(vk::PipelineStageFlags2::COMPUTE_SHADER)
                .src_access_mask(vk::AccessFlags2::SHADER_STORAGE_WRITE)
                .dst_stage_mask(vk::PipelineStageFlags2::VERTEX_SHADER)
                .dst_access_mask(vk::AccessFlags2::SHADER_STORAGE_READ)];
            unsafe { ctx.device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&b)) };
            if self.p.cull_stats != vk::Pipeline::null() {
                // The culling rate: the same test over every tile × triangle pair, counted.
                Self::barrier(ctx, cmd);
                self.bind(ctx, cmd, vk::PipelineBindPoint::COMPUTE, self.p.cull_stats, f, sets);
                self.push_object(ctx, cmd, f, view, queue);
                unsafe { ctx.device.cmd_dispatch(cmd, self.triangle_count.div_ceil(64), self.tiles, 1) };
            }
        }
        let (engine, depth) = (self.engine.as_ref().expect("checked"), self.engine_depth.as_ref().expect("checked"));
        let none = f32::from_bits(u32::MAX); // RAY_NO_TRIANGLE in every channel
        begin_rendering(
            ctx,
            cmd,
            &Target {
                color: &[engine.view],
                depth: Some(depth.view),
                width: self.ray_texture.0,
                height: self.ray_texture.1,
                view_mask: 0,
                layer_count: 1,
                clear_color: [none; 4],
                clear: true,
            },
        );
        self.bind(ctx, cmd, vk::PipelineBindPoint::GRAPHICS, self.p.engine, f, sets);
        self.push_object(ctx, cmd, f, view, queue);
        let vertices = 6 * self.tiles.max(1);
        unsafe {
            ctx.device.cmd_draw(cmd, vertices, self.triangle_count, 0, 0);
            ctx.device.cmd_end_rendering(cmd);
        }
        rec.end(open);
        let engine = self.engine.as_mut().expect("checked");
        let open = rec.pass(name).after_buffer_writes().writes(engine, Access::ComputeStorage).begin();
        self.bind(ctx, cmd, vk::PipelineBindPoint::COMPUTE, self.p.engine_copy, f, sets);
        self.push_object(ctx, cmd, f, view, queue);
        unsafe { ctx.device.cmd_dispatch_indirect(cmd, self.dispatch.raw, at) };
        rec.end(open);
    }

    /// `kernel` over the queue at `rays_at` in a queue budget's modes (raytrace/trace.glsl):
    /// counted per weight bin, cut, the cut bin counted per sub-bin, cut, kept. `which`: 0
    /// the next ray queue's budget, 1 the shadow queue's.
    fn budgeted(
        &self,
        rec: &mut Recorder,
        f: &FrameInputs,
        sets: [vk::DescriptorSet; 2],
        (rays_at, view): (u64, u32),
        (kernel, which): (vk::Pipeline, u32),
    ) {
        let (ctx, cmd) = (rec.ctx, rec.cmd);
        let compute = vk::PipelineBindPoint::COMPUTE;
        for mode in 1..=3 {
            if mode > 1 {
                self.bind(ctx, cmd, compute, self.p.spawn_cutoff, f, sets);
                self.push_object(ctx, cmd, f, view, 2 * which + (mode - 2));
                unsafe { ctx.device.cmd_dispatch(cmd, 1, 1, 1) };
                Self::barrier(ctx, cmd);
            }
            self.bind(ctx, cmd, compute, kernel, f, sets);
            self.push_object(ctx, cmd, f, view, mode);
            unsafe { ctx.device.cmd_dispatch_indirect(cmd, self.dispatch.raw, rays_at) };
            Self::barrier(ctx, cmd);
        }
    }

    /// Compute writes before the next dispatch's reads (and its indirect arguments).
    fn barrier(ctx: &Context, cmd: vk::CommandBuffer) {
        let b = [vk::MemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::COMPUTE_SHADER)
            .src_access_mask(vk::AccessFlags2::SHADER_STORAGE_WRITE | vk::AccessFlags2::SHADER_STORAGE_READ)
            .dst_stage_mask(vk::PipelineStageFlags2::COMPUTE_SHADER | vk::PipelineStageFlags2::DRAW_INDIRECT)
            .dst_access_mask(
                vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::SHADER_STORAGE_WRITE | vk::AccessFlags2::INDIRECT_COMMAND_READ,
            )];
        unsafe { ctx.device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&b)) };
    }

    fn dispatch_indirect(
        &self,
        (ctx, cmd): (&Context, vk::CommandBuffer),
        pipeline: vk::Pipeline,
        f: &FrameInputs,
        sets: [vk::DescriptorSet; 2],
        offset: u64,
        view: u32,
    ) {
        self.bind(ctx, cmd, vk::PipelineBindPoint::COMPUTE, pipeline, f, sets);
        self.push(ctx, cmd, f, view);
        unsafe { ctx.device.cmd_dispatch_indirect(cmd, self.dispatch.raw, offset) };
    }
}

/// Secondary and shadow rays start this far from the surface they leave (besides skipping
/// its triangle): 10⁻⁶ of the scene's diagonal, far above f32 rounding of positions of
/// the scene's size at any scale (1 mm or 1 km scenes alike).
fn list_offset(list: &TriangleList) -> f32 {
    let (lo, hi) = list.bounds();
    let diag = (hi - lo).length();
    if diag.is_finite() && diag > 0.0 {
        diag * 1e-6
    } else {
        1e-6
    }
}

impl RayTrace {
    /// The structure follows moved or deformed objects: a BVH by `bvh_update` (the new
    /// triangles written in place, then a refit or a linear BVH built on the GPU in the next
    /// frame, or the SAH tree built again on the CPU), every other scheme by its CPU build.
    fn follow(&mut self, ctx: &Context, scene: &crate::scene::Scene, list: &TriangleList, moved: &[usize]) -> Result<()> {
        let Scheme::Bvh { stackless, .. } = self.scheme else {
            let packed = self.scheme.build(list)?;
            return self.replace_structure(ctx, list, &packed);
        };
        let same_count = self.structure.as_ref().is_some_and(|s| s.accel.triangle_count as usize == list.len());
        let refit = same_count && !list.is_empty();
        // Only the moved meshes' shapes are hashed (a rebuild records every mesh's).
        let rigid = |m: usize| match (self.built_at.get(m), scene.meshes.get(m)) {
            (Some(&(w0, h0)), Some(mesh)) => turn(w0, mesh.world) < REFIT_TURN && shape_hash(mesh) == h0,
            _ => false,
        };
        let way = match self.bvh_update {
            BvhUpdate::Auto if refit && moved.iter().all(|&m| rigid(m)) => BvhUpdate::Refit,
            BvhUpdate::Auto if rebuild_on_gpu(self.update_costs.as_ref(), list.len(), self.cpu_device) => BvhUpdate::Lbvh,
            BvhUpdate::Auto => BvhUpdate::Sah,
            BvhUpdate::Refit if !refit => BvhUpdate::Sah,
            w => w,
        };
        match way {
            _ if list.is_empty() => self.build_on_cpu(ctx, list, stackless)?,
            BvhUpdate::Refit => {
                let structure = self.structure.as_mut().expect("same_count");
                structure.write_triangles(list)?;
                if self.gpu_bvh.is_none() {
                    self.gpu_bvh = Some(GpuBvh::refit_of(ctx, structure)?);
                }
                self.gpu_bvh.as_mut().expect("just set").request(Work::Refit)?;
                return Ok(());
            }
            BvhUpdate::Lbvh => {
                let linear = self.gpu_bvh.as_ref().is_some_and(|b| b.builds_linear());
                if linear && same_count {
                    self.structure.as_mut().expect("same_count").write_triangles(list)?;
                    let b = self.gpu_bvh.as_mut().expect("linear");
                    b.set_bounds(list);
                    b.request(Work::Build)?;
                } else {
                    // The first GPU build after a CPU-built tree (or a new triangle count):
                    // a structure of the linear BVH's size, built in the next frame.
                    self.scheme = Scheme::Bvh { stackless, gpu: true };
                    let packed = self.scheme.build(list)?;
                    self.replace_structure(ctx, list, &packed)?;
                    let s = self.structure.as_ref().expect("just set");
                    self.gpu_bvh = Some(GpuBvh::linear(ctx, s, list)?);
                }
            }
            _ => self.build_on_cpu(ctx, list, stackless)?,
        }
        if self.bvh_update == BvhUpdate::Auto {
            self.built_at = shapes_of(scene);
        }
        Ok(())
    }

    /// The SAH tree built again on the CPU.
    fn build_on_cpu(&mut self, ctx: &Context, list: &TriangleList, stackless: bool) -> Result<()> {
        self.scheme = Scheme::Bvh { stackless, gpu: false };
        let packed = self.scheme.build(list)?;
        self.replace_structure(ctx, list, &packed)
    }

    /// A fresh structure over `list` in place of the current one (and of its GPU builder),
    /// written into the ray sets.
    fn replace_structure(&mut self, ctx: &Context, list: &TriangleList, packed: &Packed) -> Result<()> {
        let fresh = Structure::new(ctx, self.scheme, list, packed)?;
        if let Some(mut old) = self.structure.replace(fresh) {
            old.destroy(ctx);
        }
        if let Some(mut b) = self.gpu_bvh.take() {
            b.destroy(ctx);
        }
        let structure = self.structure.as_ref().expect("just set");
        for &set in self.ray_sets.iter().chain(&self.shadow_sets) {
            structure.write(ctx, set);
        }
        Ok(())
    }
}

impl Stage for RayTrace {
    fn name(&self) -> &'static str {
        self.name
    }

    /// Moved objects: the structure follows the new triangles (`follow`: a BVH refitted or
    /// rebuilt on the GPU, or rebuilt on the CPU, by `bvh_update`; the other schemes rebuilt
    /// on the CPU, having no refit), the per-triangle shading is rewritten in place and the
    /// rays' start offset follows the scene's size. `raytrace.build_ms` is the CPU's part.
    fn update(&mut self, init: &StageInit, changes: &crate::scene::update::Changes, _maps: &mut crate::frame::stage::Maps) -> Result<()> {
        if changes.moved.is_empty() {
            return Ok(());
        }
        let ctx = init.ctx;
        let list = TriangleList::from_scene(init.scene);
        let start = std::time::Instant::now();
        self.follow(ctx, init.scene, &list, &changes.moved)?;
        self.build_ms = start.elapsed().as_secs_f64() * 1e3;
        // The ray queries' structures and the triangles' shading are the frame's: the
        // renderer updated them before the stages.
        let mut params = self.params.read()?.to_vec();
        let t_min = list_offset(&list);
        let size = std::mem::size_of::<GpuTraceParams>();
        for k in 0..=self.depth as usize {
            let at = k * self.stride as usize;
            let mut p: GpuTraceParams = bytemuck::pod_read_unaligned(&params[at..at + size]);
            p.t_min = t_min;
            params[at..at + size].copy_from_slice(bytemuck::bytes_of(&p));
        }
        self.params.write(&params)
    }

    fn record(&mut self, rec: &mut Recorder, f: &FrameInputs, io: &mut FrameIo) {
        let (ctx, cmd) = (rec.ctx, rec.cmd);
        let view = io.views.camera;
        let compute = vk::PipelineBindPoint::COMPUTE;
        if let Some(accel) = &self.accel {
            let mut accel = accel.borrow_mut();
            if self.tlas_every_frame {
                accel.touch();
            }
            accel.record(ctx, rec);
        }
        if let Some(b) = self.gpu_bvh.as_mut() {
            if self.tlas_every_frame && b.pending().is_none() {
                // map_updates=always: every frame pays what a move costs.
                let work = if b.builds_linear() { Work::Build } else { Work::Refit };
                let _ = b.request(work);
            }
            b.record(ctx, rec);
        }
        let (Some(vis), Some(vis_depth)) = (self.vis.as_mut(), self.vis_depth.as_mut()) else { return };

        // 1. Primary hits by rasterisation, then the first queue. The shading kernels shade
        // diffuse surfaces as every pass does (the caustics projected there, §6.3.3): what
        // diffuse shading samples is read by compute.
        let mut pass = rec.pass("raytrace.primary");
        for img in io.maps.shadow_reads() {
            pass = pass.reads(img, Access::ComputeSampled);
        }
        let open = pass.after_buffer_writes().writes(vis, Access::ColorAttachment).writes(vis_depth, Access::DepthAttachment).begin();
        unsafe {
            ctx.device.cmd_fill_buffer(cmd, self.counters.raw, 0, vk::WHOLE_SIZE, 0);
            ctx.device.cmd_fill_buffer(cmd, self.accum.raw, 0, vk::WHOLE_SIZE, 0);
            ctx.device.cmd_fill_buffer(cmd, self.spawn_budget.raw, 0, vk::WHOLE_SIZE, 0);
            if self.cull_stats.size > 0 {
                ctx.device.cmd_fill_buffer(cmd, self.cull_stats.raw, 0, vk::WHOLE_SIZE, 0);
            }
        }
        let none = f32::from_bits(u32::MAX); // clears the R32_UINT ids to RAY_NO_TRIANGLE
                                             // One raster pass per sample, the projection shifted by the sample's offset from the
                                             // pixel centre (primary.vert), into layer s.
        let layer_views: Vec<vk::ImageView> = (0..self.samples).map(|s| vis.layer_view(s)).collect();
        let depth_view = vis_depth.view;
        for (s, &layer) in layer_views.iter().enumerate() {
            if s > 0 {
                if let Some(d) = self.vis_depth.as_mut() {
                    rec.barrier(d, Access::DepthAttachment);
                }
            }
            begin_rendering(
                ctx,
                cmd,
                &Target {
                    color: &[layer],
                    depth: Some(depth_view),
                    width: self.width,
                    height: self.height,
                    view_mask: 0,
                    layer_count: 1,
                    clear_color: [none; 4],
                    clear: true,
                },
            );
            self.bind(ctx, cmd, vk::PipelineBindPoint::GRAPHICS, self.p.primary_raster, f, [self.ray_sets[0], self.primary_set]);
            self.push_object(ctx, cmd, f, view, s as u32);
            unsafe {
                ctx.device.cmd_draw(cmd, 3 * self.triangle_count, 1, 0, 0);
                ctx.device.cmd_end_rendering(cmd);
            }
        }
        rec.end(open);
        let vis = self.vis.as_mut().expect("checked above");
        let open = rec.pass("raytrace.primary").after_buffer_writes().writes(vis, Access::ComputeStorage).begin();
        self.bind(ctx, cmd, compute, self.p.primary, f, [self.ray_sets[0], self.primary_set]);
        self.push(ctx, cmd, f, view);
        unsafe { ctx.device.cmd_dispatch(cmd, self.width.div_ceil(8), self.height.div_ceil(8), self.samples) };
        rec.end(open);

        // 2. The bounces.
        for k in 0..=self.depth as usize {
            let sets = [self.ray_sets[k], self.trace_sets[k]];
            let shadow_sets = [self.shadow_sets[k], self.trace_sets[k]];
            let rays_at = 32 * k as u64;
            let shadows_at = rays_at + 16;
            let open = rec.pass("raytrace.spawn").after_buffer_writes().begin();
            self.bind(ctx, cmd, compute, self.p.args, f, sets);
            self.push(ctx, cmd, f, view);
            unsafe { ctx.device.cmd_dispatch(cmd, 1, 1, 1) };
            rec.end(open);
            // Bounce 0's hits come from rasterisation; the intersection kernel only answers
            // the pixels whose raster triangle failed the exact test (RAY_HIT_KNOWN unset).
            self.intersect(rec, f, sets, rays_at, view, 0);
            let open = rec.pass("raytrace.shade").after_buffer_writes().begin();
            if self.shadow_capacity < self.capacity * self.lights {
                // The shadow queue may overflow: its queries go through their budget.
                self.budgeted(rec, f, sets, (rays_at, view), (self.p.shade, 1));
            } else {
                self.dispatch_indirect((ctx, cmd), self.p.shade, f, sets, rays_at, view);
            }
            rec.end(open);
            let open = rec.pass("raytrace.spawn").after_buffer_writes().begin();
            if k < self.depth as usize {
                // spawn.comp in the budget's modes (trace.glsl): which children a full queue
                // keeps does not depend on the order the GPU runs it in.
                self.budgeted(rec, f, sets, (rays_at, view), (self.p.spawn, 0));
            }
            // The shadow queries' count is known now.
            self.bind(ctx, cmd, compute, self.p.args, f, sets);
            unsafe { ctx.device.cmd_dispatch(cmd, 1, 1, 1) };
            rec.end(open);
            self.intersect(rec, f, shadow_sets, shadows_at, view, 1);
            let open = rec.pass("raytrace.shade").after_buffer_writes().begin();
            self.dispatch_indirect((ctx, cmd), self.p.shadow, f, shadow_sets, shadows_at, view);
            rec.end(open);
        }

        // 3. This stage's pixels into the frame's target.
        let open = rec
            .pass("raytrace.resolve")
            .after_buffer_writes()
            .writes(io.target, Access::ColorAttachment)
            .writes(io.depth, Access::DepthAttachment)
            .begin();
        begin_camera_rendering(ctx, cmd, io.target, io.depth, io.area, false);
        self.bind(ctx, cmd, vk::PipelineBindPoint::GRAPHICS, self.p.resolve, f, [self.ray_sets[0], self.trace_sets[0]]);
        self.push(ctx, cmd, f, view);
        unsafe {
            ctx.device.cmd_draw(cmd, 3, 1, 0, 0);
            ctx.device.cmd_end_rendering(cmd);
        }
        rec.end(open);
    }

    /// Rays each bounce's queue received (`raytrace.rays.bounceK`, with the shadow rays), the
    /// rays the budget dropped, and with `ray_stats=on` the ray hierarchy's culling rate per
    /// bounce (the fraction of tile × triangle pairs its cone test rejected).
    fn stats(&self, _ctx: &Context) -> Vec<(String, f64)> {
        let mut out = Vec::new();
        let Ok(words) = self.counters.read() else { return out };
        let word = |at: u64| words.get(at as usize..at as usize + 4).map_or(0, |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]])) as u64;
        let bounces = self.depth as u64 + 1;
        // The spawn budget of bounce k decides queue k + 1: its dropped children were rays
        // of bounce k + 1 too; the shadow budget of bounce k its shadow queue.
        let budget = self.spawn_budget.read().map(|b| b.to_vec()).unwrap_or_default();
        let size = std::mem::size_of::<GpuSpawnBudget>();
        let mut dropped = 0;
        let mut weights = [0.0; 2];
        // Entry 2k: bounce k's spawn budget, 2k + 1: its shadow budget; (rays, weight).
        let mut budget_dropped = |entry: u64| {
            let at = (entry * self.budget_stride) as usize;
            let Some(bytes) = budget.get(at..at + size) else { return 0 };
            let b: GpuSpawnBudget = bytemuck::pod_read_unaligned(bytes);
            let fixed = b.dropped_weight[0] as u64 | (b.dropped_weight[1] as u64) << 32;
            weights[(entry % 2) as usize] += fixed as f64 / (1u64 << 20) as f64;
            b.dropped as u64
        };
        for k in 0..bounces {
            let spawn_dropped = if k > 0 { budget_dropped(2 * (k - 1)) } else { 0 };
            let shadow_dropped = budget_dropped(2 * k + 1);
            let rays = word(k * self.stride) + spawn_dropped;
            let shadows = word((bounces + 1 + k) * self.stride) + shadow_dropped;
            dropped += spawn_dropped
                + shadow_dropped
                + word(k * self.stride).saturating_sub(self.capacity)
                + word((bounces + 1 + k) * self.stride).saturating_sub(self.shadow_capacity);
            out.push((format!("raytrace.rays.bounce{k}"), rays as f64));
            out.push((format!("raytrace.shadow_rays.bounce{k}"), shadows as f64));
        }
        // The dropped rays' path weights (largest channel; a camera ray weighs 1), and the
        // dropped shadow queries' (the light each would have added, largest channel).
        out.push(("raytrace.dropped_weight".to_string(), weights[0]));
        if weights[1] > 0.0 {
            out.push(("raytrace.dropped_shadow_weight".to_string(), weights[1]));
        }
        out.push(("raytrace.dropped_rays".to_string(), dropped as f64));
        out.push(("raytrace.build_ms".to_string(), self.build_ms));
        if let Some(b) = &self.gpu_bvh {
            out.push(("raytrace.gpu_builds".to_string(), b.builds as f64));
            out.push(("raytrace.gpu_refits".to_string(), b.refits as f64));
        }
        if let Some(a) = &self.accel {
            let a = a.borrow();
            out.push(("raytrace.blas_builds".to_string(), a.stats.blas_builds as f64));
            out.push(("raytrace.tlas_builds".to_string(), a.stats.tlas_builds as f64));
            out.push(("raytrace.blas_build_ms".to_string(), a.stats.blas_build_ms));
            out.push(("raytrace.accel_bytes".to_string(), a.stats.bytes as f64));
            out.push(("raytrace.compacted_bytes_saved".to_string(), a.stats.compacted_away as f64));
        }
        if let Ok(c) = self.cull_stats.read() {
            let w = |i: usize| c.get(4 * i..4 * i + 4).map_or(0, |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]])) as f64;
            for k in 0..bounces as usize {
                for (q, label) in [(0, "rays"), (1, "shadow_rays")] {
                    let (tested, kept) = (w(4 * k + 2 * q), w(4 * k + 2 * q + 1));
                    if tested > 0.0 {
                        out.push((format!("raytrace.cull_rate.bounce{k}.{label}"), 1.0 - kept / tested));
                    }
                }
            }
        }
        out
    }

    fn destroy(&mut self, ctx: &Context) {
        let p = &mut self.p;
        destroy_pipelines(
            ctx,
            &mut [
                p.primary_raster,
                p.primary,
                p.intersect,
                p.shade,
                p.spawn,
                p.spawn_cutoff,
                p.shadow,
                p.args,
                p.resolve,
                p.engine,
                p.engine_copy,
                p.cones,
                p.cull_stats,
            ],
        );
        self.p = Pipelines::default();
        if let Some(mut o) = self.order.take() {
            o.destroy(ctx);
        }
        crate::vk::pipeline::destroy_layouts(ctx, &mut self.layout, &mut self.pool, &mut self.set_layouts);
        self.rq_set = vk::DescriptorSet::null();
        if let Some(s) = self.structure.as_mut() {
            s.destroy(ctx);
        }
        // The frame's acceleration structures: the renderer destroys them.
        self.accel = None;
        if let Some(mut b) = self.gpu_bvh.take() {
            b.destroy(ctx);
        }
        self.structure = None;
        for q in self.queues.iter_mut().chain(self.shadow.iter_mut()) {
            q.destroy(ctx);
        }
        self.queues.clear();
        self.shadow = None;
        // The frame's triangle shading: the renderer destroys it.
        self.shading = None;
        for b in [
            &mut self.handled,
            &mut self.counters,
            &mut self.params,
            &mut self.spawn_budget,
            &mut self.dispatch,
            &mut self.accum,
            &mut self.cones,
            &mut self.cull_stats,
        ] {
            b.destroy(ctx);
        }
        for i in self.vis.iter_mut().chain(self.vis_depth.iter_mut()).chain(self.engine.iter_mut()).chain(self.engine_depth.iter_mut()) {
            i.destroy(ctx);
        }
        self.vis = None;
        self.vis_depth = None;
        self.engine = None;
        self.engine_depth = None;
    }
}

/// The GRADED_MEDIA variant of an intersection kernel (`file#VARIANT` names one variant:
/// a kernel's own variant gains the suffix, as intersect_octree.comp declares).
fn graded_variant(shader: &str) -> String {
    match shader.split_once('#') {
        Some((file, v)) => format!("{file}#{v}_GRADED_MEDIA"),
        None => format!("{shader}#GRADED_MEDIA"),
    }
}
