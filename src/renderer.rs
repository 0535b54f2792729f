//! Runs a Plan: creates every resource the plan names (and nothing else), records a frame
//! into a command buffer it is handed, and in standalone mode submits it and reads the
//! image back with the frame's per-pass profile.

use ash::vk;
use glam::{Mat4, Vec3, Vec4};

use crate::cube::face_view_proj;
use crate::error::{Error, Result};
use crate::gpu_scene::{light_kind_code, GpuLight, GpuObject, GpuScene, GpuView};
use crate::methods::direct::{SceneDirect, DEPTH_FORMAT, TARGET_FORMAT};
use crate::methods::envmap::{CubeMaps, MapKind};
use crate::methods::image_space::Backfaces;
use crate::methods::refractor::RefractorMaps;
use crate::methods::shade::SpecularShade;
use crate::methods::shadow::ShadowMaps;
use crate::methods::{FrameInputs, FLAG_FRESNEL_EXACT, FLAG_HAS_ENVIRONMENT, FLAG_PROXY_BOX, PUSH_BYTES};
use crate::plan::{Method, Plan};
use crate::quality::FresnelMode;
use crate::scene::{Camera, LightKind, Scene};
use crate::vk::pipeline::{allocate_set, descriptor_set_layout, pipeline_layout, sampler, write_buffer, write_image, Binding};
use crate::vk::{
    record_copy_to_buffer, Access, Buffer, Context, Image, ImageData, ImageDesc, ImageKind, MemoryLocation, PassTiming, Profiler, Recorder,
};

const MAX_PASSES: u32 = 32;

/// The frame descriptor set's bindings (glsl/common/scene.glsl).
const BINDINGS: &[Binding] = &[
    (0, vk::DescriptorType::STORAGE_BUFFER, 1),
    (1, vk::DescriptorType::STORAGE_BUFFER, 1),
    (2, vk::DescriptorType::STORAGE_BUFFER, 1),
    (3, vk::DescriptorType::STORAGE_BUFFER, 1),
    (4, vk::DescriptorType::COMBINED_IMAGE_SAMPLER, 1),
    (5, vk::DescriptorType::COMBINED_IMAGE_SAMPLER, 1),
    (6, vk::DescriptorType::COMBINED_IMAGE_SAMPLER, 1),
    (7, vk::DescriptorType::COMBINED_IMAGE_SAMPLER, 1),
    (8, vk::DescriptorType::COMBINED_IMAGE_SAMPLER, 1),
];

/// The maps set's bindings (set 1 in glsl/common/scene.glsl and image_space/refract.vert).
const MAP_BINDINGS: &[Binding] = &[
    (0, vk::DescriptorType::COMBINED_IMAGE_SAMPLER, 1),
    (1, vk::DescriptorType::COMBINED_IMAGE_SAMPLER, 1),
    (2, vk::DescriptorType::COMBINED_IMAGE_SAMPLER, 1),
    (3, vk::DescriptorType::STORAGE_BUFFER, 1),
];

/// A rendered frame: linear radiance RGBA32F, its per-pass profile and the device memory
/// that the renderer's resources hold.
#[derive(Clone, Debug)]
pub struct Frame {
    pub image: ImageData,
    pub passes: Vec<PassTiming>,
    pub memory: Vec<(String, u64)>,
}

impl Frame {
    pub fn gpu_ms(&self) -> f64 {
        self.passes.iter().map(|p| p.gpu_ms).sum()
    }
    pub fn memory_bytes(&self) -> u64 {
        self.memory.iter().map(|(_, b)| b).sum()
    }
}

/// Indices into the frame's view table.
#[derive(Clone, Debug, Default)]
struct ViewLayout {
    camera: u32,
    shadow_cubes: Vec<u32>,
    shadow_planes: Vec<u32>,
    envmaps: Vec<u32>,
    count: u32,
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
    shadows: ShadowMaps,
    cube_maps: Option<CubeMaps>,
    refractor_maps: Option<RefractorMaps>,
    backfaces: Option<Backfaces>,
    /// The method's camera passes: the one for specular objects in general, and the
    /// self-refraction one for solid dielectrics (refractor-map, image-space).
    shade: Option<SpecularShade>,
    self_refraction: Option<SpecularShade>,
    maps_layout: vk::DescriptorSetLayout,
    /// `maps_sets[i]` samples `cube_maps.maps[i]`; the last one holds null maps.
    maps_sets: Vec<OwnedSet>,
    direct: Option<SceneDirect>,
    pub target: Image,
    depth: Image,
    readback: Option<Buffer>,
    profiler: Profiler,
    flags: u32,
    light_count: u32,
    light_table: Vec<GpuLight>,
    last_timings: Vec<PassTiming>,
}

