//! `layered.peel` (survey §4.5): the layered distance map of the whole scene around one
//! reference point, by depth peeling (Everitt): layer k is rendered with the depth test
//! keeping the nearest fragment *behind* layer k−1's depth at the same texel (two depth
//! buffers, ping-pong: one is written, the other sampled), so that it holds the k-th
//! surface along each texel's ray. Per texel: radiance and Euclidean distance
//! (`layered_maps`), normal and material (`layered_normals`), as `peel.frag` writes them.
//!
//! The number of layers is the `layers` knob, or (`auto`) the scene's depth complexity
//! from the reference point: `layered.count` renders every surface into the six faces with
//! additive blending and the largest count is read back (on the library's own queue; a
//! host's device without one is counted on the CPU along the same texel rays). A scene
//! that needs 3 layers allocates 3; the count is taken again when objects move, and the
//! layers are reallocated when it changes. The count is kept per cube face: layer k of a
//! face whose texels meet at most k surfaces would peel nothing, so it is cleared and not
//! drawn (six-pass cubes; `layered.faces_peeled` counts the passes that draw) — the
//! scene's deepest direction sets the layers allocated, each face peels only its own.
//! Where the layers are fewer than the depth
//! complexity (a `layers` knob under it, or more than `MAX_LAYERS` surfaces), the peel is
//! cut: one more layer then holds the *farthest* surface along each texel's ray (depth test
//! reversed over a depth cleared to the nearest), so that a ray that passes behind the
//! peeled layers meets the scene's outermost surface — in a closed room its walls, as one
//! distance map would show them — instead of leaving for the sky (black in a room).

use ash::vk;
use glam::{DVec3, Vec3};

use super::slots::{LAYERED, LAYERED_FAR, LAYERED_NORMALS};
use crate::frame::direct::DEPTH_FORMAT;
use crate::frame::layout::{LAYERED_FACE_SHIFT, LAYERED_FIRST};
use crate::frame::stage::{cube_texel_bytes, describe_cube, FrameIo, Maps, Stage, StageInit};
use crate::frame::{destroy_pipelines, FrameInputs};
use crate::methods::cube_maps::radiance_format;
use crate::quality::{CubeMode, Precision, Quality};
use crate::vk::pipeline::{allocate_set, graphics_pipeline, sampler, write_image, Blend, DepthOp, GraphicsDesc, Multisample, VertexInput};
use crate::vk::{begin_rendering, build, Access, Buffer, Context, Image, ImageDesc, ImageKind, MemoryLocation, Owner, Recorder, Target};
use crate::Result;

/// Device memory of `layers` layers (both images) and the two peeling depth buffers.
pub fn bytes(q: &Quality, layers: u32) -> u64 {
    let face = q.cube.cube_size as u64 * q.cube.cube_size as u64;
    layers as u64 * 6 * face * 2 * cube_texel_bytes(q) + 2 * 6 * face * 4
}

/// What one layer is, for `specula plan`.
pub fn describe_layer(q: &Quality) -> String {
    format!(
        "{} (radiance, distance) + {} (normal, material), {:.2} MiB",
        describe_cube(q),
        describe_cube(q),
        (bytes(q, 1) - bytes(q, 0)) as f64 / (1 << 20) as f64
    )
}

/// Where the peel draws: per cube face, per layer k, the texel rectangle whose rays meet more
/// than k surfaces (none past the face's depth complexity). Layer k holds nothing outside
/// it, so the peel clears each layer whole and draws the scene only there (scissor). From
/// the GPU's count at the map's own size (`layered.count`), or the CPU's along fewer rays
/// (the plan's prediction; `size` the texels per side it counted).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PeelExtent {
    pub size: u32,
    /// `[x0, y0, x1, y1)` per face, per layer.
    pub faces: [Vec<[u32; 4]>; 6],
}

impl PeelExtent {
    /// From each face's texel counts (`count(face, x, y)`: the surfaces along its ray).
    pub fn from_counts(size: u32, count: impl Fn(usize, u32, u32) -> u32) -> PeelExtent {
        let mut e = PeelExtent { size, faces: Default::default() };
        for (face, rects) in e.faces.iter_mut().enumerate() {
            for y in 0..size {
                for x in 0..size {
                    let n = count(face, x, y) as usize;
                    if rects.len() < n {
                        rects.resize(n, [u32::MAX, u32::MAX, 0, 0]);
                    }
                    for r in &mut rects[..n] {
                        *r = [r[0].min(x), r[1].min(y), r[2].max(x + 1), r[3].max(y + 1)];
                    }
                }
            }
        }
        e
    }

