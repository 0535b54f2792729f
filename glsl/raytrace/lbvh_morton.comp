#version 460
#extension GL_GOOGLE_include_directive : require
// GPU BVH, step 1: each triangle's Morton code (its centroid on a 1024³ grid over the
// list's bounds) into the keys' first half, its index beside it (raytrace/lbvh.glsl).
layout(local_size_x = 64) in;
#include "raytrace/lbvh.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= lbvh.triangle_count) return;
    Triangle t = lbvh_triangles[i];
    vec3 c = (t.v0.xyz + t.v1.xyz + t.v2.xyz) / 3.0;
    vec3 g = (c - lbvh.lo.xyz) * lbvh.scale.xyz;
    // A non-finite centroid (never in a validated scene) takes cell 0.
    g = mix(g, vec3(0.0), isnan(g));
    uvec3 q = uvec3(clamp(g, vec3(0.0), vec3(1023.0)));
    lbvh_keys[i] = (lbvh_spread(q.x) << 2u) | (lbvh_spread(q.y) << 1u) | lbvh_spread(q.z);
    lbvh_vals[i] = i;
}
