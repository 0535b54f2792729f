//! The exact CPU reference (`crate::reference`) as the registry's last family: one CPU
//! method, no hooks. Declared here, beside the GPU families, so that the reference itself
//! (which the planner's probe runs) imports nothing of the registry.

use crate::quality::{CausticsKnobs, FrameKnobs, ReferenceKnobs};

/// The reference as the registry's last family: one CPU method, no hooks.
pub const FAMILY: super::registry::Family = super::registry::Family {
    name: "reference",
    methods: &[REFERENCE_INFO],
    // Its rays curve through graded media (scene::medium, at its own fine turn).
    curved_rays: &[REFERENCE],
    ..super::registry::Family::NONE
};

/// The exact CPU reference as a registered method: it has no GPU passes (`Renderer::new`
/// refuses its plan); `crate::reference::render_reference` renders it.
pub const REFERENCE_INFO: &super::registry::MethodInfo = &super::registry::MethodInfo {
    name: "reference",
    abi: 99,
    section: "§2, Table 1",
    family: "reference",
    summary: "the exact CPU reference (f64, SAH BVH, Möller–Trumbore): Whitted recursion through both the reflected and the refracted branch weighted by Fresnel, up to `depth` bounces, the GPU's non-specular shading with exact shadow rays, `spp` stratified samples per pixel, both cores (rayon). Ground truth for the tests and `specula tradeoff`",
    serves: super::registry::EVERY_CLASS,
    knobs: &[
        FrameKnobs::depth,
        ReferenceKnobs::spp,
        FrameKnobs::fresnel,
        CausticsKnobs::caustics,
        ReferenceKnobs::reference_photons,
        ReferenceKnobs::caustic_radius,
        ReferenceKnobs::caustic_estimate,
        ReferenceKnobs::ppm_passes,
    ],
    gpu: None,
    fallback: None,
    shape: super::registry::Shape::Any,
    needs: super::registry::DeviceNeeds::Nothing,
};
pub const REFERENCE: super::registry::Method = super::registry::Method(REFERENCE_INFO.name);
