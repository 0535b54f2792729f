//! Vulkan acceleration structures for the `ray-query` scheme: one bottom level (BLAS) per
//! mesh over its object-space triangles, one top level (TLAS) over one instance per object.
//!
//! Rules:
//! - **BLAS**: opaque triangles (`OPAQUE`), built on the GPU with `PREFER_FAST_TRACE |
//!   ALLOW_COMPACTION`; where the library submits its own work (standalone contexts) every
//!   BLAS is compacted right after its build when the driver's compacted size saves at
//!   least [`COMPACT_BELOW`] of it. A host-device context records the builds into the first
//!   frame's command buffer and does not compact (the compacted size is known only once the
//!   host's submission has finished).
//! - **Moves** change instances only: an object's new transform is its instance's, and the
//!   TLAS is rebuilt in the next frame (`raytrace.tlas`); no BLAS is built again.
//! - **Deformation** (an object whose object-space positions differ from those its BLAS was
//!   built from): that mesh's BLAS is rebuilt (with `PREFER_FAST_TRACE`; an update would
//!   need `ALLOW_UPDATE`, which trades trace speed for refits the library has no use for,
//!   since its objects deform only when a host edits their vertices).
//! - **Hidden objects** keep their instance with mask 0: no ray hits them.
//!
//! Every buffer is named `raytrace.ray-query.<part>` in the memory registry.

use std::hash::{Hash, Hasher};

use ash::vk;
use glam::{Mat4, Vec3};

use crate::error::{Error, Result, VkCall};
use crate::vk::{Buffer, Context, MemoryLocation, RayQueryDevice};

/// A BLAS is compacted when its compacted size is at most this fraction of its build size.
pub const COMPACT_BELOW: f64 = 0.9;

/// The most triangles the TLAS can address: an instance's custom index (its mesh's first
/// triangle id) has 24 bits.
pub const MAX_TRIANGLES: u64 = 1 << 24;

/// One mesh as its BLAS sees it.
#[derive(Clone, Debug)]
pub struct MeshInput {
    /// Object-space positions and triangle indices.
    pub positions: Vec<Vec3>,
    pub indices: Vec<u32>,
    /// The id of its first triangle in the triangle list (the instance's custom index).
    pub first_triangle: u32,
    /// Object → world.
    pub world: Mat4,
    pub visible: bool,
}

impl MeshInput {
    /// Every mesh of `scene` in object space, with its world transform.
    pub fn from_scene(scene: &crate::scene::Scene) -> Vec<MeshInput> {
        let mut first = 0u32;
        scene
            .meshes
            .iter()
            .map(|m| {
                let input = MeshInput {
                    positions: m.object_positions(),
                    indices: m.indices.clone(),
                    first_triangle: first,
                    world: m.world,
                    visible: !m.hidden,
                };
                first += (m.indices.len() / 3) as u32;
                input
            })
            .collect()
    }

    /// A triangle soup in world space as one mesh (tests, tools).
    pub fn from_soup(triangles: &[[Vec3; 3]]) -> MeshInput {
        MeshInput {
            positions: triangles.iter().flatten().copied().collect(),
            indices: (0..3 * triangles.len() as u32).collect(),
            first_triangle: 0,
            world: Mat4::IDENTITY,
            visible: true,
        }
    }

    /// The BLAS build's vertices and indices: the mesh's, with every zero-area triangle
    /// (|e1 × e2| ≤ 10⁻⁶ |e1| |e2|, which the other schemes' triangle test rejects for every
    /// ray) collapsed onto one extra vertex outside the mesh's bounds, so that every triangle
    /// keeps its primitive index and no ray that the renderer makes meets those. Measured on
    /// lavapipe (Mesa 25.0.7): a ray exactly along a zero-area triangle's segment is reported
    /// as a hit, and a NaN vertex (the spec's inactive triangle) makes its builder lose
    /// other triangles' hits.
    fn build_input(&self) -> (Vec<[f32; 3]>, Vec<u32>) {
        let mut positions: Vec<[f32; 3]> = self.positions.iter().map(|p| p.to_array()).collect();
        let away = positions.len() as u32;
        let mut indices = self.indices.clone();
        let mut collapsed = false;
        for t in indices.chunks_exact_mut(3) {
            let [a, b, c] = [0, 1, 2].map(|k| self.positions.get(t[k] as usize).copied().unwrap_or(Vec3::ZERO));
            let (e1, e2) = (b - a, c - a);
            if e1.cross(e2).length() <= 1e-6 * e1.length() * e2.length() {
                t.copy_from_slice(&[away; 3]);
                collapsed = true;
            }
        }
        if collapsed {
            let (lo, hi) = self.positions.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
            let extent = (hi - lo).max_element().max(1.0);
            positions.push((hi + Vec3::splat(extent)).to_array());
        }
        (positions, indices)
    }

