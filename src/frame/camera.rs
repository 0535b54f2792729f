//! The camera pass of a specular method: its objects drawn over `scene.direct`'s colour and
//! depth with the method's shaders (`registry::CameraPass`: `envmap.shade` §3.1,
//! `proxy.shade` §3.2, `distance.search` §4.2, `refractor.search` §4.4,
//! `image_space.refract` §4.4 …). One struct serves every method; the plan says which.

use ash::vk;

use crate::frame::direct::{DEPTH_FORMAT, TARGET_FORMAT};
use crate::frame::stage::{FrameIo, Stage};
use crate::frame::{begin_camera_rendering, destroy_pipelines, FrameInputs};
use crate::plan::types::CameraPlan;
use crate::vk::pipeline::{graphics_pipeline, GraphicsDesc, Multisample, VertexInput};
use crate::vk::{Access, Context, Recorder};
use crate::Result;

pub struct CameraShade {
    name: &'static str,
    pipeline: vk::Pipeline,
    /// (mesh, push flags), the draws of this pass.
    objects: Vec<(usize, u32)>,
    extra: Option<Box<dyn PassExtra>>,
}

/// What a family may add to its camera pass beyond the frame's sets: a pipeline layout with
/// more sets, work recorded before the pass (and those sets bound for it), updates when
/// objects move, and statistics (the distance family's hybrid search traces rays).
pub trait PassExtra {
    /// The pipeline layout: the frame's sets 0 and 1 and push constants, then its own sets.
    fn layout(&self) -> vk::PipelineLayout;
    /// Recorded before the pass.
    fn before(&mut self, ctx: &Context, rec: &mut Recorder);
    /// Binds its sets for the pass's pipeline.
    fn bind(&self, ctx: &Context, cmd: vk::CommandBuffer);
    fn update(&mut self, init: &crate::frame::stage::StageInit, changes: &crate::scene::update::Changes) -> Result<()>;
    fn stats(&self) -> Vec<(String, f64)>;
    fn destroy(&mut self, ctx: &Context);
}

impl CameraShade {
    /// With per-sample MSAA the fragment shader's PER_SAMPLE variant runs (its inputs
    /// interpolated at each sample, so the search starts from the sample's own point).
    pub fn new(ctx: &Context, layout: vk::PipelineLayout, plan: &CameraPlan, multisample: Multisample) -> Result<CameraShade> {
        Self::with_extra(ctx, layout, plan, multisample, None, None)
    }

    /// `new` with the fragment shader's `variant` (`<variant>_PER_SAMPLE` where it runs per
    /// sample) and `extra`'s layout and work.
    pub fn with_extra(
        ctx: &Context,
        layout: vk::PipelineLayout,
        plan: &CameraPlan,
        multisample: Multisample,
        variant: Option<&str>,
        extra: Option<Box<dyn PassExtra>>,
    ) -> Result<CameraShade> {
        let per_sample = multisample.per_sample && multisample.samples > 1;
        let fragment = match (variant, per_sample) {
            (Some(v), true) => format!("{}#{v}_PER_SAMPLE", plan.fragment),
            (Some(v), false) => format!("{}#{v}", plan.fragment),
            (None, true) => format!("{}#PER_SAMPLE", plan.fragment),
            (None, false) => plan.fragment.to_string(),
        };
        let layout = extra.as_ref().map_or(layout, |e| e.layout());
        let pipeline = graphics_pipeline(
            ctx,
            layout,
            &GraphicsDesc {
                name: plan.name,
                vertex: plan.vertex,
                fragment: &fragment,
                vertex_input: VertexInput::Mesh,
                color_formats: &[TARGET_FORMAT],
                depth_format: Some(DEPTH_FORMAT),
                depth_test: true,
                depth_write: true,
                view_mask: 0,
                cull: vk::CullModeFlags::NONE,
                multisample,
                blend: crate::vk::pipeline::Blend::Replace,
                depth_op: crate::vk::pipeline::DepthOp::Nearer,
            },
        );
        let pipeline = match pipeline {
            Ok(p) => p,
            Err(e) => {
                if let Some(mut x) = extra {
                    x.destroy(ctx);
                }
                return Err(e);
            }
        };
        Ok(CameraShade { name: plan.name, pipeline, objects: plan.objects.clone(), extra })
    }
}

impl Stage for CameraShade {
    fn name(&self) -> &'static str {
        self.name
    }

    /// Draws this pass's objects from the camera, sampling every map the frame holds
    /// (those the last cycle wrote).
    fn record(&mut self, rec: &mut Recorder, f: &FrameInputs, io: &mut FrameIo) {
        if let Some(x) = self.extra.as_mut() {
            x.before(rec.ctx, rec);
        }
        let reads = io.maps.camera_reads();
        let mut pass = rec.pass(self.name).writes(io.target, Access::ColorAttachment).writes(io.depth, Access::DepthAttachment);
        for img in reads {
            pass = pass.reads(img, Access::FragmentSampled);
        }
        let open = pass.begin();
        let (ctx, cmd) = (rec.ctx, rec.cmd);
        begin_camera_rendering(ctx, cmd, io.target, io.depth, io.area, false);
        f.bind(ctx, cmd, self.pipeline);
        // Without maps, the set of null descriptors: a pass that reads a map only where its
        // object has one (a planar mirror's fallback) still has set 1 bound.
        match io.sets.camera.get(io.maps.latest) {
            Some(&set) => f.bind_maps(ctx, cmd, set),
            None if io.sets.empty != vk::DescriptorSet::null() => f.bind_maps(ctx, cmd, io.sets.empty),
            None => {}
        }
        if let Some(x) = &self.extra {
            x.bind(ctx, cmd);
        }
        for d in f.scene.draws.iter() {
            let Some(&(_, flags)) = self.objects.iter().find(|(m, _)| *m == d.mesh as usize) else { continue };
            let view_flags = io.object_flags.iter().find(|(m, _)| *m == d.mesh as usize).map_or(0, |(_, fl)| *fl);
            f.push_flags(ctx, cmd, io.views.camera, d.mesh, f.flags | flags | view_flags);
            unsafe { ctx.device.cmd_draw_indexed(cmd, d.index_count, 1, d.first_index, d.vertex_offset, 0) };
        }
        unsafe { ctx.device.cmd_end_rendering(cmd) };
        rec.end(open);
    }

    fn update(
        &mut self,
        init: &crate::frame::stage::StageInit,
        changes: &crate::scene::update::Changes,
        _maps: &mut crate::frame::stage::Maps,
    ) -> Result<()> {
        match self.extra.as_mut() {
            Some(x) => x.update(init, changes),
            None => Ok(()),
        }
    }

    fn stats(&self, _ctx: &Context) -> Vec<(String, f64)> {
        self.extra.as_ref().map_or_else(Vec::new, |x| x.stats())
    }

    fn destroy(&mut self, ctx: &Context) {
        destroy_pipelines(ctx, &mut [self.pipeline]);
        self.pipeline = vk::Pipeline::null();
        if let Some(x) = self.extra.as_mut() {
            x.destroy(ctx);
        }
        self.extra = None;
    }
}
