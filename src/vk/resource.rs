//! Buffers and images. Each has one owner that creates it (`new`) and destroys it
//! (`destroy`, which needs an idle GPU for anything the GPU may still use). Every
//! allocation is registered by name in the context's `MemoryRegistry`, so a frame's
//! profile can state what its resources hold.

use std::cell::Cell;

use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
pub use gpu_allocator::MemoryLocation;

use super::Context;
use crate::error::{Error, Result, VkCall};

fn alloc_err(name: &str, bytes: u64, e: gpu_allocator::AllocationError) -> Error {
    match e {
        gpu_allocator::AllocationError::OutOfMemory => {
            Error::OutOfMemory(format!("device memory for '{name}': {bytes} bytes ({:.2} MiB)", bytes as f64 / 1048576.0))
        }
        e => Error::Unsupported(format!("allocating '{name}': {e}")),
    }
}

/// Sub-allocates device memory for one resource (gpu-allocator, explicit).
fn allocate(ctx: &Context, name: &str, requirements: vk::MemoryRequirements, location: MemoryLocation, linear: bool) -> Result<Allocation> {
    ctx.memory.check_budget(name, requirements.size)?;
    let mut guard = ctx.allocator();
    let allocator = guard.as_mut().ok_or_else(|| Error::invalid(name, "context is shutting down"))?;
    let desc = AllocationCreateDesc { name, requirements, location, linear, allocation_scheme: AllocationScheme::GpuAllocatorManaged };
    allocator.allocate(&desc).map_err(|e| alloc_err(name, requirements.size, e))
}

pub struct Buffer {
    pub raw: vk::Buffer,
    pub size: u64,
    allocation: Option<Allocation>,
    registry_id: u64,
    pub name: String,
}

impl Buffer {
    pub fn new(ctx: &Context, name: &str, size: u64, usage: vk::BufferUsageFlags, location: MemoryLocation) -> Result<Buffer> {
        if size == 0 {
            return Err(Error::invalid(name, "zero-size buffer"));
        }
        let d = &ctx.device;
        let raw =
            unsafe { d.create_buffer(&vk::BufferCreateInfo::default().size(size).usage(usage), ctx.alloc()) }.call("vkCreateBuffer")?;
        let req = unsafe { d.get_buffer_memory_requirements(raw) };
        let allocation = match allocate(ctx, name, req, location, true) {
            Ok(a) => a,
            Err(e) => {
                unsafe { d.destroy_buffer(raw, ctx.alloc()) };
                return Err(e);
            }
        };
        if let Err(e) = unsafe { d.bind_buffer_memory(raw, allocation.memory(), allocation.offset()) }.call("vkBindBufferMemory") {
            unsafe { d.destroy_buffer(raw, ctx.alloc()) };
            let _ = ctx.allocator().as_mut().map(|a| a.free(allocation));
            return Err(e);
        }
        ctx.name(raw, name);
        let registry_id = ctx.memory.add(name, req.size);
        Ok(Buffer { raw, size, allocation: Some(allocation), registry_id, name: name.to_string() })
    }

    /// An empty handle that owns nothing (`destroy` is a no-op): for partial construction.
    pub fn placeholder() -> Buffer {
        Buffer { raw: vk::Buffer::null(), size: 0, allocation: None, registry_id: u64::MAX, name: String::new() }
    }

