//! BVHs built and refitted on the GPU, for geometry that moves (survey §2.3.5; the kernels
//! are `glsl/raytrace/lbvh*`).
//!
//! The CPU's SAH builder takes 1.5 s for 10⁶ triangles, which a scene pays at every move.
//! Here the GPU builds a **linear BVH** (Lauterbach et al. 2009) in the same node form the
//! traversal kernels read (`bvh.rs`): 30-bit Morton codes of the triangles' centroids on a
//! 1024³ grid over the list's bounds; a stable LSD radix sort of 8 passes of 4 bits (per
//! pass: a histogram per workgroup of 256 keys, one scan of the 16 × groups counters, a
//! scatter that ranks each key within its workgroup by a scan of packed counters); Karras's
//! construction (HPG 2012), one invocation per internal node that finds its range and split
//! from the sorted keys alone (equal keys split by their index); the boxes bottom-up, the
//! second child to reach a node uniting its children's; the stackless traversal's miss
//! links. Internal node i keeps its children in nodes 2i + 1 and 2i + 2, so the traversal's
//! "children `first` and `first + 1`" holds; every leaf holds one triangle. The tree is
//! at most 57 levels deep (each level splits on a longer common prefix of the
//! 32 key bits and then the index's 24), inside the traversal's stack of 96.
//!
//! The **refit** recomputes the boxes of a tree whose topology is kept (the same bottom-up
//! kernel over its leaves): for a linear BVH from the build's own parents, for the CPU's
//! SAH tree from parents and leaves read from its nodes once. A refit costs one pass over
//! the triangles but keeps the old grouping, so its boxes grow loose as objects travel
//! (what the rebuild avoids).
//!
//! Scratch memory (named `raytrace.lbvh.<part>`): keys and triangle indices twice (16 bytes
//! per triangle), 16 counters per 256 triangles, and per node its parent, its place and a
//! flag (12 bytes). A refit of the CPU tree has no keys.

use ash::vk;

use super::gpu::Structure;
use super::TriangleList;
use crate::error::{Error, Result};
use crate::frame::layout::{binding, GpuLbvh, Push, LBVH_BINDINGS, LBVH_NONE, LBVH_TILE};
use crate::vk::pipeline::{allocate_set, compute_pipeline, descriptor_set_layout, pipeline_layout, write_buffer};
use crate::vk::{Buffer, Context, MemoryLocation, Recorder};

const STORAGE: vk::BufferUsageFlags = vk::BufferUsageFlags::STORAGE_BUFFER;
/// The flags are cleared by a fill before each build or refit.
const FILLED: vk::BufferUsageFlags =
    vk::BufferUsageFlags::from_raw(vk::BufferUsageFlags::STORAGE_BUFFER.as_raw() | vk::BufferUsageFlags::TRANSFER_DST.as_raw());
/// Radix-sort passes over the 32-bit keys (LBVH_RADIX_BITS each).
const PASSES: u32 = 8;
/// The most triangles one build takes: a radix-sort dispatch is at most 65535 workgroups.
pub const MAX_TRIANGLES: u64 = 65_535 * LBVH_TILE as u64;

/// The kernels, in the order a build dispatches them.
const KERNELS: [&str; 8] = [
    "raytrace/lbvh_morton.comp",
    "raytrace/lbvh_count.comp",
    "raytrace/lbvh_scan.comp",
    "raytrace/lbvh_scatter.comp",
    "raytrace/lbvh_hierarchy.comp",
    "raytrace/lbvh_parents.comp",
    "raytrace/lbvh_boxes.comp",
    "raytrace/lbvh_links.comp",
];
const MORTON: usize = 0;
const COUNT: usize = 1;
const SCAN: usize = 2;
const SCATTER: usize = 3;
const HIERARCHY: usize = 4;
const PARENTS: usize = 5;
const BOXES: usize = 6;
const LINKS: usize = 7;

/// What the next recording does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Work {
    /// A linear BVH from the triangles as they are now.
    Build,
    /// The boxes of the current tree over the triangles as they are now.
    Refit,
}

/// The node words of a linear BVH over `list` before the GPU fills them (every word 0), in
/// [`Structure`]'s form: 2n − 1 nodes, n references, a miss link per node.
pub fn placeholder(list: &TriangleList, stackless: bool) -> Result<super::Packed> {
    let n = list.len() as u64;
    if n > MAX_TRIANGLES {
        return Err(Error::invalid("bvh_build=lbvh or bvh_update=lbvh", format!("{n} triangles exceed the GPU build's {MAX_TRIANGLES}")));
    }
    let nodes = if n == 0 { 0 } else { 2 * n as usize - 1 };
    Ok(super::Packed {
        nodes: vec![[0; 4]; 2 * nodes],
        refs: vec![0; n as usize],
        aux: vec![0; nodes],
        accel: crate::frame::layout::GpuAccel { triangle_count: n as u32, node_count: nodes as u32, ..bytemuck::Zeroable::zeroed() },
        shader: if stackless { "raytrace/intersect_bvh_stackless.comp" } else { "raytrace/intersect_bvh.comp" },
    })
}

