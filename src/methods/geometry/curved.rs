//! Curved reflectors by geometry transformation (survey §5, EMD*05, EMDT06, RHS06). Each
//! reflector is sampled once into a geometry image — world positions and normals in two
//! RGBA32F layers, rasterised over its UV parameterisation, or where its UVs overlap or are
//! missing a planar projection along its mean normal, or for a closed surface a cube atlas
//! around its centre (`geometry.image`, redone only when it moves). The environment — the scene's triangles, each split into `tessellation`²
//! triangles by a compute pre-pass from the scene's vertex buffer
//! (`geometry.virtual.tessellate`, redone when an object moves; the grid's indices are
//! fixed) — is searched every frame: for each of its vertices and every reflector, a compute
//! pass (`geometry.virtual.search`) finds the geometry-image sample where the normal and the
//! bisector of the directions to the eye and to the vertex meet the reflection law (Figure
//! 29), coarse to fine, and moves the vertex to its virtual position on the eye ray through
//! that point; the environment is then drawn once per reflector at those positions, shaded
//! at the real ones (one virtual object per reflector and object pair, EMDT06:
//! `geometry.virtual`), and the reflector's camera pass lays that image onto its pixels
//! with its Fresnel weight (`geometry.curved`).
//!
//! The search has one minimum only on reflectors that are convex or concave: the planner
//! classifies each mesh by the sign of its normal curvature along every edge
//! (`plan::facts::curvature`) and refuses a saddle-shaped one by name (or gives it the
//! fallback), instead of drawing garbage; likewise a mesh that bends one way along every
//! edge and still has several reflection points for the environment's vertices seen from the
//! camera (`plan::reflection_points`: two balls in one mesh). Cost: the search is O(S·D) per frame (S reflectors, D environment vertices),
//! each search (size/2^levels)² + 25·levels texel reads (survey Table 1: O(S), O(N)).

use ash::vk;
use glam::{Vec2, Vec3};

use crate::error::{Error, Result};
use crate::frame::direct::{DEPTH_FORMAT, TARGET_FORMAT};
use crate::frame::layout::{binding, GpuCurvedParams, GpuCurvedVertex, CURVED_BINDINGS, CURVED_REFLECTOR_SHIFT};
use crate::frame::stage::{order, FrameIo, Stage, StageInit};
use crate::frame::{destroy_pipelines, FrameInputs, PUSH_BYTES};
use crate::methods::registry::{CameraPass, GpuSpec, LeavesOut, MapShading, Method, MethodInfo, ObjectClass, Shape};
use crate::plan::types::CameraPlan;
use crate::quality::Quality;
use crate::quality::{FrameKnobs, GeometryKnobs};
use crate::scene::{Mesh, Scene};
use crate::vk::pipeline::{compute_pipeline, descriptor_set_layout, graphics_pipeline, pipeline_layout, write_buffer, write_image};
use crate::vk::pipeline::{sampler, Blend, DepthOp, GraphicsDesc, Multisample, VertexInput};
use crate::vk::{begin_rendering, Access, Buffer, Context, Image, ImageDesc, ImageKind, Recorder, Target};

const GEOMETRY_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
const STORAGE: vk::BufferUsageFlags = vk::BufferUsageFlags::STORAGE_BUFFER;

/// `geometry.curved`: each curved reflector drawn from the camera with its virtual objects'
/// image at its pixels, weighted by Fresnel.
pub const CURVED_PASS: CameraPass = CameraPass {
    name: "geometry.curved",
    vertex: "scene/mesh.vert",
    fragment: "geometry/curved.frag",
    flags: 0,
    order: order::CAMERA,
    create: Some(create),
    profiled: super::PROFILED,
};

const fn one(_: &Quality) -> u32 {
    1
}

pub const CURVED_REFLECTOR_INFO: &MethodInfo = &MethodInfo {
    name: "curved-reflector",
    abi: 15,
    section: "§5",
    family: "geometry",
    summary: "convex or concave mirrors by geometry transformation: the reflector's geometry image (positions and normals over its parameterisation), a coarse-to-fine search per environment vertex for the sample that meets the reflection law, the environment drawn at those virtual positions per reflector and laid onto it with its Fresnel weight; single reflections; saddle-shaped reflectors are refused, and those with several reflection points for the environment seen from the camera take the fallback (distance) with the refusal as the reason",
    serves: &[ObjectClass::Mirror],
    knobs: &[GeometryKnobs::geometry_image, GeometryKnobs::curved_search, GeometryKnobs::tessellation, FrameKnobs::fresnel],
    gpu: Some(GpuSpec { maps: &[], camera: CURVED_PASS, map_shading: MapShading::Sky, leaves_out: LeavesOut::Itself, cycles: one, views: |_| 0, shades_every_pixel: false }),
    fallback: Some(crate::methods::DISTANCE),
    shape: Shape::ConvexOrConcave,
    needs: crate::methods::registry::DeviceNeeds::Nothing,
};
pub const CURVED_REFLECTOR: Method = Method(CURVED_REFLECTOR_INFO.name);

/// Creates the stage of the plan's curved reflectors.
fn create(init: &StageInit, plan: &CameraPlan) -> Result<Box<dyn Stage>> {
    let mut me = CurvedReflectors::empty(init, plan);
    match me.init(init) {
        Ok(()) => Ok(Box::new(me)),
        Err(e) => {
            me.destroy(init.ctx);
            Err(e)
        }
    }
}

/// One environment object's triangles in the tessellated index buffer.
#[derive(Clone, Copy, Debug)]
struct EnvDraw {
    mesh: u32,
    first_index: u32,
    index_count: u32,
}

fn vertex(p: Vec3, n: Vec3, uv: Vec2) -> GpuCurvedVertex {
    GpuCurvedVertex { position: p.extend(1.0).to_array(), normal: n.extend(0.0).to_array(), uv: [uv.x, uv.y, 0.0, 0.0] }
}