    /// The most surfaces along any texel's ray.
    pub fn depth(&self) -> u32 {
        self.faces.iter().map(|f| f.len() as u32).max().unwrap_or(0)
    }

    /// The cubes' worth of texels the first `layers` layers' passes draw.
    pub fn drawn_cubes(&self, layers: u32) -> f64 {
        let face = (self.size as f64).powi(2).max(1.0);
        let area = |r: &[u32; 4]| (r[2].saturating_sub(r[0]) as f64) * (r[3].saturating_sub(r[1]) as f64);
        self.faces.iter().flat_map(|f| f.iter().take(layers as usize)).map(area).sum::<f64>() / face / 6.0
    }

    /// Face `face`'s rectangle in layer `k`, one texel wider on each side (within the
    /// face: the count and the peel are different pipelines, whose coverage of a triangle's
    /// edge could differ by a rounding), `None` where the layer holds nothing there.
    fn rect(&self, face: usize, k: u32) -> Option<vk::Rect2D> {
        let r = self.faces[face].get(k as usize)?;
        let (x0, y0) = (r[0].saturating_sub(1), r[1].saturating_sub(1));
        let (x1, y1) = ((r[2] + 1).min(self.size), (r[3] + 1).min(self.size));
        Some(vk::Rect2D { offset: vk::Offset2D { x: x0 as i32, y: y0 as i32 }, extent: vk::Extent2D { width: x1 - x0, height: y1 - y0 } })
    }
}

/// Half-precision normals hold material indices exactly up to 2048.
const HALF_MATERIALS: usize = 2048;

pub struct LayeredMaps {
    layers: u32,
    /// The depth complexity counted, and whether the GPU counted it.
    measured: Option<(u32, bool)>,
    /// Where each layer of each face holds surfaces (the GPU's count, at the peel's own size
    /// and views); `None` where the CPU counted (along fewer rays, which could miss a face's
    /// deepest texels): every layer drawn whole.
    extent: Option<PeelExtent>,
    depth: Vec<Image>,
    peel: vk::Pipeline,
    /// The last layer's pipeline where the peel is cut: the farthest surface.
    far: vk::Pipeline,
    nearest: vk::Sampler,
    /// Set-1 sets sampling depth buffer 0 and 1 as the previous layer.
    sets: Vec<(vk::DescriptorPool, vk::DescriptorSet)>,
    mode: CubeMode,
}

/// The objects that take the method share one map around `plan.layered_centre`, with its
/// own six views (`ViewLayout::layered`); their own cube views serve their other maps.
pub fn create(init: &StageInit, _objects: &[usize], maps: &mut Maps) -> Result<Box<dyn Stage>> {
    let me = LayeredMaps {
        layers: 0,
        measured: None,
        extent: None,
        depth: Vec::new(),
        peel: vk::Pipeline::null(),
        far: vk::Pipeline::null(),
        nearest: vk::Sampler::null(),
        sets: Vec::new(),
        mode: init.plan.quality.cube.cube_mode,
    };
    Ok(Box::new(build(init.ctx, me, |me| me.init(init, maps))?))
}

impl LayeredMaps {
    fn centre(&self, init: &StageInit) -> Vec3 {
        init.plan.layered_centre.unwrap_or(Vec3::ZERO)
    }

