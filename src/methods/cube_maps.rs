//! The cube maps the environment-mapping (§3) and distance-map (§4) families share, owned by
//! neither: `envmap.generate` / `distance.generate`, one cube map per specular object, rasterised
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
use crate::frame::stage::{FrameIo, Maps, Slot, Stage, StageInit};
use crate::frame::{cube_depth, destroy_pipelines, render_cube_faces_of, view_mask, FrameInputs, FLAG_FIRST_CYCLE, FLAG_INTER_OBJECT};
use crate::methods::registry::LeavesOut;
use crate::plan::types::Plan;
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
    /// Image-based reflections' captures (§3.3): radiance and distance, `captures`³ cubes per
    /// object around it (`envmap::captures`).
    Captures,
    /// Displacement-mapped proxies' height maps (§3.2): six orthographic layers per object
    /// (`envmap::relief`), radiance and depth, in a 2D array.
    Relief,
}

impl MapKind {
    /// The slot of the frame's maps its images fill.
    pub fn slot(self) -> &'static Slot {
        match self {
            MapKind::Radiance => &crate::methods::envmap::slots::RADIANCE,
            MapKind::Distance => &crate::methods::distance::slots::DISTANCE,
            MapKind::Captures => &crate::methods::envmap::slots::CAPTURES,
            MapKind::Relief => &crate::methods::envmap::slots::RELIEF,
        }
    }
}

/// The cube-map pass of one kind; its images are its kind's slot (`MapKind::slot`)
/// (one cube per object, layer = position in `objects`; two distance images only for
/// inter-object cycles).
pub struct CubeMaps {
    pub kind: MapKind,
    /// Meshes, in layer order (captures: each object's `captures`³ layers in a row).
    objects: Vec<usize>,
    depth: Image,
    sky: vk::Pipeline,
    surface: vk::Pipeline,
    /// Planar mirrors inside the maps (§5, `plan.map_mirrors`): the mirror's pixels marked
    /// in depth and filled with the environment, and the mirror laid over its mirrored view
    /// with its Fresnel weight (null without planar mirrors).
    mirror_mask: vk::Pipeline,
    mirror_weight: vk::Pipeline,
    /// `plan.map_mirrors`.
    map_mirrors: Vec<usize>,
    mode: CubeMode,
    cycles: u32,
    frame_latency: bool,
    inter_object: bool,
    /// Captures and height maps of a plan with inter-object cycles (after the distance maps):
    /// the other specular objects drawn by their own maps, read from the last cycle's
    /// distance maps (composition, §4.3 across families).
    shows_by_maps: bool,
    /// Frames recorded so far (frame-latency mode reads the previous frame's maps).
    frames: u64,
    /// Mesh draws the last frame recorded per cube face (per-face culling), over all cubes.
    face_draws: [u32; 6],
    /// Which faces the next record draws (what changed in their frusta, `cube_deps`).
    deps: crate::frame::cube_deps::FaceDeps,
    /// `map_updates=always`: every face every frame.
    always: bool,
    /// Faces drawn by the last record.
    faces_drawn: u32,
    /// The family's view block its layers' views are in (`with_views`), six per layer.
    view_block: Option<&'static str>,
    /// Height maps: per layer where each face starts along its axis, as last drawn
    /// (`relief::starts`), and the box their views span (`Plan::proxy_box`).
    relief_from: Vec<[f32; 6]>,
    relief_box: (glam::Vec3, glam::Vec3),
}

/// `envmap.generate`'s constructor (`RADIANCE_CUBES`).
pub fn create_radiance(init: &StageInit, objects: &[usize], maps: &mut Maps) -> Result<Box<dyn Stage>> {
    Ok(Box::new(CubeMaps::new(init, objects, maps, MapKind::Radiance)?))
}

/// A cube-map pass whose layers' views are a family's block (`ViewLayout::first(block)`,
/// six per layer: image-based captures, height maps), not the objects' own cube views.
pub fn with_views(init: &StageInit, layers: &[usize], maps: &mut Maps, kind: MapKind, block: &'static str) -> Result<Box<dyn Stage>> {
    let mut me = CubeMaps::new(init, layers, maps, kind)?;
    me.view_block = Some(block);
    Ok(Box::new(me))
}

