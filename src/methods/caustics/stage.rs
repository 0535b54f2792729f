//! The caustics stage: its passes (`caustics.receivers`, `caustics.photons`,
//! `caustics.splat` or `caustics.triangles`, `caustics.filter`), their pipelines and
//! images. The images the other passes sample (receiver distances, light cube maps, the
//! generator table) live in the frame's `Maps`; the photon images too, since the splat and
//! triangle shaders read them through the frame's set.

use ash::vk;
use glam::Vec3;

use super::atlas::Atlas;
use super::reach::Tracker;
use super::slots::{
    CAUSTICS, CAUSTIC_ATLAS, CAUSTIC_DISTANCES, CAUSTIC_FACES, CAUSTIC_LIGHT_MAP, CAUSTIC_MAPS, CAUSTIC_RAW, CAUSTIC_REACH,
    CAUSTIC_RECEIVER_IDS, CAUSTIC_SCREEN, CAUSTIC_TRIANGLES, PHOTON_COARSE, PHOTON_GRID, PHOTON_HITS, PHOTON_LIST, PHOTON_POWER,
};
use super::CausticsPlan;
use crate::frame::cube_deps::ShadowFrom;
use crate::frame::direct::DEPTH_FORMAT;
use crate::frame::layout::{GpuCausticCube, GpuCausticParams};
use crate::frame::layout::{
    CAUSTIC_BRANCH_SHIFT, CAUSTIC_CUBE_SHIFT, CAUSTIC_DISTANCE_TEST, CAUSTIC_LIGHT_SHIFT, CAUSTIC_ORIENTATION, CAUSTIC_PHOTON_MAP,
    CAUSTIC_SCREEN_SPACE, CAUSTIC_SURFACE_PATHS, CAUSTIC_TEXTURE_SPACE,
};
use crate::frame::shadow::FAR;
use crate::frame::shadow::{SHADOW_CUBES, SHADOW_PLANES};
use crate::frame::stage::{FrameIo, Maps, Stage, StageInit};
use crate::frame::{cube_depth, destroy_pipelines, render_cube_faces, view_mask, FrameInputs};
use crate::methods::raytrace::ray_query::scene::SceneRays;
use crate::quality::{CausticPaths, CausticSpace, Caustics, CubeMode, Quality};
use crate::vk::pipeline::{graphics_pipeline, Blend, GraphicsDesc, Multisample, VertexInput};
use crate::vk::{begin_rendering, build, Access, Buffer, Context, Image, ImageDesc, ImageKind, Owner, Recorder, Target};
use crate::Result;

const HIT_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
const LIGHT_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

pub struct CausticsStage {
    plan: CausticsPlan,
    photons: u32,
    filter: u32,
    mode: CubeMode,
    /// Depth of the receiver cubes (also attached, untested, to the light cube passes).
    cube_depth: Image,
    photon_depth: Image,
    receivers: vk::Pipeline,
    photon: vk::Pipeline,
    accumulate: vk::Pipeline,
    box_filter: vk::Pipeline,
    /// Caustic triangles: the set-up kernel (caustics/setup.comp).
    setup: vk::Pipeline,
    /// The photon map: its grid's count, scan, scatter and coarse-scatter kernels
    /// (caustics/grid.comp, caustics/grid_scan.comp).
    grid: [vk::Pipeline; 4],
    /// caustics=photon-map: places for every photon (photons² a layer, every layer).
    photon_places: u64,
    /// caustic_space=screen: the camera's depth of every surface, then the splats depth-tested
    /// against it (caustics/screen_depth.frag, caustics/splat.vert#SCREEN), and that depth.
    screen: [vk::Pipeline; 2],
    screen_depth: Image,
    /// caustic_space=texture (SKALP05): the receivers' atlas (followed as objects move), and
    /// the splats into its light map (caustics/splat.vert#TEXTURE).
    atlas: Option<Atlas>,
    light_map_splat: vk::Pipeline,
    layout: vk::PipelineLayout,
    /// caustic_paths=exact: what the photons' ray queries trace through (§6.1.1).
    exact: Option<SceneRays>,
    /// Where each cube's photons went (caustics/reach.comp; none with exact paths).
    reach: vk::Pipeline,
    /// Which generators the next record redoes (issue 33 item 4, `super::reach`).
    tracker: Tracker,
    /// map_updates=always: every record redoes every generator.
    always: bool,
    /// The scene's bounds when the last change was taken.
    scene_bounds: Option<(Vec3, Vec3)>,
}

/// The cube table the shaders read (`Caustics`, set 0), for the lights of `scene` and a
/// camera target of `(width, height)`.
pub fn table(
    plan: &CausticsPlan,
    q: &Quality,
    scene: &crate::scene::Scene,
    (width, height): (u32, u32),
) -> (GpuCausticParams, Vec<GpuCausticCube>) {
    let flags = if q.caustics.caustic_distance_test { CAUSTIC_DISTANCE_TEST } else { 0 }
        | if q.caustics.caustic_orientation { CAUSTIC_ORIENTATION } else { 0 }
        | if plan.filter == Caustics::PhotonMap { CAUSTIC_PHOTON_MAP } else { 0 }
        | if plan.space == CausticSpace::Screen { CAUSTIC_SCREEN_SPACE } else { 0 }
        | if q.caustics.caustic_paths == CausticPaths::Surface { CAUSTIC_SURFACE_PATHS } else { 0 }
        | if plan.space == CausticSpace::Texture { CAUSTIC_TEXTURE_SPACE } else { 0 };
    let diag = scene.bounds().diagonal();
    let diag = if diag.is_finite() && diag > 0.0 { diag } else { 1.0 };
    let params = GpuCausticParams {
        cube_count: plan.cubes.len() as u32,
        photon_size: q.caustics.photons,
        cube_size: q.cube.cube_size,
        flags,
        splat_size: q.caustics.splat_size,
        filter_radius: q.caustics.caustic_filter,
        triangle_count: plan.photon_layers * 2 * (q.caustics.photons - 1) * (q.caustics.photons - 1),
        layer_triangles: 2 * (q.caustics.photons - 1) * (q.caustics.photons - 1),
        ray_offset: diag * 1e-6,
        gather_k: q.caustics.photon_k,
        grid_cells: plan.grid_cells(q),
        gather_radius: diag * q.caustics.photon_radius,
        screen_width: width,
        screen_height: height,
        medium_turn: q.frame.medium_turn,
        atlas_meshes: 4 * scene.meshes.len() as u32,
        light_map_size: q.caustics.light_map_size,
        exact_bounces: q.frame.depth,
        pad: [0; 2],
    };
    let cubes = plan
        .cubes
        .iter()
        .enumerate()
        .map(|(k, c)| GpuCausticCube {
            centre: plan.scene_centre(k, scene).extend(0.0).to_array(),
            mesh: plan.generators[c.generator].mesh as u32,
            pad: [0; 3],
        })
        .collect();
    (params, cubes)
}

