#version 460
#extension GL_GOOGLE_include_directive : require
// GPU BVH, step 5, and the refit of any BVH of this form (raytrace/lbvh.glsl): invocation k
// takes leaf node lbvh_slots[k], bounds its triangles, and climbs: at each parent the
// first child to arrive stops, the second unites both children's boxes (the flags count
// arrivals; the boxes are read through coherent memory after a barrier). A node's box is
// exactly its triangles' f32 bounds, as the CPU builder's.
layout(local_size_x = 64) in;
#include "raytrace/lbvh.glsl"

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k >= lbvh.leaves) return;
    uint s = lbvh_slots[k];
    uint first = lbvh_nodes[2u * s].w;
    uint count = lbvh_nodes[2u * s + 1u].w;
    vec3 lo = vec3(uintBitsToFloat(0x7f800000u));
    vec3 hi = -lo;
    for (uint r = first; r < first + count; ++r) {
        vec3 a, b;
        lbvh_triangle_box(lbvh_refs[r], a, b);
        lo = min(lo, a);
        hi = max(hi, b);
    }
    lbvh_nodes[2u * s] = uvec4(floatBitsToUint(lo), first);
    lbvh_nodes[2u * s + 1u] = uvec4(floatBitsToUint(hi), count);
    uint p = lbvh_parents[s];
    while (p != LBVH_NONE) {  // at most the tree's depth
        memoryBarrierBuffer();
        if (atomicAdd(lbvh_flags[p], 1u) == 0u) return;
        memoryBarrierBuffer();
        uint c = lbvh_nodes[2u * p].w;
        uvec4 l0 = lbvh_nodes[2u * c], l1 = lbvh_nodes[2u * c + 1u];
        uvec4 r0 = lbvh_nodes[2u * c + 2u], r1 = lbvh_nodes[2u * c + 3u];
        lo = min(uintBitsToFloat(l0.xyz), uintBitsToFloat(r0.xyz));
        hi = max(uintBitsToFloat(l1.xyz), uintBitsToFloat(r1.xyz));
        lbvh_nodes[2u * p] = uvec4(floatBitsToUint(lo), c);
        lbvh_nodes[2u * p + 1u] = uvec4(floatBitsToUint(hi), 0u);
        p = lbvh_parents[p];
    }
}
