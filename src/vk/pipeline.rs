//! Graphics and compute pipelines from the embedded SPIR-V, and descriptor set layouts.

use ash::vk;
use ash::vk::Handle;

use super::pipeline_memo::{key_of, Key};
use super::Context;
use crate::error::{Error, Result, VkCall};

/// Gives back a pipeline layout made by [`pipeline_layout`] (the context keeps it for its
/// life; a null handle or one made elsewhere is destroyed, a no-op for null).
pub fn destroy_pipeline_layout(ctx: &Context, layout: vk::PipelineLayout) {
    if layout != vk::PipelineLayout::null() && !ctx.pipelines.is_kept(layout) {
        unsafe { ctx.device.destroy_pipeline_layout(layout, ctx.alloc()) };
    }
}

/// Gives back a descriptor set layout made by [`descriptor_set_layout`] (as
/// [`destroy_pipeline_layout`]).
pub fn destroy_set_layout(ctx: &Context, layout: vk::DescriptorSetLayout) {
    if layout != vk::DescriptorSetLayout::null() && !ctx.pipelines.is_kept(layout) {
        unsafe { ctx.device.destroy_descriptor_set_layout(layout, ctx.alloc()) };
    }
}

/// Gives back a pipeline made by [`graphics_pipeline`] or [`compute_pipeline`] (null: a
/// no-op): the context keeps it for a later renderer, or destroys it.
pub fn release_pipeline(ctx: &Context, pipeline: vk::Pipeline) {
    if pipeline != vk::Pipeline::null() {
        for p in ctx.pipelines.release(pipeline) {
            unsafe { ctx.device.destroy_pipeline(p, ctx.alloc()) };
        }
    }
}

/// The context's pipeline for `key`, made by `make` the first time.
fn memoised(
    ctx: &Context,
    layout: vk::PipelineLayout,
    key: impl std::hash::Hash,
    make: impl FnOnce() -> Result<vk::Pipeline>,
) -> Result<vk::Pipeline> {
    let Some(layout_key) = ctx.pipelines.layout_key(layout) else { return make() };
    let (p, duplicate) = ctx.pipelines.get_or_make(key_of(&(layout_key, key)), make)?;
    if let Some(d) = duplicate {
        unsafe { ctx.device.destroy_pipeline(d, ctx.alloc()) };
    }
    Ok(p)
}

pub fn shader_module(ctx: &Context, name: &str) -> Result<vk::ShaderModule> {
    let bytes = crate::shaders::get(name).ok_or_else(|| Error::invalid("shader", format!("no embedded shader '{name}'")))?;
    let words = ash::util::read_spv(&mut std::io::Cursor::new(bytes)).map_err(|e| Error::invalid(name, format!("bad SPIR-V: {e}")))?;
    let m = unsafe { ctx.device.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&words), ctx.alloc()) }
        .call("vkCreateShaderModule")?;
    ctx.name(m, name);
    Ok(m)
}

/// A descriptor binding: (binding, type, count). What a scene does not need is written as
/// a null descriptor (VK_EXT_robustness2) instead of a dummy allocation.
pub type Binding = (u32, vk::DescriptorType, u32);

pub fn descriptor_set_layout(
    ctx: &Context,
    name: &str,
    bindings: &[Binding],
    stages: vk::ShaderStageFlags,
) -> Result<vk::DescriptorSetLayout> {
    let definition: Vec<(u32, i32, u32)> = bindings.iter().map(|&(b, ty, n)| (b, ty.as_raw(), n)).collect();
    let key = key_of(&("set", definition, stages.as_raw()));
    if let Some(l) = ctx.pipelines.kept_layout(key) {
        return Ok(l);
    }
    let b: Vec<_> = bindings
        .iter()
        .map(|&(binding, ty, count)| {
            vk::DescriptorSetLayoutBinding::default().binding(binding).descriptor_type(ty).descriptor_count(count).stage_flags(stages)
        })
        .collect();
    let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&b);
    let l = unsafe { ctx.device.create_descriptor_set_layout(&info, ctx.alloc()) }.call("vkCreateDescriptorSetLayout")?;
    ctx.name(l, name);
    let (l, made_twice) = ctx.pipelines.keep_layout(l, key, false);
    if let Some(d) = made_twice {
        unsafe { ctx.device.destroy_descriptor_set_layout(d, ctx.alloc()) };
    }
    Ok(l)
}

