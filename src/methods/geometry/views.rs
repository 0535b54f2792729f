//! The GPU side of planar mirrors' views (§5): a scratch target each mirrored view renders
//! into (the camera target's format, size and samples, so that every camera pass draws into
//! it with its own pipeline), and the layered image the views are copied (or, with MSAA,
//! resolved) into, one layer per view: a view samples its children's layers while it renders
//! into the scratch target, and is copied into its own layer afterwards.

use ash::vk;
use glam::{Mat4, Vec3, Vec4};

use super::mirror::{oblique, reflection, Limits, Mirror, MirrorFrame, Rect};
use crate::cube::face_view_proj;
use crate::frame::direct::{DEPTH_FORMAT, TARGET_FORMAT};
use crate::frame::layout::{FLAG_MIRROR_DEPTH_END, FLAG_MIRROR_VIEW, MIRROR_COUNT_SHIFT, MIRROR_LAYER_SHIFT};
use crate::frame::stage::{FramePart, Maps, StageInit, ViewFrame, ViewLayout, ViewPass, EXTRA_VIEWS};
use crate::frame::FrameInputs;
use crate::gpu_scene::GpuView;
use crate::plan::types::Plan;
use crate::scene::Scene;
use crate::vk::pipeline::{graphics_pipeline, Blend, DepthOp, GraphicsDesc, Multisample, VertexInput};
use crate::vk::{Access, Context, Image, ImageDesc, ImageKind, Recorder};
use crate::Result;

pub struct MirrorViews {
    meshes: Vec<usize>,
    limits: Limits,
    pub scratch: Image,
    pub depth: Image,
    samples: u32,
    /// `geometry.stencil`: the mirror drawn from the parent view at the farthest depth.
    mask: vk::Pipeline,
    /// This frame's views (planned when the view table is written).
    pub frame: MirrorFrame,
}

impl MirrorViews {
    /// The views' images for a plan with planar mirrors (`None` without): the layered
    /// image goes into `maps` (set 0, binding 9), the scratch target stays here.
    pub fn new(
        ctx: &Context,
        plan: &Plan,
        size: (u32, u32),
        multisample: Multisample,
        layout: vk::PipelineLayout,
        maps: &mut Maps,
    ) -> Result<Option<MirrorViews>> {
        let layers = plan.mirror_layers;
        if plan.mirrors.is_empty() || layers == 0 {
            return Ok(None);
        }
        let (width, height) = size;
        let usage = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST;
        let desc =
            ImageDesc { name: "geometry.mirror_views", format: TARGET_FORMAT, width, height, kind: ImageKind::D2Array { layers }, usage };
        maps.set_image(&super::slots::MIRROR_VIEWS, Image::new(ctx, &desc)?);
        let samples = multisample.samples;
        let kind = if samples > 1 { ImageKind::D2Multisample { samples } } else { ImageKind::D2 };
        let mut me = MirrorViews {
            meshes: plan.mirrors.clone(),
            limits: Limits { depth: plan.quality.frame.depth, budget: plan.quality.geometry.mirror_budget, layers },
            scratch: Image::placeholder(),
            depth: Image::placeholder(),
            samples,
            mask: vk::Pipeline::null(),
            frame: MirrorFrame::default(),
        };
        let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC;
        let made = Image::new(ctx, &ImageDesc { name: "geometry.mirror_view", format: TARGET_FORMAT, width, height, kind, usage })
            .and_then(|s| {
                me.scratch = s;
                let usage = vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT;
                Image::new(ctx, &ImageDesc { name: "geometry.mirror_view.depth", format: DEPTH_FORMAT, width, height, kind, usage })
            })
            .and_then(|d| {
                me.depth = d;
                let formats = [TARGET_FORMAT];
                let desc = GraphicsDesc {
                    name: "geometry.stencil",
                    vertex: "scene/mesh.vert",
                    fragment: "geometry/map_mask.frag",
                    vertex_input: VertexInput::Mesh,
                    color_formats: &formats,
                    depth_format: Some(DEPTH_FORMAT),
                    depth_test: true,
                    depth_write: true,
                    view_mask: 0,
                    cull: vk::CullModeFlags::NONE,
                    multisample: Multisample { samples, per_sample: false },
                    blend: Blend::Replace,
                    depth_op: DepthOp::Always,
                };
                me.mask = graphics_pipeline(ctx, layout, &desc)?;
                Ok(Image::placeholder())
            });
        match made {
            Ok(_) => Ok(Some(me)),
            Err(e) => {
                me.destroy(ctx);
                Err(e)
            }
        }
    }

