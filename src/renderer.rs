//! Runs a Plan: creates the stages the plan lists (and nothing else), records them in
//! order into a command buffer it is handed, and in standalone mode submits the frame and
//! reads the image back with its per-pass profile. It names no method: the plan's stages
//! come from the methods' descriptions (`methods::registry`), their passes from the
//! methods' folders and `frame`.

use ash::vk;
use glam::Mat4;

use crate::error::{Error, Result};
use crate::frame::camera::CameraShade;
use crate::frame::direct::{SceneDirect, DEPTH_FORMAT, TARGET_FORMAT};
use crate::frame::layout::{binding, BINDINGS, MAP_BINDINGS, MAP_SHADING_SKY};
use crate::frame::shadow::ShadowMaps;
use crate::frame::stage::{order, FrameIo, LayerField, MapSets, Maps, Stage, StageInit, ViewLayout};
use crate::frame::{output, views};
use crate::frame::{FrameInputs, SearchKnobs, FLAG_FRESNEL_EXACT, FLAG_HAS_ENVIRONMENT, PUSH_BYTES};
use crate::gpu_scene::{GpuLight, GpuObject, GpuScene, GpuView};
use crate::methods::geometry::views::MirrorViews;
use crate::plan::{Plan, StageSpec};
use crate::quality::FresnelMode;
use crate::scene::update::Changes;
use crate::scene::{Camera, Scene};
use crate::vk::pipeline::{
    allocate_set, descriptor_set_layout, pipeline_layout, sample_count_flags, sampler, write_buffer, write_image, Multisample,
};
use crate::vk::{
    record_copy_to_buffer, Access, Buffer, Context, Image, ImageData, ImageDesc, ImageKind, MemoryLocation, PassTiming, Profiler, Recorder,
};

/// Profiled passes a frame may record (ray tracing records about 7 per bounce).
const MAX_PASSES: u32 = 512;

/// A rendered frame: linear radiance RGBA32F, its per-pass profile and the device memory
/// that the renderer's resources hold.
#[derive(Clone, Debug)]
pub struct Frame {
    pub image: ImageData,
    pub passes: Vec<PassTiming>,
    pub memory: Vec<(String, u64)>,
    /// What the stages counted in this frame (`Stage::stats`).
    pub stats: Vec<(String, f64)>,
    /// The maps this frame regenerated, and why (a map not listed was kept).
    pub map_updates: Vec<MapUpdate>,
    /// With `object_ids=on` (a debug output): each pixel's first-hit object from the
    /// camera, mesh index + 1 (0: the sky), row by row from the top.
    pub object_ids: Option<Vec<u32>>,
}

/// A map stage the frame recorded, and why: its first frame, `map_updates=always`, or what
/// it depends on that changed.
#[derive(Clone, Debug, PartialEq)]
pub struct MapUpdate {
    pub stage: &'static str,
    pub reason: String,
}

/// What a stage's output depends on, so that a frame records it only when that changed.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Deps {
    /// The camera's view (direct light, camera passes, ray tracing): every frame.
    EveryFrame,
    /// Shadow maps: the geometry and the lights (not materials, not the camera).
    Shadows,
    /// Maps of the geometry alone (refractor maps): what moved.
    Geometry,
    /// Caustics (§6): the geometry, the lights and the generators' materials (the
    /// receivers' albedo is applied when they are shaded).
    Caustics,
    /// Maps around objects (environment, distance, refractor): everything they see, which
    /// is the whole scene's geometry, materials and lights, but not the camera.
    World,
    /// Maps from the camera (image-space refraction's back faces): camera and geometry.
    CameraMap,
}

impl Frame {
    pub fn gpu_ms(&self) -> f64 {
        self.passes.iter().map(|p| p.gpu_ms).sum()
    }
    pub fn memory_bytes(&self) -> u64 {
        self.memory.iter().map(|(_, b)| b).sum()
    }
}

/// A descriptor set with its own pool.
struct OwnedSet {
    pool: vk::DescriptorPool,
    set: vk::DescriptorSet,
}

pub struct Renderer {
    pub plan: Plan,
    pub width: u32,
    pub height: u32,
    scene: GpuScene,
    camera: Camera,
    views: ViewLayout,
    view_buffer: Buffer,
    objects: Buffer,
    lights: Option<Buffer>,
    set_layout: vk::DescriptorSetLayout,
    pool: vk::DescriptorPool,
    set: vk::DescriptorSet,
    layout: vk::PipelineLayout,
    linear_repeat: vk::Sampler,
    nearest_clamp: vk::Sampler,
    /// The plan's stages, in recording order.
    stages: Vec<Box<dyn Stage>>,
    /// The frame's shared maps (every stage's images), by descriptor slot.
    maps: Maps,
    maps_layout: vk::DescriptorSetLayout,
    /// Set-1 descriptor sets, each with its own pool.
    owned_sets: Vec<OwnedSet>,
    sets: MapSets,
    pub target: Image,
    depth: Image,
    readback: Option<Buffer>,
    profiler: Profiler,
    flags: u32,
    light_count: u32,
    light_table: Vec<GpuLight>,
    last_timings: Vec<PassTiming>,
    /// The scene the GPU holds (meshes, materials, lights, camera; no texels): what
    /// `update` compares a new state with.
    cpu: Scene,
    texture_count: usize,
    has_environment: bool,
    /// Changes taken by `update`, uploaded when the next frame is recorded.
    pending: Changes,
    /// Per stage, in `stages` order.
    deps: Vec<Deps>,
    /// Per stage: frames it still records after a change (inter-object cycles spread over
    /// frames by `frame_latency`).
    latency_left: Vec<u32>,
    first_frame: bool,
    /// The map stages the last recorded frame regenerated.
    map_updates: Vec<MapUpdate>,
    /// Each view's eye (the view table's), for per-face culling.
    view_eyes: Vec<glam::Vec3>,
    /// Supersampling per axis (`aa=ssaaN`): the camera passes render `ssaa`² samples per
    /// pixel into `target`, and `resolve` halves it down to the output size (2×2 box each
    /// step). Multisampling (`aa=msaaN`): `target` and `depth` hold `multisample.samples`
    /// samples per pixel, and `resolve` is the one image they are averaged into.
    ssaa: u32,
    multisample: Multisample,
    resolve: Vec<Image>,
    /// Planar mirrors' views (§5), when the plan has planar mirrors.
    mirrors: Option<MirrorViews>,
    /// `frame.object_ids`, with `object_ids=on`.
    ids: Option<crate::frame::ids::ObjectIds>,
}