    fn init(&mut self, init: &StageInit, maps: &mut Maps) -> Result<()> {
        let (ctx, q) = (init.ctx, &init.plan.quality);
        self.layers = self.layer_count(init)?;
        self.allocate(init, maps)?;
        for i in 0..2 {
            let usage = vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT | vk::ImageUsageFlags::SAMPLED;
            let name = format!("layered.depth.{}", ["ping", "pong"][i]);
            let desc = ImageDesc {
                name: &name,
                format: DEPTH_FORMAT,
                width: q.cube.cube_size,
                height: q.cube.cube_size,
                kind: ImageKind::D2Array { layers: 6 },
                usage,
            };
            self.depth.push(Image::new(ctx, &desc)?);
        }
        self.nearest = sampler(ctx, "layered.previous_sampler", vk::Filter::NEAREST, vk::SamplerAddressMode::CLAMP_TO_EDGE)?;
        use crate::frame::layout::{binding, MAP_BINDINGS};
        for i in 0..2 {
            let (pool, set) = allocate_set(ctx, &format!("layered.peel_set{i}"), init.set_layouts[1], MAP_BINDINGS)?;
            self.sets.push((pool, set));
            let cis = vk::DescriptorType::COMBINED_IMAGE_SAMPLER;
            write_image(
                ctx,
                set,
                binding::LAYERED_PREVIOUS,
                0,
                cis,
                self.depth[i].view,
                self.nearest,
                vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            );
            for b in
                [binding::DISTANCE_MAPS, binding::REFRACTOR_MAPS, binding::BACKFACE_MAP, binding::LAYERED_MAPS, binding::LAYERED_NORMALS]
            {
                write_image(ctx, set, b, 0, cis, vk::ImageView::null(), self.nearest, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL);
            }
            crate::vk::pipeline::write_buffer(ctx, set, binding::THICKNESS, vk::DescriptorType::STORAGE_BUFFER, vk::Buffer::null());
        }
        self.peel = peel_pipeline(init, DepthOp::Nearer)?;
        if self.cut() {
            self.far = peel_pipeline(init, DepthOp::Farther)?;
        }
        self.far_counters(init, maps)
    }

    /// The counters of the pixels whose path met the farthest layer (`LAYERED_FAR`): there
    /// while the peel is cut and the device lets the camera pass count (its COUNT_FAR
    /// variant, `super::search_pass`), else absent (the pass's adds go to a null descriptor).
    fn far_counters(&self, init: &StageInit, maps: &mut Maps) -> Result<()> {
        let wanted = self.cut() && init.ctx.fragment_stores;
        if wanted == maps.has(&LAYERED_FAR) {
            return Ok(());
        }
        if let Some(mut b) = maps.take_buffer(&LAYERED_FAR) {
            b.destroy(init.ctx);
        }
        if wanted {
            let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
            let bytes = 4 * init.scene.meshes.len().max(1) as u64;
            maps.set_buffer(&LAYERED_FAR, Buffer::new(init.ctx, "layered.far_layer_pixels", bytes, usage, MemoryLocation::GpuToCpu)?);
        }
        Ok(())
    }

    /// Whether the peeled layers are fewer than the surfaces along some texel's ray: one
    /// more layer then holds the farthest surface.
    fn cut(&self) -> bool {
        self.measured.is_some_and(|(count, _)| count > self.layers)
    }

    /// The layers allocated: those peeled, and the farthest surface's where the peel is cut.
    fn allocated(&self) -> u32 {
        self.layers + u32::from(self.cut())
    }

    /// The knob, or the depth complexity counted now (at least one layer).
    /// The knob, or the depth complexity counted now (at least one layer); counted under a
    /// knob too, to know whether the peel is cut (`cut`).
    fn layer_count(&mut self, init: &StageInit) -> Result<u32> {
        let q = &init.plan.quality;
        let centre = self.centre(init);
        let (count, gpu) = if init.ctx.queue.is_some() {
            let extent = count_on_gpu(init, centre)?;
            let depth = extent.depth();
            self.extent = Some(extent);
            (depth, true)
        } else {
            self.extent = None;
            (count_on_cpu(init.scene, centre, q.cube.cube_size.min(64)), false)
        };
        self.measured = Some((count, gpu));
        Ok(super::peeled(q, Some(count)).0)
    }

    /// The layers' two images, `layers` cubes each, into the frame's maps.
    fn allocate(&mut self, init: &StageInit, maps: &mut Maps) -> Result<()> {
        let (ctx, q) = (init.ctx, &init.plan.quality);
        let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC;
        let kind = ImageKind::CubeArray { cubes: self.allocated() };
        let s = q.cube.cube_size;
        let radiance =
            ImageDesc { name: "layered.cubes", format: radiance_format(q.cube.cube_precision), width: s, height: s, kind, usage };
        maps.set_image(&LAYERED, Image::new(ctx, &radiance)?);
        let normals =
            ImageDesc { name: "layered.normals", format: normal_format(q, init.scene.materials.len()), width: s, height: s, kind, usage };
        maps.set_image(&LAYERED_NORMALS, Image::new(ctx, &normals)?);
        Ok(())
    }
}

