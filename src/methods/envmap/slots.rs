//! The environment maps' slot in the frame's maps (`frame::maps`).

use crate::frame::layout::binding;
use crate::frame::maps::{Sampler, Slot};

/// Set 0: radiance cube maps (§3), one cube per object; filtered lookups.
pub const RADIANCE: Slot = Slot { camera: true, ..Slot::image("envmap.radiance", 0, binding::ENVMAPS, Sampler::Linear) };

pub const SLOTS: &[Slot] = &[RADIANCE];
