//! The planner's knob.

use crate::quality::knob::knobs;

knobs! {
    /// What `--method auto` optimises.
    pub struct PlanKnobs {
        /// what --method auto optimises: the most accurate method per object, or a cheaper rung (single distance maps, image-space
        /// refraction)
        planner: Planner = "accuracy", one_of()["accuracy" => Planner::Accuracy, "speed" => Planner::Speed];
    }
}

/// What `--method auto` optimises when it picks a method per object.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Planner {
    /// The most accurate method that serves the object.
    Accuracy,
    /// A cheaper rung: single distance maps for mirrors, image-space refraction for solids.
    Speed,
}
