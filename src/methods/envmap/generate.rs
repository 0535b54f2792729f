//! `envmap.generate` / `distance.generate`: one cube map per specular object, rasterised
//! from its reference point (survey §3.1: "a conventional rendering pass where the
//! rasterization hardware and the z-buffer identify points visible from the reference point
//! through the faces of a cube"), the object itself left out.
//!
//! Environment maps store radiance; distance maps (§4) also store the Euclidean distance
//! from the reference point in alpha. For inter-object reflections (§4.3) the distance maps
//! are regenerated in cycles, each reading the previous cycle's maps (two images,
//! ping-pong), or one cycle per frame reading the previous frame's (frame latency).

use ash::vk;

use crate::frame::direct::DEPTH_FORMAT;
use crate::frame::stage::{FrameIo, Maps, Stage, StageInit};
use crate::frame::{cube_depth, destroy_pipelines, render_cube_faces, view_mask, FrameInputs, FLAG_FIRST_CYCLE, FLAG_INTER_OBJECT};
use crate::methods::distance::distance_images;
use crate::methods::registry::LeavesOut;
use crate::plan::Plan;
use crate::quality::{CubeMode, Precision};
use crate::vk::pipeline::{graphics_pipeline, GraphicsDesc, Multisample, VertexInput};
use crate::vk::{build, Access, Context, Image, ImageDesc, ImageKind, Owner, Recorder};
use crate::Result;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MapKind {
    /// Radiance only (classic and proxy-localised environment mapping).
    Radiance,
    /// Radiance and distance from the reference point (ray tracing in sampled geometry).
    Distance,
}

/// The cube-map pass of one kind; its images are `Maps::radiance` or `Maps::distance`
/// (one cube per object, layer = position in `objects`; two distance images only for
/// inter-object cycles).
pub struct CubeMaps {
    pub kind: MapKind,
    /// Meshes, in layer order.
    objects: Vec<usize>,
    depth: Image,
    sky: vk::Pipeline,
    surface: vk::Pipeline,
    mode: CubeMode,
    cycles: u32,
    frame_latency: bool,
    inter_object: bool,
    /// Frames recorded so far (frame-latency mode reads the previous frame's maps).
    frames: u64,
    /// Mesh draws the last frame recorded per cube face (per-face culling), over all cubes.
    face_draws: [u32; 6],
}

/// `envmap.generate`'s constructor (`RADIANCE_CUBES`).
pub fn create_radiance(init: &StageInit, objects: &[usize], maps: &mut Maps) -> Result<Box<dyn Stage>> {
    Ok(Box::new(CubeMaps::new(init, objects, maps, MapKind::Radiance)?))
}

pub fn radiance_format(p: Precision) -> vk::Format {
    match p {
        Precision::Half => vk::Format::R16G16B16A16_SFLOAT,
        Precision::Single => vk::Format::R32G32B32A32_SFLOAT,
    }
}

impl CubeMaps {
    pub fn new(init: &StageInit, objects: &[usize], maps: &mut Maps, kind: MapKind) -> Result<CubeMaps> {
        let (ctx, plan) = (init.ctx, init.plan);
        let q = &plan.quality;
        let format = radiance_format(q.cube_precision);
        let inter_object = kind == MapKind::Distance && plan.inter_object;
        let images = if kind == MapKind::Distance { distance_images(plan) as usize } else { 1 };
        let me = CubeMaps {
            kind,
            objects: objects.to_vec(),
            depth: Image::placeholder(),
            sky: vk::Pipeline::null(),
            surface: vk::Pipeline::null(),
            mode: q.cube_mode,
            cycles: plan.cycles.max(1),
            frame_latency: plan.frame_latency && inter_object,
            inter_object,
            frames: 0,
            face_draws: [0; 6],
        };
        build(ctx, me, |me| me.init(ctx, plan, init.layout, format, images, maps))
    }