/// Vertices of one triangle's barycentric grid at tessellation `t`.
fn grid_vertices(t: u32) -> u32 {
    (t + 1) * (t + 2) / 2
}

/// The t² triangles of one triangle's barycentric grid whose vertices start at `base`
/// (vertex (i, j), i + j ≤ t, row by row: the order `curved_tessellate.comp` writes).
fn grid_indices(t: u32, base: u32, indices: &mut Vec<u32>) {
    let t = t.max(1);
    let row_start = |i: u32| i * (t + 1) - i * (i.saturating_sub(1)) / 2;
    let at = |i: u32, j: u32| base + row_start(i) + j;
    for i in 0..t {
        for j in 0..t - i {
            indices.extend([at(i, j), at(i + 1, j), at(i, j + 1)]);
            if j + 1 < t - i {
                indices.extend([at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
    }
}

/// Splits every triangle of `m` into `t`² triangles on the CPU, as
/// `curved_tessellate.comp` does on the GPU (the unit tests' twin).
#[cfg(test)]
fn tessellate(m: &Mesh, t: u32, vertices: &mut Vec<GpuCurvedVertex>, indices: &mut Vec<u32>) {
    let t = t.max(1);
    let uv = |i: usize| m.uvs.get(i).copied().unwrap_or_default();
    for tri in m.indices.chunks_exact(3) {
        let (a, b, c) = (tri[0] as usize, tri[1] as usize, tri[2] as usize);
        grid_indices(t, vertices.len() as u32, indices);
        for i in 0..=t {
            for j in 0..=t - i {
                let (s, r) = (i as f32 / t as f32, j as f32 / t as f32);
                let w = 1.0 - s - r;
                let p = m.positions[a] * w + m.positions[b] * s + m.positions[c] * r;
                let n = (m.normals[a] * w + m.normals[b] * s + m.normals[c] * r).normalize_or_zero();
                vertices.push(vertex(p, n, uv(a) * w + uv(b) * s + uv(c) * r));
            }
        }
    }
}

/// A reflector's parameterisation into [0,1]², per triangle corner (`m.indices`' order; half
/// a texel of margin at `size`): its own UVs, rescaled to fill the square, when they are
/// present, span an area and do not overlap (the triangles' UV areas add up to no more than
/// their bounding box); else the projection onto the plane across its area-weighted normal
/// where that plane holds the surface one-to-one (no triangle faces away from the normal: a
/// height field over it); else — a closed surface, whose normals cancel, or one that curls
/// past the plane, as a sphere with a hole does, which a plane would fold onto itself — a cube
/// atlas around its centre ([`cube_atlas`]). Returns the coordinates and whether they are the
/// mesh's own.
pub fn parameterisation(m: &Mesh, size: u32) -> (Vec<Vec2>, bool) {
    let tri_area = |a: Vec2, b: Vec2, c: Vec2| 0.5 * ((b - a).perp_dot(c - a)).abs();
    let bbox = |uvs: &[Vec2]| uvs.iter().fold((Vec2::splat(f32::MAX), Vec2::splat(f32::MIN)), |(lo, hi), u| (lo.min(*u), hi.max(*u)));
    let usable = m.uvs.len() == m.positions.len() && !m.uvs.is_empty() && {
        let (lo, hi) = bbox(&m.uvs);
        let span = hi - lo;
        let area: f32 = m.indices.chunks_exact(3).map(|t| tri_area(m.uvs[t[0] as usize], m.uvs[t[1] as usize], m.uvs[t[2] as usize])).sum();
        span.x > 0.0 && span.y > 0.0 && area.is_finite() && area > 0.0 && area <= 1.02 * span.x * span.y
    };
    let corners = |uv: &[Vec2]| m.indices.iter().map(|&i| uv.get(i as usize).copied().unwrap_or(Vec2::ZERO)).collect::<Vec<Vec2>>();
    let raw: Vec<Vec2> = if usable {
        corners(&m.uvs)
    } else {
        let p = |i: u32| m.positions[i as usize];
        let mut n = Vec3::ZERO;
        for t in m.indices.chunks_exact(3) {
            n += (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0]));
        }
        let b = m.bounds();
        let extent = b.max - b.min;
        // The triangles' area that faces away from the plane's normal, where the plane's
        // projection folds onto the rest (edge-on rim triangles of a hemisphere do not count).
        let folded = |axis: Vec3| -> f32 {
            m.indices
                .chunks_exact(3)
                .map(|t| (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])))
                .filter(|c| c.dot(axis) < -1e-3 * c.length())
                .map(|c| 0.5 * c.length())
                .sum()
        };
        let total: f32 = m.indices.chunks_exact(3).map(|t| 0.5 * (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])).length()).sum();
        if n.length() > 1e-3 * extent.length_squared() && folded(n.normalize()) <= 1e-3 * total {
            let axis = n.normalize();
            let u = axis.any_orthonormal_vector();
            let v = axis.cross(u);
            corners(&m.positions.iter().map(|q| Vec2::new(q.dot(u), q.dot(v))).collect::<Vec<Vec2>>())
        } else {
            cube_atlas(m)
        }
    };
    let (lo, hi) = bbox(&raw);
    let span = (hi - lo).max(Vec2::splat(f32::MIN_POSITIVE));
    let margin = 0.5 / size as f32;
    let scale = 1.0 - 2.0 * margin;
    (raw.iter().map(|u| Vec2::splat(margin) + (*u - lo) / span * scale).collect(), usable)
}

