//! Records passes into a command buffer the library does not own. A pass is the unit of
//! profiling: it is bracketed by a debug label and two GPU timestamps under a stable
//! dotted name (`envmap.generate` …), and it declares what it reads and writes, from
//! which the recorder derives the barriers and layout transitions.

use std::time::Instant;

use ash::vk;

use super::{Access, Context, Image};
use crate::error::{Result, VkCall};

/// One pass of a frame: its stable name, GPU time between its timestamps, and the CPU
/// time spent recording it.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PassTiming {
    pub name: String,
    pub gpu_ms: f64,
    pub cpu_ms: f64,
    /// GPU start relative to the frame's first pass, for trace timelines.
    pub gpu_start_ms: f64,
}

/// A timestamp query pool with two queries per pass.
pub struct Profiler {
    pool: vk::QueryPool,
    capacity: u32,
    names: Vec<&'static str>,
    cpu_ms: Vec<f64>,
    /// Passes of the last frame beyond `capacity`: recorded, not timed.
    untimed: u32,
}

impl Profiler {
    pub fn new(ctx: &Context, max_passes: u32) -> Result<Profiler> {
        let info = vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::TIMESTAMP).query_count(2 * max_passes);
        let pool = unsafe { ctx.device.create_query_pool(&info, ctx.alloc()) }.call("vkCreateQueryPool")?;
        ctx.name(pool, "profiler.timestamps");
        Ok(Profiler { pool, capacity: max_passes, names: Vec::new(), cpu_ms: Vec::new(), untimed: 0 })
    }

    /// An empty profiler that owns nothing: for partial construction.
    pub fn placeholder() -> Profiler {
        Profiler { pool: vk::QueryPool::null(), capacity: 0, names: Vec::new(), cpu_ms: Vec::new(), untimed: 0 }
    }

    /// Reads the timestamps of the last recorded frame; the GPU must have finished it.
    pub fn results(&self, ctx: &Context) -> Result<Vec<PassTiming>> {
        let n = self.names.len() as u32;
        if n == 0 {
            return Ok(Vec::new());
        }
        let mut ticks = vec![0u64; 2 * n as usize];
        unsafe { ctx.device.get_query_pool_results(self.pool, 0, &mut ticks, vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT) }
            .call("vkGetQueryPoolResults")?;
        let period = ctx.timestamp_period_ns() * 1e-6;
        let t0 = ticks[0];
        Ok(self
            .names
            .iter()
            .enumerate()
            .map(|(i, name)| PassTiming {
                name: name.to_string(),
                gpu_ms: ticks[2 * i + 1].saturating_sub(ticks[2 * i]) as f64 * period,
                cpu_ms: self.cpu_ms[i],
                gpu_start_ms: ticks[2 * i].saturating_sub(t0) as f64 * period,
            })
            .collect())
    }

    /// The last recorded frame's timings if the GPU has finished it, without waiting
    /// (host-device mode: the host decides when frames complete).
    pub fn poll(&self, ctx: &Context) -> Result<Option<Vec<PassTiming>>> {
        let n = self.names.len() as u32;
        if n == 0 {
            return Ok(None);
        }
        let mut ticks = vec![0u64; 2 * n as usize];
        match unsafe { ctx.device.get_query_pool_results(self.pool, 0, &mut ticks, vk::QueryResultFlags::TYPE_64) } {
            Ok(()) => self.results(ctx).map(Some),
            Err(vk::Result::NOT_READY) => Ok(None),
            Err(e) => Err(e).call("vkGetQueryPoolResults"),
        }
    }

    /// How many passes of the last frame went untimed (the query pool was full).
    pub fn untimed(&self) -> u32 {
        self.untimed
    }

    pub fn destroy(&mut self, ctx: &Context) {
        if self.pool != vk::QueryPool::null() {
            unsafe { ctx.device.destroy_query_pool(self.pool, ctx.alloc()) };
            self.pool = vk::QueryPool::null();
        }
    }
}

/// Records one frame's passes into `cmd`.
pub struct Recorder<'a> {
    pub ctx: &'a Context,
    pub cmd: vk::CommandBuffer,
    profiler: &'a mut Profiler,
    /// While set, every pass is profiled under this name (a mirrored view's passes count as
    /// `geometry.mirror_view`).
    pub scope: Option<&'static str>,
}

