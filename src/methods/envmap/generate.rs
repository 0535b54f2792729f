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

use crate::methods::direct::DEPTH_FORMAT;
use crate::methods::{cube_depth, destroy_pipelines, render_cube_faces, view_mask, FrameInputs, FLAG_FIRST_CYCLE, FLAG_INTER_OBJECT};
use crate::plan::Plan;
use crate::quality::{CubeMode, Precision};
use crate::vk::pipeline::{graphics_pipeline, GraphicsDesc, VertexInput};
use crate::vk::{build, Access, Context, Image, ImageDesc, ImageKind, Owner, Recorder};
use crate::Result;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MapKind {
    /// Radiance only (classic and proxy-localised environment mapping).
    Radiance,
    /// Radiance and distance from the reference point (ray tracing in sampled geometry).
    Distance,
}

pub struct CubeMaps {
    pub kind: MapKind,
    /// Cube-map arrays, one cube per specular object (layer = `EnvmapPlan::layer`); two
    /// only for inter-object cycles.
    pub maps: Vec<Image>,
    depth: Image,
    sky: vk::Pipeline,
    surface: vk::Pipeline,
    mode: CubeMode,
    cycles: u32,
    frame_latency: bool,
    inter_object: bool,
    /// Frames recorded so far (frame-latency mode reads the previous frame's maps).
    frames: u64,
    /// Which image the last recorded cycle wrote.
    pub latest: usize,
}

pub fn radiance_format(p: Precision) -> vk::Format {
    match p {
        Precision::Half => vk::Format::R16G16B16A16_SFLOAT,
        Precision::Single => vk::Format::R32G32B32A32_SFLOAT,
    }
}

impl CubeMaps {
    pub fn new(ctx: &Context, plan: &Plan, layout: vk::PipelineLayout, kind: MapKind) -> Result<CubeMaps> {
        let q = &plan.quality;
        let format = radiance_format(q.cube_precision);
        let inter_object = plan.method == crate::plan::Method::DistanceMulti;
        let images = if inter_object && (plan.cycles > 1 || q.frame_latency) { 2 } else { 1 };
        let me = CubeMaps {
            kind,
            maps: Vec::new(),
            depth: Image::placeholder(),
            sky: vk::Pipeline::null(),
            surface: vk::Pipeline::null(),
            mode: q.cube_mode,
            cycles: plan.cycles.max(1),
            frame_latency: q.frame_latency && inter_object,
            inter_object,
            frames: 0,
            latest: 0,
        };
        build(ctx, me, |me| me.init(ctx, plan, layout, format, images))
    }

    fn init(&mut self, ctx: &Context, plan: &Plan, layout: vk::PipelineLayout, format: vk::Format, images: usize) -> Result<()> {
        let q = &plan.quality;
        let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC;
        let kind = ImageKind::CubeArray { cubes: plan.envmaps.len() as u32 };
        let base = match self.kind {
            MapKind::Radiance => "envmap.cubes",
            MapKind::Distance => "distance.cubes",
        };
        for i in 0..images {
            let name = if images == 1 { base.to_string() } else { format!("{base}.{}", ["ping", "pong"][i]) };
            self.maps.push(Image::new(ctx, &ImageDesc { name: &name, format, width: q.cube_size, height: q.cube_size, kind, usage })?);
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

    pub fn pass_name(&self) -> &'static str {
        match self.kind {
            MapKind::Radiance => "envmap.generate",
            MapKind::Distance => "distance.generate",
        }
    }

    /// Records this frame's cycles. `views[i]` is the first of the six views of
    /// plan.envmaps[i]; `read_sets[i]` is the maps set (set 1) that samples `maps[i]`;
    /// `empty_set` holds null descriptors (distance-map shaders always declare set 1).
    #[allow(clippy::too_many_arguments)]
    pub fn record<'a>(
        &mut self,
        rec: &mut Recorder,
        f: &FrameInputs,
        plan: &Plan,
        views: &[u32],
        read_sets: &[vk::DescriptorSet],
        empty_set: vk::DescriptorSet,
        sampled: impl Iterator<Item = &'a Image>,
    ) {
        let cycles = if self.frame_latency { 1 } else { self.cycles };
        let first_write = if self.frame_latency { (self.frames % 2) as usize } else { 0 };
        let mut pass = rec.pass(self.pass_name());
        for m in &mut self.maps {
            pass = pass.writes(m, Access::ColorAttachment);
        }
        for img in sampled {
            pass = pass.reads(img, Access::FragmentSampled);
        }
        let open = pass.begin();
        let ctx = rec.ctx;
        for cycle in 0..cycles {
            let write = (first_write + cycle as usize) % self.maps.len();
            let read = (write + 1) % self.maps.len();
            // The first cycle ever (or of this frame, without latency) has no maps to read.
            let first = if self.frame_latency { self.frames == 0 } else { cycle == 0 };
            let flags = if self.inter_object { FLAG_INTER_OBJECT | if first { FLAG_FIRST_CYCLE } else { 0 } } else { 0 };
            if self.inter_object && !first {
                rec.barrier(&mut self.maps[read], Access::FragmentSampled);
            }
            rec.barrier(&mut self.maps[write], Access::ColorAttachment);
            let (target, depth) = (&self.maps[write], &mut self.depth);
            let read_set = if self.inter_object && !first { read_sets.get(read).copied().unwrap_or(empty_set) } else { empty_set };
            let uses_maps = self.kind == MapKind::Distance;
            let clear = [0.0, 0.0, 0.0, if self.kind == MapKind::Distance { 1e30 } else { 0.0 }];
            for (e, &view) in plan.envmaps.iter().zip(views) {
                render_cube_faces(rec, target, depth, e.layer, view, self.mode, clear, |cmd, v| {
                    f.bind(ctx, cmd, self.sky);
                    f.push_flags(ctx, cmd, v, 0, f.flags | flags);
                    unsafe { ctx.device.cmd_draw(cmd, 3, 1, 0, 0) };
                    f.bind(ctx, cmd, self.surface);
                    if uses_maps {
                        f.bind_maps(ctx, cmd, read_set);
                    }
                    for d in f.scene.draws.iter().filter(|d| d.mesh as usize != e.mesh) {
                        f.push_flags(ctx, cmd, v, d.mesh, f.flags | flags);
                        unsafe { ctx.device.cmd_draw_indexed(cmd, d.index_count, 1, d.first_index, d.vertex_offset, 0) };
                    }
                });
            }
            self.latest = write;
        }
        self.frames += 1;
        rec.end(open);
    }

    /// The maps the camera pass reads: those the last cycle wrote.
    pub fn current(&self) -> &Image {
        &self.maps[self.latest]
    }

    pub fn destroy(&mut self, ctx: &Context) {
        for m in &mut self.maps {
            m.destroy(ctx);
        }
        self.depth.destroy(ctx);
        destroy_pipelines(ctx, &mut [self.sky, self.surface]);
        self.sky = vk::Pipeline::null();
        self.surface = vk::Pipeline::null();
    }
}

impl Owner for CubeMaps {
    fn destroy(&mut self, ctx: &Context) {
        CubeMaps::destroy(self, ctx)
    }
}
