//! `refractor.generate`: refractor maps (survey §4.4, Figure 23): each solid refractor seen
//! from its own reference point, alone, storing its surface normal and distance. The
//! camera pass that searches them is `refractor.search` (`methods::shade`).

use ash::vk;

use crate::methods::direct::DEPTH_FORMAT;
use crate::methods::envmap::generate::radiance_format;
use crate::methods::{cube_depth, destroy_pipelines, render_cube_faces, view_mask, FrameInputs};
use crate::plan::Plan;
use crate::quality::CubeMode;
use crate::vk::pipeline::{graphics_pipeline, GraphicsDesc, VertexInput};
use crate::vk::{build, Access, Context, Image, ImageDesc, ImageKind, Owner, Recorder};
use crate::Result;

pub struct RefractorMaps {
    /// One cube per refractor (layer = index in `plan.refractors`): xyz normal, w distance.
    pub maps: Image,
    depth: Image,
    pipeline: vk::Pipeline,
    mode: CubeMode,
}

impl RefractorMaps {
    pub fn new(ctx: &Context, plan: &Plan, layout: vk::PipelineLayout) -> Result<RefractorMaps> {
        let q = &plan.quality;
        let format = radiance_format(q.cube_precision);
        let me =
            RefractorMaps { maps: Image::placeholder(), depth: Image::placeholder(), pipeline: vk::Pipeline::null(), mode: q.cube_mode };
        build(ctx, me, |me| {
            let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC;
            let kind = ImageKind::CubeArray { cubes: plan.refractors.len() as u32 };
            me.maps =
                Image::new(ctx, &ImageDesc { name: "refractor.cubes", format, width: q.cube_size, height: q.cube_size, kind, usage })?;
            me.depth = cube_depth(ctx, "refractor.cubes.depth", q.cube_size, q.cube_mode)?;
            me.pipeline = graphics_pipeline(
                ctx,
                layout,
                &GraphicsDesc {
                    name: "refractor.surface",
                    vertex: "scene/mesh.vert",
                    fragment: "refractor/generate.frag",
                    vertex_input: VertexInput::Mesh,
                    color_formats: &[format],
                    depth_format: Some(DEPTH_FORMAT),
                    depth_test: true,
                    depth_write: true,
                    view_mask: view_mask(q.cube_mode),
                    cull: vk::CullModeFlags::NONE,
                },
            )?;
            Ok(())
        })
    }

    /// `views[k]`: first of the six views of refractor k (its reference point).
    pub fn record(&mut self, rec: &mut Recorder, f: &FrameInputs, plan: &Plan, views: &[u32]) {
        let open = rec.pass("refractor.generate").writes(&mut self.maps, Access::ColorAttachment).begin();
        let ctx = rec.ctx;
        for (k, (&mesh, &view)) in plan.refractors.iter().zip(views).enumerate() {
            // Far clear: directions where the refractor is absent read as "nothing there".
            render_cube_faces(rec, &self.maps, &mut self.depth, k as u32, view, self.mode, [0.0, 0.0, 0.0, 1e30], |cmd, v| {
                f.bind(ctx, cmd, self.pipeline);
                for d in f.scene.draws.iter().filter(|d| d.mesh as usize == mesh) {
                    f.draw(ctx, cmd, v, d);
                }
            });
        }
        rec.end(open);
    }

    pub fn destroy(&mut self, ctx: &Context) {
        self.maps.destroy(ctx);
        self.depth.destroy(ctx);
        destroy_pipelines(ctx, &mut [self.pipeline]);
        self.pipeline = vk::Pipeline::null();
    }
}

impl Owner for RefractorMaps {
    fn destroy(&mut self, ctx: &Context) {
        RefractorMaps::destroy(self, ctx)
    }
}