    /// Plans this frame's views from the camera (`view_proj`, `eye`, the frustum's corner
    /// cosine) over the current scene.
    pub fn plan_frame(&mut self, scene: &Scene, view_proj: Mat4, eye: Vec3, cos_corner: f32) {
        let size = (self.scratch.width, self.scratch.height);
        self.frame = MirrorFrame::plan(scene, &self.meshes, view_proj, eye, size, cos_corner, self.limits);
    }

    /// The push flags of the planar mirrors the camera (`None`) or view `v` sees: which
    /// layer of which image holds each one's reflection. Mirrors not listed fall back.
    /// A view at the recursion depth has no children: its planar objects get
    /// FLAG_MIRROR_DEPTH_END instead (their paths end there, as the reference's do).
    pub fn child_flags(&self, v: Option<usize>) -> Vec<(usize, u32)> {
        if v.is_some_and(|v| self.frame.views[v].level >= self.limits.depth) {
            return self.meshes.iter().map(|&m| (m, FLAG_MIRROR_DEPTH_END)).collect();
        }
        let flags = |first: u32, count: u32| FLAG_MIRROR_VIEW | (first << MIRROR_LAYER_SHIFT) | (count << MIRROR_COUNT_SHIFT);
        self.frame.children(v).into_iter().map(|(mesh, first, count)| (mesh, flags(first, count))).collect()
    }

    /// (layers allocated, bytes of one view's layer, bytes of the scratch colour and depth
    /// targets): the layered image holds one single-sample RGBA32F layer per view; the
    /// scratch targets have the camera's samples.
    pub fn memory(&self) -> (u32, u64, u64) {
        let pixels = self.scratch.width as u64 * self.scratch.height as u64;
        let colour = crate::vk::format_bytes(TARGET_FORMAT) as u64;
        let depth = crate::vk::format_bytes(DEPTH_FORMAT) as u64;
        (self.limits.layers, pixels * colour, pixels * self.samples as u64 * (colour + depth))
    }