/// The photon layers whose photons land in cube `c`.
pub fn cube_layers(plan: &CausticsPlan, c: usize) -> impl Iterator<Item = u32> + '_ {
    plan.generators
        .iter()
        .flat_map(|g| &g.lights)
        .filter(move |lv| lv.cube as usize == c)
        .flat_map(|lv| lv.first_layer..lv.first_layer + lv.faces * lv.branches)
}

fn table_bytes(plan: &CausticsPlan, q: &Quality, init: &StageInit) -> Vec<u8> {
    let (params, cubes) = table(plan, q, init.scene, (init.width, init.height));
    let mut bytes = bytemuck::bytes_of(&params).to_vec();
    bytes.extend_from_slice(bytemuck::cast_slice(&cubes));
    bytes
}

impl CausticsStage {
    pub fn create(init: &StageInit, maps: &mut Maps) -> Result<Box<dyn Stage>> {
        let plan = init.plan.caustics.clone().expect("a caustics stage is planned with its generators");
        let q = &init.plan.quality;
        let me = CausticsStage {
            plan,
            photons: q.caustics.photons,
            filter: q.caustics.caustic_filter,
            // Six passes whatever `cube_mode` says: with multiview, lavapipe (Mesa 22.3; Mesa
            // 25.0.7 renders both alike, measured on the demo's cube-mapped methods)
            // scatters the receivers' triangles over the wrong faces of the cube (measured:
            // tests/caustics.rs, multiview_and_six_passes_make_the_same_caustic).
            mode: CubeMode::SixPasses,
            cube_depth: Image::placeholder(),
            photon_depth: Image::placeholder(),
            receivers: vk::Pipeline::null(),
            photon: vk::Pipeline::null(),
            accumulate: vk::Pipeline::null(),
            box_filter: vk::Pipeline::null(),
            setup: vk::Pipeline::null(),
            grid: [vk::Pipeline::null(); 4],
            photon_places: 0,
            screen: [vk::Pipeline::null(); 2],
            screen_depth: Image::placeholder(),
            atlas: None,
            light_map_splat: vk::Pipeline::null(),
            layout: init.layout,
            exact: None,
            reach: vk::Pipeline::null(),
            tracker: Tracker::new(0, 0, Vec::new(), (false, true)),
            always: q.frame.map_updates_always,
            scene_bounds: None,
        };
        Ok(Box::new(build(init.ctx, me, |me| me.init(init, maps))?))
    }