    /// A host-visible buffer filled with `data`.
    pub fn with_data<T: bytemuck::Pod>(ctx: &Context, name: &str, data: &[T], usage: vk::BufferUsageFlags) -> Result<Buffer> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let mut b = Buffer::new(ctx, name, bytes.len().max(4) as u64, usage, MemoryLocation::CpuToGpu)?;
        b.write(bytes)?;
        Ok(b)
    }

    /// Writes into a host-visible buffer.
    pub fn write(&mut self, bytes: &[u8]) -> Result<()> {
        let slice = self
            .allocation
            .as_mut()
            .and_then(|a| a.mapped_slice_mut())
            .ok_or_else(|| Error::invalid(&self.name, "buffer is not host-visible"))?;
        if bytes.len() > slice.len() {
            return Err(Error::invalid(&self.name, format!("{} bytes do not fit in {}", bytes.len(), slice.len())));
        }
        slice[..bytes.len()].copy_from_slice(bytes);
        Ok(())
    }

    /// Writes `bytes` at byte `offset` of a host-visible buffer (in place: the GPU must not
    /// be reading that range, i.e. the frames that read it have completed).
    pub fn write_at(&mut self, offset: usize, bytes: &[u8]) -> Result<()> {
        let name = self.name.clone();
        let slice = self
            .allocation
            .as_mut()
            .and_then(|a| a.mapped_slice_mut())
            .ok_or_else(|| Error::invalid(&name, "buffer is not host-visible"))?;
        let end = offset.checked_add(bytes.len()).filter(|&e| e <= slice.len());
        let Some(end) = end else {
            return Err(Error::invalid(&name, format!("{} bytes at {offset} do not fit in {}", bytes.len(), slice.len())));
        };
        slice[offset..end].copy_from_slice(bytes);
        Ok(())
    }

    /// Reads a host-visible buffer.
    pub fn read(&self) -> Result<&[u8]> {
        self.allocation.as_ref().and_then(|a| a.mapped_slice()).ok_or_else(|| Error::invalid(&self.name, "buffer is not host-visible"))
    }

    pub fn destroy(&mut self, ctx: &Context) {
        if let Some(a) = self.allocation.take() {
            unsafe { ctx.device.destroy_buffer(self.raw, ctx.alloc()) };
            if let Some(al) = ctx.allocator().as_mut() {
                let _ = al.free(a);
            }
            ctx.memory.remove(self.registry_id);
            self.raw = vk::Buffer::null();
        }
    }
}

/// What a pass does with an image; barriers and layout transitions follow from it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    ColorAttachment,
    DepthAttachment,
    /// Sampled in fragment shaders.
    FragmentSampled,
    /// Sampled in vertex shaders.
    VertexSampled,
    /// Sampled in compute shaders.
    ComputeSampled,
    /// Written (and read) as a storage image in compute shaders.
    ComputeStorage,
    TransferSrc,
    TransferDst,
}

impl Access {
    fn state(self) -> ImageState {
        use vk::{AccessFlags2 as A, ImageLayout as L, PipelineStageFlags2 as S};
        let (stage, access, layout) = match self {
            Access::ColorAttachment => {
                (S::COLOR_ATTACHMENT_OUTPUT, A::COLOR_ATTACHMENT_WRITE | A::COLOR_ATTACHMENT_READ, L::COLOR_ATTACHMENT_OPTIMAL)
            }
            Access::DepthAttachment => (
                S::EARLY_FRAGMENT_TESTS | S::LATE_FRAGMENT_TESTS,
                A::DEPTH_STENCIL_ATTACHMENT_WRITE | A::DEPTH_STENCIL_ATTACHMENT_READ,
                L::DEPTH_ATTACHMENT_OPTIMAL,
            ),
            Access::FragmentSampled => (S::FRAGMENT_SHADER, A::SHADER_SAMPLED_READ, L::SHADER_READ_ONLY_OPTIMAL),
            Access::VertexSampled => (S::VERTEX_SHADER, A::SHADER_SAMPLED_READ, L::SHADER_READ_ONLY_OPTIMAL),
            Access::ComputeSampled => (S::COMPUTE_SHADER, A::SHADER_SAMPLED_READ, L::SHADER_READ_ONLY_OPTIMAL),
            Access::ComputeStorage => (S::COMPUTE_SHADER, A::SHADER_STORAGE_WRITE | A::SHADER_STORAGE_READ, L::GENERAL),
            // Every transfer stage: copies, blits (host-format conversion, the supersampling
            // resolve) and clears.
            Access::TransferSrc => (S::ALL_TRANSFER, A::TRANSFER_READ, L::TRANSFER_SRC_OPTIMAL),
            Access::TransferDst => (S::ALL_TRANSFER, A::TRANSFER_WRITE, L::TRANSFER_DST_OPTIMAL),
        };
        ImageState { stage, access, layout }
    }
    fn writes(self) -> bool {
        !matches!(self, Access::FragmentSampled | Access::VertexSampled | Access::ComputeSampled | Access::TransferSrc)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImageState {
    pub stage: vk::PipelineStageFlags2,
    pub access: vk::AccessFlags2,
    pub layout: vk::ImageLayout,
}

impl ImageState {
    pub const UNDEFINED: ImageState =
        ImageState { stage: vk::PipelineStageFlags2::NONE, access: vk::AccessFlags2::NONE, layout: vk::ImageLayout::UNDEFINED };
}

/// How an image is shaped: a 2D image, a layered 2D array, a cube map or a cube-map array.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageKind {
    D2,
    D2Array {
        layers: u32,
    },
    Cube,
    CubeArray {
        cubes: u32,
    },
    /// A multisampled 2D image (a camera attachment with MSAA).
    D2Multisample {
        samples: u32,
    },
}

impl ImageKind {
    pub fn layers(self) -> u32 {
        match self {
            ImageKind::D2 => 1,
            ImageKind::D2Array { layers } => layers,
            ImageKind::Cube => 6,
            ImageKind::CubeArray { cubes } => 6 * cubes,
            ImageKind::D2Multisample { .. } => 1,
        }
    }

