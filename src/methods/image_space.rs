//! Wyman's image-space double refraction (survey §4.4): `image_space.backfaces` renders the
//! refractors' back faces from the camera (normal and distance from the eye); the camera
//! pass `image_space.refract` (`methods::shade` with image_space/refract.vert) reads them,
//! with each vertex's distance through the object along its inverted normal (d_N),
//! precomputed here once by casting rays against the object's own triangles.

use ash::vk;
use glam::DVec3;

use crate::gpu_scene::Draw;
use crate::methods::direct::DEPTH_FORMAT;
use crate::methods::{destroy_pipelines, FrameInputs};
use crate::optics::ray_triangle;
use crate::plan::Plan;
use crate::scene::Scene;
use crate::vk::pipeline::{graphics_pipeline, GraphicsDesc, VertexInput};
use crate::vk::{begin_rendering, build, Access, Buffer, Context, Image, ImageDesc, ImageKind, Owner, Recorder, Target};
use crate::Result;

pub struct Backfaces {
    /// Camera-sized: xyz back-face normal, w its distance from the eye (0: no refractor).
    pub map: Image,
    depth: Image,
    pipeline: vk::Pipeline,
    /// d_N per vertex of the scene's vertex buffer (0 for other meshes).
    pub thickness: Buffer,
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
    pub fn new(ctx: &Context, scene: &Scene, plan: &Plan, layout: vk::PipelineLayout, width: u32, height: u32) -> Result<Backfaces> {
        let me = Backfaces {
            map: Image::placeholder(),
            depth: Image::placeholder(),
            pipeline: vk::Pipeline::null(),
            thickness: Buffer::placeholder(),
        };
        build(ctx, me, |me| {
            let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC;
            let format = vk::Format::R32G32B32A32_SFLOAT;
            me.map = Image::new(ctx, &ImageDesc { name: "image_space.backfaces", format, width, height, kind: ImageKind::D2, usage })?;
            me.depth = Image::new(
                ctx,
                &ImageDesc {
                    name: "image_space.backfaces.depth",
                    format: DEPTH_FORMAT,
                    width,
                    height,
                    kind: ImageKind::D2,
                    usage: vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
                },
            )?;
            me.thickness = Buffer::with_data(
                ctx,
                "image_space.thickness",
                &vertex_thickness(scene, &plan.image_space),
                vk::BufferUsageFlags::STORAGE_BUFFER,
            )?;
            me.pipeline = graphics_pipeline(
                ctx,
                layout,
                &GraphicsDesc {
                    name: "image_space.backfaces",
                    vertex: "scene/mesh.vert",
                    fragment: "image_space/backfaces.frag",
                    vertex_input: VertexInput::Mesh,
                    color_formats: &[format],
                    depth_format: Some(DEPTH_FORMAT),
                    depth_test: true,
                    depth_write: true,
                    view_mask: 0,
                    cull: vk::CullModeFlags::FRONT,
                },
            )?;
            Ok(())
        })
    }

    /// The nearest back face of the refractors `which` selects, from view `view`.
    pub fn record(&mut self, rec: &mut Recorder, f: &FrameInputs, view: u32, which: impl Fn(&Draw) -> bool) {
        let open = rec
            .pass("image_space.backfaces")
            .writes(&mut self.map, Access::ColorAttachment)
            .writes(&mut self.depth, Access::DepthAttachment)
            .begin();
        let (ctx, cmd) = (rec.ctx, rec.cmd);
        let colors = [self.map.view];
        let t = Target {
            color: &colors,
            depth: Some(self.depth.view),
            width: self.map.width,
            height: self.map.height,
            view_mask: 0,
            layer_count: 1,
            clear_color: [0.0; 4],
            clear: true,
        };
        begin_rendering(ctx, cmd, &t);
        f.bind(ctx, cmd, self.pipeline);
        for d in f.scene.draws.iter().filter(|d| which(d)) {
            f.draw(ctx, cmd, view, d);
        }
        unsafe { ctx.device.cmd_end_rendering(cmd) };
        rec.end(open);
    }

    pub fn destroy(&mut self, ctx: &Context) {
        self.map.destroy(ctx);
        self.depth.destroy(ctx);
        self.thickness.destroy(ctx);
        destroy_pipelines(ctx, &mut [self.pipeline]);
        self.pipeline = vk::Pipeline::null();
    }
}

impl Owner for Backfaces {
    fn destroy(&mut self, ctx: &Context) {
        Backfaces::destroy(self, ctx)
    }
}