    fn init(&mut self, init: &StageInit, maps: &mut Maps) -> Result<()> {
        let (ctx, layout, q) = (init.ctx, init.layout, &init.plan.quality);
        let splatted = match self.plan.space {
            CausticSpace::Screen => Some("screen: photons are splatted onto the camera's image"),
            CausticSpace::Texture => Some("texture: photons are splatted into the receivers' light map"),
            _ => None,
        };
        if let (Some(what), false) = (splatted, self.plan.filter == Caustics::Splat) {
            let filter = if self.plan.filter == Caustics::PhotonMap { "photon-map" } else { "triangles" };
            return Err(crate::Error::invalid(
                "knob caustic_space",
                format!("{what} (caustics=splat); caustics={filter} keeps them elsewhere (caustic_space=cube or light)"),
            ));
        }
        if self.plan.space == CausticSpace::Texture {
            if !ctx.geometry_shader {
                return Err(crate::Error::Unsupported(format!(
                    "caustic_space=texture reads gl_PrimitiveID in fragment shaders, which needs the geometryShader feature: {} {} (caustic_space=cube)",
                    ctx.device_name,
                    if !ctx.owns_device() { "is the host's device, whose enabled features are not known" } else { "does not have it" }
                )));
            }
            // Triangle indices travel as floats (exact below 2²⁴).
            let triangles = init.scene.triangle_count();
            if triangles >= 1 << 24 {
                return Err(crate::Error::invalid(
                    "knob caustic_space",
                    format!("texture: {triangles} triangles; texture space names a receiver triangle by a float, exact below 2^24 (caustic_space=cube)"),
                ));
            }
        }
        let (s, n) = (q.cube.cube_size, q.caustics.photons);
        let cubes = self.plan.cubes.len() as u32;
        let attach = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC;
        let cube = |name, format| {
            Image::new(ctx, &ImageDesc { name, format, width: s, height: s, kind: ImageKind::CubeArray { cubes }, usage: attach })
        };
        maps.set_image(&CAUSTIC_DISTANCES, cube("caustics.receivers", vk::Format::R32_SFLOAT)?);
        if self.plan.light_cubes() {
            maps.set_image(&CAUSTIC_MAPS, cube("caustics.light_cubes", LIGHT_FORMAT)?);
            if self.filter > 0 {
                maps.set_image(&CAUSTIC_RAW, cube("caustics.light_cubes.unfiltered", LIGHT_FORMAT)?);
            }
        } else {
            self.filter = 0;
        }
        let layers = ImageKind::D2Array { layers: self.plan.photon_layers };
        let photon = |name| Image::new(ctx, &ImageDesc { name, format: HIT_FORMAT, width: n, height: n, kind: layers, usage: attach });
        maps.set_image(&PHOTON_HITS, photon("caustics.photon_hits")?);
        maps.set_image(&PHOTON_POWER, photon("caustics.photon_power")?);
        let bytes = table_bytes(&self.plan, q, init);
        maps.set_buffer(&CAUSTICS, Buffer::with_data(ctx, "caustics.generators", &bytes, vk::BufferUsageFlags::STORAGE_BUFFER)?);
        // Where the photons went, read back to decide what a later change reaches (exact
        // photons bounce off every specular surface: any move may reach them, nothing to read).
        let tracks = self.plan.tracks_reach(q);
        let bounds = init.gpu.draws.iter().map(|d| (d.lo, d.hi)).collect();
        self.tracker = Tracker::new(self.plan.generators.len(), cubes as usize, bounds, (tracks, !self.plan.light_cubes()));
        let b = init.scene.bounds();
        self.scene_bounds = Some((b.min, b.max));
        if tracks {
            let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
            let words = Buffer::new(ctx, "caustics.reach", 32 * cubes as u64, usage, crate::vk::MemoryLocation::GpuToCpu)?;
            maps.set_buffer(&CAUSTIC_REACH, words);
            self.reach = crate::vk::pipeline::compute_pipeline(ctx, layout, "caustics/reach.comp")?;
        }
        self.cube_depth = cube_depth(ctx, "caustics.depth", s, self.mode)?;
        self.photon_depth = Image::new(
            ctx,
            &ImageDesc {
                name: "caustics.photon_depth",
                format: DEPTH_FORMAT,
                width: n,
                height: n,
                kind: ImageKind::D2,
                usage: vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
            },
        )?;
        let mask = view_mask(self.mode);
        let desc = |name, vertex, fragment, vertex_input, formats, depth_test, view_mask, blend| GraphicsDesc {
            name,
            vertex,
            fragment,
            vertex_input,
            color_formats: formats,
            depth_format: Some(DEPTH_FORMAT),
            depth_test,
            depth_write: depth_test,
            view_mask,
            cull: vk::CullModeFlags::NONE,
            multisample: Multisample::OFF,
            blend,
            depth_op: crate::vk::pipeline::DepthOp::Nearer,
        };
        let r32 = [vk::Format::R32_SFLOAT];
        let light = [LIGHT_FORMAT];
        let hits = [HIT_FORMAT, HIT_FORMAT];
        self.receivers = graphics_pipeline(
            ctx,
            layout,
            &desc("caustics.receivers", "scene/mesh.vert", "shadow/distance.frag", VertexInput::Mesh, &r32, true, mask, Blend::Replace),
        )?;
        self.photon = if q.caustics.caustic_paths == CausticPaths::Exact {
            // Photons traced through ray queries (§6.1.1): the variant with set 5.
            let exact = SceneRays::new(init, "caustics.exact")?;
            let layout = exact.layout;
            self.exact = Some(exact);
            graphics_pipeline(
                ctx,
                layout,
                &desc(
                    "caustics.photons",
                    "scene/mesh.vert",
                    "caustics/photons.frag#EXACT_PATHS",
                    VertexInput::Mesh,
                    &hits,
                    true,
                    0,
                    Blend::Replace,
                ),
            )?
        } else {
            graphics_pipeline(
                ctx,
                layout,
                &desc("caustics.photons", "scene/mesh.vert", "caustics/photons.frag", VertexInput::Mesh, &hits, true, 0, Blend::Replace),
            )?
        };
        if self.plan.filter == Caustics::PhotonMap {
            return self.init_photon_map(init, maps);
        }
        if self.plan.space == CausticSpace::Screen {
            return self.init_screen(init, maps);
        }
        if self.plan.space == CausticSpace::Texture {
            return self.init_texture(init, maps);
        }
        let (vs, fs) = match self.plan.filter {
            Caustics::Splat => ("caustics/splat.vert", "caustics/splat.frag"),
            _ => ("caustics/triangles.vert", "caustics/triangles.frag"),
        };
        self.accumulate =
            graphics_pipeline(ctx, layout, &desc("caustics.accumulate", vs, fs, VertexInput::None, &light, false, mask, Blend::Add))?;
        if self.plan.filter == Caustics::Triangles {
            // Per photon layer 2 (n − 1)² triangles of four vec4, and six face flags each.
            let count = self.plan.photon_layers as u64 * 2 * (n as u64 - 1) * (n as u64 - 1);
            let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
            let gpu = crate::vk::MemoryLocation::GpuOnly;
            // One storage-buffer descriptor must reach every triangle.
            within_storage_range(ctx, "caustic triangles", count * 64, n, self.plan.photon_layers)?;
            maps.set_buffer(&CAUSTIC_TRIANGLES, Buffer::new(ctx, "caustics.triangles", count * 64, storage, gpu)?);
            maps.set_buffer(&CAUSTIC_FACES, Buffer::new(ctx, "caustics.triangle_faces", count * 6 * 4, storage, gpu)?);
            self.setup = crate::vk::pipeline::compute_pipeline(ctx, layout, "caustics/setup.comp")?;
        }
        if self.filter > 0 {
            self.box_filter = graphics_pipeline(
                ctx,
                layout,
                &desc("caustics.filter", "scene/sky.vert", "caustics/filter.frag", VertexInput::None, &light, false, mask, Blend::Replace),
            )?;
        }
        Ok(())
    }

    /// caustic_space=texture (SKALP05): the receivers' atlas and light map, the receiver
    /// triangles beside each receiver distance cube, the receivers' pipeline that writes both
    /// and the splats'.
    fn init_texture(&mut self, init: &StageInit, maps: &mut Maps) -> Result<()> {
        let (ctx, q) = (init.ctx, &init.plan.quality);
        let atlas = Atlas::build(init.scene, q.caustics.light_map_size, super::atlas::gutter())?;
        let (words, _) = atlas.gpu_words();
        maps.set_buffer(
            &CAUSTIC_ATLAS,
            Buffer::with_data(ctx, "caustics.atlas", bytemuck::cast_slice::<[f32; 4], u8>(&words), vk::BufferUsageFlags::STORAGE_BUFFER)?,
        );
        self.atlas = Some(atlas);
        let n = q.caustics.light_map_size;
        let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC;
        maps.set_image(
            &CAUSTIC_LIGHT_MAP,
            Image::new(
                ctx,
                &ImageDesc { name: "caustics.light_map", format: LIGHT_FORMAT, width: n, height: n, kind: ImageKind::D2, usage },
            )?,
        );
        let s = q.cube.cube_size;
        let cubes = ImageKind::CubeArray { cubes: self.plan.cubes.len() as u32 };
        maps.set_image(
            &CAUSTIC_RECEIVER_IDS,
            Image::new(
                ctx,
                &ImageDesc { name: "caustics.receiver_ids", format: vk::Format::R32_SFLOAT, width: s, height: s, kind: cubes, usage },
            )?,
        );
        let desc = |name, vertex, fragment, vertex_input, formats, depth_format, blend| GraphicsDesc {
            name,
            vertex,
            fragment,
            vertex_input,
            color_formats: formats,
            depth_format,
            depth_test: depth_format.is_some(),
            depth_write: depth_format.is_some(),
            view_mask: 0,
            cull: vk::CullModeFlags::NONE,
            multisample: Multisample::OFF,
            blend,
            depth_op: crate::vk::pipeline::DepthOp::Nearer,
        };
        let two = [vk::Format::R32_SFLOAT, vk::Format::R32_SFLOAT];
        let old = std::mem::replace(
            &mut self.receivers,
            graphics_pipeline(
                ctx,
                self.layout,
                &desc(
                    "caustics.receivers",
                    "scene/mesh.vert",
                    "caustics/receivers.frag",
                    VertexInput::Mesh,
                    &two,
                    Some(DEPTH_FORMAT),
                    Blend::Replace,
                ),
            )?,
        );
        destroy_pipelines(ctx, &mut [old]);
        self.light_map_splat = graphics_pipeline(
            ctx,
            self.layout,
            &desc(
                "caustics.light_map",
                "caustics/splat.vert#TEXTURE",
                "caustics/splat.frag",
                VertexInput::None,
                &[LIGHT_FORMAT],
                None,
                Blend::Add,
            ),
        )?;
        Ok(())
    }