    /// Copies (or, with MSAA, resolves) the scratch target's `rect` into layer `layer` of
    /// `dst` (the views' layered image).
    pub fn record_store(&mut self, rec: &mut Recorder, dst: &mut Image, layer: u32, rect: Rect) {
        let open = rec.pass("geometry.mirror_view").reads(&self.scratch, Access::TransferSrc).writes(dst, Access::TransferDst).begin();
        let sub = |base_array_layer| vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer,
            layer_count: 1,
        };
        let offset = vk::Offset3D { x: rect.x0 as i32, y: rect.y0 as i32, z: 0 };
        let extent = vk::Extent3D { width: rect.x1 - rect.x0, height: rect.y1 - rect.y0, depth: 1 };
        let (s, d) = (vk::ImageLayout::TRANSFER_SRC_OPTIMAL, vk::ImageLayout::TRANSFER_DST_OPTIMAL);
        let (ctx, cmd) = (rec.ctx, rec.cmd);
        unsafe {
            if self.samples > 1 {
                let region = vk::ImageResolve {
                    src_subresource: sub(0),
                    src_offset: offset,
                    dst_subresource: sub(layer),
                    dst_offset: offset,
                    extent,
                };
                ctx.device.cmd_resolve_image(cmd, self.scratch.raw, s, dst.raw, d, &[region]);
            } else {
                let region =
                    vk::ImageCopy { src_subresource: sub(0), src_offset: offset, dst_subresource: sub(layer), dst_offset: offset, extent };
                ctx.device.cmd_copy_image(cmd, self.scratch.raw, s, dst.raw, d, &[region]);
            }
        }
        rec.end(open);
    }

    /// `geometry.stencil`: clears the scratch depth within `area` to the nearest depth and
    /// draws mesh `mesh` (the view's mirror, or its refractor) from its parent's view
    /// `parent_view` at the farthest: the view's passes then draw on the mirror's pixels
    /// only (the depth buffer is the mask, as a stencil would be).
    pub fn record_stencil(&mut self, rec: &mut Recorder, f: &FrameInputs, parent_view: u32, mesh: usize, area: vk::Rect2D) {
        // Its own profiler row, not the views' scope.
        let scope = rec.scope.take();
        let open = rec
            .pass("geometry.stencil")
            .writes(&mut self.scratch, Access::ColorAttachment)
            .writes(&mut self.depth, Access::DepthAttachment)
            .begin();
        let (ctx, cmd) = (rec.ctx, rec.cmd);
        crate::frame::begin_camera_rendering(ctx, cmd, &self.scratch, &self.depth, area, false);
        let attachment = vk::ClearAttachment {
            aspect_mask: vk::ImageAspectFlags::DEPTH,
            color_attachment: 0,
            clear_value: vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 } },
        };
        let rect = vk::ClearRect { rect: area, base_array_layer: 0, layer_count: 1 };
        unsafe { ctx.device.cmd_clear_attachments(cmd, &[attachment], &[rect]) };
        f.bind(ctx, cmd, self.mask);
        for d in f.scene.draws.iter().filter(|d| d.mesh as usize == mesh) {
            f.push_flags(ctx, cmd, parent_view, d.mesh, f.flags);
            unsafe { ctx.device.cmd_draw_indexed(cmd, d.index_count, 1, d.first_index, d.vertex_offset, 0) };
        }
        unsafe { ctx.device.cmd_end_rendering(cmd) };
        rec.end(open);
        rec.scope = scope;
    }

    pub fn destroy(&mut self, ctx: &Context) {
        self.scratch.destroy(ctx);
        self.depth.destroy(ctx);
        crate::frame::destroy_pipelines(ctx, &mut [self.mask]);
    }
}

/// The cosine of the angle between a perspective projection's axis and its frustum's corner
/// rays (`proj` the camera's, as `Renderer::camera_view_proj` builds it).
pub fn cos_corner(yfov: f32, aspect: f32) -> f32 {
    let ty = (0.5 * yfov).tan();
    let tx = ty * aspect;
    1.0 / (1.0 + tx * tx + ty * ty).sqrt()
}

/// A rectangle as the render area it is.
pub fn render_area(r: Rect) -> vk::Rect2D {
    vk::Rect2D { offset: vk::Offset2D { x: r.x0 as i32, y: r.y0 as i32 }, extent: vk::Extent2D { width: r.x1 - r.x0, height: r.y1 - r.y0 } }
}

/// The geometry family's part of a frame (§5): planar mirrors' views, recorded before the
/// camera's own, and the mirrored cube views of planar mirrors inside cube maps.
pub struct PlanarViews {
    /// `None` when the plan has no view layers (no planar mirror, or a budget of 0).
    mirrors: Option<MirrorViews>,
}

/// `registry::Family::frame_part` of the geometry family.
pub fn create_frame_part(init: &StageInit, maps: &mut Maps) -> Result<Option<Box<dyn FramePart>>> {
    let plan = init.plan;
    if plan.mirrors.is_empty() && plan.map_mirrors.is_empty() {
        return Ok(None);
    }
    let mirrors = MirrorViews::new(init.ctx, plan, (init.width, init.height), init.multisample, init.layout, maps)?;
    if counts_fallbacks(init) {
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
        let bytes = 4 * init.scene.meshes.len().max(1) as u64;
        let counts = crate::vk::Buffer::new(init.ctx, "geometry.fallback_pixels", bytes, usage, crate::vk::MemoryLocation::GpuToCpu)?;
        maps.set_buffer(&super::slots::FALLBACKS, counts);
    }
    Ok(Some(Box::new(PlanarViews { mirrors })))
}

