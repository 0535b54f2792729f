//! The frame's bindings: set 0 (views, materials, objects, lights, textures, environment and
//! the set-0 maps), the set-1 map sets, the pipeline layout every pass shares, its samplers,
//! and the tables behind them (`frame.views`, `scene.objects`, `scene.lights`).

use ash::vk;

use crate::frame::layout::{binding, BINDINGS, MAP_BINDINGS, MAP_SHADING_SKY};
use crate::frame::stage::{LayerField, MapSets, Maps};
use crate::frame::PUSH_BYTES;
use crate::gpu_scene::{GpuLight, GpuObject, GpuScene, GpuView};
use crate::plan::Plan;
use crate::scene::Scene;
use crate::vk::pipeline::{allocate_set, descriptor_set_layout, pipeline_layout, sampler, write_buffer, write_image};
use crate::vk::{Buffer, Context, Image, MemoryLocation};
use crate::Result;

/// A descriptor set with its own pool.
struct OwnedSet {
    pool: vk::DescriptorPool,
    set: vk::DescriptorSet,
}

pub(super) struct Bindings {
    set_layout: vk::DescriptorSetLayout,
    pool: vk::DescriptorPool,
    pub set: vk::DescriptorSet,
    maps_layout: vk::DescriptorSetLayout,
    pub layout: vk::PipelineLayout,
    linear_repeat: vk::Sampler,
    nearest_clamp: vk::Sampler,
    /// Set-1 descriptor sets, each with its own pool.
    owned_sets: Vec<OwnedSet>,
    pub sets: MapSets,
    /// The view table (`frame.views`), the object table and the light table.
    pub views: Buffer,
    pub objects: Buffer,
    pub lights: Option<Buffer>,
}

impl Bindings {
    /// Nothing allocated yet: `create` fills it, `destroy` frees whatever exists.
    pub fn empty() -> Bindings {
        Bindings {
            set_layout: vk::DescriptorSetLayout::null(),
            pool: vk::DescriptorPool::null(),
            set: vk::DescriptorSet::null(),
            maps_layout: vk::DescriptorSetLayout::null(),
            layout: vk::PipelineLayout::null(),
            linear_repeat: vk::Sampler::null(),
            nearest_clamp: vk::Sampler::null(),
            owned_sets: Vec::new(),
            sets: MapSets::default(),
            views: Buffer::placeholder(),
            objects: Buffer::placeholder(),
            lights: None,
        }
    }

    /// The tables, set 0, the set layouts, the pipeline layout and the samplers.
    pub fn create(&mut self, ctx: &Context, views: u32, objects: &[GpuObject], lights: &[GpuLight]) -> Result<()> {
        self.views = Buffer::new(
            ctx,
            "frame.views",
            (views as usize * std::mem::size_of::<GpuView>()) as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryLocation::CpuToGpu,
        )?;
        self.objects = Buffer::with_data(ctx, "scene.objects", objects, vk::BufferUsageFlags::STORAGE_BUFFER)?;
        if !lights.is_empty() {
            self.lights = Some(Buffer::with_data(ctx, "scene.lights", lights, vk::BufferUsageFlags::STORAGE_BUFFER)?);
        }
        // The sets are visible to compute too: the ray pipeline's kernels shade with them.
        let stages = vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT | vk::ShaderStageFlags::COMPUTE;
        self.set_layout = descriptor_set_layout(ctx, "frame.set_layout", BINDINGS, stages)?;
        (self.pool, self.set) = allocate_set(ctx, "frame.set", self.set_layout, BINDINGS)?;
        self.maps_layout = descriptor_set_layout(ctx, "maps.set_layout", MAP_BINDINGS, stages)?;
        // Push constants reach compute too: the caustic triangles' set-up kernel reads them.
        self.layout = pipeline_layout(ctx, "frame.layout", &[self.set_layout, self.maps_layout], PUSH_BYTES, stages)?;
        self.linear_repeat = sampler(ctx, "sampler.linear_repeat", vk::Filter::LINEAR, vk::SamplerAddressMode::REPEAT)?;
        self.nearest_clamp = sampler(ctx, "sampler.nearest_clamp", vk::Filter::NEAREST, vk::SamplerAddressMode::CLAMP_TO_EDGE)?;
        Ok(())
    }

