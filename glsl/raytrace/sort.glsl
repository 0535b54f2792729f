// The ray hierarchy's ray order (survey §2.2.1): the rays of a queue arrive in the order
// the kernels appended them (atomics), so the rays a tile of the ray texture holds share
// nothing and their cones cover everything — and which rays share a tile changes from run
// to run. A counting sort by pixel puts each pixel's rays together, in pixel order, as the
// survey's ray textures hold them (a secondary ray at its parent's texel): ray_order[t] is
// the ray in slot t (the texel of slot t: engine.glsl's slot_texel). Within a pixel the rays are ordered by their query's bits, so the
// order — and so the cones and the culling — is the same in every run.
//
// Steps (src/methods/raytrace/stage.rs, `sort`): the pixels' counters cleared; count
// (each ray's rank among its pixel's); an exclusive scan of the P + 1 counters (blocks,
// block totals, add); scatter; order each pixel's few rays. push.object: 0 the ray queue,
// 1 the shadow queue (its capacity).
#ifndef RAYTRACE_SORT_GLSL
#define RAYTRACE_SORT_GLSL
#include "raytrace/engine.glsl"

// Pixel keys: one per (pixel, sample), the pixels in blocks of tile_size² (the frame padded
// to whole blocks), block by block in scan-line order, so that a tile of the ray texture
// holds the rays of about one block of the screen.
uint sort_keys() {
    uint b = trace.tile_size;
    return (trace.width + b - 1u) / b * ((trace.height + b - 1u) / b) * b * b * trace.samples;
}

uint sort_key(uint ray) {
    uint b = trace.tile_size;
    uint p = payloads[ray].pixel;
    uint s = p % trace.samples;
    uint xy = min(p / trace.samples, trace.width * trace.height - 1u);
    uint x = xy % trace.width, y = xy / trace.width;
    uint blocks_per_row = (trace.width + b - 1u) / b;
    uint block = (y / b) * blocks_per_row + x / b;
    return ((block * b + y % b) * b + x % b) * trace.samples + s;
}

// Scan blocks of 1024 counters (256 invocations, 4 each).
const uint SCAN_BLOCK = 1024u;

#endif
