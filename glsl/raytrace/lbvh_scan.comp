#version 460
#extension GL_GOOGLE_include_directive : require
// GPU BVH, radix sort step 2: the exclusive scan of the 16 · groups counters in place, one
// workgroup (each invocation scans a run of them, then the runs' sums are scanned): each
// (digit, workgroup) learns where its keys go (raytrace/lbvh.glsl).
layout(local_size_x = 256) in;
#include "raytrace/lbvh.glsl"

shared uint partial[256];

void main() {
    uint lid = gl_LocalInvocationID.x;
    uint n = 16u * lbvh.groups;
    uint run = (n + 255u) / 256u;
    uint base = lid * run;
    uint sum = 0u;
    for (uint k = 0u; k < run && base + k < n; ++k) sum += lbvh_counts[base + k];
    partial[lid] = sum;
    barrier();
    for (uint d = 1u; d < 256u; d <<= 1u) {
        uint add = lid >= d ? partial[lid - d] : 0u;
        barrier();
        partial[lid] += add;
        barrier();
    }
    uint before = lid > 0u ? partial[lid - 1u] : 0u;
    for (uint k = 0u; k < run && base + k < n; ++k) {
        uint c = lbvh_counts[base + k];
        lbvh_counts[base + k] = before;
        before += c;
    }
}
