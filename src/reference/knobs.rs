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
        /// scene's bounding-box diagonal (caustic_estimate=progressive: each hit point's first radius holds 16 of the first
        /// pass's photons, at most that)
        caustic_radius: Option<f32> = auto, auto_metres();
        /// CPU reference: the caustics' density estimate: one photon map with the fixed caustic_radius kernel, or progressive photon mapping (Hachisuka et al. 2008: reference_photons split into ppm_passes passes, each camera hit point's radius shrinking from caustic_radius as photons arrive, α 0.7), which converges to the sharp caustic
        caustic_estimate: CausticEstimate = "progressive", one_of()["kernel" => CausticEstimate::Kernel, "progressive" => CausticEstimate::Progressive];
        /// CPU reference, caustic_estimate=progressive: photon passes (each of reference_photons / ppm_passes photons per light and generator)
        ppm_passes: u32 = 16, count(1..=4096, "passes");
    }
}

/// How the reference estimates caustic irradiance (issue 34).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum CausticEstimate {
    /// One photon map, a fixed Epanechnikov kernel of `caustic_radius`: biased (blurred).
    Kernel,
    /// Progressive photon mapping: consistent, the error falls as photons grow.
    Progressive,
}