    pub fn samples(self) -> u32 {
        match self {
            ImageKind::D2Multisample { samples } => samples,
            _ => 1,
        }
    }
}

pub struct ImageDesc<'a> {
    pub name: &'a str,
    pub format: vk::Format,
    pub width: u32,
    pub height: u32,
    pub kind: ImageKind,
    pub usage: vk::ImageUsageFlags,
}

pub struct Image {
    pub raw: vk::Image,
    /// The view shaders sample: 2D, 2D array, cube or cube array.
    pub view: vk::ImageView,
    /// Multiview attachments: one 2D-array view per cube (six layers) of a cube (array),
    /// or one of all layers of a 2D array.
    pub group_views: Vec<vk::ImageView>,
    /// One 2D view per layer: attachments of one-face-per-pass rendering.
    pub layer_views: Vec<vk::ImageView>,
    pub format: vk::Format,
    pub width: u32,
    pub height: u32,
    pub kind: ImageKind,
    pub aspect: vk::ImageAspectFlags,
    state: Cell<ImageState>,
    allocation: Option<Allocation>,
    registry_id: u64,
    pub name: String,
}

impl Image {
    pub fn new(ctx: &Context, desc: &ImageDesc) -> Result<Image> {
        let d = &ctx.device;
        let layers = desc.kind.layers();
        if desc.width == 0 || desc.height == 0 || layers == 0 {
            return Err(Error::invalid(desc.name, "zero-size image"));
        }
        let cube = matches!(desc.kind, ImageKind::Cube | ImageKind::CubeArray { .. });
        let info = vk::ImageCreateInfo::default()
            .flags(if cube { vk::ImageCreateFlags::CUBE_COMPATIBLE } else { vk::ImageCreateFlags::empty() })
            .image_type(vk::ImageType::TYPE_2D)
            .format(desc.format)
            .extent(vk::Extent3D { width: desc.width, height: desc.height, depth: 1 })
            .mip_levels(1)
            .array_layers(layers)
            .samples(crate::vk::pipeline::sample_count_flags(desc.kind.samples()))
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(desc.usage)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        let raw = unsafe { d.create_image(&info, ctx.alloc()) }.call("vkCreateImage")?;
        let req = unsafe { d.get_image_memory_requirements(raw) };
        let allocation = match allocate(ctx, desc.name, req, MemoryLocation::GpuOnly, false) {
            Ok(a) => a,
            Err(e) => {
                unsafe { d.destroy_image(raw, ctx.alloc()) };
                return Err(e);
            }
        };
        let aspect = if is_depth(desc.format) { vk::ImageAspectFlags::DEPTH } else { vk::ImageAspectFlags::COLOR };
        let registry_id = ctx.memory.add(desc.name, req.size);
        let mut img = Image {
            raw,
            view: vk::ImageView::null(),
            group_views: Vec::new(),
            layer_views: Vec::new(),
            format: desc.format,
            width: desc.width,
            height: desc.height,
            kind: desc.kind,
            aspect,
            state: Cell::new(ImageState::UNDEFINED),
            allocation: None,
            registry_id,
            name: desc.name.to_string(),
        };
        // From here on `destroy` cleans up whatever was made.
        img.allocation = Some(allocation);
        let a = img.allocation.as_ref().unwrap();
        if let Err(e) = unsafe { d.bind_image_memory(raw, a.memory(), a.offset()) }.call("vkBindImageMemory") {
            img.destroy(ctx);
            return Err(e);
        }
        ctx.name(raw, desc.name);
        if let Err(e) = img.create_views(ctx, desc.usage) {
            img.destroy(ctx);
            return Err(e);
        }
        Ok(img)
    }

