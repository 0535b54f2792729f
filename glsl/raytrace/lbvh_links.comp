#version 460
#extension GL_GOOGLE_include_directive : require
// GPU BVH, step 6: each node's miss link for the stackless traversal (bvh.glsl): a first
// child's sibling; for a second child its parent's link, found by climbing to the nearest
// ancestor that is a first child (raytrace/lbvh.glsl; BVH_END past the root).
layout(local_size_x = 64) in;
#include "raytrace/lbvh.glsl"

void main() {
    uint s = gl_GlobalInvocationID.x;
    if (s >= lbvh.nodes) return;
    uint m = s;
    while (m != 0u) {  // at most the tree's depth
        uint p = lbvh_parents[m];
        uint first = lbvh_nodes[2u * p].w;
        if (m == first) {
            lbvh_aux[s] = first + 1u;
            return;
        }
        m = p;
    }
    lbvh_aux[s] = LBVH_NONE;
}
