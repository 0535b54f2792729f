// What caustics (survey §6) share with their shaders: the caustic cubes and parameters,
// their bindings in the frame's set 0, consts and push flags. Concatenated with the frame's
// declaration by build.rs (see src/frame/layout.in.rs).

gpu_structs! {
    /// One caustic cube (survey §6): a light cube map and its receiver distance map, cube
    /// `index` of `caustic_maps` and `caustic_distances`, around a centre: a generator's
    /// reference point (`caustic_space=cube`), or a light (`caustic_space=light`).
    struct GpuCausticCube => struct CausticCube {
        /// xyz: the centre; w: unused
        centre: vec4,
        /// the generator's mesh (its `objects` entry)
        mesh: uint,
        pad: [uint; 3],
    }

    /// What the caustic passes and the projection share (the header of `Caustics`).
    struct GpuCausticParams => struct CausticParams {
        /// cubes in `cubes` (0: the scene has no caustics)
        cube_count: uint,
        /// edge of the photon hit location images
        photon_size: uint,
        /// edge of each face of the light cube and receiver distance maps
        cube_size: uint,
        /// CAUSTIC_* flags
        flags: uint,
        /// photon splatting: the splat's radius in light-cube texels
        splat_size: float,
        /// box filter radius in texels
        filter_radius: uint,
        /// caustic triangles: triangles of every photon layer (`caustic_faces` holds six
        /// flags of each)
        triangle_count: uint,
        /// caustic triangles: triangles per photon layer, 2 (photon_size − 1)²
        layer_triangles: uint,
        /// caustic_paths=exact: rays leave a surface this far along (10⁻⁶ of the scene's
        /// diagonal, as the ray tracers' secondary rays)
        ray_offset: float,
        /// caustics=photon-map: photons gathered per shaded point (photon_k)
        gather_k: uint,
        /// caustics=photon-map: buckets of the hashed grid's two levels, a power of two
        /// (`photon_grid` holds each bucket's first place and count among the fine cells, then
        /// among the coarse ones)
        grid_cells: uint,
        /// caustics=photon-map: the gather's largest radius (world units): the grid's fine
        /// cells are a quarter, its coarse cells twice as wide
        gather_radius: float,
        /// caustic_space=screen: the camera target's size (pixels)
        screen_width: uint,
        screen_height: uint,
        /// caustic_paths=exact through graded media: the most a photon turns per RK4 step
        /// [rad] (the medium_turn knob)
        medium_turn: float,
        /// caustic_space=texture: `vec4`s of `caustic_atlas` before its triangles (four a mesh)
        atlas_meshes: uint,
        /// caustic_space=texture: edge of the light map (texels)
        light_map_size: uint,
        /// caustic_paths=exact: the specular surfaces a photon passes after its generator
        /// before it is given up (the depth knob, as the reference's photons)
        exact_bounces: uint,
        pad: [uint; 2],
    }
}

gpu_consts! {
    /// `Push.flags` of the camera's `scene.direct`: the caustics are projected by their own
    /// pass (`caustics.project`), not inside `shade_diffuse`.
    FLAG_CAUSTICS_APART: uint = 128;

    /// `CausticParams.flags`: the projection's distance test (§6.3.3).
    CAUSTIC_DISTANCE_TEST: uint = 1;
    /// `CausticParams.flags`: the receiver-orientation factor cos α of the projection.
    CAUSTIC_ORIENTATION: uint = 2;
    /// `CausticParams.flags`: caustics=photon-map: diffuse points gather from the photon grid
    /// instead of projecting light cube maps.
    CAUSTIC_PHOTON_MAP: uint = 4;
    /// `CausticParams.flags`: caustic_space=screen: the camera's own diffuse surfaces take the
    /// caustic from `caustic_screen` at their pixel; every other view, none.
    CAUSTIC_SCREEN_SPACE: uint = 8;
    /// `CausticParams.flags`: caustic_paths=surface (§6.4): a solid generator's photons go
    /// from their refraction at its surface straight to the receivers.
    CAUSTIC_SURFACE_PATHS: uint = 16;
    /// `CausticParams.flags`: caustic_space=texture (SKALP05): photons land in the receivers'
    /// light map; the camera's diffuse surfaces and the ray tracers' diffuse hits read it.
    CAUSTIC_TEXTURE_SPACE: uint = 32;
    /// `Push.flags` of the photon pass: the caustic cube's index `(flags >> CAUSTIC_CUBE_SHIFT)
    /// & 0xff` and the light's `flags >> CAUSTIC_LIGHT_SHIFT`.
    CAUSTIC_CUBE_SHIFT: uint = 8;
    /// `Push.flags` of the photon pass: this layer's branch `(flags >> CAUSTIC_BRANCH_SHIFT) &
    /// 0xf` at a dielectric generator: 0 refracted in (and out), 1 reflected at its surface,
    /// k ≥ 2 (caustic_paths=exact) refracted in, k − 1 internal reflections, refracted out.
    CAUSTIC_BRANCH_SHIFT: uint = 16;
    CAUSTIC_LIGHT_SHIFT: uint = 20;
    /// Caustic triangles whose corners' distances from the reference point differ by more
    /// than this fraction land on different surfaces (§6.3.2) and are dropped.
    CAUSTIC_GAP: float = 0.1;
    /// caustic_space=texture: the largest splat radius in light-map texels (the atlas's
    /// charts lie this far apart and two texels more).
    TEXTURE_SPLAT_MAX: float = 8.0;
}

