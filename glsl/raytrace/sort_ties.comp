#version 460
#extension GL_GOOGLE_include_directive : require
// Ray order, step 4: the rays of each key (a pixel's rays in one direction cell, a handful:
// children and shadow rays of its earlier rays) by their query's bits, which the atomic
// ranks left in any order (raytrace/sort.glsl). The invocation at a key's first texel sorts its range.
layout(local_size_x = 64) in;
#include "raytrace/sort.glsl"

// Lexicographic order on direction, origin, t bounds and the triangle left.
bool before(uint a, uint b) {
    RayQuery x = queries[a];
    RayQuery y = queries[b];
    uint kx[9] = uint[9](floatBitsToUint(x.direction.x), floatBitsToUint(x.direction.y), floatBitsToUint(x.direction.z),
                         floatBitsToUint(x.origin.x), floatBitsToUint(x.origin.y), floatBitsToUint(x.origin.z),
                         floatBitsToUint(x.origin.w), floatBitsToUint(x.direction.w), x.skip);
    uint ky[9] = uint[9](floatBitsToUint(y.direction.x), floatBitsToUint(y.direction.y), floatBitsToUint(y.direction.z),
                         floatBitsToUint(y.origin.x), floatBitsToUint(y.origin.y), floatBitsToUint(y.origin.z),
                         floatBitsToUint(y.origin.w), floatBitsToUint(y.direction.w), y.skip);
    for (uint k = 0u; k < 9u; ++k) {
        if (kx[k] != ky[k]) return kx[k] < ky[k];
    }
    return false;
}

void main() {
    uint t = gl_GlobalInvocationID.x;
    if (t >= queue_rays()) return;
    uint key = sort_key(ray_order[t]);
    uint start = sort_offsets[key];
    uint end = sort_offsets[key + 1u];
    if (t != start || end - start < 2u) return;
    for (uint i = start + 1u; i < end; ++i) {
        uint r = ray_order[i];
        uint j = i;
        while (j > start && before(r, ray_order[j - 1u])) {
            ray_order[j] = ray_order[j - 1u];
            j--;
        }
        ray_order[j] = r;
    }
}
