#version 460
#extension GL_GOOGLE_include_directive : require
// Indirect dispatch arguments of bounce `trace.bounce` from the GPU's counters, so that no
// count is read back between bounces: entries 8k..8k+2 dispatch the bounce's rays, 8k+4..
// 8k+6 its shadow queries, in groups of 64 (capped by the queues' capacity).
layout(local_size_x = 1) in;
#include "raytrace/trace.glsl"

void main() {
    uint base = 8u * trace.bounce;
    dispatch[base + 0u] = (min(ray_count, trace.capacity) + 63u) / 64u;
    dispatch[base + 1u] = 1u;
    dispatch[base + 2u] = 1u;
    dispatch[base + 4u] = (min(shadow_count, trace.shadow_capacity) + 63u) / 64u;
    dispatch[base + 5u] = 1u;
    dispatch[base + 6u] = 1u;
}
