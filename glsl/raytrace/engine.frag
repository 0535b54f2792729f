#version 460
#extension GL_GOOGLE_include_directive : require
// The ray engine's intersection: this texel's ray against this fragment's triangle
// (Möller–Trumbore), the hit distance as depth, the hit record as colour.
#include "raytrace/engine.glsl"

layout(location = 0) flat in uint triangle_id;
layout(location = 0) out uvec4 record;

void main() {
    uint t = texel_slot(uvec2(gl_FragCoord.xy));
    if (t >= queue_rays()) discard;
    RayQuery q = queries[ray_at(t)];
    if ((q.flags & RAY_HIT_KNOWN) != 0u || triangle_id == q.skip) discard;
    Triangle tr = triangles[triangle_id];
    vec3 tuv;
    if (!ray_triangle_eps(q.origin.xyz, q.direction.xyz, tr.v0.xyz, tr.v1.xyz, tr.v2.xyz, q.origin.w, q.direction.w, RAY_EDGE_EPS, tuv)) discard;
    gl_FragDepth = engine_depth(tuv.x);
    record = uvec4(floatBitsToUint(tuv.x), floatBitsToUint(tuv.y), floatBitsToUint(tuv.z), triangle_id);
}
