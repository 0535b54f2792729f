//! `shadow.generate`: distance maps from the punctual lights. A point or spot light gets
//! a cube distance map (radial distance, built with the same cube-map machinery as the
//! environment maps); a directional light a planar one (distance along its direction).

use ash::vk;

use super::{cube_depth, destroy_pipelines, render_cube_faces, view_mask, FrameInputs};
use crate::plan::Plan;
use crate::quality::CubeMode;
use crate::vk::pipeline::{graphics_pipeline, GraphicsDesc, VertexInput};
use crate::vk::{begin_rendering, build, Access, Context, Image, ImageDesc, ImageKind, Owner, Recorder, Target};
use crate::Result;

/// Clear value of distance maps: nothing in that direction.
pub const FAR: f32 = 3.0e38;

#[derive(Default)]
pub struct ShadowMaps {
    pub cubes: Option<Image>,
    cube_depth: Option<Image>,
    pub planes: Option<Image>,
    plane_depth: Option<Image>,
    cube_pipeline: vk::Pipeline,
    plane_pipeline: vk::Pipeline,
    mode: Option<CubeMode>,
}

impl ShadowMaps {
    /// Creates what the plan's lights need; nothing when there are none.
    pub fn new(ctx: &Context, plan: &Plan, layout: vk::PipelineLayout) -> Result<ShadowMaps> {
        build(ctx, ShadowMaps::default(), |s| s.init(ctx, plan, layout))
    }

    fn init(&mut self, ctx: &Context, plan: &Plan, layout: vk::PipelineLayout) -> Result<()> {
        let size = plan.quality.shadow_size;
        let mode = plan.quality.cube_mode;
        let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC;
        let desc = |name, view_mask| GraphicsDesc {
            name,
            vertex: "scene/mesh.vert",
            fragment: "shadow/distance.frag",
            vertex_input: VertexInput::Mesh,
            color_formats: &[vk::Format::R32_SFLOAT],
            depth_format: Some(vk::Format::D32_SFLOAT),
            depth_test: true,
            depth_write: true,
            view_mask,
            cull: vk::CullModeFlags::NONE,
        };
        if !plan.shadow_cubes.is_empty() {
            let kind = ImageKind::CubeArray { cubes: plan.shadow_cubes.len() as u32 };
            self.cubes = Some(Image::new(
                ctx,
                &ImageDesc { name: "shadow.cubes", format: vk::Format::R32_SFLOAT, width: size, height: size, kind, usage },
            )?);
            self.cube_depth = Some(cube_depth(ctx, "shadow.cubes.depth", size, mode)?);
            self.cube_pipeline = graphics_pipeline(ctx, layout, &desc("shadow.cube", view_mask(mode)))?;
            self.mode = Some(mode);
        }
        if !plan.shadow_planes.is_empty() {
            let kind = ImageKind::D2Array { layers: plan.shadow_planes.len() as u32 };
            self.planes = Some(Image::new(
                ctx,
                &ImageDesc { name: "shadow.planes", format: vk::Format::R32_SFLOAT, width: size, height: size, kind, usage },
            )?);
            let dk = ImageDesc {
                name: "shadow.planes.depth",
                format: vk::Format::D32_SFLOAT,
                width: size,
                height: size,
                kind: ImageKind::D2,
                usage: vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
            };
            self.plane_depth = Some(Image::new(ctx, &dk)?);
            self.plane_pipeline = graphics_pipeline(ctx, layout, &desc("shadow.plane", 0))?;
        }
        Ok(())
    }

    /// `cube_views`: first view of each cube light; `plane_views`: view of each plane.
    pub fn record(&mut self, rec: &mut Recorder, f: &FrameInputs, cube_views: &[u32], plane_views: &[u32]) {
        if self.cubes.is_none() && self.planes.is_none() {
            return;
        }
        let mut pass = rec.pass("shadow.generate");
        if let Some(c) = self.cubes.as_mut() {
            pass = pass.writes(c, Access::ColorAttachment);
        }
        if let Some(p) = self.planes.as_mut() {
            pass = pass.writes(p, Access::ColorAttachment);
        }
        let open = pass.begin();
        let (ctx, cmd) = (rec.ctx, rec.cmd);
        let clear = [FAR, 0.0, 0.0, 0.0];
        if let (Some(cubes), Some(depth), Some(mode)) = (self.cubes.as_ref(), self.cube_depth.as_mut(), self.mode) {
            for (k, &view) in cube_views.iter().enumerate() {
                render_cube_faces(rec, cubes, depth, k as u32, view, mode, clear, |cmd, v| {
                    f.bind(ctx, cmd, self.cube_pipeline);
                    for d in &f.scene.draws {
                        f.draw(ctx, cmd, v, d);
                    }
                });
            }
        }
        if let (Some(planes), Some(depth)) = (self.planes.as_ref(), self.plane_depth.as_mut()) {
            for (j, &view) in plane_views.iter().enumerate() {
                rec.barrier(depth, Access::DepthAttachment);
                let colors = [planes.layer_view(j as u32)];
                let t = Target {
                    color: &colors,
                    depth: Some(depth.view),
                    width: planes.width,
                    height: planes.height,
                    view_mask: 0,
                    layer_count: 1,
                    clear_color: clear,
                    clear: true,
                };
                begin_rendering(ctx, cmd, &t);
                f.bind(ctx, cmd, self.plane_pipeline);
                for d in &f.scene.draws {
                    f.draw(ctx, cmd, view, d);
                }
                unsafe { ctx.device.cmd_end_rendering(cmd) };
            }
        }
        rec.end(open);
    }

    /// Declares the maps as read by a later pass's fragment shaders.
    pub fn sampled(&self) -> impl Iterator<Item = &Image> {
        self.cubes.iter().chain(self.planes.iter())
    }

    pub fn destroy(&mut self, ctx: &Context) {
        for img in [&mut self.cubes, &mut self.cube_depth, &mut self.planes, &mut self.plane_depth].into_iter().flatten() {
            img.destroy(ctx);
        }
        destroy_pipelines(ctx, &mut [self.cube_pipeline, self.plane_pipeline]);
        self.cube_pipeline = vk::Pipeline::null();
        self.plane_pipeline = vk::Pipeline::null();
    }
}

impl Owner for ShadowMaps {
    fn destroy(&mut self, ctx: &Context) {
        ShadowMaps::destroy(self, ctx)
    }
}