impl Renderer {
    /// Creates everything the plan needs at `width`×`height`. On error, everything created
    /// so far is destroyed again.
    pub fn new(ctx: &Context, scene: &Scene, plan: Plan, width: u32, height: u32) -> Result<Renderer> {
        if !plan.method.is_gpu() {
            return Err(Error::invalid("method", format!("'{}' renders on the CPU: use reference::render_reference", plan.method.name())));
        }
        if width == 0 || height == 0 || width > 16384 || height > 16384 {
            return Err(Error::invalid("size", format!("{width}x{height} is outside 1..=16384")));
        }
        let camera = scene.camera_or_default();
        camera.validate()?;
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
            shadows: ShadowMaps::default(),
            cube_maps: None,
            refractor_maps: None,
            backfaces: None,
            shade: None,
            self_refraction: None,
            maps_layout: vk::DescriptorSetLayout::null(),
            maps_sets: Vec::new(),
            direct: None,
            target: Image::placeholder(),
            depth: Image::placeholder(),
            readback: None,
            profiler: Profiler::placeholder(),
            flags: 0,
            light_count: 0,
            light_table: Vec::new(),
            last_timings: Vec::new(),
        };
        crate::vk::build(ctx, r, |r| r.init(ctx, scene))
    }

    fn init(&mut self, ctx: &Context, scene: &Scene) -> Result<()> {
        let plan = &self.plan;
        // The view table: camera, shadow cube faces, shadow planes, environment-map faces.
        let mut v = ViewLayout { camera: 0, count: 1, ..Default::default() };
        for _ in &plan.shadow_cubes {
            v.shadow_cubes.push(v.count);
            v.count += 6;
        }
        for _ in &plan.shadow_planes {
            v.shadow_planes.push(v.count);
            v.count += 1;
        }
        for _ in &plan.envmaps {
            v.envmaps.push(v.count);
            v.count += 6;
        }
        self.views = v;
        self.view_buffer = Buffer::new(
            ctx,
            "frame.views",
            (self.views.count as usize * std::mem::size_of::<GpuView>()) as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryLocation::CpuToGpu,
        )?;

        let mut objects: Vec<GpuObject> = scene
            .meshes
            .iter()
            .map(|m| GpuObject {
                material: m.material as u32,
                envmap_layer: -1,
                refractor_layer: -1,
                pad: 0,
                reference_point: [0.0; 4],
                proxy_min: plan.proxy_box.0.extend(0.0).to_array(),
                proxy_max: plan.proxy_box.1.extend(0.0).to_array(),
            })
            .collect();
        for e in &plan.envmaps {
            objects[e.mesh].envmap_layer = e.layer as i32;
            objects[e.mesh].reference_point = e.reference_point.extend(plan.proxy_radius).to_array();
        }
        for (k, &m) in plan.refractors.iter().enumerate() {
            objects[m].refractor_layer = k as i32;
        }
        self.objects = Buffer::with_data(ctx, "scene.objects", &objects, vk::BufferUsageFlags::STORAGE_BUFFER)?;

        self.light_table = self.light_table(scene);
        self.light_count = self.light_table.len() as u32;
        if !self.light_table.is_empty() {
            self.lights = Some(Buffer::with_data(ctx, "scene.lights", &self.light_table, vk::BufferUsageFlags::STORAGE_BUFFER)?);
        }
        self.flags = if plan.quality.fresnel == FresnelMode::Exact { FLAG_FRESNEL_EXACT } else { 0 }
            | if scene.environment.is_some() { FLAG_HAS_ENVIRONMENT } else { 0 };

        let stages = vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT;
        self.set_layout = descriptor_set_layout(ctx, "frame.set_layout", BINDINGS, stages)?;
        let (pool, set) = allocate_set(ctx, "frame.set", self.set_layout, BINDINGS)?;
        (self.pool, self.set) = (pool, set);
        self.maps_layout = descriptor_set_layout(ctx, "maps.set_layout", MAP_BINDINGS, stages)?;
        self.layout = pipeline_layout(ctx, "frame.layout", &[self.set_layout, self.maps_layout], PUSH_BYTES, stages)?;
        self.linear_repeat = sampler(ctx, "sampler.linear_repeat", vk::Filter::LINEAR, vk::SamplerAddressMode::REPEAT)?;
        self.nearest_clamp = sampler(ctx, "sampler.nearest_clamp", vk::Filter::NEAREST, vk::SamplerAddressMode::CLAMP_TO_EDGE)?;

        self.shadows = ShadowMaps::new(ctx, &self.plan, self.layout)?;
        let method = self.plan.method;
        if !self.plan.envmaps.is_empty() {
            let kind = if method.uses_distance_maps() { MapKind::Distance } else { MapKind::Radiance };
            self.cube_maps = Some(CubeMaps::new(ctx, &self.plan, self.layout, kind)?);
            let others = self.plan.envmaps.iter().any(|e| !self.plan.self_refracted(e.mesh));
            if others {
                let (name, fragment) = match method {
                    Method::ProxySphere | Method::ProxyBox => ("proxy.shade", "envmap/proxy.frag"),
                    m if m.uses_distance_maps() => ("distance.search", "distance/shade.frag"),
                    _ => ("envmap.shade", "envmap/shade.frag"),
                };
                self.shade = Some(SpecularShade::new(ctx, self.layout, name, "scene/mesh.vert", fragment)?);
            }
        }
        if !self.plan.refractors.is_empty() {
            self.refractor_maps = Some(RefractorMaps::new(ctx, &self.plan, self.layout)?);
            self.self_refraction =
                Some(SpecularShade::new(ctx, self.layout, "refractor.search", "scene/mesh.vert", "refractor/search.frag")?);
        }
        if !self.plan.image_space.is_empty() {
            self.backfaces = Some(Backfaces::new(ctx, scene, &self.plan, self.layout, self.width, self.height)?);
            self.self_refraction =
                Some(SpecularShade::new(ctx, self.layout, "image_space.refract", "image_space/refract.vert", "image_space/refract.frag")?);
        }
        if method.uses_distance_maps() {
            let images = self.cube_maps.as_ref().map_or(0, |c| c.maps.len());
            for i in 0..=images {
                let (pool, set) = allocate_set(ctx, &format!("maps.set{i}"), self.maps_layout, MAP_BINDINGS)?;
                self.maps_sets.push(OwnedSet { pool, set });
            }
        }
        self.direct = Some(SceneDirect::new(ctx, self.layout)?);
        let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::SAMPLED;
        self.target = Image::new(
            ctx,
            &ImageDesc { name: "frame.color", format: TARGET_FORMAT, width: self.width, height: self.height, kind: ImageKind::D2, usage },
        )?;
        self.depth = Image::new(
            ctx,
            &ImageDesc {
                name: "frame.depth",
                format: DEPTH_FORMAT,
                width: self.width,
                height: self.height,
                kind: ImageKind::D2,
                usage: vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
            },
        )?;
        self.profiler = Profiler::new(ctx, MAX_PASSES)?;
        self.write_descriptors(ctx);
        Ok(())
    }

    fn light_table(&self, scene: &Scene) -> Vec<GpuLight> {
        let bounds = scene.bounds();
        let (center, radius) = (bounds.center(), (bounds.diagonal() * 0.5).max(1e-6));
        let size = self.plan.quality.shadow_size as f32;
        scene
            .lights
            .iter()
            .enumerate()
            .map(|(i, l)| {
                let mut cone = [-2.0, -1.0, -1.0, size];
                let mut view_proj = Mat4::IDENTITY;
                let mut texel = 0.0;
                if let LightKind::Spot { inner_cone, outer_cone } = l.kind {
                    cone[0] = outer_cone.cos();
                    cone[1] = inner_cone.cos();
                }
                if let Some(k) = self.plan.shadow_cubes.iter().position(|&j| j == i) {
                    cone[2] = k as f32;
                }
                if let Some(k) = self.plan.shadow_planes.iter().position(|&j| j == i) {
                    cone[2] = k as f32;
                    view_proj = directional_view_proj(l.direction, center, radius);
                    texel = 2.0 * radius / size;
                }
                let position = if l.kind == LightKind::Directional { center - l.direction * radius } else { l.position };
                GpuLight {
                    position_range: position.extend(l.range.unwrap_or(0.0)).to_array(),
                    direction_kind: l.direction.extend(light_kind_code(l.kind)).to_array(),
                    intensity: l.intensity.extend(texel).to_array(),
                    cone,
                    shadow_view_proj: view_proj.to_cols_array_2d(),
                }
            })
            .collect()
    }

    /// Writes every binding; what the scene does not need gets a null descriptor.
    fn write_descriptors(&self, ctx: &Context) {
        let sb = vk::DescriptorType::STORAGE_BUFFER;
        let cis = vk::DescriptorType::COMBINED_IMAGE_SAMPLER;
        let ro = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        let buffer = |b: Option<&Buffer>| b.map_or(vk::Buffer::null(), |b| b.raw);
        let view = |i: Option<&Image>| i.map_or(vk::ImageView::null(), |i| i.view);
        write_buffer(ctx, self.set, 0, sb, self.view_buffer.raw);
        write_buffer(ctx, self.set, 1, sb, self.scene.materials.raw);
        write_buffer(ctx, self.set, 2, sb, self.objects.raw);
        write_buffer(ctx, self.set, 3, sb, buffer(self.lights.as_ref()));
        write_image(ctx, self.set, 4, 0, cis, view(self.scene.textures.as_ref()), self.linear_repeat, ro);
        write_image(ctx, self.set, 5, 0, cis, view(self.scene.environment.as_ref()), self.linear_repeat, ro);
        write_image(ctx, self.set, 6, 0, cis, view(self.shadows.cubes.as_ref()), self.nearest_clamp, ro);
        write_image(ctx, self.set, 7, 0, cis, view(self.shadows.planes.as_ref()), self.nearest_clamp, ro);
        let radiance = self.cube_maps.as_ref().filter(|c| c.kind == MapKind::Radiance).map(|c| &c.maps[0]);
        write_image(ctx, self.set, 8, 0, cis, view(radiance), self.linear_repeat, ro);
        // Maps sets: set i samples distance image i, the last one no distance map; all share
        // the refractor maps, the back-face map and the thickness buffer.
        let distance: Vec<&Image> = self.cube_maps.iter().filter(|c| c.kind == MapKind::Distance).flat_map(|c| c.maps.iter()).collect();
        let last = self.maps_sets.len().saturating_sub(1);
        for (i, s) in self.maps_sets.iter().enumerate() {
            // The last set is all null: map generation declares set 1 but must not see
            // maps that are not written yet.
            let camera = i < last;
            write_image(ctx, s.set, 0, 0, cis, view(distance.get(i).copied()), self.linear_repeat, ro);
            write_image(
                ctx,
                s.set,
                1,
                0,
                cis,
                view(self.refractor_maps.as_ref().map(|r| &r.maps).filter(|_| camera)),
                self.linear_repeat,
                ro,
            );
            write_image(ctx, s.set, 2, 0, cis, view(self.backfaces.as_ref().map(|b| &b.map).filter(|_| camera)), self.nearest_clamp, ro);
            write_buffer(ctx, s.set, 3, sb, buffer(self.backfaces.as_ref().map(|b| &b.thickness).filter(|_| camera)));
        }
    }

    /// Replaces the camera (the output size's aspect ratio still wins).
    pub fn set_camera(&mut self, camera: Camera) -> Result<()> {
        camera.validate()?;
        self.camera = camera;
        Ok(())
    }

    /// The environment- or distance-map cube array the camera pass reads (one cube per
    /// `plan.envmaps` entry), if planned.
    pub fn envmaps(&self) -> Option<&Image> {
        self.cube_maps.as_ref().map(|c| c.current())
    }

    /// Image-space refraction's back-face map (xyz normal, w distance from the eye).
    pub fn backface_map(&self) -> Option<&Image> {
        self.backfaces.as_ref().map(|b| &b.map)
    }

    /// The refractor-map cube array (one cube per `plan.refractors` entry), if planned.
    pub fn refractor_maps(&self) -> Option<&Image> {
        self.refractor_maps.as_ref().map(|r| &r.maps)
    }

    /// The shadow cube array (one cube per `plan.shadow_cubes` entry), if planned.
    pub fn shadow_cubes(&self) -> Option<&Image> {
        self.shadows.cubes.as_ref()
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
        let scene_lights = &self.light_table;
        let mut views = vec![GpuView::zeroed(); self.views.count as usize];
        let vp = self.camera_view_proj();
        views[self.views.camera as usize] = view(vp, self.camera.position.extend(0.0), Vec4::ZERO);
        let near = self.plan.cube_near;
        for (k, &li) in self.plan.shadow_cubes.iter().enumerate() {
            let p = Vec3::from_slice(&scene_lights[li].position_range[..3]);
            for f in 0..6 {
                views[(self.views.shadow_cubes[k] + f) as usize] = view(face_view_proj(f as usize, p, near), p.extend(0.0), Vec4::ZERO);
            }
        }
        for (k, &li) in self.plan.shadow_planes.iter().enumerate() {
            let l = &scene_lights[li];
            let m = Mat4::from_cols_array_2d(&l.shadow_view_proj);
            let origin = Vec3::from_slice(&l.position_range[..3]);
            let dir = Vec3::from_slice(&l.direction_kind[..3]);
            views[self.views.shadow_planes[k] as usize] = view(m, origin.extend(1.0), dir.extend(0.0));
        }
        for (e, &base) in self.plan.envmaps.iter().zip(&self.views.envmaps) {
            for f in 0..6 {
                views[(base + f) as usize] =
                    view(face_view_proj(f as usize, e.reference_point, near), e.reference_point.extend(0.0), Vec4::ZERO);
            }
        }
        self.view_buffer.write(bytemuck::cast_slice(&views))
    }

    /// Records one frame into `cmd` (any primary command buffer in the recording state on
    /// this context's device). Afterwards `target` holds the image in COLOR_ATTACHMENT
    /// layout. The view table is written by the host now, so only one frame may be in
    /// flight at a time.
    pub fn record(&mut self, ctx: &Context, cmd: vk::CommandBuffer) -> Result<()> {
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
            search: [q.linear_steps, q.secant_steps, q.binary_steps, q.parallax_iterations],
            tolerance: q.search_tolerance,
            internal_bounces: q.internal_bounces,
        };
        let scene_images: Vec<&Image> = f.scene.textures.iter().chain(f.scene.environment.iter()).collect();
        let maps_sets: Vec<vk::DescriptorSet> = self.maps_sets.iter().map(|s| s.set).collect();
        let empty_set = maps_sets.last().copied().unwrap_or(vk::DescriptorSet::null());
        self.shadows.record(&mut rec, &f, &self.views.shadow_cubes, &self.views.shadow_planes);
        if let Some(g) = self.cube_maps.as_mut() {
            let sampled = scene_images.iter().copied().chain(self.shadows.sampled());
            g.record(&mut rec, &f, &self.plan, &self.views.envmaps, &maps_sets, empty_set, sampled);
        }
        // Refractor maps are seen from the refractors' reference points: their views are
        // the environment maps' views.
        if let Some(r) = self.refractor_maps.as_mut() {
            let views: Vec<u32> = self
                .plan
                .refractors
                .iter()
                .map(|m| self.plan.envmaps.iter().position(|e| e.mesh == *m).map_or(0, |i| self.views.envmaps[i]))
                .collect();
            r.record(&mut rec, &f, &self.plan, &views);
        }
        if let Some(d) = &self.direct {
            let sampled = scene_images.iter().copied().chain(self.shadows.sampled());
            d.record(&mut rec, &f, self.views.camera, &mut self.target, &mut self.depth, sampled);
        }
        let plan = &self.plan;
        if let Some(b) = self.backfaces.as_mut() {
            b.record(&mut rec, &f, self.views.camera, |d| plan.image_space.contains(&(d.mesh as usize)));
        }
        // The camera passes read the maps the last cycle wrote.
        let current = self.cube_maps.as_ref().map_or(0, |c| c.latest);
        let maps_set = maps_sets.get(current).copied();
        let mut reads: Vec<&Image> = self.cube_maps.iter().map(|c| c.current()).collect();
        reads.extend(self.refractor_maps.iter().map(|r| &r.maps));
        reads.extend(self.backfaces.iter().map(|b| &b.map));
        let proxy = if plan.method == Method::ProxyBox { FLAG_PROXY_BOX } else { 0 };
        if let Some(s) = &self.shade {
            s.record(&mut rec, &f, self.views.camera, reads.iter().copied(), maps_set, proxy, &mut self.target, &mut self.depth, |d| {
                d.specular && !plan.self_refracted(d.mesh as usize)
            });
        }
        if let Some(s) = &self.self_refraction {
            s.record(&mut rec, &f, self.views.camera, reads.iter().copied(), maps_set, 0, &mut self.target, &mut self.depth, |d| {
                plan.self_refracted(d.mesh as usize)
            });
        }
        if let Some(rb) = &self.readback {
            let open = rec.pass("frame.readback").reads(&self.target, Access::TransferSrc).begin();
            record_copy_to_buffer(ctx, cmd, &self.target, rb);
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
        let open = rec.pass("frame.output").reads(&self.target, Access::TransferSrc).writes(host, Access::TransferDst).begin();
        let layers = |aspect| vk::ImageSubresourceLayers { aspect_mask: aspect, mip_level: 0, base_array_layer: 0, layer_count: 1 };
        let c = vk::ImageAspectFlags::COLOR;
        unsafe {
            if host.format == self.target.format {
                let region = vk::ImageCopy {
                    src_subresource: layers(c),
                    dst_subresource: layers(c),
                    extent: vk::Extent3D { width: self.width, height: self.height, depth: 1 },
                    ..Default::default()
                };
                ctx.device.cmd_copy_image(
                    cmd,
                    self.target.raw,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    host.raw,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[region],
                );
            } else {
                let corner = vk::Offset3D { x: self.width as i32, y: self.height as i32, z: 1 };
                let region = vk::ImageBlit {
                    src_subresource: layers(c),
                    src_offsets: [vk::Offset3D::default(), corner],
                    dst_subresource: layers(c),
                    dst_offsets: [vk::Offset3D::default(), corner],
                };
                ctx.device.cmd_blit_image(
                    cmd,
                    self.target.raw,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    host.raw,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[region],
                    vk::Filter::NEAREST,
                );
            }
            let barriers = [host.release_to(final_layout)];
            ctx.device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&barriers));
        }
        rec.end(open);
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
                self.target.byte_size(),
                vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuToCpu,
            )?);
        }
        ctx.one_shot(|cmd| self.record(ctx, cmd))?;
        self.scene.release_staging(ctx);
        let passes = self.profiler.results(ctx)?;
        self.last_timings = passes.clone();
        let rb = self.readback.as_ref().unwrap();
        let image = crate::vk::decode(self.target.format, self.width, self.height, 1, rb.read()?)?;
        let errors = ctx.validation.error_count();
        if errors > 0 {
            return Err(Error::Validation(errors));
        }
        Ok(Frame { image, passes, memory: ctx.memory.snapshot() })
    }

    /// Frees everything. The GPU must be idle with respect to this renderer's frames.
    pub fn destroy(&mut self, ctx: &Context) {
        self.shadows.destroy(ctx);
        for g in self.cube_maps.iter_mut() {
            g.destroy(ctx);
        }
        for r in self.refractor_maps.iter_mut() {
            r.destroy(ctx);
        }
        for b in self.backfaces.iter_mut() {
            b.destroy(ctx);
        }
        for s in self.shade.iter_mut().chain(self.self_refraction.iter_mut()) {
            s.destroy(ctx);
        }
        for d in self.direct.iter_mut() {
            d.destroy(ctx);
        }
        self.target.destroy(ctx);
        self.depth.destroy(ctx);
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
            for s in self.maps_sets.drain(..) {
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
        self.linear_repeat = vk::Sampler::null();
        self.nearest_clamp = vk::Sampler::null();
    }
}

