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
    }
}
