//! Layered distance maps' knobs (§4.5).

use crate::quality::knob::{count_hi, knobs};

knobs! {
    /// Layered distance maps (§4.5).
    pub struct LayeredKnobs {
        /// layered maps (§4.5): depth-peeled layers; auto = the scene's depth complexity from the map's reference point, measured
        /// on the GPU (at most 16)
        layers: Option<u32> = auto, auto_count(1..=16);
        /// layered maps: a dielectric hit follows both Fresnel branches while the shader's ray stack (8 rays) has room, else the
        /// stronger one carrying both weights; strongest: always the stronger one
        layered_both as layered_branches: bool = "both", one_of()["both" => true, "strongest" => false];
    }
}

/// The most layers a layered distance map (§4.5) peels: the `layers` knob's bound.
pub const MAX_LAYERS: u32 = count_hi(LayeredKnobs::KNOBS, LayeredKnobs::layers);
