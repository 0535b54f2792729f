//! When the frame records its passes and what their output depends on: plain data that the
//! plan (`plan::types`) and the stages (`frame::stage`) both read, importing nothing.

/// Positions of the frame's passes: a plan's stages are recorded in this order.
pub mod order {
    pub const UPLOAD: u32 = 0;
    pub const SHADOWS: u32 = 10;
    /// Maps that depend on geometry alone (refractor maps): before the radiance maps, whose
    /// generation may search them.
    pub const GEOMETRY_MAPS: u32 = 15;
    /// Caustics (§6): after the refractor maps their photons search, before every pass
    /// that shades diffuse surfaces (which projects them).
    pub const CAUSTICS: u32 = 17;
    pub const ENVIRONMENT_MAPS: u32 = 20;
    pub const DIRECT: u32 = 30;
    /// The caustics' projection onto the camera's diffuse surfaces, over `scene.direct`.
    pub const CAUSTICS_PROJECT: u32 = 35;
    /// Camera-space maps (image-space refraction's back faces).
    pub const CAMERA_MAPS: u32 = 40;
    pub const CAMERA: u32 = 50;
    /// Ray tracing in the original geometry: last, since it replaces its objects' pixels
    /// by what its own visibility pass found nearest (other camera passes draw over
    /// depth it does not write).
    pub const RAYTRACE: u32 = 60;
}

/// What a stage's output depends on, so that a frame records it only when that changed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Deps {
    /// The camera's view (direct light, camera passes, ray tracing): every frame.
    EveryFrame,
    /// Shadow maps: the geometry and the lights (not materials, not the camera).
    Shadows,
    /// Maps of the geometry alone (refractor maps): what moved.
    Geometry,
    /// A light effect of some objects (caustics, §6): the geometry, the lights and the
    /// materials of the stage's own objects (the receivers' albedo is applied when they are
    /// shaded).
    LitObjects,
    /// A light effect in the camera's view (caustic_space=screen): as `LitObjects`, and the
    /// camera.
    LitView,
    /// Maps around objects (environment, distance, refractor): everything they see, which
    /// is the whole scene's geometry, materials and lights, but not the camera.
    World,
    /// Maps from the camera (image-space refraction's back faces): camera and geometry.
    CameraMap,
}

impl Deps {
    /// Whether the stage is recorded again for every camera view (the camera's, a planar
    /// mirror's).
    pub fn per_view(self) -> bool {
        matches!(self, Deps::EveryFrame | Deps::CameraMap)
    }
}

/// The fields of `Object` (`GpuObject`, src/frame/layout.in.rs) that index map arrays.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LayerField {
    /// `envmap_layer`: the radiance (set 0, binding 8) or distance (set 1, binding 0) cubes.
    Envmap,
    /// `refractor_layer`: the refractor maps (set 1, binding 1).
    Refractor,
    /// `shown_layer`: the distance cube composition gives an object whose own maps are not
    /// that cube (image-based captures, relief height maps), for how it shows in the others'.
    Shown,
}