/// The builder of one structure: its kernels, descriptor set and scratch buffers.
pub struct GpuBvh {
    /// Whether it builds (a linear BVH) or only refits (the CPU's tree).
    linear: bool,
    set_layouts: [vk::DescriptorSetLayout; 7],
    layout: vk::PipelineLayout,
    pipelines: [vk::Pipeline; 8],
    pool: vk::DescriptorPool,
    set: vk::DescriptorSet,
    keys: Buffer,
    vals: Buffer,
    counts: Buffer,
    parents: Buffer,
    slots: Buffer,
    flags: Buffer,
    params: Buffer,
    data: GpuLbvh,
    pending: Option<Work>,
    /// Builds and refits recorded so far.
    pub builds: u32,
    pub refits: u32,
}

impl GpuBvh {
    /// A builder of linear BVHs over `list` into `structure` (made from [`placeholder`]);
    /// the first build is pending.
    pub fn linear(ctx: &Context, structure: &Structure, list: &TriangleList) -> Result<GpuBvh> {
        let n = list.len() as u64;
        if n == 0 || n > MAX_TRIANGLES {
            return Err(Error::invalid(
                "bvh_build=lbvh or bvh_update=lbvh",
                format!("{n} triangles: the GPU build takes 1 to {MAX_TRIANGLES}"),
            ));
        }
        if structure.accel.node_count as u64 != 2 * n - 1 {
            return Err(Error::invalid("bvh_build=lbvh", format!("a structure of {} nodes for {n} triangles", structure.accel.node_count)));
        }
        let groups = n.div_ceil(LBVH_TILE as u64);
        let nodes = 2 * n - 1;
        let mut me = GpuBvh::empty(
            true,
            GpuLbvh {
                triangle_count: n as u32,
                groups: groups as u32,
                leaves: n as u32,
                nodes: nodes as u32,
                ..bytemuck::Zeroable::zeroed()
            },
        );
        let made = (|| {
            let gpu = |name: &str, words: u64| {
                Buffer::new(ctx, &format!("raytrace.lbvh.{name}"), 4 * words.max(1), STORAGE, MemoryLocation::GpuOnly)
            };
            me.keys = gpu("keys", 2 * n)?;
            me.vals = gpu("triangles", 2 * n)?;
            me.counts = gpu("counts", 16 * groups)?;
            me.parents = gpu("parents", nodes)?;
            me.slots = gpu("places", nodes)?;
            me.flags = Buffer::new(ctx, "raytrace.lbvh.flags", 4 * nodes, FILLED, MemoryLocation::GpuOnly)?;
            me.set_bounds(list);
            me.init(ctx, structure)?;
            me.pending = Some(Work::Build);
            Ok(())
        })();
        match made {
            Ok(()) => Ok(me),
            Err(e) => {
                me.destroy(ctx);
                Err(e)
            }
        }
    }

    /// A refitter of the tree `structure` holds (the CPU's SAH BVH, or any tree in its form:
    /// its parents and leaves are read from its nodes here, once).
    pub fn refit_of(ctx: &Context, structure: &Structure) -> Result<GpuBvh> {
        let nodes: Vec<[u32; 4]> = bytemuck::pod_collect_to_vec(structure.node_words()?);
        let count = (structure.accel.node_count as usize).min(nodes.len() / 2);
        if count == 0 {
            return Err(Error::invalid("bvh_update=refit", "an empty tree has nothing to refit"));
        }
        let mut parents = vec![LBVH_NONE; count];
        let mut leaves = Vec::new();
        for k in 0..count {
            let (first, n) = (nodes[2 * k][3] as usize, nodes[2 * k + 1][3]);
            if n > 0 {
                leaves.push(k as u32);
            } else if first > k && first + 1 < count {
                parents[first] = k as u32;
                parents[first + 1] = k as u32;
            } else {
                return Err(Error::invalid("bvh_update=refit", format!("node {k}'s children {first} and {} are not after it", first + 1)));
            }
        }
        let data = GpuLbvh {
            triangle_count: structure.accel.triangle_count,
            groups: 0,
            leaves: leaves.len() as u32,
            nodes: count as u32,
            ..bytemuck::Zeroable::zeroed()
        };
        let mut me = GpuBvh::empty(false, data);
        let made = (|| {
            let name = |part: &str| format!("raytrace.lbvh.{part}");
            me.keys = Buffer::new(ctx, &name("keys"), 4, STORAGE, MemoryLocation::GpuOnly)?;
            me.vals = Buffer::new(ctx, &name("triangles"), 4, STORAGE, MemoryLocation::GpuOnly)?;
            me.counts = Buffer::new(ctx, &name("counts"), 4, STORAGE, MemoryLocation::GpuOnly)?;
            me.parents = Buffer::with_data(ctx, &name("parents"), &parents, STORAGE)?;
            me.slots = Buffer::with_data(ctx, &name("places"), &leaves, STORAGE)?;
            me.flags = Buffer::new(ctx, &name("flags"), 4 * count as u64, FILLED, MemoryLocation::GpuOnly)?;
            me.init(ctx, structure)
        })();
        match made {
            Ok(()) => Ok(me),
            Err(e) => {
                me.destroy(ctx);
                Err(e)
            }
        }
    }

