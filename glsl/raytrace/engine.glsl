// The ray engine (survey §2.2, CHH02): the rays of a queue laid out as a ray texture, one
// texel per ray, row by row; each triangle rasterised over it, the fragment shader testing
// its texel's ray against the triangle and writing the hit distance as depth, so that the
// z-test keeps the nearest hit (reversed: larger depth is nearer).
#ifndef RAYTRACE_ENGINE_GLSL
#define RAYTRACE_ENGINE_GLSL
#include "raytrace/trace.glsl"

// Rows of the ray texture that hold this queue's rays.
uint engine_rows() {
    uint n = min(ray_count, max(trace.capacity, trace.shadow_capacity));
    return (n + trace.ray_texture_width - 1u) / trace.ray_texture_width;
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
