#version 460
#extension GL_GOOGLE_include_directive : require
// Ray order, step 3: each ray to its key's range, at its rank (raytrace/sort.glsl).
layout(local_size_x = 64) in;
#include "raytrace/sort.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= queue_rays()) return;
    ray_order[sort_offsets[sort_key(i)] + sort_ranks[i]] = i;
}
