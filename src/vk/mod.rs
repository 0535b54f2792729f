//! The explicit-resource Vulkan backend on ash. Every object has one owner that creates
//! and destroys it; passes declare what they read and write and record into a command
//! buffer they are handed (the library's own in standalone mode, the host's otherwise).

mod context;
pub mod pipeline;
mod readback;
mod recorder;
mod resource;

pub use context::{
    process_validation_errors, required_features_supported, Context, DeviceOptions, HostHandles, MemoryRegistry, ValidationLog,
    REQUIRED_DEVICE_EXTENSIONS,
};
pub use readback::{decode, read_image, record_copy_to_buffer, ImageData};
pub use recorder::{begin_rendering, OpenPass, PassTiming, Profiler, Recorder, Target};
pub use resource::{format_bytes, is_depth, Access, Buffer, Image, ImageDesc, ImageKind, ImageState, MemoryLocation};