/// Per height-map layer (its object) where each face starts (`relief::starts`).
fn relief_starts(scene: &crate::scene::Scene, objects: &[usize]) -> Vec<[f32; 6]> {
    objects.iter().map(|&m| crate::methods::envmap::relief::starts(scene, m)).collect()
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
        let format = radiance_format(q.cube.cube_precision);
        let inter_object = kind == MapKind::Distance && plan.inter_object;
        let images = if kind == MapKind::Distance { distance_images(plan) as usize } else { 1 };
        let me = CubeMaps {
            kind,
            objects: objects.to_vec(),
            depth: Image::placeholder(),
            sky: vk::Pipeline::null(),
            surface: vk::Pipeline::null(),
            mirror_mask: vk::Pipeline::null(),
            mirror_weight: vk::Pipeline::null(),
            map_mirrors: if kind == MapKind::Captures { Vec::new() } else { plan.map_mirrors.clone() },
            mode: if kind == MapKind::Relief { CubeMode::SixPasses } else { q.cube.cube_mode },
            cycles: plan.cycles.max(1),
            frame_latency: plan.frame_latency && inter_object,
            inter_object,
            shows_by_maps: matches!(kind, MapKind::Captures | MapKind::Relief) && plan.inter_object,
            frames: 0,
            face_draws: [0; 6],
            deps: crate::frame::cube_deps::FaceDeps::new(objects.len()).leaving_out(
                objects.iter().map(|&m| (plan.object(m).map(|o| o.leaves_out) != Some(LeavesOut::Nothing)).then_some(m)).collect(),
            ),
            always: q.frame.map_updates_always,
            faces_drawn: 0,
            view_block: None,
            relief_box: plan.proxy_box,
            relief_from: if kind == MapKind::Relief { relief_starts(init.scene, objects) } else { Vec::new() },
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
        let (size, kind) = match self.kind {
            MapKind::Relief => (q.envmap.relief_size, ImageKind::D2Array { layers: 6 * self.objects.len() as u32 }),
            _ => (q.cube.cube_size, ImageKind::CubeArray { cubes: self.objects.len() as u32 }),
        };
        let base = match self.kind {
            MapKind::Radiance => "envmap.cubes",
            MapKind::Distance => "distance.cubes",
            MapKind::Captures => "envmap.captures",
            MapKind::Relief => "envmap.relief",
        };
        for i in 0..images {
            let name = if images == 1 { base.to_string() } else { format!("{base}.{}", ["ping", "pong"][i]) };
            let image = Image::new(ctx, &ImageDesc { name: &name, format, width: size, height: size, kind, usage })?;
            maps.push_image(self.kind.slot(), image);
        }
        self.depth = cube_depth(ctx, &format!("{base}.depth"), size, self.mode)?;
        // caustic_space=texture: the variants that read the receivers' light map.
        let texture = crate::methods::caustics::project::texture_space(plan);
        let (sky, surface) = match (self.kind, texture) {
            (MapKind::Radiance, false) => ("scene/sky.frag", "scene/direct.frag"),
            (MapKind::Radiance, true) => ("scene/sky.frag", "scene/direct.frag#CAUSTICS_TEXTURE"),
            (MapKind::Distance, false) if self.inter_object => ("distance/sky.frag", "distance/generate.frag#INTER_OBJECT"),
            (MapKind::Distance, true) if self.inter_object => ("distance/sky.frag", "distance/generate.frag#INTER_OBJECT_TEXTURE"),
            (MapKind::Captures, false) if self.shows_by_maps => ("distance/sky.frag", "distance/generate.frag#INTER_OBJECT"),
            (MapKind::Captures, true) if self.shows_by_maps => ("distance/sky.frag", "distance/generate.frag#INTER_OBJECT_TEXTURE"),
            (MapKind::Relief, false) if self.shows_by_maps => ("distance/sky.frag", "distance/generate.frag#PLANAR_INTER_OBJECT"),
            (MapKind::Relief, true) if self.shows_by_maps => ("distance/sky.frag", "distance/generate.frag#PLANAR_INTER_OBJECT_TEXTURE"),
            (MapKind::Distance | MapKind::Captures, false) => ("distance/sky.frag", "distance/generate.frag"),
            (MapKind::Distance | MapKind::Captures, true) => ("distance/sky.frag", "distance/generate.frag#CAUSTICS_TEXTURE"),
            (MapKind::Relief, false) => ("distance/sky.frag", "distance/generate.frag#PLANAR"),
            (MapKind::Relief, true) => ("distance/sky.frag", "distance/generate.frag#PLANAR_TEXTURE"),
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
            view_mask: view_mask(self.mode),
            cull: vk::CullModeFlags::NONE,
            multisample: Multisample::OFF,
            blend: crate::vk::pipeline::Blend::Replace,
            depth_op: crate::vk::pipeline::DepthOp::Nearer,
        };
        self.sky = graphics_pipeline(
            ctx,
            layout,
            &desc(
                match self.kind {
                    MapKind::Radiance => "envmap.sky",
                    MapKind::Distance => "distance.sky",
                    MapKind::Captures => "envmap.captures.sky",
                    MapKind::Relief => "envmap.relief.sky",
                },
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
                match self.kind {
                    MapKind::Radiance => "envmap.surface",
                    MapKind::Distance => "distance.surface",
                    MapKind::Captures => "envmap.captures.surface",
                    MapKind::Relief => "envmap.relief.surface",
                },
                "scene/mesh.vert",
                surface,
                VertexInput::Mesh,
                true,
            ),
        )?;
        if !self.map_mirrors.is_empty() {
            let mut mask = desc("geometry.map_mask", "scene/mesh.vert", "geometry/map_mask.frag", VertexInput::Mesh, true);
            mask.depth_op = crate::vk::pipeline::DepthOp::Always;
            self.mirror_mask = graphics_pipeline(ctx, layout, &mask)?;
            let mut weight = desc("geometry.map_mirror", "scene/mesh.vert", "geometry/map_mirror.frag", VertexInput::Mesh, true);
            weight.blend = crate::vk::pipeline::Blend::Multiply;
            self.mirror_weight = graphics_pipeline(ctx, layout, &weight)?;
        }
        Ok(())
    }

    /// Each layer's centre in `plan` (its cube views' eye).
    fn eyes(&self, plan: &Plan) -> Vec<glam::Vec3> {
        if self.kind == MapKind::Captures {
            return plan.captures.iter().flat_map(|c| c.centres.iter().copied()).collect();
        }
        let eye = |m: usize| plan.envmaps.iter().find(|e| e.mesh == m).map_or(glam::Vec3::ZERO, |e| e.reference_point);
        self.objects.iter().map(|&m| eye(m)).collect()
    }

    /// Whether the next record draws every face (`map_updates=always`; frame latency, whose
    /// cycles start again from the sky after any change).
    fn every_face(&self) -> bool {
        self.always || self.frame_latency
    }

    /// The images of this kind in the frame's maps.
    fn images(&self, maps: &mut Maps) -> Vec<Image> {
        maps.take_images(self.kind.slot())
    }

    fn put_back(&self, maps: &mut Maps, images: Vec<Image>) {
        maps.set_images(self.kind.slot(), images);
    }
}

