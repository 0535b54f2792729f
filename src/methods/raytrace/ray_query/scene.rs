//! What a raster pass traces ray queries through (the exact caustic photons, the hybrid
//! camera pass): the scene's acceleration structures (the frame's one set, shared with every
//! stage that traces), the triangles' shading, a pair of counters per object, set 5 over
//! them, and the pipeline layout that adds set 5 to the frame's sets 0 and 1 (sets 2–4
//! empty).

use std::cell::RefCell;
use std::rc::Rc;

use ash::vk;

use super::super::stage::SceneShading;
use super::accel::{scene_structures, write_tlas, AccelStructures};
use crate::frame::layout::{binding, RAY_QUERY_BINDINGS};
use crate::frame::stage::StageInit;
use crate::frame::PUSH_BYTES;
use crate::vk::pipeline::{allocate_set, descriptor_set_layout, destroy_layouts, pipeline_layout, write_buffer};
use crate::vk::{build, Buffer, Context, MemoryLocation, Owner, Recorder};
use crate::Result;

pub struct SceneRays {
    /// The frame's structures (the renderer destroys them).
    pub accel: Rc<RefCell<AccelStructures>>,
    /// The frame's triangle shading (shared, as the structures).
    shading: Rc<RefCell<SceneShading>>,
    /// Per mesh two words (`RQ_COUNTS`): rays a pass asked about, rays it traced.
    counts: Buffer,
    /// Empty sets 2–4, then set 5.
    set_layouts: [vk::DescriptorSetLayout; 4],
    /// The frame's sets 0 and 1, empty 2–4, set 5; the frame's push constants.
    pub layout: vk::PipelineLayout,
    pool: vk::DescriptorPool,
    pub set: vk::DescriptorSet,
    /// `map_updates=always`: the TLAS is rebuilt every frame, as when objects move.
    tlas_every_frame: bool,
}

impl SceneRays {
    /// Builds the structures over `init`'s scene (named `name.*` in the memory registry).
    pub fn new(init: &StageInit, name: &str) -> Result<SceneRays> {
        let ctx = init.ctx;
        let me = SceneRays {
            accel: scene_structures(init)?,
            shading: SceneShading::of(init)?,
            counts: Buffer::placeholder(),
            set_layouts: [vk::DescriptorSetLayout::null(); 4],
            layout: vk::PipelineLayout::null(),
            pool: vk::DescriptorPool::null(),
            set: vk::DescriptorSet::null(),
            tlas_every_frame: init.plan.quality.frame.map_updates_always,
        };
        build(ctx, me, |me| {
            let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
            let words = 2 * init.scene.meshes.len().max(1) as u64;
            me.counts = Buffer::new(
                ctx,
                &format!("{name}.counts"),
                4 * words,
                storage | vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuToCpu,
            )?;
            let stages = vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT | vk::ShaderStageFlags::COMPUTE;
            for k in 0..3 {
                me.set_layouts[k] = descriptor_set_layout(ctx, &format!("{name}.empty"), &[], stages)?;
            }
            me.set_layouts[3] = descriptor_set_layout(ctx, name, RAY_QUERY_BINDINGS, stages)?;
            let l = &me.set_layouts;
            let layouts = [init.set_layouts[0], init.set_layouts[1], l[0], l[1], l[2], l[3]];
            me.layout = pipeline_layout(ctx, name, &layouts, PUSH_BYTES, stages)?;
            (me.pool, me.set) = allocate_set(ctx, name, me.set_layouts[3], RAY_QUERY_BINDINGS)?;
            write_tlas(ctx, me.set, me.accel.borrow().tlas());
            write_buffer(ctx, me.set, binding::RQ_SHADING, vk::DescriptorType::STORAGE_BUFFER, me.shading.borrow().0.raw);
            write_buffer(ctx, me.set, binding::RQ_COUNTS, vk::DescriptorType::STORAGE_BUFFER, me.counts.raw);
            Ok(())
        })
    }

    /// Records the builds this frame needs and zeroes the counters, before the pass that
    /// traces.
    pub fn record(&mut self, ctx: &Context, rec: &mut Recorder) {
        let mut accel = self.accel.borrow_mut();
        if self.tlas_every_frame {
            accel.touch();
        }
        accel.record(ctx, rec);
        drop(accel);
        let cmd = rec.cmd;
        unsafe { ctx.device.cmd_fill_buffer(cmd, self.counts.raw, 0, vk::WHOLE_SIZE, 0) };
        let b = [vk::MemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::ALL_TRANSFER | vk::PipelineStageFlags2::FRAGMENT_SHADER)
            .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE | vk::AccessFlags2::SHADER_STORAGE_WRITE)
            .dst_stage_mask(
                vk::PipelineStageFlags2::FRAGMENT_SHADER | vk::PipelineStageFlags2::ALL_TRANSFER | vk::PipelineStageFlags2::HOST,
            )
            .dst_access_mask(
                vk::AccessFlags2::SHADER_STORAGE_READ
                    | vk::AccessFlags2::SHADER_STORAGE_WRITE
                    | vk::AccessFlags2::TRANSFER_WRITE
                    | vk::AccessFlags2::HOST_READ,
            )];
        unsafe { ctx.device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&b)) };
    }

    /// Binds set 5 for a graphics pipeline made with `layout`.
    pub fn bind(&self, ctx: &Context, cmd: vk::CommandBuffer) {
        unsafe { ctx.device.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::GRAPHICS, self.layout, 5, &[self.set], &[]) };
    }

    /// Per mesh (asked, traced) as the last completed frame counted them.
    pub fn counts(&self) -> Vec<(u32, u32)> {
        let Ok(bytes) = self.counts.read() else { return Vec::new() };
        let words: Vec<u32> = bytes.chunks_exact(4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect();
        words.chunks_exact(2).map(|w| (w[0], w[1])).collect()
    }
}

impl Owner for SceneRays {
    fn destroy(&mut self, ctx: &Context) {
        destroy_layouts(ctx, &mut self.layout, &mut self.pool, &mut self.set_layouts);
        self.counts.destroy(ctx);
    }
}