/// A closed surface's chart: each triangle projected from the surface's centre (its
/// area-weighted centroid) onto the face of a cube that its centroid's direction points
/// through (gnomonic), the six faces side by side in a 3×2 atlas, each face filling 80 % of
/// its cell so that a triangle straddling a face's edge stays in its own cell. One-to-one
/// where the surface is star-shaped from its centre (every convex one): no texel holds two
/// surface points, as a plane's projection of a closed surface would (front and back on one
/// texel). Per triangle corner, in the atlas's [0,1]².
fn cube_atlas(m: &Mesh) -> Vec<Vec2> {
    let p = |i: u32| m.positions[i as usize];
    let (mut centre, mut area) = (Vec3::ZERO, 0.0f32);
    for t in m.indices.chunks_exact(3) {
        let a = 0.5 * (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])).length();
        centre += a * (p(t[0]) + p(t[1]) + p(t[2])) / 3.0;
        area += a;
    }
    let centre = if area > 0.0 { centre / area } else { m.bounds().center() };
    // The face's share of its cell: [-1, 1] maps to the middle 80 %, up to ±1.25 fits.
    const REACH: f32 = 1.25;
    let mut uv = Vec::with_capacity(m.indices.len());
    for t in m.indices.chunks_exact(3) {
        let d = (p(t[0]) + p(t[1]) + p(t[2])) / 3.0 - centre;
        let axis = d.abs().max_position();
        let sign = if d[axis] < 0.0 { -1.0 } else { 1.0 };
        let face = 2 * axis + usize::from(sign < 0.0);
        let (u_axis, v_axis) = ((axis + 1) % 3, (axis + 2) % 3);
        let cell = Vec2::new((face % 3) as f32 / 3.0, (face / 3) as f32 / 2.0);
        for &i in t {
            let v = p(i) - centre;
            let depth = (sign * v[axis]).max(1e-6 * v.length().max(1e-12));
            let x = (v[u_axis] / depth).clamp(-REACH, REACH);
            let y = (v[v_axis] / depth).clamp(-REACH, REACH);
            uv.push(cell + Vec2::new((0.5 + 0.5 * x / REACH) / 3.0, (0.5 + 0.5 * y / REACH) / 2.0));
        }
    }
    uv
}

/// Every reflector's triangles (three vertices each) with its parameterisation in `uv`,
/// and per reflector its first vertex, vertex count and whether its own UVs serve.
fn reflector_vertices(scene: &Scene, reflectors: &[usize], size: u32) -> (Vec<GpuCurvedVertex>, Vec<(u32, u32)>, Vec<bool>) {
    let (mut vertices, mut ranges, mut own_uvs) = (Vec::new(), Vec::new(), Vec::new());
    for &r in reflectors {
        let m = &scene.meshes[r];
        let first = vertices.len() as u32;
        let (uv, own) = parameterisation(m, size);
        own_uvs.push(own);
        for (&i, &uv) in m.indices.iter().zip(&uv) {
            let i = i as usize;
            vertices.push(vertex(m.positions[i], m.normals[i], uv));
        }
        ranges.push((first, vertices.len() as u32 - first));
    }
    (vertices, ranges, own_uvs)
}

pub struct CurvedReflectors {
    name: &'static str,
    /// Reflector meshes, in layer order.
    reflectors: Vec<usize>,
    size: u32,
    levels: u32,
    tessellation: u32,
    width: u32,
    height: u32,
    multisample: Multisample,
    positions: Image,
    normals: Image,
    virtual_images: Image,
    virtual_depth: Image,
    /// The tessellated environment (written by `geometry.virtual.tessellate`), its fixed
    /// indices, the scene's triangles it is made from, and the reflectors' triangles.
    vertices: Buffer,
    indices: Buffer,
    triangles: Buffer,
    reflector_buffer: Buffer,
    virtuals: Buffer,
    params: Buffer,
    /// Per reflector, the checked vertices with a second reflection point (host-visible).
    minima: Buffer,
    env: Vec<EnvDraw>,
    environment: u32,
    reflector_vertices: Vec<(u32, u32)>,
    own_uvs: Vec<bool>,
    empty_layout: vk::DescriptorSetLayout,
    set_layout: vk::DescriptorSetLayout,
    layout: vk::PipelineLayout,
    pool: vk::DescriptorPool,
    set: vk::DescriptorSet,
    nearest: vk::Sampler,
    image_pipeline: vk::Pipeline,
    tessellate_pipeline: vk::Pipeline,
    search_pipeline: vk::Pipeline,
    virtual_pipeline: vk::Pipeline,
    shade_pipeline: vk::Pipeline,
    /// The geometry images must be (re)drawn before the next search.
    dirty: bool,
    /// The environment must be (re)tessellated before the next search.
    tessellate: bool,
}

impl CurvedReflectors {
    /// The buffers rebuilt with the scene's geometry.
    fn buffers(&mut self) -> [&mut Buffer; 7] {
        [
            &mut self.vertices,
            &mut self.indices,
            &mut self.triangles,
            &mut self.reflector_buffer,
            &mut self.virtuals,
            &mut self.params,
            &mut self.minima,
        ]
    }

    fn empty(init: &StageInit, plan: &CameraPlan) -> CurvedReflectors {
        let q = &init.plan.quality;
        CurvedReflectors {
            name: plan.name,
            reflectors: plan.objects.iter().map(|(m, _)| *m).collect(),
            size: q.geometry.geometry_image,
            levels: q.geometry.curved_search,
            tessellation: q.geometry.tessellation,
            width: init.width,
            height: init.height,
            multisample: init.multisample,
            positions: Image::placeholder(),
            normals: Image::placeholder(),
            virtual_images: Image::placeholder(),
            virtual_depth: Image::placeholder(),
            vertices: Buffer::placeholder(),
            indices: Buffer::placeholder(),
            triangles: Buffer::placeholder(),
            reflector_buffer: Buffer::placeholder(),
            virtuals: Buffer::placeholder(),
            params: Buffer::placeholder(),
            minima: Buffer::placeholder(),
            env: Vec::new(),
            environment: 0,
            reflector_vertices: Vec::new(),
            own_uvs: Vec::new(),
            empty_layout: vk::DescriptorSetLayout::null(),
            set_layout: vk::DescriptorSetLayout::null(),
            layout: vk::PipelineLayout::null(),
            pool: vk::DescriptorPool::null(),
            set: vk::DescriptorSet::null(),
            nearest: vk::Sampler::null(),
            image_pipeline: vk::Pipeline::null(),
            tessellate_pipeline: vk::Pipeline::null(),
            search_pipeline: vk::Pipeline::null(),
            virtual_pipeline: vk::Pipeline::null(),
            shade_pipeline: vk::Pipeline::null(),
            dirty: true,
            tessellate: true,
        }
    }

