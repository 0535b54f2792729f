//! One acceleration scheme on the GPU: its buffers (the triangle list, nodes, references,
//! auxiliary words, parameters, each named `raytrace.<scheme>.<part>` in the memory
//! registry), which set 2's scheme bindings point at, and the one-shot intersection of a
//! query buffer (tests, tools) with its own pipeline.

use ash::vk;

use super::lbvh::{GpuBvh, Work};
use super::ray_query::accel::{AccelStructures, MeshInput};
use super::{Packed, Scheme, TriangleList};
use crate::error::{Error, Result};
use crate::frame::layout::{binding, GpuAccel, GpuRayHit, GpuRayQuery, RAY_BINDINGS, RAY_QUERY_BINDINGS};
use crate::vk::pipeline::{allocate_set, compute_pipeline, descriptor_set_layout, pipeline_layout, write_buffer};
use crate::vk::{Buffer, Context, MemoryLocation, Profiler, Recorder};

const STORAGE: vk::BufferUsageFlags = vk::BufferUsageFlags::STORAGE_BUFFER;

/// A scheme's structure and the triangle list on the device.
pub struct Structure {
    pub scheme: Scheme,
    pub accel: GpuAccel,
    /// The scheme's intersection kernel.
    pub shader: &'static str,
    triangles: Buffer,
    nodes: Buffer,
    refs: Buffer,
    aux: Buffer,
    params: Buffer,
    structure_bytes: u64,
}

impl Structure {
    /// Uploads `list` and the scheme's structure `packed` (built from `list`).
    pub fn new(ctx: &Context, scheme: Scheme, list: &TriangleList, packed: &Packed) -> Result<Structure> {
        let mut me = Structure {
            scheme,
            accel: packed.accel,
            shader: packed.shader,
            triangles: Buffer::placeholder(),
            nodes: Buffer::placeholder(),
            refs: Buffer::placeholder(),
            aux: Buffer::placeholder(),
            params: Buffer::placeholder(),
            structure_bytes: packed.bytes(),
        };
        match me.upload(ctx, list, packed) {
            Ok(()) => Ok(me),
            Err(e) => {
                me.destroy(ctx);
                Err(e)
            }
        }
    }

    fn upload(&mut self, ctx: &Context, list: &TriangleList, packed: &Packed) -> Result<()> {
        let scheme = self.scheme.pass_name().trim_start_matches("raytrace.intersect.");
        let name = |part: &str| format!("raytrace.{scheme}.{part}");
        self.triangles = Buffer::with_data(ctx, &name("triangles"), &list.gpu(), STORAGE)?;
        // Empty parts get one word, so that every binding holds a valid buffer.
        let or_one = |v: &[u32]| if v.is_empty() { vec![0u32] } else { v.to_vec() };
        if matches!(self.scheme, Scheme::Bvh { gpu: true, .. }) {
            // The GPU writes them (`lbvh.rs`): device memory, nothing uploaded.
            let words = |n: usize| 4 * n.max(1) as u64;
            self.nodes = Buffer::new(ctx, &name("nodes"), 4 * words(packed.nodes.len()), STORAGE, MemoryLocation::GpuOnly)?;
            self.refs = Buffer::new(ctx, &name("refs"), words(packed.refs.len()), STORAGE, MemoryLocation::GpuOnly)?;
            self.aux = Buffer::new(ctx, &name("aux"), words(packed.aux.len()), STORAGE, MemoryLocation::GpuOnly)?;
        } else {
            let nodes: Vec<u32> = packed.nodes.iter().flatten().copied().collect();
            self.nodes = Buffer::with_data(ctx, &name("nodes"), &or_one(&nodes), STORAGE)?;
            self.refs = Buffer::with_data(ctx, &name("refs"), &or_one(&packed.refs), STORAGE)?;
            self.aux = Buffer::with_data(ctx, &name("aux"), &or_one(&packed.aux), STORAGE)?;
        }
        self.params = Buffer::with_data(ctx, &name("params"), &[packed.accel], STORAGE)?;
        Ok(())
    }