    /// An empty handle that owns nothing (`destroy` is a no-op): for partial construction.
    pub fn placeholder() -> Image {
        Image {
            raw: vk::Image::null(),
            view: vk::ImageView::null(),
            group_views: Vec::new(),
            layer_views: Vec::new(),
            format: vk::Format::UNDEFINED,
            width: 0,
            height: 0,
            kind: ImageKind::D2,
            aspect: vk::ImageAspectFlags::COLOR,
            state: Cell::new(ImageState::UNDEFINED),
            allocation: None,
            registry_id: u64::MAX,
            name: String::new(),
        }
    }

    /// An image the host owns (host-device mode): the library records into it and tracks
    /// its state for the frame, but never creates or destroys it.
    pub fn external(raw: vk::Image, format: vk::Format, width: u32, height: u32, layout: vk::ImageLayout, name: &str) -> Image {
        let mut img = Image::placeholder();
        img.raw = raw;
        img.format = format;
        img.width = width;
        img.height = height;
        img.name = name.to_string();
        img.state.set(ImageState {
            stage: vk::PipelineStageFlags2::ALL_COMMANDS,
            access: vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE,
            layout,
        });
        img
    }

    /// The barrier that leaves the image in `layout` for whatever comes next (host images).
    pub(crate) fn release_to(&self, layout: vk::ImageLayout) -> vk::ImageMemoryBarrier2<'static> {
        let to = ImageState {
            stage: vk::PipelineStageFlags2::ALL_COMMANDS,
            access: vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE,
            layout,
        };
        self.barrier_to(to)
    }

    /// The barrier from the tracked state to `to`; `to` becomes the tracked state.
    fn barrier_to(&self, to: ImageState) -> vk::ImageMemoryBarrier2<'static> {
        let from = self.state.replace(to);
        vk::ImageMemoryBarrier2::default()
            .src_stage_mask(from.stage)
            .src_access_mask(from.access)
            .dst_stage_mask(to.stage)
            .dst_access_mask(to.access)
            .old_layout(from.layout)
            .new_layout(to.layout)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(self.raw)
            .subresource_range(self.range())
    }

    fn create_views(&mut self, ctx: &Context, usage: vk::ImageUsageFlags) -> Result<()> {
        let layers = self.kind.layers();
        let view_type = match self.kind {
            ImageKind::D2 | ImageKind::D2Multisample { .. } => vk::ImageViewType::TYPE_2D,
            ImageKind::D2Array { .. } => vk::ImageViewType::TYPE_2D_ARRAY,
            ImageKind::Cube => vk::ImageViewType::CUBE,
            ImageKind::CubeArray { .. } => vk::ImageViewType::CUBE_ARRAY,
        };
        self.view = self.make_view(ctx, view_type, 0, layers, "")?;
        let attachment = usage.intersects(vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT);
        if attachment && layers > 1 {
            let group = if matches!(self.kind, ImageKind::D2Array { .. }) { layers } else { 6 };
            for g in 0..layers / group {
                let v = self.make_view(ctx, vk::ImageViewType::TYPE_2D_ARRAY, g * group, group, &format!(".group{g}"))?;
                self.group_views.push(v);
            }
            for l in 0..layers {
                let v = self.make_view(ctx, vk::ImageViewType::TYPE_2D, l, 1, &format!(".layer{l}"))?;
                self.layer_views.push(v);
            }
        }
        Ok(())
    }

    fn make_view(&self, ctx: &Context, ty: vk::ImageViewType, base: u32, count: u32, suffix: &str) -> Result<vk::ImageView> {
        let range = vk::ImageSubresourceRange {
            aspect_mask: self.aspect,
            base_mip_level: 0,
            level_count: 1,
            base_array_layer: base,
            layer_count: count,
        };
        let info = vk::ImageViewCreateInfo::default().image(self.raw).view_type(ty).format(self.format).subresource_range(range);
        let v = unsafe { ctx.device.create_image_view(&info, ctx.alloc()) }.call("vkCreateImageView")?;
        ctx.name(v, &format!("{}{suffix}", self.name));
        Ok(v)
    }

    pub fn layers(&self) -> u32 {
        self.kind.layers()
    }

    /// The attachment view of layer `l` (the image's own view when it has one layer).
    pub fn layer_view(&self, l: u32) -> vk::ImageView {
        self.layer_views.get(l as usize).copied().unwrap_or(self.view)
    }

    /// The multiview attachment of group `g` (six faces of cube `g`).
    pub fn group_view(&self, g: u32) -> vk::ImageView {
        self.group_views.get(g as usize).copied().unwrap_or(self.view)
    }

    pub fn range(&self) -> vk::ImageSubresourceRange {
        vk::ImageSubresourceRange {
            aspect_mask: self.aspect,
            base_mip_level: 0,
            level_count: 1,
            base_array_layer: 0,
            layer_count: self.layers(),
        }
    }

    pub fn state(&self) -> ImageState {
        self.state.get()
    }

    /// Declares the image's state as the host left it (images that come from outside).
    pub fn assume_state(&self, s: ImageState) {
        self.state.set(s)
    }

    /// The barrier that makes the image ready for `access`, or `None` when no barrier is
    /// needed (a read after a read in the same layout). Updates the tracked state.
    pub(crate) fn transition(&self, access: Access) -> Option<vk::ImageMemoryBarrier2<'static>> {
        let from = self.state.get();
        let to = access.state();
        let from_writes = from.access.intersects(
            vk::AccessFlags2::SHADER_STORAGE_WRITE
                | vk::AccessFlags2::COLOR_ATTACHMENT_WRITE
                | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE
                | vk::AccessFlags2::TRANSFER_WRITE,
        );
        if from.layout == to.layout && !from_writes && !access.writes() && from.stage.contains(to.stage) {
            // Read after read at stages the last barrier already reached: widen the tracked
            // accesses so a later write waits on all readers.
            self.state.set(ImageState { stage: from.stage | to.stage, access: from.access | to.access, layout: from.layout });
            return None;
        }
        if from.layout == to.layout && !from_writes && !access.writes() {
            // A read at a stage the last barrier did not reach (a compute pass sampling what
            // fragment shaders sampled): a barrier from those readers chains the last write's
            // (or layout transition's) visibility on to the new stage; both keep reading.
            let b = self.barrier_to(to);
            self.state.set(ImageState { stage: from.stage | to.stage, access: from.access | to.access, layout: from.layout });
            return Some(b);
        }
        Some(self.barrier_to(to))
    }

    pub fn byte_size(&self) -> u64 {
        self.width as u64 * self.height as u64 * self.layers() as u64 * self.kind.samples() as u64 * format_bytes(self.format) as u64
    }

    pub fn destroy(&mut self, ctx: &Context) {
        let d = &ctx.device;
        unsafe {
            for v in self.layer_views.drain(..).chain(self.group_views.drain(..)) {
                d.destroy_image_view(v, ctx.alloc());
            }
            if self.view != vk::ImageView::null() {
                d.destroy_image_view(self.view, ctx.alloc());
            }
            self.view = vk::ImageView::null();
            if let Some(a) = self.allocation.take() {
                d.destroy_image(self.raw, ctx.alloc());
                if let Some(al) = ctx.allocator().as_mut() {
                    let _ = al.free(a);
                }
                ctx.memory.remove(self.registry_id);
                self.raw = vk::Image::null();
            }
        }
    }
}

pub fn is_depth(f: vk::Format) -> bool {
    matches!(f, vk::Format::D32_SFLOAT | vk::Format::D16_UNORM | vk::Format::D24_UNORM_S8_UINT | vk::Format::D32_SFLOAT_S8_UINT)
}

/// Bytes per texel of the formats the library uses.
pub fn format_bytes(f: vk::Format) -> u32 {
    match f {
        vk::Format::R32G32B32A32_SFLOAT => 16,
        vk::Format::R16G16B16A16_SFLOAT => 8,
        vk::Format::R32_SFLOAT | vk::Format::D32_SFLOAT | vk::Format::R8G8B8A8_SRGB | vk::Format::R8G8B8A8_UNORM | vk::Format::R32_UINT => {
            4
        }
        vk::Format::R16_SFLOAT | vk::Format::D16_UNORM => 2,
        _ => 4,
    }
}
