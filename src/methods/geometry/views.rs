//! The GPU side of planar mirrors' views (§5): a scratch target each mirrored view renders
//! into (the camera target's format, size and samples, so that every camera pass draws into
//! it with its own pipeline), and the layered image the views are copied (or, with MSAA,
//! resolved) into, one layer per view: a view samples its children's layers while it renders
//! into the scratch target, and is copied into its own layer afterwards.

use ash::vk;
use glam::{Mat4, Vec3};

use super::mirror::{Limits, MirrorFrame, Rect};
use crate::frame::direct::{DEPTH_FORMAT, TARGET_FORMAT};
use crate::frame::layout::{FLAG_MIRROR_VIEW, MIRROR_COUNT_SHIFT, MIRROR_LAYER_SHIFT};
use crate::frame::stage::Maps;
use crate::frame::FrameInputs;
use crate::plan::Plan;
use crate::scene::Scene;
use crate::vk::pipeline::{graphics_pipeline, Blend, DepthOp, GraphicsDesc, Multisample, VertexInput};
use crate::vk::{Access, Context, Image, ImageDesc, ImageKind, Recorder};
use crate::Result;

pub struct MirrorViews {
    meshes: Vec<usize>,
    limits: Limits,
    pub scratch: Image,
    pub depth: Image,
    samples: u32,
    /// `geometry.stencil`: the mirror drawn from the parent view at the farthest depth.
    mask: vk::Pipeline,
    /// This frame's views (planned when the view table is written).
    pub frame: MirrorFrame,
}

impl MirrorViews {
    /// The views' images for a plan with planar mirrors (`None` without): the layered
    /// image goes into `maps` (set 0, binding 9), the scratch target stays here.
    pub fn new(
        ctx: &Context,
        plan: &Plan,
        size: (u32, u32),
        multisample: Multisample,
        layout: vk::PipelineLayout,
        maps: &mut Maps,
    ) -> Result<Option<MirrorViews>> {
        let layers = plan.mirror_layers;
        if plan.mirrors.is_empty() || layers == 0 {
            return Ok(None);
        }
        let (width, height) = size;
        let usage = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST;
        let desc =
            ImageDesc { name: "geometry.mirror_views", format: TARGET_FORMAT, width, height, kind: ImageKind::D2Array { layers }, usage };
        maps.mirror_views = Some(Image::new(ctx, &desc)?);
        let samples = multisample.samples;
        let kind = if samples > 1 { ImageKind::D2Multisample { samples } } else { ImageKind::D2 };
        let mut me = MirrorViews {
            meshes: plan.mirrors.clone(),
            limits: Limits { depth: plan.quality.frame.depth, budget: plan.quality.geometry.mirror_budget, layers },
            scratch: Image::placeholder(),
            depth: Image::placeholder(),
            samples,
            mask: vk::Pipeline::null(),
            frame: MirrorFrame::default(),
        };
        let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC;
        let made = Image::new(ctx, &ImageDesc { name: "geometry.mirror_view", format: TARGET_FORMAT, width, height, kind, usage })
            .and_then(|s| {
                me.scratch = s;
                let usage = vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT;
                Image::new(ctx, &ImageDesc { name: "geometry.mirror_view.depth", format: DEPTH_FORMAT, width, height, kind, usage })
            })
            .and_then(|d| {
                me.depth = d;
                let formats = [TARGET_FORMAT];
                let desc = GraphicsDesc {
                    name: "geometry.stencil",
                    vertex: "scene/mesh.vert",
                    fragment: "geometry/map_mask.frag",
                    vertex_input: VertexInput::Mesh,
                    color_formats: &formats,
                    depth_format: Some(DEPTH_FORMAT),
                    depth_test: true,
                    depth_write: true,
                    view_mask: 0,
                    cull: vk::CullModeFlags::NONE,
                    multisample: Multisample { samples, per_sample: false },
                    blend: Blend::Replace,
                    depth_op: DepthOp::Always,
                };
                me.mask = graphics_pipeline(ctx, layout, &desc)?;
                Ok(Image::placeholder())
            });
        match made {
            Ok(_) => Ok(Some(me)),
            Err(e) => {
                me.destroy(ctx);
                Err(e)
            }
        }
    }

    /// Plans this frame's views from the camera (`view_proj`, `eye`, the frustum's corner
    /// cosine) over the current scene.
    pub fn plan_frame(&mut self, scene: &Scene, view_proj: Mat4, eye: Vec3, cos_corner: f32) {
        let size = (self.scratch.width, self.scratch.height);
        self.frame = MirrorFrame::plan(scene, &self.meshes, view_proj, eye, size, cos_corner, self.limits);
    }

    /// The push flags of the planar mirrors the camera (`None`) or view `v` sees: which
    /// layer of which image holds each one's reflection. Mirrors not listed fall back.
    pub fn child_flags(&self, v: Option<usize>) -> Vec<(usize, u32)> {
        let flags = |first: u32, count: u32| FLAG_MIRROR_VIEW | (first << MIRROR_LAYER_SHIFT) | (count << MIRROR_COUNT_SHIFT);
        self.frame.children(v).into_iter().map(|(mesh, first, count)| (mesh, flags(first, count))).collect()
    }