    fn init(
        &mut self,
        ctx: &Context,
        plan: &Plan,
        layout: vk::PipelineLayout,
        format: vk::Format,
        images: usize,
        maps: &mut Maps,
    ) -> Result<()> {
        let q = &plan.quality;
        let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC;
        let kind = ImageKind::CubeArray { cubes: self.objects.len() as u32 };
        let base = match self.kind {
            MapKind::Radiance => "envmap.cubes",
            MapKind::Distance => "distance.cubes",
        };
        for i in 0..images {
            let name = if images == 1 { base.to_string() } else { format!("{base}.{}", ["ping", "pong"][i]) };
            let image = Image::new(ctx, &ImageDesc { name: &name, format, width: q.cube_size, height: q.cube_size, kind, usage })?;
            match self.kind {
                MapKind::Radiance => maps.radiance = Some(image),
                MapKind::Distance => maps.distance.push(image),
            }
        }
        self.depth = cube_depth(ctx, &format!("{base}.depth"), q.cube_size, q.cube_mode)?;
        let (sky, surface) = match self.kind {
            MapKind::Radiance => ("scene/sky.frag", "scene/direct.frag"),
            MapKind::Distance => ("distance/sky.frag", "distance/generate.frag"),
        };
        let formats = [format];
        let desc = |name: &'static str, vertex, fragment, vertex_input, depth_test| GraphicsDesc {
            name,
            vertex,
            fragment,
            vertex_input,
            color_formats: &formats,
            depth_format: Some(DEPTH_FORMAT),
            depth_test,
            depth_write: depth_test,
            view_mask: view_mask(q.cube_mode),
            cull: vk::CullModeFlags::NONE,
            multisample: Multisample::OFF,
            blend: crate::vk::pipeline::Blend::Replace,
            depth_op: crate::vk::pipeline::DepthOp::Nearer,
        };
        self.sky = graphics_pipeline(
            ctx,
            layout,
            &desc(
                if self.kind == MapKind::Radiance { "envmap.sky" } else { "distance.sky" },
                "scene/sky.vert",
                sky,
                VertexInput::None,
                false,
            ),
        )?;
        self.surface = graphics_pipeline(
            ctx,
            layout,
            &desc(
                if self.kind == MapKind::Radiance { "envmap.surface" } else { "distance.surface" },
                "scene/mesh.vert",
                surface,
                VertexInput::Mesh,
                true,
            ),
        )?;
        Ok(())
    }

    /// The images of this kind in the frame's maps.
    fn images(&self, maps: &mut Maps) -> Vec<Image> {
        match self.kind {
            MapKind::Radiance => maps.radiance.take().into_iter().collect(),
            MapKind::Distance => std::mem::take(&mut maps.distance),
        }
    }

    fn put_back(&self, maps: &mut Maps, mut images: Vec<Image>) {
        match self.kind {
            MapKind::Radiance => maps.radiance = images.pop(),
            MapKind::Distance => maps.distance = images,
        }
    }
}