/// Whether the frame counts the planar objects' fallback fragments: some planar object's
/// views the budget can cut (the plan gave it maps of its own for the branches it leaves
/// out, `super::plan_fallback_maps`), and the device lets fragment shaders write.
fn counts_fallbacks(init: &StageInit) -> bool {
    let planar = [super::PLANAR_MIRROR, super::PLANAR_REFRACTION];
    let own_maps = |o: &crate::plan::types::ObjectPlan| o.maps.iter().any(|m| m.pass == crate::methods::distance::DISTANCE_CUBES.name);
    init.ctx.fragment_stores && init.plan.objects.iter().any(|o| planar.contains(&o.method) && own_maps(o))
}

/// `geometry.mirror` / `geometry.refract`: the plain camera pass, or where the fallbacks are
/// counted (`create_frame_part` made the counters: the plan gives the objects maps for the
/// branches the budget cuts, and the device lets fragment shaders write) its COUNT_FALLBACKS
/// variant.
pub fn counting_pass(init: &StageInit, plan: &crate::plan::types::CameraPlan) -> Result<Box<dyn crate::frame::stage::Stage>> {
    let variant = counts_fallbacks(init).then_some("COUNT_FALLBACKS");
    Ok(Box::new(crate::frame::camera::CameraShade::with_extra(init.ctx, init.layout, plan, init.multisample, variant, None)?))
}

impl FramePart for PlanarViews {
    fn write_views(&mut self, fr: &ViewFrame, table: &mut [GpuView]) {
        if let Some(m) = self.mirrors.as_mut() {
            m.plan_frame(fr.scene, fr.view_proj, fr.eye, cos_corner(fr.yfov, fr.aspect));
            for (i, v) in m.frame.views.iter().enumerate() {
                if let Some(slot) = fr.layout.first(EXTRA_VIEWS).and_then(|first| table.get_mut(first as usize + i)) {
                    // Rasterisation clips at the mirror (oblique near plane); pixels unproject
                    // to rays through the plain mirrored projection.
                    *slot = GpuView {
                        view_proj: v.view_proj.to_cols_array_2d(),
                        inv_view_proj: v.plain_view_proj.inverse().to_cols_array_2d(),
                        eye: v.eye.extend(0.0).to_array(),
                        dir: [0.0, 0.0, 0.0, v.hair],
                        clip: v.clip.to_array(),
                    };
                }
            }
        }
        if !fr.plan.map_mirrors.is_empty() {
            map_mirror_views(fr.plan, fr.layout, fr.scene, table);
        }
    }

    /// Planar mirrors' views, deepest first: each renders the camera-dependent stages from
    /// its mirrored camera into the scratch target, within its mirror's pixels, and is
    /// stored in its layer for the views (and the camera) that see the mirror.
    fn record_views(
        &mut self,
        rec: &mut Recorder,
        f: &FrameInputs,
        layout: &ViewLayout,
        maps: &mut Maps,
        camera_stages: &mut dyn FnMut(&mut Recorder, ViewPass),
    ) -> bool {
        let Some(mv) = self.mirrors.as_mut() else { return false };
        let first = layout.first(EXTRA_VIEWS).expect("planar mirrors declare their views");
        rec.scope = Some("geometry.mirror_view");
        for i in mv.frame.order() {
            let v = mv.frame.views[i].clone();
            let views = ViewLayout { camera: first + i as u32, ..layout.clone() };
            let flags = mv.child_flags(Some(i));
            let area = render_area(v.rect);
            // geometry.stencil: the mirror's pixels (as its parent sees them) marked in the
            // scratch depth; the view's passes draw there only. With MSAA the view renders
            // its whole rectangle: an edge pixel of the mirror averages samples beyond it.
            let masked = mv.samples == 1;
            if masked {
                let parent_view = v.parent.map_or(layout.camera, |p| first + p as u32);
                let mesh = mv.frame.mirrors[v.mirror].mesh;
                mv.record_stencil(rec, f, parent_view, mesh, area);
            }
            let pass = ViewPass {
                views,
                target: &mut mv.scratch,
                depth: &mut mv.depth,
                maps: &mut *maps,
                area,
                object_flags: &flags,
                depth_masked: masked,
            };
            camera_stages(rec, pass);
            if let Some(dst) = maps.image_mut(&super::slots::MIRROR_VIEWS) {
                mv.record_store(rec, dst, v.layer, v.rect);
            }
        }
        rec.scope = None;
        !mv.frame.views.is_empty()
    }

