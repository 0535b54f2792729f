//! `frame.object_ids` (issue 15): a debug output beside the colour, off by default (knob
//! `object_ids`) and costing nothing then — each pixel's first-hit object from the camera,
//! its mesh index + 1 (0: the sky), rasterised at the output size into an R32_UINT image
//! with a depth buffer of its own, and read back with the frame. The CPU reference writes
//! the same from its first hits (`reference::object_ids`); `metrics` restricts errors to
//! the pixels of one object, of the specular objects or of the rest.

use ash::vk;
use gpu_allocator::MemoryLocation;

use crate::frame::direct::DEPTH_FORMAT;
use crate::frame::{destroy_pipelines, FrameInputs};
use crate::vk::pipeline::{graphics_pipeline, Blend, DepthOp, GraphicsDesc, Multisample, VertexInput};
use crate::vk::{build, Access, Buffer, Context, Image, ImageDesc, ImageKind, Owner, Recorder};
use crate::Result;

pub const ID_FORMAT: vk::Format = vk::Format::R32_UINT;

pub struct ObjectIds {
    image: Image,
    depth: Image,
    pipeline: vk::Pipeline,
    readback: Buffer,
}

impl ObjectIds {
    pub fn new(ctx: &Context, layout: vk::PipelineLayout, width: u32, height: u32) -> Result<ObjectIds> {
        let me = ObjectIds {
            image: Image::placeholder(),
            depth: Image::placeholder(),
            pipeline: vk::Pipeline::null(),
            readback: Buffer::placeholder(),
        };
        build(ctx, me, |me| {
            let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC;
            me.image =
                Image::new(ctx, &ImageDesc { name: "frame.object_ids", format: ID_FORMAT, width, height, kind: ImageKind::D2, usage })?;
            let usage = vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT;
            me.depth = Image::new(
                ctx,
                &ImageDesc { name: "frame.object_ids.depth", format: DEPTH_FORMAT, width, height, kind: ImageKind::D2, usage },
            )?;
            let formats = [ID_FORMAT];
            me.pipeline = graphics_pipeline(
                ctx,
                layout,
                &GraphicsDesc {
                    name: "frame.object_ids",
                    vertex: "scene/mesh.vert",
                    fragment: "scene/object_id.frag",
                    vertex_input: VertexInput::Mesh,
                    color_formats: &formats,
                    depth_format: Some(DEPTH_FORMAT),
                    depth_test: true,
                    depth_write: true,
                    view_mask: 0,
                    cull: vk::CullModeFlags::NONE,
                    multisample: Multisample::OFF,
                    blend: Blend::Replace,
                    depth_op: DepthOp::Nearer,
                },
            )?;
            me.readback = Buffer::new(
                ctx,
                "frame.object_ids.readback",
                me.image.byte_size(),
                vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuToCpu,
            )?;
            Ok(())
        })
    }

    /// Draws every object from the camera view `view` and copies the image for reading.
    pub fn record(&mut self, rec: &mut Recorder, f: &FrameInputs, view: u32) {
        let open = rec
            .pass("frame.object_ids")
            .writes(&mut self.image, Access::ColorAttachment)
            .writes(&mut self.depth, Access::DepthAttachment)
            .begin();
        let (ctx, cmd) = (rec.ctx, rec.cmd);
        let colors = [self.image.view];
        let t = crate::vk::Target {
            color: &colors,
            depth: Some(self.depth.view),
            width: self.image.width,
            height: self.image.height,
            view_mask: 0,
            layer_count: 1,
            clear_color: [0.0; 4],
            clear: true,
        };
        crate::vk::begin_rendering(ctx, cmd, &t);
        f.bind(ctx, cmd, self.pipeline);
        for d in f.scene.draws.iter().filter(|d| d.index_count > 0) {
            f.draw(ctx, cmd, view, d);
        }
        unsafe { ctx.device.cmd_end_rendering(cmd) };
        rec.end(open);
        let open = rec.pass("frame.object_ids").reads(&self.image, Access::TransferSrc).begin();
        crate::vk::record_copy_to_buffer(rec.ctx, rec.cmd, &self.image, &self.readback);
        rec.end(open);
    }

    /// The last frame's ids, row by row from the top.
    pub fn read(&self) -> Result<Vec<u32>> {
        Ok(bytemuck::pod_collect_to_vec::<u8, u32>(self.readback.read()?))
    }
}

impl Owner for ObjectIds {
    fn destroy(&mut self, ctx: &Context) {
        destroy_pipelines(ctx, &mut [self.pipeline]);
        self.image.destroy(ctx);
        self.depth.destroy(ctx);
        self.readback.destroy(ctx);
    }
}
