//! The distance family's slots in the frame's maps (`frame::maps`), all in set 1.

use crate::frame::layout::binding;
use crate::frame::maps::{Sampler, Slot};

/// Distance cube maps (§4), one cube per object; two images (ping-pong) for inter-object
/// cycles, which read the previous cycle's while writing the other (§4.3).
pub const DISTANCE: Slot =
    Slot { camera: true, generation: true, ping_pong: true, ..Slot::image("distance.cubes", 1, binding::DISTANCE_MAPS, Sampler::Linear) };

/// Refractor maps (§4.4): made before the distance maps, whose generation searches them
/// (self refraction), and searched by caustic photons (§6).
pub const REFRACTOR: Slot = Slot {
    camera: true,
    generation: true,
    geometry: true,
    needs_sets: true,
    ..Slot::image("distance.refractor", 1, binding::REFRACTOR_MAPS, Sampler::Linear)
};

/// Camera-space back faces of image-space refraction (§4.4): the camera passes only.
pub const BACKFACES: Slot =
    Slot { camera: true, needs_sets: true, ..Slot::image("distance.backfaces", 1, binding::BACKFACE_MAP, Sampler::Nearest) };

/// Per-vertex thickness of image-space refraction.
pub const THICKNESS: Slot = Slot::buffer("distance.thickness", 1, binding::THICKNESS);

pub const SLOTS: &[Slot] = &[DISTANCE, REFRACTOR, BACKFACES, THICKNESS];