/// `layered.peel`'s pipeline: the nearest surface behind the previous layer, or
/// (`DepthOp::Farther`, `layered.peel_far`) the farthest surface.
fn peel_pipeline(init: &StageInit, depth_op: DepthOp) -> Result<vk::Pipeline> {
    let q = &init.plan.quality;
    let formats = [radiance_format(q.cube.cube_precision), normal_format(q, init.scene.materials.len())];
    let desc = GraphicsDesc {
        name: if depth_op == DepthOp::Farther { "layered.peel_far" } else { "layered.peel" },
        vertex: "scene/mesh.vert",
        fragment: if crate::methods::caustics::project::texture_space(init.plan) {
            "layered/peel.frag#CAUSTICS_TEXTURE"
        } else {
            "layered/peel.frag"
        },
        vertex_input: VertexInput::Mesh,
        color_formats: &formats,
        depth_format: Some(DEPTH_FORMAT),
        depth_test: true,
        depth_write: true,
        view_mask: crate::frame::view_mask(q.cube.cube_mode),
        cull: vk::CullModeFlags::NONE,
        multisample: Multisample::OFF,
        blend: Blend::Replace,
        depth_op,
    };
    graphics_pipeline(init.ctx, init.layout, &desc)
}

fn normal_format(q: &Quality, materials: usize) -> vk::Format {
    match q.cube.cube_precision {
        Precision::Half if materials <= HALF_MATERIALS => vk::Format::R16G16B16A16_SFLOAT,
        _ => vk::Format::R32G32B32A32_SFLOAT,
    }
}

/// `layered.count`: every surface rendered into the six faces around `centre` with
/// additive blending (one per surface along each texel's ray), read back: where each layer
/// of each face holds surfaces.
fn count_on_gpu(init: &StageInit, centre: Vec3) -> Result<PeelExtent> {
    let ctx = init.ctx;
    let size = init.plan.quality.cube.cube_size;
    let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC;
    let desc = ImageDesc {
        name: "layered.count",
        format: vk::Format::R32_SFLOAT,
        width: size,
        height: size,
        kind: ImageKind::D2Array { layers: 6 },
        usage,
    };
    let mut target = Image::new(ctx, &desc)?;
    let mut layout = vk::PipelineLayout::null();
    let mut pipeline = vk::Pipeline::null();
    let result = (|| {
        layout = crate::vk::pipeline::pipeline_layout(ctx, "layered.count_layout", &[], 64, vk::ShaderStageFlags::VERTEX)?;
        let formats = [vk::Format::R32_SFLOAT];
        pipeline = graphics_pipeline(
            ctx,
            layout,
            &GraphicsDesc {
                name: "layered.count",
                vertex: "layered/count.vert",
                fragment: "layered/count.frag",
                vertex_input: VertexInput::Positions,
                color_formats: &formats,
                depth_format: None,
                depth_test: false,
                depth_write: false,
                view_mask: 0,
                cull: vk::CullModeFlags::NONE,
                multisample: Multisample::OFF,
                blend: Blend::Add,
                depth_op: DepthOp::Nearer,
            },
        )?;
        ctx.one_shot(|cmd| {
            if let Some(b) = target.transition(Access::ColorAttachment) {
                unsafe { ctx.device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&[b])) };
            }
            for face in 0..6 {
                let colors = [target.layer_view(face)];
                let t = Target {
                    color: &colors,
                    depth: None,
                    width: size,
                    height: size,
                    view_mask: 0,
                    layer_count: 1,
                    clear_color: [0.0; 4],
                    clear: true,
                };
                begin_rendering(ctx, cmd, &t);
                let vp = crate::cube::face_view_proj(face as usize, centre, init.plan.cube_near);
                unsafe {
                    ctx.device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pipeline);
                    ctx.device.cmd_push_constants(cmd, layout, vk::ShaderStageFlags::VERTEX, 0, bytemuck::bytes_of(&vp.to_cols_array()));
                }
                init.gpu.bind_geometry(ctx, cmd);
                for d in init.gpu.draws.iter().filter(|d| d.index_count > 0) {
                    unsafe { ctx.device.cmd_draw_indexed(cmd, d.index_count, 1, d.first_index, d.vertex_offset, 0) };
                }
                unsafe { ctx.device.cmd_end_rendering(cmd) };
            }
            Ok(())
        })?;
        let counts = crate::vk::read_image(ctx, &target)?;
        Ok(PeelExtent::from_counts(size, |face, x, y| counts.texel(face as u32, x, y)[0].round().max(0.0) as u32))
    })();
    destroy_pipelines(ctx, &mut [pipeline]);
    crate::vk::pipeline::destroy_pipeline_layout(ctx, layout);
    target.destroy(ctx);
    result
}

