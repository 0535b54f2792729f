//! The CPU reference's knobs.

use crate::quality::knob::knobs;

knobs! {
    /// The CPU reference.
    pub struct ReferenceKnobs {
        /// reference: samples per pixel on a k×k stratified grid (a perfect square; 1 = pixel centre)
        spp: u32 = 16, square(..=1024);
        /// CPU reference: photons traced from each punctual light into each caustic generator's bounding cone for its caustics
        reference_photons: u32 = 1000000, count(1000..=100000000, "photons");
        /// CPU reference: radius of the caustics' density estimate on the receivers (Epanechnikov kernel); auto: 0.5 % of the
        /// scene's bounding-box diagonal
        caustic_radius: Option<f32> = auto, auto_metres();
    }
}