    fn camera_flags(&self) -> Vec<(usize, u32)> {
        self.mirrors.as_ref().map_or_else(Vec::new, |m| m.child_flags(None))
    }

    /// Each mirrored view records the camera's passes again.
    fn extra_views(&self) -> u32 {
        self.mirrors.as_ref().map_or(0, |m| m.limits.layers)
    }

    fn stats(&self) -> Vec<(String, f64)> {
        let Some(m) = &self.mirrors else { return Vec::new() };
        // The views this frame rendered, their deepest level, and the mirrors that showed
        // the fallback for want of depth or budget.
        let f = &m.frame;
        let (layers, view, scratch) = m.memory();
        vec![
            ("geometry.mirror_views".into(), f.views.len() as f64),
            ("geometry.mirror_depth".into(), f.views.iter().map(|v| v.level).max().unwrap_or(0) as f64),
            ("geometry.mirror_fallbacks".into(), f.fallbacks as f64),
            // Memory (issue 11): the layers allocated for the plan's views, the bytes of one
            // view's layer, and the scratch target every view renders into (colour + depth).
            ("geometry.mirror_layers".into(), layers as f64),
            ("geometry.mirror_view_bytes".into(), view as f64),
            ("geometry.mirror_scratch_bytes".into(), scratch as f64),
        ]
    }

    fn destroy(&mut self, ctx: &Context) {
        if let Some(m) = self.mirrors.as_mut() {
            m.destroy(ctx);
        }
        self.mirrors = None;
    }
}

/// The mirrored cube views of planar mirrors inside cube maps (§5 inside §3/§4): per
/// cube-mapped object, per mirror of `plan.map_mirrors`, per face, the face's view mirrored
/// through the mirror's plane (oriented towards the reference point) with an oblique near
/// plane there, from the mirrored reference point. A mirror hidden, of no plane, or with
/// the reference point in its plane keeps an empty view (its mask draws nothing then).
fn map_mirror_views(plan: &Plan, layout: &ViewLayout, scene: &Scene, views: &mut [GpuView]) {
    let near = plan.cube_near;
    // A cube face's corner rays make an angle of arccos(1/√3) with its axis.
    let cos_corner = 1.0 / 3f32.sqrt();
    let mirrors: Vec<Option<Mirror>> = plan.map_mirrors.iter().map(|&m| Mirror::of(scene, m).into_iter().next()).collect();
    let Some(first) = layout.first(crate::methods::cube_maps::MAP_MIRROR_VIEWS) else { return };
    for (i, e) in plan.envmaps.iter().enumerate() {
        let base = first + (6 * plan.map_mirrors.len() * i) as u32;
        let p = e.reference_point;
        for (k, m) in mirrors.iter().enumerate() {
            let Some(m) = m else { continue };
            let side = m.plane.truncate().dot(p) + m.plane.w;
            if side.abs() <= m.hair() {
                continue;
            }
            let plane = if side > 0.0 { m.plane } else { -m.plane };
            let r = reflection(plane);
            let keep = plane - Vec4::new(0.0, 0.0, 0.0, m.hair());
            let eye = r.transform_point3(p);
            for f in 0..6 {
                let plain = face_view_proj(f, p, near) * r;
                views[(base + 6 * k as u32 + f as u32) as usize] = GpuView {
                    view_proj: oblique(plain, keep, cos_corner).to_cols_array_2d(),
                    inv_view_proj: plain.inverse().to_cols_array_2d(),
                    eye: eye.extend(0.0).to_array(),
                    dir: [0.0, 0.0, 0.0, m.hair()],
                    clip: keep.to_array(),
                };
            }
        }
    }
}
