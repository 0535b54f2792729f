// The ray engine (survey §2.2, CHH02): the rays of a queue laid out as a ray texture, one
// texel per ray, row by row; each triangle rasterised over it, the fragment shader testing
// its texel's ray against the triangle and writing the hit distance as depth, so that the
// z-test keeps the nearest hit (reversed: larger depth is nearer).
#ifndef RAYTRACE_ENGINE_GLSL
#define RAYTRACE_ENGINE_GLSL
#include "raytrace/trace.glsl"

// Rays of the bound queue that were stored (push.object: 0 the ray queue, 1 the shadow
// queue; a queue counts the rays its budget dropped too).
uint queue_rays() {
    return min(ray_count, push.object == 0u ? trace.capacity : trace.shadow_capacity);
}

// The slot of texel xy of the ray texture: row by row (the ray engine), or tile by tile
// (the ray hierarchy: tile k holds slots k·ts² … (k + 1)·ts² − 1 of its pixel order, so
// that a tile's rays are consecutive in that order and come from one block of the screen).
uint texel_slot(uvec2 xy) {
    if (trace.ordered == 0u) return xy.y * trace.ray_texture_width + xy.x;
    uint ts = trace.tile_size;
    uint tile = (xy.y / ts) * trace.tiles_per_row + xy.x / ts;
    return tile * ts * ts + (xy.y % ts) * ts + xy.x % ts;
}

// The texel of slot t (texel_slot's inverse).
uvec2 slot_texel(uint t) {
    uint w = trace.ray_texture_width;
    if (trace.ordered == 0u) return uvec2(t % w, t / w);
    uint ts = trace.tile_size;
    uint tile = t / (ts * ts);
    uint j = t % (ts * ts);
    return uvec2(tile % trace.tiles_per_row, tile / trace.tiles_per_row) * ts + uvec2(j % ts, j / ts);
}

// The ray in slot t (the ray hierarchy's pixel order, raytrace/sort.glsl; else t itself).
uint ray_at(uint t) {
    return trace.ordered != 0u ? ray_order[t] : t;
}

// Rows of the ray texture that hold this queue's rays (whole rows of tiles when ordered).
uint engine_rows() {
    uint w = trace.ray_texture_width;
    if (trace.ordered == 0u) return (queue_rays() + w - 1u) / w;
    uint ts = trace.tile_size;
    return (queue_rays() + w * ts - 1u) / (w * ts) * ts;
}

// Clip-space position of ray-texture point (x, y) in texels.
vec4 engine_clip(vec2 texel) {
    uint w = trace.ray_texture_width;
    uint h = (max(trace.capacity, trace.shadow_capacity) + w - 1u) / w;
    return vec4(texel / vec2(w, h) * 2.0 - 1.0, 0.0, 1.0);
}

// Depth of a hit at t: decreasing in t, positive for every finite t ≥ 0 (cleared depth 0 is
// "no hit"), so the GREATER test keeps the nearest.
float engine_depth(float t) {
    return 1.0 / (1.0 + max(t, 0.0));
}

// Corner k (0 … 5) of the rectangle [lo, hi] as two triangles.
vec2 quad_corner(uint k, vec2 lo, vec2 hi) {
    const uvec2 c[6] = uvec2[6](uvec2(0, 0), uvec2(1, 0), uvec2(1, 1), uvec2(0, 0), uvec2(1, 1), uvec2(0, 1));
    return mix(lo, hi, vec2(c[k]));
}

#endif
