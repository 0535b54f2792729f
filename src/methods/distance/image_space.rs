//! Wyman's image-space double refraction (survey §4.4): `image_space.backfaces` renders the
//! refractors' back faces from the camera (normal and distance from the eye); the camera
//! pass `image_space.refract` (glsl/distance/image_space/refract.*) reads them,
//! with each vertex's distance through the object along its inverted normal (d_N),
//! precomputed here once by casting rays against the object's own triangles.

use ash::vk;
use glam::DVec3;

use super::slots::{BACKFACES, THICKNESS};
use crate::frame::direct::DEPTH_FORMAT;
use crate::frame::stage::{FrameIo, Maps, Stage, StageInit};
use crate::frame::{destroy_pipelines, FrameInputs};
use crate::optics::ray_triangle;
use crate::scene::Scene;
use crate::vk::pipeline::{graphics_pipeline, GraphicsDesc, Multisample, VertexInput};
use crate::vk::{begin_rendering, build, Access, Buffer, Context, Image, ImageDesc, ImageKind, Owner, Recorder, Target};
use crate::Result;

/// The pass; its images are the slots `BACKFACES` (camera-sized: xyz back-face normal, w its
/// distance from the eye, 0: no refractor) and `THICKNESS` (d_N per vertex of the
/// scene's vertex buffer, 0 for other meshes).
pub struct Backfaces {
    objects: Vec<usize>,
    depth: Image,
    pipeline: vk::Pipeline,
}

/// `BACKFACES`' constructor.
pub fn create(init: &StageInit, objects: &[usize], maps: &mut Maps) -> Result<Box<dyn Stage>> {
    Ok(Box::new(Backfaces::new(init, objects, maps)?))
}

/// Distance from each vertex through its own mesh along the inverted normal (Wyman's d_N).
pub fn vertex_thickness(scene: &Scene, meshes: &[usize]) -> Vec<f32> {
    let mut out = Vec::new();
    for (i, m) in scene.meshes.iter().enumerate() {
        if !meshes.contains(&i) {
            out.extend(std::iter::repeat_n(0.0, m.positions.len()));
            continue;
        }
        let p: Vec<DVec3> = m.positions.iter().map(|v| v.as_dvec3()).collect();
        let scale = m.bounds().diagonal().max(1e-12) as f64;
        for (v, n) in p.iter().zip(&m.normals) {
            let dir = -n.as_dvec3().normalize_or_zero();
            let origin = *v + dir * (1e-5 * scale);
            let mut best = f64::INFINITY;
            for t in m.indices.chunks_exact(3) {
                if let Some(hit) = ray_triangle(origin, dir, p[t[0] as usize], p[t[1] as usize], p[t[2] as usize], 0.0, best) {
                    best = hit.t;
                }
            }
            out.push(if best.is_finite() { best as f32 } else { 0.0 });
        }
    }
    out
}

impl Backfaces {
    pub fn new(init: &StageInit, objects: &[usize], maps: &mut Maps) -> Result<Backfaces> {
        let (ctx, scene, layout, width, height) = (init.ctx, init.scene, init.layout, init.width, init.height);
        let me = Backfaces { objects: objects.to_vec(), depth: Image::placeholder(), pipeline: vk::Pipeline::null() };
        build(ctx, me, |me| {
            let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC;
            let format = vk::Format::R32G32B32A32_SFLOAT;
            let backfaces = ImageDesc { name: "image_space.backfaces", format, width, height, kind: ImageKind::D2, usage };
            maps.set_image(&BACKFACES, Image::new(ctx, &backfaces)?);
            me.depth = crate::frame::depth_2d(ctx, "image_space.backfaces.depth", width, height)?;
            maps.set_buffer(
                &THICKNESS,
                Buffer::with_data(
                    ctx,
                    "image_space.thickness",
                    &vertex_thickness(scene, &me.objects),
                    vk::BufferUsageFlags::STORAGE_BUFFER,
                )?,
            );
            me.pipeline = graphics_pipeline(
                ctx,
                layout,
                &GraphicsDesc {
                    name: "image_space.backfaces",
                    vertex: "scene/mesh.vert",
                    fragment: "distance/image_space/backfaces.frag",
                    vertex_input: VertexInput::Mesh,
                    color_formats: &[format],
                    depth_format: Some(DEPTH_FORMAT),
                    depth_test: true,
                    depth_write: true,
                    view_mask: 0,
                    cull: vk::CullModeFlags::FRONT,
                    multisample: Multisample::OFF,
                    blend: crate::vk::pipeline::Blend::Replace,
                    depth_op: crate::vk::pipeline::DepthOp::Nearer,
                },
            )?;
            Ok(())
        })
    }
}

impl Stage for Backfaces {
    fn name(&self) -> &'static str {
        "image_space.backfaces"
    }

    /// A moved (possibly scaled) refractor has other thicknesses: rewritten in place.
    fn update(&mut self, init: &StageInit, changes: &crate::scene::update::Changes, maps: &mut Maps) -> Result<()> {
        if !changes.moved.iter().any(|m| self.objects.contains(m)) {
            return Ok(());
        }
        match maps.buffer_mut(&THICKNESS) {
            Some(t) => t.write(bytemuck::cast_slice(&vertex_thickness(init.scene, &self.objects))),
            None => Ok(()),
        }
    }

    /// The nearest back face of this pass's refractors, from the camera.
    fn record(&mut self, rec: &mut Recorder, f: &FrameInputs, io: &mut FrameIo) {
        let Some(map) = io.maps.image_mut(&BACKFACES) else { return };
        let open =
            rec.pass("image_space.backfaces").writes(map, Access::ColorAttachment).writes(&mut self.depth, Access::DepthAttachment).begin();
        let (ctx, cmd) = (rec.ctx, rec.cmd);
        let colors = [map.view];
        begin_rendering(ctx, cmd, &Target::cleared(&colors, Some(self.depth.view), map.width, map.height));
        f.bind(ctx, cmd, self.pipeline);
        for d in f.scene.draws.iter().filter(|d| self.objects.contains(&(d.mesh as usize))) {
            f.draw(ctx, cmd, io.views.camera, d);
        }
        unsafe { ctx.device.cmd_end_rendering(cmd) };
        rec.end(open);
    }

    fn destroy(&mut self, ctx: &Context) {
        self.depth.destroy(ctx);
        destroy_pipelines(ctx, &mut [self.pipeline]);
        self.pipeline = vk::Pipeline::null();
    }
}

impl Owner for Backfaces {
    fn destroy(&mut self, ctx: &Context) {
        Stage::destroy(self, ctx)
    }
}
