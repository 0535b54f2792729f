//! `scene.direct`: the camera's view of everything that is not specular: the sky
//! (environment map) and emission + Lambertian direct light with shadows. Specular
//! objects are drawn by their method's shading pass afterwards, into the same target.

use ash::vk;

use super::stage::{FrameIo, Stage};
use super::{begin_camera_rendering, destroy_pipelines, FrameInputs};
use crate::vk::pipeline::{graphics_pipeline, GraphicsDesc, Multisample, VertexInput};
use crate::vk::{Access, Context, Recorder};
use crate::Result;

pub const TARGET_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

pub struct SceneDirect {
    sky: vk::Pipeline,
    direct: vk::Pipeline,
}

/// The sky and direct-light pipelines for a colour format and view mask (also used to
/// fill environment maps).
pub fn sky_and_direct(
    ctx: &Context,
    layout: vk::PipelineLayout,
    format: vk::Format,
    view_mask: u32,
    multisample: Multisample,
    name: &str,
) -> Result<(vk::Pipeline, vk::Pipeline)> {
    let formats = [format];
    let sky = graphics_pipeline(
        ctx,
        layout,
        &GraphicsDesc {
            name: &format!("{name}.sky"),
            vertex: "scene/sky.vert",
            fragment: "scene/sky.frag",
            vertex_input: VertexInput::None,
            color_formats: &formats,
            depth_format: Some(DEPTH_FORMAT),
            depth_test: false,
            depth_write: false,
            view_mask,
            cull: vk::CullModeFlags::NONE,
            multisample,
            blend: crate::vk::pipeline::Blend::Replace,
            depth_op: crate::vk::pipeline::DepthOp::Nearer,
        },
    )?;
    let direct = graphics_pipeline(
        ctx,
        layout,
        &GraphicsDesc {
            name: &format!("{name}.direct"),
            vertex: "scene/mesh.vert",
            fragment: "scene/direct.frag",
            vertex_input: VertexInput::Mesh,
            color_formats: &formats,
            depth_format: Some(DEPTH_FORMAT),
            depth_test: true,
            depth_write: true,
            view_mask,
            cull: vk::CullModeFlags::NONE,
            multisample,
            blend: crate::vk::pipeline::Blend::Replace,
            depth_op: crate::vk::pipeline::DepthOp::Nearer,
        },
    );
    match direct {
        Ok(d) => Ok((sky, d)),
        Err(e) => {
            crate::vk::pipeline::release_pipeline(ctx, sky);
            Err(e)
        }
    }
}

impl SceneDirect {
    /// Its pipelines draw into the camera target's samples (`multisample`), shading once
    /// per pixel: diffuse surfaces need coverage only, their textures are filtered.
    pub fn new(ctx: &Context, layout: vk::PipelineLayout, multisample: Multisample) -> Result<SceneDirect> {
        let ms = Multisample { per_sample: false, ..multisample };
        let (sky, direct) = sky_and_direct(ctx, layout, TARGET_FORMAT, 0, ms, "scene")?;
        Ok(SceneDirect { sky, direct })
    }
}

impl Stage for SceneDirect {
    fn name(&self) -> &'static str {
        "scene.direct"
    }

    /// Clears the target, draws the sky, then every non-specular mesh from the camera.
    fn record(&mut self, rec: &mut Recorder, f: &FrameInputs, io: &mut FrameIo) {
        let mut pass = rec.pass("scene.direct").writes(io.target, Access::ColorAttachment).writes(io.depth, Access::DepthAttachment);
        for img in io.scene_images.iter().copied().chain(io.maps.shadow_reads()) {
            pass = pass.reads(img, Access::FragmentSampled);
        }
        let open = pass.begin();
        let (ctx, cmd, view) = (rec.ctx, rec.cmd, io.views.camera);
        // A planar mirror's view keeps the depth mask geometry.stencil left (the colour is
        // all overwritten by the sky).
        begin_camera_rendering(ctx, cmd, io.target, io.depth, io.area, !io.depth_masked);
        f.bind(ctx, cmd, self.sky);
        f.draw_sky(ctx, cmd, view);
        f.bind(ctx, cmd, self.direct);
        // Stages that take over part of direct shading say so (caustics.project).
        let flags = f.flags | io.direct_flags;
        for d in f.scene.draws.iter().filter(|d| !d.specular) {
            f.push_flags(ctx, cmd, view, d.mesh, flags);
            unsafe { ctx.device.cmd_draw_indexed(cmd, d.index_count, 1, d.first_index, d.vertex_offset, 0) };
        }
        unsafe { ctx.device.cmd_end_rendering(cmd) };
        rec.end(open);
    }

    fn destroy(&mut self, ctx: &Context) {
        destroy_pipelines(ctx, &mut [self.sky, self.direct]);
        self.sky = vk::Pipeline::null();
        self.direct = vk::Pipeline::null();
    }
}