/// A pool sized for exactly one set of `bindings`, and that set.
pub fn allocate_set(
    ctx: &Context,
    name: &str,
    layout: vk::DescriptorSetLayout,
    bindings: &[Binding],
) -> Result<(vk::DescriptorPool, vk::DescriptorSet)> {
    let sizes: Vec<_> = bindings.iter().map(|&(_, ty, count)| vk::DescriptorPoolSize { ty, descriptor_count: count }).collect();
    let pool =
        unsafe { ctx.device.create_descriptor_pool(&vk::DescriptorPoolCreateInfo::default().max_sets(1).pool_sizes(&sizes), ctx.alloc()) }
            .call("vkCreateDescriptorPool")?;
    let layouts = [layout];
    let set = match unsafe {
        ctx.device.allocate_descriptor_sets(&vk::DescriptorSetAllocateInfo::default().descriptor_pool(pool).set_layouts(&layouts))
    } {
        Ok(s) => s[0],
        Err(e) => {
            unsafe { ctx.device.destroy_descriptor_pool(pool, ctx.alloc()) };
            return Err(e).call("vkAllocateDescriptorSets");
        }
    };
    ctx.name(set, name);
    Ok((pool, set))
}

/// Destroys a pipeline layout, a descriptor pool (with its sets) and set layouts, and nulls
/// the handles (null ones are no-ops), as every owner of its own layout does.
pub fn destroy_layouts(
    ctx: &Context,
    layout: &mut vk::PipelineLayout,
    pool: &mut vk::DescriptorPool,
    set_layouts: &mut [vk::DescriptorSetLayout],
) {
    destroy_pipeline_layout(ctx, *layout);
    unsafe { ctx.device.destroy_descriptor_pool(*pool, ctx.alloc()) };
    for &l in set_layouts.iter() {
        destroy_set_layout(ctx, l);
    }
    *layout = vk::PipelineLayout::null();
    *pool = vk::DescriptorPool::null();
    set_layouts.fill(vk::DescriptorSetLayout::null());
}

/// Writes a buffer descriptor; a null `buffer` writes a null descriptor.
pub fn write_buffer(ctx: &Context, set: vk::DescriptorSet, binding: u32, ty: vk::DescriptorType, buffer: vk::Buffer) {
    let info = [vk::DescriptorBufferInfo { buffer, offset: 0, range: vk::WHOLE_SIZE }];
    let w = vk::WriteDescriptorSet::default().dst_set(set).dst_binding(binding).descriptor_type(ty).buffer_info(&info);
    unsafe { ctx.device.update_descriptor_sets(&[w], &[]) };
}

/// Writes an image descriptor; a null `view` writes a null descriptor.
#[allow(clippy::too_many_arguments)]
pub fn write_image(
    ctx: &Context,
    set: vk::DescriptorSet,
    binding: u32,
    element: u32,
    ty: vk::DescriptorType,
    view: vk::ImageView,
    sampler: vk::Sampler,
    layout: vk::ImageLayout,
) {
    let info = [vk::DescriptorImageInfo { sampler, image_view: view, image_layout: layout }];
    let w = vk::WriteDescriptorSet::default()
        .dst_set(set)
        .dst_binding(binding)
        .dst_array_element(element)
        .descriptor_type(ty)
        .image_info(&info);
    unsafe { ctx.device.update_descriptor_sets(&[w], &[]) };
}

