//! The envmap family's own knobs (its cube maps' are `CubeKnobs`).

use crate::quality::knob::knobs;

knobs! {
    /// Localised environment mapping (§3.2: proxies, displacement-mapped proxies) and image-based reflections (§3.3).
    pub struct EnvmapKnobs {
        /// proxy-sphere radius (§3.2); auto: mean half-extent of the scene's box
        proxy_radius: Option<f32> = auto, auto_metres();
        /// image-based (§3.3): captures per axis of the lattice of cube maps (radiance and distance) each object's rays are
        /// reconstructed from: 1, 8, 27 or 64 cube maps an object, at the centres of the lattice's cells in capture_box
        captures: u32 = 2, count(1..=4, "per axis");
        /// image-based: where the captures lie: in the object's bounding box, following it as it moves (`object`), or in the
        /// scene's box (`room`): fixed in the world, the engine practice of probes that objects move between, redrawn only when
        /// something they see changes (the object itself is not in its own captures); a capture inside another object is moved
        /// towards its box's centre until it is clear
        capture_box: CaptureBox = "object", one_of()["object" => CaptureBox::Object, "room" => CaptureBox::Room];
        /// image-based: how the captures around the shaded point (its lattice cell's corners, trilinear weights) give a ray's
        /// radiance: `depth` warps each by its distances (the ray searched in each capture's distance map, §4.1; captures whose
        /// hit is not a surface they hold, or lies beyond the nearest hit any of them holds, are left out, the rest blended),
        /// `blend` blends the captures' radiance looked up towards where the ray leaves the scene's box (several
        /// parallax-corrected cube maps blended by position, as engines blend their reflection probes)
        capture_warp: CaptureWarp = "depth", one_of()["depth" => CaptureWarp::Depth, "blend" => CaptureWarp::Blend];
        /// proxy-relief (§3.2, PMDS06): edge of each of the six height maps per object (one per face of the scene's box: what
        /// stands in front of that face, rasterised orthographically from the opposite face: radiance and height)
        relief_size: u32 = 256, count(16..=4096, "texels");
        /// proxy-relief: linear steps of each ray's march through a height map (then 8 halvings)
        relief_steps: u32 = 32, count(1..=256);
        /// proxy-relief: where the height maps come from: rasterised orthographically from each face's opposite face
        /// (`raster`: what stands in front of the face, whatever the object's reference point sees) or sampled from the
        /// object's distance map (`distance`: per texel the distance-map search along the face's direction, §4.1; only what
        /// the reference point sees, as PMDS06 and the survey describe it)
        relief_source: ReliefSource = "raster", one_of()["raster" => ReliefSource::Raster, "distance" => ReliefSource::Distance];
    }
}

/// Where image-based reflections' captures lie (`capture_box`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum CaptureBox {
    /// A lattice over the object's bounding box, moving with it.
    Object,
    /// A lattice over the scene's box, fixed in the world.
    Room,
}

/// How image-based reflections combine their captures (`capture_warp`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum CaptureWarp {
    /// Per-pixel depth warping: the ray searched in each capture's distance map.
    Depth,
    /// Position-weighted blend of parallax-corrected lookups (proxy: the scene's box).
    Blend,
}

/// Where displacement-mapped proxies' height maps come from (`relief_source`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum ReliefSource {
    /// Rasterised orthographically from the opposite face.
    Raster,
    /// Sampled from the object's distance map by a search per texel.
    Distance,
}