    /// caustic_space=screen: the camera-sized irradiance image and depth buffer, and the two
    /// pipelines that fill them.
    fn init_screen(&mut self, init: &StageInit, maps: &mut Maps) -> Result<()> {
        let ctx = init.ctx;
        let (width, height) = (init.width, init.height);
        let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED;
        maps.set_image(
            &CAUSTIC_SCREEN,
            Image::new(ctx, &ImageDesc { name: "caustics.screen", format: LIGHT_FORMAT, width, height, kind: ImageKind::D2, usage })?,
        );
        self.screen_depth = crate::frame::depth_2d(ctx, "caustics.screen_depth", width, height)?;
        let light = [LIGHT_FORMAT];
        let desc = |name, vertex, fragment, vertex_input, depth_write, depth_op| GraphicsDesc {
            name,
            vertex,
            fragment,
            vertex_input,
            color_formats: &light,
            depth_format: Some(DEPTH_FORMAT),
            depth_test: true,
            depth_write,
            view_mask: 0,
            cull: vk::CullModeFlags::NONE,
            multisample: Multisample::OFF,
            blend: Blend::Add,
            depth_op,
        };
        use crate::vk::pipeline::DepthOp;
        self.screen = [
            graphics_pipeline(
                ctx,
                self.layout,
                &desc("caustics.screen_depth", "scene/mesh.vert", "caustics/screen_depth.frag", VertexInput::Mesh, true, DepthOp::Nearer),
            )?,
            graphics_pipeline(
                ctx,
                self.layout,
                &desc(
                    "caustics.screen",
                    "caustics/splat.vert#SCREEN",
                    "caustics/splat.frag",
                    VertexInput::None,
                    false,
                    DepthOp::NearerOrEqual,
                ),
            )?,
        ];
        Ok(())
    }

    /// caustics=photon-map: the sorted photons and the grid (in the frame's set: every pass
    /// that shades a diffuse surface gathers from them), and the kernels that build them.
    fn init_photon_map(&mut self, init: &StageInit, maps: &mut Maps) -> Result<()> {
        let (ctx, q) = (init.ctx, &init.plan.quality);
        let photons = self.plan.photon_count(q);
        within_storage_range(ctx, "the photon map", photons * 32, q.caustics.photons, self.plan.photon_layers)?;
        let gpu = crate::vk::MemoryLocation::GpuOnly;
        let grid = self.plan.grid_cells(q) as u64 * 16;
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
        maps.set_buffer(&PHOTON_GRID, Buffer::new(ctx, "caustics.photon_grid", grid, usage, gpu)?);
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        maps.set_buffer(&PHOTON_LIST, Buffer::new(ctx, "caustics.photon_list", photons * 32, storage, gpu)?);
        maps.set_buffer(&PHOTON_COARSE, Buffer::new(ctx, "caustics.photon_coarse", photons * 4, storage, gpu)?);
        let compute = |shader| crate::vk::pipeline::compute_pipeline(ctx, self.layout, shader);
        self.grid = [
            compute("caustics/grid.comp")?,
            compute("caustics/grid_scan.comp")?,
            compute("caustics/grid.comp#SCATTER")?,
            compute("caustics/grid.comp#COARSE")?,
        ];
        self.photon_places = photons;
        Ok(())
    }