/// An open pass, returned by `PassBuilder::begin` and closed by `Recorder::end`.
#[must_use = "close the pass with Recorder::end"]
pub struct OpenPass {
    index: u32,
    cpu_start: Instant,
}

pub struct PassBuilder<'r, 'a> {
    rec: &'r mut Recorder<'a>,
    name: &'static str,
    barriers: Vec<vk::ImageMemoryBarrier2<'static>>,
    memory_barrier: bool,
}

impl<'a> Recorder<'a> {
    /// Starts a frame: resets the profiler's queries (outside any render pass).
    pub fn new(ctx: &'a Context, cmd: vk::CommandBuffer, profiler: &'a mut Profiler) -> Recorder<'a> {
        unsafe { ctx.device.cmd_reset_query_pool(cmd, profiler.pool, 0, 2 * profiler.capacity) };
        profiler.names.clear();
        profiler.cpu_ms.clear();
        profiler.untimed = 0;
        Recorder { ctx, cmd, profiler, scope: None }
    }

    /// Continues recording passes of a frame that `new` started (same query pool).
    pub fn resume(ctx: &'a Context, cmd: vk::CommandBuffer, profiler: &'a mut Profiler) -> Recorder<'a> {
        Recorder { ctx, cmd, profiler, scope: None }
    }

    pub fn pass<'r>(&'r mut self, name: &'static str) -> PassBuilder<'r, 'a> {
        PassBuilder { rec: self, name, barriers: Vec::new(), memory_barrier: false }
    }

    /// A barrier inside a pass: `image` is about to be used as `access` again (e.g. a depth
    /// buffer reused for the next cube face).
    pub fn barrier(&self, image: &mut Image, access: Access) {
        if let Some(b) = image.transition(access) {
            let barriers = [b];
            unsafe { self.ctx.device.cmd_pipeline_barrier2(self.cmd, &vk::DependencyInfo::default().image_memory_barriers(&barriers)) };
        }
    }

    /// A global memory barrier from the (stages, accesses) `src` to `dst` (buffers written by
    /// one kernel or transfer and read by the next).
    pub fn memory_barrier(&self, src: (vk::PipelineStageFlags2, vk::AccessFlags2), dst: (vk::PipelineStageFlags2, vk::AccessFlags2)) {
        let b = [vk::MemoryBarrier2::default().src_stage_mask(src.0).src_access_mask(src.1).dst_stage_mask(dst.0).dst_access_mask(dst.1)];
        unsafe { self.ctx.device.cmd_pipeline_barrier2(self.cmd, &vk::DependencyInfo::default().memory_barriers(&b)) };
    }

    pub fn end(&mut self, pass: OpenPass) {
        let (d, cmd) = (&self.ctx.device, self.cmd);
        if pass.index == u32::MAX {
            self.ctx.end_label(cmd);
            return;
        }
        unsafe { d.cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::ALL_COMMANDS, self.profiler.pool, 2 * pass.index + 1) };
        self.ctx.end_label(cmd);
        self.profiler.cpu_ms.push(pass.cpu_start.elapsed().as_secs_f64() * 1e3);
    }
}

impl PassBuilder<'_, '_> {
    /// The pass samples or copies from `image`.
    pub fn reads(mut self, image: &Image, access: Access) -> Self {
        self.barriers.extend(image.transition(access));
        self
    }

    /// The pass writes `image` (a `&mut`, so who changes what is visible in the types).
    pub fn writes(mut self, image: &mut Image, access: Access) -> Self {
        self.barriers.extend(image.transition(access));
        self
    }

    /// The pass reads buffers that earlier commands of this frame wrote (copies, compute).
    pub fn after_buffer_writes(mut self) -> Self {
        self.memory_barrier = true;
        self
    }