    fn init(&mut self, init: &StageInit) -> Result<()> {
        let ctx = init.ctx;
        let layers = self.reflectors.len() as u32;
        if layers == 0 {
            return Err(Error::invalid("curved-reflector", "no reflector to serve"));
        }
        let limit = ctx.properties.limits.max_image_dimension2_d;
        if self.size > limit {
            return Err(Error::invalid("knob geometry_image", format!("{} texels exceed the device's {limit}² image limit", self.size)));
        }
        let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED;
        let kind = ImageKind::D2Array { layers };
        let image = |name, format, width, height, kind, usage| Image::new(ctx, &ImageDesc { name, format, width, height, kind, usage });
        self.positions = image("geometry.image.positions", GEOMETRY_FORMAT, self.size, self.size, kind, usage)?;
        self.normals = image("geometry.image.normals", GEOMETRY_FORMAT, self.size, self.size, kind, usage)?;
        self.virtual_images = image("geometry.virtual_images", TARGET_FORMAT, self.width, self.height, kind, usage)?;
        let depth_usage = vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT;
        self.virtual_depth = image("geometry.virtual_depth", DEPTH_FORMAT, self.width, self.height, ImageKind::D2, depth_usage)?;
        self.nearest = sampler(ctx, "geometry.nearest", vk::Filter::NEAREST, vk::SamplerAddressMode::CLAMP_TO_EDGE)?;

        let stages = vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT | vk::ShaderStageFlags::COMPUTE;
        self.empty_layout = descriptor_set_layout(ctx, "geometry.empty_set_layout", &[], stages)?;
        self.set_layout = descriptor_set_layout(ctx, "geometry.curved_set_layout", CURVED_BINDINGS, stages)?;
        let sets = [init.set_layouts[0], init.set_layouts[1], self.empty_layout, self.empty_layout, self.set_layout];
        self.layout = pipeline_layout(ctx, "geometry.curved_layout", &sets, PUSH_BYTES, stages)?;
        let (pool, set) = crate::vk::pipeline::allocate_set(ctx, "geometry.curved_set", self.set_layout, CURVED_BINDINGS)?;
        (self.pool, self.set) = (pool, set);
        self.upload(ctx, init.scene, init.gpu)?;
        self.create_pipelines(ctx)
    }

    /// Creates the buffers of the environment's tessellation (its fixed indices and the
    /// scene's triangles it reads; the vertices are the GPU's), of the reflectors' triangles,
    /// the virtual vertices and the parameters, and writes the stage's descriptors.
    fn upload(&mut self, ctx: &Context, scene: &Scene, gpu: &crate::gpu_scene::GpuScene) -> Result<()> {
        // Sizes checked before anything is built: (t + 1)(t + 2)/2 vertices per environment
        // triangle, three per reflector triangle.
        let t = self.tessellation.max(1);
        let per = grid_vertices(t) as u64;
        let triangles = scene.triangle_count() as u64;
        let environment = triangles * per;
        let own: u64 = self.reflectors.iter().map(|&r| scene.meshes[r].indices.len() as u64).sum();
        let layers = self.reflectors.len() as u64;
        let virtual_bytes = 16 * layers * environment.max(1);
        let vertex_bytes = environment.max(own) * std::mem::size_of::<GpuCurvedVertex>() as u64;
        let index_bytes = 12 * triangles * (t * t) as u64;
        let range = (ctx.properties.limits.max_storage_buffer_range as u64).min(u32::MAX as u64);
        if virtual_bytes.max(vertex_bytes).max(index_bytes) > range {
            return Err(Error::invalid(
                "knob tessellation",
                format!(
                    "{environment} environment vertices at tessellation {t} need {} MiB per buffer, beyond the device's {} MiB storage-buffer range",
                    virtual_bytes.max(vertex_bytes).max(index_bytes) >> 20,
                    range >> 20
                ),
            ));
        }
        // The scene's triangles (global vertex indices, mesh), each object's range of the
        // fixed tessellated indices.
        let mut source = Vec::with_capacity(triangles as usize);
        let mut indices = Vec::with_capacity((3 * triangles * (t * t) as u64) as usize);
        self.env.clear();
        for (i, m) in scene.meshes.iter().enumerate() {
            let offset = gpu.draws.get(i).map_or(0, |d| d.vertex_offset) as u32;
            let first_index = indices.len() as u32;
            for tri in m.indices.chunks_exact(3) {
                grid_indices(t, source.len() as u32 * per as u32, &mut indices);
                source.push([offset + tri[0], offset + tri[1], offset + tri[2], i as u32]);
            }
            self.env.push(EnvDraw { mesh: i as u32, first_index, index_count: indices.len() as u32 - first_index });
        }
        let (reflector_vertices, ranges, own_uvs) = reflector_vertices(scene, &self.reflectors, self.size);
        for b in self.buffers() {
            b.destroy(ctx);
        }
        let gpu_only = crate::vk::MemoryLocation::GpuOnly;
        self.vertices = Buffer::new(ctx, "geometry.curved_vertices", vertex_bytes.max(16), STORAGE, gpu_only)?;
        let indices = if indices.is_empty() { vec![0u32; 3] } else { indices };
        self.indices = Buffer::with_data(ctx, "geometry.curved_indices", &indices, vk::BufferUsageFlags::INDEX_BUFFER)?;
        let source = if source.is_empty() { vec![[0u32; 4]] } else { source };
        self.triangles = Buffer::with_data(ctx, "geometry.curved_triangles", &source, STORAGE)?;
        let reflector_vertices =
            if reflector_vertices.is_empty() { vec![vertex(Vec3::ZERO, Vec3::Z, Vec2::ZERO)] } else { reflector_vertices };
        self.reflector_buffer = Buffer::with_data(ctx, "geometry.reflector_vertices", &reflector_vertices, STORAGE)?;
        self.virtuals = Buffer::new(ctx, "geometry.virtual_vertices", virtual_bytes, STORAGE, gpu_only)?;
        let params = GpuCurvedParams {
            vertex_count: environment as u32,
            image_size: self.size,
            search_levels: self.levels,
            reflector_count: layers as u32,
            tessellation: t,
            triangle_count: triangles as u32,
            pad: [0; 2],
        };
        self.params = Buffer::with_data(ctx, "geometry.curved_params", &[params], STORAGE)?;
        let usage = STORAGE | vk::BufferUsageFlags::TRANSFER_DST;
        self.minima = Buffer::new(ctx, "geometry.curved_minima", 4 * layers, usage, crate::vk::MemoryLocation::GpuToCpu)?;
        (self.environment, self.reflector_vertices, self.own_uvs) = (environment as u32, ranges, own_uvs);
        let sb = vk::DescriptorType::STORAGE_BUFFER;
        let cis = vk::DescriptorType::COMBINED_IMAGE_SAMPLER;
        let ro = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        write_image(ctx, self.set, binding::GEOMETRY_POSITIONS, 0, cis, self.positions.view, self.nearest, ro);
        write_image(ctx, self.set, binding::GEOMETRY_NORMALS, 0, cis, self.normals.view, self.nearest, ro);
        write_image(ctx, self.set, binding::VIRTUAL_IMAGES, 0, cis, self.virtual_images.view, self.nearest, ro);
        write_buffer(ctx, self.set, binding::CURVED_VERTICES, sb, self.vertices.raw);
        write_buffer(ctx, self.set, binding::VIRTUAL_VERTICES, sb, self.virtuals.raw);
        write_buffer(ctx, self.set, binding::CURVED, sb, self.params.raw);
        write_buffer(ctx, self.set, binding::SCENE_VERTICES, sb, gpu.vertices.raw);
        write_buffer(ctx, self.set, binding::SOURCE_TRIANGLES, sb, self.triangles.raw);
        write_buffer(ctx, self.set, binding::REFLECTOR_VERTICES, sb, self.reflector_buffer.raw);
        write_buffer(ctx, self.set, binding::CURVED_MINIMA, sb, self.minima.raw);
        self.dirty = true;
        self.tessellate = true;
        Ok(())
    }

