//! `shadow.generate`: distance maps from the punctual lights. A point or spot light gets
//! a cube distance map (radial distance, built with the same cube-map machinery as the
//! environment maps); a directional light a planar one (distance along its direction).

use ash::vk;

use super::maps::{Sampler, Slot};
use super::stage::{FrameIo, Maps, Stage, StageInit};
use super::{cube_depth, destroy_pipelines, render_cube_faces_of, view_mask, FrameInputs};
use crate::plan::types::Plan;
use crate::quality::CubeMode;
use crate::vk::pipeline::{graphics_pipeline, GraphicsDesc, Multisample, VertexInput};
use crate::vk::{begin_rendering, build, Access, Context, Image, ImageDesc, ImageKind, Owner, Recorder, Target};
use crate::Result;

/// Clear value of distance maps: nothing in that direction.
pub const FAR: f32 = 3.0e38;

/// Set 0: shadow distance cubes of point and spot lights, sampled wherever diffuse
/// surfaces are shaded.
pub const SHADOW_CUBES: Slot =
    Slot { shading: true, ..Slot::image("shadow.cubes", 0, super::layout::binding::SHADOW_CUBES, Sampler::Nearest) };
/// Set 0: planar shadow distance maps of directional lights.
pub const SHADOW_PLANES: Slot =
    Slot { shading: true, ..Slot::image("shadow.planes", 0, super::layout::binding::SHADOW_PLANES, Sampler::Nearest) };
/// The frame's own map slots (`maps::all_slots` lists them before the families').
pub const SLOTS: &[Slot] = &[SHADOW_CUBES, SHADOW_PLANES];

/// The shadow pass; its maps live in the slots `SHADOW_CUBES` and `SHADOW_PLANES`.
#[derive(Default)]
pub struct ShadowMaps {
    cube_depth: Option<Image>,
    plane_depth: Option<Image>,
    cube_pipeline: vk::Pipeline,
    plane_pipeline: vk::Pipeline,
    mode: Option<CubeMode>,
    /// Mesh draws per cube face in the last frame recorded, over all shadow cubes.
    face_draws: [u32; 6],
    /// Which cube faces the next record draws: those whose frusta from the light saw a
    /// caster move (`frame::cube_deps`); all on a light change.
    deps: crate::frame::cube_deps::FaceDeps,
    /// Directional lights' planar maps: drawn again on any move.
    planes_dirty: bool,
    always: bool,
}

impl ShadowMaps {
    /// Creates what the plan's lights need (the maps into `maps`).
    pub fn create(init: &StageInit, maps: &mut Maps) -> Result<Box<dyn Stage>> {
        Ok(Box::new(build(init.ctx, ShadowMaps::default(), |s| s.init(init.ctx, init.plan, init.layout, maps))?))
    }

    fn init(&mut self, ctx: &Context, plan: &Plan, layout: vk::PipelineLayout, maps: &mut Maps) -> Result<()> {
        self.deps = crate::frame::cube_deps::FaceDeps::new(plan.shadow_cubes.len());
        self.planes_dirty = true;
        self.always = plan.quality.frame.map_updates_always;
        let size = plan.quality.frame.shadow_size;
        let mode = plan.quality.cube.cube_mode;
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
            multisample: Multisample::OFF,
            blend: crate::vk::pipeline::Blend::Replace,
            depth_op: crate::vk::pipeline::DepthOp::Nearer,
        };
        if !plan.shadow_cubes.is_empty() {
            let kind = ImageKind::CubeArray { cubes: plan.shadow_cubes.len() as u32 };
            maps.set_image(
                &SHADOW_CUBES,
                Image::new(
                    ctx,
                    &ImageDesc { name: "shadow.cubes", format: vk::Format::R32_SFLOAT, width: size, height: size, kind, usage },
                )?,
            );
            self.cube_depth = Some(cube_depth(ctx, "shadow.cubes.depth", size, mode)?);
            self.cube_pipeline = graphics_pipeline(ctx, layout, &desc("shadow.cube", view_mask(mode)))?;
            self.mode = Some(mode);
        }
        if !plan.shadow_planes.is_empty() {
            let kind = ImageKind::D2Array { layers: plan.shadow_planes.len() as u32 };
            maps.set_image(
                &SHADOW_PLANES,
                Image::new(
                    ctx,
                    &ImageDesc { name: "shadow.planes", format: vk::Format::R32_SFLOAT, width: size, height: size, kind, usage },
                )?,
            );
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
}

impl ShadowMaps {
    /// Each shadow cube's centre: its light's position (the cube views' eye).
    fn eyes(scene: &crate::scene::Scene, plan: &Plan) -> Vec<glam::Vec3> {
        plan.shadow_cubes.iter().map(|&i| scene.lights.get(i).map_or(glam::Vec3::ZERO, |l| l.position)).collect()
    }
}

impl Stage for ShadowMaps {
    fn name(&self) -> &'static str {
        "shadow.generate"
    }