    /// Writes the triangle list and the structure into a set-2 descriptor set.
    pub fn write(&self, ctx: &Context, set: vk::DescriptorSet) {
        let ty = vk::DescriptorType::STORAGE_BUFFER;
        write_buffer(ctx, set, binding::RAY_TRIANGLES, ty, self.triangles.raw);
        write_buffer(ctx, set, binding::ACCEL_NODES, ty, self.nodes.raw);
        write_buffer(ctx, set, binding::ACCEL_REFS, ty, self.refs.raw);
        write_buffer(ctx, set, binding::ACCEL_AUX, ty, self.aux.raw);
        write_buffer(ctx, set, binding::ACCEL_PARAMS, ty, self.params.raw);
    }

    /// Device bytes of the structure (nodes, references, auxiliary words), without the
    /// triangle list that every scheme shares.
    pub fn structure_bytes(&self) -> u64 {
        self.structure_bytes
    }

    /// The triangle list, nodes, references and auxiliary words (what a GPU builder writes).
    pub fn buffers(&self) -> [vk::Buffer; 4] {
        [self.triangles.raw, self.nodes.raw, self.refs.raw, self.aux.raw]
    }

    /// The node words as the device holds them (host-visible; no frame may be writing them).
    pub fn node_words(&self) -> Result<&[u8]> {
        self.nodes.read()
    }

    /// Rewrites the triangle list in place (the frames that read it have completed): the
    /// same number of triangles, moved or deformed; the structure is then stale until a
    /// GPU build or refit (`lbvh.rs`).
    pub fn write_triangles(&mut self, list: &TriangleList) -> Result<()> {
        if list.len() as u32 != self.accel.triangle_count {
            return Err(Error::invalid(
                "raytrace.triangles",
                format!("{} triangles where the structure has {}", list.len(), self.accel.triangle_count),
            ));
        }
        self.triangles.write(bytemuck::cast_slice(&list.gpu()))
    }

    pub fn destroy(&mut self, ctx: &Context) {
        for b in [&mut self.triangles, &mut self.nodes, &mut self.refs, &mut self.aux, &mut self.params] {
            b.destroy(ctx);
        }
    }
}

/// A structure with its own intersection pipeline and descriptor set.
pub struct Intersector {
    pub structure: Structure,
    count: Buffer,
    /// Empty layouts for sets 0 and 1, then set 2; for ray queries empty sets 3 and 4 and set 5.
    set_layouts: [vk::DescriptorSetLayout; 6],
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
    pool: vk::DescriptorPool,
    set: vk::DescriptorSet,
    /// The ray-query scheme's structures (over the list as one mesh) and its set 5.
    pub accel: Option<AccelStructures>,
    /// The GPU builder (`bvh_build=lbvh`, or a refit asked for by `update`).
    pub gpu_bvh: Option<GpuBvh>,
    rq_pool: vk::DescriptorPool,
    rq_set: vk::DescriptorSet,
}

impl Intersector {
    /// Uploads `list` and the scheme's structure `packed` (built from `list`).
    pub fn new(ctx: &Context, scheme: Scheme, list: &TriangleList, packed: &Packed) -> Result<Intersector> {
        let structure = Structure::new(ctx, scheme, list, packed)?;
        let mut me = Intersector {
            structure,
            count: Buffer::placeholder(),
            set_layouts: [vk::DescriptorSetLayout::null(); 6],
            layout: vk::PipelineLayout::null(),
            pipeline: vk::Pipeline::null(),
            pool: vk::DescriptorPool::null(),
            set: vk::DescriptorSet::null(),
            accel: None,
            gpu_bvh: None,
            rq_pool: vk::DescriptorPool::null(),
            rq_set: vk::DescriptorSet::null(),
        };
        match me.init(ctx, list) {
            Ok(()) => Ok(me),
            Err(e) => {
                me.destroy(ctx);
                Err(e)
            }
        }
    }