    /// The frame's descriptor set layouts (set 0, set 1).
    pub fn set_layouts(&self) -> [vk::DescriptorSetLayout; 2] {
        [self.set_layout, self.maps_layout]
    }

    /// The maps' set-1 descriptor sets, as many as the maps need.
    pub fn allocate_map_sets(&mut self, ctx: &Context, maps: &Maps) -> Result<()> {
        for i in 0..maps.set_count() {
            let (pool, set) = allocate_set(ctx, &format!("maps.set{i}"), self.maps_layout, MAP_BINDINGS)?;
            self.owned_sets.push(OwnedSet { pool, set });
        }
        self.sets = maps.sets(&self.owned_sets.iter().map(|s| s.set).collect::<Vec<_>>());
        Ok(())
    }

    /// Writes every binding; what the scene does not need gets a null descriptor.
    pub fn write(&self, ctx: &Context, scene: &GpuScene, maps: &Maps) {
        let sb = vk::DescriptorType::STORAGE_BUFFER;
        let cis = vk::DescriptorType::COMBINED_IMAGE_SAMPLER;
        let ro = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        let buffer = |b: Option<&Buffer>| b.map_or(vk::Buffer::null(), |b| b.raw);
        let view = |i: Option<&Image>| i.map_or(vk::ImageView::null(), |i| i.view);
        write_buffer(ctx, self.set, binding::VIEWS, sb, self.views.raw);
        write_buffer(ctx, self.set, binding::MATERIALS, sb, scene.materials.raw);
        write_buffer(ctx, self.set, binding::OBJECTS, sb, self.objects.raw);
        write_buffer(ctx, self.set, binding::LIGHTS, sb, buffer(self.lights.as_ref()));
        write_image(ctx, self.set, binding::TEXTURES, 0, cis, view(scene.textures.as_ref()), self.linear_repeat, ro);
        write_image(ctx, self.set, binding::ENVIRONMENT_MAP, 0, cis, view(scene.environment.as_ref()), self.linear_repeat, ro);
        maps.write_descriptors(ctx, self.set, &self.sets, self.linear_repeat, self.nearest_clamp);
    }

    pub fn destroy(&mut self, ctx: &Context) {
        for b in [Some(&mut self.views), Some(&mut self.objects), self.lights.as_mut()].into_iter().flatten() {
            b.destroy(ctx);
        }
        crate::vk::pipeline::destroy_pipeline_layout(ctx, self.layout);
        crate::vk::pipeline::destroy_set_layout(ctx, self.set_layout);
        crate::vk::pipeline::destroy_set_layout(ctx, self.maps_layout);
        unsafe {
            let d = &ctx.device;
            if self.pool != vk::DescriptorPool::null() {
                d.destroy_descriptor_pool(self.pool, ctx.alloc());
            }
            for s in self.owned_sets.drain(..) {
                d.destroy_descriptor_pool(s.pool, ctx.alloc());
            }
            for s in [self.linear_repeat, self.nearest_clamp] {
                if s != vk::Sampler::null() {
                    d.destroy_sampler(s, ctx.alloc());
                }
            }
        }
        *self = Bindings::empty();
    }
}

/// The object table (`scene.objects`): per mesh its material, reference point and proxy,
/// how it shows in maps, and its layer in each map array.
pub(super) fn object_table(scene: &Scene, plan: &Plan) -> Vec<GpuObject> {
    let mut objects: Vec<GpuObject> = scene
        .meshes
        .iter()
        .map(|m| {
            let b = m.bounds();
            let centre = b.center();
            let radius = m.positions.iter().map(|p| p.distance(centre)).fold(0.0f32, f32::max);
            GpuObject {
                material: m.material as u32,
                envmap_layer: -1,
                refractor_layer: -1,
                shown_layer: -1,
                pad: [0; 3],
                map_shading: MAP_SHADING_SKY,
                reference_point: [0.0; 4],
                map_centre: [0.0; 4],
                proxy_min: plan.proxy_box.0.extend(0.0).to_array(),
                proxy_max: plan.proxy_box.1.extend(0.0).to_array(),
                bounds_min: b.min.extend(radius).to_array(),
                bounds_max: b.max.extend(0.0).to_array(),
            }
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
                Some(LayerField::Shown) => g.shown_layer = m.layer as i32,
                None => {}
            }
        }
    }
    objects
}
