//! Cube-map knobs, shared by the families that render objects' cube maps (envmap,
//! distance, layered, caustics): none of them owns these.

use glam::Vec3;

use crate::quality::knob::knobs;

knobs! {
    /// Cube maps around each specular object's reference point.
    pub struct CubeKnobs {
        /// edge of each face of an object's cube maps (environment, distance, refractor)
        cube_size: u32 = 256, count(16..=4096, "texels");
        /// cube-map storage (radiance and distance): RGBA16F or RGBA32F
        cube_precision: Precision = "half", one_of()["half" => Precision::Half, "single" => Precision::Single];
        /// cube faces in six passes or one multiview pass (equal speed on lavapipe, six needs less depth memory: BENCHMARKS.md;
        /// lavapipe before Mesa 25 puts large clipped triangles on wrong faces with multiview: use six there; Mesa 25.0.7 renders both bit for bit alike); the caustics' cubes always take six
        /// passes
        cube_mode: CubeMode = "six", one_of()["six" => CubeMode::SixPasses, "multiview" => CubeMode::Multiview];
        /// reference point of every specular object's maps; auto = its bounding-box centre, moved when that lies inside or next to
        /// another object
        ref_point: Option<Vec3> = auto, auto_point("metres");
    }
}

/// How the six faces of a cube map are rasterised.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum CubeMode {
    /// One render pass per face.
    SixPasses,
    /// All six faces in one pass with multiview (view mask 0x3F).
    Multiview,
}

/// Storage precision of radiance cube maps.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Precision {
    Half,
    Single,
}
