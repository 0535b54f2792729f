#version 460
#extension GL_GOOGLE_include_directive : require
// Ray order, step 2a: the exclusive scan of each block of SCAN_BLOCK counters in place,
// and the block's total into sort_blocks (raytrace/sort.glsl).
layout(local_size_x = 256) in;
#include "raytrace/sort.glsl"

shared uint partial[256];

void main() {
    uint n = sort_keys() + 1u;
    uint lid = gl_LocalInvocationID.x;
    uint base = gl_WorkGroupID.x * SCAN_BLOCK + 4u * lid;
    uint v[4];
    uint sum = 0u;
    for (uint k = 0u; k < 4u; ++k) {
        uint c = base + k < n ? sort_offsets[base + k] : 0u;
        v[k] = sum;
        sum += c;
    }
    partial[lid] = sum;
    barrier();
    // Hillis–Steele inclusive scan of the 256 thread sums.
    for (uint d = 1u; d < 256u; d <<= 1u) {
        uint add = lid >= d ? partial[lid - d] : 0u;
        barrier();
        partial[lid] += add;
        barrier();
    }
    uint before = lid > 0u ? partial[lid - 1u] : 0u;
    for (uint k = 0u; k < 4u; ++k) {
        if (base + k < n) sort_offsets[base + k] = before + v[k];
    }
    if (lid == 255u) sort_blocks[gl_WorkGroupID.x] = partial[255];
}