    fn init(&mut self, ctx: &Context, list: &TriangleList) -> Result<()> {
        self.count = Buffer::with_data(ctx, "raytrace.count", &[0u32], STORAGE)?;
        let stage = vk::ShaderStageFlags::COMPUTE;
        self.set_layouts[0] = descriptor_set_layout(ctx, "raytrace.set0", &[], stage)?;
        self.set_layouts[1] = descriptor_set_layout(ctx, "raytrace.set1", &[], stage)?;
        self.set_layouts[2] = descriptor_set_layout(ctx, "raytrace.rays", RAY_BINDINGS, stage)?;
        let sets = if self.structure.scheme == Scheme::RayQuery {
            let mut accel = AccelStructures::new(ctx, &[MeshInput::from_soup(&list.triangles)])?;
            let built = accel.build_tlas_now(ctx);
            self.accel = Some(accel);
            built?;
            self.set_layouts[3] = descriptor_set_layout(ctx, "raytrace.set3", &[], stage)?;
            self.set_layouts[4] = descriptor_set_layout(ctx, "raytrace.set4", &[], stage)?;
            self.set_layouts[5] = descriptor_set_layout(ctx, "raytrace.ray-query", RAY_QUERY_BINDINGS, stage)?;
            let (pool, set) = allocate_set(ctx, "raytrace.ray-query", self.set_layouts[5], RAY_QUERY_BINDINGS)?;
            self.rq_pool = pool;
            self.rq_set = set;
            super::ray_query::accel::write_tlas(ctx, set, self.accel.as_ref().map_or(vk::AccelerationStructureKHR::null(), |a| a.tlas()));
            // The kernel reads no shading.
            write_buffer(ctx, set, binding::RQ_SHADING, vk::DescriptorType::STORAGE_BUFFER, vk::Buffer::null());
            write_buffer(ctx, set, binding::RQ_COUNTS, vk::DescriptorType::STORAGE_BUFFER, vk::Buffer::null());
            6
        } else {
            3
        };
        self.layout = pipeline_layout(ctx, "raytrace.intersect", &self.set_layouts[..sets], 0, stage)?;
        self.pipeline = compute_pipeline(ctx, self.layout, self.structure.shader)?;
        let (pool, set) = allocate_set(ctx, "raytrace.rays", self.set_layouts[2], RAY_BINDINGS)?;
        self.pool = pool;
        self.set = set;
        self.structure.write(ctx, set);
        let ty = vk::DescriptorType::STORAGE_BUFFER;
        write_buffer(ctx, set, binding::RAY_COUNT, ty, self.count.raw);
        write_buffer(ctx, set, binding::RAY_PAYLOADS, ty, vk::Buffer::null());
        if matches!(self.structure.scheme, Scheme::Bvh { gpu: true, .. }) && !list.is_empty() {
            self.gpu_bvh = Some(GpuBvh::linear(ctx, &self.structure, list)?);
            self.run_gpu_work(ctx)?;
        }
        Ok(())
    }

    /// Moves the triangles to `list` (the same count) and brings the structure up to date
    /// on the GPU by `work`: a fresh linear BVH (only for `bvh_build=lbvh` structures) or a
    /// refit of the current tree (any BVH). Returns the GPU milliseconds it took.
    pub fn update(&mut self, ctx: &Context, list: &TriangleList, work: Work) -> Result<f64> {
        if !matches!(self.structure.scheme, Scheme::Bvh { .. }) {
            return Err(Error::invalid("raytrace.update", format!("{:?} has no GPU build or refit", self.structure.scheme)));
        }
        self.structure.write_triangles(list)?;
        if self.gpu_bvh.is_none() {
            self.gpu_bvh = Some(GpuBvh::refit_of(ctx, &self.structure)?);
        }
        let b = self.gpu_bvh.as_mut().expect("just set");
        b.set_bounds(list);
        b.request(work)?;
        self.run_gpu_work(ctx)
    }

    /// Submits the builder's pending work and waits; its GPU milliseconds.
    fn run_gpu_work(&mut self, ctx: &Context) -> Result<f64> {
        let Some(b) = self.gpu_bvh.as_mut() else { return Ok(0.0) };
        let mut profiler = Profiler::new(ctx, 2)?;
        let r = ctx.one_shot(|cmd| {
            let mut rec = Recorder::new(ctx, cmd, &mut profiler);
            b.record(ctx, &mut rec);
            Ok(())
        });
        let ms = r.and_then(|_| profiler.results(ctx)).map(|p| p.iter().map(|p| p.gpu_ms).sum::<f64>());
        profiler.destroy(ctx);
        ms
    }

