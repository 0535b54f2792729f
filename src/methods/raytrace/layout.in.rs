// What ray tracing in the original geometry (survey §2) shares with its kernels: the ray,
// hit, triangle and acceleration structs, their consts and sets 2 and 3. Concatenated with
// the frame's declaration by build.rs (see src/frame/layout.in.rs).

gpu_structs! {
    /// One ray of the ray-tracing pipeline's intersection query (survey §2.3.1: the rays
    /// live in GPU memory; every acceleration scheme answers the same query).
    struct GpuRayQuery => struct RayQuery {
        /// xyz origin, w t_min
        origin: vec4,
        /// xyz direction (any length), w t_max (+inf: unbounded)
        direction: vec4,
        /// the triangle the ray leaves (RAY_NO_TRIANGLE: none)
        skip: uint,
        /// RAY_ANY_HIT: the first hit found will do (shadow rays); RAY_LOST (written by the
        /// intersection kernels): given up inside a graded medium
        flags: uint,
        /// The graded medium the ray runs in, its material index + 1 (0: none: straight);
        /// its intersection then marches the curved path (common/medium.glsl) and writes the
        /// last chord back as origin and direction
        medium: uint,
        /// A curved ray's path length before its last chord (float bits; written back with it)
        before: uint,
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
        /// 1: the ray texture holds the queue's rays in `ray_order` (the ray hierarchy's
        /// direction cell and pixel order, raytrace/sort.glsl); 0: texel t is ray t
        ordered: uint,
        /// graded media (survey §6.5, common/medium.glsl): the most a ray turns per RK4 step
        /// [rad] (the medium_turn knob)
        medium_turn: float,
        /// the ray order's direction cells per side (ray_order.rs's `direction_cells`: at most
        /// SORT_DIRECTION_CELLS, fewer where the counters would outgrow their cap)
        direction_cells: uint,
        pad: [uint; 2],
    }

    /// One bounce's budget for a queue (raytrace/trace.glsl's budget_*): which rays the
    /// queue keeps when more arrive than it holds.
    struct GpuSpawnBudget => struct SpawnBudgetState {
        /// rays per weight bin (bin 0: the heaviest)
        hist: [uint; 64],
        /// the cut bin's rays per sub-bin (a hash of the pixel and direction)
        sub: [uint; 64],
        /// the first bin not kept whole (SPAWN_BINS: every ray kept)
        cutoff: uint,
        /// the first sub-bin of the cut bin not kept
        sub_cutoff: uint,
        /// rays the bins before the cut hold
        kept: uint,
        /// rays dropped
        dropped: uint,
        /// their path weights (largest channel), 64-bit fixed point 2^-20 (lo, hi)
        dropped_weight: [uint; 2],
        pad: [uint; 2],
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

    /// The GPU BVH builder's parameters (src/methods/raytrace/lbvh.rs): a linear BVH over
    /// Morton codes (Karras 2012) and the bottom-up refit of any BVH of the `Accel` form.
    struct GpuLbvh => struct Lbvh {
        /// triangles in the list (the leaves of a linear BVH)
        triangle_count: uint,
        /// workgroups of LBVH_TILE keys per radix-sort pass
        groups: uint,
        /// leaf nodes (the refit's first threads); n for a linear BVH
        leaves: uint,
        /// nodes of the tree (2n - 1 for a linear BVH)
        nodes: uint,
        /// the Morton grid's minimum corner (xyz): the triangle list's bounds
        lo: vec4,
        /// Morton cells per world unit along each axis (xyz): 1024 over the bounds
        scale: vec4,
    }
}

gpu_consts! {
    /// The GPU BVH builder's workgroup of keys (one per invocation) in the radix sort, and
    /// the bits of the radix sort's digit (16 bins per pass, 8 passes over 32-bit keys).
    LBVH_TILE: uint = 256;
    LBVH_RADIX_BITS: uint = 4;
    /// The ray hierarchy's ray order: the most direction cells per side of the octahedral
    /// map that groups a queue's rays before their pixels (raytrace/sort.glsl).
    SORT_DIRECTION_CELLS: uint = 4;
    /// `lbvh_parents`: the root's parent.
    LBVH_NONE: uint = 4294967295;
    /// Bins of a queue budget's weight histogram: half an octave each, from 2^16 down to
    /// 2^-16 (the first and last bins hold everything heavier and lighter); and sub-bins of
    /// the cut bin.
    SPAWN_BINS: uint = 64;
    /// `RayHit.triangle` and `RayQuery.skip`: no triangle.
    RAY_NO_TRIANGLE: uint = 4294967295;
    /// `RayQuery.flags`: any hit will do (shadow rays).
    RAY_ANY_HIT: uint = 1;
    /// `RayQuery.flags`: the hit is already known (a primary hit from rasterisation that the
    /// exact triangle test confirmed); the intersection kernels leave it.
    RAY_HIT_KNOWN: uint = 2;
    /// `RayQuery.flags`: lost inside a graded medium (common/medium.glsl's ⌈MEDIUM_MAX_TURN / turn⌉
    /// chords without a hit): it adds nothing.
    RAY_LOST: uint = 4;
}

descriptor_sets! {
    /// Ray tracing in the original geometry (survey §2), set 2: the ray queries and their
    /// hits, the triangle list, and the acceleration scheme's buffers. Nodes are 16-byte
    /// words whose meaning is the scheme's (src/methods/raytrace/: BVH nodes, grid cells,
    /// kd-tree nodes); references index the triangle list.
    RAY_BINDINGS = set 2 {
        /// (written back by the intersection kernels for rays in graded media)
        RAY_QUERIES = 0: STORAGE_BUFFER => "buffer RayQueries { RayQuery queries[]; }";
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
        /// The ray hierarchy's ray order: the ray at each texel of the ray texture, the
        /// queue's rays by direction cell and pixel (raytrace/sort.glsl)
        RAY_ORDER = 16: STORAGE_BUFFER => "buffer RayOrder { uint ray_order[]; }";
        /// The ray order's key counters, then (scanned) where each key's rays start
        SORT_OFFSETS = 17: STORAGE_BUFFER => "buffer SortOffsets { uint sort_offsets[]; }";
        /// Each ray's rank among its pixel's rays
        SORT_RANKS = 18: STORAGE_BUFFER => "buffer SortRanks { uint sort_ranks[]; }";
        /// The scan's block totals
        SORT_BLOCKS = 19: STORAGE_BUFFER => "buffer SortBlocks { uint sort_blocks[]; }";
        /// This bounce's spawn budget (raytrace/spawn.comp): the children's weights in
        /// SPAWN_BINS bins, the first bin dropped, and the rays and path weight dropped
        SPAWN_BUDGET = 20: STORAGE_BUFFER => "buffer SpawnBudget { SpawnBudgetState spawn_budget; }";
        /// The same for this bounce's shadow queries (raytrace/shade.comp), where the shadow
        /// queue may overflow (its capacity clamped by the device's storage-buffer range)
        SHADOW_BUDGET = 21: STORAGE_BUFFER => "buffer ShadowBudget { SpawnBudgetState shadow_budget; }";
    }

    /// The `ray-query` scheme's own set 5 (src/methods/raytrace/ray_query/): the TLAS over
    /// one instance per object. Declared in GLSL only where SPECULA_RAY_QUERY is defined (the
    /// shaders that enable GL_EXT_ray_query); only devices with VK_KHR_acceleration_structure
    /// create it.
    RAY_QUERY_BINDINGS = set 5 {
        TLAS = 0: ACCELERATION_STRUCTURE_KHR => "uniform accelerationStructureEXT tlas";
        /// The triangles' shading attributes, as set 3's `SHADING` (caustic_paths=exact: the
        /// normal and material at each photon hit)
        RQ_SHADING = 1: STORAGE_BUFFER => "readonly buffer RqShading { TriangleShading rq_shading[]; }";
        /// Per object two counters a raster pass that traces keeps (distance_fallback=rays:
        /// the rays its search answered, the rays it traced)
        RQ_COUNTS = 2: STORAGE_BUFFER => "buffer RqCounts { uint rq_counts[]; }";
    }

    /// The GPU BVH builder (src/methods/raytrace/lbvh.rs), set 6 of its own kernels: it
    /// writes the nodes, references and miss links that set 2 reads, in `Accel`'s BVH form.
    LBVH_BINDINGS = set 6 {
        LBVH_TRIANGLES = 0: STORAGE_BUFFER => "readonly buffer LbvhTriangles { Triangle lbvh_triangles[]; }";
        /// The BVH's nodes (bvh.glsl's form: min bits and first, max bits and count); the
        /// refit reads children its other invocations wrote
        LBVH_NODES = 1: STORAGE_BUFFER => "coherent buffer LbvhNodes { uvec4 lbvh_nodes[]; }";
        LBVH_REFS = 2: STORAGE_BUFFER => "buffer LbvhRefs { uint lbvh_refs[]; }";
        /// Each node's miss link (the stackless traversal)
        LBVH_AUX = 3: STORAGE_BUFFER => "buffer LbvhAux { uint lbvh_aux[]; }";
        /// Morton keys and their triangles, two halves of n each (the radix sort's ping-pong)
        LBVH_KEYS = 4: STORAGE_BUFFER => "buffer LbvhKeys { uint lbvh_keys[]; }";
        LBVH_VALS = 5: STORAGE_BUFFER => "buffer LbvhVals { uint lbvh_vals[]; }";
        /// Per radix-sort pass the keys per (digit, workgroup), digit-major, then scanned
        LBVH_COUNTS = 6: STORAGE_BUFFER => "buffer LbvhCounts { uint lbvh_counts[]; }";
        /// Each node's parent node (LBVH_NONE at the root)
        LBVH_PARENTS = 7: STORAGE_BUFFER => "buffer LbvhParents { uint lbvh_parents[]; }";
        /// The leaf nodes (the refit starts there), then a linear BVH's internal nodes by
        /// their Karras index
        LBVH_SLOTS = 8: STORAGE_BUFFER => "buffer LbvhSlots { uint lbvh_slots[]; }";
        /// Per node the refit's arrivals (the second child to finish unites the boxes)
        LBVH_FLAGS = 9: STORAGE_BUFFER => "coherent buffer LbvhFlags { uint lbvh_flags[]; }";
        LBVH_PARAMS = 10: STORAGE_BUFFER => "readonly buffer LbvhParams { Lbvh lbvh; }";
    }
}