    /// (layers allocated, bytes of one view's layer, bytes of the scratch colour and depth
    /// targets): the layered image holds one single-sample RGBA32F layer per view; the
    /// scratch targets have the camera's samples.
    pub fn memory(&self) -> (u32, u64, u64) {
        let pixels = self.scratch.width as u64 * self.scratch.height as u64;
        let colour = crate::vk::format_bytes(TARGET_FORMAT) as u64;
        let depth = crate::vk::format_bytes(DEPTH_FORMAT) as u64;
        (self.limits.layers, pixels * colour, pixels * self.samples as u64 * (colour + depth))
    }

    /// Copies (or, with MSAA, resolves) the scratch target's `rect` into layer `layer` of
    /// `dst` (the views' layered image).
    pub fn record_store(&mut self, rec: &mut Recorder, dst: &mut Image, layer: u32, rect: Rect) {
        let open = rec.pass("geometry.mirror_view").reads(&self.scratch, Access::TransferSrc).writes(dst, Access::TransferDst).begin();
        let sub = |base_array_layer| vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer,
            layer_count: 1,
        };
        let offset = vk::Offset3D { x: rect.x0 as i32, y: rect.y0 as i32, z: 0 };
        let extent = vk::Extent3D { width: rect.x1 - rect.x0, height: rect.y1 - rect.y0, depth: 1 };
        let (s, d) = (vk::ImageLayout::TRANSFER_SRC_OPTIMAL, vk::ImageLayout::TRANSFER_DST_OPTIMAL);
        let (ctx, cmd) = (rec.ctx, rec.cmd);
        unsafe {
            if self.samples > 1 {
                let region = vk::ImageResolve {
                    src_subresource: sub(0),
                    src_offset: offset,
                    dst_subresource: sub(layer),
                    dst_offset: offset,
                    extent,
                };
                ctx.device.cmd_resolve_image(cmd, self.scratch.raw, s, dst.raw, d, &[region]);
            } else {
                let region =
                    vk::ImageCopy { src_subresource: sub(0), src_offset: offset, dst_subresource: sub(layer), dst_offset: offset, extent };
                ctx.device.cmd_copy_image(cmd, self.scratch.raw, s, dst.raw, d, &[region]);
            }
        }
        rec.end(open);
    }

    /// `geometry.stencil`: clears the scratch depth within `area` to the nearest depth and
    /// draws mesh `mesh` (the view's mirror, or its refractor) from its parent's view
    /// `parent_view` at the farthest: the view's passes then draw on the mirror's pixels
    /// only (the depth buffer is the mask, as a stencil would be).
    pub fn record_stencil(&mut self, rec: &mut Recorder, f: &FrameInputs, parent_view: u32, mesh: usize, area: vk::Rect2D) {
        // Its own profiler row, not the views' scope.
        let scope = rec.scope.take();
        let open = rec
            .pass("geometry.stencil")
            .writes(&mut self.scratch, Access::ColorAttachment)
            .writes(&mut self.depth, Access::DepthAttachment)
            .begin();
        let (ctx, cmd) = (rec.ctx, rec.cmd);
        crate::frame::begin_camera_rendering(ctx, cmd, &self.scratch, &self.depth, area, false);
        let attachment = vk::ClearAttachment {
            aspect_mask: vk::ImageAspectFlags::DEPTH,
            color_attachment: 0,
            clear_value: vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 } },
        };
        let rect = vk::ClearRect { rect: area, base_array_layer: 0, layer_count: 1 };
        unsafe { ctx.device.cmd_clear_attachments(cmd, &[attachment], &[rect]) };
        f.bind(ctx, cmd, self.mask);
        for d in f.scene.draws.iter().filter(|d| d.mesh as usize == mesh) {
            f.push_flags(ctx, cmd, parent_view, d.mesh, f.flags);
            unsafe { ctx.device.cmd_draw_indexed(cmd, d.index_count, 1, d.first_index, d.vertex_offset, 0) };
        }
        unsafe { ctx.device.cmd_end_rendering(cmd) };
        rec.end(open);
        rec.scope = scope;
    }

    pub fn destroy(&mut self, ctx: &Context) {
        self.scratch.destroy(ctx);
        self.depth.destroy(ctx);
        crate::frame::destroy_pipelines(ctx, &mut [self.mask]);
    }
}

/// The cosine of the angle between a perspective projection's axis and its frustum's corner
/// rays (`proj` the camera's, as `Renderer::camera_view_proj` builds it).
pub fn cos_corner(yfov: f32, aspect: f32) -> f32 {
    let ty = (0.5 * yfov).tan();
    let tx = ty * aspect;
    1.0 / (1.0 + tx * tx + ty * ty).sqrt()
}

/// A rectangle as the render area it is.
pub fn render_area(r: Rect) -> vk::Rect2D {
    vk::Rect2D { offset: vk::Offset2D { x: r.x0 as i32, y: r.y0 as i32 }, extent: vk::Extent2D { width: r.x1 - r.x0, height: r.y1 - r.y0 } }
}
