//! The environment maps' slots in the frame's maps (`frame::maps`).

use crate::frame::layout::binding;
use crate::frame::maps::{Sampler, Slot};

/// Set 0: radiance cube maps (§3), one cube per object; filtered lookups.
pub const RADIANCE: Slot = Slot { camera: true, ..Slot::image("envmap.radiance", 0, binding::ENVMAPS, Sampler::Linear) };

/// Set 0: image-based reflections' captures (§3.3), `captures`³ cubes per object, radiance
/// and distance; filtered lookups (the distance search interpolates as the distance maps').
pub const CAPTURES: Slot = Slot { camera: true, ..Slot::image("envmap.captures", 0, binding::CAPTURES, Sampler::Linear) };

/// Set 0: displacement-mapped proxies' height maps (§3.2), six layers per object; filtered
/// lookups (the march interpolates heights between texels).
pub const RELIEF: Slot = Slot { camera: true, ..Slot::image("envmap.relief", 0, binding::RELIEF_MAPS, Sampler::Linear) };

pub const SLOTS: &[Slot] = &[RADIANCE, CAPTURES, RELIEF];
