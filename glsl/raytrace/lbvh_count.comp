#version 460
#extension GL_GOOGLE_include_directive : require
// GPU BVH, radix sort pass push.object, step 1: each workgroup's keys per digit, into
// lbvh_counts[digit · groups + workgroup] (raytrace/lbvh.glsl).
layout(local_size_x = 256) in;  // LBVH_TILE
#include "raytrace/lbvh.glsl"

shared uint bins[16];

void main() {
    uint lid = gl_LocalInvocationID.x;
    uint i = gl_GlobalInvocationID.x;
    uint pass = push.object;
    if (lid < 16u) bins[lid] = 0u;
    barrier();
    if (i < lbvh.triangle_count) {
        uint digit = (lbvh_key(pass & 1u, i) >> (LBVH_RADIX_BITS * pass)) & 15u;
        atomicAdd(bins[digit], 1u);
    }
    barrier();
    if (lid < 16u) lbvh_counts[lid * lbvh.groups + gl_WorkGroupID.x] = bins[lid];
}
