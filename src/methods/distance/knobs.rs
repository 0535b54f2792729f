//! The distance family's knobs: the distance-map search (§4.1, shared with layered and
//! caustics), inter-object cycles (§4.3) and self refraction (§4.4).

use crate::quality::knob::knobs;

knobs! {
    /// The distance-map search (§4.1).
    pub struct SearchKnobs {
        /// distance-map linear search steps (§4.1.2); 0: parallax correction only
        linear_steps: u32 = 16, count(0..=256);
        /// secant (false position) refinement steps after the linear search (survey eq. 5)
        secant_steps: u32 = 2, count(0..=64);
        /// binary refinement steps after the linear search (§4.1.4)
        binary_steps: u32 = 0, count(0..=64);
        /// parallax-correction iterations (survey eq. 4) when linear_steps = 0
        parallax_iterations: u32 = 1, count(1..=64);
        /// search stops once ‖l‖/‖l′‖ is within this of 1
        search_tolerance: f32 = 0.001, real(0..=1);
    }
}

knobs! {
    /// Inter-object reflections (§4.3) and self refraction (§4.4).
    pub struct DistanceKnobs {
        /// distance-multi: distance-map generation cycles per frame (§4.3); cycle k shows k specular bounces in the maps
        cycles: u32 = 4, count(1..=16, "cycles");
        /// refractor-map: total internal reflections followed inside a refractor (§4.4); with `hybrid`, the budget of
        /// interfaces a path meets is internal_bounces + 2 as the exact tracers count `depth` (the camera's hit, each surface
        /// inside, each meeting from outside), shared by the paths that leave a non-convex refractor and come back in
        internal_bounces: u32 = 2, count(0..=16);
        /// distance-multi: one map cycle per frame reusing the previous frame's maps (§4.3)
        frame_latency: bool = "off", one_of()["on" => true, "off" => false];
        /// distance, distance-multi, refractor-map: the camera pass's searches that the map cannot answer (escaped, or a hit the
        /// map does not hold: a gap behind a silhouette, beyond the search's tolerance; inside a refractor too) are traced through
        /// Vulkan ray queries and their hits shaded (`rays`; needs a device with ray queries), or left to the map (`off`); `confirm`
        /// also checks every answer the map gives by a ray query from the ray's start to 1 % of its distance past the map's hit
        /// (the hit bounds the query; a face hidden from the reference point before it is found too) and shades the triangle it
        /// meets (exact geometry, normal and texture), tracing the whole ray where that segment holds none
        hybrid: Hybrid = "off", one_of()["off" => Hybrid::Off, "rays" => Hybrid::Rays, "confirm" => Hybrid::Confirm];
        /// image-space-refraction (§4.4): Newton steps that move Wyman's estimated exit point along the refracted ray onto the back
        /// faces' depth where it projects (beyond the paper, whose interpolated distance is far off near the silhouette: a
        /// sphere's chord 1.49 r estimated 1.06 r); 0: the paper's estimate alone
        image_space_iterations: u32 = 0, count(0..=8, "iterations");
    }
}

/// What the distance-map camera passes do where their maps cannot answer (`hybrid`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Hybrid {
    /// The map's answer, whatever it is.
    Off,
    /// A ray query where the search cannot answer; the map's radiance where it can.
    Rays,
    /// As `Rays`, and every answer of the map confirmed by a ray query bounded by its hit
    /// (from the ray's start to just past it), whose triangle is shaded.
    Confirm,
}

impl Hybrid {
    /// The camera passes fire ray queries.
    pub fn traces(self) -> bool {
        self != Hybrid::Off
    }
}
