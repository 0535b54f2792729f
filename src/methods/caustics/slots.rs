//! The caustics' slots in the frame's maps (`frame::maps`), all in set 0: the photon and
//! light images live there since the splat and filter passes sample them through it.

use crate::frame::layout::binding;
use crate::frame::maps::{Sampler, Slot};

/// Generators' receiver distance cubes (§6), sampled wherever diffuse surfaces are shaded.
/// Its presence means caustic photons, which bind set 1 (a refractor map, or nothing for a
/// mirror).
pub const CAUSTIC_DISTANCES: Slot =
    Slot { shading: true, needs_sets: true, ..Slot::image("caustics.receivers", 0, binding::CAUSTIC_DISTANCES, Sampler::Nearest) };

/// Generators' light cube maps (filtered, when filtering), sampled where diffuse surfaces
/// are shaded (§6.3.3).
pub const CAUSTIC_MAPS: Slot = Slot { shading: true, ..Slot::image("caustics.light_cubes", 0, binding::CAUSTIC_MAPS, Sampler::Linear) };

/// The light cube maps before filtering (only with a filter).
pub const CAUSTIC_RAW: Slot = Slot::image("caustics.light_cubes.unfiltered", 0, binding::CAUSTIC_RAW, Sampler::Nearest);

/// Photon hit location images and the photons' power, one layer per light view.
pub const PHOTON_HITS: Slot = Slot::image("caustics.photon_hits", 0, binding::PHOTON_HITS, Sampler::Nearest);
pub const PHOTON_POWER: Slot = Slot::image("caustics.photon_power", 0, binding::PHOTON_POWER, Sampler::Nearest);

/// The caustics' parameters and cube table.
pub const CAUSTICS: Slot = Slot::buffer("caustics.generators", 0, binding::CAUSTICS);

/// Caustic triangles set up once, and per face which of them it draws.
pub const CAUSTIC_TRIANGLES: Slot = Slot::buffer("caustics.triangles", 0, binding::CAUSTIC_TRIANGLES);
pub const CAUSTIC_FACES: Slot = Slot::buffer("caustics.triangle_faces", 0, binding::CAUSTIC_FACES);

/// caustics=photon-map: the hashed grid and the photons sorted into it, read wherever diffuse
/// surfaces are shaded.
pub const PHOTON_GRID: Slot = Slot::buffer("caustics.photon_grid", 0, binding::PHOTON_GRID);
pub const PHOTON_LIST: Slot = Slot::buffer("caustics.photon_list", 0, binding::PHOTON_LIST);
pub const PHOTON_COARSE: Slot = Slot::buffer("caustics.photon_coarse", 0, binding::PHOTON_COARSE);

/// caustic_space=screen: the caustic's irradiance per camera pixel, read where the camera's
/// diffuse surfaces are shaded.
pub const CAUSTIC_SCREEN: Slot = Slot { shading: true, ..Slot::image("caustics.screen", 0, binding::CAUSTIC_SCREEN, Sampler::Nearest) };

/// caustic_space=texture (SKALP05): the receivers' atlas, their light map (read where the
/// camera's and the ray tracers' diffuse surfaces are shaded) and the receiver triangles seen
/// from each caustic cube's centre (the splats read them).
pub const CAUSTIC_ATLAS: Slot = Slot::buffer("caustics.atlas", 0, binding::CAUSTIC_ATLAS);
pub const CAUSTIC_LIGHT_MAP: Slot =
    Slot { shading: true, ..Slot::image("caustics.light_map", 0, binding::CAUSTIC_LIGHT_MAP, Sampler::Linear) };
pub const CAUSTIC_RECEIVER_IDS: Slot = Slot::image("caustics.receiver_ids", 0, binding::CAUSTIC_RECEIVER_IDS, Sampler::Nearest);

/// Where each caustic cube's photons went in its last record (caustics/reach.comp), read
/// back by the stage after the frame (`super::reach`).
pub const CAUSTIC_REACH: Slot = Slot::buffer("caustics.reach", 0, binding::CAUSTIC_REACH);

pub const SLOTS: &[Slot] = &[
    CAUSTIC_DISTANCES,
    CAUSTIC_MAPS,
    CAUSTIC_RAW,
    PHOTON_HITS,
    PHOTON_POWER,
    CAUSTICS,
    CAUSTIC_TRIANGLES,
    CAUSTIC_FACES,
    PHOTON_GRID,
    PHOTON_LIST,
    PHOTON_COARSE,
    CAUSTIC_SCREEN,
    CAUSTIC_ATLAS,
    CAUSTIC_LIGHT_MAP,
    CAUSTIC_RECEIVER_IDS,
    CAUSTIC_REACH,
];

impl crate::frame::maps::Maps {
    /// Caustics: the photon hit location images (xyz hit relative to the reference point,
    /// w > 0 for a photon, −1 for one that escaped) and the photons' power, one layer per light view.
    pub fn photon_images(&self) -> Option<(&crate::vk::Image, &crate::vk::Image)> {
        self.image(&PHOTON_HITS).zip(self.image(&PHOTON_POWER))
    }
}