pub fn pipeline_layout(
    ctx: &Context,
    name: &str,
    sets: &[vk::DescriptorSetLayout],
    push_bytes: u32,
    stages: vk::ShaderStageFlags,
) -> Result<vk::PipelineLayout> {
    // Its definition: its sets' (a set layout made elsewhere: this handle's own).
    let keys: Vec<Key> = sets.iter().map(|&s| ctx.pipelines.layout_key(s).unwrap_or((s.as_raw(), u64::MAX))).collect();
    let key = key_of(&("layout", keys, push_bytes, stages.as_raw()));
    if let Some(l) = ctx.pipelines.kept_layout(key) {
        return Ok(l);
    }
    let ranges = [vk::PushConstantRange { stage_flags: stages, offset: 0, size: push_bytes }];
    let mut info = vk::PipelineLayoutCreateInfo::default().set_layouts(sets);
    if push_bytes > 0 {
        info = info.push_constant_ranges(&ranges);
    }
    let l = unsafe { ctx.device.create_pipeline_layout(&info, ctx.alloc()) }.call("vkCreatePipelineLayout")?;
    ctx.name(l, name);
    let (l, made_twice) = ctx.pipelines.keep_layout(l, key, true);
    if let Some(d) = made_twice {
        unsafe { ctx.device.destroy_pipeline_layout(d, ctx.alloc()) };
    }
    Ok(l)
}

/// Vertex layout of the scene's interleaved vertex buffer (see `gpu_scene::Vertex`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VertexInput {
    None,
    /// position vec3, normal vec3, uv vec2: 32 bytes.
    Mesh,
    /// The same buffer, positions only (passes that need nothing else: `layered.count`).
    Positions,
}

/// Everything that distinguishes one graphics pipeline of this library from another.
pub struct GraphicsDesc<'a> {
    pub name: &'a str,
    pub vertex: &'a str,
    pub fragment: &'a str,
    pub vertex_input: VertexInput,
    pub color_formats: &'a [vk::Format],
    pub depth_format: Option<vk::Format>,
    /// Reversed-Z: GREATER passes nearer fragments.
    pub depth_test: bool,
    pub depth_write: bool,
    /// Multiview mask (0x3F renders all six cube faces in one pass).
    pub view_mask: u32,
    /// Faces to cull; NONE draws both sides (rooms are seen from inside, refractors from
    /// both sides), FRONT keeps back faces (image-space refraction's first pass).
    pub cull: vk::CullModeFlags,
    /// Samples per pixel of the attachments, and whether every sample runs the fragment
    /// shader (sample-rate shading).
    pub multisample: Multisample,
    /// How fragments combine with the attachments' contents.
    pub blend: Blend,
    /// Which fragments the depth test keeps (reversed-Z).
    pub depth_op: DepthOp,
}

/// The depth test's comparison, reversed-Z (greater is nearer).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DepthOp {
    /// Strictly nearer than what is there.
    Nearer,
    /// Nearer or at the same depth: a second pass over the same surfaces (caustics.project).
    NearerOrEqual,
    /// Always: a mask written into the depth buffer (planar mirrors in cube maps).
    Always,
    /// Strictly farther (over a depth cleared to the nearest): the farthest surface
    /// (layered maps' last layer where the peel is cut).
    Farther,
}

/// Colour blending of a pipeline's attachments.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Blend {
    /// The fragment replaces what is there.
    Replace,
    /// Additive (ONE, ONE): accumulation, e.g. photon splats into a light cube map.
    Add,
    /// Colour multiplied by the fragment's (ZERO, SRC_COLOR), alpha replaced: a planar
    /// mirror's Fresnel weight laid over its reflection already in a cube map.
    Multiply,
}

/// The rasteriser's samples per pixel for a pipeline.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Multisample {
    pub samples: u32,
    pub per_sample: bool,
}

impl Multisample {
    /// One sample per pixel (every map pass, and camera passes without MSAA).
    pub const OFF: Multisample = Multisample { samples: 1, per_sample: false };

    pub fn flags(self) -> vk::SampleCountFlags {
        sample_count_flags(self.samples)
    }
}

/// The Vulkan flag of a sample count (1, 2, 4, 8, 16, 32 or 64; anything else is 1).
pub fn sample_count_flags(samples: u32) -> vk::SampleCountFlags {
    match samples {
        2 => vk::SampleCountFlags::TYPE_2,
        4 => vk::SampleCountFlags::TYPE_4,
        8 => vk::SampleCountFlags::TYPE_8,
        16 => vk::SampleCountFlags::TYPE_16,
        32 => vk::SampleCountFlags::TYPE_32,
        64 => vk::SampleCountFlags::TYPE_64,
        _ => vk::SampleCountFlags::TYPE_1,
    }
}

