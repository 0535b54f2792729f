#version 460
#extension GL_GOOGLE_include_directive : require
// Ray order, step 2b: the exclusive scan of the blocks' totals, in one workgroup, 256 at a
// time with a running carry (raytrace/sort.glsl).
layout(local_size_x = 256) in;
#include "raytrace/sort.glsl"

shared uint partial[256];

void main() {
    uint blocks = (sort_keys() + 1u + SCAN_BLOCK - 1u) / SCAN_BLOCK;
    uint lid = gl_LocalInvocationID.x;
    uint carry = 0u;
    for (uint chunk = 0u; chunk < blocks; chunk += 256u) {
        uint i = chunk + lid;
        uint own = i < blocks ? sort_blocks[i] : 0u;
        partial[lid] = own;
        barrier();
        for (uint d = 1u; d < 256u; d <<= 1u) {
            uint add = lid >= d ? partial[lid - d] : 0u;
            barrier();
            partial[lid] += add;
            barrier();
        }
        if (i < blocks) sort_blocks[i] = carry + partial[lid] - own;
        carry += partial[255];
        barrier();
    }
}
