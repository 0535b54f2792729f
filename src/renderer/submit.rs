//! Submitting frames: standalone (record, submit, wait, read the image back with its
//! per-pass profile) and host-device (record into the host's command buffer and copy into
//! its image), and the timings of the last completed frame.

use ash::vk;

use crate::error::{Error, Result};
use crate::frame::direct::TARGET_FORMAT;
use crate::frame::output;
use crate::vk::{Buffer, Context, Image, ImageData, MemoryLocation, PassTiming, Recorder};

use super::{MapUpdate, Renderer};

/// A rendered frame: linear radiance RGBA32F, its per-pass profile and the device memory
/// that the renderer's resources hold.
#[derive(Clone, Debug)]
pub struct Frame {
    pub image: ImageData,
    pub passes: Vec<PassTiming>,
    pub memory: Vec<(String, u64)>,
    /// What the stages and frame parts counted in this frame (`Stage::stats`).
    pub stats: Vec<(String, f64)>,
    /// The maps this frame regenerated, and why (a map not listed was kept).
    pub map_updates: Vec<MapUpdate>,
    /// With `object_ids=on` (a debug output): each pixel's first-hit object from the
    /// camera, mesh index + 1 (0: the sky), row by row from the top.
    pub object_ids: Option<Vec<u32>>,
}

impl Frame {
    pub fn gpu_ms(&self) -> f64 {
        self.passes.iter().map(|p| p.gpu_ms).sum()
    }
    pub fn memory_bytes(&self) -> u64 {
        self.memory.iter().map(|(_, b)| b).sum()
    }
}

impl Renderer {
    /// Host-device mode: records a frame into the host's `cmd` and copies the result into
    /// the host's image (same size; a bit-exact copy for R32G32B32A32_SFLOAT, a blit with
    /// format conversion otherwise), leaving it in `final_layout`.
    pub fn record_into(&mut self, ctx: &Context, cmd: vk::CommandBuffer, host: &mut Image, final_layout: vk::ImageLayout) -> Result<()> {
        if host.width != self.width || host.height != self.height {
            return Err(Error::invalid(
                "target image",
                format!("{}x{} but the renderer was configured for {}x{}", host.width, host.height, self.width, self.height),
            ));
        }
        // The previous frame's timings, if the host has let it complete.
        if let Some(t) = self.profiler.poll(ctx)? {
            self.last_timings = t;
            self.scene.release_staging(ctx);
        }
        self.record(ctx, cmd)?;
        let mut rec = Recorder::resume(ctx, cmd, &mut self.profiler);
        output::record_copy(&mut rec, self.targets.output(), host, final_layout);
        Ok(())
    }

    /// Per-pass timings of the last frame the GPU has completed (host-device mode polls
    /// without waiting; standalone frames are always complete).
    pub fn last_timings(&mut self, ctx: &Context) -> Result<&[PassTiming]> {
        if let Some(t) = self.profiler.poll(ctx)? {
            self.last_timings = t;
        }
        Ok(&self.last_timings)
    }

    /// Standalone: records, submits and waits for one frame, then reads the image back.
    pub fn render(&mut self, ctx: &Context) -> Result<Frame> {
        if self.readback.is_none() {
            let bytes = self.targets.output().byte_size();
            let usage = vk::BufferUsageFlags::TRANSFER_DST;
            self.readback = Some(Buffer::new(ctx, "frame.readback", bytes, usage, MemoryLocation::GpuToCpu)?);
        }
        ctx.one_shot(|cmd| self.record(ctx, cmd))?;
        self.scene.release_staging(ctx);
        let passes = self.profiler.results(ctx)?;
        self.last_timings = passes.clone();
        let rb = self.readback.as_ref().unwrap();
        let image = crate::vk::decode(TARGET_FORMAT, self.width, self.height, 1, rb.read()?)?;
        let errors = ctx.validation.error_count();
        if errors > 0 {
            return Err(Error::Validation(errors));
        }
        let mut stats: Vec<(String, f64)> = self.stages.iter().flat_map(|s| s.stats(ctx)).collect();
        if self.profiler.untimed() > 0 {
            stats.push(("profiler.untimed_passes".into(), self.profiler.untimed() as f64));
        }
        stats.extend(self.parts.iter().flat_map(|p| p.stats()));
        // Per-object counters (`Slot::counts`): the objects' non-zero ones.
        for (name, words) in self.maps.counts() {
            for o in self.plan.objects.iter().filter(|o| words.get(o.mesh).is_some_and(|&n| n > 0)) {
                stats.push((format!("{name}.{}", o.name), words[o.mesh] as f64));
            }
        }
        let object_ids = self.ids.as_ref().map(|i| i.read()).transpose()?;
        let map_updates = self.updates.recorded().to_vec();
        Ok(Frame { image, passes, memory: ctx.memory.snapshot(), stats, map_updates, object_ids })
    }
}