    /// The photon map's grid (§6.1.1, PDC03), rebuilt from this frame's photon images: the
    /// buckets' counts zeroed, every photon counted into its fine and coarse buckets, the
    /// counts scanned into first places, every photon scattered into its fine place, then
    /// its place into its coarse one; then made visible to every pass that shades. (The
    /// previous frame's reads are behind the pass's opening barrier.)
    fn build_photon_grid(&self, rec: &mut Recorder, f: &FrameInputs, grid: vk::Buffer) {
        let (ctx, cmd) = (rec.ctx, rec.cmd);
        let barrier = |src, src_access, dst, dst_access| rec.memory_barrier((src, src_access), (dst, dst_access));
        let compute = vk::PipelineStageFlags2::COMPUTE_SHADER;
        let storage = vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::SHADER_STORAGE_WRITE;
        unsafe { ctx.device.cmd_fill_buffer(cmd, grid, 0, vk::WHOLE_SIZE, 0) };
        barrier(vk::PipelineStageFlags2::ALL_TRANSFER, vk::AccessFlags2::TRANSFER_WRITE, compute, storage);
        let (x, y) = spread_groups((self.photons as u64 * self.photons as u64).div_ceil(64));
        let per_layer = |pipeline: vk::Pipeline| {
            unsafe {
                ctx.device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, pipeline);
                ctx.device.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::COMPUTE, self.layout, 0, &[f.set], &[]);
            }
            for c in 0..self.plan.cubes.len() {
                for layer in cube_layers(&self.plan, c) {
                    f.push_flags(ctx, cmd, 0, layer, c as u32);
                    unsafe { ctx.device.cmd_dispatch(cmd, x, y, 1) };
                }
            }
        };
        per_layer(self.grid[0]);
        barrier(compute, vk::AccessFlags2::SHADER_STORAGE_WRITE, compute, storage);
        unsafe {
            ctx.device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.grid[1]);
            ctx.device.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::COMPUTE, self.layout, 0, &[f.set], &[]);
            ctx.device.cmd_dispatch(cmd, 1, 1, 1);
        }
        barrier(compute, vk::AccessFlags2::SHADER_STORAGE_WRITE, compute, storage);
        per_layer(self.grid[2]);
        // The coarse level: every place of the sorted photons (those past the photons placed return).
        barrier(compute, vk::AccessFlags2::SHADER_STORAGE_WRITE, compute, storage);
        unsafe {
            ctx.device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.grid[3]);
            let (x, y) = spread_groups(self.photon_places.div_ceil(64));
            ctx.device.cmd_dispatch(cmd, x, y, 1);
        }
        barrier(
            compute,
            vk::AccessFlags2::SHADER_STORAGE_WRITE,
            vk::PipelineStageFlags2::ALL_COMMANDS,
            vk::AccessFlags2::SHADER_STORAGE_READ,
        );
    }

    /// Texture space: the receiver distance cubes and the receiver triangles beside them, six
    /// passes a cube of two attachments (both cleared to FAR: no receiver).
    fn receivers_with_triangles(&mut self, rec: &Recorder, f: &FrameInputs, distances: &Image, ids: &Image, cube_views: &[u32]) {
        let (ctx, cmd) = (rec.ctx, rec.cmd);
        for (k, cube) in self.plan.cubes.iter().enumerate() {
            let mesh = self.plan.generators[cube.generator].mesh;
            for face in 0..6u32 {
                rec.barrier(&mut self.cube_depth, Access::DepthAttachment);
                let layer = 6 * k as u32 + face;
                let colors = [distances.layer_view(layer), ids.layer_view(layer)];
                let target = Target {
                    clear_color: [FAR, 0.0, 0.0, 0.0],
                    ..Target::cleared(&colors, Some(self.cube_depth.view), distances.width, distances.width)
                };
                begin_rendering(ctx, cmd, &target);
                f.bind(ctx, cmd, self.receivers);
                for d in f.scene.draws.iter().filter(|d| d.mesh as usize != mesh && d.index_count > 0) {
                    f.draw(ctx, cmd, cube_views[k] + face, d);
                }
                unsafe { ctx.device.cmd_end_rendering(cmd) };
            }
        }
    }

    /// `caustics.reach`: where the measured cubes' photons went (caustics/reach.comp), their
    /// words cleared first (bounds empty, nothing escaped, none landed); the stage reads them
    /// back at the next change (`Stage::update`).
    /// `reads`: the photon hits and power and the receiver distances.
    fn record_reach(&self, rec: &mut Recorder, f: &FrameInputs, maps: &Maps, reads: [&Image; 3], measure: &[bool]) {
        let Some(words) = maps.buffer(&CAUSTIC_REACH).map(|b| b.raw) else { return };
        let [hits, power, distances] = reads;
        let pass = rec.pass("caustics.reach").reads(hits, Access::ComputeSampled).reads(power, Access::ComputeSampled);
        let open = pass.reads(distances, Access::ComputeSampled).begin();
        let (ctx, cmd) = (rec.ctx, rec.cmd);
        let barrier = |src, src_access, dst, dst_access| rec.memory_barrier((src, src_access), (dst, dst_access));
        let compute = vk::PipelineStageFlags2::COMPUTE_SHADER;
        let storage = vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::SHADER_STORAGE_WRITE;
        let transfer = vk::PipelineStageFlags2::ALL_TRANSFER;
        // After the last record's kernel (and the host's read, behind the frame's fence).
        barrier(compute, vk::AccessFlags2::SHADER_STORAGE_WRITE, transfer, vk::AccessFlags2::TRANSFER_WRITE);
        for k in (0..measure.len()).filter(|&k| measure[k]) {
            let at = 32 * k as u64;
            unsafe {
                ctx.device.cmd_fill_buffer(cmd, words, at, 12, u32::MAX);
                ctx.device.cmd_fill_buffer(cmd, words, at + 12, 20, 0);
            }
        }
        barrier(transfer, vk::AccessFlags2::TRANSFER_WRITE, compute, storage);
        unsafe {
            ctx.device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.reach);
            ctx.device.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::COMPUTE, self.layout, 0, &[f.set], &[]);
        }
        let (x, y) = spread_groups((self.photons as u64 * self.photons as u64).div_ceil(64));
        for c in (0..self.plan.cubes.len()).filter(|&c| measure[c]) {
            for layer in cube_layers(&self.plan, c) {
                f.push_flags(ctx, cmd, 0, layer, c as u32);
                unsafe { ctx.device.cmd_dispatch(cmd, x, y, 1) };
            }
        }
        rec.end(open);
    }

    /// Every photon layer's splats into one target seen from `view` (screen and texture
    /// space), push.flags naming the layer's caustic cube.
    fn draw_splats(&self, ctx: &Context, cmd: vk::CommandBuffer, f: &FrameInputs, view: u32) {
        for c in 0..self.plan.cubes.len() {
            for layer in cube_layers(&self.plan, c) {
                f.push_flags(ctx, cmd, view, layer, c as u32);
                unsafe { ctx.device.cmd_draw(cmd, self.vertices(), 1, 0, 0) };
            }
        }
    }

    /// Vertices of one photon layer's splat draw (a quad per photon).
    fn vertices(&self) -> u32 {
        6 * self.photons * self.photons
    }

    /// Caustic triangles (§6.3.2): sets up every photon layer's triangles once, each flagged
    /// for the faces of its cube it may reach. (The previous frame's reads of the buffers
    /// are behind the pass's opening barrier.)
    fn setup_triangles(&self, rec: &mut Recorder, f: &FrameInputs, views: &crate::frame::stage::ViewLayout, redo: &[bool]) {
        let (ctx, cmd) = (rec.ctx, rec.cmd);
        unsafe {
            ctx.device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.setup);
            ctx.device.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::COMPUTE, self.layout, 0, &[f.set], &[]);
        }
        let per_layer = 2 * (self.photons - 1) * (self.photons - 1);
        let cubes = views.first(super::CUBE_VIEWS).expect("caustics declare their views");
        for c in (0..self.plan.cubes.len()).filter(|&c| redo[c]) {
            let first_view = cubes + 6 * c as u32;
            for layer in cube_layers(&self.plan, c) {
                f.push_flags(ctx, cmd, first_view, layer, 0);
                unsafe { ctx.device.cmd_dispatch(cmd, per_layer.div_ceil(64), 1, 1) };
            }
        }
        let barrier = [vk::MemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::COMPUTE_SHADER)
            .src_access_mask(vk::AccessFlags2::SHADER_STORAGE_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags2::VERTEX_SHADER)
            .dst_access_mask(vk::AccessFlags2::SHADER_STORAGE_READ)];
        unsafe { ctx.device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&barrier)) };
    }
}