/// A graphics pipeline of `desc` on `layout`: the context's, where a renderer made the same
/// one before (`pipeline_memo`). Give it back with [`release_pipeline`].
pub fn graphics_pipeline(ctx: &Context, layout: vk::PipelineLayout, desc: &GraphicsDesc) -> Result<vk::Pipeline> {
    let formats: Vec<i32> = desc.color_formats.iter().map(|f| f.as_raw()).collect();
    let key = (
        ("graphics", desc.name, desc.vertex, desc.fragment, desc.vertex_input as u8, formats, desc.depth_format.map(|f| f.as_raw())),
        (desc.depth_test, desc.depth_write, desc.view_mask, desc.cull.as_raw()),
        (desc.multisample.samples, desc.multisample.per_sample, desc.blend as u8, desc.depth_op as u8),
    );
    memoised(ctx, layout, key, || make_graphics_pipeline(ctx, layout, desc))
}

fn make_graphics_pipeline(ctx: &Context, layout: vk::PipelineLayout, desc: &GraphicsDesc) -> Result<vk::Pipeline> {
    let vs = shader_module(ctx, desc.vertex)?;
    let fs = match shader_module(ctx, desc.fragment) {
        Ok(f) => f,
        Err(e) => {
            unsafe { ctx.device.destroy_shader_module(vs, ctx.alloc()) };
            return Err(e);
        }
    };
    let stages = [
        vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::VERTEX).module(vs).name(c"main"),
        vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::FRAGMENT).module(fs).name(c"main"),
    ];
    let bindings = [vk::VertexInputBindingDescription { binding: 0, stride: 32, input_rate: vk::VertexInputRate::VERTEX }];
    let attrs = [
        vk::VertexInputAttributeDescription { location: 0, binding: 0, format: vk::Format::R32G32B32_SFLOAT, offset: 0 },
        vk::VertexInputAttributeDescription { location: 1, binding: 0, format: vk::Format::R32G32B32_SFLOAT, offset: 12 },
        vk::VertexInputAttributeDescription { location: 2, binding: 0, format: vk::Format::R32G32_SFLOAT, offset: 24 },
    ];
    let vi = match desc.vertex_input {
        VertexInput::None => vk::PipelineVertexInputStateCreateInfo::default(),
        VertexInput::Mesh => {
            vk::PipelineVertexInputStateCreateInfo::default().vertex_binding_descriptions(&bindings).vertex_attribute_descriptions(&attrs)
        }
        VertexInput::Positions => vk::PipelineVertexInputStateCreateInfo::default()
            .vertex_binding_descriptions(&bindings)
            .vertex_attribute_descriptions(&attrs[..1]),
    };
    let ia = vk::PipelineInputAssemblyStateCreateInfo::default().topology(vk::PrimitiveTopology::TRIANGLE_LIST);
    let vp = vk::PipelineViewportStateCreateInfo::default().viewport_count(1).scissor_count(1);
    // Two-sided: rooms are seen from inside, refractors from both sides.
    let rs = vk::PipelineRasterizationStateCreateInfo::default()
        .polygon_mode(vk::PolygonMode::FILL)
        .cull_mode(desc.cull)
        // With the y-flipped projections used here, glTF's counter-clockwise front faces
        // stay counter-clockwise in the framebuffer (tests/image_space checks it).
        .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
        .line_width(1.0);
    let per_sample = desc.multisample.per_sample && desc.multisample.samples > 1;
    let ms = vk::PipelineMultisampleStateCreateInfo::default()
        .rasterization_samples(desc.multisample.flags())
        .sample_shading_enable(per_sample)
        .min_sample_shading(if per_sample { 1.0 } else { 0.0 });
    let ds = vk::PipelineDepthStencilStateCreateInfo::default()
        .depth_test_enable(desc.depth_test)
        .depth_write_enable(desc.depth_write)
        .depth_compare_op(match desc.depth_op {
            DepthOp::Nearer => vk::CompareOp::GREATER,
            DepthOp::NearerOrEqual => vk::CompareOp::GREATER_OR_EQUAL,
            DepthOp::Always => vk::CompareOp::ALWAYS,
            DepthOp::Farther => vk::CompareOp::LESS,
        });
    let blend: Vec<_> = desc
        .color_formats
        .iter()
        .map(|_| {
            let b = vk::PipelineColorBlendAttachmentState::default().color_write_mask(vk::ColorComponentFlags::RGBA);
            match desc.blend {
                Blend::Replace => b,
                Blend::Add => b
                    .blend_enable(true)
                    .src_color_blend_factor(vk::BlendFactor::ONE)
                    .dst_color_blend_factor(vk::BlendFactor::ONE)
                    .color_blend_op(vk::BlendOp::ADD)
                    .src_alpha_blend_factor(vk::BlendFactor::ONE)
                    .dst_alpha_blend_factor(vk::BlendFactor::ONE)
                    .alpha_blend_op(vk::BlendOp::ADD),
                Blend::Multiply => b
                    .blend_enable(true)
                    .src_color_blend_factor(vk::BlendFactor::ZERO)
                    .dst_color_blend_factor(vk::BlendFactor::SRC_COLOR)
                    .color_blend_op(vk::BlendOp::ADD)
                    .src_alpha_blend_factor(vk::BlendFactor::ONE)
                    .dst_alpha_blend_factor(vk::BlendFactor::ZERO)
                    .alpha_blend_op(vk::BlendOp::ADD),
            }
        })
        .collect();
    let cb = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend);
    let dyn_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
    let dy = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dyn_states);
    let mut rendering = vk::PipelineRenderingCreateInfo::default()
        .color_attachment_formats(desc.color_formats)
        .depth_attachment_format(desc.depth_format.unwrap_or(vk::Format::UNDEFINED))
        .view_mask(desc.view_mask);
    let info = vk::GraphicsPipelineCreateInfo::default()
        .stages(&stages)
        .vertex_input_state(&vi)
        .input_assembly_state(&ia)
        .viewport_state(&vp)
        .rasterization_state(&rs)
        .multisample_state(&ms)
        .depth_stencil_state(&ds)
        .color_blend_state(&cb)
        .dynamic_state(&dy)
        .layout(layout)
        .push_next(&mut rendering);
    let r = unsafe { ctx.device.create_graphics_pipelines(vk::PipelineCache::null(), &[info], ctx.alloc()) };
    unsafe {
        ctx.device.destroy_shader_module(vs, ctx.alloc());
        ctx.device.destroy_shader_module(fs, ctx.alloc());
    }
    let p = r.map_err(|(_, e)| e).call("vkCreateGraphicsPipelines")?[0];
    ctx.name(p, desc.name);
    Ok(p)
}