    fn create_pipelines(&mut self, ctx: &Context) -> Result<()> {
        let desc = |name, vertex, fragment, formats, depth: Option<vk::Format>, input, multisample| GraphicsDesc {
            name,
            vertex,
            fragment,
            vertex_input: input,
            color_formats: formats,
            depth_format: depth,
            depth_test: depth.is_some(),
            depth_write: depth.is_some(),
            view_mask: 0,
            cull: vk::CullModeFlags::NONE,
            multisample,
            blend: Blend::Replace,
            depth_op: DepthOp::Nearer,
        };
        let off = Multisample::OFF;
        let geometry = [GEOMETRY_FORMAT, GEOMETRY_FORMAT];
        let (v, f) = ("geometry/curved_image.vert", "geometry/curved_image.frag");
        self.image_pipeline = graphics_pipeline(ctx, self.layout, &desc("geometry.image", v, f, &geometry, None, VertexInput::None, off))?;
        self.tessellate_pipeline = compute_pipeline(ctx, self.layout, "geometry/curved_tessellate.comp")?;
        self.search_pipeline = compute_pipeline(ctx, self.layout, "geometry/curved_search.comp")?;
        let target = [TARGET_FORMAT];
        let (v, f) = ("geometry/curved_virtual.vert", "geometry/curved_virtual.frag");
        self.virtual_pipeline =
            graphics_pipeline(ctx, self.layout, &desc("geometry.virtual", v, f, &target, Some(DEPTH_FORMAT), VertexInput::None, off))?;
        let per_sample = self.multisample.per_sample && self.multisample.samples > 1;
        let fragment = if per_sample { format!("{}#PER_SAMPLE", CURVED_PASS.fragment) } else { CURVED_PASS.fragment.to_string() };
        self.shade_pipeline = graphics_pipeline(
            ctx,
            self.layout,
            &desc(self.name, CURVED_PASS.vertex, &fragment, &target, Some(DEPTH_FORMAT), VertexInput::Mesh, self.multisample),
        )?;
        Ok(())
    }

    fn bind(&self, ctx: &Context, cmd: vk::CommandBuffer, point: vk::PipelineBindPoint, pipeline: vk::Pipeline, f: &FrameInputs) {
        unsafe {
            ctx.device.cmd_bind_pipeline(cmd, point, pipeline);
            ctx.device.cmd_bind_descriptor_sets(cmd, point, self.layout, 0, &[f.set], &[]);
            ctx.device.cmd_bind_descriptor_sets(cmd, point, self.layout, 4, &[self.set], &[]);
        }
    }

    fn push(&self, ctx: &Context, cmd: vk::CommandBuffer, f: &FrameInputs, view: u32, object: u32, flags: u32) {
        f.push_in(ctx, cmd, self.layout, view, object, flags);
    }

