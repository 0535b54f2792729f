#version 460
#extension GL_GOOGLE_include_directive : require
// GPU BVH, radix sort step 3: every key (and its triangle) to its place in the other half:
// its (digit, workgroup)'s offset plus its rank among the workgroup's keys of that digit
// before it, so that the sort is stable (raytrace/lbvh.glsl). The ranks come from one scan
// over the workgroup of 16 counters per invocation, packed two to a word (16 bits each:
// a workgroup holds at most 256 keys).
layout(local_size_x = 256) in;  // LBVH_TILE
#include "raytrace/lbvh.glsl"

shared uint counters[8][256];

void main() {
    uint lid = gl_LocalInvocationID.x;
    uint i = gl_GlobalInvocationID.x;
    uint n = lbvh.triangle_count;
    uint pass = push.object;
    uint src = pass & 1u;
    bool valid = i < n;
    uint key = valid ? lbvh_key(src, i) : 0u;
    uint val = valid ? lbvh_vals[src * n + i] : 0u;
    // Keys past the end count for nothing (they are the workgroup's last).
    uint digit = (key >> (LBVH_RADIX_BITS * pass)) & 15u;
    uint one = valid ? 1u << (16u * (digit & 1u)) : 0u;
    for (uint w = 0u; w < 8u; ++w) counters[w][lid] = w == (digit >> 1u) ? one : 0u;
    barrier();
    // Hillis–Steele inclusive scan of the packed counters.
    for (uint d = 1u; d < 256u; d <<= 1u) {
        uint add[8];
        for (uint w = 0u; w < 8u; ++w) add[w] = lid >= d ? counters[w][lid - d] : 0u;
        barrier();
        for (uint w = 0u; w < 8u; ++w) counters[w][lid] += add[w];
        barrier();
    }
    if (!valid) return;
    uint rank = ((counters[digit >> 1u][lid] >> (16u * (digit & 1u))) & 0xffffu) - 1u;
    uint at = lbvh_counts[digit * lbvh.groups + gl_WorkGroupID.x] + rank;
    uint dst = 1u - src;
    lbvh_keys[dst * n + at] = key;
    lbvh_vals[dst * n + at] = val;
}
