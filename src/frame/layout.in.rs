// What the frame shares with its shaders: the std430 structs of the scene (views,
// materials, objects, lights), the push-constant block, the consts and push flags every pass
// may read, and the frame's descriptor sets. Each method family declares its own part beside
// its code (src/methods/<family>/layout.in.rs); build/layout.rs concatenates the files
// (a family may add bindings to a set declared here), checks that std430 and `repr(C)` lay
// every field out at the same offset, and writes the Rust twin (`$OUT_DIR/layout.rs`, which
// src/frame/layout.rs includes) and the GLSL twin (`$OUT_DIR/glsl/generated/layout.glsl`,
// included by glsl/common/scene.glsl). Field types are GLSL's (`[T; N]` is an array; a struct
// is named by its Rust name); doc comments go to both sides.

gpu_structs! {
    /// std430 twin of `View`: one camera, cube face or shadow view.
    struct GpuView => struct View {
        /// world -> clip (reversed-Z, Vulkan y-down)
        view_proj: mat4,
        /// clip -> world, for the sky
        inv_view_proj: mat4,
        /// xyz: eye or reference point; w: 0 radial distance, 1 planar distance
        eye: vec4,
        /// xyz: direction for planar distance (directional shadow maps); w: a planar
        /// mirror's view: how far beyond its plane `clip` lies
        dir: vec4,
        /// World-space plane (n, w) a camera view keeps the side n·p + w ≥ 0 of: a planar
        /// mirror's view (survey §5) sees only what lies in front of its mirror; (0, 0, 0, 1)
        /// elsewhere. Its rasterisation clips there by an oblique near plane in `view_proj`.
        clip: vec4,
    }

    /// std430 twin of `Material`.
    struct GpuMaterial => struct Material {
        /// rgb linear albedo, a: unused
        base_color: vec4,
        /// rgb emitted radiance
        emissive: vec4,
        /// mirror: ν per rgb; dielectric: the ior per rgb (all three the same but under
        /// KHR_materials_dispersion; y is glTF's `ior`, the d line's)
        nu: vec4,
        /// mirror: κ per rgb
        kappa: vec4,
        /// rgb KHR_materials_specular colour, a factor
        specular: vec4,
        /// KIND_*
        kind: uint,
        /// -1: none
        base_texture: int,
        emissive_texture: int,
        /// dielectric: thin-walled
        thin: uint,
        /// rgb: a solid dielectric's absorption coefficient σ [1/m] (KHR_materials_volume,
        /// Beer–Lambert inside); zero elsewhere. a: unused
        absorption: vec4,
        /// A solid dielectric whose index varies (survey §6.5, src/scene/medium.rs): xyz the
        /// field's origin, w 1 (0: a uniform index, the rest unused)
        medium_origin: vec4,
        /// xyz the field's gradient at the origin [1/m], w ‖H‖ (Frobenius)
        medium_gradient: vec4,
        /// the Hessian H [1/m²]: xx, yy, zz, xy
        medium_hessian: vec4,
        /// xz, yz; zw unused
        medium_hessian2: vec4,
    }

    /// std430 twin of `Object`: one mesh as the passes see it.
    struct GpuObject => struct Object {
        material: uint,
        /// cube index in the environment/distance-map arrays, -1: none
        envmap_layer: int,
        /// cube index in the refractor-map array, -1: none
        refractor_layer: int,
        /// how it looks in other objects' distance maps: MAP_SHADING_* (`MapShading::code()`
        /// of its method)
        map_shading: uint,
        /// cube index in the distance maps of the map composition gives an object whose own maps
        /// are not that one cube (image-based captures, relief height maps), for how it shows in
        /// the other objects' maps (`LayerField::Shown`); -1: none (`envmap_layer` is that cube)
        shown_layer: int,
        pad: [uint; 3],
        /// xyz; w: proxy sphere radius (§3.2)
        reference_point: vec4,
        /// proxy box (§3.2), world space
        proxy_min: vec4,
        proxy_max: vec4,
        /// xyz: the centre of the map its own search reads: the reference point, or the
        /// shared layered map's (§4.5) for an object that takes `layered`
        map_centre: vec4,
        /// The mesh's world-space bounding box; min.w: the radius of its bounding sphere
        /// about the box's centre. Where a method does not trace a solid's inside, the chord
        /// through both bounds the path length its absorption needs (common/specular.glsl).
        bounds_min: vec4,
        bounds_max: vec4,
    }

    /// std430 twin of `Light`.
    struct GpuLight => struct Light {
        /// xyz position, w range (0: unbounded)
        position_range: vec4,
        /// xyz direction the light travels, w kind (LIGHT_*)
        direction_kind: vec4,
        /// rgb W/sr (point, spot) or W/m^2 (directional); w: directional shadow texel [m]
        intensity: vec4,
        /// x cos(outer), y cos(inner), z shadow layer (-1 none), w shadow map size
        cone: vec4,
        /// directional: world -> shadow clip
        shadow_view_proj: mat4,
    }

    /// Push constants of every scene-drawing shader.
    struct Push => push_constant Push push {
        /// first view of this draw (multiview adds gl_ViewIndex)
        view: uint,
        object: uint,
        /// FLAG_* and the drawing pass's own bits (`flag_bits!`)
        flags: uint,
        light_count: uint,
        /// Parameters the frame and the families declare word by word (`push_words!`), set
        /// once a frame for every pass; shaders read them through `push_<name>()`.
        words: [uint; 14],
    }
}

