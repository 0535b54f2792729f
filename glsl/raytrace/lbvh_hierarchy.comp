#version 460
#extension GL_GOOGLE_include_directive : require
// GPU BVH, step 3: Karras's hierarchy over the sorted keys (raytrace/lbvh.glsl). Invocation
// i < n puts triangle i of the sorted order into the references (leaf i holds it); i < n − 1
// finds internal node i's range (its direction from δ, its far end by an exponential then a
// binary search) and its split γ, and writes its two children into nodes 2i + 1 and
// 2i + 2: a leaf (first γ, count 1) or an internal node (first 2c + 1, count 0), recording
// where each child went (the leaf list, the internal nodes' places). The boxes follow.
layout(local_size_x = 64) in;
#include "raytrace/lbvh.glsl"

void place(uint slot, bool leaf, uint index) {
    uint n = lbvh.triangle_count;
    if (leaf) {
        lbvh_slots[index] = slot;
        lbvh_nodes[2u * slot] = uvec4(0u, 0u, 0u, index);
        lbvh_nodes[2u * slot + 1u] = uvec4(0u, 0u, 0u, 1u);
    } else {
        lbvh_slots[n + index] = slot;
        lbvh_nodes[2u * slot] = uvec4(0u, 0u, 0u, 2u * index + 1u);
        lbvh_nodes[2u * slot + 1u] = uvec4(0u);
    }
}

void main() {
    uint n = lbvh.triangle_count;
    uint u = gl_GlobalInvocationID.x;
    if (u >= n) return;
    lbvh_refs[u] = lbvh_vals[u];
    if (n == 1u) {
        place(0u, true, 0u);
        return;
    }
    if (u == 0u) place(0u, false, 0u);
    if (u + 1u >= n) return;
    int i = int(u);
    int d = lbvh_delta(i, i + 1) - lbvh_delta(i, i - 1) >= 0 ? 1 : -1;
    int delta_min = lbvh_delta(i, i - d);
    int l_max = 2;
    while (lbvh_delta(i, i + l_max * d) > delta_min) l_max *= 2;  // at most log₂ n + 1 doublings
    int l = 0;
    for (int t = l_max / 2; t >= 1; t /= 2) {
        if (lbvh_delta(i, i + (l + t) * d) > delta_min) l += t;
    }
    int j = i + l * d;
    int delta_node = lbvh_delta(i, j);
    int s = 0;
    int t = l;
    do {
        t = (t + 1) / 2;
        if (lbvh_delta(i, i + (s + t) * d) > delta_node) s += t;
    } while (t > 1);
    int gamma = i + s * d + min(d, 0);
    uint g = uint(gamma);
    place(2u * u + 1u, min(i, j) == gamma, g);
    place(2u * u + 2u, max(i, j) == gamma + 1, g + 1u);
}
