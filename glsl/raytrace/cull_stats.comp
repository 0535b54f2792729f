#version 460
#extension GL_GOOGLE_include_directive : require
// The ray hierarchy's culling rate (ray_stats knob): for every tile × triangle pair the
// same cone test the vertex shader makes, counted: pairs tested (non-empty tiles) and
// pairs kept, into cull_stats[4 · bounce + 2 · queue] (queue: push.object, 0 rays, 1 shadow
// rays).
layout(local_size_x = 64) in;
#include "raytrace/hierarchy.glsl"

void main() {
    uint t = gl_GlobalInvocationID.x;
    uint tile = gl_GlobalInvocationID.y;
    if (t >= accel.triangle_count || trace.tiles_per_row == 0u || (tile / trace.tiles_per_row) * trace.tile_size >= engine_rows()) return;
    if (tile_cones[2u * tile].w == CONE_EMPTY) return;
    vec3 c;
    float r;
    triangle_sphere(triangles[t], c, r);
    uint slot = 4u * trace.bounce + 2u * push.object;
    atomicAdd(cull_stats[slot], 1u);
    if (cone_meets_sphere(tile, c, r)) atomicAdd(cull_stats[slot + 1u], 1u);
}