/// Clears the depth attachment of the rendering in progress (a `size`² cube face, every
/// view of a multiview pass) to `depth`.
pub(crate) fn clear_depth(ctx: &Context, cmd: vk::CommandBuffer, size: u32, depth: f32) {
    let attachment = vk::ClearAttachment {
        aspect_mask: vk::ImageAspectFlags::DEPTH,
        color_attachment: 0,
        clear_value: vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth, stencil: 0 } },
    };
    let rect = vk::ClearRect {
        rect: vk::Rect2D { offset: vk::Offset2D::default(), extent: vk::Extent2D { width: size, height: size } },
        base_array_layer: 0,
        layer_count: 1,
    };
    unsafe { ctx.device.cmd_clear_attachments(cmd, &[attachment], &[rect]) };
}

impl Stage for CubeMaps {
    fn name(&self) -> &'static str {
        match self.kind {
            MapKind::Radiance => "envmap.generate",
            MapKind::Distance => "distance.generate",
            MapKind::Captures => "envmap.captures",
            MapKind::Relief => "envmap.relief",
        }
    }

    /// Records this frame's cycles. The maps set (set 1) `io.sets.generate[i]` samples
    /// distance image i (and the refractor maps); `io.sets.empty` holds null descriptors
    /// (distance-map shaders always declare set 1).
    /// Mesh draws per cube face in the last frame this stage recorded (six-pass mode culls
    /// each face to the objects in its frustum; multiview draws every object in every face).
    /// And the faces it drew (`<name>.faces_drawn`: those whose frusta saw what changed).
    fn stats(&self, _ctx: &Context) -> Vec<(String, f64)> {
        let mut out: Vec<(String, f64)> = (0..6).map(|k| (format!("{}.draws.face{k}", self.name()), self.face_draws[k] as f64)).collect();
        out.push((format!("{}.faces_drawn", self.name()), self.faces_drawn as f64));
        out
    }

    /// With frame latency the inter-object cycles run one per frame on the previous frame's
    /// maps: after a change they start again from the sky, like a fresh renderer's, so that
    /// no bounce keeps the old scene.
    fn update(&mut self, init: &StageInit, changes: &crate::scene::update::Changes, maps: &mut Maps) -> Result<()> {
        let seen = !changes.moved.is_empty() || !changes.materials.is_empty() || !changes.lights.is_empty();
        if self.frame_latency && seen {
            self.frames = 0;
        }
        let relief = self.kind == MapKind::Relief;
        if relief && init.plan.proxy_box != self.relief_box {
            // The box the height maps' views span moved (a scene without a room, whose bounds
            // follow its objects): every view changed.
            self.relief_box = init.plan.proxy_box;
            self.deps.all();
        }
        if self.every_face() || (self.shows_by_maps && seen) {
            // Maps that show the others by the distance maps: whatever changed may have
            // changed those.
            self.deps.all();
            if relief {
                self.relief_from = relief_starts(init.scene, &self.objects);
            }
        } else if relief {
            // Height maps: orthographic views over the whole box, every face of a layer that
            // sees the change: a light or material, another object's move, or its own
            // object's where its shadows or caustics fall on what the layer draws. Its own
            // move also moves where its faces start (`relief::starts`): a face changes where
            // something lies between where it was drawn from and where it starts now.
            let lighting = crate::frame::cube_deps::Lighting::of(init.scene, init.plan, maps);
            let casts = !lighting.shadows.is_empty() || lighting.caustics != crate::frame::cube_deps::CausticReach::Unchanged;
            let global = !changes.lights.is_empty() || !changes.materials.is_empty();
            for (k, &own) in self.objects.iter().enumerate() {
                if global || changes.moved.iter().any(|&m| m != own || casts) {
                    self.deps.faces[k] = crate::frame::ALL_FACES;
                }
                let now = crate::methods::envmap::relief::starts(init.scene, own);
                for (f, from) in self.relief_from[k].iter_mut().enumerate() {
                    let moved = *from != now[f];
                    if moved && crate::methods::envmap::relief::holds_between(init.scene, own, f, *from, now[f]) {
                        self.deps.faces[k] |= 1 << f;
                    }
                    if self.deps.faces[k] & (1 << f) != 0 {
                        *from = now[f];
                    }
                }
            }
        } else {
            let eyes = self.eyes(init.plan);
            let lighting = crate::frame::cube_deps::Lighting::of(init.scene, init.plan, maps);
            self.deps.mark(init.scene, &self.objects, &eyes, &init.gpu.draws, changes, (self.inter_object, &self.map_mirrors), &lighting);
        }
        Ok(())
    }

    /// Faces the next record draws, of all (`frame::cube_deps`), unless it draws every face.
    fn redraw(&self) -> Option<(u32, u32)> {
        (!self.every_face()).then(|| self.deps.count())
    }

    fn record(&mut self, rec: &mut Recorder, f: &FrameInputs, io: &mut FrameIo) {
        // Only inter-object distance maps read their own previous cycle; every other kind
        // (radiance cubes, captures and height maps, which read the distance maps' last
        // cycle) would draw the same image again each cycle: once.
        let cycles = if self.frame_latency || !self.inter_object { 1 } else { self.cycles };
        // The images are taken out of the frame's maps while this pass writes them.
        let mut images = self.images(io.maps);
        let count = images.len();
        let first_write = if self.frame_latency { (self.frames % 2) as usize } else { 0 };
        let mut pass = rec.pass(self.name());
        for m in &mut images {
            pass = pass.writes(m, Access::ColorAttachment);
        }
        // Distance maps bind the generation sets: what they hold besides these images.
        let generation = io.maps.generation_reads().filter(|_| self.kind == MapKind::Distance || self.shows_by_maps);
        // Captures and height maps shown by maps read the last cycle's distance maps.
        let last_cycle = io.maps.image(MapKind::Distance.slot()).filter(|_| self.shows_by_maps);
        for img in io.scene_images.iter().copied().chain(io.maps.shadow_reads()).chain(generation).chain(last_cycle) {
            pass = pass.reads(img, Access::FragmentSampled);
        }
        let open = pass.begin();
        let ctx = rec.ctx;
        let mut latest = 0;
        self.face_draws = [0; 6];
        if self.every_face() {
            self.deps.all();
        }
        self.faces_drawn = self.deps.count().0;
        // Per-face culling by the cube faces' frusta (not the height maps' orthographic views).
        let (eyes, six) = (io.view_eyes, self.mode == CubeMode::SixPasses && self.kind != MapKind::Relief);
        for cycle in 0..cycles {
            let write = (first_write + cycle as usize) % count;
            let read = (write + 1) % count;
            // The first cycle ever (or of this frame, without latency) has no maps to read.
            let first = if self.frame_latency { self.frames == 0 } else { cycle == 0 };
            let flags = if self.inter_object {
                FLAG_INTER_OBJECT | if first { FLAG_FIRST_CYCLE } else { 0 }
            } else if self.shows_by_maps {
                FLAG_INTER_OBJECT
            } else {
                0
            };
            if self.inter_object && !first {
                rec.barrier(&mut images[read], Access::FragmentSampled);
            }
            rec.barrier(&mut images[write], Access::ColorAttachment);
            let (target, depth) = (&images[write], &mut self.depth);
            let read_set = if self.inter_object && !first {
                io.sets.generate.get(read).copied().unwrap_or(io.sets.empty)
            } else if self.shows_by_maps {
                io.sets.generate.get(io.maps.latest).copied().unwrap_or(io.sets.empty)
            } else {
                io.sets.empty
            };
            let uses_maps = self.kind != MapKind::Radiance;
            let clear = [0.0, 0.0, 0.0, if uses_maps { 1e30 } else { 0.0 }];
            let block = self.view_block.and_then(|b| io.views.first(b));
            for (layer, &mesh) in self.objects.iter().enumerate() {
                let view = match block {
                    Some(first) => first + 6 * layer as u32,
                    None => io.views.cube_of(io.plan, mesh).expect("cube-mapped object has views"),
                };
                let skip = match io.plan.object(mesh).map(|o| o.leaves_out) {
                    Some(LeavesOut::Nothing) => None,
                    _ => Some(mesh),
                };
                let face_draws = &mut self.face_draws;
                let map_mirrors = &self.map_mirrors;
                let mirror_base = io
                    .plan
                    .envmaps
                    .iter()
                    .position(|e| e.mesh == mesh)
                    .zip(io.views.first(MAP_MIRROR_VIEWS))
                    .map(|(i, first)| first + (6 * map_mirrors.len() * i) as u32);
                let (mirror_mask, mirror_weight, surface) = (self.mirror_mask, self.mirror_weight, self.surface);
                let faces = self.deps.faces.get(layer).copied().unwrap_or(crate::frame::ALL_FACES);
                render_cube_faces_of(rec, target, depth, (layer as u32, faces), view, self.mode, clear, |cmd, v| {
                    // Six passes: each face draws only the objects inside its frustum.
                    let face = (v - view) as usize;
                    let eye = eyes.get(v as usize).copied().unwrap_or_default();
                    let sees =
                        |d: &&crate::gpu_scene::Draw| d.index_count > 0 && (!six || crate::cube::face_sees_box(face, eye, d.lo, d.hi));
                    f.bind(ctx, cmd, self.sky);
                    f.push_flags(ctx, cmd, v, 0, f.flags | flags);
                    unsafe { ctx.device.cmd_draw(cmd, 3, 1, 0, 0) };
                    // Planar mirrors (§5): each mirror's pixels marked in depth, then the
                    // scene from the mirrored reference point drawn there only (no mirror in
                    // it: one reflection deep); the depth cleared for the map's own draws.
                    let mirrored = mirror_base.filter(|_| !map_mirrors.is_empty());
                    if let Some(base) = mirrored {
                        for (k, &mirror) in map_mirrors.iter().enumerate() {
                            let Some(md) = f.scene.draws.iter().find(|d| d.mesh as usize == mirror).filter(|d| sees(d)) else { continue };
                            clear_depth(ctx, cmd, target.width, 1.0);
                            f.bind(ctx, cmd, mirror_mask);
                            f.push_flags(ctx, cmd, v, md.mesh, f.flags | flags);
                            unsafe { ctx.device.cmd_draw_indexed(cmd, md.index_count, 1, md.first_index, md.vertex_offset, 0) };
                            f.bind(ctx, cmd, surface);
                            if uses_maps {
                                f.bind_maps(ctx, cmd, read_set);
                            }
                            let mv = base + 6 * k as u32 + (v - view);
                            for d in f.scene.draws.iter().filter(|d| d.index_count > 0 && !map_mirrors.contains(&(d.mesh as usize))) {
                                face_draws[face] += 1;
                                f.push_flags(ctx, cmd, mv, d.mesh, f.flags | flags);
                                unsafe { ctx.device.cmd_draw_indexed(cmd, d.index_count, 1, d.first_index, d.vertex_offset, 0) };
                            }
                        }
                        clear_depth(ctx, cmd, target.width, 0.0);
                    }
                    f.bind(ctx, cmd, surface);
                    if uses_maps {
                        f.bind_maps(ctx, cmd, read_set);
                    }
                    for d in f.scene.draws.iter().filter(|d| Some(d.mesh as usize) != skip).filter(sees) {
                        face_draws[face] += 1;
                        let weighted = mirrored.is_some() && map_mirrors.contains(&(d.mesh as usize));
                        if weighted {
                            f.bind(ctx, cmd, mirror_weight);
                        }
                        f.push_flags(ctx, cmd, v, d.mesh, f.flags | flags);
                        unsafe { ctx.device.cmd_draw_indexed(cmd, d.index_count, 1, d.first_index, d.vertex_offset, 0) };
                        if weighted {
                            f.bind(ctx, cmd, surface);
                            if uses_maps {
                                f.bind_maps(ctx, cmd, read_set);
                            }
                        }
                    }
                });
            }
            latest = write;
        }
        self.frames += 1;
        rec.end(open);
        self.put_back(io.maps, images);
        self.deps.drawn(self.eyes(io.plan), &f.scene.draws);
        if self.kind == MapKind::Distance {
            io.maps.latest = latest;
        }
    }

    fn destroy(&mut self, ctx: &Context) {
        self.depth.destroy(ctx);
        destroy_pipelines(ctx, &mut [self.sky, self.surface, self.mirror_mask, self.mirror_weight]);
        self.sky = vk::Pipeline::null();
        self.surface = vk::Pipeline::null();
        self.mirror_mask = vk::Pipeline::null();
        self.mirror_weight = vk::Pipeline::null();
    }
}

impl Owner for CubeMaps {
    fn destroy(&mut self, ctx: &Context) {
        Stage::destroy(self, ctx)
    }
}

/// The view block of planar mirrors' mirrored cube views inside the maps (§5 inside §3/§4):
/// per cube-mapped object (as `plan.envmaps`), six per mirror of `plan.map_mirrors`, in
/// that order. The geometry family declares and writes it.
pub const MAP_MIRROR_VIEWS: &str = "geometry.map_mirror_views";

/// Images the distance maps need: two for cycles that read the previous cycle's maps.
pub fn distance_images(p: &Plan) -> u64 {
    if p.inter_object && (p.cycles > 1 || p.frame_latency) {
        2
    } else {
        1
    }
}

impl Maps {
    /// The environment- or distance-map cube array the camera passes read (one cube per
    /// object of that map), if planned.
    pub fn object_cubes(&self) -> Option<&Image> {
        self.image(MapKind::Distance.slot()).or(self.image(MapKind::Radiance.slot()))
    }
}