    fn empty(linear: bool, data: GpuLbvh) -> GpuBvh {
        GpuBvh {
            linear,
            set_layouts: [vk::DescriptorSetLayout::null(); 7],
            layout: vk::PipelineLayout::null(),
            pipelines: [vk::Pipeline::null(); 8],
            pool: vk::DescriptorPool::null(),
            set: vk::DescriptorSet::null(),
            keys: Buffer::placeholder(),
            vals: Buffer::placeholder(),
            counts: Buffer::placeholder(),
            parents: Buffer::placeholder(),
            slots: Buffer::placeholder(),
            flags: Buffer::placeholder(),
            params: Buffer::placeholder(),
            data,
            pending: None,
            builds: 0,
            refits: 0,
        }
    }

    fn init(&mut self, ctx: &Context, structure: &Structure) -> Result<()> {
        let sets = ctx.properties.limits.max_bound_descriptor_sets;
        if sets < 7 {
            return Err(Error::invalid("GPU BVH build", format!("the device binds {sets} descriptor sets; its kernels use set 6")));
        }
        self.params = Buffer::with_data(ctx, "raytrace.lbvh.params", &[self.data], STORAGE)?;
        let stage = vk::ShaderStageFlags::COMPUTE;
        for k in 0..6 {
            self.set_layouts[k] = descriptor_set_layout(ctx, "raytrace.lbvh.empty", &[], stage)?;
        }
        self.set_layouts[6] = descriptor_set_layout(ctx, "raytrace.lbvh", LBVH_BINDINGS, stage)?;
        self.layout = pipeline_layout(ctx, "raytrace.lbvh", &self.set_layouts, std::mem::size_of::<Push>() as u32, stage)?;
        for (p, shader) in self.pipelines.iter_mut().zip(KERNELS) {
            *p = compute_pipeline(ctx, self.layout, shader)?;
        }
        let (pool, set) = allocate_set(ctx, "raytrace.lbvh", self.set_layouts[6], LBVH_BINDINGS)?;
        self.pool = pool;
        self.set = set;
        let ty = vk::DescriptorType::STORAGE_BUFFER;
        let [triangles, nodes, refs, aux] = structure.buffers();
        for (b, raw) in [
            (binding::LBVH_TRIANGLES, triangles),
            (binding::LBVH_NODES, nodes),
            (binding::LBVH_REFS, refs),
            (binding::LBVH_AUX, aux),
            (binding::LBVH_KEYS, self.keys.raw),
            (binding::LBVH_VALS, self.vals.raw),
            (binding::LBVH_COUNTS, self.counts.raw),
            (binding::LBVH_PARENTS, self.parents.raw),
            (binding::LBVH_SLOTS, self.slots.raw),
            (binding::LBVH_FLAGS, self.flags.raw),
            (binding::LBVH_PARAMS, self.params.raw),
        ] {
            write_buffer(ctx, set, b, ty, raw);
        }
        Ok(())
    }

    /// Whether it builds linear BVHs (else it only refits).
    pub fn builds_linear(&self) -> bool {
        self.linear
    }

