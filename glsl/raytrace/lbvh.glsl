// The GPU BVH builder (src/methods/raytrace/lbvh.rs): a linear BVH (Lauterbach et al. 2009)
// over 30-bit Morton codes of the triangles' centroids, sorted by a stable LSD radix sort
// (LBVH_RADIX_BITS per pass) and split by Karras's parallel construction (HPG 2012: one
// invocation per internal node finds its range and split from the sorted keys alone); then
// the boxes bottom-up (each leaf's invocation climbs, the second child to arrive at a node
// unites its children's boxes) and the miss links of the stackless traversal.
//
// Node layout (bvh.glsl's form, set 2): internal node i of Karras's tree keeps its children
// in nodes 2i + 1 and 2i + 2 (the root is node 0), so that the traversal's "children first
// and first + 1" holds; each leaf holds one triangle. Steps (lbvh.rs, `record`): morton;
// per pass count, scan, scatter; hierarchy; parents; boxes (also the refit, alone); links.
// push.object: the radix-sort pass (its digit and which half of the keys it reads).
#ifndef RAYTRACE_LBVH_GLSL
#define RAYTRACE_LBVH_GLSL
#include "common/scene.glsl"

// Keys of half h (0 or 1): the radix sort's ping-pong.
uint lbvh_key(uint h, uint i) {
    return lbvh_keys[h * lbvh.triangle_count + i];
}

// Spreads the low 10 bits of v to every third bit.
uint lbvh_spread(uint v) {
    v &= 0x3ffu;
    v = (v | (v << 16u)) & 0x030000ffu;
    v = (v | (v << 8u)) & 0x0300f00fu;
    v = (v | (v << 4u)) & 0x030c30c3u;
    v = (v | (v << 2u)) & 0x09249249u;
    return v;
}

// Leading zero bits of a 32-bit word (32 for 0).
int lbvh_clz(uint v) {
    return v == 0u ? 32 : 31 - findMSB(v);
}

// Karras's δ(i, j): the common prefix of the sorted keys i and j, the index breaking ties
// (equal keys share all 32 bits, then the indices' prefix); −1 outside [0, n).
int lbvh_delta(int i, int j) {
    int n = int(lbvh.triangle_count);
    if (j < 0 || j >= n) return -1;
    uint a = lbvh_keys[i], b = lbvh_keys[j];
    if (a == b) return 32 + lbvh_clz(uint(i) ^ uint(j));
    return lbvh_clz(a ^ b);
}

void lbvh_triangle_box(uint t, out vec3 lo, out vec3 hi) {
    Triangle tri = lbvh_triangles[t];
    lo = min(tri.v0.xyz, min(tri.v1.xyz, tri.v2.xyz));
    hi = max(tri.v0.xyz, max(tri.v1.xyz, tri.v2.xyz));
}

#endif
