// What ray tracing in distance maps (survey §4.1–4.4) shares with its shaders: its maps in
// the map set (set 1) and its push flags. Concatenated with the frame's declaration by
// build.rs (see src/frame/layout.in.rs).

gpu_consts! {
    /// `Push.flags` of `distance.search` only (`debug_fault=flip_reflection`, a test knob):
    /// the reflected ray is traced in the opposite direction.
    FLAG_DEBUG_FLIP_REFLECTION: uint = 16384;
}

flag_bits! {
    own_passes 14..15 { FLAG_DEBUG_FLIP_REFLECTION }
}

descriptor_sets! {
    MAP_BINDINGS = set 1 {
        /// rgb radiance, a distance
        DISTANCE_MAPS = 0: COMBINED_IMAGE_SAMPLER => "uniform samplerCubeArray distance_maps";
        /// xyz normal, w distance
        REFRACTOR_MAPS = 1: COMBINED_IMAGE_SAMPLER => "uniform samplerCubeArray refractor_maps";
        /// xyz normal, w distance from the eye
        BACKFACE_MAP = 2: COMBINED_IMAGE_SAMPLER => "uniform sampler2D backface_map";
        /// Per-vertex distance through the object along the inverted normal (d_N), read by
        /// distance/image_space/refract.vert.
        THICKNESS = 3: STORAGE_BUFFER => "readonly buffer Thickness { float thickness[]; }";
    }
}
