// The one declaration of what Rust and the shaders share: the std430 structs, the
// push-constant block, the consts and the descriptor bindings. Two macros read it:
// src/frame/layout.rs expands it into the crate's `#[repr(C)]` structs and consts, and
// build/layout.rs into `$OUT_DIR/glsl/generated/layout.glsl` (included by
// glsl/common/scene.glsl), after checking that std430 and `repr(C)` lay every field out at
// the same offset. Field types are GLSL's (`[T; N]` is an array; a struct is named by its
// Rust name); doc comments go to both sides.

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
        /// mirror: ν per rgb; dielectric: x = ior
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
        /// xyz; w: proxy sphere radius (§3.2)
        reference_point: vec4,
        /// proxy box (§3.2), world space
        proxy_min: vec4,
        proxy_max: vec4,
        /// xyz: the centre of the map its own search reads: the reference point, or the
        /// shared layered map's (§4.5) for an object that takes `layered`
        map_centre: vec4,
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

    /// The distance-map search knobs (§4.1) as the shaders read them.
    struct SearchKnobs => struct SearchKnobs {
        /// 0: parallax correction only
        linear_steps: uint,
        secant_steps: uint,
        binary_steps: uint,
        parallax_iterations: uint,
    }

    /// One ray of the ray-tracing pipeline's intersection query (survey §2.3.1: the rays
    /// live in GPU memory; every acceleration scheme answers the same query).
    struct GpuRayQuery => struct RayQuery {
        /// xyz origin, w t_min
        origin: vec4,
        /// xyz direction (any length), w t_max (+inf: unbounded)
        direction: vec4,
        /// the triangle the ray leaves (RAY_NO_TRIANGLE: none)
        skip: uint,
        /// RAY_ANY_HIT: the first hit found will do (shadow rays)
        flags: uint,
        pad: [uint; 2],
    }

    /// The answer to one `RayQuery`: the nearest hit, or `triangle` = RAY_NO_TRIANGLE.
    struct GpuRayHit => struct RayHit {
        t: float,
        /// barycentric of v1
        u: float,
        /// barycentric of v2
        v: float,
        /// index into the triangle list (scene order: mesh by mesh, index by index)
        triangle: uint,
    }

    /// One scene triangle in world space, as the intersection kernels read it.
    struct GpuTriangle => struct Triangle {
        /// xyz; w: unused
        v0: vec4,
        v1: vec4,
        v2: vec4,
    }

    /// What a traced ray carries besides its query: whose pixel it lights and how much.
    struct GpuRayPayload => struct RayPayload {
        /// rgb: the path's weight (product of Fresnel factors); a: unused
        weight: vec4,
        /// y * width + x
        pixel: uint,
        pad: [uint; 3],
    }

    /// The shading attributes of one triangle of the list (the positions are `Triangle`).
    struct GpuTriangleShading => struct TriangleShading {
        /// vertex normals (xyz); n0.w: the material index as uint bits
        n0: vec4,
        n1: vec4,
        n2: vec4,
        /// texture coordinates of v0 (xy) and v1 (zw)
        uv01: vec4,
        /// texture coordinates of v2 (xy); z: the mesh index as uint bits
        uv2: vec4,
    }

    /// One bounce of the ray pipeline, as its kernels read it (one entry per bounce).
    struct GpuTraceParams => struct TraceParams {
        /// camera image size
        width: uint,
        height: uint,
        /// 0: the primary hits; the last bounce spawns no children
        bounce: uint,
        last: uint,
        /// capacity of each ray queue, and of the shadow queue
        capacity: uint,
        shadow_capacity: uint,
        /// secondary and shadow rays start this far from the surface they leave
        t_min: float,
        /// the ray engine's ray texture (§2.2): width; its height is capacity / width
        ray_texture_width: uint,
        /// the ray hierarchy (§2.2.1): edge of a tile of the ray texture, and tiles per row
        tile_size: uint,
        tiles_per_row: uint,
        /// camera rays per pixel (MSAA samples; 1 without)
        samples: uint,
        pad: uint,
    }

    /// What an acceleration scheme's kernel needs besides its node and reference buffers.
    struct GpuAccel => struct Accel {
        /// uniform grid: world-space minimum corner (xyz)
        grid_min: vec4,
        /// uniform grid: cells per world unit along each axis (xyz)
        grid_inv_cell: vec4,
        /// uniform grid: cells per axis (xyz); w: 1 with empty-cell skipping (KL04)
        grid_res: uvec4,
        /// kd-tree: the root node's box, minimum corner (xyz; f32 values the builder split)
        bounds_min: vec4,
        /// kd-tree: the root node's box, maximum corner (xyz)
        bounds_max: vec4,
        /// unused (the query count is `RAY_COUNT`'s)
        unused: uint,
        /// triangles in the triangle list
        triangle_count: uint,
        /// nodes of the tree (BVH, kd-tree); 0 for the grid and brute force
        node_count: uint,
        pad: uint,
    }

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
    }

    /// One environment vertex of curved reflectors (survey §5, EMDT06): the scene's
    /// triangles, subdivided `tessellation`² times, in world space.
    struct GpuCurvedVertex => struct CurvedVertex {
        /// xyz; w: unused
        position: vec4,
        /// xyz; w: unused
        normal: vec4,
        /// xy texture coordinates; zw: unused
        uv: vec4,
    }

    /// What the curved-reflector passes share (survey §5, EMD*05/EMDT06).
    struct GpuCurvedParams => struct CurvedParams {
        /// environment vertices (one virtual vertex each per reflector)
        vertex_count: uint,
        /// edge of each reflector's geometry image (texels)
        image_size: uint,
        /// coarse-to-fine levels of the reflection-point search: the coarsest is searched
        /// exhaustively at a stride of 2^levels texels
        search_levels: uint,
        /// reflectors (layers of the geometry images and of the virtual images)
        reflector_count: uint,
        /// each environment triangle is split into tessellation² triangles
        tessellation: uint,
        /// triangles of the scene (`source_triangles`), each (t + 1)(t + 2)/2 vertices
        triangle_count: uint,
        pad: [uint; 2],
    }

    /// Push constants of every scene-drawing shader.
    struct Push => push_constant Push push {
        /// first view of this draw (multiview adds gl_ViewIndex)
        view: uint,
        object: uint,
        /// FLAG_*
        flags: uint,
        light_count: uint,
        search: SearchKnobs,
        /// early exit when | |l|/|l'| − 1 | ≤ tolerance
        tolerance: float,
        /// self refraction: total internal reflections followed (§4.4)
        internal_bounces: uint,
        /// specular recursion depth R (`depth`): layered maps (§4.5) trace this many bounces
        depth: uint,
        /// the view table's first planar-mirror view (`ViewLayout::mirrors`): layer L of
        /// `mirror_views` is view `mirror_base + L`
        mirror_base: uint,
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
    /// Specular objects drawn into maps search their own (previous-cycle) distance maps (§4.3).
    FLAG_INTER_OBJECT: uint = 4;
    /// Proxy geometry of localised environment mapping (§3.2): box, else sphere.
    FLAG_PROXY_BOX: uint = 8;
    /// First inter-object cycle: no map holds anything yet, specular objects in maps are black
    /// (paths longer than the requested depth end black, as in the reference).
    FLAG_FIRST_CYCLE: uint = 16;
    /// `geometry.mirror` and `geometry.refract` (§5): the object's planes have child views
    /// in the `(flags >> MIRROR_COUNT_SHIFT)` layers of `mirror_views` from `(flags >>
    /// MIRROR_LAYER_SHIFT) & 0xff` on; without the flag (or for a plane none of them is
    /// of), the budget's fallback (the environment along the ray).
    FLAG_MIRROR_VIEW: uint = 32;
    /// `Push.flags` of the camera's `scene.direct`: the caustics are projected by their own
    /// pass (`caustics.project`), not inside `shade_diffuse`.
    FLAG_CAUSTICS_APART: uint = 128;
    MIRROR_LAYER_SHIFT: uint = 16;
    MIRROR_COUNT_SHIFT: uint = 24;

    /// `CausticParams.flags`: the projection's distance test (§6.3.3).
    CAUSTIC_DISTANCE_TEST: uint = 1;
    /// `CausticParams.flags`: the receiver-orientation factor cos α of the projection.
    CAUSTIC_ORIENTATION: uint = 2;
    /// `Push.flags` of the photon pass: the caustic cube's index `(flags >> CAUSTIC_CUBE_SHIFT)
    /// & 0xff` and the light's `flags >> CAUSTIC_LIGHT_SHIFT`.
    CAUSTIC_CUBE_SHIFT: uint = 8;
    /// `Push.flags` of the photon pass: this layer's photons take the reflected branch at a
    /// dielectric generator's surface (else the refracted one).
    CAUSTIC_REFLECTED: uint = 64;
    CAUSTIC_LIGHT_SHIFT: uint = 20;
    /// Caustic triangles whose corners' distances from the reference point differ by more
    /// than this fraction land on different surfaces (§6.3.2) and are dropped.
    CAUSTIC_GAP: float = 0.1;

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
    FLAG_LAYERED_STRONGEST: uint = 4096;
    /// `Push.flags` (`shadows=off`): punctual lights reach every diffuse surface facing them
    /// unoccluded (no shadow maps are planned; ray tracers send no shadow rays).
    FLAG_UNSHADOWED: uint = 8192;
    /// `Push.flags` of `distance.search` only (`debug_fault=flip_reflection`, a test knob):
    /// the reflected ray is traced in the opposite direction. Never in the frame-wide flags
    /// (bits 8–15 of the photon pass's flags are its cube index).
    FLAG_DEBUG_FLIP_REFLECTION: uint = 16384;

    /// Curved reflectors (§5): `Push.flags >> CURVED_REFLECTOR_SHIFT` is the reflector's layer
    /// in the geometry and virtual images (the `geometry.curved` and `geometry.virtual` draws).
    CURVED_REFLECTOR_SHIFT: uint = 16;
    /// Curved reflectors: a virtual vertex is kept when the angle between the normal at its
    /// reflection point and the bisector of the directions to the eye and to the vertex has a
    /// cosine above this (else its reflection point lies off the reflector's silhouette or
    /// rim, and its virtual triangles are dropped).
    CURVED_MIN_COS: float = 0.98;
    /// Curved reflectors: every this many-th environment vertex is searched a second time,
    /// away from its reflection point, for a second one (several minima: the reflector is
    /// neither convex nor concave as seen from there, survey §5); found ones are counted.
    CURVED_CHECK_STRIDE: uint = 16;
    /// Curved reflectors: a reflector pixel its virtual image leaves uncovered takes the
    /// nearest covered pixel within this many pixels (the holes at its silhouette and rim).
    CURVED_FILL: int = 2;

    /// `RayHit.triangle` and `RayQuery.skip`: no triangle.
    RAY_NO_TRIANGLE: uint = 4294967295;
    /// `RayQuery.flags`: any hit will do (shadow rays).
    RAY_ANY_HIT: uint = 1;
    /// `RayQuery.flags`: the hit is already known (a primary hit from rasterisation that the
    /// exact triangle test confirmed); the intersection kernels leave it.
    RAY_HIT_KNOWN: uint = 2;
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
        ENVMAPS = 8: COMBINED_IMAGE_SAMPLER => "uniform samplerCubeArray envmaps";
        /// Planar mirrors' views (survey §5), one layer per view of the frame. A view
        /// renders into a scratch target while it samples its children here, and is copied
        /// into its layer afterwards.
        MIRROR_VIEWS = 9: COMBINED_IMAGE_SAMPLER => "uniform sampler2DArray mirror_views";
        /// Caustics (§6): per caustic cube, the distance of the nearest receiver (everything but
        /// the generator) from its centre, the terminal hits' search map and the projection's
        /// distance test.
        CAUSTIC_DISTANCES = 10: COMBINED_IMAGE_SAMPLER => "uniform samplerCubeArray caustic_distances";
        /// Caustics: per caustic cube, the light cube map: radiant intensity J (W/sr) of the
        /// caustic as seen from its centre, the projection's input.
        CAUSTIC_MAPS = 11: COMBINED_IMAGE_SAMPLER => "uniform samplerCubeArray caustic_maps";
        /// Caustics: photon hit location images, one layer per light view of a generator:
        /// xyz the hit relative to its cube's centre, w 1 for a photon.
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
    }

    /// Maps of ray tracing in the sampled geometry (survey §4), bound per pass as set 1.
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

    /// Ray tracing in the original geometry (survey §2), set 2: the ray queries and their
    /// hits, the triangle list, and the acceleration scheme's buffers. Nodes are 16-byte
    /// words whose meaning is the scheme's (src/methods/raytrace/: BVH nodes, grid cells,
    /// kd-tree nodes); references index the triangle list.
    RAY_BINDINGS = set 2 {
        RAY_QUERIES = 0: STORAGE_BUFFER => "readonly buffer RayQueries { RayQuery queries[]; }";
        RAY_HITS = 1: STORAGE_BUFFER => "buffer RayHits { RayHit hits[]; }";
        RAY_TRIANGLES = 2: STORAGE_BUFFER => "readonly buffer Triangles { Triangle triangles[]; }";
        ACCEL_NODES = 3: STORAGE_BUFFER => "readonly buffer AccelNodes { uvec4 accel_nodes[]; }";
        ACCEL_REFS = 4: STORAGE_BUFFER => "readonly buffer AccelRefs { uint accel_refs[]; }";
        /// BVH: the miss link of each node (stackless traversal); grid, kd-tree: unused
        ACCEL_AUX = 5: STORAGE_BUFFER => "readonly buffer AccelAux { uint accel_aux[]; }";
        ACCEL_PARAMS = 6: STORAGE_BUFFER => "readonly buffer AccelParams { Accel accel; }";
        /// The payload of each query (the ray pipeline; unused by the intersection kernels)
        RAY_PAYLOADS = 7: STORAGE_BUFFER => "readonly buffer RayPayloads { RayPayload payloads[]; }";
        /// How many queries the buffer holds (written by the GPU in the ray pipeline)
        RAY_COUNT = 8: STORAGE_BUFFER => "readonly buffer RayCount { uint ray_count; }";
    }

    /// The ray pipeline's per-bounce outputs (survey §2.3.1), set 3: the next bounce's
    /// queue and the shadow queue (appended through their counters), the fixed-point
    /// radiance accumulator, and what shading needs.
    TRACE_BINDINGS = set 3 {
        NEXT_QUERIES = 0: STORAGE_BUFFER => "writeonly buffer NextQueries { RayQuery next_queries[]; }";
        NEXT_PAYLOADS = 1: STORAGE_BUFFER => "writeonly buffer NextPayloads { RayPayload next_payloads[]; }";
        NEXT_COUNT = 2: STORAGE_BUFFER => "buffer NextCount { uint next_count; }";
        SHADOW_QUERIES = 3: STORAGE_BUFFER => "writeonly buffer ShadowQueries { RayQuery shadow_queries[]; }";
        SHADOW_PAYLOADS = 4: STORAGE_BUFFER => "writeonly buffer ShadowPayloads { RayPayload shadow_payloads[]; }";
        SHADOW_COUNT = 5: STORAGE_BUFFER => "buffer ShadowCount { uint shadow_count; }";
        /// Per pixel and channel a 64-bit fixed-point sum (lo, hi words): integer atomics,
        /// so the image does not depend on the order rays are processed in
        ACCUM = 6: STORAGE_BUFFER => "buffer Accum { uint accum[]; }";
        SHADING = 7: STORAGE_BUFFER => "readonly buffer Shading { TriangleShading shading[]; }";
        /// Per mesh: 1 when this stage renders its pixels
        HANDLED = 8: STORAGE_BUFFER => "readonly buffer Handled { uint handled[]; }";
        TRACE = 9: STORAGE_BUFFER => "readonly buffer Trace { TraceParams trace; }";
        /// The primary hits: each pixel's nearest triangle id, from rasterisation
        VISIBILITY = 10: STORAGE_IMAGE => "layout(r32ui) uniform readonly uimage2DArray visibility";
        /// Indirect dispatch arguments of the next kernels (args.comp)
        DISPATCH = 11: STORAGE_BUFFER => "buffer Dispatch { uint dispatch[]; }";
        /// The first queue's hits (primary.comp writes them from the visibility image)
        NEXT_HITS = 12: STORAGE_BUFFER => "writeonly buffer NextHits { RayHit next_hits[]; }";
        /// The ray engine's hit records (t, u, v bits, triangle) per texel of the ray texture
        ENGINE_HITS = 13: STORAGE_IMAGE => "layout(rgba32ui) uniform readonly uimage2D engine_hits";
        /// The ray hierarchy's cone per tile: apex (xyz), cos of the half angle (w; 2: no
        /// cone, test every triangle; 3: empty tile) and axis (xyz), sin of the half angle (w)
        TILE_CONES = 14: STORAGE_BUFFER => "buffer TileCones { vec4 tile_cones[]; }";
        /// The ray hierarchy's culling counts (with the ray_stats knob): per bounce and
        /// queue (rays, shadow rays) the tile×triangle pairs tested and those kept
        CULL_STATS = 15: STORAGE_BUFFER => "buffer CullStats { uint cull_stats[]; }";
    }

    /// Curved reflectors by geometry transformation (survey §5, EMD*05/EMDT06), set 4 of
    /// the `geometry.*` passes of `curved-reflector`.
    CURVED_BINDINGS = set 4 {
        /// The reflectors' geometry images, one layer each: xyz world position, w 1 where the
        /// parameterisation covers the texel (0: empty)
        GEOMETRY_POSITIONS = 0: COMBINED_IMAGE_SAMPLER => "uniform sampler2DArray geometry_positions";
        /// xyz the interpolated unit normal (w unused)
        GEOMETRY_NORMALS = 1: COMBINED_IMAGE_SAMPLER => "uniform sampler2DArray geometry_normals";
        /// The environment's vertices (tessellated by `geometry.virtual.tessellate`), in world
        /// space: source triangle k's grid vertices from k · (t + 1)(t + 2)/2 on
        CURVED_VERTICES = 2: STORAGE_BUFFER => "buffer CurvedVertices { CurvedVertex curved_vertices[]; }";
        /// Per reflector k and environment vertex i, entry k · vertex_count + i: xyz its
        /// virtual position, w 1 when it has a reflection point on the reflector (else 0)
        VIRTUAL_VERTICES = 3: STORAGE_BUFFER => "buffer VirtualVertices { vec4 virtual_vertices[]; }";
        CURVED = 4: STORAGE_BUFFER => "readonly buffer Curved { CurvedParams curved; }";
        /// The virtual objects drawn for each reflector from the camera, one layer each: rgb
        /// radiance, a 1 where a virtual object covers the pixel
        VIRTUAL_IMAGES = 5: COMBINED_IMAGE_SAMPLER => "uniform sampler2DArray virtual_images";
        /// The scene's vertex buffer (`gpu_scene::Vertex`: position, normal, uv; 8 floats
        /// each), what the tessellation reads
        SCENE_VERTICES = 6: STORAGE_BUFFER => "readonly buffer SceneVertices { float scene_vertices[]; }";
        /// Every triangle of the scene: its three vertices' indices in `scene_vertices` (w
        /// its mesh)
        SOURCE_TRIANGLES = 7: STORAGE_BUFFER => "readonly buffer SourceTriangles { uvec4 source_triangles[]; }";
        /// Each reflector's triangles, three vertices each, with its parameterisation in
        /// `uv` (the geometry image's raster pass)
        REFLECTOR_VERTICES = 8: STORAGE_BUFFER => "readonly buffer ReflectorVertices { CurvedVertex reflector_vertices[]; }";
        /// Per reflector: the checked vertices (every CURVED_CHECK_STRIDE-th) that have a
        /// second reflection point apart from the first (read back as a frame stat)
        CURVED_MINIMA = 9: STORAGE_BUFFER => "buffer CurvedMinima { uint curved_minima[]; }";
    }
}
