//! The ray hierarchy's ray order (survey §2.2.1; the kernels are `glsl/raytrace/sort*`).
//!
//! The ray pipeline appends rays to its queues through atomic counters, so a queue holds
//! its rays in whatever order the GPU ran the kernels that made them: a tile of the ray
//! texture then gathers rays from anywhere on the screen, its cone covers everything, and
//! the hierarchy culls nothing past the camera rays — and culls differently in every run
//! (measured on lavapipe at 16², bounce 1: 17 % of the tile × triangle pairs in most runs,
//! 0.1 % in others). The survey's ray textures keep a secondary ray at its parent's texel;
//! here a counting sort gives each queue that order before the tiles' cones are built: slot
//! t holds ray `ray_order[t]`, a pixel's rays together, the pixels in blocks of tile_size²
//! block by block, and a pixel's few rays ordered by their query's bits, so that the order
//! is the same in every run; the ray texture holds the slots tile by tile, so that a tile's
//! rays come from about one block of the screen (glsl/raytrace/engine.glsl's texel_slot).
//!
//! The method assumes coherent tiles: rays that share origins *and* directions. After a
//! curved mirror or through glass, the rays of one screen block point everywhere, and a
//! tile's cone covered everything (bounce 1 of the demo at 48²: 0 % culled). So the rays
//! (not the shadow rays, whose directions follow their origins towards the lights) are
//! ordered by direction first: the key is the ray's cell on a 4 × 4 octahedral map of
//! directions (`SORT_DIRECTION_CELLS`, the cells in Morton order), then its pixel — a key
//! over direction and origin (the pixel standing for the origin, as the parent's hit
//! point). Measured on the demo at 256², depth 4 (BENCHMARKS.md, the ray hierarchy's
//! culling): bounce 1 rays culled 46 → 74 % at tile 8, 14 → 48 % at tile 16; 2 × 2 cells
//! 64 / 39 %, 8 × 8 cells 62 / 37 % (a cell's rays of a block are then too few for a tile,
//! which spans blocks).
//!
//! Cost: per queue two passes over its rays, one over the K + 1 counters (a three-step
//! scan; K = the pixel keys × the cells, at most 16), one scatter and one pass that orders each
//! key's rays; memory: one word per ray for the order and one for the ranks, one per key
//! for the counters — at most `COUNTER_CAP` (32 MiB): a frame with more pixel keys gets 2 × 2
//! cells or the pixel order alone (512² at 16 samples; 1024² gets 2 × 2).

use ash::vk;

use crate::error::Result;
use crate::frame::layout::{binding, SORT_DIRECTION_CELLS};
use crate::vk::pipeline::{compute_pipeline, write_buffer};
use crate::vk::{Buffer, Context, MemoryLocation};

/// The most bytes the key counters take: where `SORT_DIRECTION_CELLS`² keys per pixel key
/// would need more (512² at 16 samples), the cells per side halve.
const COUNTER_CAP: u64 = 32 << 20;

/// Pixel keys of a `width`×`height` frame of `samples` rays per pixel in tiles of `tile`²:
/// the frame padded to whole blocks, times the samples (glsl/raytrace/sort.glsl's
/// sort_pixel_keys).
fn pixel_keys(width: u32, height: u32, samples: u32, tile: u32) -> u64 {
    let tile = tile.max(1) as u64;
    (width as u64).div_ceil(tile) * (height as u64).div_ceil(tile) * tile * tile * samples.max(1) as u64
}

/// Direction cells per side of the ray order's octahedral map (the `direction_cells` of
/// the trace parameters): `SORT_DIRECTION_CELLS`, halved while the counters (a word per key
/// and one more) would exceed `COUNTER_CAP`; 1 is the pixel order alone.
pub(super) fn direction_cells(width: u32, height: u32, samples: u32, tile: u32) -> u32 {
    let pixels = pixel_keys(width, height, samples, tile);
    let mut cells = SORT_DIRECTION_CELLS;
    while cells > 1 && 4 * (pixels * cells as u64 * cells as u64 + 1) > COUNTER_CAP {
        cells /= 2;
    }
    cells
}

const STORAGE: vk::BufferUsageFlags = vk::BufferUsageFlags::STORAGE_BUFFER;
/// Counters per scan block (glsl/raytrace/sort.glsl's SCAN_BLOCK).
const SCAN_BLOCK: u64 = 1024;

/// The kernels, in the order `record` dispatches them.
const KERNELS: [&str; 6] = [
    "raytrace/sort_count.comp",
    "raytrace/sort_scan_blocks.comp",
    "raytrace/sort_scan_totals.comp",
    "raytrace/sort_scan_add.comp",
    "raytrace/sort_scatter.comp",
    "raytrace/sort_ties.comp",
];

/// The order's buffers and kernels (built with the ray stage's pipeline layout: the
/// kernels read the queue through set 2 and write set 3's order bindings).
pub(super) struct RayOrder {
    order: Buffer,
    offsets: Buffer,
    ranks: Buffer,
    blocks: Buffer,
    pipelines: [vk::Pipeline; 6],
    /// Keys: the frame in whole tile_size² blocks, times the samples, times the direction
    /// cells (glsl/raytrace/sort.glsl's sort_keys).
    keys: u64,
}