    fn triangles(&self) -> u32 {
        (self.indices.len() / 3) as u32
    }

    /// What decides whether a BLAS must be rebuilt: the object-space positions and indices.
    fn shape_hash(&self) -> u64 {
        let mut h = std::collections::hash_map::DefaultHasher::new();
        for p in &self.positions {
            p.to_array().map(f32::to_bits).hash(&mut h);
        }
        self.indices.hash(&mut h);
        h.finish()
    }
}

/// One acceleration structure and the buffer that holds it.
struct Structure {
    raw: vk::AccelerationStructureKHR,
    buffer: Buffer,
    address: u64,
}

impl Structure {
    fn new(ctx: &Context, rq: &RayQueryDevice, name: &str, ty: vk::AccelerationStructureTypeKHR, size: u64) -> Result<Structure> {
        let usage = vk::BufferUsageFlags::ACCELERATION_STRUCTURE_STORAGE_KHR | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS;
        let mut buffer = Buffer::new(ctx, name, size.max(256), usage, MemoryLocation::GpuOnly)?;
        let info = vk::AccelerationStructureCreateInfoKHR::default().buffer(buffer.raw).size(size.max(256)).ty(ty);
        let raw = match unsafe { rq.accel.create_acceleration_structure(&info, ctx.alloc()) }.call("vkCreateAccelerationStructureKHR") {
            Ok(r) => r,
            Err(e) => {
                buffer.destroy(ctx);
                return Err(e);
            }
        };
        ctx.name(raw, name);
        let address = unsafe {
            rq.accel.get_acceleration_structure_device_address(
                &vk::AccelerationStructureDeviceAddressInfoKHR::default().acceleration_structure(raw),
            )
        };
        Ok(Structure { raw, buffer, address })
    }

    fn destroy(&mut self, ctx: &Context, rq: &RayQueryDevice) {
        if self.raw != vk::AccelerationStructureKHR::null() {
            unsafe { rq.accel.destroy_acceleration_structure(self.raw, ctx.alloc()) };
            self.raw = vk::AccelerationStructureKHR::null();
        }
        self.buffer.destroy(ctx);
    }
}

fn device_address(ctx: &Context, b: &Buffer) -> u64 {
    unsafe { ctx.device.get_buffer_device_address(&vk::BufferDeviceAddressInfo::default().buffer(b.raw)) }
}

const INPUT: vk::BufferUsageFlags = vk::BufferUsageFlags::from_raw(
    vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR.as_raw() | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS.as_raw(),
);
const SCRATCH: vk::BufferUsageFlags =
    vk::BufferUsageFlags::from_raw(vk::BufferUsageFlags::STORAGE_BUFFER.as_raw() | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS.as_raw());

/// One mesh's BLAS and what its pending build reads.
struct Blas {
    structure: Option<Structure>,
    triangles: u32,
    vertices: u32,
    /// The build's inputs and scratch until the build has run.
    positions: Option<Buffer>,
    indices: Option<Buffer>,
    scratch: Option<Buffer>,
    scratch_address: u64,
    shape: u64,
}

/// Build counts and times, for `Stage::stats` and the tests.
#[derive(Clone, Copy, Debug, Default)]
pub struct AccelStats {
    pub blas_builds: u64,
    pub tlas_builds: u64,
    /// Bytes of every BLAS and the TLAS as they are now (compacted where it paid).
    pub bytes: u64,
    /// Bytes the compaction saved.
    pub compacted_away: u64,
    /// The last BLAS builds' and TLAS build's GPU time (standalone builds), milliseconds.
    pub blas_build_ms: f64,
}

