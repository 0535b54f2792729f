#version 460
#extension GL_GOOGLE_include_directive : require
// The exact shadow test's outcome: a shadow query that met nothing adds its light.
layout(local_size_x = 64) in;
#include "raytrace/trace.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= min(ray_count, trace.shadow_capacity)) return;
    if (hits[i].triangle == RAY_NO_TRIANGLE) accumulate(payloads[i].pixel, payloads[i].weight.rgb);
}