push_words! {
    /// The frame's words.
    0..2 {
        /// specular recursion depth R (`depth`): layered maps (§4.5) trace this many bounces
        RECURSION_DEPTH: uint,
        /// the view table's first extra camera view (the `frame::stage::EXTRA_VIEWS` block,
        /// planar mirrors'): layer L of `mirror_views` is view `push_extra_view_base() + L`
        EXTRA_VIEW_BASE: uint,
    }
}

gpu_consts! {
    /// `Material.kind`: diffuse.
    KIND_DIFFUSE: uint = 0;
    /// `Material.kind`: mirror (conductor Fresnel from ν, κ).
    KIND_MIRROR: uint = 1;
    /// `Material.kind`: dielectric (ior in ν.x).
    KIND_DIELECTRIC: uint = 2;

    /// `Light.direction_kind.w` (as a float): point, spot, directional.
    LIGHT_POINT: uint = 0;
    LIGHT_SPOT: uint = 1;
    LIGHT_DIRECTIONAL: uint = 2;

    /// How a specular object is drawn into the other objects' distance maps (§4.3), when the
    /// frame runs inter-object cycles (FLAG_INTER_OBJECT): the environment only, its own
    /// distance map of the previous cycle, or self refraction in its refractor map (§4.4).
    MAP_SHADING_SKY: uint = 0;
    MAP_SHADING_TRACED: uint = 1;
    MAP_SHADING_REFRACTOR: uint = 2;

    /// `Push.flags`: exact Fresnel (else Schlick's approximation).
    FLAG_FRESNEL_EXACT: uint = 1;
    /// `Push.flags`: the scene has an environment map.
    FLAG_HAS_ENVIRONMENT: uint = 2;
    /// `Push.flags` (`shadows=off`): punctual lights reach every diffuse surface facing them
    /// unoccluded (no shadow maps are planned; ray tracers send no shadow rays).
    FLAG_UNSHADOWED: uint = 32;
}

// Who owns which bits of `Push.flags`. `every_pass` bits are in the frame-wide flags, so no
// other owner may use them; `own_passes` bits are set only on the owner's own passes, so
// families may reuse each other's. build/layout.rs refuses a flag outside its owner's range
// and any overlap with an `every_pass` range: a pass's own bits never alias a frame-wide flag.
flag_bits! {
    every_pass 0..2 { FLAG_FRESNEL_EXACT, FLAG_HAS_ENVIRONMENT }
    every_pass 5..6 { FLAG_UNSHADOWED }
}

descriptor_sets! {
    /// The frame's descriptor set (set 0), shared by every pass that draws the scene.
    /// Bindings that a scene does not need (no lights, no textures, no specular objects) hold
    /// null descriptors (VK_EXT_robustness2 nullDescriptor), so nothing is allocated for them.
    BINDINGS = set 0 {
        VIEWS = 0: STORAGE_BUFFER => "readonly buffer Views { View views[]; }";
        MATERIALS = 1: STORAGE_BUFFER => "readonly buffer Materials { Material materials[]; }";
        OBJECTS = 2: STORAGE_BUFFER => "readonly buffer Objects { Object objects[]; }";
        LIGHTS = 3: STORAGE_BUFFER => "readonly buffer Lights { Light lights[]; }";
        /// All base-colour and emissive textures as layers of one array: lavapipe has no
        /// dynamic indexing of sampler arrays (shaderSampledImageArrayDynamicIndexing = false).
        TEXTURES = 4: COMBINED_IMAGE_SAMPLER => "uniform sampler2DArray textures";
        ENVIRONMENT_MAP = 5: COMBINED_IMAGE_SAMPLER => "uniform sampler2D environment_map";
        SHADOW_CUBES = 6: COMBINED_IMAGE_SAMPLER => "uniform samplerCubeArray shadow_cubes";
        SHADOW_PLANES = 7: COMBINED_IMAGE_SAMPLER => "uniform sampler2DArray shadow_planes";
    }

    /// Maps of ray tracing in the sampled geometry (survey §4), bound per pass as set 1.
    MAP_BINDINGS = set 1 {}
}