    /// Records the intersection of `count` queries into `hits` under the pass name
    /// `raytrace.intersect.<scheme>`; one recording per submission (the count and the
    /// query and hit descriptors are rewritten).
    pub fn record(&mut self, ctx: &Context, rec: &mut Recorder, queries: &Buffer, hits: &Buffer, count: u32) -> Result<()> {
        if (queries.size as usize) < count as usize * std::mem::size_of::<GpuRayQuery>()
            || (hits.size as usize) < count as usize * std::mem::size_of::<GpuRayHit>()
        {
            return Err(Error::invalid("raytrace.intersect", format!("buffers too small for {count} rays")));
        }
        self.count.write(bytemuck::bytes_of(&count))?;
        let ty = vk::DescriptorType::STORAGE_BUFFER;
        write_buffer(ctx, self.set, binding::RAY_QUERIES, ty, queries.raw);
        write_buffer(ctx, self.set, binding::RAY_HITS, ty, hits.raw);
        let cmd = rec.cmd;
        let open = rec.pass(self.structure.scheme.pass_name()).begin();
        unsafe {
            ctx.device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.pipeline);
            ctx.device.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::COMPUTE, self.layout, 2, &[self.set], &[]);
            if self.rq_set != vk::DescriptorSet::null() {
                ctx.device.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::COMPUTE, self.layout, 5, &[self.rq_set], &[]);
            }
            ctx.device.cmd_dispatch(cmd, count.div_ceil(64), 1, 1);
        }
        rec.end(open);
        Ok(())
    }

    /// Intersects `queries` in one submission and reads the hits back, with the GPU time.
    pub fn intersect(&mut self, ctx: &Context, queries: &[GpuRayQuery]) -> Result<(Vec<GpuRayHit>, f64)> {
        let n = queries.len().max(1);
        let mut q = Buffer::with_data(ctx, "raytrace.queries", queries, STORAGE)?;
        let mut h =
            match Buffer::new(ctx, "raytrace.hits", (n * std::mem::size_of::<GpuRayHit>()) as u64, STORAGE, MemoryLocation::GpuToCpu) {
                Ok(h) => h,
                Err(e) => {
                    q.destroy(ctx);
                    return Err(e);
                }
            };
        let result = (|| {
            let mut profiler = Profiler::new(ctx, 2)?;
            let r = ctx.one_shot(|cmd| {
                let mut rec = Recorder::new(ctx, cmd, &mut profiler);
                self.record(ctx, &mut rec, &q, &h, queries.len() as u32)?;
                let barrier = [vk::MemoryBarrier2::default()
                    .src_stage_mask(vk::PipelineStageFlags2::COMPUTE_SHADER)
                    .src_access_mask(vk::AccessFlags2::SHADER_STORAGE_WRITE)
                    .dst_stage_mask(vk::PipelineStageFlags2::HOST)
                    .dst_access_mask(vk::AccessFlags2::HOST_READ)];
                unsafe { ctx.device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&barrier)) };
                Ok(())
            });
            let ms = r.and_then(|_| profiler.results(ctx)).map(|p| p.iter().map(|p| p.gpu_ms).sum::<f64>());
            profiler.destroy(ctx);
            let ms = ms?;
            let hits: Vec<GpuRayHit> = bytemuck::pod_collect_to_vec(&h.read()?[..queries.len() * std::mem::size_of::<GpuRayHit>()]);
            Ok((hits, ms))
        })();
        q.destroy(ctx);
        h.destroy(ctx);
        result
    }

    pub fn destroy(&mut self, ctx: &Context) {
        unsafe {
            crate::vk::pipeline::release_pipeline(ctx, self.pipeline);
            ctx.device.destroy_descriptor_pool(self.rq_pool, ctx.alloc());
        }
        self.pipeline = vk::Pipeline::null();
        self.rq_pool = vk::DescriptorPool::null();
        self.rq_set = vk::DescriptorSet::null();
        crate::vk::pipeline::destroy_layouts(ctx, &mut self.layout, &mut self.pool, &mut self.set_layouts);
        if let Some(mut a) = self.accel.take() {
            a.destroy(ctx);
        }
        if let Some(mut b) = self.gpu_bvh.take() {
            b.destroy(ctx);
        }
        self.count.destroy(ctx);
        self.structure.destroy(ctx);
    }
}
