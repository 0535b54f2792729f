#version 460
#extension GL_GOOGLE_include_directive : require
// variants: GRADED_MEDIA
#extension GL_EXT_ray_query : require
// Vulkan's ray queries (src/methods/raytrace/ray_query/): the driver's traversal of the
// acceleration structures (one bottom level per mesh, one instance per object) answers the
// same query as every other scheme.
// Set 5 (`tlas`, src/methods/raytrace/layout.in.rs) is declared where this is defined.
#define SPECULA_RAY_QUERY
#include "raytrace/rays.glsl"
#include "raytrace/ray_query.glsl"

RayHit intersect_ray_query(RayQuery q) {
    return rq_trace(q.origin.xyz, q.direction.xyz, q.origin.w, q.direction.w, q.skip, (q.flags & RAY_ANY_HIT) != 0u);
}

#define INTERSECT intersect_ray_query
#include "raytrace/intersect_main.glsl"
