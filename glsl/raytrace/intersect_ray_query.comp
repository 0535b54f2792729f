#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_ray_query : require
// Vulkan's ray queries (src/methods/raytrace/ray_query/): the driver's traversal of the
// acceleration structures (one bottom level per mesh, one instance per object) answers the
// same query as every other scheme. The triangle id is the instance's custom index (its
// mesh's first triangle in the list) plus the primitive index.
// Set 5 (`tlas`, src/methods/raytrace/layout.in.rs) is declared where this is defined.
#define SPECULA_RAY_QUERY
#include "raytrace/rays.glsl"

// The largest finite f32: ray queries take no infinite t_max.
const float RQ_T_MAX = 3.4028234663852886e38;

uint candidate_id(rayQueryEXT rq) {
    return uint(rayQueryGetIntersectionInstanceCustomIndexEXT(rq, false)) + uint(rayQueryGetIntersectionPrimitiveIndexEXT(rq, false));
}

RayHit intersect_ray_query(RayQuery q) {
    RayHit best = no_hit(q);
    vec3 o = q.origin.xyz;
    vec3 d = q.direction.xyz;
    float t_min = max(q.origin.w, 0.0);
    float t_max = min(q.direction.w, RQ_T_MAX);
    // The API's valid-usage rules: finite origin and direction, 0 ≤ t_min ≤ t_max.
    if (!is_finite(o) || !is_finite(d) || dot(d, d) == 0.0 || is_nan(t_max) || !(t_min <= t_max)) return best;
    bool any_hit = (q.flags & RAY_ANY_HIT) != 0u;
    // Triangles are opaque; a ray that leaves a triangle has every candidate reported so
    // that its own triangle is skipped (the other schemes' `skip`), then confirmed.
    bool skips = q.skip != RAY_NO_TRIANGLE;
    uint flags = (skips ? gl_RayFlagsNoOpaqueEXT : gl_RayFlagsOpaqueEXT) | (any_hit ? gl_RayFlagsTerminateOnFirstHitEXT : 0u);
    rayQueryEXT rq;
    rayQueryInitializeEXT(rq, tlas, flags, 0xffu, o, t_min, d, t_max);
    while (rayQueryProceedEXT(rq)) {
        if (rayQueryGetIntersectionTypeEXT(rq, false) == gl_RayQueryCandidateIntersectionTriangleEXT && candidate_id(rq) != q.skip) {
            rayQueryConfirmIntersectionEXT(rq);
        }
    }
    if (rayQueryGetIntersectionTypeEXT(rq, true) == gl_RayQueryCommittedIntersectionTriangleEXT) {
        vec2 uv = rayQueryGetIntersectionBarycentricsEXT(rq, true);
        uint id = uint(rayQueryGetIntersectionInstanceCustomIndexEXT(rq, true)) + uint(rayQueryGetIntersectionPrimitiveIndexEXT(rq, true));
        best = RayHit(rayQueryGetIntersectionTEXT(rq, true), uv.x, uv.y, id);
    }
    return best;
}

#define INTERSECT intersect_ray_query
#include "raytrace/intersect_main.glsl"