/// The frame-wide part of what stages see, built once a frame; `io` adds one view's target.
struct FrameShared<'a> {
    plan: &'a Plan,
    sets: &'a MapSets,
    view_eyes: &'a [glam::Vec3],
    scene_images: Vec<&'a Image>,
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
        }
    }
}

/// The camera target's samples for the plan's `aa` (MSAA), checked against what the
/// device can render: the sample counts of the target's colour and depth formats, and
/// sample-rate shading (the per-sample passes, and the ray pipelines' one ray per sample).
fn camera_multisample(ctx: &Context, plan: &Plan) -> Result<Multisample> {
    let q = &plan.quality;
    let samples = q.frame.aa.msaa();
    if samples == 1 {
        return Ok(Multisample::OFF);
    }
    let name = format!("msaa{samples}");
    if ![2, 4, 8].contains(&samples) {
        return Err(Error::invalid("knob aa", format!("{name}: multisampling takes 2, 4 or 8 samples per pixel")));
    }
    let counts = |format: vk::Format, usage: vk::ImageUsageFlags| unsafe {
        ctx.instance
            .get_physical_device_image_format_properties(
                ctx.physical,
                format,
                vk::ImageType::TYPE_2D,
                vk::ImageTiling::OPTIMAL,
                usage,
                vk::ImageCreateFlags::empty(),
            )
            .map_or(vk::SampleCountFlags::TYPE_1, |p| p.sample_counts)
    };
    let colour = counts(TARGET_FORMAT, vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC);
    let depth = counts(DEPTH_FORMAT, vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT);
    let both =
        colour & depth & ctx.properties.limits.framebuffer_color_sample_counts & ctx.properties.limits.framebuffer_depth_sample_counts;
    if !both.contains(sample_count_flags(samples)) {
        let offered: Vec<String> =
            [2u32, 4, 8, 16].iter().filter(|&&n| both.contains(sample_count_flags(n))).map(|n| format!("msaa{n}")).collect();
        let offered = if offered.is_empty() { "none".to_string() } else { offered.join(", ") };
        return Err(Error::invalid(
            "knob aa",
            format!(
                "{name}: {} cannot render {TARGET_FORMAT:?} colour with {DEPTH_FORMAT:?} depth at {samples} samples per pixel (it offers: {offered}; ssaa2 and ssaa4 work everywhere)",
                ctx.device_name
            ),
        ));
    }
    if !ctx.sample_rate_shading {
        return Err(Error::invalid(
            "knob aa",
            format!(
                "{name} shades specular passes and ray-traced pixels per sample, which needs the device feature sampleRateShading: {} (ssaa2 and ssaa4 need nothing)",
                if ctx.queue.is_none() { "a host device does not tell whether it enabled it" } else { "this device lacks it" }
            ),
        ));
    }
    Ok(Multisample { samples, per_sample: q.frame.msaa_per_sample })
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
        let ssaa = plan.quality.frame.aa.ssaa();
        if ![1, 2, 4].contains(&ssaa) {
            return Err(Error::invalid("knob aa", format!("{ssaa} samples per axis: supersampling takes 1, 2 or 4")));
        }
        if width * ssaa > 16384 || height * ssaa > 16384 {
            return Err(Error::invalid("knob aa", format!("{width}x{height} with {ssaa}×{ssaa} samples exceeds 16384 per axis")));
        }
        let multisample = camera_multisample(ctx, &plan)?;
        // Partial construction: every field that owns something starts empty, and
        // `destroy` frees whatever exists.
        let r = Renderer {
            plan,
            width,
            height,
            scene: GpuScene::new(ctx, scene)?,
            camera,
            views: ViewLayout::default(),
            view_buffer: Buffer::placeholder(),
            objects: Buffer::placeholder(),
            lights: None,
            set_layout: vk::DescriptorSetLayout::null(),
            pool: vk::DescriptorPool::null(),
            set: vk::DescriptorSet::null(),
            layout: vk::PipelineLayout::null(),
            linear_repeat: vk::Sampler::null(),
            nearest_clamp: vk::Sampler::null(),
            stages: Vec::new(),
            maps: Maps::default(),
            maps_layout: vk::DescriptorSetLayout::null(),
            owned_sets: Vec::new(),
            sets: MapSets::default(),
            target: Image::placeholder(),
            depth: Image::placeholder(),
            readback: None,
            profiler: Profiler::placeholder(),
            flags: 0,
            light_count: 0,
            light_table: Vec::new(),
            last_timings: Vec::new(),
            cpu: geometry_of(scene),
            texture_count: scene.textures.len(),
            has_environment: scene.environment.is_some(),
            pending: Changes::default(),
            deps: Vec::new(),
            latency_left: Vec::new(),
            first_frame: true,
            map_updates: Vec::new(),
            view_eyes: Vec::new(),
            ssaa,
            multisample,
            resolve: Vec::new(),
            mirrors: None,
            ids: None,
        };
        crate::vk::build(ctx, r, |r| r.init(ctx, scene))
    }

    fn init(&mut self, ctx: &Context, scene: &Scene) -> Result<()> {
        let plan = &self.plan;
        self.views = ViewLayout::of(plan);
        self.view_buffer = Buffer::new(
            ctx,
            "frame.views",
            (self.views.count as usize * std::mem::size_of::<GpuView>()) as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryLocation::CpuToGpu,
        )?;

        self.objects = Buffer::with_data(ctx, "scene.objects", &object_table(scene, plan), vk::BufferUsageFlags::STORAGE_BUFFER)?;

        self.light_table = views::light_table(scene, &self.plan);
        self.light_count = self.light_table.len() as u32;
        if !self.light_table.is_empty() {
            self.lights = Some(Buffer::with_data(ctx, "scene.lights", &self.light_table, vk::BufferUsageFlags::STORAGE_BUFFER)?);
        }
        self.flags = if plan.quality.frame.fresnel == FresnelMode::Exact { FLAG_FRESNEL_EXACT } else { 0 }
            | if scene.environment.is_some() { FLAG_HAS_ENVIRONMENT } else { 0 }
            | if plan.quality.layered.layered_both { 0 } else { crate::frame::layout::FLAG_LAYERED_STRONGEST }
            | if plan.quality.frame.shadows { 0 } else { crate::frame::layout::FLAG_UNSHADOWED };

        let stages = vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT;
        // The sets are visible to compute too: the ray pipeline's kernels shade with them.
        let set_stages = stages | vk::ShaderStageFlags::COMPUTE;
        self.set_layout = descriptor_set_layout(ctx, "frame.set_layout", BINDINGS, set_stages)?;
        let (pool, set) = allocate_set(ctx, "frame.set", self.set_layout, BINDINGS)?;
        (self.pool, self.set) = (pool, set);
        self.maps_layout = descriptor_set_layout(ctx, "maps.set_layout", MAP_BINDINGS, set_stages)?;
        // Push constants reach compute too: the caustic triangles' set-up kernel reads them.
        self.layout = pipeline_layout(ctx, "frame.layout", &[self.set_layout, self.maps_layout], PUSH_BYTES, set_stages)?;
        self.linear_repeat = sampler(ctx, "sampler.linear_repeat", vk::Filter::LINEAR, vk::SamplerAddressMode::REPEAT)?;
        self.nearest_clamp = sampler(ctx, "sampler.nearest_clamp", vk::Filter::NEAREST, vk::SamplerAddressMode::CLAMP_TO_EDGE)?;

        self.create_stages(ctx, scene)?;
        // The maps' set-1 descriptor sets, as many as the maps need.
        for i in 0..self.maps.set_count() {
            let (pool, set) = allocate_set(ctx, &format!("maps.set{i}"), self.maps_layout, MAP_BINDINGS)?;
            self.owned_sets.push(OwnedSet { pool, set });
        }
        self.sets = self.maps.sets(&self.owned_sets.iter().map(|s| s.set).collect::<Vec<_>>());
        let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::SAMPLED;
        let (sw, sh) = (self.width * self.ssaa, self.height * self.ssaa);
        let samples = self.multisample.samples;
        let kind = if samples > 1 { ImageKind::D2Multisample { samples } } else { ImageKind::D2 };
        // A multisampled target is only resolved from, never sampled.
        let usage = if samples > 1 { usage & !vk::ImageUsageFlags::SAMPLED } else { usage };
        self.target = Image::new(ctx, &ImageDesc { name: "frame.color", format: TARGET_FORMAT, width: sw, height: sh, kind, usage })?;
        self.depth = Image::new(
            ctx,
            &ImageDesc {
                name: "frame.depth",
                format: DEPTH_FORMAT,
                width: sw,
                height: sh,
                kind,
                usage: vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
            },
        )?;
        if samples > 1 {
            let usage = vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::SAMPLED;
            let desc = ImageDesc { name: "frame.resolved", format: TARGET_FORMAT, width: sw, height: sh, kind: ImageKind::D2, usage };
            self.resolve.push(Image::new(ctx, &desc)?);
        }
        // Supersampling: halving steps down to the output size (linear 2:1 blits average
        // each 2×2 block exactly).
        if self.ssaa > 1 {
            let props = unsafe { ctx.instance.get_physical_device_format_properties(ctx.physical, TARGET_FORMAT) };
            let need =
                vk::FormatFeatureFlags::BLIT_SRC | vk::FormatFeatureFlags::BLIT_DST | vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR;
            if !props.optimal_tiling_features.contains(need) {
                return Err(Error::invalid("knob aa", format!("the device cannot blit {TARGET_FORMAT:?} with linear filtering")));
            }
            let mut f = self.ssaa;
            while f > 1 {
                f /= 2;
                let usage = vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::SAMPLED;
                let name = if f == 1 { "frame.resolved" } else { "frame.resolve_half" };
                let desc =
                    ImageDesc { name, format: TARGET_FORMAT, width: self.width * f, height: self.height * f, kind: ImageKind::D2, usage };
                self.resolve.push(Image::new(ctx, &desc)?);
            }
        }
        if self.plan.quality.frame.object_ids {
            self.ids = Some(crate::frame::ids::ObjectIds::new(ctx, self.layout, self.width, self.height)?);
        }
        self.mirrors = MirrorViews::new(ctx, &self.plan, (sw, sh), self.multisample, self.layout, &mut self.maps)?;
        // Each mirrored view records the camera's passes again (a ray pipeline is a hundred
        // passes at depth 16), and its copy.
        self.profiler = Profiler::new(ctx, MAX_PASSES * (1 + self.plan.mirror_layers))?;
        self.write_descriptors(ctx);
        Ok(())
    }

    /// Writes every binding; what the scene does not need gets a null descriptor.
    fn write_descriptors(&self, ctx: &Context) {
        let sb = vk::DescriptorType::STORAGE_BUFFER;
        let cis = vk::DescriptorType::COMBINED_IMAGE_SAMPLER;
        let ro = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        let buffer = |b: Option<&Buffer>| b.map_or(vk::Buffer::null(), |b| b.raw);
        let view = |i: Option<&Image>| i.map_or(vk::ImageView::null(), |i| i.view);
        write_buffer(ctx, self.set, binding::VIEWS, sb, self.view_buffer.raw);
        write_buffer(ctx, self.set, binding::MATERIALS, sb, self.scene.materials.raw);
        write_buffer(ctx, self.set, binding::OBJECTS, sb, self.objects.raw);
        write_buffer(ctx, self.set, binding::LIGHTS, sb, buffer(self.lights.as_ref()));
        write_image(ctx, self.set, binding::TEXTURES, 0, cis, view(self.scene.textures.as_ref()), self.linear_repeat, ro);
        write_image(ctx, self.set, binding::ENVIRONMENT_MAP, 0, cis, view(self.scene.environment.as_ref()), self.linear_repeat, ro);
        self.maps.write_descriptors(ctx, self.set, &self.sets, self.linear_repeat, self.nearest_clamp);
    }

    /// Creates the plan's stages in order; each map stage puts its images into `maps`.
    fn create_stages(&mut self, ctx: &Context, scene: &Scene) -> Result<()> {
        let init = StageInit {
            ctx,
            scene,
            gpu: &self.scene,
            plan: &self.plan,
            layout: self.layout,
            set_layouts: [self.set_layout, self.maps_layout],
            width: self.width * self.ssaa,
            height: self.height * self.ssaa,
            multisample: self.multisample,
        };
        for spec in &self.plan.stages {
            self.deps.push(match spec {
                StageSpec::Upload | StageSpec::Direct | StageSpec::Camera(_) | StageSpec::CausticsProject => Deps::EveryFrame,
                StageSpec::Shadows => Deps::Shadows,
                StageSpec::Map(m) if m.info.order == order::CAMERA_MAPS => Deps::CameraMap,
                StageSpec::Map(m) if m.info.order == order::GEOMETRY_MAPS => Deps::Geometry,
                StageSpec::Caustics => Deps::Caustics,
                StageSpec::Map(_) => Deps::World,
            });
            let stage: Box<dyn Stage> = match spec {
                // The scene records its own upload (first frame only).
                StageSpec::Upload => {
                    self.deps.pop();
                    continue;
                }
                StageSpec::Shadows => ShadowMaps::create(&init, &mut self.maps)?,
                StageSpec::Direct => Box::new(SceneDirect::new(ctx, self.layout, self.multisample)?),
                StageSpec::Map(m) => (m.info.create)(&init, &m.objects, &mut self.maps)?,
                StageSpec::Caustics => crate::methods::caustics::stage::CausticsStage::create(&init, &mut self.maps)?,
                StageSpec::CausticsProject => crate::methods::caustics::project::CausticsProject::create(&init)?,
                StageSpec::Camera(c) => match c.pass.create {
                    Some(create) => create(&init, c)?,
                    None => {
                        // The test knob debug_fault=flip_reflection breaks distance.search.
                        let mut c = c.clone();
                        if c.name == "distance.search" && self.plan.quality.frame.debug_fault == crate::quality::DebugFault::FlipReflection
                        {
                            c.objects.iter_mut().for_each(|(_, f)| *f |= crate::frame::layout::FLAG_DEBUG_FLIP_REFLECTION);
                        }
                        Box::new(CameraShade::new(ctx, self.layout, &c, self.multisample)?)
                    }
                },
            };
            self.stages.push(stage);
        }
        self.latency_left = vec![0; self.stages.len()];
        Ok(())
    }

    /// Takes the scene's new state for the next recorded frame: moved objects, changed
    /// materials, lights and camera (the scene's own setters validate each change:
    /// `Scene::set_object_transform`, `set_material`, `set_light`). The topology must be
    /// the renderer's (same objects, triangles, textures, material and light kinds), and the
    /// plan's structure must survive (each object keeps its method and maps; reference
    /// points and proxies follow the objects). Touches no GPU memory: the next `record`
    /// uploads the change in place, so a frame may still be in flight. On error nothing
    /// changes. Returns what changed.
    pub fn update(&mut self, scene: &Scene) -> Result<Changes> {
        scene.validate()?;
        if scene.textures.len() != self.texture_count || scene.environment.is_some() != self.has_environment {
            return Err(Error::invalid("scene update", "other textures or environment: make a new renderer"));
        }
        let new = geometry_of(scene);
        let c = Changes::between(&self.cpu, &new)?;
        if c.is_empty() {
            return Ok(c);
        }
        let mut plan = self.plan.clone();
        if !c.moved.is_empty() {
            plan.refresh_geometry(scene)?;
        }
        let camera = if c.camera { Some(scene.camera_or_default()) } else { None };
        if let Some(cam) = &camera {
            cam.validate()?;
        }
        self.plan = plan;
        self.cpu = new;
        if let Some(cam) = camera {
            self.camera = cam;
        }
        self.pending.merge(&c);
        Ok(c)
    }

    /// The map stages the last recorded frame regenerated, and why.
    pub fn map_updates(&self) -> &[MapUpdate] {
        &self.map_updates
    }

    /// Uploads the pending changes in place and decides which map stages this frame
    /// records. Called by `record`: every earlier frame has completed (the one-frame-in-
    /// flight rule), so the host-visible buffers are free to write.
    fn apply_updates(&mut self, ctx: &Context) -> Result<()> {
        // The changes stay pending until they are all in: a frame that fails half-way (a
        // structure rebuild out of memory) leaves them for the next one, which redoes them.
        let c = self.pending.clone();
        self.apply(ctx, &c)?;
        self.pending = Changes::default();
        Ok(())
    }

    fn apply(&mut self, ctx: &Context, c: &Changes) -> Result<()> {
        if !c.moved.is_empty() {
            for &i in &c.moved {
                let d = self.scene.draws[i];
                let v: Vec<crate::gpu_scene::Vertex> = crate::gpu_scene::vertices_of(&self.cpu.meshes[i]).collect();
                let at = d.vertex_offset as usize * std::mem::size_of::<crate::gpu_scene::Vertex>();
                self.scene.vertices.write_at(at, bytemuck::cast_slice(&v))?;
                let mesh = &self.cpu.meshes[i];
                let b = mesh.bounds();
                let draw = &mut self.scene.draws[i];
                (draw.lo, draw.hi) = (b.min, b.max);
                // A hidden object draws no triangle anywhere.
                draw.index_count = if mesh.hidden { 0 } else { mesh.indices.len() as u32 };
            }
            self.objects.write(bytemuck::cast_slice(&object_table(&self.cpu, &self.plan)))?;
        }
        if !c.materials.is_empty() {
            let m: Vec<_> = self.cpu.materials.iter().map(crate::gpu_scene::gpu_material).collect();
            self.scene.materials.write(bytemuck::cast_slice(&m))?;
        }
        if !c.moved.is_empty() || !c.lights.is_empty() {
            // A directional light's shadow projection covers the scene's bounds.
            self.light_table = views::light_table(&self.cpu, &self.plan);
            if let Some(l) = &mut self.lights {
                l.write(bytemuck::cast_slice(&self.light_table))?;
            }
        }
        if !c.is_empty() {
            let init = StageInit {
                ctx,
                scene: &self.cpu,
                gpu: &self.scene,
                plan: &self.plan,
                layout: self.layout,
                set_layouts: [self.set_layout, self.maps_layout],
                width: self.width * self.ssaa,
                height: self.height * self.ssaa,
                multisample: self.multisample,
            };
            for s in &mut self.stages {
                s.update(&init, c, &mut self.maps)?;
            }
            // A stage may have reallocated its maps (the layered maps' layer count).
            if !c.moved.is_empty() && self.maps.layered.is_some() {
                self.write_descriptors(ctx);
            }
        }
        self.map_updates.clear();
        let names = |ids: &[usize], name: &dyn Fn(usize) -> String| ids.iter().map(|&i| name(i)).collect::<Vec<_>>().join(", ");
        let moved = names(&c.moved, &|i| format!("'{}'", self.cpu.meshes[i].name));
        let materials = names(&c.materials, &|i| format!("'{}'", self.cpu.materials[i].name));
        let lights = names(&c.lights, &|i| format!("'{}'", self.cpu.lights[i].name));
        let q = &self.plan.quality;
        let generators: Vec<usize> =
            self.plan.caustics.as_ref().map_or_else(Vec::new, |p| p.generators.iter().map(|g| self.cpu.meshes[g.mesh].material).collect());
        let generator_materials = c.materials.iter().any(|m| generators.contains(m));
        for (i, deps) in self.deps.iter().enumerate() {
            let mut why = Vec::new();
            if self.first_frame {
                why.push("first frame".to_string());
            } else if q.frame.map_updates_always {
                why.push("map_updates=always".to_string());
            } else {
                let geometry = !c.moved.is_empty();
                let (g, m, l, cam) = match deps {
                    Deps::EveryFrame => continue,
                    Deps::Shadows => (geometry, false, !c.lights.is_empty(), false),
                    Deps::Geometry => (geometry, false, false, false),
                    Deps::Caustics => (geometry, generator_materials, !c.lights.is_empty(), false),
                    Deps::World => (geometry, !c.materials.is_empty(), !c.lights.is_empty(), false),
                    Deps::CameraMap => (geometry, false, false, c.camera),
                };
                if g {
                    why.push(format!("moved {moved}"));
                }
                if m {
                    why.push(format!("material {materials}"));
                }
                if l {
                    why.push(format!("light {lights}"));
                }
                if cam {
                    why.push("camera".to_string());
                }
            }
            if *deps == Deps::EveryFrame {
                continue;
            }
            if !why.is_empty() && self.plan.frame_latency && *deps == Deps::World {
                // One inter-object cycle per frame: the change needs `cycles` frames.
                self.latency_left[i] = q.distance.cycles.max(1);
            }
            if why.is_empty() && self.latency_left[i] > 0 {
                why.push(format!("frame latency: {} more cycle(s)", self.latency_left[i]));
            }
            self.latency_left[i] = self.latency_left[i].saturating_sub(1);
            if !why.is_empty() {
                self.map_updates.push(MapUpdate { stage: self.stages[i].name(), reason: why.join("; ") });
            }
        }
        self.first_frame = false;
        Ok(())
    }

    /// Replaces the camera (the output size's aspect ratio still wins).
    pub fn set_camera(&mut self, camera: Camera) -> Result<()> {
        camera.validate()?;
        if camera != self.camera {
            self.pending.camera = true;
        }
        self.camera = camera;
        self.cpu.camera = Some(camera);
        Ok(())
    }

    /// The environment- or distance-map cube array the camera passes read (one cube per
    /// object of that map), if planned.
    pub fn envmaps(&self) -> Option<&Image> {
        self.maps.distance.get(self.maps.distance_latest).or(self.maps.radiance.as_ref())
    }

    /// Image-space refraction's back-face map (xyz normal, w distance from the eye).
    pub fn backface_map(&self) -> Option<&Image> {
        self.maps.backfaces.as_ref()
    }

    /// The refractor maps' cube array (one cube per refractor), if planned.
    pub fn refractor_maps(&self) -> Option<&Image> {
        self.maps.refractor.as_ref()
    }

    /// Caustics (§6): the light cube maps (radiant intensity seen from each generator's
    /// reference point, one cube per generator, after filtering), if planned.
    pub fn caustic_maps(&self) -> Option<&Image> {
        self.maps.caustic_maps.as_ref()
    }

    /// Caustics: the receiver distance cubes, one per generator.
    pub fn caustic_distances(&self) -> Option<&Image> {
        self.maps.caustic_distances.as_ref()
    }

    /// Caustics: the photon hit location images (xyz hit relative to the reference point,
    /// w 1 for a photon) and the photons' power, one layer per light view.
    pub fn photon_images(&self) -> Option<(&Image, &Image)> {
        self.maps.photon_hits.as_ref().zip(self.maps.photon_power.as_ref())
    }

    /// The shadow cube array (one cube per `plan.shadow_cubes` entry), if planned.
    pub fn shadow_cubes(&self) -> Option<&Image> {
        self.maps.shadow_cubes.as_ref()
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

    fn write_views(&mut self) -> Result<()> {
        let vp = self.camera_view_proj();
        let cos_corner = crate::methods::geometry::views::cos_corner(self.camera.yfov, self.width as f32 / self.height as f32);
        if let Some(m) = self.mirrors.as_mut() {
            m.plan_frame(&self.cpu, vp, self.camera.position, cos_corner);
        }
        let mirror_views = self.mirrors.as_ref().map_or(&[][..], |m| &m.frame.views[..]);
        let photons = self.plan.caustics.as_ref().map_or_else(Vec::new, |c| {
            crate::methods::caustics::photon_views(c, &self.cpu, &self.light_table, &self.plan.quality, self.plan.cube_near)
        });
        let views =
            views::view_table(&self.plan, &self.views, &self.light_table, (vp, self.camera.position), mirror_views, &photons, &self.cpu);
        self.view_eyes = views.iter().map(|v| glam::Vec3::from_slice(&v.eye[..3])).collect();
        self.view_buffer.write(bytemuck::cast_slice(&views))
    }

    /// Records one frame into `cmd` (any primary command buffer in the recording state on
    /// this context's device). Afterwards `target` holds the image in COLOR_ATTACHMENT
    /// layout. The view table is written by the host now, so only one frame may be in
    /// flight at a time.
    pub fn record(&mut self, ctx: &Context, cmd: vk::CommandBuffer) -> Result<()> {
        self.apply_updates(ctx)?;
        self.write_views()?;
        let mut rec = Recorder::new(ctx, cmd, &mut self.profiler);
        self.scene.record_upload(&mut rec);
        let q = &self.plan.quality;
        let f = FrameInputs {
            scene: &self.scene,
            set: self.set,
            layout: self.layout,
            flags: self.flags,
            light_count: self.light_count,
            search: SearchKnobs::of(q),
            tolerance: q.search.search_tolerance,
            internal_bounces: q.distance.internal_bounces,
            depth: q.frame.depth,
            mirror_base: self.views.mirrors,
        };
        let full =
            vk::Rect2D { offset: vk::Offset2D::default(), extent: vk::Extent2D { width: self.target.width, height: self.target.height } };
        // The camera-dependent stages: camera-space maps, direct light and camera passes.
        let per_view = |d: &Deps| matches!(d, Deps::EveryFrame | Deps::CameraMap);
        let shared = FrameShared {
            plan: &self.plan,
            sets: &self.sets,
            view_eyes: &self.view_eyes,
            scene_images: f.scene.textures.iter().chain(f.scene.environment.iter()).collect(),
        };
        let mut io = shared.io(&self.views, &mut self.target, &mut self.depth, &mut self.maps, full, &[]);
        // The world's maps first.
        for (stage, deps) in self.stages.iter_mut().zip(&self.deps) {
            if per_view(deps) || !self.map_updates.iter().any(|u| u.stage == stage.name()) {
                continue; // camera-dependent, or its maps still hold what this frame would draw
            }
            stage.record(&mut rec, &f, &mut io);
        }
        drop(io);
        // Planar mirrors' views (§5), deepest first: each renders the camera-dependent stages
        // from its mirrored camera into the scratch target, within its mirror's pixels, and
        // is stored in its layer for the views (and the camera) that see the mirror.
        if let Some(mv) = self.mirrors.as_mut() {
            rec.scope = Some("geometry.mirror_view");
            for i in mv.frame.order() {
                let v = mv.frame.views[i].clone();
                let views = ViewLayout { camera: self.views.mirrors + i as u32, ..self.views.clone() };
                let flags = mv.child_flags(Some(i));
                let area = crate::methods::geometry::views::render_area(v.rect);
                // geometry.stencil: the mirror's pixels (as its parent sees them) marked in the
                // scratch depth; the view's passes draw there only. With MSAA the view renders
                // its whole rectangle: an edge pixel of the mirror averages samples beyond it.
                let masked = self.multisample.samples == 1;
                if masked {
                    let parent_view = v.parent.map_or(self.views.camera, |p| self.views.mirrors + p as u32);
                    let mesh = mv.frame.mirrors[v.mirror].mesh;
                    mv.record_stencil(&mut rec, &f, parent_view, mesh, area);
                }
                let mut io = shared.io(&views, &mut mv.scratch, &mut mv.depth, &mut self.maps, area, &flags);
                io.depth_masked = masked;
                for (stage, _) in self.stages.iter_mut().zip(&self.deps).filter(|(_, d)| per_view(d)) {
                    stage.record(&mut rec, &f, &mut io);
                }
                drop(io);
                if let Some(dst) = self.maps.mirror_views.as_mut() {
                    mv.record_store(&mut rec, dst, v.layer, v.rect);
                }
            }
            rec.scope = None;
        }
        let camera_flags = self.mirrors.as_ref().map_or_else(Vec::new, |m| m.child_flags(None));
        let mut io = shared.io(&self.views, &mut self.target, &mut self.depth, &mut self.maps, full, &camera_flags);
        // Mirrored views re-recorded the camera-space maps from their cameras.
        let views_ran = self.mirrors.as_ref().is_some_and(|m| !m.frame.views.is_empty());
        for (stage, deps) in self.stages.iter_mut().zip(&self.deps) {
            let needed = *deps == Deps::EveryFrame || views_ran || self.map_updates.iter().any(|u| u.stage == stage.name());
            if per_view(deps) && needed {
                stage.record(&mut rec, &f, &mut io);
            }
        }
        drop(io);
        if self.multisample.samples > 1 {
            // Multisampling: the samples' average (vkCmdResolveImage on a float format).
            let dst = &mut self.resolve[0];
            let open = rec.pass("frame.resolve").reads(&self.target, Access::TransferSrc).writes(dst, Access::TransferDst).begin();
            let layers =
                vk::ImageSubresourceLayers { aspect_mask: vk::ImageAspectFlags::COLOR, mip_level: 0, base_array_layer: 0, layer_count: 1 };
            let region = vk::ImageResolve {
                src_subresource: layers,
                src_offset: vk::Offset3D::default(),
                dst_subresource: layers,
                dst_offset: vk::Offset3D::default(),
                extent: vk::Extent3D { width: dst.width, height: dst.height, depth: 1 },
            };
            let (s, d) = (vk::ImageLayout::TRANSFER_SRC_OPTIMAL, vk::ImageLayout::TRANSFER_DST_OPTIMAL);
            unsafe { ctx.device.cmd_resolve_image(cmd, self.target.raw, s, dst.raw, d, &[region]) };
            rec.end(open);
        }
        // Supersampling: 2×2 box steps down to the output size (with MSAA `resolve` holds
        // the multisample resolve's one image instead).
        let blits = if self.ssaa > 1 { self.resolve.len() } else { 0 };
        for i in 0..blits {
            let (done, rest) = self.resolve.split_at_mut(i);
            let src = done.last_mut().unwrap_or(&mut self.target);
            let dst = &mut rest[0];
            let open = rec.pass("frame.resolve").reads(src, Access::TransferSrc).writes(dst, Access::TransferDst).begin();
            let layers =
                vk::ImageSubresourceLayers { aspect_mask: vk::ImageAspectFlags::COLOR, mip_level: 0, base_array_layer: 0, layer_count: 1 };
            let corner = |i: &Image| vk::Offset3D { x: i.width as i32, y: i.height as i32, z: 1 };
            let region = vk::ImageBlit {
                src_subresource: layers,
                src_offsets: [vk::Offset3D::default(), corner(src)],
                dst_subresource: layers,
                dst_offsets: [vk::Offset3D::default(), corner(dst)],
            };
            let (s, d) = (vk::ImageLayout::TRANSFER_SRC_OPTIMAL, vk::ImageLayout::TRANSFER_DST_OPTIMAL);
            unsafe { ctx.device.cmd_blit_image(cmd, src.raw, s, dst.raw, d, &[region], vk::Filter::LINEAR) };
            rec.end(open);
        }
        if let Some(ids) = self.ids.as_mut() {
            ids.record(&mut rec, &f, self.views.camera);
        }
        if let Some(rb) = &self.readback {
            let out = self.resolve.last().unwrap_or(&self.target);
            let open = rec.pass("frame.readback").reads(out, Access::TransferSrc).begin();
            record_copy_to_buffer(ctx, cmd, out, rb);
            rec.end(open);
        }
        Ok(())
    }

    /// Host-device mode: records a frame into the host's `cmd` and copies the result into
    /// the host's image (same size; a bit-exact copy for R32G32B32A32_SFLOAT, a blit with
    /// format conversion otherwise), leaving it in `final_layout`.
    pub fn record_into(&mut self, ctx: &Context, cmd: vk::CommandBuffer, host: &mut Image, final_layout: vk::ImageLayout) -> Result<()> {
        if host.width != self.width || host.height != self.height {
            return Err(Error::invalid(
                "target image",
                format!("{}x{} but the renderer was configured for {}x{}", host.width, host.height, self.width, self.height),
            ));
        }
        // The previous frame's timings, if the host has let it complete.
        if let Some(t) = self.profiler.poll(ctx)? {
            self.last_timings = t;
            self.scene.release_staging(ctx);
        }
        self.record(ctx, cmd)?;
        let mut rec = Recorder::resume(ctx, cmd, &mut self.profiler);
        output::record_copy(&mut rec, self.resolve.last().unwrap_or(&self.target), host, final_layout);
        Ok(())
    }

    /// Per-pass timings of the last frame the GPU has completed (host-device mode polls
    /// without waiting; standalone frames are always complete).
    pub fn last_timings(&mut self, ctx: &Context) -> Result<&[PassTiming]> {
        if let Some(t) = self.profiler.poll(ctx)? {
            self.last_timings = t;
        }
        Ok(&self.last_timings)
    }

    /// Standalone: records, submits and waits for one frame, then reads the image back.
    pub fn render(&mut self, ctx: &Context) -> Result<Frame> {
        if self.readback.is_none() {
            self.readback = Some(Buffer::new(
                ctx,
                "frame.readback",
                self.resolve.last().unwrap_or(&self.target).byte_size(),
                vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuToCpu,
            )?);
        }
        ctx.one_shot(|cmd| self.record(ctx, cmd))?;
        self.scene.release_staging(ctx);
        let passes = self.profiler.results(ctx)?;
        self.last_timings = passes.clone();
        let rb = self.readback.as_ref().unwrap();
        let image = crate::vk::decode(TARGET_FORMAT, self.width, self.height, 1, rb.read()?)?;
        let errors = ctx.validation.error_count();
        if errors > 0 {
            return Err(Error::Validation(errors));
        }
        let mut stats: Vec<(String, f64)> = self.stages.iter().flat_map(|s| s.stats(ctx)).collect();
        if self.profiler.untimed() > 0 {
            stats.push(("profiler.untimed_passes".into(), self.profiler.untimed() as f64));
        }
        if let Some(m) = &self.mirrors {
            // Planar mirrors (§5): the views this frame rendered, their deepest level, and
            // the mirrors that showed the fallback for want of depth or budget.
            let f = &m.frame;
            stats.push(("geometry.mirror_views".into(), f.views.len() as f64));
            stats.push(("geometry.mirror_depth".into(), f.views.iter().map(|v| v.level).max().unwrap_or(0) as f64));
            stats.push(("geometry.mirror_fallbacks".into(), f.fallbacks as f64));
            // Memory (issue 11): the layers allocated for the plan's views, the bytes of one
            // view's layer, and the scratch target every view renders into (colour + depth).
            let (layers, view, scratch) = m.memory();
            stats.push(("geometry.mirror_layers".into(), layers as f64));
            stats.push(("geometry.mirror_view_bytes".into(), view as f64));
            stats.push(("geometry.mirror_scratch_bytes".into(), scratch as f64));
        }
        let object_ids = self.ids.as_ref().map(|i| i.read()).transpose()?;
        Ok(Frame { image, passes, memory: ctx.memory.snapshot(), stats, map_updates: self.map_updates.clone(), object_ids })
    }

    /// Frees everything. The GPU must be idle with respect to this renderer's frames.
    pub fn destroy(&mut self, ctx: &Context) {
        for s in &mut self.stages {
            s.destroy(ctx);
        }
        self.stages.clear();
        if let Some(m) = self.mirrors.as_mut() {
            m.destroy(ctx);
        }
        self.mirrors = None;
        if let Some(mut i) = self.ids.take() {
            crate::vk::Owner::destroy(&mut i, ctx);
        }
        self.maps.destroy(ctx);
        self.target.destroy(ctx);
        self.depth.destroy(ctx);
        for i in &mut self.resolve {
            i.destroy(ctx);
        }
        self.resolve.clear();
        for b in [Some(&mut self.view_buffer), Some(&mut self.objects), self.lights.as_mut(), self.readback.as_mut()].into_iter().flatten()
        {
            b.destroy(ctx);
        }
        self.scene.destroy(ctx);
        self.profiler.destroy(ctx);
        unsafe {
            let d = &ctx.device;
            if self.layout != vk::PipelineLayout::null() {
                d.destroy_pipeline_layout(self.layout, None);
            }
            if self.pool != vk::DescriptorPool::null() {
                d.destroy_descriptor_pool(self.pool, None);
            }
            if self.set_layout != vk::DescriptorSetLayout::null() {
                d.destroy_descriptor_set_layout(self.set_layout, None);
            }
            for s in self.owned_sets.drain(..) {
                d.destroy_descriptor_pool(s.pool, None);
            }
            if self.maps_layout != vk::DescriptorSetLayout::null() {
                d.destroy_descriptor_set_layout(self.maps_layout, None);
            }
            for s in [self.linear_repeat, self.nearest_clamp] {
                if s != vk::Sampler::null() {
                    d.destroy_sampler(s, None);
                }
            }
        }
        self.layout = vk::PipelineLayout::null();
        self.pool = vk::DescriptorPool::null();
        self.set_layout = vk::DescriptorSetLayout::null();
        self.maps_layout = vk::DescriptorSetLayout::null();
        self.sets = MapSets::default();
        self.linear_repeat = vk::Sampler::null();
        self.nearest_clamp = vk::Sampler::null();
    }
}

