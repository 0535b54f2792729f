#version 460
#extension GL_GOOGLE_include_directive : require
// Ray order, step 2c: each counter plus its block's offset: sort_offsets[k] is where key
// k's rays start, sort_offsets[K] the total (raytrace/sort.glsl).
layout(local_size_x = 256) in;
#include "raytrace/sort.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i > sort_keys()) return;
    sort_offsets[i] += sort_blocks[i / SCAN_BLOCK];
}