    /// `geometry.image`: each reflector's triangles over its parameterisation.
    fn record_images(&mut self, rec: &mut Recorder, f: &FrameInputs) {
        let open = rec
            .pass("geometry.image")
            .writes(&mut self.positions, Access::ColorAttachment)
            .writes(&mut self.normals, Access::ColorAttachment)
            .begin();
        let (ctx, cmd) = (rec.ctx, rec.cmd);
        for (k, &(first, count)) in self.reflector_vertices.iter().enumerate() {
            let colors = [self.positions.layer_view(k as u32), self.normals.layer_view(k as u32)];
            let target = Target {
                color: &colors,
                depth: None,
                width: self.size,
                height: self.size,
                view_mask: 0,
                layer_count: 1,
                clear_color: [0.0; 4],
                clear: true,
            };
            begin_rendering(ctx, cmd, &target);
            self.bind(ctx, cmd, vk::PipelineBindPoint::GRAPHICS, self.image_pipeline, f);
            self.push(ctx, cmd, f, 0, k as u32, f.flags);
            unsafe {
                if count > 0 {
                    ctx.device.cmd_draw(cmd, count, 1, first, 0);
                }
                ctx.device.cmd_end_rendering(cmd);
            }
        }
        rec.end(open);
        self.dirty = false;
    }

    /// Device memory: (one reflector's geometry image: positions + normals; one reflector's
    /// virtual image per view, and the depth buffer the views share).
    pub fn memory(&self) -> (u64, u64, u64) {
        let texel = crate::vk::format_bytes(GEOMETRY_FORMAT) as u64;
        let image = 2 * self.size as u64 * self.size as u64 * texel;
        let pixels = self.width as u64 * self.height as u64;
        (image, pixels * crate::vk::format_bytes(TARGET_FORMAT) as u64, pixels * crate::vk::format_bytes(DEPTH_FORMAT) as u64)
    }
}

