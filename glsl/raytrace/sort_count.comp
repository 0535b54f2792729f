#version 460
#extension GL_GOOGLE_include_directive : require
// Ray order, step 1: each ray's rank among its key's rays (direction cell and pixel) (raytrace/sort.glsl).
layout(local_size_x = 64) in;
#include "raytrace/sort.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= queue_rays()) return;
    sort_ranks[i] = atomicAdd(sort_offsets[sort_key(i)], 1u);
}
