#version 460
#extension GL_GOOGLE_include_directive : require
// The ray engine's hit records into the queue's hit buffer (what every scheme answers).
layout(local_size_x = 64) in;
#include "raytrace/engine.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= ray_count || (queries[i].flags & RAY_HIT_KNOWN) != 0u) return;
    uint w = trace.ray_texture_width;
    uvec4 r = imageLoad(engine_hits, ivec2(i % w, i / w));
    hits[i] = r.w == RAY_NO_TRIANGLE ? no_hit(queries[i]) : RayHit(uintBitsToFloat(r.x), uintBitsToFloat(r.y), uintBitsToFloat(r.z), r.w);
}
