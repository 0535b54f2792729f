// What geometry transformation (survey §5) shares with its shaders: planar mirrors' views
// and their push flags, and the curved reflectors' structs, consts and set 4. Concatenated
// with the frame's declaration by build.rs (see src/frame/layout.in.rs).

gpu_structs! {
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
}

gpu_consts! {
    /// `geometry.mirror` and `geometry.refract` (§5): the object's planes have child views
    /// in the `(flags >> MIRROR_COUNT_SHIFT)` layers of `mirror_views` from `(flags >>
    /// MIRROR_LAYER_SHIFT) & 0xff` on; without the flag (or for a plane none of them is
    /// of), the budget's fallback (the environment along the ray).
    FLAG_MIRROR_VIEW: uint = 32768;
    /// `geometry.mirror` and `geometry.refract` drawn in a view at the recursion depth: what
    /// the object reflects or refracts there ends as the reference's paths end (the
    /// environment along the ray), not in the budget's fallback maps.
    FLAG_MIRROR_DEPTH_END: uint = 8192;
    MIRROR_LAYER_SHIFT: uint = 16;
    MIRROR_COUNT_SHIFT: uint = 24;

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
}

flag_bits! {
    /// Planar mirrors' child views on `geometry.mirror` and `geometry.refract` draws; the curved
    /// reflector's layer on `geometry.curved` and `geometry.virtual` draws.
    own_passes 13..14 { FLAG_MIRROR_DEPTH_END }
    own_passes 15..32 { FLAG_MIRROR_VIEW, MIRROR_LAYER_SHIFT: 8, MIRROR_COUNT_SHIFT: 8, CURVED_REFLECTOR_SHIFT: 16 }
}

descriptor_sets! {
    BINDINGS = set 0 {
        /// Planar mirrors' views (survey §5), one layer per view of the frame. A view
        /// renders into a scratch target while it samples its children here, and is copied
        /// into its layer afterwards.
        MIRROR_VIEWS = 9: COMBINED_IMAGE_SAMPLER => "uniform sampler2DArray mirror_views";
        /// Per mesh, the camera's fragments (pixels, or samples with per-sample shading)
        /// whose branch a view budget cut and the object's own maps served instead
        /// (`geometry.mirror`, `geometry.refract`; branches cut inside the mirrored views are
        /// counted by plane, `geometry.mirror_fallbacks`); zeroed each frame, reported as
        /// `geometry.fallback_pixels.<object>`.
        FALLBACKS = 27: STORAGE_BUFFER => "buffer Fallbacks { uint fallbacks[]; }";
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