/// Every mesh's BLAS, the objects' instances and the TLAS over them.
pub struct AccelStructures {
    blas: Vec<Blas>,
    inputs: Vec<(u32, Mat4, bool)>,
    instances: Buffer,
    tlas: Option<Structure>,
    tlas_scratch: Buffer,
    tlas_scratch_address: u64,
    /// Meshes whose BLAS build is still to be recorded (host-device contexts).
    pending: Vec<usize>,
    tlas_dirty: bool,
    /// The TLAS was recorded since the frame began (`touch` then asks for no other build:
    /// the stages that share it all touch it under `map_updates=always`).
    tlas_built_this_frame: bool,
    pub stats: AccelStats,
}

/// Where the frame keeps the scene's structures (`frame::shared`).
const SHARED_KEY: &str = "ray-query.scene";

/// The scene's structures over `init`'s scene, one set per frame whichever stages trace
/// through them (the ray-query scheme, caustic_paths=exact, the hybrid searches): made by the
/// first that asks, updated by the renderer once per scene change, recorded by the first that
/// records in a frame, destroyed by the renderer.
pub fn scene_structures(init: &crate::frame::stage::StageInit) -> Result<std::rc::Rc<std::cell::RefCell<AccelStructures>>> {
    init.shared.get_or_create(SHARED_KEY, || AccelStructures::new(init.ctx, &MeshInput::from_scene(init.scene)))
}

impl crate::frame::shared::SharedResource for AccelStructures {
    /// Moved objects: new instances (a TLAS in the next frame), BLAS for deformed meshes.
    fn scene_changed(&mut self, init: &crate::frame::stage::StageInit, changes: &crate::scene::update::Changes) -> Result<()> {
        if changes.moved.is_empty() {
            return Ok(());
        }
        self.update(init.ctx, &MeshInput::from_scene(init.scene), &changes.moved)
    }

    fn begin_frame(&mut self) {
        self.tlas_built_this_frame = false;
    }

    fn destroy(&mut self, ctx: &Context) {
        AccelStructures::destroy(self, ctx);
    }
}

fn rq(ctx: &Context) -> Result<&RayQueryDevice> {
    ctx.ray_query.as_ref().map_err(|why| Error::Unsupported(format!("ray queries: {why}")))
}

fn aligned(address: u64, alignment: u64) -> u64 {
    address.div_ceil(alignment) * alignment
}

impl AccelStructures {
    /// Creates every BLAS (built and compacted now on a standalone context; recorded by the
    /// first [`AccelStructures::record`] on a host's) and the TLAS (built by the first
    /// `record`).
    pub fn new(ctx: &Context, meshes: &[MeshInput]) -> Result<AccelStructures> {
        let total: u64 = meshes.iter().map(|m| m.triangles() as u64).sum();
        if total >= MAX_TRIANGLES {
            return Err(Error::invalid(
                "ray-query",
                format!("{total} triangles exceed the {MAX_TRIANGLES} an instance's 24-bit custom index can address"),
            ));
        }
        let mut me = AccelStructures {
            blas: Vec::new(),
            inputs: meshes.iter().map(|m| (m.first_triangle, m.world, m.visible)).collect(),
            instances: Buffer::placeholder(),
            tlas: None,
            tlas_scratch: Buffer::placeholder(),
            tlas_scratch_address: 0,
            pending: Vec::new(),
            tlas_dirty: true,
            tlas_built_this_frame: false,
            stats: AccelStats::default(),
        };
        match me.init(ctx, meshes) {
            Ok(()) => Ok(me),
            Err(e) => {
                me.destroy(ctx);
                Err(e)
            }
        }
    }

    fn init(&mut self, ctx: &Context, meshes: &[MeshInput]) -> Result<()> {
        let rq = rq(ctx)?;
        for m in meshes {
            self.blas.push(Blas {
                structure: None,
                triangles: m.triangles(),
                vertices: m.positions.len() as u32,
                positions: None,
                indices: None,
                scratch: None,
                scratch_address: 0,
                shape: m.shape_hash(),
            });
        }
        let all: Vec<usize> = (0..meshes.len()).collect();
        self.prepare_blas(ctx, rq, meshes, &all)?;
        // Instances: one per mesh, rewritten when objects move.
        let bytes = (meshes.len().max(1) * std::mem::size_of::<vk::AccelerationStructureInstanceKHR>()) as u64;
        self.instances = Buffer::new(ctx, "raytrace.ray-query.instances", bytes, INPUT, MemoryLocation::CpuToGpu)?;
        self.write_instances(ctx)?;
        let count = meshes.len() as u32;
        let (size, scratch) = self.tlas_sizes(ctx, rq, count);
        self.tlas = Some(Structure::new(ctx, rq, "raytrace.ray-query.tlas", vk::AccelerationStructureTypeKHR::TOP_LEVEL, size)?);
        self.tlas_scratch =
            Buffer::new(ctx, "raytrace.ray-query.tlas_scratch", scratch + rq.scratch_alignment, SCRATCH, MemoryLocation::GpuOnly)?;
        self.tlas_scratch_address = aligned(device_address(ctx, &self.tlas_scratch), rq.scratch_alignment);
        if ctx.queue.is_some() {
            self.build_now(ctx, rq, &all)?;
        } else {
            self.pending = all;
        }
        self.update_bytes();
        Ok(())
    }

