// What ray tracing in distance maps (survey §4.1–4.4) shares with its shaders: its maps in
// the map set (set 1) and its push flags. Concatenated with the frame's declaration by
// build.rs (see src/frame/layout.in.rs).

gpu_consts! {
    /// `Push.flags` of `distance.search` only (`debug_fault=flip_reflection`, a test knob):
    /// the reflected ray is traced in the opposite direction.
    FLAG_DEBUG_FLIP_REFLECTION: uint = 16384;
    /// `Push.flags` of the hybrid camera passes (`hybrid=confirm`): every answer of the map
    /// confirmed by a ray query around its hit.
    FLAG_HYBRID_CONFIRM: uint = 32768;
    /// `Push.flags` of a hybrid camera pass's object that rays leaving it may meet again
    /// (`plan::facts::may_meet_itself`): they are traced against it first.
    FLAG_HYBRID_REENTERS: uint = 65536;
}

flag_bits! {
    own_passes 14..17 { FLAG_DEBUG_FLIP_REFLECTION, FLAG_HYBRID_CONFIRM, FLAG_HYBRID_REENTERS }
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

push_words! {
    /// Image-space refraction's exit-point refinement (§4.4).
    13..14 {
        /// Newton steps onto the back faces' depth (`image_space_iterations`)
        IMAGE_SPACE_ITERATIONS: uint,
    }

    /// The distance-map search (§4.1) that every search of a cube map runs (common/search.glsl:
    /// distance's, layered's, the caustics' photons), and self refraction's bounces (§4.4).
    2..8 {
        /// linear steps on the projected segment (0: parallax correction only)
        SEARCH_LINEAR_STEPS: uint,
        SEARCH_SECANT_STEPS: uint,
        SEARCH_BINARY_STEPS: uint,
        SEARCH_PARALLAX_ITERATIONS: uint,
        /// early exit when | |l|/|l'| − 1 | ≤ tolerance
        SEARCH_TOLERANCE: float,
        /// self refraction: total internal reflections followed (§4.4)
        INTERNAL_BOUNCES: uint,
    }
}