flag_bits! {
    /// `scene.direct` is the frame's pass: the caustics' flag there is frame-wide.
    every_pass 7..8 { FLAG_CAUSTICS_APART }
    /// The photon pass's cube, branch and light.
    own_passes 8..32 { CAUSTIC_CUBE_SHIFT: 8, CAUSTIC_BRANCH_SHIFT: 4, CAUSTIC_LIGHT_SHIFT: 12 }
}

descriptor_sets! {
    BINDINGS = set 0 {
        /// Caustics (§6): per caustic cube, the distance of the nearest receiver (everything but
        /// the generator) from its centre, the terminal hits' search map and the projection's
        /// distance test.
        CAUSTIC_DISTANCES = 10: COMBINED_IMAGE_SAMPLER => "uniform samplerCubeArray caustic_distances";
        /// Caustics: per caustic cube, the light cube map: radiant intensity J (W/sr) of the
        /// caustic as seen from its centre, the projection's input.
        CAUSTIC_MAPS = 11: COMBINED_IMAGE_SAMPLER => "uniform samplerCubeArray caustic_maps";
        /// Caustics: photon hit location images, one layer per light view of a generator:
        /// xyz the hit relative to its cube's centre, w in (0, 1] for a photon (1/(1 + its
        /// last segment's length); more than 1.5: an exact hit's code), −1 with xyz its
        /// direction for one that escaped the receivers, 0 for none.
        PHOTON_HITS = 12: COMBINED_IMAGE_SAMPLER => "uniform sampler2DArray photon_hits";
        /// Caustics: the photons' power (rgb, W).
        PHOTON_POWER = 13: COMBINED_IMAGE_SAMPLER => "uniform sampler2DArray photon_power";
        CAUSTICS = 14: STORAGE_BUFFER => "readonly buffer Caustics { CausticParams caustic; CausticCube cubes[]; }";
        /// Caustics: the light cube maps before filtering (the filter pass reads them).
        CAUSTIC_RAW = 15: COMBINED_IMAGE_SAMPLER => "uniform samplerCubeArray caustic_raw";
        /// Caustic triangles, set up once (caustics/setup.comp): per triangle of a photon layer
        /// four vec4: its corners relative to the cube's centre with J's r, g, b in w, and
        /// (1: a tent around the centroid, 0: the triangle itself).
        CAUSTIC_TRIANGLES = 16: STORAGE_BUFFER => "buffer CausticTriangles { vec4 caustic_triangles[]; }";
        /// Caustic triangles: per cube face f and triangle i, `caustic_faces[f · triangle_count
        /// + i]` is 1 when the face draws it (its frustum may hold it).
        CAUSTIC_FACES = 17: STORAGE_BUFFER => "buffer CausticFaces { uint caustic_faces[]; }";
        /// caustics=photon-map: the hashed uniform grid, two levels of `grid_cells` buckets: the
        /// fine cells' first places in `photon_list` and counts, then the coarse cells' first
        /// places in `photon_coarse` and counts (caustics/grid.comp builds it every frame;
        /// glsl/caustics/photon_map.glsl).
        PHOTON_GRID = 18: STORAGE_BUFFER => "buffer PhotonGrid { uint photon_grid[]; }";
        /// caustics=photon-map: the photons sorted by bucket, two vec4 each: the world position
        /// with the power's r, then g, b, and the arrival direction (octahedral, 12 bits a
        /// coordinate, `photon_direction`).
        PHOTON_LIST = 19: STORAGE_BUFFER => "buffer PhotonList { vec4 photon_list[]; }";
        /// caustics=photon-map: the photons' places in `photon_list`, sorted by coarse bucket.
        PHOTON_COARSE = 20: STORAGE_BUFFER => "buffer PhotonCoarse { uint photon_coarse[]; }";
        /// caustic_space=screen: the caustic's irradiance per pixel of the camera target, per
        /// unit area across the view (caustics.screen splats the photons there).
        CAUSTIC_SCREEN = 21: COMBINED_IMAGE_SAMPLER => "uniform sampler2D caustic_screen";
        /// caustic_space=texture: the receivers' light-map atlas (src/methods/caustics/atlas.rs):
        /// per mesh four vec4 (world-to-object rows, then its first triangle's index as bits,
        /// its texel's world area, 1 for a receiver), then per triangle of the scene's list four
        /// (the rows to light-map coordinates, its chart's rectangle, the chart's object-space
        /// normal with the mesh's index as bits).
        CAUSTIC_ATLAS = 24: STORAGE_BUFFER => "readonly buffer CausticAtlas { vec4 caustic_atlas[]; }";
        /// caustic_space=texture: the light map, irradiance (W/m², rgb) per texel of the
        /// receivers' charts; a: the signed luminance, + for photons on the chart's front.
        CAUSTIC_LIGHT_MAP = 25: COMBINED_IMAGE_SAMPLER => "uniform sampler2D caustic_light_map";
        /// caustic_space=texture: per caustic cube, the receiver triangle (its index in the
        /// scene's list + 1, as a float; 0 or FAR: none) in each direction from its centre.
        CAUSTIC_RECEIVER_IDS = 26: COMBINED_IMAGE_SAMPLER => "uniform samplerCubeArray caustic_receiver_ids";
        /// Caustics: where each caustic cube's photons went in its last record (issue 33 item
        /// 4; caustics/reach.comp), eight words a cube: the terminal hits' world bounds (min xyz,
        /// max xyz, as order-preserving uints: `reach_key`), 1 if a photon escaped the receivers,
        /// the photons that landed. Read back by the stage to decide which generators a later
        /// change reaches.
        CAUSTIC_REACH = 28: STORAGE_BUFFER => "buffer CausticReach { uint caustic_reach[]; }";
    }
}