impl Stage for CurvedReflectors {
    fn name(&self) -> &'static str {
        self.name
    }

    fn record(&mut self, rec: &mut Recorder, f: &FrameInputs, io: &mut FrameIo) {
        let view = io.views.camera;
        if self.dirty {
            self.record_images(rec, f);
        }
        let (ctx, cmd) = (rec.ctx, rec.cmd);
        if self.tessellate {
            // The environment's tessellation, from the scene's vertices as they are now.
            let open = rec.pass("geometry.virtual.tessellate").after_buffer_writes().begin();
            self.bind(ctx, cmd, vk::PipelineBindPoint::COMPUTE, self.tessellate_pipeline, f);
            self.push(ctx, cmd, f, view, 0, f.flags);
            unsafe { ctx.device.cmd_dispatch(cmd, self.environment.div_ceil(64).max(1), 1, 1) };
            rec.end(open);
            self.tessellate = false;
        }
        // The search (`geometry.virtual.search`, timed apart: its cost is the O(S·D) of survey
        // Table 1): one dispatch per reflector over the environment's vertices.
        let open = rec
            .pass("geometry.virtual.search")
            .after_buffer_writes()
            .reads(&self.positions, Access::ComputeSampled)
            .reads(&self.normals, Access::ComputeSampled)
            .begin();
        unsafe { ctx.device.cmd_fill_buffer(cmd, self.minima.raw, 0, vk::WHOLE_SIZE, 0) };
        let fill = [vk::MemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::ALL_TRANSFER)
            .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags2::COMPUTE_SHADER)
            .dst_access_mask(vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::SHADER_STORAGE_WRITE)];
        unsafe { ctx.device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&fill)) };
        self.bind(ctx, cmd, vk::PipelineBindPoint::COMPUTE, self.search_pipeline, f);
        for k in 0..self.reflectors.len() as u32 {
            self.push(ctx, cmd, f, view, k, f.flags);
            unsafe { ctx.device.cmd_dispatch(cmd, self.environment.div_ceil(64).max(1), 1, 1) };
        }
        rec.end(open);
        // The virtual objects: the environment at its virtual positions, per reflector.
        let mut pass = rec
            .pass("geometry.virtual")
            .after_buffer_writes()
            .writes(&mut self.virtual_images, Access::ColorAttachment)
            .writes(&mut self.virtual_depth, Access::DepthAttachment);
        for img in io.scene_images.iter().copied().chain(io.maps.shadow_reads()).chain(io.maps.camera_reads()) {
            pass = pass.reads(img, Access::FragmentSampled);
        }
        let open = pass.begin();
        // Specular objects of the environment are shaded by their own maps where they have
        // them (curved_virtual.frag): the camera's set 1, or the null one.
        let maps = io.sets.camera.get(io.maps.latest).copied().unwrap_or(io.sets.empty);
        for (k, &reflector) in self.reflectors.iter().enumerate() {
            if k > 0 {
                rec.barrier(&mut self.virtual_depth, Access::DepthAttachment);
            }
            let colors = [self.virtual_images.layer_view(k as u32)];
            let target = Target {
                color: &colors,
                depth: Some(self.virtual_depth.view),
                width: self.width,
                height: self.height,
                view_mask: 0,
                layer_count: 1,
                clear_color: [0.0; 4],
                clear: true,
            };
            begin_rendering(ctx, cmd, &target);
            self.bind(ctx, cmd, vk::PipelineBindPoint::GRAPHICS, self.virtual_pipeline, f);
            if maps != vk::DescriptorSet::null() {
                unsafe { ctx.device.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::GRAPHICS, self.layout, 1, &[maps], &[]) };
            }
            unsafe { ctx.device.cmd_bind_index_buffer(cmd, self.indices.raw, 0, vk::IndexType::UINT32) };
            let flags = f.flags | ((k as u32) << CURVED_REFLECTOR_SHIFT);
            // Hidden objects draw nothing (their scene draw has no index).
            let shown = |d: &&EnvDraw| f.scene.draws.get(d.mesh as usize).is_some_and(|s| s.index_count > 0);
            for d in self.env.iter().filter(|d| d.mesh as usize != reflector).filter(shown) {
                self.push(ctx, cmd, f, view, d.mesh, flags);
                unsafe { ctx.device.cmd_draw_indexed(cmd, d.index_count, 1, d.first_index, 0, 0) };
            }
            unsafe { ctx.device.cmd_end_rendering(cmd) };
        }
        rec.end(open);
        // The reflectors from the camera.
        let open = rec
            .pass(self.name)
            .reads(&self.virtual_images, Access::FragmentSampled)
            .writes(io.target, Access::ColorAttachment)
            .writes(io.depth, Access::DepthAttachment)
            .begin();
        crate::frame::begin_camera_rendering(ctx, cmd, io.target, io.depth, io.area, false);
        self.bind(ctx, cmd, vk::PipelineBindPoint::GRAPHICS, self.shade_pipeline, f);
        f.scene.bind_geometry(ctx, cmd);
        for (k, &reflector) in self.reflectors.iter().enumerate() {
            let Some(d) = f.scene.draws.get(reflector) else { continue };
            self.push(ctx, cmd, f, view, d.mesh, f.flags | ((k as u32) << CURVED_REFLECTOR_SHIFT));
            unsafe { ctx.device.cmd_draw_indexed(cmd, d.index_count, 1, d.first_index, d.vertex_offset, 0) };
        }
        unsafe { ctx.device.cmd_end_rendering(cmd) };
        rec.end(open);
    }

    /// Moved objects: the environment is tessellated again on the GPU from the scene's
    /// updated vertices, the reflectors' triangles are rewritten in place and their geometry
    /// images redrawn.
    fn update(&mut self, init: &StageInit, changes: &crate::scene::update::Changes, _maps: &mut crate::frame::stage::Maps) -> Result<()> {
        if changes.moved.is_empty() {
            return Ok(());
        }
        self.tessellate = true;
        if self.reflectors.iter().any(|r| changes.moved.contains(r)) {
            let (vertices, _, _) = reflector_vertices(init.scene, &self.reflectors, self.size);
            self.reflector_buffer.write(bytemuck::cast_slice(&vertices))?;
            self.dirty = true;
        }
        Ok(())
    }

    /// The environment's vertices (each searched once per reflector and view: the O(S·D) of
    /// survey Table 1), and memory (issue 11): bytes of one geometry image (positions and
    /// normals), of one reflector's virtual image per view and of the shared depth buffer;
    /// reflectors parameterised by a planar projection (no usable UVs); of the vertices
    /// checked for a second reflection point (every CURVED_CHECK_STRIDE-th, per reflector),
    /// those that have one (several minima: a reflector neither convex nor concave from
    /// there, which the planner's convexity test should have refused).
    fn stats(&self, _ctx: &Context) -> Vec<(String, f64)> {
        let (image, view, depth) = self.memory();
        let minima = self.minima.read().map_or(0, |w| w.chunks_exact(4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as u64).sum());
        let checked = self.environment.div_ceil(crate::frame::layout::CURVED_CHECK_STRIDE) as u64 * self.reflectors.len() as u64;
        vec![
            ("geometry.curved_checked".into(), checked as f64),
            ("geometry.curved_multiple_minima".into(), minima as f64),
            ("geometry.curved_reflectors".into(), self.reflectors.len() as f64),
            ("geometry.curved_vertices".into(), self.environment as f64),
            ("geometry.curved_image_bytes".into(), image as f64),
            ("geometry.curved_view_bytes".into(), view as f64),
            ("geometry.curved_depth_bytes".into(), depth as f64),
            ("geometry.curved_projected".into(), self.own_uvs.iter().filter(|o| !**o).count() as f64),
        ]
    }

    fn destroy(&mut self, ctx: &Context) {
        let mut pipelines =
            [self.image_pipeline, self.tessellate_pipeline, self.search_pipeline, self.virtual_pipeline, self.shade_pipeline];
        destroy_pipelines(ctx, &mut pipelines);
        [self.image_pipeline, self.tessellate_pipeline, self.search_pipeline, self.virtual_pipeline, self.shade_pipeline] = pipelines;
        for i in [&mut self.positions, &mut self.normals, &mut self.virtual_images, &mut self.virtual_depth] {
            i.destroy(ctx);
        }
        for b in self.buffers() {
            b.destroy(ctx);
        }
        crate::vk::pipeline::destroy_pipeline_layout(ctx, self.layout);
        for l in [self.set_layout, self.empty_layout] {
            crate::vk::pipeline::destroy_set_layout(ctx, l);
        }
        unsafe {
            let d = &ctx.device;
            if self.pool != vk::DescriptorPool::null() {
                d.destroy_descriptor_pool(self.pool, ctx.alloc());
            }
            if self.nearest != vk::Sampler::null() {
                d.destroy_sampler(self.nearest, ctx.alloc());
            }
        }
        self.layout = vk::PipelineLayout::null();
        self.pool = vk::DescriptorPool::null();
        self.set = vk::DescriptorSet::null();
        self.set_layout = vk::DescriptorSetLayout::null();
        self.empty_layout = vk::DescriptorSetLayout::null();
        self.nearest = vk::Sampler::null();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::facts::{curvature, Curvature};
    use crate::scene::shapes;

    #[test]
    fn tessellation_splits_each_triangle_into_n_squared() {
        let q = shapes::quad("q", Vec3::ZERO, Vec3::X, Vec3::Z, 1, 0);
        for n in [1u32, 2, 5] {
            let (mut v, mut i) = (Vec::new(), Vec::new());
            tessellate(&q, n, &mut v, &mut i);
            assert_eq!(i.len() / 3, (q.triangle_count() as u32 * n * n) as usize, "n = {n}");
            assert_eq!(v.len() as u32, q.triangle_count() as u32 * (n + 1) * (n + 2) / 2);
            // Sub-triangle areas add up to the triangle's.
            let p = |k: u32| Vec3::from_slice(&v[k as usize].position[..3]);
            let area: f32 = i.chunks_exact(3).map(|t| 0.5 * (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])).length()).sum();
            assert!((area - 1.0).abs() < 1e-5, "n = {n}: {area}");
        }
    }

    #[test]
    fn a_sphere_keeps_its_uvs_and_a_uvless_cap_is_projected() {
        let s = shapes::uv_sphere("s", Vec3::ZERO, 1.0, 16, 8, 0);
        let (uv, own) = parameterisation(&s, 64);
        assert!(own);
        assert!(uv.iter().all(|u| u.x >= 0.5 / 64.0 - 1e-6 && u.x <= 1.0 - 0.5 / 64.0 + 1e-6));
        let mut cap = bowl(1.0, 0.7, 12);
        cap.uvs.clear();
        let (uv, own) = parameterisation(&cap, 64);
        assert!(!own);
        assert_eq!(uv.len(), cap.indices.len());
        assert_eq!(curvature(&cap), Curvature::Concave);
    }

    /// Whether no two triangles' charts in `uv` (per corner) overlap, sampled at each
    /// triangle's centroid and its corners pulled towards it; the first overlap found else.
    fn first_overlap(uv: &[Vec2]) -> Option<(usize, Vec2, usize)> {
        let tris: Vec<[Vec2; 3]> =
            uv.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).filter(|t| (t[1] - t[0]).perp_dot(t[2] - t[0]).abs() > 1e-9).collect();
        let inside = |t: &[Vec2; 3], q: Vec2| {
            let s = |a: Vec2, b: Vec2| (b - a).perp_dot(q - a);
            let (a, b, c) = (s(t[0], t[1]), s(t[1], t[2]), s(t[2], t[0]));
            (a > 0.0 && b > 0.0 && c > 0.0) || (a < 0.0 && b < 0.0 && c < 0.0)
        };
        for (i, t) in tris.iter().enumerate() {
            let c = (t[0] + t[1] + t[2]) / 3.0;
            for q in [c, c.lerp(t[0], 0.8), c.lerp(t[1], 0.8), c.lerp(t[2], 0.8)] {
                if let Some(j) = tris.iter().enumerate().position(|(j, o)| j != i && inside(o, q)) {
                    return Some((i, q, j));
                }
            }
        }
        None
    }

    /// A closed sphere without UVs: the cube atlas gives every triangle its own place — no
    /// two triangles' charts overlap, where a plane's projection folds the back onto the
    /// front. So does a nearly closed one (a hole at its pole: its normals do not cancel,
    /// but a plane would still fold it), and a hemisphere keeps the plane's projection,
    /// which holds it one-to-one.
    #[test]
    fn a_closed_uvless_sphere_gets_a_chart_without_overlaps() {
        let mut s = shapes::uv_sphere("s", Vec3::new(0.3, -0.2, 0.1), 0.7, 24, 12, 0);
        s.uvs.clear();
        let (uv, own) = parameterisation(&s, 128);
        assert!(!own && uv.len() == s.indices.len());
        assert!(uv.iter().all(|u| u.x > 0.0 && u.x < 1.0 && u.y > 0.0 && u.y < 1.0));
        assert_eq!(first_overlap(&uv), None);
        // The pole's ring of triangles cut out: a hole of 0.26 of the radius.
        let top = s.positions.iter().map(|p| p.y).fold(f32::MIN, f32::max);
        let cut = |m: &Mesh, above: f32| -> Mesh {
            let keep: Vec<u32> =
                m.indices.chunks_exact(3).filter(|t| t.iter().all(|&i| m.positions[i as usize].y < above)).flatten().copied().collect();
            Mesh { indices: keep, ..m.clone() }
        };
        let holed = cut(&s, top - 1e-3);
        assert!(holed.indices.len() < s.indices.len());
        let (uv, _) = parameterisation(&holed, 128);
        assert_eq!(first_overlap(&uv), None, "the sphere with a hole folds");
        let mut cap = bowl(1.0, 1.5, 12);
        cap.uvs.clear();
        let (uv, _) = parameterisation(&cap, 128);
        assert_eq!(first_overlap(&uv), None, "a cap short of a hemisphere");
    }

    /// A spherical cap of radius r and half-angle a around −y, normals towards its centre.
    fn bowl(r: f32, a: f32, n: u32) -> Mesh {
        let mut m = Mesh { name: "bowl".into(), ..Default::default() };
        for i in 0..=n {
            for j in 0..=n {
                let (u, v) = (i as f32 / n as f32 * 2.0 - 1.0, j as f32 / n as f32 * 2.0 - 1.0);
                let d = Vec3::new(u * a.sin(), -1.0, v * a.sin()).normalize();
                m.positions.push(d * r);
                m.normals.push(-d);
                m.uvs.push(Vec2::new(u, v));
            }
        }
        for i in 0..n {
            for j in 0..n {
                let at = |i: u32, j: u32| i * (n + 1) + j;
                m.indices.extend([at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        m
    }

    #[test]
    fn curvature_tells_spheres_bowls_planes_and_saddles_apart() {
        assert_eq!(curvature(&shapes::uv_sphere("s", Vec3::ZERO, 1.0, 24, 12, 0)), Curvature::Convex);
        let mut inside = shapes::uv_sphere("s", Vec3::ZERO, 1.0, 24, 12, 0);
        inside.normals.iter_mut().for_each(|n| *n = -*n);
        assert_eq!(curvature(&inside), Curvature::Concave);
        assert_eq!(curvature(&bowl(1.0, 0.7, 8)), Curvature::Concave);
        assert_eq!(curvature(&shapes::quad("q", Vec3::ZERO, Vec3::X, Vec3::Z, 4, 0)), Curvature::Flat);
        // z = x² − y² over [−1, 1]², normals up.
        let mut saddle = shapes::quad("q", Vec3::new(-1.0, 0.0, -1.0), Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 2.0), 8, 0);
        for (p, n) in saddle.positions.iter_mut().zip(saddle.normals.iter_mut()) {
            p.y = p.x * p.x - p.z * p.z;
            *n = Vec3::new(-2.0 * p.x, 1.0, 2.0 * p.z).normalize();
        }
        assert_eq!(curvature(&saddle), Curvature::Saddle);
    }
}
