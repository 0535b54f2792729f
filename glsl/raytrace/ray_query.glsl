// Vulkan ray queries through the TLAS of set 5 (src/methods/raytrace/ray_query/): the
// nearest (or any) triangle a ray meets, as the other schemes' RayHit. Included by the shaders
// that define SPECULA_RAY_QUERY and enable GL_EXT_ray_query before the layout.
#ifndef RAYTRACE_RAY_QUERY_GLSL
#define RAYTRACE_RAY_QUERY_GLSL
#include "common/scene.glsl"
#include "common/optics.glsl"

// The largest finite f32: ray queries take no infinite t_max.
const float RQ_T_MAX = 3.4028234663852886e38;

// The triangle-list id of a candidate (committed: false) or of the committed hit of ray
// query rq: the instance's custom index (its mesh's first triangle) plus the primitive index.
// (A macro: ray queries are no function arguments, and `committed` must be a constant.)
#define RQ_TRIANGLE(rq, committed) \
    (uint(rayQueryGetIntersectionInstanceCustomIndexEXT(rq, committed)) + uint(rayQueryGetIntersectionPrimitiveIndexEXT(rq, committed)))

// The nearest triangle other than `skip` on o + t d, t_min ≤ t ≤ t_max (any triangle with
// `any_hit`); `triangle` = RAY_NO_TRIANGLE and t = t_max when none. Triangles are opaque; a
// ray that leaves a triangle has its candidates reported so that that one is skipped.
RayHit rq_trace(vec3 o, vec3 d, float t_min, float t_max, uint skip, bool any_hit) {
    RayHit best = RayHit(t_max, 0.0, 0.0, RAY_NO_TRIANGLE);
    t_min = max(t_min, 0.0);
    t_max = min(t_max, RQ_T_MAX);
    // The API's valid-usage rules: finite origin and direction, 0 ≤ t_min ≤ t_max.
    if (!is_finite(o) || !is_finite(d) || dot(d, d) == 0.0 || is_nan(t_max) || !(t_min <= t_max)) return best;
    bool skips = skip != RAY_NO_TRIANGLE;
    uint flags = (skips ? gl_RayFlagsNoOpaqueEXT : gl_RayFlagsOpaqueEXT) | (any_hit ? gl_RayFlagsTerminateOnFirstHitEXT : 0u);
    rayQueryEXT rq;
    rayQueryInitializeEXT(rq, tlas, flags, 0xffu, o, t_min, d, t_max);
    while (rayQueryProceedEXT(rq)) {
        if (rayQueryGetIntersectionTypeEXT(rq, false) == gl_RayQueryCandidateIntersectionTriangleEXT && RQ_TRIANGLE(rq, false) != skip) {
            rayQueryConfirmIntersectionEXT(rq);
        }
    }
    if (rayQueryGetIntersectionTypeEXT(rq, true) == gl_RayQueryCommittedIntersectionTriangleEXT) {
        vec2 uv = rayQueryGetIntersectionBarycentricsEXT(rq, true);
        best = RayHit(rayQueryGetIntersectionTEXT(rq, true), uv.x, uv.y, RQ_TRIANGLE(rq, true));
    }
    return best;
}

// The surface at ray-query hit h of a ray along d, from set 5's triangle shading: the
// interpolated unit normal (−d where it degenerates), texture coordinates and material.
struct RqSurface {
    vec3 n;
    vec2 uv;
    uint material;
};

RqSurface rq_surface(RayHit h, vec3 d) {
    TriangleShading sh = rq_shading[h.triangle];
    float w = 1.0 - h.u - h.v;
    vec3 n = sh.n0.xyz * w + sh.n1.xyz * h.u + sh.n2.xyz * h.v;
    RqSurface s;
    s.n = dot(n, n) > 0.0 ? normalize(n) : -normalize(d);
    s.uv = sh.uv01.xy * w + sh.uv01.zw * h.u + sh.uv2.xy * h.v;
    s.material = floatBitsToUint(sh.n0.w);
    return s;
}

#endif
