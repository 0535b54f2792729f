#version 460
#extension GL_GOOGLE_include_directive : require
// Bounce 0 of the ray pipeline: each pixel whose rasterised nearest triangle belongs to an
// object this stage renders becomes a camera ray in the first queue, with its hit (the
// exact Möller–Trumbore solution on that triangle for the pixel-centre ray, as the
// reference computes it; with MSAA one ray per sample, at the sample's position). Pixels of other objects, or of no triangle, are left alone.
layout(local_size_x = 8, local_size_y = 8) in;
#include "raytrace/trace.glsl"

void main() {
    uvec2 xy = gl_GlobalInvocationID.xy;
    uint sample_id = gl_GlobalInvocationID.z;  // MSAA: one ray per sample
    if (xy.x >= trace.width || xy.y >= trace.height || sample_id >= trace.samples) return;
    uint id = imageLoad(visibility, ivec3(xy, sample_id)).r;
    if (id == RAY_NO_TRIANGLE) return;
    uint mesh = floatBitsToUint(shading[id].uv2.z);
    if (handled[mesh] == 0u) return;
    vec3 o, d;
    camera_ray(xy.x, xy.y, sample_id, o, d);
    // The rasteriser snaps to a sub-pixel grid: a pixel centre within a fraction of a
    // pixel of an edge may land on either triangle. Where the exact test on the raster's
    // triangle fails, the ray goes through the intersection kernel like any other.
    Triangle tr = triangles[id];
    vec3 tuv;
    bool known = ray_triangle(o, d, tr.v0.xyz, tr.v1.xyz, tr.v2.xyz, 0.0, 1.0 / 0.0, tuv);
    // A planar mirror's view (survey §5) keeps only what lies in front of its mirror: rays
    // the intersection kernel answers start at the mirror's plane.
    View v = views[push.view];
    float t0 = near_plane_t(d);
    float side = dot(v.clip.xyz, o) + v.clip.w, towards = dot(v.clip.xyz, d);
    if (side < 0.0 && towards > 0.0) t0 = max(t0, -side / towards);
    uint slot = atomicAdd(next_count, 1u);
    if (slot >= trace.capacity) return;
    uint pixel = (xy.y * trace.width + xy.x) * trace.samples + sample_id;
    next_queries[slot] = make_query(o, d, t0, 1.0 / 0.0, RAY_NO_TRIANGLE, known ? RAY_HIT_KNOWN : 0u);
    next_payloads[slot] = make_payload(vec3(1.0), pixel);
    next_hits[slot] = known ? RayHit(tuv.x, tuv.y, tuv.z, id) : RayHit(1.0 / 0.0, 0.0, 0.0, RAY_NO_TRIANGLE);
}
