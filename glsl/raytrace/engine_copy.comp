#version 460
#extension GL_GOOGLE_include_directive : require
// The ray engine's hit records into the queue's hit buffer (what every scheme answers):
// texel t's record is ray_at(t)'s hit.
layout(local_size_x = 64) in;
#include "raytrace/engine.glsl"

void main() {
    uint t = gl_GlobalInvocationID.x;
    if (t >= queue_rays()) return;
    uint i = ray_at(t);
    if ((queries[i].flags & RAY_HIT_KNOWN) != 0u) return;
    uvec4 r = imageLoad(engine_hits, ivec2(slot_texel(t)));
    hits[i] = r.w == RAY_NO_TRIANGLE ? no_hit(queries[i]) : RayHit(uintBitsToFloat(r.x), uintBitsToFloat(r.y), uintBitsToFloat(r.z), r.w);
}
