//! The passes every frame may need, whatever its methods: shadows, direct light, the
//! camera passes' machinery, and the frame's bindings and views (`stage`). One file per
//! pass, each with its resources in one struct (`new` creates everything, `destroy` frees
//! everything) and a `record` that reads like a sentence: declare reads and writes, render,
//! close. Mirrors `glsl/scene/` and `glsl/shadow/`.

pub mod camera;
pub mod cube_deps;
pub mod direct;
pub mod ids;
pub mod knobs;
pub mod layout;
pub mod maps;
pub mod output;
pub mod schedule;
pub mod shadow;
pub mod shared;
pub mod stage;
pub mod views;
pub mod words;

pub use layout::{Push, FLAG_FIRST_CYCLE, FLAG_FRESNEL_EXACT, FLAG_HAS_ENVIRONMENT, FLAG_INTER_OBJECT, FLAG_PROXY_BOX};

use ash::vk;

use crate::gpu_scene::{Draw, GpuScene};
use crate::quality::CubeMode;
use crate::vk::{begin_rendering, Access, Context, Image, Recorder, Target};

pub const PUSH_BYTES: u32 = std::mem::size_of::<Push>() as u32;
const _: () = assert!(PUSH_BYTES as usize == 16 + 4 * words::COUNT, "words::COUNT is the push block's `words` length");

/// What every pass needs to draw the scene: geometry, the frame's descriptor set and
/// pipeline layout, and the frame-wide push-constant fields.
pub struct FrameInputs<'a> {
    pub scene: &'a GpuScene,
    pub set: vk::DescriptorSet,
    pub layout: vk::PipelineLayout,
    pub flags: u32,
    pub light_count: u32,
    /// `Push.words` of this frame (`words`).
    pub words: words::PushWords,
}

impl FrameInputs<'_> {
    pub fn bind(&self, ctx: &Context, cmd: vk::CommandBuffer, pipeline: vk::Pipeline) {
        unsafe {
            ctx.device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pipeline);
            ctx.device.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::GRAPHICS, self.layout, 0, &[self.set], &[]);
        }
        self.scene.bind_geometry(ctx, cmd);
    }

    /// Binds a maps set (set 1) for the passes of §4.
    pub fn bind_maps(&self, ctx: &Context, cmd: vk::CommandBuffer, maps: vk::DescriptorSet) {
        unsafe { ctx.device.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::GRAPHICS, self.layout, 1, &[maps], &[]) };
    }

    pub fn push(&self, ctx: &Context, cmd: vk::CommandBuffer, view: u32, object: u32) {
        self.push_flags(ctx, cmd, view, object, self.flags);
    }

    pub fn push_flags(&self, ctx: &Context, cmd: vk::CommandBuffer, view: u32, object: u32, flags: u32) {
        self.push_in(ctx, cmd, self.layout, view, object, flags);
    }

    /// `push_flags` into another pipeline layout with the same push range (a method's own
    /// stage with sets of its own).
    pub fn push_in(&self, ctx: &Context, cmd: vk::CommandBuffer, layout: vk::PipelineLayout, view: u32, object: u32, flags: u32) {
        let p = Push { view, object, flags, light_count: self.light_count, words: self.words.0 };
        unsafe {
            ctx.device.cmd_push_constants(
                cmd,
                layout,
                vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT | vk::ShaderStageFlags::COMPUTE,
                0,
                bytemuck::bytes_of(&p),
            )
        };
    }

    pub fn draw(&self, ctx: &Context, cmd: vk::CommandBuffer, view: u32, d: &Draw) {
        self.push(ctx, cmd, view, d.mesh);
        unsafe { ctx.device.cmd_draw_indexed(cmd, d.index_count, 1, d.first_index, d.vertex_offset, 0) };
    }

    /// The full-screen sky triangle (bound pipeline must be a sky pipeline).
    pub fn draw_sky(&self, ctx: &Context, cmd: vk::CommandBuffer, view: u32) {
        self.push(ctx, cmd, view, 0);
        unsafe { ctx.device.cmd_draw(cmd, 3, 1, 0, 0) };
    }
}

/// Renders the six faces of cube `cube` of `color` (a cube or cube-array attachment),
/// either in six passes or in one multiview pass. `draw(cmd, view)` records the draws of
/// one pass whose first view is `view` (the face's view, or the cube's first view with
/// multiview, where the shader adds gl_ViewIndex).
#[allow(clippy::too_many_arguments)]
pub fn render_cube_faces(
    rec: &Recorder,
    color: &Image,
    depth: &mut Image,
    cube: u32,
    view_base: u32,
    mode: CubeMode,
    clear_color: [f32; 4],
    draw: impl FnMut(vk::CommandBuffer, u32),
) {
    render_cube_faces_of(rec, color, depth, (cube, ALL_FACES), view_base, mode, clear_color, draw)
}

