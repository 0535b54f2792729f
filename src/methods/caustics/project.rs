//! `caustics.project` (survey §6.3.3): the camera's diffuse surfaces drawn again over
//! `scene.direct`'s depth (nearer or equal: the same vertices through the same vertex shader),
//! adding the caustics' radiance. A pass of its own so that the projection's cost is
//! profiled; `scene.direct` then shades without it (`FLAG_CAUSTICS_APART`), and the map
//! passes, which have no such second pass, project inside their shading.

use ash::vk;

use crate::frame::direct::{DEPTH_FORMAT, TARGET_FORMAT};
use crate::frame::stage::{FrameIo, Stage, StageInit};
use crate::frame::{begin_camera_rendering, destroy_pipelines, FrameInputs};
use crate::vk::pipeline::{graphics_pipeline, Blend, DepthOp, GraphicsDesc, Multisample, VertexInput};
use crate::vk::{Access, Context, Recorder};
use crate::Result;

pub struct CausticsProject {
    pipeline: vk::Pipeline,
}

impl CausticsProject {
    pub fn create(init: &StageInit) -> Result<Box<dyn Stage>> {
        // Diffuse surfaces shade once per pixel (as scene.direct), on every sample's coverage.
        let multisample = Multisample { per_sample: false, ..init.multisample };
        let pipeline = graphics_pipeline(
            init.ctx,
            init.layout,
            &GraphicsDesc {
                name: "caustics.project",
                vertex: "scene/mesh.vert",
                fragment: match init.plan.caustics.as_ref() {
                    _ if photon_map(init) => "caustics/project.frag#CAUSTICS_PHOTON_MAP",
                    _ if texture_space(init.plan) => "caustics/project.frag#CAUSTICS_TEXTURE",
                    _ => "caustics/project.frag",
                },
                vertex_input: VertexInput::Mesh,
                color_formats: &[TARGET_FORMAT],
                depth_format: Some(DEPTH_FORMAT),
                depth_test: true,
                depth_write: false,
                view_mask: 0,
                cull: vk::CullModeFlags::NONE,
                multisample,
                blend: Blend::Add,
                depth_op: DepthOp::NearerOrEqual,
            },
        )?;
        Ok(Box::new(CausticsProject { pipeline }))
    }
}

impl Stage for CausticsProject {
    fn name(&self) -> &'static str {
        "caustics.project"
    }

    /// The camera's surfaces get their caustics here, not in `scene.direct`.
    fn direct_flags(&self) -> u32 {
        crate::frame::layout::FLAG_CAUSTICS_APART
    }

    fn record(&mut self, rec: &mut Recorder, f: &FrameInputs, io: &mut FrameIo) {
        let mut pass = rec.pass("caustics.project").writes(io.target, Access::ColorAttachment).writes(io.depth, Access::DepthAttachment);
        use super::slots::{CAUSTIC_DISTANCES, CAUSTIC_LIGHT_MAP, CAUSTIC_MAPS, CAUSTIC_SCREEN};
        let maps = [&CAUSTIC_DISTANCES, &CAUSTIC_MAPS, &CAUSTIC_SCREEN, &CAUSTIC_LIGHT_MAP].map(|s| io.maps.image(s));
        for img in io.scene_images.iter().copied().chain(maps.into_iter().flatten()) {
            pass = pass.reads(img, Access::FragmentSampled);
        }
        let open = pass.begin();
        let (ctx, cmd) = (rec.ctx, rec.cmd);
        begin_camera_rendering(ctx, cmd, io.target, io.depth, io.area, false);
        f.bind(ctx, cmd, self.pipeline);
        for d in f.scene.draws.iter().filter(|d| !d.specular && d.index_count > 0) {
            f.draw(ctx, cmd, io.views.camera, d);
        }
        unsafe { ctx.device.cmd_end_rendering(cmd) };
        rec.end(open);
    }

    fn destroy(&mut self, ctx: &Context) {
        destroy_pipelines(ctx, &mut [self.pipeline]);
        self.pipeline = vk::Pipeline::null();
    }
}

/// Whether the plan's caustics are stored in texture space (SKALP05), which the passes that
/// shade diffuse surfaces read in their `CAUSTICS_TEXTURE` variants.
pub fn texture_space(plan: &crate::plan::types::Plan) -> bool {
    plan.caustics.as_ref().is_some_and(|c| c.space == crate::quality::CausticSpace::Texture)
}

/// Whether the plan's caustics are the photon map, whose gather only the passes' variants
/// hold (glsl/caustics/project.glsl).
pub fn photon_map(init: &crate::frame::stage::StageInit) -> bool {
    init.plan.caustics.as_ref().is_some_and(|c| c.filter == crate::quality::Caustics::PhotonMap)
}
