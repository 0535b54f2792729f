//! The geometry family's slot in the frame's maps (`frame::maps`).

use crate::frame::layout::binding;
use crate::frame::maps::{Sampler, Slot};

/// Set 0: planar mirrors' views (§5), one layer per view of a frame.
pub const MIRROR_VIEWS: Slot = Slot { camera: true, ..Slot::image("geometry.mirror_views", 0, binding::MIRROR_VIEWS, Sampler::Nearest) };

/// Set 0: per mesh the fragments a view budget sent to the object's own maps (`counts`: the
/// frame reports them), where the plan gave planar objects such maps.
pub const FALLBACKS: Slot = Slot { counts: true, ..Slot::buffer("geometry.fallback_pixels", 0, binding::FALLBACKS) };

pub const SLOTS: &[Slot] = &[MIRROR_VIEWS, FALLBACKS];