/// The depth complexity along the rays through the texel centres of six `size`² faces
/// around `centre`, by the reference's BVH (every surface crossed counts).
pub fn count_on_cpu(scene: &crate::scene::Scene, centre: Vec3, size: u32) -> u32 {
    extent_on_cpu(scene, centre, size).depth()
}

/// [`count_on_cpu`] texel by texel: where each layer of each face holds surfaces.
pub fn extent_on_cpu(scene: &crate::scene::Scene, centre: Vec3, size: u32) -> PeelExtent {
    let bvh = crate::reference::bvh::Bvh::new(scene);
    let o = centre.as_dvec3();
    let mut counts = vec![0u32; 6 * (size * size) as usize];
    for face in 0..6 {
        for j in 0..size {
            for i in 0..size {
                let (s, t) = ((i as f32 + 0.5) / size as f32, (j as f32 + 0.5) / size as f32);
                let d: DVec3 = crate::cube::face_st_to_direction(face, s, t).as_dvec3().normalize();
                let (mut t_min, mut skip, mut n) = (0.0, None, 0);
                while let Some(h) = bvh.intersect(o, d, t_min, f64::INFINITY, skip) {
                    n += 1;
                    t_min = h.t;
                    skip = Some(h.triangle);
                    if n >= 64 {
                        break;
                    }
                }
                counts[(face * size as usize + j as usize) * size as usize + i as usize] = n;
            }
        }
    }
    PeelExtent::from_counts(size, |face, x, y| counts[(face * size as usize + y as usize) * size as usize + x as usize])
}

