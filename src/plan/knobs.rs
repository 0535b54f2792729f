//! The planner's knob.

use crate::quality::knob::knobs;

knobs! {
    /// What `--method auto` optimises.
    pub struct PlanKnobs {
        /// what --method auto optimises: within the exact tracer's predicted frame time, the fastest choice predicted within
        /// 0.5 dB (accuracy) or 3 dB (speed) of the most accurate one
        planner: Planner = "accuracy", one_of()["accuracy" => Planner::Accuracy, "speed" => Planner::Speed];
    }
}

/// What `--method auto` optimises when it picks a method per object.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Planner {
    /// The fastest choice within `predict::TOLERANCE_DB` of the most accurate.
    Accuracy,
    /// The fastest choice within `predict::SPEED_TOLERANCE_DB` of the most accurate.
    Speed,
}