impl crate::vk::Owner for Renderer {
    fn destroy(&mut self, ctx: &Context) {
        Renderer::destroy(self, ctx)
    }
}

/// The scene without its texels and environment: what the renderer keeps to compare
/// updates with and to hand its stages.
fn geometry_of(scene: &Scene) -> Scene {
    Scene {
        meshes: scene.meshes.clone(),
        materials: scene.materials.clone(),
        lights: scene.lights.clone(),
        camera: scene.camera,
        textures: Vec::new(),
        environment: None,
        skipped: Vec::new(),
        animation: None,
    }
}

/// The object table (`scene.objects`): per mesh its material, reference point and proxy,
/// how it shows in maps, and its layer in each map array.
fn object_table(scene: &Scene, plan: &Plan) -> Vec<GpuObject> {
    let mut objects: Vec<GpuObject> = scene
        .meshes
        .iter()
        .map(|m| GpuObject {
            material: m.material as u32,
            envmap_layer: -1,
            refractor_layer: -1,
            map_shading: MAP_SHADING_SKY,
            reference_point: [0.0; 4],
            map_centre: [0.0; 4],
            proxy_min: plan.proxy_box.0.extend(0.0).to_array(),
            proxy_max: plan.proxy_box.1.extend(0.0).to_array(),
        })
        .collect();
    for o in &plan.objects {
        let g = &mut objects[o.mesh];
        g.reference_point = o.own_reference_point.extend(plan.proxy_radius).to_array();
        g.map_centre = o.reference_point.extend(0.0).to_array();
        g.map_shading = o.map_shading.code();
        // The object's layer in each map array, by the slot the map fills.
        for m in &o.maps {
            match m.layer_field {
                Some(LayerField::Envmap) => g.envmap_layer = m.layer as i32,
                Some(LayerField::Refractor) => g.refractor_layer = m.layer as i32,
                None => {}
            }
        }
    }
    objects
}
