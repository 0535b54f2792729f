//! The window's side of the viewer: a surface and swapchain on the library's own device,
//! one frame in flight (the renderer's rule), and the frame's command buffer: the renderer
//! records into it and copies its image into the swapchain image (`Renderer::record_into`,
//! the same path a host engine takes), the overlay draws on top, and the image is presented.

use ash::vk;
use specula::error::VkCall;
use specula::vk::{Context, Image};

/// Formats the swapchain may take, best first: 8-bit sRGB, so the linear radiance the
/// renderer blits in is encoded on the way, as `specula render` encodes its PNGs.
const FORMATS: [vk::Format; 2] = [vk::Format::B8G8R8A8_SRGB, vk::Format::R8G8B8A8_SRGB];

pub struct Presenter {
    surface_fn: ash::khr::surface::Instance,
    swapchain_fn: ash::khr::swapchain::Device,
    pub surface: vk::SurfaceKHR,
    swapchain: vk::SwapchainKHR,
    images: Vec<vk::Image>,
    views: Vec<vk::ImageView>,
    pub format: vk::Format,
    pub extent: vk::Extent2D,
    pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
    acquired: vk::Semaphore,
    /// One per swapchain image: presentation waits on the image's own.
    rendered: Vec<vk::Semaphore>,
    pub out_of_date: bool,
}

/// The image a frame draws into.
pub struct Target {
    pub index: u32,
    pub image: vk::Image,
    pub view: vk::ImageView,
}