    /// Mesh draws per cube face in the last frame this stage recorded (six-pass mode culls
    /// each face to the objects in its frustum).
    fn stats(&self, _ctx: &Context) -> Vec<(String, f64)> {
        (0..6).map(|k| (format!("shadow.generate.draws.face{k}"), self.face_draws[k] as f64)).collect()
    }

    /// The cube faces that saw a caster move (or all, the lights changed); the planar maps on
    /// any move. Materials do not matter to distances.
    fn update(&mut self, init: &StageInit, changes: &crate::scene::update::Changes, _maps: &mut Maps) -> Result<()> {
        let geometry = crate::scene::update::Changes { materials: Vec::new(), camera: false, ..changes.clone() };
        let eyes = Self::eyes(init.scene, init.plan);
        let lighting = crate::frame::cube_deps::Lighting::default();
        self.deps.mark(init.scene, &init.plan.shadow_cubes, &eyes, &init.gpu.draws, &geometry, (false, &[]), &lighting);
        self.planes_dirty |= !changes.moved.is_empty() || !changes.lights.is_empty();
        Ok(())
    }

    fn redraw(&self) -> Option<(u32, u32)> {
        let (faces, all) = self.deps.count();
        let planes = 6 * u32::from(self.planes_dirty) * self.plane_depth.is_some() as u32;
        let plane_all = 6 * self.plane_depth.is_some() as u32;
        (!self.always).then_some((faces + planes, all + plane_all))
    }

    fn record(&mut self, rec: &mut Recorder, f: &FrameInputs, io: &mut FrameIo) {
        if self.always {
            self.deps.all();
            self.planes_dirty = true;
        }
        // Taken out of the table while recorded (both are written at once), put back after.
        let (mut cubes, mut planes) = (io.maps.take_image(&SHADOW_CUBES), io.maps.take_image(&SHADOW_PLANES));
        if cubes.is_none() && planes.is_none() {
            return;
        }
        let mut pass = rec.pass("shadow.generate");
        if let Some(c) = cubes.as_mut() {
            pass = pass.writes(c, Access::ColorAttachment);
        }
        if let Some(p) = planes.as_mut() {
            pass = pass.writes(p, Access::ColorAttachment);
        }
        let open = pass.begin();
        let (ctx, cmd) = (rec.ctx, rec.cmd);
        let clear = [FAR, 0.0, 0.0, 0.0];
        if let (Some(cubes), Some(depth), Some(mode)) = (cubes.as_ref(), self.cube_depth.as_mut(), self.mode) {
            self.face_draws = [0; 6];
            let (eyes, six, face_draws) = (io.view_eyes, mode == CubeMode::SixPasses, &mut self.face_draws);
            for (k, &view) in io.views.shadow_cubes.iter().enumerate() {
                let faces = self.deps.faces.get(k).copied().unwrap_or(super::ALL_FACES);
                render_cube_faces_of(rec, cubes, depth, (k as u32, faces), view, mode, clear, |cmd, v| {
                    // Six passes: each face draws only the objects inside its frustum.
                    let face = (v - view) as usize;
                    let eye = eyes.get(v as usize).copied().unwrap_or_default();
                    f.bind(ctx, cmd, self.cube_pipeline);
                    for d in
                        f.scene.draws.iter().filter(|d| d.index_count > 0 && (!six || crate::cube::face_sees_box(face, eye, d.lo, d.hi)))
                    {
                        face_draws[face] += 1;
                        f.draw(ctx, cmd, v, d);
                    }
                });
            }
        }
        if let (Some(planes), Some(depth), true) = (planes.as_ref(), self.plane_depth.as_mut(), self.planes_dirty) {
            for (j, &view) in io.views.shadow_planes.iter().enumerate() {
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
        let eyes = io.views.shadow_cubes.iter().map(|&v| io.view_eyes.get(v as usize).copied().unwrap_or_default()).collect();
        self.deps.drawn(eyes, &f.scene.draws);
        self.planes_dirty = false;
        for (slot, image) in [(&SHADOW_CUBES, cubes), (&SHADOW_PLANES, planes)] {
            if let Some(image) = image {
                io.maps.set_image(slot, image);
            }
        }
    }

    fn destroy(&mut self, ctx: &Context) {
        for img in [&mut self.cube_depth, &mut self.plane_depth].into_iter().flatten() {
            img.destroy(ctx);
        }
        destroy_pipelines(ctx, &mut [self.cube_pipeline, self.plane_pipeline]);
        self.cube_pipeline = vk::Pipeline::null();
        self.plane_pipeline = vk::Pipeline::null();
    }
}

impl Owner for ShadowMaps {
    fn destroy(&mut self, ctx: &Context) {
        Stage::destroy(self, ctx)
    }
}