    pub fn begin(self) -> OpenPass {
        let PassBuilder { rec, name, barriers, memory_barrier } = self;
        let name = rec.scope.unwrap_or(name);
        let timed = (rec.profiler.names.len() as u32) < rec.profiler.capacity;
        // Beyond the query pool's capacity a pass is recorded untimed (counted), never refused.
        let index = if timed { rec.profiler.names.len() as u32 } else { u32::MAX };
        let cpu_start = Instant::now();
        let (ctx, cmd) = (rec.ctx, rec.cmd);
        ctx.begin_label(cmd, name);
        if timed {
            unsafe { ctx.device.cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::ALL_COMMANDS, rec.profiler.pool, 2 * index) };
        } else {
            rec.profiler.untimed += 1;
        }
        // Always a barrier after the first timestamp: without one lavapipe lets compute
        // work slip out from between the two timestamps (LAVAPIPE-NOTES).
        let mem = [vk::MemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
            .src_access_mask(if memory_barrier { vk::AccessFlags2::MEMORY_WRITE } else { vk::AccessFlags2::NONE })
            .dst_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
            .dst_access_mask(if memory_barrier {
                vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE
            } else {
                vk::AccessFlags2::NONE
            })];
        let dep = vk::DependencyInfo::default().memory_barriers(&mem).image_memory_barriers(&barriers);
        unsafe { ctx.device.cmd_pipeline_barrier2(cmd, &dep) };
        if timed {
            rec.profiler.names.push(name);
        }
        OpenPass { index, cpu_start }
    }
}

/// Starts dynamic rendering into `color` (one layer, or all layers with a view mask) and
/// `depth`, cleared; sets a full viewport.
pub struct Target<'a> {
    pub color: &'a [vk::ImageView],
    pub depth: Option<vk::ImageView>,
    pub width: u32,
    pub height: u32,
    pub view_mask: u32,
    pub layer_count: u32,
    pub clear_color: [f32; 4],
    /// Clear (true) or keep (false) the attachments' contents.
    pub clear: bool,
}

impl<'a> Target<'a> {
    /// One layer of `color` (and `depth`) of `width` × `height`, cleared to zero.
    pub fn cleared(color: &'a [vk::ImageView], depth: Option<vk::ImageView>, width: u32, height: u32) -> Target<'a> {
        Target { color, depth, width, height, view_mask: 0, layer_count: 1, clear_color: [0.0; 4], clear: true }
    }
}

pub fn begin_rendering(ctx: &Context, cmd: vk::CommandBuffer, t: &Target) {
    let area = vk::Rect2D { offset: vk::Offset2D::default(), extent: vk::Extent2D { width: t.width, height: t.height } };
    begin_rendering_in(ctx, cmd, t, area);
}

/// `begin_rendering` within `area` (render area and scissor; the viewport stays the whole
/// attachment, so that pixels keep their positions).
pub fn begin_rendering_in(ctx: &Context, cmd: vk::CommandBuffer, t: &Target, area: vk::Rect2D) {
    let load = if t.clear { vk::AttachmentLoadOp::CLEAR } else { vk::AttachmentLoadOp::LOAD };
    let colors: Vec<_> = t
        .color
        .iter()
        .map(|&v| {
            vk::RenderingAttachmentInfo::default()
                .image_view(v)
                .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                .load_op(load)
                .store_op(vk::AttachmentStoreOp::STORE)
                .clear_value(vk::ClearValue { color: vk::ClearColorValue { float32: t.clear_color } })
        })
        .collect();
    // Reversed-Z: clear depth to 0 (infinitely far).
    let depth = t.depth.map(|v| {
        vk::RenderingAttachmentInfo::default()
            .image_view(v)
            .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
            .load_op(load)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 0.0, stencil: 0 } })
    });
    let mut info =
        vk::RenderingInfo::default().render_area(area).layer_count(t.layer_count).view_mask(t.view_mask).color_attachments(&colors);
    if let Some(d) = depth.as_ref() {
        info = info.depth_attachment(d);
    }
    unsafe {
        ctx.device.cmd_begin_rendering(cmd, &info);
        let vp = vk::Viewport { x: 0.0, y: 0.0, width: t.width as f32, height: t.height as f32, min_depth: 0.0, max_depth: 1.0 };
        ctx.device.cmd_set_viewport(cmd, 0, &[vp]);
        ctx.device.cmd_set_scissor(cmd, 0, &[area]);
    }
}