impl Presenter {
    /// The swapchain for `surface` at `size` (the surface's own extent where it fixes one).
    pub fn new(ctx: &Context, surface: vk::SurfaceKHR, size: (u32, u32)) -> specula::Result<Presenter> {
        let surface_fn = ash::khr::surface::Instance::new(&ctx.entry, &ctx.instance);
        let supported = unsafe { surface_fn.get_physical_device_surface_support(ctx.physical, ctx.queue_family, surface) }
            .call("vkGetPhysicalDeviceSurfaceSupportKHR")?;
        if !supported {
            unsafe { surface_fn.destroy_surface(surface, None) };
            return Err(specula::Error::invalid(
                "window",
                format!("{}'s graphics queue family {} cannot present to this window", ctx.device_name, ctx.queue_family),
            ));
        }
        let d = &ctx.device;
        let pool = unsafe {
            d.create_command_pool(
                &vk::CommandPoolCreateInfo::default()
                    .queue_family_index(ctx.queue_family)
                    .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER),
                None,
            )
        }
        .call("vkCreateCommandPool")?;
        let mut p = Presenter {
            surface_fn,
            swapchain_fn: ash::khr::swapchain::Device::new(&ctx.instance, d),
            surface,
            swapchain: vk::SwapchainKHR::null(),
            images: Vec::new(),
            views: Vec::new(),
            format: vk::Format::UNDEFINED,
            extent: vk::Extent2D::default(),
            pool,
            cmd: vk::CommandBuffer::null(),
            fence: vk::Fence::null(),
            acquired: vk::Semaphore::null(),
            rendered: Vec::new(),
            out_of_date: false,
        };
        if let Err(e) = p.init(ctx, size) {
            p.destroy(ctx);
            return Err(e);
        }
        Ok(p)
    }

    fn init(&mut self, ctx: &Context, size: (u32, u32)) -> specula::Result<()> {
        let d = &ctx.device;
        self.cmd = unsafe {
            d.allocate_command_buffers(
                &vk::CommandBufferAllocateInfo::default()
                    .command_pool(self.pool)
                    .level(vk::CommandBufferLevel::PRIMARY)
                    .command_buffer_count(1),
            )
        }
        .call("vkAllocateCommandBuffers")?[0];
        self.fence =
            unsafe { d.create_fence(&vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED), None) }.call("vkCreateFence")?;
        self.acquired = unsafe { d.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }.call("vkCreateSemaphore")?;
        self.recreate(ctx, size)
    }

    /// (Re)creates the swapchain at `size`, or the surface's fixed extent. Waits for the
    /// device first: the old images may still be in use.
    pub fn recreate(&mut self, ctx: &Context, size: (u32, u32)) -> specula::Result<()> {
        let d = &ctx.device;
        ctx.wait_idle()?;
        let caps = unsafe { self.surface_fn.get_physical_device_surface_capabilities(ctx.physical, self.surface) }
            .call("vkGetPhysicalDeviceSurfaceCapabilitiesKHR")?;
        let formats = unsafe { self.surface_fn.get_physical_device_surface_formats(ctx.physical, self.surface) }
            .call("vkGetPhysicalDeviceSurfaceFormatsKHR")?;
        let blit_dst = |f: vk::Format| {
            let p = unsafe { ctx.instance.get_physical_device_format_properties(ctx.physical, f) };
            p.optimal_tiling_features.contains(vk::FormatFeatureFlags::BLIT_DST | vk::FormatFeatureFlags::COLOR_ATTACHMENT)
        };
        let chosen = FORMATS
            .iter()
            .find_map(|f| formats.iter().find(|s| s.format == *f && s.color_space == vk::ColorSpaceKHR::SRGB_NONLINEAR && blit_dst(*f)))
            .copied()
            .ok_or_else(|| {
                let offered: Vec<String> = formats.iter().map(|f| format!("{:?}", f.format)).collect();
                specula::Error::invalid(
                    "window",
                    format!("it offers no 8-bit sRGB swapchain format the renderer can blit into (offered: {})", offered.join(", ")),
                )
            })?;
        let need = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_DST;
        if !caps.supported_usage_flags.contains(need) {
            return Err(specula::Error::invalid(
                "window",
                format!("its swapchain images cannot be transfer destinations and colour attachments ({:?})", caps.supported_usage_flags),
            ));
        }
        let extent = if caps.current_extent.width != u32::MAX {
            caps.current_extent
        } else {
            vk::Extent2D {
                width: size.0.clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                height: size.1.clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            }
        };
        let count = if caps.max_image_count == 0 { caps.min_image_count + 1 } else { (caps.min_image_count + 1).min(caps.max_image_count) };
        let old = self.swapchain;
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(self.surface)
            .min_image_count(count)
            .image_format(chosen.format)
            .image_color_space(chosen.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(need)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(vk::CompositeAlphaFlagsKHR::OPAQUE)
            .present_mode(vk::PresentModeKHR::FIFO)
            .clipped(true)
            .old_swapchain(old);
        self.destroy_images(ctx);
        if extent.width == 0 || extent.height == 0 {
            // Minimised: nothing to draw into until the window returns.
            self.extent = extent;
            return Ok(());
        }
        self.swapchain = unsafe { self.swapchain_fn.create_swapchain(&info, None) }.call("vkCreateSwapchainKHR")?;
        if old != vk::SwapchainKHR::null() {
            unsafe { self.swapchain_fn.destroy_swapchain(old, None) };
        }
        self.format = chosen.format;
        self.extent = extent;
        self.images = unsafe { self.swapchain_fn.get_swapchain_images(self.swapchain) }.call("vkGetSwapchainImagesKHR")?;
        for (i, &image) in self.images.iter().enumerate() {
            ctx.name(image, &format!("swapchain[{i}]"));
            let view = unsafe {
                d.create_image_view(
                    &vk::ImageViewCreateInfo::default()
                        .image(image)
                        .view_type(vk::ImageViewType::TYPE_2D)
                        .format(chosen.format)
                        .subresource_range(color_range()),
                    None,
                )
            }
            .call("vkCreateImageView")?;
            self.views.push(view);
            let s = unsafe { d.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }.call("vkCreateSemaphore")?;
            self.rendered.push(s);
        }
        self.out_of_date = false;
        Ok(())
    }

    fn destroy_images(&mut self, ctx: &Context) {
        let d = &ctx.device;
        unsafe {
            for v in self.views.drain(..) {
                d.destroy_image_view(v, None);
            }
            for s in self.rendered.drain(..) {
                d.destroy_semaphore(s, None);
            }
        }
        self.images.clear();
    }

    /// Waits for the frame in flight (one at a time: the renderer writes its view table from
    /// the host while recording).
    pub fn wait(&self, ctx: &Context) -> specula::Result<()> {
        unsafe { ctx.device.wait_for_fences(&[self.fence], true, u64::MAX) }.call("vkWaitForFences")
    }

    /// The next image to draw into; `None` when the swapchain must be recreated first.
    pub fn acquire(&mut self) -> specula::Result<Option<Target>> {
        if self.out_of_date || self.swapchain == vk::SwapchainKHR::null() {
            return Ok(None);
        }
        match unsafe { self.swapchain_fn.acquire_next_image(self.swapchain, u64::MAX, self.acquired, vk::Fence::null()) } {
            Ok((index, _suboptimal)) => {
                let i = index as usize;
                Ok(Some(Target { index, image: self.images[i], view: self.views[i] }))
            }
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => {
                self.out_of_date = true;
                Ok(None)
            }
            Err(e) => Err(e).call("vkAcquireNextImageKHR"),
        }
    }

    /// The frame's command buffer, reset and begun.
    pub fn begin(&self, ctx: &Context) -> specula::Result<vk::CommandBuffer> {
        let d = &ctx.device;
        unsafe {
            d.reset_command_buffer(self.cmd, vk::CommandBufferResetFlags::empty()).call("vkResetCommandBuffer")?;
            d.begin_command_buffer(self.cmd, &vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT))
                .call("vkBeginCommandBuffer")?;
        }
        Ok(self.cmd)
    }

    /// Leaves the target presentable, submits the frame and presents it.
    pub fn submit_and_present(&mut self, ctx: &Context, target: &Target) -> specula::Result<()> {
        let d = &ctx.device;
        let queue = ctx.queue.ok_or_else(|| specula::Error::invalid("window", "the viewer's context has no queue"))?;
        let to_present = [vk::ImageMemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT)
            .src_access_mask(vk::AccessFlags2::COLOR_ATTACHMENT_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags2::NONE)
            .dst_access_mask(vk::AccessFlags2::NONE)
            .old_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .new_layout(vk::ImageLayout::PRESENT_SRC_KHR)
            .image(target.image)
            .subresource_range(color_range())];
        unsafe {
            d.cmd_pipeline_barrier2(self.cmd, &vk::DependencyInfo::default().image_memory_barriers(&to_present));
            d.end_command_buffer(self.cmd).call("vkEndCommandBuffer")?;
            d.reset_fences(&[self.fence]).call("vkResetFences")?;
        }
        let rendered = self.rendered[target.index as usize];
        let wait = [vk::SemaphoreSubmitInfo::default().semaphore(self.acquired).stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)];
        let signal = [vk::SemaphoreSubmitInfo::default().semaphore(rendered).stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)];
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(self.cmd)];
        let submit = [vk::SubmitInfo2::default().wait_semaphore_infos(&wait).command_buffer_infos(&cmds).signal_semaphore_infos(&signal)];
        unsafe { d.queue_submit2(queue, &submit, self.fence) }.call("vkQueueSubmit2")?;
        let (swapchains, indices, waits) = ([self.swapchain], [target.index], [rendered]);
        let present = vk::PresentInfoKHR::default().wait_semaphores(&waits).swapchains(&swapchains).image_indices(&indices);
        match unsafe { self.swapchain_fn.queue_present(queue, &present) } {
            Ok(false) => Ok(()),
            Ok(true) | Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => {
                self.out_of_date = true;
                Ok(())
            }
            Err(e) => Err(e).call("vkQueuePresentKHR"),
        }
    }

    /// The swapchain image as the renderer sees a host image: it copies into it and leaves
    /// it ready for the overlay's colour attachment writes.
    pub fn host_image(&self, target: &Target) -> Image {
        Image::external(target.image, self.format, self.extent.width, self.extent.height, vk::ImageLayout::UNDEFINED, "swapchain")
    }

    pub fn pool(&self) -> vk::CommandPool {
        self.pool
    }

    /// Destroys everything but the surface's instance; the device must be idle.
    pub fn destroy(&mut self, ctx: &Context) {
        let _ = ctx.wait_idle();
        self.destroy_images(ctx);
        let d = &ctx.device;
        unsafe {
            if self.swapchain != vk::SwapchainKHR::null() {
                self.swapchain_fn.destroy_swapchain(self.swapchain, None);
                self.swapchain = vk::SwapchainKHR::null();
            }
            d.destroy_semaphore(self.acquired, None);
            d.destroy_fence(self.fence, None);
            d.destroy_command_pool(self.pool, None);
            self.surface_fn.destroy_surface(self.surface, None);
        }
        (self.acquired, self.fence, self.pool, self.surface) =
            (vk::Semaphore::null(), vk::Fence::null(), vk::CommandPool::null(), vk::SurfaceKHR::null());
    }
}

pub fn color_range() -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange {
        aspect_mask: vk::ImageAspectFlags::COLOR,
        base_mip_level: 0,
        level_count: 1,
        base_array_layer: 0,
        layer_count: 1,
    }
}