impl RayOrder {
    /// For queues of at most `rays` rays of a `width`×`height` frame of `samples` rays per
    /// pixel, in tiles of `tile`² rays: the pixel keys are the frame padded to whole
    /// `tile`² blocks, times the samples, times the direction cells (glsl/raytrace/sort.glsl's
    /// sort_keys).
    pub fn new(
        ctx: &Context,
        layout: vk::PipelineLayout,
        rays: u64,
        (width, height, samples, tile): (u32, u32, u32, u32),
    ) -> Result<RayOrder> {
        let cells = direction_cells(width, height, samples, tile) as u64;
        let keys = pixel_keys(width, height, samples, tile) * cells * cells;
        let mut me = RayOrder {
            order: Buffer::placeholder(),
            offsets: Buffer::placeholder(),
            ranks: Buffer::placeholder(),
            blocks: Buffer::placeholder(),
            pipelines: [vk::Pipeline::null(); 6],
            keys,
        };
        let r = (|| {
            let words = |n: u64| 4 * n.max(1);
            me.order = Buffer::new(ctx, "raytrace.order", words(rays), STORAGE, MemoryLocation::GpuOnly)?;
            me.ranks = Buffer::new(ctx, "raytrace.order.ranks", words(rays), STORAGE, MemoryLocation::GpuOnly)?;
            let usage = STORAGE | vk::BufferUsageFlags::TRANSFER_DST;
            me.offsets = Buffer::new(ctx, "raytrace.order.offsets", words(keys + 1), usage, MemoryLocation::GpuOnly)?;
            me.blocks = Buffer::new(ctx, "raytrace.order.blocks", words(Self::blocks(keys)), STORAGE, MemoryLocation::GpuOnly)?;
            for (p, shader) in me.pipelines.iter_mut().zip(KERNELS) {
                *p = compute_pipeline(ctx, layout, shader)?;
            }
            Ok(())
        })();
        match r {
            Ok(()) => Ok(me),
            Err(e) => {
                me.destroy(ctx);
                Err(e)
            }
        }
    }

    fn blocks(keys: u64) -> u64 {
        (keys + 1).div_ceil(SCAN_BLOCK)
    }

    /// Points set 3's order bindings at this order's buffers, or (no order) at nothing.
    pub fn write(order: Option<&RayOrder>, ctx: &Context, set: vk::DescriptorSet) {
        let sb = vk::DescriptorType::STORAGE_BUFFER;
        let raw = |f: fn(&RayOrder) -> &Buffer| order.map_or(vk::Buffer::null(), |o| f(o).raw);
        write_buffer(ctx, set, binding::RAY_ORDER, sb, raw(|o| &o.order));
        write_buffer(ctx, set, binding::SORT_OFFSETS, sb, raw(|o| &o.offsets));
        write_buffer(ctx, set, binding::SORT_RANKS, sb, raw(|o| &o.ranks));
        write_buffer(ctx, set, binding::SORT_BLOCKS, sb, raw(|o| &o.blocks));
    }

    /// Records the order of the queue bound by `bind` (which binds the kernel with the
    /// queue's sets and push constants): `rays_at` is the queue's indirect dispatch
    /// arguments in `dispatch` (groups of 64 rays).
    pub fn record(&self, ctx: &Context, cmd: vk::CommandBuffer, bind: &dyn Fn(vk::Pipeline), (dispatch, rays_at): (vk::Buffer, u64)) {
        let d = &ctx.device;
        let barrier = |src: vk::PipelineStageFlags2, src_access: vk::AccessFlags2| {
            let b = [vk::MemoryBarrier2::default()
                .src_stage_mask(src)
                .src_access_mask(src_access)
                .dst_stage_mask(vk::PipelineStageFlags2::COMPUTE_SHADER)
                .dst_access_mask(vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::SHADER_STORAGE_WRITE)];
            unsafe { d.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&b)) };
        };
        let compute = || barrier(vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_STORAGE_WRITE);
        let [count, scan_blocks, scan_totals, scan_add, scatter, ties] = self.pipelines;
        let per_ray = |p: vk::Pipeline| {
            bind(p);
            unsafe { d.cmd_dispatch_indirect(cmd, dispatch, rays_at) };
            compute();
        };
        let direct = |p: vk::Pipeline, groups: u64| {
            bind(p);
            unsafe { d.cmd_dispatch(cmd, groups.min(u32::MAX as u64) as u32, 1, 1) };
            compute();
        };
        unsafe { d.cmd_fill_buffer(cmd, self.offsets.raw, 0, vk::WHOLE_SIZE, 0) };
        barrier(vk::PipelineStageFlags2::ALL_TRANSFER, vk::AccessFlags2::TRANSFER_WRITE);
        per_ray(count);
        direct(scan_blocks, Self::blocks(self.keys));
        direct(scan_totals, 1);
        direct(scan_add, (self.keys + 1).div_ceil(256));
        per_ray(scatter);
        per_ray(ties);
    }

    pub fn destroy(&mut self, ctx: &Context) {
        crate::frame::destroy_pipelines(ctx, &mut self.pipelines);
        for b in [&mut self.order, &mut self.offsets, &mut self.ranks, &mut self.blocks] {
            b.destroy(ctx);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cells halve where the counters would pass their cap, and the counters then fit.
    #[test]
    fn direction_cells_fit_the_counter_cap() {
        assert_eq!(direction_cells(48, 48, 1, 8), SORT_DIRECTION_CELLS);
        assert_eq!(direction_cells(512, 512, 1, 8), 4);
        assert_eq!(direction_cells(1024, 1024, 1, 8), 2);
        assert_eq!(direction_cells(512, 512, 16, 8), 1);
        for (w, h, s, t) in [(48, 48, 1, 8), (512, 512, 1, 8), (1024, 1024, 1, 16), (512, 512, 16, 8), (4096, 4096, 16, 32)] {
            let c = direction_cells(w, h, s, t) as u64;
            assert!(c == 1 || 4 * (pixel_keys(w, h, s, t) * c * c + 1) <= COUNTER_CAP, "{w}x{h}x{s}: {c}");
        }
    }
}
