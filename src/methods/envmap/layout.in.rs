// What environment mapping (survey §3) shares with its shaders: the cube maps binding and
// the push flags of its passes. Concatenated with the frame's declaration by build.rs
// (see src/frame/layout.in.rs).

gpu_consts! {
    /// Specular objects drawn into maps search their own (previous-cycle) distance maps (§4.3).
    FLAG_INTER_OBJECT: uint = 4;
    /// Proxy geometry of localised environment mapping (§3.2): box, else sphere.
    FLAG_PROXY_BOX: uint = 8;
    /// First inter-object cycle: no map holds anything yet, specular objects in maps are black
    /// (paths longer than the requested depth end black, as in the reference).
    FLAG_FIRST_CYCLE: uint = 16;
}

flag_bits! {
    /// The proxy on its camera draws; the inter-object cycles on the map generation's draws.
    own_passes 2..5 { FLAG_INTER_OBJECT, FLAG_PROXY_BOX, FLAG_FIRST_CYCLE }
}

descriptor_sets! {
    BINDINGS = set 0 {
        ENVMAPS = 8: COMBINED_IMAGE_SAMPLER => "uniform samplerCubeArray envmaps";
        /// image-based (§3.3): per object `captures`³ cube maps, radiance in rgb and the
        /// distance from the capture's centre in alpha; object o's capture k is layer
        /// `o.envmap_layer · captures³ + k`, centred at the eye of view
        /// `push_capture_view_base() + 6 · layer`.
        CAPTURES = 22: COMBINED_IMAGE_SAMPLER => "uniform samplerCubeArray captures";
        /// proxy-relief (§3.2, PMDS06): per object six height maps, one per face f of the
        /// scene's box (the cube faces' order): rgb the radiance, alpha the depth from the
        /// opposite face along the face's direction (`views[push_relief_view_base() + 6 ·
        /// o.envmap_layer + f]`: its orthographic view; eye.xyz on the opposite face, dir.xyz
        /// the direction) of what stands in front of face f, the object left out.
        RELIEF_MAPS = 23: COMBINED_IMAGE_SAMPLER => "uniform sampler2DArray relief_maps";
    }
}

push_words! {
    /// image-based reflections (§3.3) and displacement-mapped proxies (§3.2).
    8..13 {
        /// captures per axis of each object's lattice (`captures`)
        CAPTURES_PER_AXIS: uint,
        /// the view table's first capture view (the `envmap.captures` block)
        CAPTURE_VIEW_BASE: uint,
        /// how the captures combine (`capture_warp`): 0 warped by their distances, 1 blended
        CAPTURE_WARP: uint,
        /// the view table's first relief view (the `envmap.relief` block)
        RELIEF_VIEW_BASE: uint,
        /// linear steps of a ray's march through a height map (`relief_steps`)
        RELIEF_STEPS: uint,
    }
}
