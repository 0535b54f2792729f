//! `envmap.generate`: one cube map per specular object, rasterised from its reference
//! point (survey §3.1: "a conventional rendering pass where the rasterization hardware and
//! the z-buffer identify points visible from the reference point through the faces of a
//! cube"). The object itself is left out; other specular objects, which have no map of
//! their own in this method, reflect and refract the environment map.

use ash::vk;

use crate::methods::direct::sky_and_direct;
use crate::methods::{cube_depth, destroy_pipelines, render_cube_faces, view_mask, FrameInputs};
use crate::plan::Plan;
use crate::quality::{CubeMode, Precision};
use crate::vk::{Access, Context, Image, ImageDesc, ImageKind, Recorder};
use crate::Result;

pub struct EnvmapGenerate {
    /// Cube-map array, one cube per specular object (layer = `EnvmapPlan::layer`).
    pub maps: Image,
    depth: Image,
    sky: vk::Pipeline,
    direct: vk::Pipeline,
    mode: CubeMode,
}

pub fn radiance_format(p: Precision) -> vk::Format {
    match p {
        Precision::Half => vk::Format::R16G16B16A16_SFLOAT,
        Precision::Single => vk::Format::R32G32B32A32_SFLOAT,
    }
}

impl EnvmapGenerate {
    pub fn new(ctx: &Context, plan: &Plan, layout: vk::PipelineLayout) -> Result<EnvmapGenerate> {
        let q = &plan.quality;
        let format = radiance_format(q.cube_precision);
        let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC;
        let kind = ImageKind::CubeArray { cubes: plan.envmaps.len() as u32 };
        let mut maps = Image::new(ctx, &ImageDesc { name: "envmap.cubes", format, width: q.cube_size, height: q.cube_size, kind, usage })?;
        let mut depth = match cube_depth(ctx, "envmap.cubes.depth", q.cube_size, q.cube_mode) {
            Ok(d) => d,
            Err(e) => {
                maps.destroy(ctx);
                return Err(e);
            }
        };
        match sky_and_direct(ctx, layout, format, view_mask(q.cube_mode), "envmap") {
            Ok((sky, direct)) => Ok(EnvmapGenerate { maps, depth, sky, direct, mode: q.cube_mode }),
            Err(e) => {
                maps.destroy(ctx);
                depth.destroy(ctx);
                Err(e)
            }
        }
    }

    /// `views[i]`: first of the six views of plan.envmaps[i].
    pub fn record<'a>(
        &mut self,
        rec: &mut Recorder,
        f: &FrameInputs,
        plan: &Plan,
        views: &[u32],
        sampled: impl Iterator<Item = &'a Image>,
    ) {
        let mut pass = rec.pass("envmap.generate").writes(&mut self.maps, Access::ColorAttachment);
        for img in sampled {
            pass = pass.reads(img, Access::FragmentSampled);
        }
        let open = pass.begin();
        let ctx = rec.ctx;
        for (e, &view) in plan.envmaps.iter().zip(views) {
            render_cube_faces(rec, &self.maps, &mut self.depth, e.layer, view, self.mode, [0.0; 4], |cmd, v| {
                f.bind(ctx, cmd, self.sky);
                f.draw_sky(ctx, cmd, v);
                f.bind(ctx, cmd, self.direct);
                for d in f.scene.draws.iter().filter(|d| d.mesh as usize != e.mesh) {
                    f.draw(ctx, cmd, v, d);
                }
            });
        }
        rec.end(open);
    }

    pub fn destroy(&mut self, ctx: &Context) {
        self.maps.destroy(ctx);
        self.depth.destroy(ctx);
        destroy_pipelines(ctx, &mut [self.sky, self.direct]);
        self.sky = vk::Pipeline::null();
        self.direct = vk::Pipeline::null();
    }
}
