//! The layered maps' slots in the frame's maps (`frame::maps`), in set 1. They hold
//! materials and silhouettes: sampled nearest, never blended.

use crate::frame::layout::binding;
use crate::frame::maps::{Sampler, Slot};

/// The layered distance map of the whole scene (§4.5), one cube per layer: radiance and
/// distance. The camera passes reach it through a camera set, so it needs a set pair even
/// without distance maps.
pub const LAYERED: Slot =
    Slot { camera: true, needs_pair: true, ..Slot::image("layered.radiance", 1, binding::LAYERED_MAPS, Sampler::Nearest) };

/// Its normals and materials, one cube per layer.
pub const LAYERED_NORMALS: Slot =
    Slot { camera: true, needs_pair: true, ..Slot::image("layered.normals", 1, binding::LAYERED_NORMALS, Sampler::Nearest) };

/// The previous layer while peeling: bound only in the peel's own sets (`peel.rs`), so
/// never filled in the frame's (null there).
pub const LAYERED_PREVIOUS: Slot = Slot::image("layered.previous", 1, binding::LAYERED_PREVIOUS, Sampler::Nearest);

/// Per mesh, the pixels whose path met the farthest layer of a cut peel (counted where the
/// device lets fragment shaders write; `layered.far_layer_pixels.<object>` in the stats).
pub const LAYERED_FAR: Slot = Slot { counts: true, ..Slot::buffer("layered.far_layer_pixels", 0, binding::LAYERED_FAR) };

pub const SLOTS: &[Slot] = &[LAYERED, LAYERED_NORMALS, LAYERED_PREVIOUS, LAYERED_FAR];