/// A compute pipeline of `shader` on `layout`: the context's, where a renderer made the same
/// one before. Give it back with [`release_pipeline`].
pub fn compute_pipeline(ctx: &Context, layout: vk::PipelineLayout, shader: &str) -> Result<vk::Pipeline> {
    memoised(ctx, layout, ("compute", shader), || make_compute_pipeline(ctx, layout, shader))
}

fn make_compute_pipeline(ctx: &Context, layout: vk::PipelineLayout, shader: &str) -> Result<vk::Pipeline> {
    let cs = shader_module(ctx, shader)?;
    let stage = vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::COMPUTE).module(cs).name(c"main");
    let info = vk::ComputePipelineCreateInfo::default().stage(stage).layout(layout);
    let r = unsafe { ctx.device.create_compute_pipelines(vk::PipelineCache::null(), &[info], ctx.alloc()) };
    unsafe { ctx.device.destroy_shader_module(cs, ctx.alloc()) };
    let p = r.map_err(|(_, e)| e).call("vkCreateComputePipelines")?[0];
    ctx.name(p, shader);
    Ok(p)
}

pub fn sampler(ctx: &Context, name: &str, filter: vk::Filter, address: vk::SamplerAddressMode) -> Result<vk::Sampler> {
    let info = vk::SamplerCreateInfo::default()
        .mag_filter(filter)
        .min_filter(filter)
        .mipmap_mode(vk::SamplerMipmapMode::NEAREST)
        .address_mode_u(address)
        .address_mode_v(address)
        .address_mode_w(address)
        .max_lod(0.0);
    let s = unsafe { ctx.device.create_sampler(&info, ctx.alloc()) }.call("vkCreateSampler")?;
    ctx.name(s, name);
    Ok(s)
}