use bytemuck::Zeroable;

fn view(view_proj: Mat4, eye: Vec4, dir: Vec4) -> GpuView {
    GpuView {
        view_proj: view_proj.to_cols_array_2d(),
        inv_view_proj: view_proj.inverse().to_cols_array_2d(),
        eye: eye.to_array(),
        dir: dir.to_array(),
    }
}

/// Orthographic world → clip for a directional light's planar distance map covering the
/// sphere (center, radius); reversed depth.
pub fn directional_view_proj(dir: Vec3, center: Vec3, radius: f32) -> Mat4 {
    let up = if dir.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
    let eye = center - dir * radius;
    let view = Mat4::look_to_rh(eye, dir, up);
    // x, y in [−r, r] → [−1, 1]; depth d along dir in [0, 2r] → z_ndc = 1 − d/2r.
    let proj = Mat4::from_cols(
        Vec4::new(1.0 / radius, 0.0, 0.0, 0.0),
        Vec4::new(0.0, -1.0 / radius, 0.0, 0.0),
        Vec4::new(0.0, 0.0, 1.0 / (2.0 * radius), 0.0),
        Vec4::new(0.0, 0.0, 1.0, 1.0),
    );
    proj * view
}

impl crate::vk::Owner for Renderer {
    fn destroy(&mut self, ctx: &Context) {
        Renderer::destroy(self, ctx)
    }
}
