//! The planner's knob.

use crate::quality::knob::knobs;

knobs! {
    /// What `--method auto` optimises.
    pub struct PlanKnobs {
        /// what --method auto optimises: within the exact tracer's predicted frame time, the fastest choice predicted within
        /// 0.5 dB (accuracy) or 3 dB (speed) of the most accurate one
        planner: Planner = "accuracy", one_of()["accuracy" => Planner::Accuracy, "speed" => Planner::Speed];
        /// when objects or the camera move, auto keeps its per-object choices unless the new ones are predicted better by
        /// more than 1 dB or 20 % faster (on); off: every move re-chooses as a fresh plan would, so a frame equals a
        /// fresh context's, at the price of choices that may flicker between frames
        plan_hysteresis: bool = "on", one_of()["on" => true, "off" => false];
        /// whether --method auto may also choose frame knobs that are left at their defaults (cube_size 128/512, aa msaa4/ssaa2)
        /// when they are predicted to give a better image within its time (choose), or keeps every knob as asked (keep)
        plan_knobs: bool = "choose", one_of()["choose" => true, "keep" => false];
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