    fn geometry(&self, ctx: &Context, k: usize) -> vk::AccelerationStructureGeometryKHR<'static> {
        let b = &self.blas[k];
        let address = |buf: &Option<Buffer>| buf.as_ref().map_or(0, |b| device_address(ctx, b));
        let triangles = vk::AccelerationStructureGeometryTrianglesDataKHR::default()
            .vertex_format(vk::Format::R32G32B32_SFLOAT)
            .vertex_data(vk::DeviceOrHostAddressConstKHR { device_address: address(&b.positions) })
            .vertex_stride(12)
            .max_vertex(b.vertices.saturating_sub(1))
            .index_type(vk::IndexType::UINT32)
            .index_data(vk::DeviceOrHostAddressConstKHR { device_address: address(&b.indices) });
        vk::AccelerationStructureGeometryKHR::default()
            .geometry_type(vk::GeometryTypeKHR::TRIANGLES)
            .geometry(vk::AccelerationStructureGeometryDataKHR { triangles })
            .flags(vk::GeometryFlagsKHR::OPAQUE)
    }

    const BLAS_FLAGS: vk::BuildAccelerationStructureFlagsKHR = vk::BuildAccelerationStructureFlagsKHR::from_raw(
        vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE.as_raw()
            | vk::BuildAccelerationStructureFlagsKHR::ALLOW_COMPACTION.as_raw(),
    );

    /// Uploads the inputs of meshes `which`, sizes their BLAS and allocates it and its scratch.
    fn prepare_blas(&mut self, ctx: &Context, rq: &RayQueryDevice, meshes: &[MeshInput], which: &[usize]) -> Result<()> {
        for &k in which {
            let m = &meshes[k];
            let b = &mut self.blas[k];
            b.triangles = m.triangles();
            b.vertices = m.positions.len() as u32;
            b.shape = m.shape_hash();
            if b.triangles == 0 {
                continue;
            }
            let (positions, indices) = m.build_input();
            b.vertices = positions.len() as u32;
            b.positions = Some(Buffer::with_data(ctx, "raytrace.ray-query.vertices", &positions, INPUT)?);
            b.indices = Some(Buffer::with_data(ctx, "raytrace.ray-query.indices", &indices, INPUT)?);
            let geometry = [self.geometry(ctx, k)];
            let info = vk::AccelerationStructureBuildGeometryInfoKHR::default()
                .ty(vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL)
                .flags(Self::BLAS_FLAGS)
                .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
                .geometries(&geometry);
            let mut sizes = vk::AccelerationStructureBuildSizesInfoKHR::default();
            unsafe {
                rq.accel.get_acceleration_structure_build_sizes(
                    vk::AccelerationStructureBuildTypeKHR::DEVICE,
                    &info,
                    &[self.blas[k].triangles],
                    &mut sizes,
                )
            };
            let b = &mut self.blas[k];
            let fresh = Structure::new(
                ctx,
                rq,
                "raytrace.ray-query.blas",
                vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL,
                sizes.acceleration_structure_size,
            )?;
            if let Some(mut old) = b.structure.replace(fresh) {
                old.destroy(ctx, rq);
            }
            let scratch = Buffer::new(
                ctx,
                "raytrace.ray-query.blas_scratch",
                sizes.build_scratch_size.max(1) + rq.scratch_alignment,
                SCRATCH,
                MemoryLocation::GpuOnly,
            )?;
            b.scratch_address = aligned(device_address(ctx, &scratch), rq.scratch_alignment);
            b.scratch = Some(scratch);
        }
        Ok(())
    }

    fn tlas_geometry(&self, ctx: &Context) -> vk::AccelerationStructureGeometryKHR<'static> {
        let instances = vk::AccelerationStructureGeometryInstancesDataKHR::default()
            .array_of_pointers(false)
            .data(vk::DeviceOrHostAddressConstKHR { device_address: device_address(ctx, &self.instances) });
        vk::AccelerationStructureGeometryKHR::default()
            .geometry_type(vk::GeometryTypeKHR::INSTANCES)
            .geometry(vk::AccelerationStructureGeometryDataKHR { instances })
    }

    fn tlas_sizes(&self, ctx: &Context, rq: &RayQueryDevice, count: u32) -> (u64, u64) {
        let geometry = [self.tlas_geometry(ctx)];
        let info = vk::AccelerationStructureBuildGeometryInfoKHR::default()
            .ty(vk::AccelerationStructureTypeKHR::TOP_LEVEL)
            .flags(vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE)
            .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
            .geometries(&geometry);
        let mut sizes = vk::AccelerationStructureBuildSizesInfoKHR::default();
        unsafe {
            rq.accel.get_acceleration_structure_build_sizes(vk::AccelerationStructureBuildTypeKHR::DEVICE, &info, &[count], &mut sizes)
        };
        (sizes.acceleration_structure_size, sizes.build_scratch_size.max(1))
    }

    /// Writes one instance per mesh: its transform, custom index (first triangle), mask
    /// (0 when hidden) and BLAS address (0, inactive, for a mesh without triangles).
    fn write_instances(&mut self, _ctx: &Context) -> Result<()> {
        let mut data = Vec::with_capacity(self.inputs.len());
        for (k, &(first, world, visible)) in self.inputs.iter().enumerate() {
            let c = world.transpose().to_cols_array(); // rows of the 3×4 matrix
            let mut matrix = [0.0f32; 12];
            matrix.copy_from_slice(&c[..12]);
            let address = self.blas[k].structure.as_ref().map_or(0, |s| s.address);
            let mask = if visible && address != 0 { 0xff } else { 0 };
            data.push(vk::AccelerationStructureInstanceKHR {
                transform: vk::TransformMatrixKHR { matrix },
                instance_custom_index_and_mask: vk::Packed24_8::new(first, mask),
                instance_shader_binding_table_record_offset_and_flags: vk::Packed24_8::new(
                    0,
                    vk::GeometryInstanceFlagsKHR::TRIANGLE_FACING_CULL_DISABLE.as_raw() as u8,
                ),
                acceleration_structure_reference: vk::AccelerationStructureReferenceKHR { device_handle: address },
            });
        }
        if data.is_empty() {
            return Ok(());
        }
        // SAFETY: AccelerationStructureInstanceKHR is a repr(C) struct of plain words.
        let bytes = unsafe {
            std::slice::from_raw_parts(data.as_ptr() as *const u8, data.len() * std::mem::size_of::<vk::AccelerationStructureInstanceKHR>())
        };
        self.instances.write(bytes)
    }

    /// Records the BLAS builds of meshes `which`, then a barrier before what reads them.
    fn record_blas(&self, ctx: &Context, rq: &RayQueryDevice, cmd: vk::CommandBuffer, which: &[usize]) {
        let built: Vec<usize> = which.iter().copied().filter(|&k| self.blas[k].triangles > 0 && self.blas[k].structure.is_some()).collect();
        if built.is_empty() {
            return;
        }
        let geometries: Vec<[vk::AccelerationStructureGeometryKHR; 1]> = built.iter().map(|&k| [self.geometry(ctx, k)]).collect();
        let infos: Vec<vk::AccelerationStructureBuildGeometryInfoKHR> = built
            .iter()
            .zip(&geometries)
            .map(|(&k, g)| {
                let b = &self.blas[k];
                vk::AccelerationStructureBuildGeometryInfoKHR::default()
                    .ty(vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL)
                    .flags(Self::BLAS_FLAGS)
                    .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
                    .dst_acceleration_structure(b.structure.as_ref().map_or(vk::AccelerationStructureKHR::null(), |s| s.raw))
                    .geometries(g)
                    .scratch_data(vk::DeviceOrHostAddressKHR { device_address: b.scratch_address })
            })
            .collect();
        let ranges: Vec<[vk::AccelerationStructureBuildRangeInfoKHR; 1]> = built
            .iter()
            .map(|&k| [vk::AccelerationStructureBuildRangeInfoKHR::default().primitive_count(self.blas[k].triangles)])
            .collect();
        let range_refs: Vec<&[vk::AccelerationStructureBuildRangeInfoKHR]> = ranges.iter().map(|r| &r[..]).collect();
        unsafe { rq.accel.cmd_build_acceleration_structures(cmd, &infos, &range_refs) };
        build_barrier(ctx, cmd);
    }

    /// Records the TLAS build over the instances as they are, then a barrier before the
    /// ray queries.
    fn record_tlas(&self, ctx: &Context, rq: &RayQueryDevice, cmd: vk::CommandBuffer) {
        let Some(tlas) = &self.tlas else { return };
        let geometry = [self.tlas_geometry(ctx)];
        let info = [vk::AccelerationStructureBuildGeometryInfoKHR::default()
            .ty(vk::AccelerationStructureTypeKHR::TOP_LEVEL)
            .flags(vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE)
            .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
            .dst_acceleration_structure(tlas.raw)
            .geometries(&geometry)
            .scratch_data(vk::DeviceOrHostAddressKHR { device_address: self.tlas_scratch_address })];
        let range = [vk::AccelerationStructureBuildRangeInfoKHR::default().primitive_count(self.inputs.len() as u32)];
        // Ray queries recorded before (an earlier frame in the same command buffer) finish
        // reading the TLAS before it is written again.
        let before = [vk::MemoryBarrier2::default()
            .src_stage_mask(READERS)
            .src_access_mask(vk::AccessFlags2::ACCELERATION_STRUCTURE_READ_KHR)
            .dst_stage_mask(vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR)
            .dst_access_mask(vk::AccessFlags2::ACCELERATION_STRUCTURE_WRITE_KHR)];
        unsafe { ctx.device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&before)) };
        unsafe { rq.accel.cmd_build_acceleration_structures(cmd, &info, &[&range[..]]) };
        let b = [vk::MemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR)
            .src_access_mask(vk::AccessFlags2::ACCELERATION_STRUCTURE_WRITE_KHR)
            .dst_stage_mask(READERS | vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR)
            .dst_access_mask(vk::AccessFlags2::ACCELERATION_STRUCTURE_READ_KHR | vk::AccessFlags2::ACCELERATION_STRUCTURE_WRITE_KHR)];
        unsafe { ctx.device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&b)) };
    }

    /// Builds the BLAS of meshes `which` in one submission, compacts those where it pays,
    /// and frees their inputs and scratch (standalone contexts).
    fn build_now(&mut self, ctx: &Context, rq: &RayQueryDevice, which: &[usize]) -> Result<()> {
        let built: Vec<usize> = which.iter().copied().filter(|&k| self.blas[k].structure.is_some()).collect();
        if built.is_empty() {
            return Ok(());
        }
        let queries = unsafe {
            ctx.device.create_query_pool(
                &vk::QueryPoolCreateInfo::default()
                    .query_type(vk::QueryType::ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR)
                    .query_count(built.len() as u32),
                None,
            )
        }
        .call("vkCreateQueryPool")?;
        let result = (|| {
            let mut profiler = crate::vk::Profiler::new(ctx, 1)?;
            let r = ctx.one_shot(|cmd| {
                let mut rec = crate::vk::Recorder::new(ctx, cmd, &mut profiler);
                let open = rec.pass("raytrace.blas").begin();
                self.record_blas(ctx, rq, cmd, &built);
                rec.end(open);
                let raws: Vec<vk::AccelerationStructureKHR> = built
                    .iter()
                    .map(|&k| self.blas[k].structure.as_ref().map_or(vk::AccelerationStructureKHR::null(), |s| s.raw))
                    .collect();
                unsafe {
                    ctx.device.cmd_reset_query_pool(cmd, queries, 0, built.len() as u32);
                    rq.accel.cmd_write_acceleration_structures_properties(
                        cmd,
                        &raws,
                        vk::QueryType::ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR,
                        queries,
                        0,
                    );
                }
                Ok(())
            });
            let ms = r.and_then(|_| profiler.results(ctx));
            profiler.destroy(ctx);
            self.stats.blas_build_ms = ms?.iter().map(|p| p.gpu_ms).sum();
            self.stats.blas_builds += built.len() as u64;
            let mut sizes = vec![0u64; built.len()];
            unsafe {
                ctx.device.get_query_pool_results(queries, 0, &mut sizes, vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT)
            }
            .call("vkGetQueryPoolResults")?;
            self.compact(ctx, rq, &built, &sizes)
        })();
        unsafe { ctx.device.destroy_query_pool(queries, ctx.alloc()) };
        for &k in &built {
            self.free_inputs(ctx, k);
        }
        result
    }

    /// Copies each BLAS whose compacted size saves enough into a structure of that size.
    fn compact(&mut self, ctx: &Context, rq: &RayQueryDevice, built: &[usize], sizes: &[u64]) -> Result<()> {
        let mut fresh: Vec<(usize, Structure)> = Vec::new();
        for (&k, &size) in built.iter().zip(sizes) {
            let Some(old) = &self.blas[k].structure else { continue };
            if size == 0 || size as f64 > COMPACT_BELOW * old.buffer.size as f64 {
                continue;
            }
            match Structure::new(ctx, rq, "raytrace.ray-query.blas", vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL, size) {
                Ok(s) => fresh.push((k, s)),
                Err(e) => {
                    for (_, mut s) in fresh {
                        s.destroy(ctx, rq);
                    }
                    return Err(e);
                }
            }
        }
        if fresh.is_empty() {
            return Ok(());
        }
        let copied = ctx.one_shot(|cmd| {
            for (k, s) in &fresh {
                let src = self.blas[*k].structure.as_ref().map_or(vk::AccelerationStructureKHR::null(), |s| s.raw);
                let info =
                    vk::CopyAccelerationStructureInfoKHR::default().src(src).dst(s.raw).mode(vk::CopyAccelerationStructureModeKHR::COMPACT);
                unsafe { rq.accel.cmd_copy_acceleration_structure(cmd, &info) };
            }
            Ok(())
        });
        if let Err(e) = copied {
            for (_, mut s) in fresh {
                s.destroy(ctx, rq);
            }
            return Err(e);
        }
        for (k, s) in fresh {
            if let Some(mut old) = self.blas[k].structure.replace(s) {
                self.stats.compacted_away += old.buffer.size.saturating_sub(self.blas[k].structure.as_ref().map_or(0, |s| s.buffer.size));
                old.destroy(ctx, rq);
            }
        }
        Ok(())
    }

    fn free_inputs(&mut self, ctx: &Context, k: usize) {
        let b = &mut self.blas[k];
        for buf in [&mut b.positions, &mut b.indices, &mut b.scratch] {
            if let Some(mut x) = buf.take() {
                x.destroy(ctx);
            }
        }
    }

    fn update_bytes(&mut self) {
        let blas: u64 = self.blas.iter().filter_map(|b| b.structure.as_ref()).map(|s| s.buffer.size).sum();
        self.stats.bytes = blas + self.tlas.as_ref().map_or(0, |t| t.buffer.size);
    }

    /// Takes the scene's changes for `moved` objects: new transforms and visibility go into
    /// the instances (the TLAS is rebuilt by the next `record`); an object whose object-space
    /// shape changed gets its BLAS rebuilt (now on a standalone context, else by `record`).
    pub fn update(&mut self, ctx: &Context, meshes: &[MeshInput], moved: &[usize]) -> Result<()> {
        let rq = rq(ctx)?;
        if meshes.len() != self.inputs.len() {
            return Err(Error::invalid(
                "ray-query",
                format!("{} meshes, the structures were built for {}", meshes.len(), self.inputs.len()),
            ));
        }
        let deformed: Vec<usize> = moved
            .iter()
            .copied()
            .filter(|&k| {
                k < meshes.len() && (meshes[k].shape_hash() != self.blas[k].shape || meshes[k].triangles() != self.blas[k].triangles)
            })
            .collect();
        for &k in moved.iter().filter(|&&k| k < meshes.len()) {
            self.inputs[k] = (meshes[k].first_triangle, meshes[k].world, meshes[k].visible);
        }
        if !deformed.is_empty() {
            self.prepare_blas(ctx, rq, meshes, &deformed)?;
            if ctx.queue.is_some() {
                self.build_now(ctx, rq, &deformed)?;
            } else {
                self.pending.extend(deformed);
            }
            self.update_bytes();
        }
        self.write_instances(ctx)?;
        self.tlas_dirty |= !moved.is_empty();
        Ok(())
    }

    /// Records what the frame needs built: pending BLAS (host-device contexts), then the
    /// TLAS when objects moved since it was built. Returns whether anything was recorded.
    pub fn record(&mut self, ctx: &Context, rec: &mut crate::vk::Recorder) -> bool {
        let Ok(rq) = ctx.ray_query.as_ref() else { return false };
        let cmd = rec.cmd;
        let mut recorded = false;
        if !self.pending.is_empty() {
            let pending = std::mem::take(&mut self.pending);
            let open = rec.pass("raytrace.blas").begin();
            self.record_blas(ctx, rq, cmd, &pending);
            rec.end(open);
            self.stats.blas_builds += pending.iter().filter(|&&k| self.blas[k].triangles > 0).count() as u64;
            recorded = true;
        }
        if self.tlas_dirty {
            let open = rec.pass("raytrace.tlas").begin();
            self.record_tlas(ctx, rq, cmd);
            rec.end(open);
            self.stats.tlas_builds += 1;
            self.tlas_dirty = false;
            self.tlas_built_this_frame = true;
            recorded = true;
        }
        recorded
    }

    /// Rebuilds the TLAS in the next `record` although nothing moved (`map_updates=always`:
    /// what a frame costs when objects move), unless this frame built it already.
    pub fn touch(&mut self) {
        self.tlas_dirty |= !self.tlas_built_this_frame;
    }

    /// Builds the TLAS now (standalone contexts: tests and tools that intersect without a frame).
    pub fn build_tlas_now(&mut self, ctx: &Context) -> Result<()> {
        let rq = rq(ctx)?;
        ctx.one_shot(|cmd| {
            self.record_tlas(ctx, rq, cmd);
            Ok(())
        })?;
        self.stats.tlas_builds += 1;
        self.tlas_dirty = false;
        Ok(())
    }

    /// The TLAS, for set 4's descriptor.
    pub fn tlas(&self) -> vk::AccelerationStructureKHR {
        self.tlas.as_ref().map_or(vk::AccelerationStructureKHR::null(), |t| t.raw)
    }

    pub fn destroy(&mut self, ctx: &Context) {
        if let Ok(rq) = ctx.ray_query.as_ref() {
            for b in &mut self.blas {
                if let Some(mut s) = b.structure.take() {
                    s.destroy(ctx, rq);
                }
            }
            if let Some(mut t) = self.tlas.take() {
                t.destroy(ctx, rq);
            }
        }
        for k in 0..self.blas.len() {
            self.free_inputs(ctx, k);
        }
        self.blas.clear();
        self.instances.destroy(ctx);
        self.tlas_scratch.destroy(ctx);
    }
}

