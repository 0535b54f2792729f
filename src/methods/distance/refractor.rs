//! `refractor.generate`: refractor maps (survey §4.4, Figure 23): each solid refractor seen
//! from its own reference point, alone, storing its surface normal and distance. They
//! depend on the geometry alone, so they are made before the distance maps, whose
//! inter-object cycles may self-refract through them. The camera pass that searches them
//! is `refractor.search` (glsl/distance/refractor/).

use ash::vk;

use crate::frame::direct::DEPTH_FORMAT;
use crate::frame::stage::{FrameIo, Maps, Stage, StageInit};
use crate::frame::{cube_depth, destroy_pipelines, render_cube_faces, view_mask, FrameInputs};
use crate::methods::cube_maps::radiance_format;
use crate::quality::CubeMode;
use crate::vk::pipeline::{graphics_pipeline, GraphicsDesc, Multisample, VertexInput};
use crate::vk::{build, Access, Context, Image, ImageDesc, ImageKind, Owner, Recorder};
use crate::Result;

/// The pass; its images are the slot `slots::REFRACTOR`, one cube per refractor (layer = position in
/// `objects`): xyz normal, w distance.
pub struct RefractorMaps {
    objects: Vec<usize>,
    depth: Image,
    pipeline: vk::Pipeline,
    mode: CubeMode,
    /// Per layer: its refractor moved since its cube was drawn (a refractor map sees its own
    /// object alone: nothing else moves it, issue 33 item 4).
    dirty: Vec<bool>,
    /// `map_updates=always`: every cube every frame.
    always: bool,
}

/// `REFRACTOR_CUBES`' constructor.
pub fn create(init: &StageInit, objects: &[usize], maps: &mut Maps) -> Result<Box<dyn Stage>> {
    Ok(Box::new(RefractorMaps::new(init, objects, maps)?))
}

impl RefractorMaps {
    pub fn new(init: &StageInit, objects: &[usize], maps: &mut Maps) -> Result<RefractorMaps> {
        let (ctx, layout, q) = (init.ctx, init.layout, &init.plan.quality);
        let format = radiance_format(q.cube.cube_precision);
        let me = RefractorMaps {
            objects: objects.to_vec(),
            depth: Image::placeholder(),
            pipeline: vk::Pipeline::null(),
            mode: q.cube.cube_mode,
            dirty: vec![true; objects.len()],
            always: q.frame.map_updates_always,
        };
        build(ctx, me, |me| {
            let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC;
            let kind = ImageKind::CubeArray { cubes: me.objects.len() as u32 };
            maps.set_image(
                &super::slots::REFRACTOR,
                Image::new(
                    ctx,
                    &ImageDesc { name: "refractor.cubes", format, width: q.cube.cube_size, height: q.cube.cube_size, kind, usage },
                )?,
            );
            me.depth = cube_depth(ctx, "refractor.cubes.depth", q.cube.cube_size, q.cube.cube_mode)?;
            me.pipeline = graphics_pipeline(
                ctx,
                layout,
                &GraphicsDesc {
                    name: "refractor.surface",
                    vertex: "scene/mesh.vert",
                    fragment: "distance/refractor/generate.frag",
                    vertex_input: VertexInput::Mesh,
                    color_formats: &[format],
                    depth_format: Some(DEPTH_FORMAT),
                    depth_test: true,
                    depth_write: true,
                    view_mask: view_mask(q.cube.cube_mode),
                    cull: vk::CullModeFlags::NONE,
                    multisample: Multisample::OFF,
                    blend: crate::vk::pipeline::Blend::Replace,
                    depth_op: crate::vk::pipeline::DepthOp::Nearer,
                },
            )?;
            Ok(())
        })
    }
}

impl Stage for RefractorMaps {
    fn name(&self) -> &'static str {
        "refractor.generate"
    }

    /// Each refractor alone, from its reference point (its cube views): those that moved
    /// since their cube was drawn.
    fn record(&mut self, rec: &mut Recorder, f: &FrameInputs, io: &mut FrameIo) {
        let Some(maps) = io.maps.image_mut(&super::slots::REFRACTOR) else { return };
        let open = rec.pass("refractor.generate").writes(maps, Access::ColorAttachment).begin();
        let ctx = rec.ctx;
        let always = self.always;
        for (k, &mesh) in self.objects.iter().enumerate().filter(|&(k, _)| always || self.dirty[k]) {
            let view = io.views.cube_of(io.plan, mesh).expect("refractor has cube views");
            // Far clear: directions where the refractor is absent read as "nothing there".
            render_cube_faces(rec, maps, &mut self.depth, k as u32, view, self.mode, [0.0, 0.0, 0.0, 1e30], |cmd, v| {
                f.bind(ctx, cmd, self.pipeline);
                for d in f.scene.draws.iter().filter(|d| d.mesh as usize == mesh) {
                    f.draw(ctx, cmd, v, d);
                }
            });
        }
        rec.end(open);
        self.dirty.iter_mut().for_each(|d| *d = false);
    }

    /// A refractor's cube is drawn again when it moved (or was hidden or shown).
    fn update(&mut self, _init: &StageInit, changes: &crate::scene::update::Changes, _maps: &mut Maps) -> Result<()> {
        for (k, &mesh) in self.objects.iter().enumerate() {
            self.dirty[k] |= changes.moved.contains(&mesh);
        }
        Ok(())
    }

    fn redraw(&self) -> Option<(u32, u32)> {
        let n = 6 * self.objects.len() as u32;
        (!self.always).then(|| (6 * self.dirty.iter().filter(|&&d| d).count() as u32, n))
    }

    fn destroy(&mut self, ctx: &Context) {
        self.depth.destroy(ctx);
        destroy_pipelines(ctx, &mut [self.pipeline]);
        self.pipeline = vk::Pipeline::null();
    }
}

impl Owner for RefractorMaps {
    fn destroy(&mut self, ctx: &Context) {
        Stage::destroy(self, ctx)
    }
}
