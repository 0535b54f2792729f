//! The budgeted planner (issue 15): per specular object a method, and for the frame one set
//! of knob values, chosen from per-object error and cost models so that the frame meets an
//! error floor (`--min-psnr`: every specular object's PSNR on its own pixels) at the least
//! predicted time, or a time budget (`--max-ms`) at the least predicted error.
//!
//! **Models** come from predictions (`plan::predict`: per object and method, error from the
//! object's facts, cost from the device's unit costs) or from a calibration run of the very
//! scene (`specula tradeoff --calibrate`): the study renders
//! every method × knob variant; per row, each specular object's PSNR on its own pixels (the
//! reference's object ids) and its share of the GPU time. A pass belongs to the objects whose
//! plan lists it (`ObjectPlan::passes`); a pass a stage records under the prefix its
//! camera pass declares (`Profiled::prefix`: a ray tracer's per-bounce kernels, planar
//! mirrors' views), to the objects of the camera stages that declare it; what belongs to
//! none is the frame's base (its own stages: direct light, shadow maps), and so is a frame
//! effect's (caustics: the same whatever methods the objects get). Map and camera
//! passes work per object (a layer, the object's pixels) and are split evenly among their
//! objects; a ray tracer's kernels run over the whole screen whatever it serves, so its
//! camera pass declares them *shared* (`Profiled::shared`): paid once per method a frame
//! uses; so is a map that is one map for all its objects (`MapInfo::shared`: the layered map
//! of the whole scene, whose peel costs the same for one layered object as for three; split
//! among them, a plan with fewer of them was predicted at a fraction of its peel: 2× under
//! on corpus scene 38's mirror torus). Each cost
//! has a fixed part (maps, shadow maps, photons: independent of the output size) and a screen
//! part, scaled by the pixel count when a frame's size differs from the calibration's.
//!
//! **Choice.** Knob values are global to a frame (one `Quality`), so a choice is one
//! calibrated knob variant and, per object, one method measured with it. Predicted frame ms =
//! base + Σ object shares + Σ shared kernels of the methods used, the maps' share scaled by
//! the frame's inter-object cycles over the calibration row's: objects of different methods
//! compose through cycles (survey §4.3; `plan_with` runs at least two where a map sees a
//! self-refracting object), which a study of whole-scene methods never ran. A choice that
//! gives every object the same method is planned as that whole-scene method, exactly what the
//! study measured. Object o's PSNR is the one measured with its method and variant (other
//! objects' methods change what o reflects only at second order); the specular pixels' PSNR
//! combines the objects' mean squared errors weighted by their pixel counts. The search is
//! exhaustive over the variants and the per-object candidates left after dropping the
//! dominated ones (slower and no more accurate), greedy past [`MAX_COMBINATIONS`].

// One job a file: the models and their storage; a frame's time split among its objects;
// the fit to a study; each object's candidates; the search; the choice; the prediction.
mod attribute;
mod candidates;
mod choose;
mod fit;
mod models;
pub mod prediction;
mod search;

pub use attribute::{attribute, measured_by_object, Cost};
pub use choose::{choose, choose_with};
pub use fit::{fit, Measured};
pub(crate) use models::{mse_of, psnr_of};
pub use models::{variant_quality, Models, ObjectModel, RowBase, VariantModel, FORMAT, PSNR_CAP};
pub use prediction::{report, Budget, FrameMeasured, ObjectMeasured, ObjectPrediction, Prediction};
pub use search::MAX_COMBINATIONS;
