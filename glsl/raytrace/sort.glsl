// The ray hierarchy's ray order (survey §2.2.1): the rays of a queue arrive in the order
// the kernels appended them (atomics), so the rays a tile of the ray texture holds share
// nothing and their cones cover everything — and which rays share a tile changes from run
// to run. A counting sort by direction cell and pixel puts each pixel's rays of one cell
// together, in pixel order, as the survey's ray textures hold them (a secondary ray at its
// parent's texel), the cells one after the other: ray_order[t] is the ray in slot t (the
// texel of slot t: engine.glsl's slot_texel). Within a key the rays are ordered by their
// query's bits, so the order — and so the cones and the culling — is the same in every run.
//
// Steps (src/methods/raytrace/stage.rs, `sort`): the pixels' counters cleared; count
// (each ray's rank among its pixel's); an exclusive scan of the P + 1 counters (blocks,
// block totals, add); scatter; order each pixel's few rays. push.object: 0 the ray queue,
// 1 the shadow queue (its capacity).
#ifndef RAYTRACE_SORT_GLSL
#define RAYTRACE_SORT_GLSL
#include "raytrace/engine.glsl"

// trace.direction_cells per side of the octahedral map of directions (at most
// SORT_DIRECTION_CELLS; fewer where the counters would outgrow their cap): the rays of a queue
// are grouped by their direction's cell first, then by pixel, so that a tile holds rays of
// one cell from about one block of the screen — rays whose directions a screen block
// spreads over the sphere (behind a curved mirror, through glass) no longer share a cone.

// Pixel keys: one per (pixel, sample), the pixels in blocks of tile_size² (the frame padded
// to whole blocks), block by block in scan-line order, so that a tile of the ray texture
// holds the rays of about one block of the screen; times the direction cells.
uint sort_pixel_keys() {
    uint b = trace.tile_size;
    return (trace.width + b - 1u) / b * ((trace.height + b - 1u) / b) * b * b * trace.samples;
}

uint sort_keys() {
    return sort_pixel_keys() * trace.direction_cells * trace.direction_cells;
}

// The cell of direction d on the octahedral map, the cells in Morton order (neighbouring
// cells mostly adjacent in the order, so a tile that spans two spans neighbours).
// `precise`: the count, scatter and ties kernels each compute a ray's key and must agree to
// the bit (a ray whose key moved between them would leave a hole in ray_order), so no
// compiler may fuse or reorder this arithmetic differently in one of the three pipelines.
uint sort_direction_cell(vec3 d) {
    precise vec3 a = abs(d);
    precise float l1 = a.x + a.y + a.z;
    if (!(l1 > 0.0) || isinf(l1)) return 0u;
    precise vec2 p = d.xy / l1;
    if (d.z < 0.0) p = (1.0 - abs(p.yx)) * vec2(p.x >= 0.0 ? 1.0 : -1.0, p.y >= 0.0 ? 1.0 : -1.0);
    float n = float(trace.direction_cells);
    precise vec2 q = (p * 0.5 + 0.5) * n;
    uvec2 c = uvec2(clamp(q, vec2(0.0), vec2(n - 0.5)));
    uint m = 0u;
    for (uint bit = 0u; (1u << bit) < trace.direction_cells; ++bit) {
        m |= ((c.x >> bit) & 1u) << (2u * bit) | ((c.y >> bit) & 1u) << (2u * bit + 1u);
    }
    return m;
}

uint sort_key(uint ray) {
    uint b = trace.tile_size;
    uint p = payloads[ray].pixel;
    uint s = p % trace.samples;
    uint xy = min(p / trace.samples, trace.width * trace.height - 1u);
    uint x = xy % trace.width, y = xy / trace.width;
    uint blocks_per_row = (trace.width + b - 1u) / b;
    uint block = (y / b) * blocks_per_row + x / b;
    uint pixel = ((block * b + y % b) * b + x % b) * trace.samples + s;
    // Shadow rays aim at the lights: their directions follow their origins, which the
    // pixel order already groups (the cells would only split a block's tiles).
    uint cell = push.object == 0u ? sort_direction_cell(queries[ray].direction.xyz) : 0u;
    return cell * sort_pixel_keys() + pixel;
}

// Scan blocks of 1024 counters (256 invocations, 4 each).
const uint SCAN_BLOCK = 1024u;

#endif