/// Every face of a cube (bit f: face f).
pub const ALL_FACES: u8 = 0x3F;

/// `render_cube_faces` for the faces of `faces` (bit f: face f) only: the others keep what
/// they hold. Multiview renders the six together, so any face renders all.
#[allow(clippy::too_many_arguments)]
pub fn render_cube_faces_of(
    rec: &Recorder,
    color: &Image,
    depth: &mut Image,
    (cube, faces): (u32, u8),
    view_base: u32,
    mode: CubeMode,
    clear_color: [f32; 4],
    mut draw: impl FnMut(vk::CommandBuffer, u32),
) {
    let (ctx, cmd) = (rec.ctx, rec.cmd);
    let size = color.width;
    if faces & ALL_FACES == 0 {
        return;
    }
    match mode {
        CubeMode::Multiview => {
            rec.barrier(depth, Access::DepthAttachment);
            let colors = [color.group_view(cube)];
            begin_rendering(
                ctx,
                cmd,
                &Target {
                    color: &colors,
                    depth: Some(depth.group_view(0)),
                    width: size,
                    height: size,
                    view_mask: 0x3F,
                    layer_count: 1,
                    clear_color,
                    clear: true,
                },
            );
            draw(cmd, view_base);
            unsafe { ctx.device.cmd_end_rendering(cmd) };
        }
        CubeMode::SixPasses => {
            for face in (0..6).filter(|f| faces & (1 << f) != 0) {
                rec.barrier(depth, Access::DepthAttachment);
                let colors = [color.layer_view(6 * cube + face)];
                begin_rendering(
                    ctx,
                    cmd,
                    &Target {
                        color: &colors,
                        depth: Some(depth.view),
                        width: size,
                        height: size,
                        view_mask: 0,
                        layer_count: 1,
                        clear_color,
                        clear: true,
                    },
                );
                draw(cmd, view_base + face);
                unsafe { ctx.device.cmd_end_rendering(cmd) };
            }
        }
    }
}

/// Starts rendering into the camera's colour and depth targets (cleared or kept) within
/// `area` (the whole target for the camera; a mirrored view's mirror pixels).
pub fn begin_camera_rendering(ctx: &Context, cmd: vk::CommandBuffer, target: &Image, depth: &Image, area: vk::Rect2D, clear: bool) {
    let colors = [target.view];
    let t = Target {
        color: &colors,
        depth: Some(depth.view),
        width: target.width,
        height: target.height,
        view_mask: 0,
        layer_count: 1,
        clear_color: [0.0; 4],
        clear,
    };
    crate::vk::begin_rendering_in(ctx, cmd, &t, area);
}

/// A 2D depth buffer of `width` × `height` (`DEPTH_FORMAT`) for a pass of its own.
pub fn depth_2d(ctx: &Context, name: &str, width: u32, height: u32) -> crate::Result<Image> {
    Image::new(
        ctx,
        &crate::vk::ImageDesc {
            name,
            format: direct::DEPTH_FORMAT,
            width,
            height,
            kind: crate::vk::ImageKind::D2,
            usage: vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
        },
    )
}

/// The depth buffer cube rendering needs: six layers for multiview, one otherwise.
pub fn cube_depth(ctx: &Context, name: &str, size: u32, mode: CubeMode) -> crate::Result<Image> {
    let kind = match mode {
        CubeMode::Multiview => crate::vk::ImageKind::D2Array { layers: 6 },
        CubeMode::SixPasses => crate::vk::ImageKind::D2,
    };
    Image::new(
        ctx,
        &crate::vk::ImageDesc {
            name,
            format: vk::Format::D32_SFLOAT,
            width: size,
            height: size,
            kind,
            usage: vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
        },
    )
}

pub fn view_mask(mode: CubeMode) -> u32 {
    match mode {
        CubeMode::Multiview => 0x3F,
        CubeMode::SixPasses => 0,
    }
}

/// Destroys pipelines that were created (null handles are skipped).
pub fn destroy_pipelines(ctx: &Context, pipelines: &mut [vk::Pipeline]) {
    for p in pipelines.iter_mut() {
        crate::vk::pipeline::release_pipeline(ctx, *p);
        *p = vk::Pipeline::null();
    }
}