impl Stage for CausticsStage {
    fn name(&self) -> &'static str {
        "caustics"
    }

    fn stats(&self, _ctx: &Context) -> Vec<(String, f64)> {
        let mut v = vec![
            ("caustics.generators".into(), self.plan.generators.len() as f64),
            ("caustics.cubes".into(), self.plan.cubes.len() as f64),
            ("caustics.photon_layers".into(), self.plan.photon_layers as f64),
        ];
        if let Some(e) = &self.exact {
            let stats = e.accel.borrow().stats;
            v.push(("caustics.exact.blas_builds".into(), stats.blas_builds as f64));
            v.push(("caustics.exact.tlas_builds".into(), stats.tlas_builds as f64));
        }
        v
    }

    /// Reference points follow their objects; the table is rewritten before the frame. Which
    /// generators the change reaches (`super::reach`: where their photons went at their last
    /// record, read back now) and where their light may land (`Maps::caustic_reach`, for the
    /// maps' faces).
    fn update(&mut self, init: &StageInit, c: &crate::scene::update::Changes, maps: &mut Maps) -> Result<()> {
        if let Some(words) = maps.buffer(&CAUSTIC_REACH).map(Buffer::read).transpose()? {
            let words: Vec<u32> = words.chunks_exact(4).map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]])).collect();
            self.tracker.read(&words);
        }
        let q = &init.plan.quality;
        let scene = init.scene;
        let from = |l: usize| match scene.lights[l].kind {
            crate::scene::LightKind::Directional => ShadowFrom::Directional(scene.lights[l].direction),
            _ => ShadowFrom::Point(scene.lights[l].position),
        };
        // The cubes' centres at their last record, and now (reference points follow their
        // objects; one may move away from what blocks it without its object moving).
        let centres = |plan: &CausticsPlan| -> Vec<Vec3> { (0..plan.cubes.len()).map(|k| plan.scene_centre(k, scene)).collect() };
        let before = centres(&self.plan);
        if let Some(p) = init.plan.caustics.as_ref() {
            for (g, fresh) in self.plan.generators.iter_mut().zip(&p.generators) {
                g.reference_point = fresh.reference_point;
            }
        }
        let after = centres(&self.plan);
        let bounds = scene.bounds();
        let bounds = (bounds.min, bounds.max);
        // The scene's bounds size the shadow planes of directional lights (the photons'
        // visibility) and the photon map's cells: a change there reaches every generator.
        let world_changed = self.scene_bounds.is_some_and(|b| b != bounds);
        self.scene_bounds = Some(bounds);
        let gens: Vec<_> = self
            .plan
            .generators
            .iter()
            .enumerate()
            .map(|(g, gen)| {
                let ids: Vec<usize> = gen.lights.iter().map(|lv| lv.light).collect();
                let own: Vec<(usize, Vec3)> =
                    (0..self.plan.cubes.len()).filter(|&k| self.plan.cubes[k].generator == g).map(|k| (k, before[k])).collect();
                let forced = if world_changed {
                    Some("the scene's bounds changed".to_string())
                } else if own.iter().any(|&(k, c)| c != after[k]) {
                    Some("its caustic cube's centre moved".to_string())
                } else if self.plan.space == CausticSpace::Screen && !c.moved.is_empty() {
                    Some("moved in the camera's view".to_string())
                } else {
                    None
                };
                let lights = ids.iter().map(|&l| from(l)).collect();
                super::reach::GeneratorSpec { mesh: gen.mesh, lights, light_ids: ids, cubes: own, forced }
            })
            .collect();
        let materials = |m: usize| scene.meshes.get(m).is_some_and(|mesh| c.materials.contains(&mesh.material));
        let now = init.gpu.draws.iter().map(|d| (d.lo, d.hi)).collect();
        // The margin: 2 % of the region's size (rounding), and the splats' and the filter's
        // texels and one more.
        let texels = q.caustics.splat_size + self.filter as f32 + 1.0;
        let name = |m: usize| scene.meshes.get(m).map_or_else(|| format!("mesh {m}"), |mesh| mesh.name.clone());
        let changed = super::reach::Changed { moved: &c.moved, materials: &materials, lights: &c.lights, name: &name };
        let reach = self.tracker.change(&gens, &changed, now, (0.02, texels, q.cube.cube_size));
        if c.camera && self.plan.space == CausticSpace::Screen {
            self.tracker.all("camera");
        }
        maps.caustic_reach = if self.plan.shown_in_maps() { reach } else { crate::frame::cube_deps::CausticReach::Unchanged };
        if let Some(b) = maps.buffer_mut(&CAUSTICS) {
            b.write(&table_bytes(&self.plan, &init.plan.quality, init))?;
        }
        // Texture space: the charts follow their objects (the per-mesh rows).
        if let (Some(atlas), Some(b)) = (self.atlas.as_mut(), maps.buffer_mut(&CAUSTIC_ATLAS)) {
            atlas.follow(init.scene);
            b.write(bytemuck::cast_slice::<[f32; 4], u8>(&atlas.mesh_words()))?;
        }
        Ok(())
    }

    /// The generators the next record redoes, of all.
    fn redraw(&self) -> Option<(u32, u32)> {
        Some(self.tracker.count())
    }

    /// Which generators, and why.
    fn redraw_note(&self) -> Option<String> {
        let names: Vec<String> = self
            .plan
            .generators
            .iter()
            .zip(&self.tracker.dirty)
            .filter_map(|(g, d)| d.as_ref().map(|why| format!("'{}': {why}", g.name)))
            .collect();
        let (k, n) = self.tracker.count();
        Some(format!("{k} of {n} generators ({})", names.join(", ")))
    }

    fn record(&mut self, rec: &mut Recorder, f: &FrameInputs, io: &mut FrameIo) {
        if self.always {
            self.tracker.all("map_updates=always");
        }
        // Taken out of the frame's maps while recorded (several are written at once), put
        // back after.
        let own = [
            &CAUSTIC_DISTANCES,
            &PHOTON_HITS,
            &PHOTON_POWER,
            &CAUSTIC_MAPS,
            &CAUSTIC_RAW,
            &CAUSTIC_SCREEN,
            &CAUSTIC_LIGHT_MAP,
            &CAUSTIC_RECEIVER_IDS,
        ];
        let mut images = own.map(|s| io.maps.take_image(s));
        // The cubes of the generators this record redoes; the others keep what they hold.
        let redo: Vec<bool> = self.plan.cubes.iter().map(|c| self.tracker.dirty[c.generator].is_some()).collect();
        // Measured where the photons go: the redone cubes of generators not moving every frame.
        let measures = self.tracker.measures();
        let measure: Vec<bool> = self.plan.cubes.iter().zip(&redo).map(|(c, &r)| r && measures[c.generator]).collect();
        self.record_images(rec, f, io, &mut images, (&redo, &measure));
        self.tracker.recorded(&redo, &measure);
        for (slot, image) in own.into_iter().zip(images) {
            if let Some(image) = image {
                io.maps.set_image(slot, image);
            }
        }
    }

    fn destroy(&mut self, ctx: &Context) {
        if let Some(mut e) = self.exact.take() {
            Owner::destroy(&mut e, ctx);
        }
        self.cube_depth.destroy(ctx);
        self.photon_depth.destroy(ctx);
        destroy_pipelines(ctx, &mut [self.receivers, self.photon, self.accumulate, self.box_filter, self.setup, self.reach]);
        destroy_pipelines(ctx, &mut self.grid);
        destroy_pipelines(ctx, &mut self.screen);
        destroy_pipelines(ctx, &mut [self.light_map_splat]);
        self.screen_depth.destroy(ctx);
    }
}