/// Points a ray-query set 5's TLAS binding at `tlas`.
pub fn write_tlas(ctx: &Context, set: vk::DescriptorSet, tlas: vk::AccelerationStructureKHR) {
    let structures = [tlas];
    let mut info = vk::WriteDescriptorSetAccelerationStructureKHR::default().acceleration_structures(&structures);
    let mut w = vk::WriteDescriptorSet::default()
        .dst_set(set)
        .dst_binding(crate::frame::layout::binding::TLAS)
        .descriptor_type(vk::DescriptorType::ACCELERATION_STRUCTURE_KHR)
        .push_next(&mut info);
    w.descriptor_count = 1;
    unsafe { ctx.device.update_descriptor_sets(&[w], &[]) };
}

/// BLAS builds before the TLAS build (and any later build) reads them.
/// The stages whose shaders trace ray queries: the ray pipeline's kernels, the raster passes'
/// fragments (exact caustic photons, the hybrid searches).
const READERS: vk::PipelineStageFlags2 =
    vk::PipelineStageFlags2::from_raw(vk::PipelineStageFlags2::COMPUTE_SHADER.as_raw() | vk::PipelineStageFlags2::FRAGMENT_SHADER.as_raw());

fn build_barrier(ctx: &Context, cmd: vk::CommandBuffer) {
    let b = [vk::MemoryBarrier2::default()
        .src_stage_mask(vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR)
        .src_access_mask(vk::AccessFlags2::ACCELERATION_STRUCTURE_WRITE_KHR)
        .dst_stage_mask(
            vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR | vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_COPY_KHR | READERS,
        )
        .dst_access_mask(vk::AccessFlags2::ACCELERATION_STRUCTURE_READ_KHR | vk::AccessFlags2::ACCELERATION_STRUCTURE_WRITE_KHR)];
    unsafe { ctx.device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&b)) };
}
