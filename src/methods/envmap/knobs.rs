//! The envmap family's own knob (its cube maps' are `CubeKnobs`).

use crate::quality::knob::knobs;

knobs! {
    /// Localised environment mapping (§3.2).
    pub struct EnvmapKnobs {
        /// proxy-sphere radius (§3.2); auto: mean half-extent of the scene's box
        proxy_radius: Option<f32> = auto, auto_metres();
    }
}