impl Stage for CubeMaps {
    fn name(&self) -> &'static str {
        match self.kind {
            MapKind::Radiance => "envmap.generate",
            MapKind::Distance => "distance.generate",
        }
    }

    /// Records this frame's cycles. The maps set (set 1) `io.sets.generate[i]` samples
    /// distance image i (and the refractor maps); `io.sets.empty` holds null descriptors
    /// (distance-map shaders always declare set 1).
    /// Mesh draws per cube face in the last frame this stage recorded (six-pass mode culls
    /// each face to the objects in its frustum; multiview draws every object in every face).
    fn stats(&self, _ctx: &Context) -> Vec<(String, f64)> {
        (0..6).map(|k| (format!("{}.draws.face{k}", self.name()), self.face_draws[k] as f64)).collect()
    }

    /// With frame latency the inter-object cycles run one per frame on the previous frame's
    /// maps: after a change they start again from the sky, like a fresh renderer's, so that
    /// no bounce keeps the old scene.
    fn update(&mut self, _init: &StageInit, changes: &crate::scene::update::Changes, _maps: &mut Maps) -> Result<()> {
        let seen = !changes.moved.is_empty() || !changes.materials.is_empty() || !changes.lights.is_empty();
        if self.frame_latency && seen {
            self.frames = 0;
        }
        Ok(())
    }

    fn record(&mut self, rec: &mut Recorder, f: &FrameInputs, io: &mut FrameIo) {
        let cycles = if self.frame_latency { 1 } else { self.cycles };
        // The images are taken out of the frame's maps while this pass writes them.
        let mut images = self.images(io.maps);
        let count = images.len();
        let first_write = if self.frame_latency { (self.frames % 2) as usize } else { 0 };
        let mut pass = rec.pass(self.name());
        for m in &mut images {
            pass = pass.writes(m, Access::ColorAttachment);
        }
        let refractor = io.maps.refractor.as_ref().filter(|_| self.kind == MapKind::Distance);
        for img in io.scene_images.iter().copied().chain(io.maps.shadow_reads()).chain(refractor) {
            pass = pass.reads(img, Access::FragmentSampled);
        }
        let open = pass.begin();
        let ctx = rec.ctx;
        let mut latest = 0;
        self.face_draws = [0; 6];
        let (eyes, six) = (io.view_eyes, self.mode == CubeMode::SixPasses);
        for cycle in 0..cycles {
            let write = (first_write + cycle as usize) % count;
            let read = (write + 1) % count;
            // The first cycle ever (or of this frame, without latency) has no maps to read.
            let first = if self.frame_latency { self.frames == 0 } else { cycle == 0 };
            let flags = if self.inter_object { FLAG_INTER_OBJECT | if first { FLAG_FIRST_CYCLE } else { 0 } } else { 0 };
            if self.inter_object && !first {
                rec.barrier(&mut images[read], Access::FragmentSampled);
            }
            rec.barrier(&mut images[write], Access::ColorAttachment);
            let (target, depth) = (&images[write], &mut self.depth);
            let read_set =
                if self.inter_object && !first { io.sets.generate.get(read).copied().unwrap_or(io.sets.empty) } else { io.sets.empty };
            let uses_maps = self.kind == MapKind::Distance;
            let clear = [0.0, 0.0, 0.0, if self.kind == MapKind::Distance { 1e30 } else { 0.0 }];
            for (layer, &mesh) in self.objects.iter().enumerate() {
                let view = io.views.cube_of(io.plan, mesh).expect("cube-mapped object has views");
                let skip = match io.plan.object(mesh).map(|o| o.leaves_out) {
                    Some(LeavesOut::Nothing) => None,
                    _ => Some(mesh),
                };
                let face_draws = &mut self.face_draws;
                render_cube_faces(rec, target, depth, layer as u32, view, self.mode, clear, |cmd, v| {
                    // Six passes: each face draws only the objects inside its frustum.
                    let face = (v - view) as usize;
                    let eye = eyes.get(v as usize).copied().unwrap_or_default();
                    let sees =
                        |d: &&crate::gpu_scene::Draw| d.index_count > 0 && (!six || crate::cube::face_sees_box(face, eye, d.lo, d.hi));
                    f.bind(ctx, cmd, self.sky);
                    f.push_flags(ctx, cmd, v, 0, f.flags | flags);
                    unsafe { ctx.device.cmd_draw(cmd, 3, 1, 0, 0) };
                    f.bind(ctx, cmd, self.surface);
                    if uses_maps {
                        f.bind_maps(ctx, cmd, read_set);
                    }
                    for d in f.scene.draws.iter().filter(|d| Some(d.mesh as usize) != skip).filter(sees) {
                        face_draws[face] += 1;
                        f.push_flags(ctx, cmd, v, d.mesh, f.flags | flags);
                        unsafe { ctx.device.cmd_draw_indexed(cmd, d.index_count, 1, d.first_index, d.vertex_offset, 0) };
                    }
                });
            }
            latest = write;
        }
        self.frames += 1;
        rec.end(open);
        self.put_back(io.maps, images);
        if self.kind == MapKind::Distance {
            io.maps.distance_latest = latest;
        }
    }

    fn destroy(&mut self, ctx: &Context) {
        self.depth.destroy(ctx);
        destroy_pipelines(ctx, &mut [self.sky, self.surface]);
        self.sky = vk::Pipeline::null();
        self.surface = vk::Pipeline::null();
    }
}

impl Owner for CubeMaps {
    fn destroy(&mut self, ctx: &Context) {
        Stage::destroy(self, ctx)
    }
}