impl Stage for LayeredMaps {
    fn name(&self) -> &'static str {
        "layered.peel"
    }

    /// Peels the layers: layer k tests against layer k−1's depth (sampled from the other
    /// depth buffer); six passes per layer, or one multiview pass.
    fn record(&mut self, rec: &mut Recorder, f: &FrameInputs, io: &mut FrameIo) {
        // Taken out of the frame's maps while written, put back after.
        let (Some(mut radiance), Some(mut normals)) = (io.maps.take_image(&LAYERED), io.maps.take_image(&LAYERED_NORMALS)) else { return };
        let Some(view) = io.views.first(super::VIEWS) else {
            io.maps.set_image(&LAYERED, radiance);
            io.maps.set_image(&LAYERED_NORMALS, normals);
            return;
        };
        let mut pass =
            rec.pass("layered.peel").writes(&mut radiance, Access::ColorAttachment).writes(&mut normals, Access::ColorAttachment);
        for img in io.scene_images.iter().copied().chain(io.maps.shadow_reads()) {
            pass = pass.reads(img, Access::FragmentSampled);
        }
        let open = pass.begin();
        let (ctx, cmd) = (rec.ctx, rec.cmd);
        let size = radiance.width;
        let six = self.mode == CubeMode::SixPasses;
        let eyes = io.view_eyes;
        let cut = self.cut();
        for k in 0..self.allocated() {
            let (cur, prev) = ((k % 2) as usize, ((k + 1) % 2) as usize);
            rec.barrier(&mut self.depth[cur], Access::DepthAttachment);
            // Layer 0 samples nothing, but its set names the other buffer all the same.
            rec.barrier(&mut self.depth[prev], Access::FragmentSampled);
            // A cut peel's extra layer: the farthest surface, peeling nothing.
            let far = cut && k == self.layers;
            // Where this layer of a face holds surfaces: the scissor of its draws (none: the
            // layer is cleared there, not drawn); the whole face without a GPU count, in one
            // multiview pass, and in the farthest surfaces' layer.
            let whole = vk::Rect2D { offset: vk::Offset2D::default(), extent: vk::Extent2D { width: size, height: size } };
            let area = |face: u32| match &self.extent {
                Some(e) if six && !far => e.rect(face as usize, k),
                _ => Some(whole),
            };
            let first = if k == 0 || far { LAYERED_FIRST } else { 0 };
            let faces: &[u32] = if six { &[0, 1, 2, 3, 4, 5] } else { &[0] };
            for &face in faces {
                let (colors, depth, mask) = if six {
                    ([radiance.layer_view(6 * k + face), normals.layer_view(6 * k + face)], self.depth[cur].layer_view(face), 0)
                } else {
                    ([radiance.group_view(k), normals.group_view(k)], self.depth[cur].group_view(0), 0x3F)
                };
                let t = Target {
                    color: &colors,
                    depth: Some(depth),
                    width: size,
                    height: size,
                    view_mask: mask,
                    layer_count: 1,
                    clear_color: [0.0, 0.0, 0.0, 1e30],
                    clear: true,
                };
                begin_rendering(ctx, cmd, &t);
                if far {
                    crate::methods::cube_maps::clear_depth(ctx, cmd, size, 1.0);
                }
                f.bind(ctx, cmd, if far { self.far } else { self.peel });
                f.bind_maps(ctx, cmd, self.sets[prev].1);
                let v = view + face;
                let eye = eyes.get(v as usize).copied().unwrap_or_default();
                let flags = f.flags | first | if six { face << LAYERED_FACE_SHIFT } else { 0 };
                let drawn = area(face);
                if let Some(r) = drawn.filter(|r| *r != whole) {
                    unsafe { ctx.device.cmd_set_scissor(cmd, 0, &[r]) };
                }
                for d in f.scene.draws.iter().filter(|d| {
                    d.index_count > 0 && drawn.is_some() && (!six || crate::cube::face_sees_box(face as usize, eye, d.lo, d.hi))
                }) {
                    f.push_flags(ctx, cmd, v, d.mesh, flags);
                    unsafe { ctx.device.cmd_draw_indexed(cmd, d.index_count, 1, d.first_index, d.vertex_offset, 0) };
                }
                unsafe { ctx.device.cmd_end_rendering(cmd) };
            }
        }
        rec.end(open);
        io.maps.set_image(&LAYERED, radiance);
        io.maps.set_image(&LAYERED_NORMALS, normals);
    }

    fn stats(&self, _ctx: &Context) -> Vec<(String, f64)> {
        let mut s = vec![("layered.layers".to_string(), self.layers as f64)];
        if let Some((count, gpu)) = self.measured {
            s.push(("layered.depth_complexity".into(), count as f64));
            s.push(("layered.counted_on_gpu".into(), if gpu { 1.0 } else { 0.0 }));
        }
        // 1 where the peel is cut and one more layer holds the farthest surfaces.
        s.push(("layered.far_layer".into(), if self.cut() { 1.0 } else { 0.0 }));
        // The (layer, face) passes that draw the scene, of 6 per layer, and the texels
        // they draw, in cubes (six-pass cubes counted on the GPU).
        if let (Some(e), CubeMode::SixPasses) = (&self.extent, self.mode) {
            let drawn: usize = e.faces.iter().map(|f| f.len().min(self.layers as usize)).sum::<usize>() + 6 * usize::from(self.cut());
            s.push(("layered.faces_peeled".into(), drawn as f64));
            s.push(("layered.cubes_drawn".into(), e.drawn_cubes(self.layers) + f64::from(u32::from(self.cut()))));
        }
        s
    }

    /// Objects moved: the depth complexity is counted again (under a `layers` knob too:
    /// whether the peel is cut), and the layers are reallocated when what they need changed
    /// (the renderer rewrites the descriptors).
    fn update(&mut self, init: &StageInit, changes: &crate::scene::update::Changes, maps: &mut Maps) -> Result<()> {
        if changes.moved.is_empty() {
            return Ok(());
        }
        let allocated = self.allocated();
        self.layers = self.layer_count(init)?;
        if self.allocated() != allocated {
            for i in [maps.take_image(&LAYERED), maps.take_image(&LAYERED_NORMALS)].iter_mut().flatten() {
                i.destroy(init.ctx);
            }
            self.allocate(init, maps)?;
        }
        if self.cut() && self.far == vk::Pipeline::null() {
            self.far = peel_pipeline(init, DepthOp::Farther)?;
        }
        self.far_counters(init, maps)
    }

    fn destroy(&mut self, ctx: &Context) {
        destroy_pipelines(ctx, &mut [self.peel, self.far]);
        for d in &mut self.depth {
            d.destroy(ctx);
        }
        self.depth.clear();
        for (pool, _) in self.sets.drain(..) {
            unsafe { ctx.device.destroy_descriptor_pool(pool, ctx.alloc()) };
        }
        if self.nearest != vk::Sampler::null() {
            unsafe { ctx.device.destroy_sampler(self.nearest, ctx.alloc()) };
            self.nearest = vk::Sampler::null();
        }
    }
}

impl Owner for LayeredMaps {
    fn destroy(&mut self, ctx: &Context) {
        Stage::destroy(self, ctx)
    }
}
