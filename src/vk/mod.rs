//! The explicit-resource Vulkan backend on ash. Every object has one owner that creates
//! and destroys it; passes declare what they read and write and record into a command
//! buffer they are handed (the library's own in standalone mode, the host's otherwise).

mod context;
pub mod pipeline;
mod pipeline_memo;
mod readback;
mod recorder;
mod resource;

pub use context::{
    process_validation_errors, ray_query_supported, required_features_supported, Context, DeviceOptions, HostHandles, MemoryRegistry,
    RayQueryDevice, ValidationLog, VulkanAllocator, RAY_QUERY_DEVICE_EXTENSIONS, REQUIRED_DEVICE_EXTENSIONS,
};
pub use readback::{decode, read_image, record_copy_to_buffer};
// ImageData moved to crate::image; the old path keeps working.
pub use crate::image::ImageData;
pub use recorder::{begin_rendering, begin_rendering_in, OpenPass, PassTiming, Profiler, Recorder, Target};
/// An owner of device objects whose `destroy` frees whatever exists, a partly built owner
/// included (handles start null or as placeholders).
pub trait Owner {
    fn destroy(&mut self, ctx: &Context);
}

/// Finishes building `me` with `init`; on error frees what was made, so a failure part-way
/// (out of memory, a missing feature) loses nothing.
pub fn build<T: Owner>(ctx: &Context, mut me: T, init: impl FnOnce(&mut T) -> crate::Result<()>) -> crate::Result<T> {
    match init(&mut me) {
        Ok(()) => Ok(me),
        Err(e) => {
            me.destroy(ctx);
            Err(e)
        }
    }
}

pub use resource::{format_bytes, is_depth, Access, Buffer, Image, ImageDesc, ImageKind, ImageState, MemoryLocation};