    /// The Morton grid over `list`'s bounds (before a build over triangles that moved).
    pub fn set_bounds(&mut self, list: &TriangleList) {
        let (lo, hi) = list.bounds();
        let extent = (hi - lo).max(glam::Vec3::splat(f32::MIN_POSITIVE));
        let scale = glam::Vec3::splat(1024.0) / extent;
        let scale = glam::Vec3::select(scale.is_finite_mask(), scale, glam::Vec3::ZERO);
        self.data.lo = [lo.x, lo.y, lo.z, 0.0];
        self.data.scale = [scale.x, scale.y, scale.z, 0.0];
        if self.params.size > 0 {
            // Host-visible; the frames that read it have completed.
            let _ = self.params.write(bytemuck::bytes_of(&self.data));
        }
    }

    /// Asks the next [`record`](Self::record) for `work` (a refitter cannot build).
    pub fn request(&mut self, work: Work) -> Result<()> {
        if work == Work::Build && !self.linear {
            return Err(Error::invalid("bvh_update=lbvh", "this structure's builder only refits"));
        }
        // A build pending stays one: it covers the refit.
        self.pending = match (self.pending, work) {
            (Some(Work::Build), _) => Some(Work::Build),
            _ => Some(work),
        };
        Ok(())
    }

    /// Whether a build or refit waits for the next recording.
    pub fn pending(&self) -> Option<Work> {
        self.pending
    }

    /// Records the pending work as the pass `raytrace.build` or `raytrace.refit`; nothing
    /// when none is pending. Later passes see the nodes (a memory barrier closes the pass).
    pub fn record(&mut self, ctx: &Context, rec: &mut Recorder) {
        // The kernels read `push.object` alone: the radix-sort pass.
        let push = |pass: u32| Push { view: 0, object: pass, flags: 0, light_count: 0, words: [0; crate::frame::words::COUNT] };
        let Some(work) = self.pending.take() else { return };
        let cmd = rec.cmd;
        let name = if work == Work::Build { "raytrace.build" } else { "raytrace.refit" };
        let open = rec.pass(name).after_buffer_writes().begin();
        let d = &ctx.device;
        let compute = vk::PipelineBindPoint::COMPUTE;
        let groups = |n: u32, size: u32| n.div_ceil(size).max(1);
        let run = |kernel: usize, pass: u32, x: u32| unsafe {
            d.cmd_bind_pipeline(cmd, compute, self.pipelines[kernel]);
            d.cmd_push_constants(cmd, self.layout, vk::ShaderStageFlags::COMPUTE, 0, bytemuck::bytes_of(&push(pass)));
            d.cmd_dispatch(cmd, x, 1, 1);
            barrier(ctx, cmd);
        };
        unsafe {
            d.cmd_bind_descriptor_sets(cmd, compute, self.layout, 6, &[self.set], &[]);
            d.cmd_fill_buffer(cmd, self.flags.raw, 0, vk::WHOLE_SIZE, 0);
        }
        barrier(ctx, cmd);
        let (n, nodes, leaves) = (self.data.triangle_count, self.data.nodes, self.data.leaves);
        if work == Work::Build {
            run(MORTON, 0, groups(n, 64));
            for pass in 0..PASSES {
                run(COUNT, pass, self.data.groups);
                run(SCAN, pass, 1);
                run(SCATTER, pass, self.data.groups);
            }
            run(HIERARCHY, 0, groups(n, 64));
            run(PARENTS, 0, groups(nodes, 64));
        }
        run(BOXES, 0, groups(leaves, 64));
        if work == Work::Build {
            run(LINKS, 0, groups(nodes, 64));
            self.builds += 1;
        } else {
            self.refits += 1;
        }
        rec.end(open);
    }

    /// Device bytes of its scratch buffers.
    pub fn scratch_bytes(&self) -> u64 {
        [&self.keys, &self.vals, &self.counts, &self.parents, &self.slots, &self.flags, &self.params].iter().map(|b| b.size).sum()
    }

    pub fn destroy(&mut self, ctx: &Context) {
        for p in &mut self.pipelines {
            crate::vk::pipeline::release_pipeline(ctx, *p);
            *p = vk::Pipeline::null();
        }
        self.set = vk::DescriptorSet::null();
        crate::vk::pipeline::destroy_layouts(ctx, &mut self.layout, &mut self.pool, &mut self.set_layouts);
        for b in [&mut self.keys, &mut self.vals, &mut self.counts, &mut self.parents, &mut self.slots, &mut self.flags, &mut self.params] {
            b.destroy(ctx);
        }
    }
}

/// Every kernel's writes before the next kernel's reads and writes.
fn barrier(ctx: &Context, cmd: vk::CommandBuffer) {
    let mem = [vk::MemoryBarrier2::default()
        .src_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
        .src_access_mask(vk::AccessFlags2::MEMORY_WRITE)
        .dst_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
        .dst_access_mask(vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE)];
    unsafe { ctx.device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&mem)) };
}