impl CausticsStage {
    /// Records the passes into the caustics' own images: receiver distances, photon hits
    /// and power, light cube maps and their unfiltered twins, the screen's irradiance (`own` in
    /// `record`'s order).
    /// `redo`: per caustic cube, whether its generator is redone (in the spaces that record
    /// every generator at once, all or none); `measure`: whether `caustics.reach` measures it.
    fn record_images(
        &mut self,
        rec: &mut Recorder,
        f: &FrameInputs,
        io: &mut FrameIo,
        images: &mut [Option<Image>; 8],
        (redo, measure): (&[bool], &[bool]),
    ) {
        let ctx = rec.ctx;
        let maps = &*io.maps;
        let [distances, hits, power, light_image, raw_image, screen_image, light_map, receiver_ids] = images;
        let (Some(distances), Some(hits), Some(power)) = (distances.as_mut(), hits.as_mut(), power.as_mut()) else {
            return;
        };
        let first = |name| io.views.first(name).expect("caustics declare their views");
        let (cubes, photons) = (first(super::CUBE_VIEWS), first(super::PHOTON_VIEWS));
        let cube_views: Vec<u32> = (0..self.plan.cubes.len() as u32).map(|k| cubes + 6 * k).collect();

        // The receivers: everything but the generator, from its reference point (texture
        // space: with the receiver triangles beside their distances).
        if let Some(ids) = receiver_ids.as_mut() {
            let open =
                rec.pass("caustics.receivers").writes(distances, Access::ColorAttachment).writes(ids, Access::ColorAttachment).begin();
            self.receivers_with_triangles(rec, f, distances, ids, &cube_views);
            rec.end(open);
        } else {
            let open = rec.pass("caustics.receivers").writes(distances, Access::ColorAttachment).begin();
            for (k, cube) in self.plan.cubes.iter().enumerate().filter(|&(k, _)| redo[k]) {
                let mesh = self.plan.generators[cube.generator].mesh;
                render_cube_faces(
                    rec,
                    distances,
                    &mut self.cube_depth,
                    k as u32,
                    cube_views[k],
                    self.mode,
                    [FAR, 0.0, 0.0, 0.0],
                    |cmd, v| {
                        f.bind(ctx, cmd, self.receivers);
                        for d in f.scene.draws.iter().filter(|d| d.mesh as usize != mesh && d.index_count > 0) {
                            f.draw(ctx, cmd, v, d);
                        }
                    },
                );
            }
            rec.end(open);
        }

        // Exact photons: the structures they trace through, built where this frame needs them.
        if let Some(e) = self.exact.as_mut() {
            e.record(ctx, rec);
        }
        // The photon hit location images.
        let mut pass = rec.pass("caustics.photons").writes(hits, Access::ColorAttachment).writes(power, Access::ColorAttachment);
        pass = pass.reads(distances, Access::FragmentSampled);
        // The shadow maps, and what the geometry set the photons bind holds (refractor maps).
        let shadows = [&SHADOW_CUBES, &SHADOW_PLANES].into_iter().filter_map(|s| maps.image(s));
        for img in io.scene_images.iter().copied().chain(shadows).chain(maps.geometry_reads()) {
            pass = pass.reads(img, Access::FragmentSampled);
        }
        let open = pass.begin();
        let cmd = rec.cmd;
        for (_, gen) in self.plan.generators.iter().enumerate().filter(|&(g, _)| self.tracker.dirty[g].is_some()) {
            for lv in &gen.lights {
                for (branch, face) in (0..lv.branches).flat_map(|b| (0..lv.faces).map(move |f| (b, f))) {
                    let layer = lv.first_layer + branch * lv.faces + face;
                    rec.barrier(&mut self.photon_depth, Access::DepthAttachment);
                    let colors = [hits.layer_view(layer), power.layer_view(layer)];
                    begin_rendering(ctx, cmd, &Target::cleared(&colors, Some(self.photon_depth.view), self.photons, self.photons));
                    f.bind(ctx, cmd, self.photon);
                    f.bind_maps(ctx, cmd, io.sets.geometry);
                    if let Some(e) = &self.exact {
                        e.bind(ctx, cmd);
                    }
                    // Bits 8-31 are the caustics' own (layout.in.rs), apart from every frame-wide flag.
                    let flags = f.flags
                        | (branch << CAUSTIC_BRANCH_SHIFT)
                        | (lv.cube << CAUSTIC_CUBE_SHIFT)
                        | ((lv.light as u32) << CAUSTIC_LIGHT_SHIFT);
                    for d in f.scene.draws.iter().filter(|d| d.mesh as usize == gen.mesh && d.index_count > 0) {
                        f.push_flags(ctx, cmd, photons + layer, d.mesh, flags);
                        unsafe { ctx.device.cmd_draw_indexed(cmd, d.index_count, 1, d.first_index, d.vertex_offset, 0) };
                    }
                    unsafe { ctx.device.cmd_end_rendering(cmd) };
                }
            }
        }
        rec.end(open);
        self.record_reach(rec, f, maps, [hits, power, distances], measure);

        // Screen space (LC04, WD06b): the camera's depth of everything, then every photon's
        // splat at its pixel, depth-tested against it, in one rendering.
        if let Some(screen) = screen_image.as_mut() {
            let open = rec
                .pass("caustics.screen")
                .writes(screen, Access::ColorAttachment)
                .writes(&mut self.screen_depth, Access::DepthAttachment)
                .reads(hits, Access::VertexSampled)
                .reads(power, Access::VertexSampled)
                .begin();
            let colors = [screen.view];
            begin_rendering(ctx, cmd, &Target::cleared(&colors, Some(self.screen_depth.view), screen.width, screen.height));
            f.bind(ctx, cmd, self.screen[0]);
            for d in f.scene.draws.iter().filter(|d| d.index_count > 0) {
                f.draw(ctx, cmd, io.views.camera, d);
            }
            f.bind(ctx, cmd, self.screen[1]);
            self.draw_splats(ctx, cmd, f, io.views.camera);
            unsafe { ctx.device.cmd_end_rendering(cmd) };
            rec.end(open);
            return;
        }
        // Texture space (SKALP05): every photon's splat at its receiver's light-map coordinates.
        if let (Some(map), Some(ids)) = (light_map.as_mut(), receiver_ids.as_ref()) {
            let open = rec
                .pass("caustics.light_map")
                .writes(map, Access::ColorAttachment)
                .reads(hits, Access::VertexSampled)
                .reads(power, Access::VertexSampled)
                .reads(ids, Access::VertexSampled)
                .begin();
            let colors = [map.view];
            begin_rendering(ctx, cmd, &Target::cleared(&colors, None, map.width, map.height));
            f.bind(ctx, cmd, self.light_map_splat);
            self.draw_splats(ctx, cmd, f, io.views.camera);
            unsafe { ctx.device.cmd_end_rendering(cmd) };
            rec.end(open);
            return;
        }
        // The photon map: the photons sorted into its grid, gathered where surfaces are shaded.
        if self.plan.filter == Caustics::PhotonMap {
            let Some(grid) = maps.buffer(&PHOTON_GRID).map(|b| b.raw) else { return };
            let open = rec
                .pass("caustics.photon_map")
                .reads(hits, Access::ComputeSampled)
                .reads(power, Access::ComputeSampled)
                .after_buffer_writes()
                .begin();
            self.build_photon_grid(rec, f, grid);
            rec.end(open);
            return;
        }
        // Splats or triangles into the light cube maps (the unfiltered ones with a filter).
        let name = if self.plan.filter == Caustics::Splat { "caustics.splat" } else { "caustics.triangles" };
        let filtering = self.filter > 0;
        let Some(light) = light_image.as_mut() else { return };
        let target: &mut Image = match raw_image.as_mut() {
            Some(r) if filtering => r,
            _ => light,
        };
        // The splats' vertex shader reads the photon images; triangles read them once, in
        // their set-up kernel.
        let photon_access = if self.plan.filter == Caustics::Splat { Access::VertexSampled } else { Access::ComputeSampled };
        let open = rec.pass(name).writes(target, Access::ColorAttachment).reads(hits, photon_access).reads(power, photon_access).begin();
        let triangles = self.plan.filter == Caustics::Triangles;
        if triangles {
            self.setup_triangles(rec, f, io.views, redo);
        }
        // A photon layer's quads (splat) or triangles (the faces skip those not flagged).
        let vertices = if triangles { 6 * (self.photons - 1) * (self.photons - 1) } else { self.vertices() };
        let plan = &self.plan;
        for (k, &first_view) in cube_views.iter().enumerate().take(plan.cubes.len()).filter(|&(k, _)| redo[k]) {
            render_cube_faces(rec, target, &mut self.cube_depth, k as u32, first_view, self.mode, [0.0; 4], |cmd, v| {
                f.bind(ctx, cmd, self.accumulate);
                for layer in cube_layers(plan, k) {
                    // Triangles: the face's index in push.flags, for its flags.
                    f.push_flags(ctx, cmd, v, layer, if triangles { v - first_view } else { f.flags });
                    unsafe { ctx.device.cmd_draw(cmd, vertices, 1, 0, 0) };
                }
            });
        }
        rec.end(open);

        if filtering {
            let (Some(light), Some(raw)) = (light_image.as_mut(), raw_image.as_ref()) else { return };
            let open = rec.pass("caustics.filter").writes(light, Access::ColorAttachment).reads(raw, Access::FragmentSampled).begin();
            for (g, &first_view) in cube_views.iter().enumerate().take(self.plan.cubes.len()).filter(|&(k, _)| redo[k]) {
                render_cube_faces(rec, light, &mut self.cube_depth, g as u32, first_view, self.mode, [0.0; 4], |cmd, v| {
                    f.bind(ctx, cmd, self.box_filter);
                    f.push(ctx, cmd, v, g as u32);
                    unsafe { ctx.device.cmd_draw(cmd, 3, 1, 0, 0) };
                });
            }
            rec.end(open);
        }
    }
}

/// Refuses, naming the `photons` knob, a buffer of `bytes` that one storage-buffer descriptor
/// cannot reach on this device (`what`: what it holds, for `layers` photon layers).
fn within_storage_range(ctx: &Context, what: &str, bytes: u64, photons: u32, layers: u32) -> Result<()> {
    let limit = ctx.properties.limits.max_storage_buffer_range as u64;
    if bytes <= limit {
        return Ok(());
    }
    Err(crate::Error::invalid(
        "knob photons",
        format!(
            "{photons}: {what} for {layers} photon layers needs {bytes} bytes in one storage buffer, beyond {}'s {limit} (fewer photons, or caustics=splat)",
            ctx.device_name
        ),
    ))
}

/// Workgroups (x, y) covering `groups`: at most 32768 along x (every device allows 65535 an
/// axis), the rest along y (caustics/grid.comp's `invocation`; surplus invocations return).
fn spread_groups(groups: u64) -> (u32, u32) {
    let x = groups.clamp(1, 32768);
    (x as u32, groups.div_ceil(x).max(1) as u32)
}

impl Owner for CausticsStage {
    fn destroy(&mut self, ctx: &Context) {
        Stage::destroy(self, ctx)
    }
}
