#version 460
#extension GL_GOOGLE_include_directive : require
// variants: SCATTER
// caustics.photon_map (survey §6.1.1, PDC03), building the photon grid on the GPU: one
// invocation per texel of photon layer push.object, whose caustic cube is push.flags (its
// hits are stored relative to that cube's centre). Without SCATTER it counts the photons
// of each bucket (photon_grid[grid_cells + b]); caustics/grid_scan.comp turns the counts
// into each bucket's first place and zeroes them; with SCATTER each photon takes the next
// place of its bucket: the photons end sorted by bucket, with no readback.
layout(local_size_x = 64) in;
#include "common/scene.glsl"
#include "caustics/photon_map.glsl"

// The invocation's index: dispatches of more than 32768 groups spread over y (Rust's
// `spread_groups`), within every device's 65535 groups an axis.
uint invocation() {
    return gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 64u;
}

void main() {
    uint n = caustic.photon_size;
    uint i = invocation();
    if (i >= n * n) return;
    ivec3 tc = ivec3(int(i % n), int(i / n), int(push.object));
    vec4 hit = texelFetch(photon_hits, tc, 0);
    vec4 power = texelFetch(photon_power, tc, 0);
    if (hit.w == 0.0 || all(lessThanEqual(power.rgb, vec3(0.0)))) return;
    vec3 p = cubes[push.flags].centre.xyz + hit.xyz;
    if (any(isnan(p)) || any(isinf(p))) return;
    uint b = photon_bucket(photon_cell(p));
#ifdef SCATTER
    uint slot = photon_grid[b] + atomicAdd(photon_grid[caustic.grid_cells + b], 1u);
    photon_list[2u * slot] = vec4(p, power.r);
    photon_list[2u * slot + 1u] = vec4(power.g, power.b, power.w, 0.0);
#else
    atomicAdd(photon_grid[caustic.grid_cells + b], 1u);
#endif
}
