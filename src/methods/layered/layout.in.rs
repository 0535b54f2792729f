// What layered distance maps (survey §4.5) share with their shaders: their maps in the map
// set (set 1), the consts of the peel and trace, and their push flags. Concatenated with the
// frame's declaration by build.rs (see src/frame/layout.in.rs).

gpu_consts! {
    /// `Push.flags` of `layered.peel` (§4.5): the first layer (nothing to peel against).
    LAYERED_FIRST: uint = 256;
    /// `Push.flags` of `layered.peel` in six-pass mode: the cube face `(flags >>
    /// LAYERED_FACE_SHIFT) & 7` (multiview adds gl_ViewIndex).
    LAYERED_FACE_SHIFT: uint = 9;
    /// Depth peeling keeps a fragment when its window depth is below the previous layer's
    /// by more than this fraction (reversed-Z depth is relative: 1 km and 1 mm alike).
    LAYERED_PEEL_EPSILON: float = 0.00001;
    /// A crossing of a layer's surface found by the search is a hit only if the ray meets
    /// the surface there within this fraction of the distance (else it is the gap between
    /// two surfaces of one layer, and the search goes on).
    LAYERED_GAP: float = 0.05;
    /// Rays the layered trace keeps pending (both Fresnel branches while there is room).
    LAYERED_STACK: uint = 8;
    /// `Push.flags`: a dielectric hit in the layered maps follows only its stronger Fresnel
    /// branch (`layered_branches=strongest`).
    FLAG_LAYERED_STRONGEST: uint = 64;
}

flag_bits! {
    /// The branch choice is frame-wide: every pass that traces the layered maps reads it.
    every_pass 6..7 { FLAG_LAYERED_STRONGEST }
    /// `layered.peel`'s first layer and cube face.
    own_passes 8..12 { LAYERED_FIRST, LAYERED_FACE_SHIFT: 3 }
}

descriptor_sets! {
    MAP_BINDINGS = set 1 {
        /// Layered distance maps (§4.5), one cube per layer around the map's reference
        /// point: rgb the reflected radiance of a diffuse surface, a its distance (1e30:
        /// nothing in this layer).
        LAYERED_MAPS = 4: COMBINED_IMAGE_SAMPLER => "uniform samplerCubeArray layered_maps";
        /// Layered maps: xyz the surface normal, w 0 for a diffuse surface, else the specular
        /// material's index + 1.
        LAYERED_NORMALS = 5: COMBINED_IMAGE_SAMPLER => "uniform samplerCubeArray layered_normals";
        /// `layered.peel`: the previous layer's depth, six faces (only the peel's own sets).
        LAYERED_PREVIOUS = 6: COMBINED_IMAGE_SAMPLER => "uniform sampler2DArray layered_previous";
    }
    BINDINGS = set 0 {
        /// Layered maps (§4.5) cut short of the depth complexity: per mesh, the pixels whose
        /// path met a surface in the farthest layer (the fallback past the peeled layers;
        /// `layered.far_layer_pixels`), zeroed every frame. Only where the peel is cut.
        LAYERED_FAR = 29: STORAGE_BUFFER => "buffer LayeredFar { uint layered_far[]; }";
    }
}
