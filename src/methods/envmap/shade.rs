//! `envmap.shade`: the camera's view of the specular objects, each looking its own cube
//! map up with the reflected and refracted directions, weighted by Fresnel (survey §3.1,
//! eq. 1). Draws over `scene.direct`'s colour and depth.

use ash::vk;

use crate::methods::direct::{DEPTH_FORMAT, TARGET_FORMAT};
use crate::methods::{begin_camera_rendering, destroy_pipelines, FrameInputs};
use crate::vk::pipeline::{graphics_pipeline, GraphicsDesc, VertexInput};
use crate::vk::{Access, Context, Image, Recorder};
use crate::Result;

pub struct EnvmapShade {
    pipeline: vk::Pipeline,
}

impl EnvmapShade {
    pub fn new(ctx: &Context, layout: vk::PipelineLayout) -> Result<EnvmapShade> {
        let pipeline = graphics_pipeline(
            ctx,
            layout,
            &GraphicsDesc {
                name: "envmap.shade",
                vertex: "scene/mesh.vert",
                fragment: "envmap/shade.frag",
                vertex_input: VertexInput::Mesh,
                color_formats: &[TARGET_FORMAT],
                depth_format: Some(DEPTH_FORMAT),
                depth_test: true,
                depth_write: true,
                view_mask: 0,
            },
        )?;
        Ok(EnvmapShade { pipeline })
    }

    pub fn record(&self, rec: &mut Recorder, f: &FrameInputs, view: u32, maps: &Image, target: &mut Image, depth: &mut Image) {
        let open = rec
            .pass("envmap.shade")
            .reads(maps, Access::FragmentSampled)
            .writes(target, Access::ColorAttachment)
            .writes(depth, Access::DepthAttachment)
            .begin();
        let (ctx, cmd) = (rec.ctx, rec.cmd);
        begin_camera_rendering(ctx, cmd, target, depth, false);
        f.bind(ctx, cmd, self.pipeline);
        for d in f.scene.draws.iter().filter(|d| d.specular) {
            f.draw(ctx, cmd, view, d);
        }
        unsafe { ctx.device.cmd_end_rendering(cmd) };
        rec.end(open);
    }

    pub fn destroy(&mut self, ctx: &Context) {
        destroy_pipelines(ctx, &mut [self.pipeline]);
        self.pipeline = vk::Pipeline::null();
    }
}
