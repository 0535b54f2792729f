//! The camera pass of a specular method: its specular objects drawn over `scene.direct`'s
//! colour and depth with the method's fragment shader. One struct serves every method;
//! the pass name and the shader say which (`envmap.shade` §3.1, `proxy.shade` §3.2,
//! `distance.search` §4.2, `refractor.search` §4.4, `image_space.refract` §4.4).

use ash::vk;

use crate::gpu_scene::Draw;
use crate::methods::direct::{DEPTH_FORMAT, TARGET_FORMAT};
use crate::methods::{begin_camera_rendering, destroy_pipelines, FrameInputs};
use crate::vk::pipeline::{graphics_pipeline, GraphicsDesc, VertexInput};
use crate::vk::{Access, Context, Image, Recorder};
use crate::Result;

pub struct SpecularShade {
    pub name: &'static str,
    pipeline: vk::Pipeline,
}

impl SpecularShade {
    pub fn new(ctx: &Context, layout: vk::PipelineLayout, name: &'static str, vertex: &str, fragment: &str) -> Result<SpecularShade> {
        let pipeline = graphics_pipeline(
            ctx,
            layout,
            &GraphicsDesc {
                name,
                vertex,
                fragment,
                vertex_input: VertexInput::Mesh,
                color_formats: &[TARGET_FORMAT],
                depth_format: Some(DEPTH_FORMAT),
                depth_test: true,
                depth_write: true,
                view_mask: 0,
                cull: vk::CullModeFlags::NONE,
            },
        )?;
        Ok(SpecularShade { name, pipeline })
    }

    /// Draws the draws `which` selects from view `view`, sampling `reads`, with the maps
    /// set (set 1) when the method has one and extra push flags.
    #[allow(clippy::too_many_arguments)]
    pub fn record<'a>(
        &self,
        rec: &mut Recorder,
        f: &FrameInputs,
        view: u32,
        reads: impl Iterator<Item = &'a Image>,
        maps: Option<vk::DescriptorSet>,
        flags: u32,
        target: &mut Image,
        depth: &mut Image,
        which: impl Fn(&Draw) -> bool,
    ) {
        let mut pass = rec.pass(self.name).writes(target, Access::ColorAttachment).writes(depth, Access::DepthAttachment);
        for img in reads {
            pass = pass.reads(img, Access::FragmentSampled);
        }
        let open = pass.begin();
        let (ctx, cmd) = (rec.ctx, rec.cmd);
        begin_camera_rendering(ctx, cmd, target, depth, false);
        f.bind(ctx, cmd, self.pipeline);
        if let Some(m) = maps {
            f.bind_maps(ctx, cmd, m);
        }
        for d in f.scene.draws.iter().filter(|d| which(d)) {
            f.push_flags(ctx, cmd, view, d.mesh, f.flags | flags);
            unsafe { ctx.device.cmd_draw_indexed(cmd, d.index_count, 1, d.first_index, d.vertex_offset, 0) };
        }
        unsafe { ctx.device.cmd_end_rendering(cmd) };
        rec.end(open);
    }

    pub fn destroy(&mut self, ctx: &Context) {
        destroy_pipelines(ctx, &mut [self.pipeline]);
        self.pipeline = vk::Pipeline::null();
    }
}
