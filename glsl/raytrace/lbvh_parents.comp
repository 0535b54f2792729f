#version 460
#extension GL_GOOGLE_include_directive : require
// GPU BVH, step 4: each node's parent, from where the hierarchy put the internal nodes:
// node s > 0 is a child of internal node (s − 1) / 2 (raytrace/lbvh.glsl).
layout(local_size_x = 64) in;
#include "raytrace/lbvh.glsl"

void main() {
    uint s = gl_GlobalInvocationID.x;
    if (s >= lbvh.nodes) return;
    lbvh_parents[s] = s == 0u ? LBVH_NONE : lbvh_slots[lbvh.triangle_count + (s - 1u) / 2u];
}
